"""The lane profile (:mod:`hcomc.metrics.lane_profile`) of a log's rows: the Python side
that reads a :class:`~hcomc.sim.log.SimulationLog`'s stored cells and the roster of its
vehicles on the road (:func:`hcomc.sim.log.slots.active_columns`) and hands them to the
compiled profile.
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.lane_profile import profile_rows
from hcomc.sim.log import SimulationLog
from hcomc.sim.log.slots import active_columns

__all__ = ["lane_profile_at", "profile_along"]


def profile_along(
    log: SimulationLog, rows: np.ndarray, lanes: np.ndarray, x: FloatArray, *names: str,
    clamp: bool,
) -> FloatArray:  # fmt: skip
    """Profiles of ``log``'s stored values ``names`` (e.g. ``"v"``, ``"a"``) of lane
    ``lanes[k]`` at positions ``x[k]`` [m] in row ``rows[k]``: (len(names), R, Q).

    ``rows`` (R,) are row indices in ``[0, T)``; ``lanes`` (R,) the lane per row, negative
    for none (NaN); ``x`` (R, Q) the positions per row.
    """
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    lanes = np.ascontiguousarray(lanes, dtype=np.int64)
    x = np.ascontiguousarray(x, dtype=np.float64)
    asked = rows[lanes >= 0]  # the roster covers only the rows profiled
    r0, r1 = (int(asked.min()), int(asked.max()) + 1) if asked.size else (0, 0)
    cells = log.cells
    start, _, column = active_columns(cells["active"], log.slot, log.span, r0, r1)
    out = np.empty((len(names), *x.shape))
    values = tuple(cells[name] for name in names)
    profile_rows(cells["x"], cells["lane"], values, start, column, r0, rows, lanes, x,
                 bool(clamp), out)  # fmt: skip
    return out


def lane_profile_at(
    log: SimulationLog, row: int, lane: int, x: FloatArray, *, clamp: bool = False
) -> tuple[FloatArray, FloatArray]:
    """Speed [m/s] and acceleration [m/s²] of lane ``lane`` at positions ``x`` [m] in one
    logged row (negative: from the end).

    Linear interpolation in x between the active vehicles of the lane (sorted by x). Outside
    their range: NaN, or with ``clamp=True`` the nearest vehicle's value. NaN everywhere if
    the lane is empty in that row.
    """
    row = int(np.arange(log.n_steps)[row])  # bounds checked, negatives resolved
    x = np.ascontiguousarray(x, dtype=np.float64)
    lanes = np.array([lane], dtype=np.int64)
    v, a = profile_along(log, np.array([row]), lanes, x.reshape(1, -1), "v", "a", clamp=clamp)
    return v[0].reshape(x.shape), a[0].reshape(x.shape)
