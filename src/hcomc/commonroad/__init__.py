"""Export of hcomc runs to CommonRoad, the automated-driving community's scenario format.

Why: CommonRoad's tools (its collision and drivability checker, criticality measures,
motion planners and their benchmarks) then read hcomc's merges as they are. What: a run of
the paper's conditions (C1-C5, corridors of the paper's layout) or of any other corridor
becomes one XML file (``hcomc export trajectories RUN --format commonroad``,
:func:`~hcomc.commonroad.export.export_commonroad`):

* **lanelets** from the road: one per lane and stretch between the points where a lane
  begins or ends, with predecessors, successors, neighbours, line markings and types
  (:mod:`hcomc.commonroad.lanes`, the geometry the SUMO exports use);
* **dynamic obstacles**, one per vehicle on the road at two time steps or more: a rectangle
  of its length and width, and per time step its body centre, orientation, speed and
  acceleration along the orientation (:mod:`hcomc.commonroad.tracks`); obstacle id
  ``1000000 + hcomc vehicle id``;
* optionally **VR's planning problem** (:mod:`hcomc.commonroad.scenario`).

Units are SI (m, s, rad, m/s, m/s^2); x runs along the road in driving direction, y to the
left, angles counter-clockwise from +x; CommonRoad's time step k is the run's logging row k
(sample k of a corridor run), ``dt`` its logging interval. hcomc's reference point is
the front bumper's centre, CommonRoad's the body centre: ``centre = front - L/2 (cos h,
sin h)``; hcomc's speed is longitudinal, CommonRoad's along the heading: ``v / cos h``.

commonroad-io and the drivability checker are the optional extra ``commonroad``
(``pip install 'hcomc[commonroad]'``); this package's modules that need them import them, so
that :func:`commonroad_missing` can tell without importing them.
"""

from __future__ import annotations

from importlib.util import find_spec

__all__ = ["INSTALL_HINT", "commonroad_missing"]

INSTALL_HINT = "pip install 'hcomc[commonroad]'"
"""How to install what the export needs."""


def commonroad_missing() -> str | None:
    """Why the export cannot run here (one line), or None when commonroad-io is installed."""
    if find_spec("commonroad") is None:
        return f"needs commonroad-io, the optional extra 'commonroad'; install it: {INSTALL_HINT}"
    return None
