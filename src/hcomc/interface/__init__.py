"""What engines and merge controllers exchange: the bottom layer every other one builds on.

An engine (ours, or the SUMO co-simulation: both are an :class:`Engine`) hands a controller a
read-only :class:`TrafficView`, with the :class:`Ramp` it is for (the road as the controller
sees it: control zone, acceleration lane, lane codes), and the key vehicles
(:class:`MergeGroup`) of a ramp vehicle; the controller (a :class:`MergeController`) returns
a :class:`MergePlan`. :class:`Fleet` carries the per-vehicle model parameters both read. To
write your own controller, import from here::

    from hcomc.interface import MergeGroup, MergePlan, Mode, TrafficView, elapsed_ms
"""

from hcomc.interface.controller import MergeController, elapsed_ms
from hcomc.interface.engine import Engine, run_all
from hcomc.interface.fleet import Fleet, follow
from hcomc.interface.plan import MergeGroup, MergePlan, Mode, PlanDetails
from hcomc.interface.ramp import Ramp
from hcomc.interface.view import TrafficView

__all__ = [
    "Engine",
    "Fleet",
    "MergeController",
    "MergeGroup",
    "MergePlan",
    "Mode",
    "PlanDetails",
    "Ramp",
    "TrafficView",
    "elapsed_ms",
    "follow",
    "run_all",
]
