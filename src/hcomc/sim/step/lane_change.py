"""Kernels of the compiled step that decide and start lane changes: MOBIL and the ramp's
gap acceptance (:mod:`hcomc.sim.mobil`), commanded changes of merge plans, and the start of
the quintic manoeuvre (Eq. 4-6)."""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import borrow, kernel
from hcomc.sim.arrays import nonzero_into, search_left
from hcomc.sim.mobil import Candidates, MobilWork, Traffic, mobil_decide_into
from hcomc.sim.neighbours import LaneIndex, neighbour
from hcomc.sim.step.state import (
    ACCEL_END,
    ACCEL_START,
    EV_FALLBACK,
    EV_LC_START,
    MAIN_1,
    MAIN_2,
    RAMP,
    S_CAND,
    S_CAND_FOLLOWER,
    S_CAND_LANE,
    S_CAND_LEADER,
    S_CAND_TARGET,
    S_FORCE,
    S_MOBIL,
    S_MOBIL_B,
    S_MOBIL_F,
    S_POS,
    S_SELECTED,
    CoreArrays,
    add_event,
)  # fmt: skip


# --------------------------------------------------------------------------- decide
@kernel
def _mobil(
    c: CoreArrays, ids: np.ndarray, cand_pos: np.ndarray, lead: np.ndarray, index: LaneIndex,
    target: np.ndarray, force: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """MOBIL / gap acceptance (:func:`hcomc.sim.mobil.mobil_decide_into`) for the vehicles at
    positions ``cand_pos`` of ``ids``: ``(vehicles, targets)`` accepted, views of the step's
    work rows."""
    vs, ls, rank = index.vehicle, index.lane, index.rank
    n = cand_pos.size
    si = c.scratch_int
    cand, lanes = si[S_CAND, :n], si[S_CAND_LANE, :n]
    leader, follower = si[S_CAND_LEADER, :n], si[S_CAND_FOLLOWER, :n]
    vb, lb = borrow(vs), borrow(ls)  # no reference counting per call (hcomc._jit.borrow)
    for k in range(n):
        p = cand_pos[k]
        cand[k], lanes[k], leader[k] = ids[p], c.lane[ids[p]], lead[p]
        follower[k] = neighbour(vb, lb, rank[p] - 1, lb[rank[p]])
    work = si[S_MOBIL : S_MOBIL + 4]
    m = mobil_decide_into(Traffic(c.matrix, c.iidm, c.length, c.x, c.v, c.a), index,
                          Candidates(cand, lanes, leader, follower, target, force), c.lc_params,
                          MobilWork(work, c.scratch_b[S_MOBIL_B : S_MOBIL_B + 2],
                                    c.scratch_f[S_MOBIL_F : S_MOBIL_F + 2]))  # fmt: skip
    return work[0, :m], work[1, :m]


@kernel
def commanded_changes(
    c: CoreArrays, ids: np.ndarray, t: float, lead: np.ndarray, index: LaneIndex,
    req_vehicle: np.ndarray, req_target: np.ndarray,
    req_duration: np.ndarray, req_release_x: np.ndarray, req_vr: np.ndarray,
    req_other: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Lane changes a live plan commands now, each checked by the MOBIL safety criterion.

    Result per request: 1 started; -1 failed for good (the unsafe vehicle is at or past
    ``req_release_x``: a FALLBACK event for ``req_vr``/``req_other`` is logged); 0 not yet.
    ``req_duration`` NaN keeps the vehicle's own lane-change duration.
    """
    out = np.zeros(req_vehicle.size, dtype=np.int64)
    for r in range(req_vehicle.size):
        i = req_vehicle[r]
        pos = np.array([search_left(ids, i)])
        tgt = np.array([req_target[r]])
        chosen, _ = _mobil(c, ids, pos, lead, index, tgt, np.ones(1, dtype=np.bool_))
        if chosen.size:
            start_lane_changes(c, chosen, tgt, t, req_duration[r : r + 1])
            out[r] = 1
        elif c.x[req_vr[r]] >= req_release_x[r]:
            out[r] = -1
            add_event(c, t, EV_FALLBACK, req_vr[r], req_other[r], c.x[req_vr[r]], math.nan)
    return out


@kernel
def discretionary_changes(
    c: CoreArrays, ids: np.ndarray, changing: np.ndarray, holding: np.ndarray, lead: np.ndarray,
    index: LaneIndex,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """MOBIL decisions of every vehicle free to change now (not changing, not scripted, not
    holding its lane for a plan; ramp vehicles on the acceleration lane only)."""
    sel = c.scratch_b[S_SELECTED, : ids.size]
    for k in range(ids.size):
        i = ids[k]
        ramp = c.lane[i] == RAMP
        on_accel = ramp and c.consts[ACCEL_START] <= c.x[i] <= c.consts[ACCEL_END]
        sel[k] = not changing[k] and not c.scripted[i] and (not ramp or on_accel) and not holding[i]
    pos = c.scratch_int[S_POS]
    pos = pos[: nonzero_into(sel, pos)]
    target = c.scratch_int[S_CAND_TARGET, : pos.size]
    for k in range(pos.size):
        target[k] = MAIN_2 if c.lane[ids[pos[k]]] == MAIN_1 else MAIN_1
    force = c.scratch_b[S_FORCE, : pos.size]
    force[:] = False
    return _mobil(c, ids, pos, lead, index, target, force)


@kernel
def start_lane_changes(
    c: CoreArrays, chosen: np.ndarray, target: np.ndarray, t: float, duration: np.ndarray
) -> None:
    """Begin quintic lane changes (Eq. 4-6); x_f is predicted from the current speed.
    ``duration`` (one value, NaN: the vehicle's own) is a merge plan's duration for VR."""
    for k in range(chosen.size):
        i = chosen[k]
        if duration.size and not math.isnan(duration[0]):
            c.lc_dur[i] = duration[0]
        c.origin[i] = c.lane[i]
        c.target[i] = target[k]
        c.lc_t0[i] = t
        c.lc_x0[i] = c.x[i]
        c.lc_xf[i] = c.x[i] + max(c.v[i] * c.lc_dur[i], 3.0 * c.length[i])
    for k in range(chosen.size):
        add_event(c, t, EV_LC_START, chosen[k], -1, c.x[chosen[k]], target[k])
