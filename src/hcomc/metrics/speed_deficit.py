"""Speed deficits of the vehicles of lanes 1 and 2 against themselves in the undisturbed
run, from two logs' stored cells (compiled): the pass behind the low-speed region volume
(:func:`hcomc.metrics.lsrv.low_speed_region_volume`, whose module docstring defines the
cells that count).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray

__all__ = ["Cells", "lane_deficits"]


class Cells(NamedTuple):
    """The stored cells of a log (:attr:`~hcomc.sim.log.SimulationLog.cells`, each (T, S))
    that LSRV needs, and which vehicle a column holds when."""

    x: np.ndarray  # front-bumper position [m]
    v: np.ndarray  # speed [m/s]
    lane: np.ndarray  # logged lane
    active: np.ndarray  # bool: the vehicle is on the road
    slot: np.ndarray  # (N,) each vehicle's column (-1: none)
    span: np.ndarray  # (N, 2) the rows [first, end) its column holds it


@kernel
def lane_deficits(
    cells: Cells, reference: Cells, r0: int, r1: int, skip: int, x_lo: float, x_hi: float
) -> FloatArray:
    """(2,) the speed deficits ``max(0, v_u - v)`` [m/s] of the counting cells of lanes 1
    and 2 (:mod:`hcomc.metrics.lsrv`) in rows ``[r0, r1)`` and the area ``[x_lo, x_hi]`` [m], each
    vehicle against its own cell of the ``reference``, summed per lane; vehicle ``skip``
    (VR) is left out."""
    x, v, lane, active, slot, span = cells
    _, v_ref, _, active_ref, slot_ref, span_ref = reference
    out = np.zeros(2)
    for i in range(slot.size):
        s, s_ref = slot[i], slot_ref[i]
        if i == skip or s < 0 or s_ref < 0:
            continue
        lo = max(r0, span[i, 0], span_ref[i, 0])
        hi = min(r1, span[i, 1], span_ref[i, 1])
        for k in range(lo, hi):
            if not (active[k, s] and active_ref[k, s_ref]):
                continue
            lane_k = lane[k, s]
            x_k = np.float64(x[k, s])
            if 1 <= lane_k <= 2 and x_lo <= x_k <= x_hi:
                short = np.float64(v_ref[k, s_ref]) - np.float64(v[k, s])
                if short > 0.0:
                    out[lane_k - 1] += short
    return out
