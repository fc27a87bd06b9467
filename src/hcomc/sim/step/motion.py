"""Kernels of the compiled step that move vehicles: car following with HDV
perception (Eq. 1-3), the Eq. 14 blend, lane-end and virtual leaders, integration, quintic
lateral motion (Eq. 4-6) and exits (the collision check is
:mod:`hcomc.sim.step.collisions`)."""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.equations.car_following import follow_accel
from hcomc.equations.integrate import ballistic_step
from hcomc.equations.lane_change import lateral_state
from hcomc.equations.perception import ErrorScales
from hcomc.equations.transition import blend, transition_psi
from hcomc.sim.arrays import nonzero_into, search_left
from hcomc.sim.lane_table import (
    ENDS_BLOCKED,
    KIND_MAIN,
    KIND_ON,
    L_CENTRE,
    L_END,
    L_ENDS,
    L_EXIT,
    L_KIND,
    L_OPENS,
    L_SPEED,
    L_WIDTH,
    MIN_CHANGE_LENGTHS,
)
from hcomc.sim.mobil import LC_SAFE_DECEL, NOT_KNOWN
from hcomc.sim.neighbours import (
    LaneIndex,
    PreviousOrder,
    lookup_one,
    neighbours_into,
    sort_entries_into,
)
from hcomc.sim.perception import Estimates, EstimationErrors, History, perceive_into
from hcomc.sim.step.road import lane_end_at, road_of, section_at, speed_limit, stop_point
from hcomc.sim.step.state import (
    DT,
    EMERGENCY,
    ERRORS,
    EV_EXIT,
    EV_LC_ABORT,
    EV_LC_END,
    EV_MERGE,
    EV_MISSED_EXIT,
    EV_WAIT,
    GAMMA,
    GAP_ERROR,
    PERCEIVE,
    S_ACC,
    S_BUFFER,
    S_CHANGER_IDS,
    S_CHANGERS,
    S_CHANGING,
    S_FIRST_ENTRY,
    S_GAP,
    S_IN_ORI,
    S_IN_TGT,
    S_KEY,
    S_KNOWN,
    S_KNOWN_LEADER,
    S_KS,
    S_LANE,
    S_LEAD,
    S_LEADER_ACC,
    S_LEADER_LENGTH,
    S_LEADER_SPEED,
    S_LS,
    S_NEW_ACC,
    S_NEW_LEADER,
    S_ORDER,
    S_RANK,
    S_SECOND_ENTRY,
    S_SPEED,
    S_VEH,
    S_VS,
    S_X,
    SPEED_LIMITS,
    STEP,
    TTC_ERROR,
    CoreArrays,
    add_event,
)  # fmt: skip

WAIT_SPEED = 0.1  # [m/s] below this a ramp vehicle near the lane end counts as waiting
WAIT_ZONE = 20.0  # [m] distance to the lane end within which waiting is logged


StepAccelerations = tuple[np.ndarray, np.ndarray, LaneIndex, np.ndarray]
"""What :func:`step_accelerations` returns: ``(acc, changing, index, lead)``: the
accelerations, whether each vehicle is changing lanes, the step's sorted entries and each
vehicle's leader, views of the step's work rows."""


# ------------------------------------------------------------------------- perceive
@kernel
def follow_many(c: CoreArrays, ids: np.ndarray, leaders: np.ndarray) -> np.ndarray:
    """Car-following acceleration of each vehicle of ``ids`` behind its leader (-1: none),
    HDVs perceiving Eq. 2 (reaction delays and estimation errors) when the run has them."""
    out = np.empty(ids.size)
    follow_into(c, ids, leaders, out)
    return out


@kernel
def follow_into(c: CoreArrays, ids: np.ndarray, leaders: np.ndarray, out: np.ndarray) -> None:
    """:func:`follow_many` written into ``out[:ids.size]``, in three passes over plain arrays
    (the step's work rows): the exact inputs, the HDVs' perceived inputs, Eq. 1/3. Each
    acceleration taken from exact inputs is kept with its leader (rows ``S_KNOWN``,
    ``S_KNOWN_LEADER``), for MOBIL to reuse in the same step
    (:class:`hcomc.sim.mobil.Traffic`)."""
    matrix, length, x, v, a, iidm = c.matrix, c.length, c.x, c.v, c.a, c.iidm
    n = ids.size
    sf = c.scratch_f
    s, vi, vl, al = sf[S_GAP, :n], sf[S_SPEED, :n], sf[S_LEADER_SPEED, :n], sf[S_LEADER_ACC, :n]
    ll = sf[S_LEADER_LENGTH, :n]
    for k in range(n):
        i, j = ids[k], leaders[k]
        if j >= 0:
            s[k], vl[k], al[k], ll[k] = x[j] - length[j] - x[i], v[j], a[j], length[j]
        else:
            s[k], vl[k], al[k], ll[k] = math.inf, v[i], 0.0, length[i]
        vi[k] = v[i]
    perceive = c.flags[PERCEIVE] > 0
    if perceive:
        history = History(c.x_hist, c.v_hist, c.taus, c.consts[DT])
        scales = ErrorScales(c.consts[GAP_ERROR], c.consts[TTC_ERROR], c.flags[ERRORS] > 0)
        errors = EstimationErrors(c.w_gap, c.w_ttc, scales)
        perceive_into(history, c.counters[STEP], errors, ids, leaders, ll, c.is_hdv,
                      Estimates(s, vi, vl))  # fmt: skip
    known, known_leader, hdv = sf[S_KNOWN], c.scratch_int[S_KNOWN_LEADER], c.is_hdv
    for k in range(n):
        i = ids[k]
        out[k] = known[i] = follow_accel(s[k], vi[k], vl[k], al[k], matrix[0, i], matrix[1, i],
                                         matrix[2, i], matrix[3, i], matrix[4, i], matrix[5, i],
                                         matrix[6, i], iidm[i])  # fmt: skip
        known_leader[i] = NOT_KNOWN if perceive and hdv[i] else leaders[k]


@kernel(inline="always")
def follow_exact(
    matrix: np.ndarray, iidm: np.ndarray, i: int, s: float, v: float, vl: float, al: float
) -> float:
    """Eq. 1/3 of vehicle i with exact inputs (lane end, virtual leaders)."""
    return follow_accel(s, v, vl, al, matrix[0, i], matrix[1, i], matrix[2, i], matrix[3, i],
                        matrix[4, i], matrix[5, i], matrix[6, i], iidm[i])  # fmt: skip


@kernel(inline="always")  # its six views returned from a call would be reference-counted
def lane_index(
    c: CoreArrays, ids: np.ndarray, changing: np.ndarray
) -> tuple[LaneIndex, np.ndarray, np.ndarray]:
    """Sorted entries of this step: every vehicle in its lane and a changer also in the
    other lane its body overlaps (the target lane from its start, the origin lane while its
    body still overlaps it). Returns ``(index, in_ori, in_tgt)``, views of the step's work
    rows."""
    centre, width = c.road_f[L_CENTRE], c.road_f[L_WIDTH]
    n = ids.size
    si, sf, sb = c.scratch_int, c.scratch_f, c.scratch_b
    veh, lanes, xs = si[S_VEH], si[S_LANE], sf[S_X]
    in_ori, in_tgt = sb[S_IN_ORI, :n], sb[S_IN_TGT, :n]
    for k in range(n):
        i = ids[k]
        veh[k], lanes[k], xs[k] = i, c.lane[i], c.x[i]
        in_ori[k] = in_tgt[k] = False
    m = n
    for k in range(n):  # changers' second entries follow all first entries, in ids order
        i = ids[k]
        if not changing[k]:
            continue
        o, g = c.origin[i], c.target[i]
        in_ori[k] = abs(c.y[i] - centre[o]) < 0.5 * (width[o] + c.width[i])
        in_tgt[k] = abs(c.y[i] - centre[g]) < 0.5 * (width[g] + c.width[i])
        crossed = c.lane[i] == c.target[i]
        if crossed and not in_ori[k]:
            continue
        veh[m], lanes[m], xs[m] = i, (c.origin[i] if crossed else c.target[i]), c.x[i]
        m += 1
    previous = PreviousOrder(True, si[S_FIRST_ENTRY], si[S_SECOND_ENTRY])
    vs, ls, ks, rank = sort_entries_into(
        veh[:m], lanes[:m], xs[:m], si[S_ORDER], si[S_BUFFER], si[S_RANK], si[S_VS], si[S_LS],
        sf[S_KEY], sf[S_KS], previous,
    )  # fmt: skip
    return LaneIndex(vs, ls, ks, rank), in_ori, in_tgt


@kernel
def step_accelerations(
    c: CoreArrays, ids: np.ndarray, t: float, following: np.ndarray, vv_fol: np.ndarray,
    vv_x: np.ndarray, vv_v: np.ndarray, vv_a: np.ndarray, vv_len: np.ndarray,
) -> StepAccelerations:  # fmt: skip
    """Accelerations of every active vehicle ``ids`` for this step, from one snapshot.

    Car following (Eq. 1/3, HDVs perceiving Eq. 2) behind the leader of the lane it drives
    in; a changer blends (Eq. 14) the accelerations behind its origin- and target-lane
    leaders and respects the leader of every lane its body overlaps; ramp vehicles that have
    not started merging stop at the acceleration-lane end unless they follow a live plan
    (``following``); commanded vehicles also follow their virtual leaders (rows ``vv_*``);
    a vehicle driven from outside (``a_cmd`` not NaN) takes its command instead; every
    deceleration is limited to the emergency value; a scripted leader follows its
    profile exactly. Returns ``(acc, changing, index, lead)``, views of the step's work
    rows.
    """
    n = ids.size
    if c.flags[SPEED_LIMITS] > 0:
        kinds, rows, sec_x0, sec_speed = c.road_int[L_KIND], c.road_f, c.sec_x0, c.sec_speed
        matrix, desired, lane, x = c.matrix, c.desired, c.lane, c.x
        for k in range(n):  # the desired speed within the limit where the vehicle is
            i, g = ids[k], lane[ids[k]]
            limit = speed_limit(kinds[g], rows[L_OPENS, g], rows[L_END, g], rows[L_SPEED, g],
                                sec_speed[section_at(sec_x0, x[i])], x[i])  # fmt: skip
            matrix[0, i] = min(desired[i], limit)
    changing = c.scratch_b[S_CHANGING, :n]
    for k in range(n):
        changing[k] = c.origin[ids[k]] != c.target[ids[k]]
    index, in_ori, in_tgt = lane_index(c, ids, changing)
    vs, ls, ks, rank = index
    lead = c.scratch_int[S_LEAD, :n]
    neighbours_into(vs, ls, rank, 1, lead)
    for k in range(n):  # a changer's leader: the one ahead of it in its origin lane
        if changing[k]:
            i = ids[k]
            lead[k] = lookup_one(ks, ls, vs, c.origin[i], c.x[i])[0]
    acc = c.scratch_f[S_ACC, :n]
    follow_into(c, ids, lead, acc)
    _blend_changers(c, ids, t, acc, changing, in_ori, in_tgt, index)
    _limits(c, ids, t, acc, changing, following, vv_fol, vv_x, vv_v, vv_a, vv_len)
    return acc, changing, index, lead


@kernel
def _blend_changers(
    c: CoreArrays, ids: np.ndarray, t: float, acc: np.ndarray, changing: np.ndarray,
    in_ori: np.ndarray, in_tgt: np.ndarray, index: LaneIndex,
) -> None:  # fmt: skip
    """Eq. 14 for every changer: the blend of the accelerations behind its origin-lane
    (``acc`` on entry) and target-lane leaders, capped by the leader of each lane its body
    overlaps, and by the target-lane leader from the start when that leader asks for more
    than the safe deceleration (Ψ is 0.01 at the start: a pure blend would keep a changer
    that accepted a short gap accelerating into it until its body reached the lane)."""
    vs, ls, ks = index.vehicle, index.lane, index.key
    if not changing.any():
        return
    ch = c.scratch_int[S_CHANGERS]
    ch = ch[: nonzero_into(changing, ch)]
    n_ch = ch.size
    changers, lead_new = c.scratch_int[S_CHANGER_IDS, :n_ch], c.scratch_int[S_NEW_LEADER, :n_ch]
    for m in range(n_ch):
        i = changers[m] = ids[ch[m]]
        lead_new[m] = lookup_one(ks, ls, vs, c.target[i], c.x[i])[0]
    a_new = c.scratch_f[S_NEW_ACC, :n_ch]
    follow_into(c, changers, lead_new, a_new)
    for m in range(n_ch):
        k = ch[m]
        i = ids[k]
        a_ori = acc[k]
        psi = transition_psi(t - c.lc_t0[i], c.lc_dur[i], c.consts[GAMMA])
        b = blend(a_ori, a_new[m], psi)
        if in_ori[k]:
            b = min(b, a_ori)
        urgent = a_new[m] < -c.lc_params[LC_SAFE_DECEL]
        acc[k] = min(b, a_new[m]) if in_tgt[k] or urgent else b


@kernel
def _limits(
    c: CoreArrays, ids: np.ndarray, t: float, acc: np.ndarray, changing: np.ndarray,
    following: np.ndarray, vv_fol: np.ndarray, vv_x: np.ndarray, vv_v: np.ndarray,
    vv_a: np.ndarray, vv_len: np.ndarray,
) -> None:  # fmt: skip
    """The lane end (where a stalled vehicle ends it, for every vehicle in it), virtual
    leaders, commanded accelerations, the emergency limit and scripted profiles."""
    n = ids.size
    road, matrix, iidm, x, v, lane, route = road_of(c), c.matrix, c.iidm, c.x, c.v, c.lane, c.route
    ends, kinds, lane_ends = road.ints[L_ENDS], road.ints[L_KIND], road.floats[L_END]
    for k in range(n):  # where it must have left its lane, a static obstacle seen exactly
        i, g, exit_code = ids[k], lane[ids[k]], route[ids[k]]
        if exit_code < 0 and not ends[g]:
            continue  # its lane never ends and it leaves by none: nowhere
        lane_end = lane_end_at(road, g, x[i]) if ends[g] else math.inf  # (a call with arrays)
        exit_end = lane_ends[exit_code] if exit_code >= 0 else math.inf
        end = stop_point(lane_end, kinds[g] == KIND_MAIN, exit_end, x[i])
        blocked = ends[g] == ENDS_BLOCKED  # a stalled vehicle stands beyond the end
        if changing[k]:  # a changer drives on unless its change would end at the obstacle
            stops = blocked and c.lc_xf[i] > end + MIN_CHANGE_LENGTHS * c.length[i]
        else:
            stops = blocked or not following[i]
        if end < math.inf and stops:
            a_stop = follow_exact(matrix, iidm, i, end - x[i], v[i], 0.0, 0.0)
            acc[k] = min(acc[k], a_stop)
    if vv_fol.size:
        before = acc.copy()
        for r in range(vv_fol.size):  # a later row for the same follower replaces an earlier
            i = vv_fol[r]
            if vv_x[r] > c.x[i]:
                k = search_left(ids, i)
                gap = vv_x[r] - vv_len[r] - c.x[i]
                a_v = follow_exact(c.matrix, c.iidm, i, gap, c.v[i], vv_v[r], vv_a[r])
                acc[k] = min(before[k], a_v)
    dt, emergency, a_cmd, scripted = c.consts[DT], c.consts[EMERGENCY], c.a_cmd, c.scripted
    for k in range(n):
        i = ids[k]
        if not math.isnan(a_cmd[i]):  # driven from outside: the command replaces the model
            acc[k] = a_cmd[i]
        acc[k] = max(acc[k], -emergency)
        if scripted[i]:  # a scripted profile is followed exactly
            target = np.interp(t + dt, c.profile[:, 0], c.profile[:, 1])
            acc[k] = (target - v[i]) / dt


# ------------------------------------------------------------------------ integrate
@kernel
def integrate(c: CoreArrays, ids: np.ndarray, acc: np.ndarray) -> None:
    """Advance the vehicles ``ids`` one step with their accelerations ``acc`` (Eq. 1/3's
    output) by :func:`~hcomc.equations.integrate.ballistic_step`."""
    dt = c.consts[DT]
    for k in range(ids.size):
        i = ids[k]
        dx, c.v[i], c.a[i] = ballistic_step(c.v[i], acc[k], dt)
        c.x[i] += dx


@kernel
def lateral(c: CoreArrays, ids: np.ndarray, t: float) -> None:
    """Move the changing vehicles among ``ids`` (the vehicles on the road, in index order)
    along their quintic path; switch lane at the lane line; a change from a ramp lane to the
    mainline is a merge. A change that stands still when its duration is over ends where
    the vehicle stands: given up before the lane line (back on its own lane's centre line),
    completed past it (on the target lane's centre line). Eq. 4-6 move a vehicle sideways
    only as it moves along x, and one that stopped across two lanes would block both for
    good."""
    centre, kind = c.road_f[L_CENTRE], c.road_int[L_KIND]
    for i in ids:
        if c.origin[i] == c.target[i]:
            continue
        x0, xf = c.lc_x0[i], c.lc_xf[i]
        xi = (c.x[i] - x0) / (xf - x0)
        stalled = c.v[i] < WAIT_SPEED and t - c.lc_t0[i] > c.lc_dur[i]
        if xi < 0.5 and stalled:
            add_event(c, t, EV_LC_ABORT, i, -1, c.x[i], c.target[i])
            c.target[i] = c.lane[i] = c.origin[i]
            c.y[i], c.heading[i] = centre[c.origin[i]], 0.0
            c.lc_dur[i] = c.lc_duration[i]
            continue
        y, dy_dx, _ = lateral_state(c.x[i], x0, xf, centre[c.origin[i]], centre[c.target[i]])
        c.y[i] = y
        c.heading[i] = math.atan(dy_dx)
        c.lane[i] = c.target[i] if xi >= 0.5 else c.origin[i]
        if xi >= 1.0 or stalled:
            add_event(c, t, EV_LC_END, i, -1, c.x[i], c.target[i])
            if kind[c.origin[i]] != KIND_MAIN and kind[c.target[i]] == KIND_MAIN:
                add_event(c, t, EV_MERGE, i, -1, c.x[i], math.nan)
            c.lc_dur[i] = c.lc_duration[i]
            c.origin[i] = c.target[i]
            c.y[i] = centre[c.target[i]]
            c.heading[i] = 0.0


@kernel
def bookkeeping(c: CoreArrays, ids: np.ndarray, t: float) -> None:
    """Exits (the rear past where the vehicle's lane leaves the road: the mainline's end,
    an off-ramp road's); off-ramps missed (a vehicle bound for one still on the mainline past
    the end of its deceleration lane drives on to the mainline's end); ramp vehicles waiting
    at the end of their acceleration lane."""
    x, lane, route, kinds, road_f = c.x, c.lane, c.route, c.road_int[L_KIND], c.road_f
    for i in ids:
        if x[i] - c.length[i] > road_f[L_EXIT, lane[i]]:
            c.active[i] = False
            add_event(c, t, EV_EXIT, i, -1, x[i], math.nan)
        exit_code = route[i]
        if exit_code < 0:
            continue
        on_main = kinds[lane[i]] == KIND_MAIN and c.target[i] != exit_code
        if on_main and x[i] > road_f[L_END, exit_code]:
            route[i] = -1
            add_event(c, t, EV_MISSED_EXIT, i, -1, x[i], exit_code)
    for i in ids:
        if (kinds[lane[i]] == KIND_ON and c.origin[i] == c.target[i] and c.v[i] < WAIT_SPEED
                and not c.waited[i] and x[i] > road_f[L_END, lane[i]] - WAIT_ZONE):  # fmt: skip
            c.waited[i] = True
            add_event(c, t, EV_WAIT, i, -1, c.x[i], math.nan)
