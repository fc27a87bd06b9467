"""Executing merge plans inside the compiled step: the plan table and its kernels.

The live plans of a run are rows of a table in its compiled state (``plan_int`` and
``plan_f`` of :class:`hcomc.sim.step.state.CoreArrays`, the first ``counters[N_PLANS]`` rows,
in the order the plans were made; a replan replaces its VR's row and moves to the end). With
the table in the compiled state, a step with live plans needs no Python: Python is entered
only when the controller decides (a first plan, or a replan that :func:`replan_due` says is
due). The rules executed here are those described in :mod:`hcomc.sim.plan_execution`; these
kernels are their one implementation, used by the compiled loop, by the engine's Python step
after a decision, and (on a table built from a list of plans) by the SUMO co-simulation.

Columns: ``plan_int`` holds the key vehicles (role order of
:meth:`hcomc.interface.MergeGroup.as_array`), the mode, which virtual vehicles the plan
has, the progress flags of :class:`hcomc.sim.plan_execution.ActivePlan` and the index of the plan
in the run's decisions; ``plan_f`` holds t0, the horizon, the merge position, VR's duration
and the cubic coefficients of VV0, VV1 and VV2.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from hcomc._jit import kernel
from hcomc.equations.safety import stopping_distance
from hcomc.equations.virtual_vehicle import cubic_point
from hcomc.sim.lane_table import KIND_MAIN, L_END, L_KIND, L_LEFT
from hcomc.sim.mobil import LC_SAFE_DECEL
from hcomc.sim.neighbours import LaneIndex
from hcomc.sim.step.lane_change import commanded_changes
from hcomc.sim.step.state import (
    CONTROLLER,
    EV_FALLBACK,
    N_PLANS,
    REPLAN_PERIOD,
    CoreArrays,
    add_event,
)

if TYPE_CHECKING:
    from hcomc.interface.plan import MergePlan

# plan_int columns
P_VR, P_VMC, P_VMF, P_VMR, P_VNF, P_VNR = range(6)  # MergeGroup.as_array order
P_MODE, P_HAS_VV0, P_HAS_VV1, P_HAS_VV2 = range(6, 10)
P_VR_CMD, P_VMC_CMD, P_VNR_CMD, P_VR_STARTED, P_VMC_STARTED, P_RELEASED = range(10, 16)
P_ID = 16  # index of the plan in the run's decisions
N_INT = 17
# plan_f columns
F_T0, F_HORIZON, F_MERGE_X, F_VR_DURATION = range(4)
F_VV0, F_VV1, F_VV2 = 4, 8, 12  # four cubic coefficients each
N_FLOAT = 16

LONGITUDINAL, LATERAL = 1, 2  # hcomc.interface.Mode, as plain ints


def encode_plan(
    plan: MergePlan, vr_commanded: bool, vmc_commanded: bool, vnr_commanded: bool, ident: int
) -> tuple[np.ndarray, np.ndarray]:
    """The table row ``(ints, floats)`` of a plan just made (nothing started yet)."""
    ints = np.zeros(N_INT, dtype=np.int64)
    floats = np.zeros(N_FLOAT)
    ints[P_VR : P_VNR + 1] = plan.group.as_array()
    ints[P_MODE] = int(plan.mode)
    ints[[P_VR_CMD, P_VMC_CMD, P_VNR_CMD]] = vr_commanded, vmc_commanded, vnr_commanded
    ints[P_ID] = ident
    floats[[F_T0, F_HORIZON, F_MERGE_X, F_VR_DURATION]] = (
        plan.t0, plan.horizon, plan.merge_x, plan.vr_duration
    )  # fmt: skip
    for has, col, coeffs in ((P_HAS_VV0, F_VV0, plan.vv0), (P_HAS_VV1, F_VV1, plan.vv1),
                             (P_HAS_VV2, F_VV2, plan.vv2)):  # fmt: skip
        if coeffs is not None:
            ints[has] = 1
            floats[col : col + 4] = np.asarray(coeffs, dtype=np.float64)
    return ints, floats


def add_plan(plan_int: np.ndarray, plan_f: np.ndarray, n: int, ints: np.ndarray,
             floats: np.ndarray) -> int:  # fmt: skip
    """Put a new plan at the end of the first ``n`` rows, replacing its VR's live plan (the
    others keep their order); returns the new number of rows."""
    keep = np.flatnonzero(plan_int[:n, P_VR] != ints[P_VR])
    m = keep.size
    if m >= plan_int.shape[0]:
        raise RuntimeError(
            f"plan table full: {plan_int.shape[0]} live plans (there is one per ramp vehicle "
            "at most, and the table has a row per ramp vehicle of the run)"
        )
    plan_int[:m], plan_f[:m] = plan_int[keep], plan_f[keep]
    plan_int[m], plan_f[m] = ints, floats
    return m + 1


# -------------------------------------------------------------------------- masks
@kernel(inline="always")
def vr_following(pi: np.ndarray, k: int) -> bool:
    """Whether plan k's VR is on the ramp following the plan (VV0, no lane-end braking)."""
    return pi[k, P_VR_CMD] != 0 and pi[k, P_VR_STARTED] == 0 and pi[k, P_RELEASED] == 0


@kernel
def following_mask(pi: np.ndarray, n_plans: int, n: int) -> np.ndarray:
    """Vehicles (N,) that are a VR following its plan."""
    return following_into(pi, n_plans, np.empty(n, dtype=np.bool_))


@kernel
def following_into(pi: np.ndarray, n_plans: int, mask: np.ndarray) -> np.ndarray:
    """:func:`following_mask` written into ``mask`` (N,), which it returns."""
    mask[:] = False
    for k in range(n_plans):
        if vr_following(pi, k):
            mask[pi[k, P_VR]] = True
    return mask


@kernel
def commanded_mask(pi: np.ndarray, n_plans: int, n: int) -> np.ndarray:
    """Vehicles (N,) a live plan commands (excluded from MOBIL decisions)."""
    mask = np.zeros(n, dtype=np.bool_)
    for k in range(n_plans):
        if vr_following(pi, k):
            mask[pi[k, P_VR]] = True
        if pi[k, P_VMC_CMD]:
            mask[pi[k, P_VMC]] = True
        if pi[k, P_VNR_CMD]:
            mask[pi[k, P_VNR]] = True
    return mask


@kernel
def holding_mask(pi: np.ndarray, n_plans: int, is_cav: np.ndarray) -> np.ndarray:
    """Vehicles that make no discretionary change for a plan: those it commands and every
    connected (CAV) key vehicle of a live plan but VR
    (:func:`hcomc.sim.plan_execution.holding_lane`).

    A VR the plan does not command merges by gap acceptance, as an HDV VR does."""
    mask = commanded_mask(pi, n_plans, is_cav.size)
    for k in range(n_plans):
        for role in range(P_VMC, P_VNR + 1):
            j = pi[k, role]
            if j >= 0 and is_cav[j]:
                mask[j] = True
    return mask


# ------------------------------------------------------------------ virtual leaders
@kernel(inline="always")
def _virtual(
    pf: np.ndarray, k: int, col: int, tau: float, after: int, x: np.ndarray, v: np.ndarray,
    a: np.ndarray,
) -> tuple[bool, float, float, float]:  # fmt: skip
    """(exists, x, v, a) of plan k's virtual vehicle at ``col``: its cubic within the horizon,
    after it the state of vehicle ``after`` (-1: the virtual vehicle has ended)."""
    if tau <= pf[k, F_HORIZON]:
        xv, vv, av = cubic_point(pf[k, col], pf[k, col + 1], pf[k, col + 2], pf[k, col + 3], tau)
        return True, xv, vv, av
    if after >= 0:
        return True, x[after], v[after], a[after]
    return False, 0.0, 0.0, 0.0


@kernel
def virtual_rows(
    pi: np.ndarray, pf: np.ndarray, n_plans: int, t: float, x: np.ndarray, v: np.ndarray,
    a: np.ndarray, length: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """``(followers, x_vv, v_vv, a_vv, length_vv)`` of every virtual vehicle in force at t,
    plan by plan VV0, VV1, VV2 (the states of
    :func:`hcomc.control.hierarchical.controller.virtual_states`).

    VV0 leads a CAV VR that follows its plan on the ramp (when VR has a future leader VMF),
    VV1 a cooperating VMC in longitudinal mode, VV2 a CAV VNR in lateral mode (within the
    horizon)."""
    fol = np.empty(3 * n_plans, dtype=np.int64)
    out = np.empty((4, 3 * n_plans))
    m = virtual_rows_into(pi, pf, n_plans, t, x, v, a, length, fol, out)
    return fol[:m], out[0, :m].copy(), out[1, :m].copy(), out[2, :m].copy(), out[3, :m].copy()


@kernel
def virtual_rows_into(
    pi: np.ndarray, pf: np.ndarray, n_plans: int, t: float, x: np.ndarray, v: np.ndarray,
    a: np.ndarray, length: np.ndarray, fol: np.ndarray, out: np.ndarray,
) -> int:  # fmt: skip
    """:func:`virtual_rows` written into ``fol`` and the rows of ``out`` (x, v, a, length;
    at least ``3 n_plans`` wide); the number of rows."""
    m = 0
    for k in range(n_plans):
        tau = t - pf[k, F_T0]
        vmf, vr, vmc = pi[k, P_VMF], pi[k, P_VR], pi[k, P_VMC]
        if vr_following(pi, k) and pi[k, P_HAS_VV0] and vmf >= 0:
            ok, xv, vv, av = _virtual(pf, k, F_VV0, tau, vmf, x, v, a)
            if ok:
                fol[m], out[0, m], out[1, m], out[2, m], out[3, m] = vr, xv, vv, av, length[vmf]
                m += 1
        if pi[k, P_VMC_CMD] and pi[k, P_MODE] == LONGITUDINAL and pi[k, P_HAS_VV1]:
            ok, xv, vv, av = _virtual(pf, k, F_VV1, tau, vr, x, v, a)
            if ok:
                fol[m], out[0, m], out[1, m], out[2, m], out[3, m] = vmc, xv, vv, av, length[vr]
                m += 1
        if pi[k, P_VNR_CMD] and pi[k, P_HAS_VV2]:
            ok, xv, vv, av = _virtual(pf, k, F_VV2, tau, -1, x, v, a)
            if ok:
                fol[m], out[0, m], out[1, m], out[2, m] = pi[k, P_VNR], xv, vv, av
                out[3, m] = length[vmc]
                m += 1
    return m


# ------------------------------------------------------------------------- replans
@kernel
def replan_due(
    vr_commanded: bool, vr_started: bool, vmc_started: bool, released: bool, t0: float,
    merge_x: float, t: float, period: float, x_vr: float, v_vr: float,
) -> bool:  # fmt: skip
    """Receding horizon: replan every ``period`` s until a commanded lane change began
    (:meth:`hcomc.sim.plan_execution.ActivePlan.may_replan`).

    Within one period before its merge position VR keeps the plan it is about to execute;
    if the change cannot start there, replanning resumes until VR is released."""
    committed = vr_commanded and merge_x - v_vr * period <= x_vr < merge_x
    return (
        period > 0.0
        and not committed
        and not vr_started
        and not vmc_started
        and not released
        and t - t0 >= period - 1e-9
    )


@kernel
def due_plans(c: CoreArrays, t: float) -> np.ndarray:
    """VRs (in table order) whose live plan is due for a replan at t: VR still in its ramp
    lane, keeping it, and :func:`replan_due`."""
    pi, pf = c.plan_int, c.plan_f
    n_plans = c.counters[N_PLANS]
    out = np.empty(n_plans, dtype=np.int64)
    m = 0
    if c.flags[CONTROLLER] == 0:
        return out[:0]
    period = c.consts[REPLAN_PERIOD]
    for k in range(n_plans):
        vr = pi[k, P_VR]
        ramp = c.road_int[L_KIND, c.lane[vr]] != KIND_MAIN
        on_ramp = ramp and c.origin[vr] == c.target[vr] and c.active[vr]
        if on_ramp and replan_due(
            pi[k, P_VR_CMD] != 0, pi[k, P_VR_STARTED] != 0, pi[k, P_VMC_STARTED] != 0,
            pi[k, P_RELEASED] != 0, pf[k, F_T0], pf[k, F_MERGE_X], t, period, c.x[vr], c.v[vr],
        ):  # fmt: skip
            out[m] = vr
            m += 1
    return out[:m]


# ------------------------------------------------------------------------ execution
@kernel
def _command(
    c: CoreArrays, ids: np.ndarray, t: float, lead: np.ndarray, index: LaneIndex, i: int,
    target: int, duration: float, release_x: float, vr: int, other: int,
) -> bool:  # fmt: skip
    """One commanded lane change (:func:`hcomc.sim.step.lane_change.commanded_changes`)."""
    result = commanded_changes(
        c, ids, t, lead, index, np.array([i]), np.array([target]),
        np.array([duration]), np.array([release_x]), np.array([vr]), np.array([other]),
    )  # fmt: skip
    return result[0]


@kernel
def execute_plans(
    c: CoreArrays, ids: np.ndarray, t: float, lead: np.ndarray, index: LaneIndex
) -> None:
    """Start the lane changes the live plans command, each when the MOBIL safety criterion
    holds: a lateral VMC's change at once to the lane beyond VR's target lane (lane 2;
    failing, the plan falls back to VR's gap acceptance: FALLBACK), VR's change from its
    merge position on to the lane left of its ramp lane (lane 1; until it could no longer
    stop before its lane's end at the safe deceleration: then the plan fails). A plan also
    fails when its VR, commanded or not, waits at its lane's end (FALLBACK). A failed plan
    releases every key vehicle to its own model: VR to gap acceptance, VMC and VNR from
    their virtual leaders (VV1 ends on VR's state, and a VMC behind a VR standing at the
    lane's end would keep closed the very gap VR needs)."""
    pi, pf = c.plan_int, c.plan_f
    left, end = c.road_int[L_LEFT], c.road_f[L_END]
    for k in range(c.counters[N_PLANS]):
        vr, vmc = pi[k, P_VR], pi[k, P_VMC]
        if c.waited[vr] and not pi[k, P_RELEASED] and not pi[k, P_VR_STARTED]:
            add_event(c, t, EV_FALLBACK, vr, vmc, c.x[vr], math.nan)
            _fail(pi, k)
            continue
        if pi[k, P_MODE] == LATERAL and pi[k, P_VMC_CMD] and not pi[k, P_VMC_STARTED]:
            merge_lane = left[c.lane[vr]]  # VR keeps its ramp lane until VMC has started
            escape = left[merge_lane] if merge_lane >= 0 else -1
            started = 0
            if escape >= 0:
                started = _command(c, ids, t, lead, index, vmc, escape, math.nan, -math.inf, vr,
                                   vmc)  # fmt: skip
            if started > 0:
                pi[k, P_VMC_STARTED] = 1
            else:
                pi[k, P_VMC_CMD] = pi[k, P_VNR_CMD] = 0
                pi[k, P_RELEASED] = 1
        if (
            not pi[k, P_VR_CMD]
            or pi[k, P_VR_STARTED]
            or pi[k, P_RELEASED]
            or c.origin[vr] != c.target[vr]
            or c.x[vr] < pf[k, F_MERGE_X]
        ):
            continue
        release_x = end[c.lane[vr]] - stopping_distance(
            c.v[vr], c.lc_params[LC_SAFE_DECEL], c.matrix[2, vr]
        )  # s0, row 2 of the matrix
        started = _command(c, ids, t, lead, index, vr, left[c.lane[vr]], pf[k, F_VR_DURATION],
                           release_x, vr, vmc)  # fmt: skip
        pi[k, P_VR_STARTED] = started > 0
        if started < 0:  # FALLBACK logged by commanded_changes
            _fail(pi, k)


@kernel(inline="always")
def _fail(pi: np.ndarray, k: int) -> None:
    """Plan k failed: VR released to gap acceptance, VMC and VNR no longer commanded."""
    pi[k, P_RELEASED] = 1
    pi[k, P_VMC_CMD] = pi[k, P_VNR_CMD] = 0


@kernel(inline="always")
def compact_plans(plan_int: np.ndarray, plan_f: np.ndarray, n: int) -> int:
    """Close the gaps that dropped plans (VR set to -1) left in the first ``n`` rows of the plan
    table, the other plans keeping their order; returns how many remain."""
    m = 0
    for k in range(n):
        if plan_int[k, P_VR] < 0:
            continue
        if m != k:
            plan_int[m] = plan_int[k]
            plan_f[m] = plan_f[k]
        m += 1
    return m


@kernel
def finish_plans(c: CoreArrays) -> None:
    """Drop the plans whose merge is complete (VR on the mainline, keeping its lane) or
    whose VR or VMC left the road; the others keep their order."""
    pi, n = c.plan_int, c.counters[N_PLANS]
    for k in range(n):
        vr, vmc = pi[k, P_VR], pi[k, P_VMC]
        merged = c.road_int[L_KIND, c.lane[vr]] == KIND_MAIN and c.origin[vr] == c.target[vr]
        gone = not c.active[vr] or (vmc >= 0 and not c.active[vmc])
        if merged or gone:
            pi[k, P_VR] = -1
    c.counters[N_PLANS] = compact_plans(pi, c.plan_f, n)
