"""What a fault and the shield read of the run they act on, and how they drive its vehicles.

A fault (:mod:`hcomc.robustness.faults`) and the shield (:mod:`hcomc.robustness.shield`) act
between two steps of a run of either engine with impairments
(:class:`hcomc.robustness.impairments.Impairments`, mixed into our engine and into the SUMO
co-simulation). They see it through :class:`ImpairedRun`, the part of it they use, so that
they depend on this description rather than on the engines that carry them.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.interface import Fleet

__all__ = ["DrivenVehicles", "ImpairedRun", "ScenarioRun"]


class DrivenVehicles(Protocol):
    """A fault as the shield asks it: whether it drives a vehicle now."""

    def drives(self, i: int) -> bool:
        """Whether vehicle ``i`` is driven by the fault (so not by the shield)."""
        ...


class ImpairedRun(Protocol):
    """A run with impairments, between two steps: the true state of every vehicle, the
    fleet's nominal and driving parameters, and the ways to drive a vehicle from outside."""

    dt: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    lane: IntArray
    origin: IntArray
    active: BoolArray
    fleet: Fleet

    @property
    def arrays(self) -> Any:
        """Lane occupancy (x, lane, origin, target, active), and our engine's plans."""
        ...

    def command(self, i: int, accel: float, /) -> None:
        """Drive vehicle ``i`` from outside at ``accel`` for the next step (NaN: stop)."""
        ...

    def _follow(self, ids: IntArray, leader: IntArray, /) -> FloatArray:
        """The car-following acceleration of vehicles ``ids`` behind ``leader``."""
        ...

    def _state(self) -> dict[str, np.ndarray]:
        """The state a broadcast carries (x, v, a, lane, active of every vehicle)."""
        ...

    @property
    def driving(self) -> Fleet:
        """The parameters the engine drives with (which faults and degraded headways
        change)."""
        ...

    @property
    def fault(self) -> DrivenVehicles:
        """The run's fault."""
        ...


class ScenarioRun(ImpairedRun, Protocol):
    """A run of our engine with impairments: also each vehicle's target lane, which a lane
    change in progress differs from its origin in."""

    target: IntArray
