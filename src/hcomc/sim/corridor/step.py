"""The compiled corridor step: lane entries, car following, lane-change decisions.

A step at time t: insert due vehicles (:mod:`hcomc.sim.corridor.motion`), sort the lane
entries (:func:`sort_entries`), take every vehicle's acceleration (:func:`accelerations`),
decide lane changes (:func:`decide`), then move, measure and finish (motion).

**Lane entries.** Every vehicle on the road is an entry (vehicle, code) in the lane it drives
in and, while it changes lane, also in its target lane, so that followers in both lanes see
it during the manoeuvre. Entries are sorted by ``code * OFFSET + x``; a vehicle's leader in a
lane is the next entry of that lane. They stay nearly sorted from step to step, so an
insertion sort is linear.

**Car following.** Each vehicle drives the IDM (paper Eq. 1, :func:`hcomc.equations.car_following.
follow_accel_given`) with its desired speed capped by the speed limit, behind the nearest
leader over its entries (the strictest acceleration wins), and brakes for the point where it
must have left its lane (:func:`hcomc.sim.corridor.lanes.stop_point`) as for a standing
obstacle once that point is within its stopping distance ``s0 + v T + v^2 / (2 b)``;
accelerations are bounded below by ``-emergency_decel``.

**Lane changes.** A change the route needs (:func:`hcomc.sim.corridor.lanes.mandatory_target`)
is taken as soon as it is safe, checked every step; a discretionary change between mainline
lanes follows MOBIL (Kesting, Treiber & Helbing 2007) with a keep-right bias, checked every
``decision_interval``. Safe means: bumper gaps to the new leader and follower of at least
``min_gap``, neither the vehicle nor its new follower braking harder than ``safe_decel``
behind the other (a needed change within ``urgent_distance`` of its last point accepts up to
``emergency_decel``, linearly), and a clear path (no standing leader within 3 lengths plus
``min_gap``). Changes are taken downstream first; a vehicle that is part of a change accepted
in this step (changer, new leader or new follower) takes part in no other.

**Merge control.** A ramp vehicle following a live merge plan (``s.following``) neither
brakes for the end of its acceleration lane nor takes its merge by the rule above: the plan
commands it (:mod:`hcomc.sim.corridor.plans`, whose changes are started before these); the
vehicles a plan holds in their lane (``s.holding``) make no discretionary change.

**Agents' vehicles** (a learning environment's; ``counters[C_AGENTS]`` > 0) drive at the
acceleration they are given (``s.agent_acc``, bounded below by ``-emergency_decel``; NaN: the
vehicle's own model) and change lane only when told (``s.agent_lane``, the target code,
taken at once without any safety check: the agent answers for it); they neither brake for
the end of their lane nor change lane on their own.
"""

from __future__ import annotations

import math

from hcomc._jit import borrow_all, kernel
from hcomc.equations.car_following import follow_accel_given, free_term
from hcomc.equations.incentive import mobil_incentive
from hcomc.sim.corridor.lanes import mandatory_target, section_at, speed_limit, stop_point
from hcomc.sim.corridor.layout import Layout
from hcomc.sim.corridor.state import (
    C_AGENTS,
    C_DECIDE_EVERY,
    C_ENTRIES,
    C_LANE_CHANGES,
    C_ON_ROAD,
    C_SORTED,
    OFFSET,
    ON_ROAD,
    P_BIAS,
    P_EMERGENCY,
    P_LC_DURATION,
    P_LOOKAHEAD,
    P_MIN_GAP,
    P_POLITENESS,
    P_SAFE_DECEL,
    P_THRESHOLD,
    P_URGENT,
    State,
    Vehicles,
)  # fmt: skip

__all__ = ["accelerations", "decide", "sort_entries"]


@kernel
def sort_entries(s: State) -> None:
    """Drop the entries of vehicles gone or of lanes left, sort the rest, and list the
    vehicles on the road (``ids``) and the most upstream vehicle of each code."""
    s = borrow_all(s)
    e_veh, e_code, e_key, counters = s.e_veh, s.e_code, s.e_key, s.counters
    m = 0
    for p in range(counters[C_ENTRIES]):
        i, c = e_veh[p], e_code[p]
        if s.status[i] == ON_ROAD and (c == s.code[i] or c == s.target[i]):
            e_veh[m], e_code[m], e_key[m] = i, c, c * OFFSET + s.x[i]
            m += 1
    for p in range(1, m):  # insertion sort: linear for entries that stay nearly sorted
        i, c, key = e_veh[p], e_code[p], e_key[p]
        q = p - 1
        while q >= 0 and e_key[q] > key:
            e_veh[q + 1], e_code[q + 1], e_key[q + 1] = e_veh[q], e_code[q], e_key[q]
            q -= 1
        e_veh[q + 1], e_code[q + 1], e_key[q + 1] = i, c, key
    counters[C_ENTRIES] = counters[C_SORTED] = m
    s.code_first[:] = -1
    n = 0
    for p in range(m - 1, -1, -1):
        s.code_first[e_code[p]] = e_veh[p]
    for p in range(m):
        if e_code[p] == s.code[e_veh[p]]:
            s.ids[n] = e_veh[p]
            n += 1
    counters[C_ON_ROAD] = n


@kernel(inline="always")
def follow_behind(veh: Vehicles, s: State, i: int, j: int) -> float:
    """IDM acceleration of vehicle i behind vehicle j (free road for j = -1; 0 for i = -1)."""
    if i < 0:
        return 0.0
    if j < 0:
        gap, vl = math.inf, s.v[i]
    else:
        gap, vl = s.x[j] - veh.length[j] - s.x[i], s.v[j]
    return follow_accel_given(gap, s.v[i], vl, 0.0, s.v0e[i], veh.T[i], veh.s0[i], veh.a[i],
                              veh.b[i], 0.0, False, s.free[i])  # fmt: skip


@kernel
def accelerations(road: Layout, veh: Vehicles, s: State) -> None:
    """Every vehicle's acceleration for this step into ``s.acc`` (module docstring)."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    n, m = s.counters[C_ON_ROAD], s.counters[C_SORTED]
    for k in range(n):
        i = s.ids[k]
        s.v0e[i] = min(veh.v0[i], speed_limit(road, s.code[i], s.x[i]))
        s.free[i] = free_term(s.v[i], s.v0e[i], veh.a[i], veh.b[i], veh.delta[i], False)
        s.acc[i] = math.inf
    for p in range(m):
        i, lead = s.e_veh[p], -1
        if p + 1 < m and s.e_code[p + 1] == s.e_code[p]:
            lead = s.e_veh[p + 1]
        s.acc[i] = min(s.acc[i], follow_behind(veh, s, i, lead))
    for k in range(n):
        i = s.ids[k]
        if s.target[i] == s.code[i] and not s.following[i]:
            gap = stop_point(road, s.code[i], s.x[i], s.exit_code[i]) - s.x[i]
            v = s.v[i]
            if gap < veh.s0[i] + v * veh.T[i] + v * v / (2.0 * veh.b[i]):
                a_stop = follow_accel_given(
                    gap, v, 0.0, 0.0, s.v0e[i], veh.T[i], veh.s0[i], veh.a[i], veh.b[i],
                    0.0, False, s.free[i],
                )  # fmt: skip
                s.acc[i] = min(s.acc[i], a_stop)
        s.acc[i] = max(s.acc[i], -s.params[P_EMERGENCY])
    if s.counters[C_AGENTS]:
        for k in range(n):
            i = s.ids[k]
            if not math.isnan(s.agent_acc[i]):
                s.acc[i] = max(s.agent_acc[i], -s.params[P_EMERGENCY])


@kernel(inline="always")
def neighbours_in(s: State, code: int, x: float) -> tuple[int, int]:
    """Leader and follower a vehicle at x would have in lane ``code`` (-1 if none)."""
    m, value = s.counters[C_SORTED], code * OFFSET + x
    lo, hi = 0, m
    while lo < hi:  # first sorted entry with a larger key
        mid = (lo + hi) // 2
        if value < s.e_key[mid]:
            hi = mid
        else:
            lo = mid + 1
    lead = s.e_veh[lo] if lo < m and s.e_code[lo] == code else -1
    follow = s.e_veh[lo - 1] if lo > 0 and s.e_code[lo - 1] == code else -1
    return lead, follow


@kernel(inline="always")
def gaps_clear(veh: Vehicles, s: State, i: int, old_lead: int, lead: int, fol: int,
                step: int) -> bool:  # fmt: skip
    """The gap criteria of a change of i between ``lead`` and ``fol`` (module docstring)."""
    if s.busy[i] == step or (lead >= 0 and s.busy[lead] == step):
        return False
    if fol >= 0 and s.busy[fol] == step:
        return False
    min_gap, x = s.params[P_MIN_GAP], s.x[i]
    if lead >= 0 and s.x[lead] - veh.length[lead] - x < min_gap:
        return False
    if fol >= 0 and x - veh.length[i] - s.x[fol] < min_gap:
        return False
    if old_lead >= 0 and s.v[old_lead] < 1.0:
        return s.x[old_lead] - veh.length[old_lead] - x >= 3.0 * veh.length[i] + min_gap
    return True


@kernel(inline="always")
def start_change(s: State, i: int, code: int, lead: int, fol: int, t: float, step: int,
                 duration: float) -> None:  # fmt: skip
    """Start the change of i into ``code``, lasting ``duration`` [s] (a new entry there)."""
    s.target[i], s.lc_start[i], s.lc_dur[i] = code, t, duration
    s.busy[i] = step
    if lead >= 0:
        s.busy[lead] = step
    if fol >= 0:
        s.busy[fol] = step
    if duration <= 0.0:  # instantaneous: ends in this step's bookkeeping
        s.lc_start[i] = t - 1.0
    p = s.counters[C_ENTRIES]
    s.e_veh[p], s.e_code[p], s.e_key[p] = i, code, code * OFFSET + s.x[i]
    s.counters[C_ENTRIES] = p + 1
    s.counters[C_LANE_CHANGES] += 1
    first = s.code_first[code]
    if first < 0 or s.x[i] < s.x[first]:
        s.code_first[code] = i


@kernel
def decide(road: Layout, veh: Vehicles, s: State, t: float, step: int) -> None:
    """Lane changes started in this step (module docstring)."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    m, every = s.counters[C_SORTED], s.counters[C_DECIDE_EVERY]
    b_safe, b_max = s.params[P_SAFE_DECEL], s.params[P_EMERGENCY]
    urgent, lookahead = s.params[P_URGENT], s.params[P_LOOKAHEAD]
    agents = s.counters[C_AGENTS] != 0
    if agents:
        _agent_changes(s, t, step)
    for p in range(m - 1, -1, -1):  # downstream first
        i, c = s.e_veh[p], s.e_code[p]
        if c != s.code[i] or s.target[i] != c or (agents and not math.isnan(s.agent_acc[i])):
            continue
        x = s.x[i]
        lead = s.e_veh[p + 1] if p + 1 < m and s.e_code[p + 1] == c else -1
        if s.following[i]:
            continue  # its merge is the plan's (hcomc.sim.corridor.plans)
        tgt, left = mandatory_target(road, c, x, s.exit_code[i], lookahead)
        if tgt >= 0:
            ln, fn = neighbours_in(s, tgt, x)
            if not gaps_clear(veh, s, i, lead, ln, fn, step):
                continue
            urgency = max(0.0, 1.0 - left / urgent) if urgent > 0 else 0.0
            b_ok = b_safe + (b_max - b_safe) * urgency
            if follow_behind(veh, s, i, ln) >= -b_ok and follow_behind(veh, s, fn, i) >= -b_ok:
                start_change(s, i, tgt, ln, fn, t, step, s.params[P_LC_DURATION])
            continue
        if c >= road.lane_end.shape[0] or (step + i) % every != 0 or s.holding[i]:
            continue
        _discretionary(road, veh, s, p, lead, t, step)


@kernel(inline="always")
def _agent_changes(s: State, t: float, step: int) -> None:
    """Start the lane changes agents' vehicles were told to take (module docstring)."""
    for k in range(s.counters[C_ON_ROAD]):
        i = s.ids[k]
        code = s.agent_lane[i]
        if code < 0:
            continue
        s.agent_lane[i] = -1
        if s.status[i] != ON_ROAD or s.target[i] != s.code[i]:
            continue
        lead, fol = neighbours_in(s, code, s.x[i])
        start_change(s, i, code, lead, fol, t, step, s.params[P_LC_DURATION])


@kernel(inline="always")
def _discretionary(road: Layout, veh: Vehicles, s: State, p: int, lead: int, t: float,
                   step: int) -> None:  # fmt: skip
    """MOBIL between mainline lanes for the vehicle of sorted entry p (module docstring)."""
    i, c = s.e_veh[p], s.e_code[p]
    x = s.x[i]
    fo = s.e_veh[p - 1] if p > 0 and s.e_code[p - 1] == c else -1
    sec = section_at(road.sec_x0, x)
    lookahead, b_safe = s.params[P_LOOKAHEAD], s.params[P_SAFE_DECEL]
    exit_code = s.exit_code[i]
    a_c = follow_behind(veh, s, i, lead)
    best, best_gain, best_lead, best_fol = -1, 0.0, -1, -1
    for side in (-1, 1):
        tgt = c + side
        if tgt < 0 or tgt >= road.sec_lanes[sec] or road.lane_end[tgt, sec] - x < lookahead:
            continue
        if side > 0 and exit_code >= 0 and road.code_x1[exit_code] - x < (c + 2) * lookahead:
            continue  # its exit is near: no move away from it
        ln, fn = neighbours_in(s, tgt, x)
        if not gaps_clear(veh, s, i, lead, ln, fn, step):
            continue
        acc1, acc3 = follow_behind(veh, s, i, ln), follow_behind(veh, s, fn, i)
        if acc1 < -b_safe or acc3 < -b_safe:
            continue
        acc2, acc4, acc5 = (
            follow_behind(veh, s, fn, ln),
            follow_behind(veh, s, fo, i),
            follow_behind(veh, s, fo, lead),
        )
        bias = s.params[P_BIAS] if side > 0 else -s.params[P_BIAS]
        gain = mobil_incentive(acc1 - a_c, (acc3 - acc2) + (acc5 - acc4), s.params[P_POLITENESS])
        gain -= s.params[P_THRESHOLD] + bias
        if gain > best_gain:
            best, best_gain, best_lead, best_fol = tgt, gain, ln, fn
    if best >= 0:
        start_change(s, i, best, best_lead, best_fol, t, step, s.params[P_LC_DURATION])
