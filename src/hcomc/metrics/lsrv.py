r"""Low-speed region volume (paper "LSRV"; smaller is better), per vehicle.

The paper says only that LSRV integrates "the product of velocity, longitudinal displacement
and time"; this definition is ours. Every vehicle of lanes 1 and 2 in the merge area is
compared with **itself** in the undisturbed run (the ``reference`` log, see
:mod:`hcomc.metrics.window`), as average acceleration compares the key vehicles, and its speed
deficit is weighted by the road length one vehicle of its lane stands for when nothing
merges:

.. math::

   \mathrm{LSRV} = \sum_{\text{lane} \in \{1, 2\}} \bar s_\text{lane}
       \sum_{\text{rows}} \sum_{i \in \text{lane}} \max(0,\; v^u_i - v_i)\, \Delta t

* a cell (row, vehicle i) counts if the row lies in the window ``[t_start, t_end]``, i is on
  the road in the factual run with logged lane 1 or 2 and front bumper in the merge area
  ``road.control_zone_start <= x_i <= road.length``, and its counterpart exists: i itself
  in the undisturbed run (active in that row), or, for VR, from its merge on, the undisturbed
  traffic of its lane at its position (:func:`hcomc.metrics.paper.vr_counterpart`, as
  :func:`~hcomc.metrics.paper.deviations` uses); a vehicle the undisturbed run does not
  have (with a ramp flow, the other ramp vehicles) does not count;
* ``Δt`` = ``log.dt`` (rectangle rule); the lane is the factual logged lane of the row;
* :math:`\bar s_\text{lane}` [m] = the merge area's length / the mean number of undisturbed
  vehicles of that lane in the area over the window rows (at least one vehicle): the lane's
  mean undisturbed spacing, the same for every vehicle and every controller.

Units: m/s · s · m = m². Weighting by the mean spacing rather than by each vehicle's own gap
keeps a gap that a cooperating vehicle opens from counting as a low-speed region over its
whole length, and compares no vehicle with another; summed over a lane's vehicles it
approximates the space-time integral of the speed deficit. A run identical to its reference
scores exactly 0.
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.paper import vr_counterpart
from hcomc.metrics.speed_deficit import Cells, lane_deficits
from hcomc.metrics.window import MetricWindow, reference_or_score, road_of, window_rows
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog

__all__ = ["lane_spacing", "low_speed_region_volume"]

_LANES = (int(Lane.MAIN_1), int(Lane.MAIN_2))


def low_speed_region_volume(
    log: SimulationLog, window: MetricWindow, *, reference: SimulationLog | None = None
) -> float:
    """Low-speed region volume LSRV [m²] (paper "LSRV"; smaller is better).

    Definition: see the module docstring.

    Returns
    -------
    float
        LSRV [m²], >= 0. 0 if the run has no ramp vehicle (empty group: nothing merges).
        NaN without a reference, or if VR never merged (an outcome, see
        :func:`hcomc.metrics.outcome.merge_outcome`).
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    rows = window_rows(log, window)
    if rows.stop <= rows.start:
        return 0.0
    road = road_of(log)
    area = (road.control_zone_start, road.length)
    deficit = lane_deficits(_cells(log), _cells(ref), rows.start, rows.stop, window.vr, *area)
    if window.vr >= 0:
        deficit += _vr_deficits(log, window, ref, rows, *area)
    return float(np.sum(deficit * lane_spacing(ref, rows, *area)) * log.dt)


def lane_spacing(reference: SimulationLog, rows: slice, x_lo: float, x_hi: float) -> FloatArray:
    """(2,) mean spacing of lanes 1 and 2 in the area ``[x_lo, x_hi]`` over ``rows`` [m]:
    the area's length / the mean number of the lane's active vehicles in it (at least 1)."""
    cells = reference.cells
    x = cells["x"][rows].astype(np.float64)
    with np.errstate(invalid="ignore"):
        inside = cells["active"][rows] & (x >= x_lo) & (x <= x_hi)
    lane = cells["lane"][rows]
    n_rows = max(x.shape[0], 1)
    mean = np.array([np.count_nonzero(inside & (lane == k)) / n_rows for k in _LANES])
    return (x_hi - x_lo) / np.maximum(mean, 1.0)


def _vr_deficits(
    log: SimulationLog, window: MetricWindow, reference: SimulationLog, rows: slice,
    x_lo: float, x_hi: float,
) -> FloatArray:  # fmt: skip
    """(2,) VR's summed speed deficits [m/s] in lanes 1 and 2 against its counterpart."""
    vr = window.vr
    (v_u,) = vr_counterpart(log, window, reference, rows, "v")
    x = log.x[rows, vr].astype(np.float64)
    lane = log.lane[rows, vr]
    with np.errstate(invalid="ignore"):
        counts = np.isfinite(v_u) & (x >= x_lo) & (x <= x_hi)
        short = np.maximum(0.0, v_u - log.v[rows, vr].astype(np.float64))
    return np.array([float(np.sum(short[counts & (lane == k)])) for k in _LANES])


def _cells(log: SimulationLog) -> Cells:
    """The cells of ``log`` that LSRV needs."""
    cells = log.cells
    return Cells(cells["x"], cells["v"], cells["lane"], cells["active"], log.slot, log.span)
