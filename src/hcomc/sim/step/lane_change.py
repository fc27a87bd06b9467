"""Kernels of the compiled step that decide and start lane changes: MOBIL and the ramp's
gap acceptance (:mod:`hcomc.sim.mobil`), commanded changes of merge plans, and the start of
the quintic manoeuvre (Eq. 4-6)."""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import borrow, kernel
from hcomc.sim.arrays import search_left
from hcomc.sim.lane_table import (
    KIND_MAIN,
    KIND_ON,
    L_END,
    L_ENDS,
    L_KIND,
    L_LEFT,
    L_OPENS,
    L_RIGHT,
    MIN_CHANGE_LENGTHS,
)
from hcomc.sim.mobil import Candidates, MobilWork, Traffic, mobil_decide_into
from hcomc.sim.neighbours import LaneIndex, neighbour
from hcomc.sim.step.road import needed_change, road_of, side_allowed
from hcomc.sim.step.state import (
    EV_FALLBACK,
    EV_LC_START,
    LOOKAHEAD,
    S_CAND,
    S_CAND_FOLLOWER,
    S_CAND_LANE,
    S_CAND_LEADER,
    S_CAND_TARGET,
    S_FORCE,
    S_KNOWN,
    S_KNOWN_LEADER,
    S_MARGIN,
    S_MOBIL,
    S_MOBIL_B,
    S_MOBIL_F,
    S_POS,
    S_URGENCY,
    URGENT,
    CoreArrays,
    add_event,
)  # fmt: skip


# --------------------------------------------------------------------------- decide
@kernel
def _mobil(
    c: CoreArrays, ids: np.ndarray, cand_pos: np.ndarray, lead: np.ndarray, index: LaneIndex,
    target: np.ndarray, force: np.ndarray, urgency: np.ndarray,
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
    known, known_leader = c.scratch_f[S_KNOWN], c.scratch_int[S_KNOWN_LEADER]  # (follow_into)
    m = mobil_decide_into(Traffic(c.matrix, c.iidm, c.length, c.x, c.v, c.a, known, known_leader),
                          index,
                          Candidates(cand, lanes, leader, follower, target, force, urgency),
                          c.lc_params,
                          c.road_int, MobilWork(work, c.scratch_b[S_MOBIL_B : S_MOBIL_B + 2],
                                    c.scratch_f[S_MOBIL_F : S_MOBIL_F + 2],
                                    c.scratch_f[S_MARGIN]))  # fmt: skip
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
        chosen, _ = _mobil(c, ids, pos, lead, index, tgt, np.ones(1, dtype=np.bool_),
                           np.zeros(1))  # fmt: skip
        if chosen.size:
            start_lane_changes(c, chosen, tgt, t, req_duration[r : r + 1])
            out[r] = 1
        elif c.x[req_vr[r]] >= req_release_x[r]:
            out[r] = -1
            add_event(c, t, EV_FALLBACK, req_vr[r], req_other[r], c.x[req_vr[r]], math.nan)
    return out


@kernel(inline="always")
def free_target(road_int: np.ndarray, lane: int) -> int:
    """The one lane a change out of ``lane`` goes to when nobody names it (-1: none): from a
    ramp lane the lane to its left; from the mainline the mainline lane to its left, else the
    one to its right (on the paper's road: lane 1 -> lane 2, lane 2 -> lane 1). A learning
    agent's "change lane" action and :func:`hcomc.sim.lane_change_decisions.decide` without
    targets mean it; the step's own decisions weigh both sides
    (:func:`discretionary_changes`)."""
    left = road_int[L_LEFT, lane]
    if road_int[L_KIND, lane] != KIND_MAIN:
        return left
    if left >= 0 and road_int[L_KIND, left] == KIND_MAIN:
        return left
    right = road_int[L_RIGHT, lane]
    return right if right >= 0 and road_int[L_KIND, right] == KIND_MAIN else -1


@kernel
def discretionary_changes(
    c: CoreArrays, ids: np.ndarray, changing: np.ndarray, holding: np.ndarray, lead: np.ndarray,
    index: LaneIndex,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The lane changes vehicles free to change now (not changing, a change a plan started
    in this step included; not scripted, not holding their lane for a plan) take of their own
    accord, decided by MOBIL
    (:func:`hcomc.sim.mobil.mobil_decide_into`): a ramp vehicle's merge where its lane lets
    it leave (on the acceleration lane, by gap acceptance); on the mainline the change its
    lane or route needs (:func:`hcomc.sim.step.road.needed_change`, by gap acceptance), else
    a change to the lane on either side (:func:`hcomc.sim.step.road.side_allowed`),
    the better of the two when both qualify."""
    pos = c.scratch_int[S_POS]
    target = c.scratch_int[S_CAND_TARGET]
    force, urgency = c.scratch_b[S_FORCE], c.scratch_f[S_URGENCY]
    urgent, lookahead, road = c.consts[URGENT], c.consts[LOOKAHEAD], road_of(c)
    ints, floats, route, scripted = road.ints, road.floats, c.route, c.scripted
    lanes, xs = c.lane, c.x
    m = 0
    origin, target_of = c.origin, c.target
    for k in range(ids.size):
        i = ids[k]
        # changing: since the step began, or since a plan started its change in this step
        if changing[k] or origin[i] != target_of[i] or scripted[i] or holding[i]:
            continue
        lane, x, exit_code = lanes[i], xs[i], route[i]
        kind = ints[L_KIND, lane]
        if kind != KIND_MAIN:
            left = ints[L_LEFT, lane]
            opens, end = floats[L_OPENS, lane], floats[L_END, lane]
            if kind == KIND_ON and left >= 0 and opens <= x:  # past its end too
                pos[m], target[m], force[m] = k, left, False  # a ramp lane's
                urgency[m] = min(max(0.0, 1.0 - (end - x) / urgent), 1.0) if urgent > 0 else 0.0
                m += 1
            continue
        # the road's rules matter only to a vehicle bound for an off-ramp or in (beside) a
        # lane that ends (L_ENDS): for the others needed_change finds none and side_allowed
        # allows, so neither is called
        if exit_code >= 0 or ints[L_ENDS, lane]:
            needed, room = needed_change(road, lane, x, exit_code, lookahead)
            if needed >= 0:
                pos[m], target[m], force[m] = k, needed, True
                urgency[m] = max(0.0, 1.0 - room / urgent) if urgent > 0 else 0.0
                m += 1
                continue
        for side in (L_LEFT, L_RIGHT):  # the mainline lane on either side, where the road allows
            tgt = ints[side, lane]
            if tgt < 0 or ints[L_KIND, tgt] != KIND_MAIN:
                continue
            if (exit_code >= 0 or ints[L_ENDS, tgt]) and not side_allowed(
                road, lane, tgt, x, exit_code, lookahead
            ):
                continue
            pos[m], target[m], force[m], urgency[m] = k, tgt, False, 0.0
            m += 1
    return _mobil(c, ids, pos[:m], lead, index, target[:m], force[:m], urgency[:m])


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
        c.lc_xf[i] = c.x[i] + max(c.v[i] * c.lc_dur[i], MIN_CHANGE_LENGTHS * c.length[i])
    for k in range(chosen.size):
        add_event(c, t, EV_LC_START, chosen[k], -1, c.x[chosen[k]], target[k])
