"""Prediction of the six key vehicles for a whole population of candidate plans.

One call simulates every candidate (candidates x key vehicles x horizon steps) with the same
equations the engine uses — Eq. 1/3 car following, the quintic lane change of Eq. 4-6 with the
Eq. 14 tanh blend, the virtual vehicles of Eq. 8-13 — under these prediction assumptions
(documented in docs/models.md):

* VMF and VNF keep their current speed (their own leaders are outside the key group);
* perception is exact (HDVs are predicted with their IDM or IIDM, without delays or noise);
* every vehicle follows the nearest key vehicle ahead in the lane(s) it occupies; a vehicle
  that changes lane occupies both lanes until the change ends (as in the engine);
* a CAV VR on the ramp follows its plan: VV0, a cubic virtual leader from its start state to
  the state of its future leader (the VMF role) at the horizon H, then that leader's
  projection onto the ramp; it does not brake for the lane end (the engine brakes for it only
  if the plan fails). An HDV VR keeps its IDM with the lane end as a standing obstacle.
  VR starts its change at the merge position (candidate variable 0) with the candidate's
  duration (variable 1);
* longitudinal mode: a cooperating VMC also follows VV1, the cubic from its start state to
  VR's predicted state at the horizon H (variable 2), and VR's projection after H;
* lateral mode: a cooperating VMC changes to lane 2 now, blending from VMF to VNF (Eq. 14),
  and a CAV VNR follows VV2, the cubic from VNF's state now to VMC's predicted state at H.

Three passes per candidate population:

0. the **no-merge counterfactual** (candidate-independent): VR alone on a free road, the
   mainline key vehicles without VR and without cooperation; it is the reference of the
   common distance of Eq. 16, VV0's target and VNR's motion in longitudinal mode;
1. a **pre-pass** in which VR follows only VV0 and VMF, VMC only VMF and VNF, which fixes the
   end states of VV1 and VV2 at H exactly as the engine executes them (the cubics are fixed
   when the plan is made);
2. the **joint pass** of every key vehicle, from which trajectories, constraints, Eq. 15 (at
   VR's merge completion) and Eq. 17 (the accelerations before VR's lane change, at its start,
   and after it, at its end) are taken.

The kernels are compiled with numba: a population is evaluated per optimiser generation, which
a numpy time-stepping loop cannot do within the decision-time budget. Simulated annealing asks
for one candidate at a time: :func:`rollout_into` scores one with the same per-candidate body,
without the per-call work only a population needs. They are split by concern — array layouts
(:mod:`~hcomc.control.prediction.layout`), car following and integration
(:mod:`~hcomc.control.prediction.step`), accelerations of the roles
(:mod:`~hcomc.control.prediction.accelerations`), lane-change progress
(:mod:`~hcomc.control.prediction.lane_changes`), the passes
(:mod:`~hcomc.control.prediction.passes`), one candidate
(:mod:`~hcomc.control.prediction.candidate`), scoring
(:mod:`~hcomc.control.prediction.scoring`) and fuel
(:mod:`~hcomc.control.prediction.fuel`) — and every equation is called from its one home
in :mod:`hcomc.equations`, :mod:`hcomc.safety` and :mod:`hcomc.control.virtual_vehicle`, the
same functions the engine executes.
"""

from __future__ import annotations

import functools

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.control.prediction.candidate import (
    candidate,
    mode_index,
    rollout_into,
    rollout_work,
    vmc_tracks,
)
from hcomc.control.prediction.layout import (
    C_A_MERG,
    C_ACCEL_END,
    C_B_SAFE,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_DT,
    C_EMERGENCY,
    C_GAMMA,
    C_MIN_GAP,
    C_POLITENESS,
    C_REPLAN,
    C_VMC_DUR,
    C_VV_DECEL,
    C_WIDTH,
    G_COLLISION,
    G_EXECUTION,
    G_NO_RETURN,
    G_NOT_MERGED,
    G_OVERRUN,
    G_UNSAFE,
    G_VIRTUAL,
    N_CONSTS,
    N_G,
    N_PARAMS,
    N_PROGRESS,
    N_ROLES,
    N_STARTS,
    N_STATE,
    P_A,
    P_B,
    P_C,
    P_DELTA,
    P_IIDM,
    P_LEN,
    P_S0,
    P_T,
    P_V0,
    P_WID,
    S_VV0_V,
    S_VV0_X,
    S_VV1_V,
    S_VV1_X,
    VMC,
    VMF,
    VMR,
    VNF,
    VNR,
    VR,
    KeyVehicles,
    Scratch,
    Trajectories,
)
from hcomc.control.prediction.passes import counterfactual, vmc_pre_track
from hcomc.equations.idm import equilibrium_gap

__all__ = [
    "C_ACCEL_END", "C_A_MERG", "C_B_SAFE", "C_D", "C_DELAY_CAV", "C_DELAY_HDV", "C_DT",
    "C_EMERGENCY", "C_GAMMA", "C_MIN_GAP", "C_POLITENESS", "C_REPLAN", "C_VMC_DUR",
    "C_VV_DECEL", "C_WIDTH", "G_COLLISION", "G_EXECUTION", "G_NOT_MERGED", "G_NO_RETURN",
    "G_OVERRUN", "G_UNSAFE", "G_VIRTUAL", "N_CONSTS", "N_PARAMS", "N_ROLES",
    "N_STARTS", "P_A", "P_B", "P_C", "P_DELTA", "P_IIDM", "P_LEN", "P_S0", "P_T", "P_V0",
    "P_WID", "S_VV0_V", "S_VV0_X", "S_VV1_V", "S_VV1_X", "VMC", "VMF", "VMR", "VNF", "VNR",
    "VR", "KeyVehicles", "counterfactual", "resolve_starts", "rollout", "rollout_into",
    "rollout_work", "vmc_tracks", "warm_up", "warm_up_instant",
]  # fmt: skip

_EQ_SPEED_CAP = 0.999  # VV0's default gap is the equilibrium gap at <= 0.999 v0 (finite)


@kernel
def _rollout_kernel(
    key: KeyVehicles, starts: np.ndarray, merge_x: np.ndarray, vr_dur: np.ndarray,
    horizon: np.ndarray, lateral: np.ndarray, consts: np.ndarray, n_steps: int, cf: np.ndarray,
) -> tuple[np.ndarray, ...]:  # fmt: skip
    """The compiled body of :func:`rollout` (same arguments, ``starts`` resolved)."""
    n_c, K = merge_x.size, n_steps
    X = np.empty((n_c, K + 1, N_ROLES))
    V = np.empty((n_c, K + 1, N_ROLES))
    Y = np.zeros((n_c, K + 1, N_ROLES))
    A = np.zeros((n_c, K + 1, N_ROLES))
    HEAD = np.zeros((n_c, K + 1, N_ROLES))
    k_merge = np.full(n_c, -1, dtype=np.int64)
    u_safe = np.full(n_c, np.inf)
    u_eff = np.zeros(n_c)
    g = np.zeros((n_c, N_G))
    vvs = np.zeros((n_c, 3, 4))
    # VMC's pre-pass trajectory depends on the mode only: once per mode, when a candidate has it
    tracks = np.empty((2, K + 1, 2))
    tracked = np.zeros(2, dtype=np.bool_)
    plan = np.empty(3)
    scratch = Scratch(np.empty((N_STATE, N_ROLES)), np.empty(N_PROGRESS),
                      np.empty((4, N_ROLES)), np.empty(max(K, 1)))  # fmt: skip
    for c in range(n_c):
        plan[0], plan[1], plan[2] = merge_x[c], vr_dur[c], horizon[c]
        mode = mode_index(lateral[c], key.coop, key.present)
        if not tracked[mode]:
            tracks[mode] = vmc_pre_track(key, mode == 1, consts, K)
            tracked[mode] = True
        trajectories = Trajectories(X[c], Y[c], V[c], A[c], HEAD[c])
        k_merge[c], u_safe[c], u_eff[c] = candidate(
            key, starts, plan, lateral[c], consts, cf, tracks[mode], trajectories, g[c], vvs[c],
            scratch,
        )  # fmt: skip
    vv0, vv1, vv2 = vvs[:, 0].copy(), vvs[:, 1].copy(), vvs[:, 2].copy()
    return X, Y, V, A, HEAD, k_merge, u_safe, u_eff, g, vv0, vv1, vv2


def resolve_starts(
    x0: FloatArray, v0: FloatArray, params: FloatArray, starts: FloatArray
) -> FloatArray:
    """``starts`` with its NaN entries replaced by the Eq. 8 defaults.

    VV1 starts at VMF's state; VV0 at VR's speed, a VMF-length leader at VR's IDM equilibrium
    gap (:func:`hcomc.equations.idm.equilibrium_gap`, at a speed capped just below v0 so that
    the gap is finite).
    """
    out = np.array(starts, dtype=np.float64)
    if np.isnan(out[S_VV0_X]):
        p = params[VR]
        v = min(float(v0[VR]), _EQ_SPEED_CAP * float(p[P_V0]))
        gap = equilibrium_gap(v, v0=p[P_V0], T=p[P_T], s0=p[P_S0], delta=p[P_DELTA])
        out[S_VV0_X] = x0[VR] + params[VMF, P_LEN] + float(gap)
        out[S_VV0_V] = v0[VR]
    if np.isnan(out[S_VV1_X]):
        out[S_VV1_X], out[S_VV1_V] = x0[VMF], v0[VMF]
    return out


def rollout(
    key: KeyVehicles,
    starts: FloatArray,
    merge_x: FloatArray,
    vr_dur: FloatArray,
    horizon: FloatArray,
    lateral: np.ndarray,
    consts: FloatArray,
    n_steps: int,
    cf: FloatArray,
    *,
    resolved: bool = False,
) -> tuple[np.ndarray, ...]:
    """Simulate every candidate; return trajectories, objectives and constraint parts.

    Parameters
    ----------
    key : :class:`KeyVehicles`, the key vehicles at planning time: x, v, a; whether each
        role exists (``present``), is a CAV (``cav``: selects the Eq. 15 delay; a CAV VR
        follows VV0) and cooperates when its mode asks it to (``coop``; VMC: VV1 or lateral
        change; VNR: VV2; normally equal to ``cav``); the (6, 10) model parameters (columns
        ``P_*``; ``P_IIDM`` 1 selects the IIDM).
    starts : (4,) start states of VV0 and VV1 (``S_*``); NaN selects the defaults of
        :func:`resolve_starts`. A replanning controller passes the live virtual vehicles'
        states for continuity.
    merge_x, vr_dur, horizon, lateral : (C,) candidate variables.
    consts : (15,) constants (``C_*``).
    n_steps : prediction steps K.
    cf : (3, K + 1, 6) x, v and a of the no-merge :func:`counterfactual` (candidate-independent:
        the caller computes it once per planning instant, not once per population).
    resolved : ``starts`` holds no NaN (:func:`resolve_starts` was applied once per planning
        instant by the caller), so it is passed on as it is.

    Returns
    -------
    X, Y, V, A, HEAD : (C, K + 1, 6) trajectories [m, m, m/s, m/s^2, rad].
    k_merge : (C,) step at which VR's lane change ends, -1 if it does not within the window.
    u_safe : (C,) Eq. 15 at k_merge, the largest over the follower-leader pairs the merge
        creates (VR behind its new leader, VR's new follower; lateral mode also VMC behind its
        lane-2 leader and VNR behind VMC).
    u_eff : (C,) Eq. 17, the incentive of VR's lane change from the accelerations before it
        (predicted state in which it begins) and after it (state in which it ends, or the
        window's end) (:func:`~hcomc.control.prediction.scoring.lane_change_incentive`), 0 if
        it never begins [m/s^2].
    g : (C, 9) constraint parts (columns ``G_*``; columns 5 and 6 are the merge problem's,
        left 0); column ``G_COLLISION`` counts the colliding (pair, step) combinations of the
        key vehicles (oriented rectangles, Eq. 7); ``G_NO_RETURN`` and ``G_EXECUTION`` are 0
        unless ``consts[C_REPLAN] > 0``.
    vv0, vv1, vv2 : (C, 4) cubic coefficients of the virtual vehicles (relative time).
    """
    if not resolved:
        starts = resolve_starts(key.x, key.v, key.params, starts)
    return _rollout_kernel(key, starts, merge_x, vr_dur, horizon, lateral, consts, n_steps, cf)


@functools.cache  # once per process
def warm_up() -> None:
    """Load (or compile) the kernels once per process, so decision times exclude it."""
    key, consts, n_steps, cf = warm_up_instant()
    one = np.ones(1)
    starts = np.full(N_STARTS, np.nan)
    rollout(key, starts, one * 800.0, one * 4.0, one * 6.0, np.zeros(1, dtype=np.bool_), consts,
            n_steps, cf)  # fmt: skip


def warm_up_instant() -> tuple[KeyVehicles, np.ndarray, int, np.ndarray]:
    """A small synthetic planning instant (key vehicles, consts, n_steps, cf) with the
    argument types of real ones: calling a kernel on it loads (or compiles) the variant that
    decisions use."""
    row = np.array([33.3, 1.0, 2.0, 1.4, 2.0, 4.0, 0.99, 5.0, 1.8, 0.0])
    params = np.tile(row, (N_ROLES, 1))
    consts = np.zeros(N_CONSTS)
    consts[C_DT], consts[C_ACCEL_END], consts[C_WIDTH], consts[C_VMC_DUR] = 0.5, 950, 3.75, 4
    consts[C_GAMMA], consts[C_EMERGENCY], consts[C_VV_DECEL] = 2.3, 9.0, 7.5
    consts[C_D], consts[C_A_MERG], consts[C_DELAY_CAV], consts[C_DELAY_HDV] = 2.0, 7.5, 0.5, 1.0
    x = np.array([400.0, 380.0, 480.0, 300.0, 450.0, 330.0])
    flags = np.ones(N_ROLES, dtype=np.bool_)
    v, a = np.full(N_ROLES, 25.0), np.zeros(N_ROLES)
    n_steps = 4
    key = KeyVehicles(x, v, a, flags, flags, flags, params)
    cf = np.stack(counterfactual(key, consts, n_steps))
    return key, consts, n_steps, cf
