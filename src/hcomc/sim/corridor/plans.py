"""Merge control on a corridor, inside the compiled step: merge events and live plans.

**Merge events.** When a ramp vehicle (VR) on lane j = 0 of an on-ramp, keeping its lane,
reaches the ramp's control zone (``ramp.x - control_zone_length``), its key vehicles are
identified as in paper Section II-A on the ramp's *local view*: the ramp lane is
:attr:`~hcomc.road.Lane.RAMP`, mainline lane 0 (the one the ramp joins) ``MAIN_1`` and
mainline lane 1 ``MAIN_2``; a vehicle counts in the lane it drives in up to the lateral
midpoint of a change and in its target lane after it, and vehicles on other lanes are not
in the view (:func:`fill_view`, then :func:`hcomc.control.key_vehicles.key_vehicle_indices`, the
function the controllers use). This happens in every run, with or without a controller, so
runs compare the same vehicles. The event's window runs from then until ``window_after``
seconds after VR's merge is complete (or VR leaves the road); over it
:func:`track_events` keeps the surrogate safety of VR, VMC, VMR and VNR, each against its
leader in every lane it occupies while it closes in at
:data:`~hcomc.safety.surrogate.CLOSING_SPEED` or more (as :mod:`hcomc.metrics.surrogate` on
the paper's scene): the least time to collision, the largest deceleration rate to avoid a
crash (DRAC), the hardest braking, and VMC's lowest speed.

**Live plans** are rows of the plan table of :mod:`hcomc.sim.step.plans` (same columns), in
``plan_int`` / ``plan_f`` of the state; Python enters only to decide (a new event, or a plan
due for a replan every ``control.replan_period`` s: :func:`due_replans`). They are executed
here by the rules of :mod:`hcomc.sim.plan_execution`:

* a CAV VR the plan commands follows its virtual leader VV0 and does not brake for the end
  of the acceleration lane; from the merge position on it starts its change (with the plan's
  duration) as soon as the corridor's safety criterion holds, until it could no longer stop
  before the lane's end at ``safe_decel``: then the plan is *released* and VR merges by gap
  acceptance, as an uncontrolled vehicle does;
* longitudinal mode: the commanded VMC follows the nearer of its real leader and VV1;
* lateral mode: the commanded VMC changes to mainline lane 1 at once if that is safe (else
  the plan is released), and a commanded VNR follows VV2 within the horizon;
* commanded vehicles and the CAV key vehicles of a live plan make no discretionary change;
  a plan ends when VR's merge is complete, or VR or VMC has left the road or the mainline.

A vehicle is commanded by at most one live plan: the rule is kept where plans enter the
table (:mod:`hcomc.sim.corridor.control`).
"""

from __future__ import annotations

import math

from hcomc._jit import borrow_all, kernel
from hcomc.control.key_vehicles import key_vehicle_indices
from hcomc.equations.car_following import follow_accel_given
from hcomc.equations.safety import stopping_distance
from hcomc.equations.virtual_vehicle import cubic_point
from hcomc.road import VMC, VMR, VNR, VR, Lane
from hcomc.safety.surrogate import CLOSING_SPEED
from hcomc.sim.corridor.lanes import section_at
from hcomc.sim.corridor.layout import KIND_MAIN, KIND_ON, Layout
from hcomc.sim.corridor.state import (
    C_CONTROLLED,
    C_ON_ROAD,
    C_OPEN,
    C_PENDING,
    C_PLANS,
    ON_ROAD,
    P_EMERGENCY,
    P_LC_DURATION,
    P_REPLAN,
    P_SAFE_DECEL,
    P_WINDOW,
    State,
    Vehicles,
)  # fmt: skip
from hcomc.sim.corridor.step import follow_behind, gaps_clear, neighbours_in, start_change
from hcomc.sim.step.plans import (
    F_HORIZON,
    F_MERGE_X,
    F_T0,
    F_VR_DURATION,
    F_VV0,
    F_VV1,
    F_VV2,
    LATERAL,
    LONGITUDINAL,
    P_HAS_VV0,
    P_HAS_VV1,
    P_HAS_VV2,
    P_MODE,
    P_RELEASED,
    P_VMC,
    P_VMC_CMD,
    P_VMC_STARTED,
    P_VMF,
    P_VNR,
    P_VNR_CMD,
    P_VR,
    P_VR_CMD,
    P_VR_STARTED,
    compact_plans,
    replan_due,
    vr_following,
)  # fmt: skip

__all__ = [
    "due_replans", "execute", "fill_view", "finish_plans", "identify", "mark_commanded",
    "track_events", "virtual_leaders",
]  # fmt: skip

_RAMP, _MAIN_1, _MAIN_2 = int(Lane.RAMP), int(Lane.MAIN_1), int(Lane.MAIN_2)


# --------------------------------------------------------------------- merge events
@kernel(inline="always")
def _lane_now(s: State, i: int, t: float) -> int:
    """The lane code vehicle i counts in at t: its target from the middle of a change on."""
    if s.target[i] != s.code[i] and t - s.lc_start[i] >= 0.5 * s.lc_dur[i]:
        return s.target[i]
    return s.code[i]


@kernel
def fill_view(s: State, ramp_code: int, t: float) -> None:
    """``view_lane`` / ``view_active``: the local view of the on-ramp whose lane j = 0 is
    ``ramp_code`` (module docstring), over the vehicles on the road."""
    s = borrow_all(s)
    s.view_active[:] = False
    for k in range(s.counters[C_ON_ROAD]):
        i = s.ids[k]
        if s.status[i] != ON_ROAD:
            continue
        c = _lane_now(s, i, t)
        lane = _RAMP if c == ramp_code else _MAIN_1 if c == 0 else _MAIN_2 if c == 1 else -1
        if lane >= 0:
            s.view_lane[i], s.view_active[i] = lane, True


@kernel
def identify(s: State, t: float) -> None:
    """Open a merge event for each VR that reached its control zone by t (module docstring);
    with a controller, list it for a first plan."""
    s = borrow_all(s)
    for k in range(s.counters[C_ON_ROAD]):
        i = s.ids[k]
        c = s.code[i]
        if s.status[i] != ON_ROAD or c != s.target[i] or not s.x[i] >= s.zone[c]:
            continue  # a nan zone (no on-ramp lane j = 0) compares False
        if not math.isnan(s.ev_t[i]):
            continue
        fill_view(s, c, t)
        group = key_vehicle_indices(s.x, s.view_lane, s.view_active, i, _MAIN_1, _MAIN_2)
        s.ev_t[i] = t
        s.ev_group[i, :] = group
        vmc = group[VMC]
        if vmc >= 0:
            s.ev_vmc_v[i] = s.ev_vmc_min_v[i] = s.v[vmc]
        s.ev_open[s.counters[C_OPEN]] = i
        s.counters[C_OPEN] += 1
        if s.counters[C_CONTROLLED]:
            s.pending[s.counters[C_PENDING]] = i
            s.counters[C_PENDING] += 1


@kernel(inline="always")
def _watch(veh: Vehicles, s: State, ev: int, i: int, code: int) -> None:
    """Fold vehicle i's closing on its leader in lane ``code`` into event ``ev``."""
    lead = neighbours_in(s, code, s.x[i])[0]
    if lead < 0:
        return
    closing = s.v[i] - s.v[lead]
    if closing < CLOSING_SPEED:
        return
    gap = s.x[lead] - veh.length[lead] - s.x[i]
    s.ev_min_ttc[ev] = min(s.ev_min_ttc[ev], max(gap, 0.0) / closing)
    s.ev_max_drac[ev] = max(s.ev_max_drac[ev], closing * closing / (2.0 * max(gap, 1e-3)))


@kernel
def track_events(veh: Vehicles, s: State, t: float) -> None:
    """Update the surrogate safety of every open event at t (entries sorted at t); close
    the events whose window ended."""
    veh, s = borrow_all(veh), borrow_all(s)
    window, m = s.params[P_WINDOW], 0
    for k in range(s.counters[C_OPEN]):
        ev = s.ev_open[k]
        if s.status[ev] != ON_ROAD or s.merge_t[ev] + window < t:
            continue  # a nan merge time compares False: VR is still merging
        s.ev_open[m] = ev
        m += 1
        for role in (VR, VMC, VMR, VNR):
            i = s.ev_group[ev, role]
            if i < 0 or s.status[i] != ON_ROAD:
                continue
            _watch(veh, s, ev, i, s.code[i])
            if s.target[i] != s.code[i]:
                _watch(veh, s, ev, i, s.target[i])
            s.ev_max_decel[ev] = max(s.ev_max_decel[ev], -s.a[i])
            if role == VMC:
                s.ev_vmc_min_v[ev] = min(s.ev_vmc_min_v[ev], s.v[i])
    s.counters[C_OPEN] = m


# ----------------------------------------------------------------------- live plans
@kernel
def due_replans(s: State, t: float) -> None:
    """List the VRs whose live plan is due for a replan at t (VR on its ramp keeping its
    lane, :func:`hcomc.sim.step.plans.replan_due`)."""
    s = borrow_all(s)
    pi, pf, period = s.plan_int, s.plan_f, s.params[P_REPLAN]
    for k in range(s.counters[C_PLANS]):
        vr = pi[k, P_VR]
        if s.status[vr] != ON_ROAD or s.code[vr] != s.target[vr] or math.isnan(s.zone[s.code[vr]]):
            continue
        if replan_due(
            pi[k, P_VR_CMD] != 0, pi[k, P_VR_STARTED] != 0, pi[k, P_VMC_STARTED] != 0,
            pi[k, P_RELEASED] != 0, pf[k, F_T0], pf[k, F_MERGE_X], t, period, s.x[vr], s.v[vr],
        ):  # fmt: skip
            s.pending[s.counters[C_PENDING]] = vr
            s.counters[C_PENDING] += 1


@kernel
def mark_commanded(veh: Vehicles, s: State) -> None:
    """``following`` and ``holding`` of the vehicles on the road, from the live plans."""
    veh, s = borrow_all(veh), borrow_all(s)
    for k in range(s.counters[C_ON_ROAD]):
        i = s.ids[k]
        s.following[i] = s.holding[i] = False
    pi = s.plan_int
    for k in range(s.counters[C_PLANS]):
        if vr_following(pi, k):
            s.following[pi[k, P_VR]] = s.holding[pi[k, P_VR]] = True
        if pi[k, P_VMC_CMD]:
            s.holding[pi[k, P_VMC]] = True
        if pi[k, P_VNR_CMD]:
            s.holding[pi[k, P_VNR]] = True
        for role in range(P_VMC, P_VNR + 1):
            j = pi[k, role]
            if j >= 0 and veh.cav[j]:
                s.holding[j] = True


@kernel(inline="always")
def _behind_virtual(veh: Vehicles, s: State, i: int, x: float, v: float, length: float) -> None:
    """Vehicle i's acceleration, capped by the IDM behind a virtual vehicle at (x, v)."""
    gap = x - length - s.x[i]
    acc = follow_accel_given(gap, s.v[i], v, 0.0, s.v0e[i], veh.T[i], veh.s0[i], veh.a[i],
                             veh.b[i], 0.0, False, s.free[i])  # fmt: skip
    s.acc[i] = max(min(s.acc[i], acc), -s.params[P_EMERGENCY])


@kernel(inline="always")
def _virtual(s: State, k: int, col: int, tau: float, after: int) -> tuple[bool, float, float]:
    """(exists, x, v) of plan k's virtual vehicle at column ``col``: its cubic within the
    horizon, then vehicle ``after``'s state (-1: it has ended)."""
    pf = s.plan_f
    if tau <= pf[k, F_HORIZON]:
        xv, vv, _ = cubic_point(pf[k, col], pf[k, col + 1], pf[k, col + 2], pf[k, col + 3], tau)
        return True, xv, vv
    if after >= 0:
        return True, s.x[after], s.v[after]
    return False, 0.0, 0.0


@kernel
def virtual_leaders(veh: Vehicles, s: State, t: float) -> None:
    """Cap the accelerations of the vehicles following a virtual vehicle (VV0, VV1, VV2 as
    :func:`hcomc.sim.step.plans.virtual_rows`)."""
    veh, s = borrow_all(veh), borrow_all(s)
    pi = s.plan_int
    for k in range(s.counters[C_PLANS]):
        tau = t - s.plan_f[k, F_T0]
        vr, vmc, vmf = pi[k, P_VR], pi[k, P_VMC], pi[k, P_VMF]
        if vr_following(pi, k) and pi[k, P_HAS_VV0] and vmf >= 0:
            ok, xv, vv = _virtual(s, k, F_VV0, tau, vmf)
            if ok:
                _behind_virtual(veh, s, vr, xv, vv, veh.length[vmf])
        if pi[k, P_VMC_CMD] and pi[k, P_MODE] == LONGITUDINAL and pi[k, P_HAS_VV1]:
            ok, xv, vv = _virtual(s, k, F_VV1, tau, vr)
            if ok and s.status[vmc] == ON_ROAD:
                _behind_virtual(veh, s, vmc, xv, vv, veh.length[vr])
        if pi[k, P_VNR_CMD] and pi[k, P_HAS_VV2] and s.status[pi[k, P_VNR]] == ON_ROAD:
            ok, xv, vv = _virtual(s, k, F_VV2, tau, -1)
            if ok:
                _behind_virtual(veh, s, pi[k, P_VNR], xv, vv, veh.length[vmc])


@kernel(inline="always")
def _try_change(road: Layout, veh: Vehicles, s: State, i: int, tgt: int, t: float, step: int,
                duration: float) -> bool:  # fmt: skip
    """Start i's change into ``tgt`` if the lane is there and the corridor's safety
    criterion holds (gaps, ``safe_decel`` for i and its new follower)."""
    c, x = s.code[i], s.x[i]
    if tgt < 0 or s.target[i] != c:
        return False
    if road.code_kind[tgt] == KIND_MAIN and tgt >= road.sec_lanes[section_at(road.sec_x0, x)]:
        return False
    lead = neighbours_in(s, c, x)[0]
    ln, fn = neighbours_in(s, tgt, x)
    if not gaps_clear(veh, s, i, lead, ln, fn, step):
        return False
    b_safe = s.params[P_SAFE_DECEL]
    if follow_behind(veh, s, i, ln) < -b_safe or follow_behind(veh, s, fn, i) < -b_safe:
        return False
    start_change(s, i, tgt, ln, fn, t, step, duration)
    return True


@kernel
def execute(road: Layout, veh: Vehicles, s: State, t: float, step: int) -> None:
    """Start the lane changes the live plans command (module docstring)."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    pi, pf = s.plan_int, s.plan_f
    default = s.params[P_LC_DURATION]
    for k in range(s.counters[C_PLANS]):
        vr, vmc = pi[k, P_VR], pi[k, P_VMC]
        if pi[k, P_MODE] == LATERAL and pi[k, P_VMC_CMD] and not pi[k, P_VMC_STARTED]:
            if _try_change(road, veh, s, vmc, 1, t, step, default):
                pi[k, P_VMC_STARTED] = 1
            else:
                pi[k, P_VMC_CMD] = pi[k, P_VNR_CMD] = 0
                pi[k, P_RELEASED] = 1
                s.ev_released[vr] = True
        c = s.code[vr]
        if not vr_following(pi, k) or c != s.target[vr] or road.code_kind[c] != KIND_ON:
            continue
        if s.x[vr] < pf[k, F_MERGE_X]:
            continue
        duration = pf[k, F_VR_DURATION]
        if _try_change(road, veh, s, vr, road.code_left[c], t, step,
                       default if math.isnan(duration) else duration):  # fmt: skip
            pi[k, P_VR_STARTED] = 1
            continue
        stop = stopping_distance(s.v[vr], s.params[P_SAFE_DECEL], veh.s0[vr])
        if s.x[vr] >= road.code_x1[c] - stop:
            pi[k, P_RELEASED] = 1
            s.ev_released[vr] = True


@kernel
def finish_plans(road: Layout, s: State) -> None:
    """Drop the plans whose merge is complete or whose VR or VMC left the road or the
    mainline; the others keep their order."""
    road, s = borrow_all(road), borrow_all(s)
    pi, n = s.plan_int, s.counters[C_PLANS]
    for k in range(n):
        vr, vmc = pi[k, P_VR], pi[k, P_VMC]
        merged = road.code_kind[s.code[vr]] == KIND_MAIN and s.code[vr] == s.target[vr]
        gone = s.status[vr] != ON_ROAD or (
            vmc >= 0 and (s.status[vmc] != ON_ROAD or road.code_kind[s.target[vmc]] != KIND_MAIN)
        )
        if merged or gone:
            pi[k, P_VR] = -1
    s.counters[C_PLANS] = compact_plans(pi, s.plan_f, n)
