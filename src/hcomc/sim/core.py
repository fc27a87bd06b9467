"""The compiled simulation step: struct-of-arrays state and the kernels that advance it.

:class:`Core` holds every array the step reads or writes (per-vehicle parameters and state,
the HDV perception buffers, the demand queues, the event buffer, counters). The step is split
into kernels that the engine composes in two ways:

* :func:`run_steps` advances many steps in one compiled call while nothing needs Python:
  no live merge plan, no ramp vehicle entering the control zone, no game-confirmed lane
  change; it writes log rows and events itself;
* at a decision event the engine runs the same kernels one step at a time
  (:func:`release`, :func:`step_accelerations`, :func:`start_lane_changes`,
  :func:`step_finish`) with the controller's inputs in between.

Each equation is called from its one home (:mod:`hcomc.models`, :mod:`hcomc.safety`,
:mod:`hcomc.sim.perception`, :mod:`hcomc.sim.mobil`, :mod:`hcomc.sim.neighbours`). Semantics
(order of operations, who sees whom, events) are those documented in
:mod:`hcomc.sim.engine`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from hcomc.models.following import follow_accel
from hcomc.models.quintic import lateral_state
from hcomc.models.transition import blend, transition_psi
from hcomc.safety.collision import vehicle_pair_collides
from hcomc.sim.mobil import mobil_decide
from hcomc.sim.neighbours import lookup_one, neighbour, sort_entries
from hcomc.sim.perception import advance_errors_of, perceive_one

# lanes and event kinds (IntEnums of hcomc.road and hcomc.sim.log, as plain ints)
RAMP, MAIN_1, MAIN_2 = 0, 1, 2
EV_INSERTION, EV_LC_START, EV_LC_END, EV_MERGE, EV_COLLISION, EV_WAIT, EV_EXIT = range(7)
EV_FALLBACK = 8
# counters
STEP, VEHICLE_STEPS, N_EVENTS, N_COLLIDING, INNOV_CURSOR, ROWS = range(6)
# consts
(DT, WARMUP, WIDTH, ACCEL_START, ACCEL_END, CZ_START, ROAD_LENGTH, EMERGENCY, GAMMA, DECAY,
 KICK, GAP_ERROR, TTC_ERROR) = range(13)  # fmt: skip
# flags
(PERCEIVE, ERRORS, PLATOON, DECIDE_EVERY, LOG_EVERY, N_WARMUP, CONTROLLER, CAV_GAME,
 HAS_PLANS) = range(9)  # fmt: skip
# reasons run_steps returns
DONE, NEED_PYTHON, FLUSH, REFILL = range(4)

_WAIT_SPEED = 0.1  # [m/s] below this a ramp vehicle near the lane end counts as waiting
_WAIT_ZONE = 20.0  # [m] distance to the lane end within which waiting is logged


class Core(NamedTuple):
    """Every array of one run's step (shape (N,) unless noted)."""

    matrix: np.ndarray  # (7, N): v0, T, s0, a, b, delta, coolness
    iidm: np.ndarray
    length: np.ndarray
    width: np.ndarray
    lc_duration: np.ndarray
    scripted: np.ndarray
    is_hdv: np.ndarray
    x: np.ndarray
    y: np.ndarray
    v: np.ndarray
    a: np.ndarray
    heading: np.ndarray
    lane: np.ndarray
    origin: np.ndarray  # lane a change started from (= lane when keeping)
    target: np.ndarray  # lane a change goes to (= lane when keeping)
    lc_t0: np.ndarray
    lc_x0: np.ndarray
    lc_xf: np.ndarray
    lc_dur: np.ndarray
    active: np.ndarray
    waited: np.ndarray
    identified: np.ndarray  # key vehicles recorded at control-zone entry
    planned: np.ndarray  # a controller planned for this ramp vehicle
    x_hist: np.ndarray  # (K, N) perception ring buffers
    v_hist: np.ndarray
    w_gap: np.ndarray
    w_ttc: np.ndarray
    taus: np.ndarray  # (3,) reaction times on gap, speed, approach rate [s]
    d_t: np.ndarray  # demand: release time, position, speed
    d_x: np.ndarray
    d_v: np.ndarray
    queues: np.ndarray  # vehicles by lane, concatenated
    queue_start: np.ndarray  # (4,) start of each lane's queue in ``queues``
    queue_pos: np.ndarray  # (3,) next vehicle of each queue
    colliding: np.ndarray  # pair codes i * N + j of the pairs in contact last step
    ev_t: np.ndarray  # event buffer
    ev_kind: np.ndarray
    ev_vehicle: np.ndarray
    ev_other: np.ndarray
    ev_x: np.ndarray
    ev_value: np.ndarray
    counters: np.ndarray  # int64, see STEP ... ROWS
    consts: np.ndarray  # float64, see DT ... TTC_ERROR
    flags: np.ndarray  # int64, see PERCEIVE ... HAS_PLANS
    lc_params: np.ndarray  # MOBIL parameters (hcomc.sim.mobil.lane_change_params)
    profile: np.ndarray  # (k, 2) scripted leader speed profile (t, v)
    innov: np.ndarray  # (m, 2, N) pre-drawn innovations of the estimation errors


# ----------------------------------------------------------------------------- events
@njit(cache=True, inline="always")
def add_event(c: Core, t: float, kind: int, i: int, other: int, x: float, value: float) -> None:
    """Append an event to the buffer (the engine flushes it to the log)."""
    k = c.counters[N_EVENTS]
    c.ev_t[k], c.ev_kind[k], c.ev_vehicle[k], c.ev_other[k] = t, kind, i, other
    c.ev_x[k], c.ev_value[k] = x, value
    c.counters[N_EVENTS] = k + 1


# ---------------------------------------------------------------------------- release
@njit(cache=True)
def _insert(c: Core, i: int, lane: int, t: float) -> bool:
    """Place vehicle i at its release point if the gap to the vehicle ahead allows it.

    The release speed is kept if the gap exceeds ``s0 + v T``; otherwise the vehicle is
    released at the speed of the vehicle ahead if that gap suffices, else it waits. The
    initial fill (released at ``-warmup``) does not check gaps.
    """
    x, v = c.d_x[i], c.d_v[i]
    if c.d_t[i] > -c.consts[WARMUP] + 1e-9:
        j, best = -1, math.inf
        for k in range(c.x.size):
            in_lane = c.active[k] and (c.lane[k] == lane or c.target[k] == lane)
            if in_lane and x <= c.x[k] < best:
                j, best = k, c.x[k]
        if j >= 0:
            gap = c.x[j] - c.length[j] - x
            s0, T = c.matrix[2, i], c.matrix[1, i]
            if gap < s0 + v * T:
                v = min(v, c.v[j])
                if gap < s0 + v * T:
                    return False
    c.x[i], c.v[i], c.active[i] = x, v, True
    c.x_hist[:, i] = x
    c.v_hist[:, i] = v
    add_event(c, t, EV_INSERTION, i, -1, x, t - c.d_t[i])
    return True


@njit(cache=True)
def release(c: Core, t: float) -> None:
    """Insert due vehicles lane by lane; a blocked entry waits (and blocks its queue).
    Releasing twice at the same t is a no-op."""
    for lane in range(3):
        start, end = c.queue_start[lane], c.queue_start[lane + 1]
        pos = c.queue_pos[lane]
        while start + pos < end and c.d_t[c.queues[start + pos]] <= t + 1e-9:
            if not _insert(c, c.queues[start + pos], lane, t):
                break
            pos += 1
        c.queue_pos[lane] = pos


# ------------------------------------------------------------------------- perceive
@njit(cache=True, inline="always")
def follow_one(c: Core, i: int, leader: int, perceive: bool) -> float:
    """Car-following acceleration of i behind ``leader`` (-1: none), HDVs perceiving Eq. 2
    when ``perceive`` (reaction delays and estimation errors)."""
    has = leader >= 0
    lead = leader if has else i
    s = c.x[lead] - c.length[lead] - c.x[i] if has else math.inf
    v, vl, al = c.v[i], (c.v[lead] if has else c.v[i]), (c.a[lead] if has else 0.0)
    if perceive and c.is_hdv[i]:
        s, v, vl = perceive_one(
            c.x_hist, c.v_hist, c.w_gap, c.w_ttc, c.counters[STEP], i, leader, c.length[lead],
            c.consts[DT], c.taus, c.consts[GAP_ERROR], c.consts[TTC_ERROR], c.flags[ERRORS] > 0,
        )  # fmt: skip
    m = c.matrix[:, i]
    return follow_accel(s, v, vl, al, m[0], m[1], m[2], m[3], m[4], m[5], m[6], c.iidm[i])


@njit(cache=True)
def follow_many(c: Core, ids: np.ndarray, leaders: np.ndarray) -> np.ndarray:
    """:func:`follow_one` of each vehicle of ``ids`` behind its leader."""
    out = np.empty(ids.size)
    perceive = c.flags[PERCEIVE] > 0
    for k in range(ids.size):
        out[k] = follow_one(c, ids[k], leaders[k], perceive)
    return out


@njit(cache=True, inline="always")
def _centre(lane: int, width: float) -> float:
    return (lane - 1.0) * width


@njit(cache=True)
def lane_index(c: Core, ids: np.ndarray, changing: np.ndarray):
    """Sorted entries of this step: every vehicle in its lane and a changer also in the
    other lane its body overlaps (the target lane from its start, the origin lane while its
    body still overlaps it). Returns ``(vehicle, lane, key, rank, in_ori, in_tgt)``."""
    width = c.consts[WIDTH]
    n = ids.size
    n_ch = 0
    for k in range(n):
        n_ch += changing[k]
    veh = np.empty(n + n_ch, dtype=np.int64)
    lanes = np.empty(n + n_ch, dtype=np.int64)
    xs = np.empty(n + n_ch)
    in_ori = np.zeros(n, dtype=np.bool_)
    in_tgt = np.zeros(n, dtype=np.bool_)
    m = n
    for k in range(n):
        i = ids[k]
        veh[k], lanes[k], xs[k] = i, c.lane[i], c.x[i]
    for k in range(n):  # changers' second entries follow all first entries, in ids order
        i = ids[k]
        if not changing[k]:
            continue
        reach = 0.5 * (width + c.width[i])
        in_ori[k] = abs(c.y[i] - _centre(c.origin[i], width)) < reach
        in_tgt[k] = abs(c.y[i] - _centre(c.target[i], width)) < reach
        crossed = c.lane[i] == c.target[i]
        if crossed and not in_ori[k]:
            continue
        veh[m], lanes[m], xs[m] = i, (c.origin[i] if crossed else c.target[i]), c.x[i]
        m += 1
    vs, ls, ks, rank = sort_entries(veh[:m], lanes[:m], xs[:m])
    return vs, ls, ks, rank, in_ori, in_tgt


@njit(cache=True)
def step_accelerations(
    c: Core, ids: np.ndarray, t: float, following: np.ndarray, vv_fol: np.ndarray,
    vv_x: np.ndarray, vv_v: np.ndarray, vv_a: np.ndarray, vv_len: np.ndarray,
):  # fmt: skip
    """Accelerations of every active vehicle ``ids`` for this step, from one snapshot.

    Car following (Eq. 1/3, HDVs perceiving Eq. 2) behind the leader of the lane it drives
    in; a changer blends (Eq. 14) the accelerations behind its origin- and target-lane
    leaders and respects the leader of every lane its body overlaps; ramp vehicles that have
    not started merging stop at the acceleration-lane end unless they follow a live plan
    (``following``); commanded vehicles also follow their virtual leaders (rows ``vv_*``);
    every deceleration is limited to the emergency value; a scripted leader follows its
    profile exactly. Returns ``(acc, changing, vehicle, lane, key, rank, lead)``.
    """
    n = ids.size
    changing = np.empty(n, dtype=np.bool_)
    for k in range(n):
        changing[k] = c.origin[ids[k]] != c.target[ids[k]]
    vs, ls, ks, rank, in_ori, in_tgt = lane_index(c, ids, changing)
    perceive = c.flags[PERCEIVE] > 0
    lead = np.empty(n, dtype=np.int64)
    acc = np.empty(n)
    for k in range(n):
        i = ids[k]
        pos = rank[k]
        lead[k] = neighbour(vs, ls, pos + 1, ls[pos])
        if changing[k]:
            lead[k] = lookup_one(ks, ls, vs, c.origin[i], c.x[i])[0]
        acc[k] = follow_one(c, i, lead[k], perceive)
        if changing[k]:
            a_ori = acc[k]
            a_new = follow_one(c, i, lookup_one(ks, ls, vs, c.target[i], c.x[i])[0], perceive)
            psi = transition_psi(t - c.lc_t0[i], c.lc_dur[i], c.consts[GAMMA])
            b = blend(a_ori, a_new, psi)
            if in_ori[k]:
                b = min(b, a_ori)
            acc[k] = min(b, a_new) if in_tgt[k] else b
    accel_end = c.consts[ACCEL_END]
    for k in range(n):  # the acceleration-lane end, a static obstacle seen exactly
        i = ids[k]
        if c.lane[i] == RAMP and not changing[k] and not following[i]:
            m = c.matrix[:, i]
            a_stop = follow_accel(accel_end - c.x[i], c.v[i], 0.0, 0.0, m[0], m[1], m[2], m[3],
                                  m[4], m[5], m[6], c.iidm[i])  # fmt: skip
            acc[k] = min(acc[k], a_stop)
    if vv_fol.size:
        before = acc.copy()
        for r in range(vv_fol.size):  # a later row for the same follower replaces an earlier
            i = vv_fol[r]
            if vv_x[r] > c.x[i]:
                k = np.searchsorted(ids, i)
                m = c.matrix[:, i]
                a_v = follow_accel(vv_x[r] - vv_len[r] - c.x[i], c.v[i], vv_v[r], vv_a[r], m[0],
                                   m[1], m[2], m[3], m[4], m[5], m[6], c.iidm[i])  # fmt: skip
                acc[k] = min(before[k], a_v)
    dt = c.consts[DT]
    for k in range(n):
        i = ids[k]
        acc[k] = max(acc[k], -c.consts[EMERGENCY])
        if c.scripted[i]:  # a scripted profile is followed exactly
            target = np.interp(t + dt, c.profile[:, 0], c.profile[:, 1])
            acc[k] = (target - c.v[i]) / dt
    return acc, changing, vs, ls, ks, rank, lead


# --------------------------------------------------------------------------- decide
@njit(cache=True)
def _mobil(c, ids, cand_pos, lead, vs, ls, ks, rank, target, force):
    """MOBIL / gap acceptance (:func:`hcomc.sim.mobil.mobil_decide`) for the vehicles at
    positions ``cand_pos`` of ``ids``."""
    n = cand_pos.size
    cand = np.empty(n, dtype=np.int64)
    lanes = np.empty(n, dtype=np.int64)
    leader = np.empty(n, dtype=np.int64)
    follower = np.empty(n, dtype=np.int64)
    for k in range(n):
        p = cand_pos[k]
        cand[k], lanes[k], leader[k] = ids[p], c.lane[ids[p]], lead[p]
        follower[k] = neighbour(vs, ls, rank[p] - 1, ls[rank[p]])
    return mobil_decide(c.matrix, c.iidm, c.length, c.x, c.v, c.a, ks, ls, vs, cand, lanes,
                        leader, follower, target, force, c.lc_params)  # fmt: skip


@njit(cache=True)
def commanded_changes(
    c: Core, ids: np.ndarray, t: float, lead: np.ndarray, vs: np.ndarray, ls: np.ndarray,
    ks: np.ndarray, rank: np.ndarray, req_vehicle: np.ndarray, req_target: np.ndarray,
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
        pos = np.array([np.searchsorted(ids, i)])
        tgt = np.array([req_target[r]])
        chosen, _ = _mobil(c, ids, pos, lead, vs, ls, ks, rank, tgt, np.ones(1, dtype=np.bool_))
        if chosen.size:
            start_lane_changes(c, chosen, tgt, t, req_duration[r : r + 1])
            out[r] = 1
        elif c.x[req_vr[r]] >= req_release_x[r]:
            out[r] = -1
            add_event(c, t, EV_FALLBACK, req_vr[r], req_other[r], c.x[req_vr[r]], math.nan)
    return out


@njit(cache=True)
def discretionary_changes(
    c: Core, ids: np.ndarray, changing: np.ndarray, holding: np.ndarray, lead: np.ndarray,
    vs: np.ndarray, ls: np.ndarray, ks: np.ndarray, rank: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """MOBIL decisions of every vehicle free to change now (not changing, not scripted, not
    holding its lane for a plan; ramp vehicles on the acceleration lane only)."""
    sel = np.zeros(ids.size, dtype=np.bool_)
    for k in range(ids.size):
        i = ids[k]
        ramp = c.lane[i] == RAMP
        on_accel = ramp and c.consts[ACCEL_START] <= c.x[i] <= c.consts[ACCEL_END]
        sel[k] = not changing[k] and not c.scripted[i] and (not ramp or on_accel) and not holding[i]
    pos = np.flatnonzero(sel)
    target = np.empty(pos.size, dtype=np.int64)
    for k in range(pos.size):
        target[k] = MAIN_2 if c.lane[ids[pos[k]]] == MAIN_1 else MAIN_1
    force = np.zeros(pos.size, dtype=np.bool_)
    return _mobil(c, ids, pos, lead, vs, ls, ks, rank, target, force)


@njit(cache=True)
def start_lane_changes(
    c: Core, chosen: np.ndarray, target: np.ndarray, t: float, duration: np.ndarray
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


# ---------------------------------------------------------------------------- check
@njit(cache=True)
def check_collisions(c: Core, t: float, vs: np.ndarray, ls: np.ndarray) -> None:
    """Oriented-rectangle test (Eq. 7) of each entry against its next two leaders per lane;
    a pair is logged when its contact begins.

    A 1-D prefilter skips pairs whose x-extents cannot overlap: a rectangle whose front
    bumper centre is at x lies within ``[x - L - W/2, x + W/2]`` for any heading.
    """
    n = c.x.size
    codes = np.empty(4 * vs.size + 1, dtype=np.int64)
    m = 0
    for gap in (1, 2):
        for p in range(vs.size - gap):
            i, j = vs[p], vs[p + gap]
            if ls[p] != ls[p + gap] or i == j:
                continue
            if c.x[i] + 0.5 * c.width[i] < c.x[j] - c.length[j] - 0.5 * c.width[j]:
                continue
            if vehicle_pair_collides(
                c.x[i],
                c.y[i],
                c.heading[i],
                c.length[i],
                c.width[i],
                c.x[j],
                c.y[j],
                c.heading[j],
                c.length[j],
                c.width[j],
            ):
                codes[m] = min(i, j) * n + max(i, j)
                m += 1
    now = np.unique(codes[:m])
    before = c.colliding[: c.counters[N_COLLIDING]]
    for code in now:
        k = np.searchsorted(before, code)
        if k < before.size and before[k] == code:
            continue
        i, j = code // n, code % n
        add_event(c, t, EV_COLLISION, i, j, c.x[i], math.nan)
    c.colliding[: now.size] = now
    c.counters[N_COLLIDING] = now.size


# ------------------------------------------------------------------------ integrate
@njit(cache=True)
def integrate(c: Core, ids: np.ndarray, acc: np.ndarray) -> None:
    """Ballistic update; a vehicle that would reverse stops exactly at v = 0."""
    dt = c.consts[DT]
    for k in range(ids.size):
        i = ids[k]
        v0, ak = c.v[i], acc[k]
        v1 = v0 + ak * dt
        if v1 < 0.0:
            c.x[i] += -(v0 * v0) / (2.0 * ak)
            c.v[i] = 0.0
            c.a[i] = -v0 / dt
        else:
            c.x[i] += v0 * dt + 0.5 * ak * dt * dt
            c.v[i] = v1
            c.a[i] = ak


@njit(cache=True)
def lateral(c: Core, t: float) -> None:
    """Move changing vehicles along their quintic path; switch lane at the lane line."""
    width = c.consts[WIDTH]
    for i in range(c.x.size):
        if not c.active[i] or c.origin[i] == c.target[i]:
            continue
        x0, xf = c.lc_x0[i], c.lc_xf[i]
        y, dy_dx, _ = lateral_state(c.x[i], x0, xf, _centre(c.origin[i], width),
                                    _centre(c.target[i], width))  # fmt: skip
        c.y[i] = y
        c.heading[i] = math.atan(dy_dx)
        xi = (c.x[i] - x0) / (xf - x0)
        c.lane[i] = c.target[i] if xi >= 0.5 else c.origin[i]
        if xi >= 1.0:
            add_event(c, t, EV_LC_END, i, -1, c.x[i], c.target[i])
            if c.origin[i] == RAMP:
                add_event(c, t, EV_MERGE, i, -1, c.x[i], math.nan)
            c.lc_dur[i] = c.lc_duration[i]
            c.origin[i] = c.target[i]
            c.y[i] = _centre(c.target[i], width)
            c.heading[i] = 0.0


@njit(cache=True)
def bookkeeping(c: Core, ids: np.ndarray, t: float) -> None:
    """Exits past the road end; ramp vehicles waiting at the acceleration-lane end."""
    for i in ids:
        if c.x[i] - c.length[i] > c.consts[ROAD_LENGTH]:
            c.active[i] = False
            add_event(c, t, EV_EXIT, i, -1, c.x[i], math.nan)
    for i in ids:
        if (c.lane[i] == RAMP and c.origin[i] == c.target[i] and c.v[i] < _WAIT_SPEED
                and c.x[i] > c.consts[ACCEL_END] - _WAIT_ZONE and not c.waited[i]):  # fmt: skip
            c.waited[i] = True
            add_event(c, t, EV_WAIT, i, -1, c.x[i], math.nan)


@njit(cache=True)
def step_finish(
    c: Core, ids: np.ndarray, t: float, acc: np.ndarray, vs: np.ndarray, ls: np.ndarray
) -> None:
    """Collisions, integration, lateral motion, exits, the HDVs' error processes (one row of
    pre-drawn innovations per step with active vehicles) and the perception history."""
    check_collisions(c, t, vs, ls)
    integrate(c, ids, acc)
    lateral(c, t)
    bookkeeping(c, ids, t)
    if c.flags[ERRORS] > 0:
        hdv = ids[c.is_hdv[ids]]
        xi = c.innov[c.counters[INNOV_CURSOR]]
        c.counters[INNOV_CURSOR] += 1
        advance_errors_of(c.w_gap, c.w_ttc, hdv, xi, c.consts[DECAY], c.consts[KICK])
    push_history(c)


@njit(cache=True)
def push_history(c: Core) -> None:
    """End of a step: count it and store the state in the perception ring buffer."""
    c.counters[STEP] += 1
    row = c.counters[STEP] % c.x_hist.shape[0]
    c.x_hist[row] = c.x
    c.v_hist[row] = c.v


# --------------------------------------------------------------------------- record
@njit(cache=True)
def record_row(
    c: Core, k: int, t: float, lt: np.ndarray, lx: np.ndarray, ly: np.ndarray,
    lv: np.ndarray, la: np.ndarray, lh: np.ndarray, ll: np.ndarray, lact: np.ndarray,
) -> None:  # fmt: skip
    """Write log row k; inactive vehicles get NaN (floats) and -1 (lane)."""
    lt[k] = t
    for i in range(c.x.size):
        on = c.active[i]
        lact[k, i] = on
        lx[k, i] = c.x[i] if on else np.nan
        ly[k, i] = c.y[i] if on else np.nan
        lv[k, i] = c.v[i] if on else np.nan
        la[k, i] = c.a[i] if on else np.nan
        lh[k, i] = c.heading[i] if on else np.nan
        ll[k, i] = c.lane[i] if on else -1


# ----------------------------------------------------------------------------- loop
@njit(cache=True)
def needs_python(c: Core) -> bool:
    """Whether this step needs the engine's Python side: a live plan, game-confirmed lane
    changes, or a ramp vehicle entering the control zone (key vehicles, a plan)."""
    if c.flags[HAS_PLANS] > 0 or c.flags[CAV_GAME] > 0:
        return True
    for i in range(c.x.size):
        if (
            c.active[i]
            and c.lane[i] == RAMP
            and c.origin[i] == c.target[i]
            and c.x[i] >= c.consts[CZ_START]
            and (not c.identified[i] or (c.flags[CONTROLLER] > 0 and not c.planned[i]))
        ):
            return True  # fmt: skip
    return False


@njit(cache=True)
def step_alone(c: Core, t: float) -> None:
    """One whole step after release with no controller inputs (the fast path)."""
    ids = np.flatnonzero(c.active)
    if ids.size == 0:
        push_history(c)
        return
    c.counters[VEHICLE_STEPS] += ids.size
    no_int = np.empty(0, dtype=np.int64)
    no_float = np.empty(0)
    free = np.zeros(c.x.size, dtype=np.bool_)
    acc, changing, vs, ls, ks, rank, lead = step_accelerations(
        c, ids, t, free, no_int, no_float, no_float, no_float, no_float
    )
    if (c.counters[STEP] % c.flags[DECIDE_EVERY] == 0) and c.flags[PLATOON] == 0:
        chosen, target = discretionary_changes(c, ids, changing, free, lead, vs, ls, ks, rank)
        start_lane_changes(c, chosen, target, t, no_float)
    step_finish(c, ids, t, acc, vs, ls)


@njit(cache=True)
def run_steps(
    c: Core, stop: int, log_rows: bool, lt: np.ndarray, lx: np.ndarray, ly: np.ndarray,
    lv: np.ndarray, la: np.ndarray, lh: np.ndarray, ll: np.ndarray, lact: np.ndarray,
) -> int:  # fmt: skip
    """Advance until step ``stop`` or until Python is needed; returns why it stopped.

    With ``log_rows`` every ``log_every``-th step after the warm-up writes a log row.
    """
    dt, warmup = c.consts[DT], c.consts[WARMUP]
    margin = 8 * c.x.size + 64
    while c.counters[STEP] < stop:
        if c.counters[N_EVENTS] + margin > c.ev_t.size:
            return FLUSH
        if c.flags[ERRORS] > 0 and c.counters[INNOV_CURSOR] >= c.innov.shape[0]:
            return REFILL
        t = -warmup + c.counters[STEP] * dt
        release(c, t)
        if needs_python(c):
            return NEED_PYTHON
        step_alone(c, t)
        k = c.counters[STEP] - c.flags[N_WARMUP]
        if log_rows and k > 0 and k % c.flags[LOG_EVERY] == 0:
            t_row = -warmup + c.counters[STEP] * dt
            record_row(c, c.counters[ROWS], t_row, lt, lx, ly, lv, la, lh, ll, lact)
            c.counters[ROWS] += 1
    return DONE
