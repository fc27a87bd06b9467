"""Prediction of the six key vehicles for a whole population of candidate plans.

One call simulates every candidate (candidates x key vehicles x horizon steps) with the same
equations the engine uses — Eq. 1/3 car following, the quintic lane change of Eq. 4-6 with the
Eq. 14 tanh blend, the virtual vehicles of Eq. 8-13 — under these prediction assumptions
(documented in docs/models.md):

* VMF and VNF keep their current speed (their own leaders are outside the key group);
* perception is exact (HDVs are predicted with their IDM, without delays or noise);
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
   accumulated Eq. 17 gains and of the common distance of Eq. 16;
1. a **pre-pass** in which VR follows only VV0 and VMF, VMC only VMF and VNF, which fixes the
   end states of VV1 and VV2 at H exactly as the engine executes them (the cubics are fixed
   when the plan is made);
2. the **joint pass** of every key vehicle, from which trajectories, constraints, Eq. 15 and
   Eq. 17 are taken.

The kernel is compiled with numba: a population is evaluated per optimiser generation, which a
numpy time-stepping loop cannot do within the decision-time budget. The scalar forms of
Eq. 1, 3, 4 and 14 below are cross-checked against the vectorised kernels of
:mod:`hcomc.models` in the tests.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit

from hcomc.road import KEY_ROLES

VR, VMC, VMF, VMR, VNF, VNR = range(6)
N_ROLES = len(KEY_ROLES)  # role indices above follow KEY_ROLES
# params columns
P_V0, P_T, P_S0, P_A, P_B, P_DELTA, P_C, P_LEN, P_WID = range(9)
N_PARAMS = 9
# constants vector layout
(
    C_DT,
    C_ACCEL_END,
    C_WIDTH,
    C_VMC_DUR,
    C_GAMMA,
    C_EMERGENCY,
    C_VV_DECEL,
    C_POLITENESS,
    C_D,
    C_A_MERG,
    C_DELAY_CAV,
    C_DELAY_HDV,
) = range(12)
N_CONSTS = 12
# start states of the virtual vehicles (NaN: the Eq. 8 default), see ``rollout``
S_VV0_X, S_VV0_V, S_VV1_X, S_VV1_V = range(4)
N_STARTS = 4
# constraint columns
G_COLLISION, G_NOT_MERGED, G_UNSAFE, G_VIRTUAL, G_OVERRUN = range(5)
# passes
_COUNTERFACTUAL, _PRE, _JOINT = range(3)
_LANE0 = np.array([0, 1, 1, 1, 2, 2])  # lanes of the roles at planning time (0 = ramp)


@njit(cache=True)
def accel(p: np.ndarray, s: float, v: float, vl: float, al: float) -> float:
    """Eq. 1 (IDM) and, for coolness c > 0, Eq. 3 (ACC with CAH) for one vehicle [m/s^2]."""
    v0, T, s0, a, b, delta, c = p[P_V0], p[P_T], p[P_S0], p[P_A], p[P_B], p[P_DELTA], p[P_C]
    ratio = v / v0
    if delta == 4.0:  # the default exponent: avoid a slow pow()
        ratio *= ratio
        free = 1.0 - ratio * ratio
    else:
        free = 1.0 - ratio**delta
    if s == np.inf:
        return a * free
    dv = v - vl
    s_star = s0 + max(0.0, v * T + v * dv / (2.0 * math.sqrt(a * b)))
    z = s_star / max(s, 1e-3)
    a_idm = a * (free - z * z)
    if c <= 0.0:
        return a_idm
    s_g = max(s, 0.01)
    a_lt = min(al, a)
    denom = vl * vl - 2.0 * s_g * a_lt
    if vl * (v - vl) <= -2.0 * s_g * a_lt and denom > 0.0:
        a_cah = v * v * a_lt / denom
    else:
        dvp = max(v - vl, 0.0)
        a_cah = a_lt - dvp * dvp / (2.0 * s_g)
    if a_idm >= a_cah:
        return a_idm
    return (1.0 - c) * a_idm + c * (a_cah + b * math.tanh((a_idm - a_cah) / b))


@njit(cache=True)
def psi(tau: float, duration: float, gamma: float) -> float:
    """Eq. 14 transition weight with lambda = 2 gamma / duration."""
    return 0.5 * (math.tanh(2.0 * gamma / duration * tau - gamma) + 1.0)


@njit(cache=True)
def quintic(xi: float) -> tuple[float, float]:
    """Normalised quintic 10ξ³ − 15ξ⁴ + 6ξ⁵ and its slope, ξ clipped to [0, 1] (Eq. 4)."""
    xi = min(max(xi, 0.0), 1.0)
    x2 = xi * xi
    return x2 * xi * (10.0 - 15.0 * xi + 6.0 * x2), 30.0 * x2 * (1.0 - 2.0 * xi + x2)


@njit(cache=True)
def equilibrium_gap(p: np.ndarray, v: float) -> float:
    """IDM steady-state gap s_e(v) = (s0 + v T) / sqrt(1 - (v/v0)^delta) [m] (v < v0)."""
    free = 1.0 - (min(v, 0.999 * p[P_V0]) / p[P_V0]) ** p[P_DELTA]
    return (p[P_S0] + v * p[P_T]) / math.sqrt(free)


@njit(cache=True)
def _leader(
    r: int, lane: int, x: np.ndarray, in1: np.ndarray, in2: np.ndarray, present: np.ndarray
) -> int:
    """Nearest key vehicle strictly ahead of role r in ``lane`` (1 or 2), -1 if none."""
    best, best_x = -1, np.inf
    for j in range(N_ROLES):
        if j == r or not present[j]:
            continue
        member = in1[j] if lane == 1 else in2[j]
        if member and x[r] < x[j] < best_x:
            best, best_x = j, x[j]
    return best


@njit(cache=True)
def _behind(
    r: int, j: int, x: np.ndarray, v: np.ndarray, a: np.ndarray, params: np.ndarray
) -> float:
    """Acceleration of role r behind role j (free road for j = -1)."""
    if j < 0:
        return accel(params[r], np.inf, v[r], v[r], 0.0)
    return accel(params[r], x[j] - params[j, P_LEN] - x[r], v[r], v[j], a[j])


@njit(cache=True)
def _cubic(h: float, x0: float, v0: float, xf: float, vf: float, out: np.ndarray) -> None:
    """Eq. 10 with t0 = 0 (see :func:`hcomc.control.virtual_vehicle.cubic_coefficients`)."""
    dx = xf - x0
    out[0], out[1] = x0, v0
    out[2] = (3.0 * dx - (2.0 * v0 + vf) * h) / (h * h)
    out[3] = (-2.0 * dx + (v0 + vf) * h) / (h * h * h)


@njit(cache=True)
def _virtual(b: np.ndarray, tau: float) -> tuple[float, float, float]:
    x = b[0] + tau * (b[1] + tau * (b[2] + tau * b[3]))
    v = b[1] + tau * (2.0 * b[2] + 3.0 * tau * b[3])
    return x, v, 2.0 * b[2] + 6.0 * tau * b[3]


@njit(cache=True)
def _cubic_violation(b: np.ndarray, h: float, max_decel: float) -> float:
    """How far a cubic virtual vehicle leaves v >= 0 and a >= -b_max on [0, H] (<= 0: ok)."""
    a_min = min(2.0 * b[2], 2.0 * b[2] + 6.0 * h * b[3])
    v_min = min(b[1], b[1] + h * (2.0 * b[2] + 3.0 * h * b[3]))
    if b[3] > 0.0:
        tau = -b[2] / (3.0 * b[3])
        if 0.0 < tau < h:
            v_min = min(v_min, b[1] + tau * (2.0 * b[2] + 3.0 * tau * b[3]))
    return max(-v_min, -a_min - max_decel)


@njit(cache=True)
def _near_pairs(
    x: np.ndarray,
    y: np.ndarray,
    h: np.ndarray,
    present: np.ndarray,
    params: np.ndarray,
    out: np.ndarray,
) -> None:
    """Axis-aligned bounding-box overlap of every key pair (front-bumper reference point).

    A rectangle of length L and width W at heading h lies within x in [x - L - W/2, x + W/2]
    and y within W/2 + L |sin h| of its reference point.
    """
    reach = np.empty(N_ROLES)
    for r in range(N_ROLES):
        reach[r] = 0.5 * params[r, P_WID] + params[r, P_LEN] * abs(math.sin(h[r]))
    p = 0
    for i in range(N_ROLES):
        for j in range(i + 1, N_ROLES):
            if present[i] and present[j]:
                wi, wj = 0.5 * params[i, P_WID], 0.5 * params[j, P_WID]
                out[p] = (
                    abs(y[i] - y[j]) <= reach[i] + reach[j]
                    and x[i] + wi >= x[j] - params[j, P_LEN] - wj
                    and x[j] + wj >= x[i] - params[i, P_LEN] - wi
                )
            p += 1


@njit(cache=True)
def _critical(d: float, v_r: float, v_f: float, delay: float, D: float, a_merg: float) -> float:
    denom = 2.0 * (d - D - v_r * delay + v_f * v_f / (2.0 * a_merg))  # Eq. 15
    return v_r * v_r / denom if denom > 0.0 else np.inf


@njit(cache=True)
def _integrate(
    x: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    acc: np.ndarray,
    present: np.ndarray,
    dt: float,
    emergency: float,
) -> None:
    """Ballistic step of every present role, stopping exactly at v = 0 (as the engine)."""
    for r in range(N_ROLES):
        if not present[r]:
            continue
        ar = max(acc[r], -emergency)
        v1 = v[r] + ar * dt
        if v1 < 0.0:
            x[r] += -v[r] * v[r] / (2.0 * ar) if ar < 0.0 else 0.0
            a[r] = -v[r] / dt
            v[r] = 0.0
        else:
            x[r] += v[r] * dt + 0.5 * ar * dt * dt
            v[r] = v1
            a[r] = ar


@njit(cache=True)
def counterfactual(
    x0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    present: np.ndarray,
    params: np.ndarray,
    consts: np.ndarray,
    n_steps: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pass 0: the key vehicles without the merge, (n_steps + 1, 6) each of x, v, a.

    VR drives alone on a free road (no lane end); every mainline key vehicle follows the
    nearest key vehicle ahead in its own lane, nobody cooperates or changes lane.
    """
    dt, emergency = consts[C_DT], consts[C_EMERGENCY]
    X = np.empty((n_steps + 1, N_ROLES))
    V = np.empty((n_steps + 1, N_ROLES))
    A = np.empty((n_steps + 1, N_ROLES))
    x, v, a = x0.copy(), v0.copy(), a0.copy()
    acc = np.zeros(N_ROLES)
    in1 = _LANE0 == 1
    in2 = _LANE0 == 2
    for k in range(n_steps + 1):
        X[k], V[k], A[k] = x, v, a
        if k == n_steps:
            break
        acc[VR] = accel(params[VR], np.inf, v[VR], v[VR], 0.0)
        acc[VMF] = 0.0
        acc[VNF] = 0.0
        for r in (VMC, VMR, VNR):
            if present[r]:
                acc[r] = _behind(r, _leader(r, _LANE0[r], x, in1, in2, present), x, v, a, params)
        _integrate(x, v, a, acc, present, dt, emergency)
    return X, V, A


@njit(cache=True)
def rollout(
    x0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    present: np.ndarray,
    cav: np.ndarray,
    coop: np.ndarray,
    params: np.ndarray,
    starts: np.ndarray,
    merge_x: np.ndarray,
    vr_dur: np.ndarray,
    horizon: np.ndarray,
    lateral: np.ndarray,
    consts: np.ndarray,
    n_steps: int,
    cf: np.ndarray,
):
    """Simulate every candidate; return trajectories, objectives and constraint parts.

    Parameters
    ----------
    x0, v0, a0 : (6,) key-vehicle states at planning time, role order VR … VNR.
    present : (6,) whether each role exists.
    cav : (6,) whether each role is a CAV (selects the Eq. 15 delay; a CAV VR follows VV0).
    coop : (6,) whether the role cooperates when its mode asks it to (VMC: VV1 or lateral
        change; VNR: VV2); normally equal to ``cav``.
    params : (6, 9) model parameters (columns ``P_*``).
    starts : (4,) start states of VV0 and VV1 (``S_*``); NaN selects the paper's Eq. 8 start
        (VV1 at VMF's state) and, for VV0, a leader at VR's equilibrium gap at VR's speed.
        A replanning controller passes the live virtual vehicles' states for continuity.
    merge_x, vr_dur, horizon, lateral : (C,) candidate variables.
    consts : (12,) constants (``C_*``).
    n_steps : prediction steps K.
    cf : (3, K + 1, 6) x, v and a of the no-merge :func:`counterfactual` (candidate-independent:
        the caller computes it once per planning instant, not once per population).

    Returns
    -------
    X, Y, V, A, HEAD : (C, K + 1, 6) trajectories [m, m, m/s, m/s^2, rad].
    k_merge : (C,) step at which VR's lane change ends, -1 if it does not within the window.
    u_safe : (C,) Eq. 15 at k_merge, the largest over the follower-leader pairs the merge
        creates (VR behind its new leader, VR's new follower; lateral mode also VMC behind its
        lane-2 leader and VNR behind VMC).
    u_eff : (C,) Eq. 17 gain accumulated over the window against the no-merge counterfactual:
        mean over the K steps of (a_VR − a_VR,cf) + eta Σ_{VMC, VMR, VNR} (a_i − a_i,cf)
        [m/s^2].
    g : (C, 5) constraint parts (collision column left 0 for the caller).
    vv0, vv1, vv2 : (C, 4) cubic coefficients of the virtual vehicles (relative time).
    near : (C, K + 1, 15) key-vehicle pairs (i < j, row-major) whose bounding boxes overlap;
        only these can collide (the exact Eq. 7 test is left to the caller).
    """
    n_c = merge_x.size
    dt, accel_end, width = consts[C_DT], consts[C_ACCEL_END], consts[C_WIDTH]
    vmc_dur, gamma, emergency = consts[C_VMC_DUR], consts[C_GAMMA], consts[C_EMERGENCY]
    K = n_steps
    Xc, Vc, Ac = cf[0], cf[1], cf[2]
    X = np.empty((n_c, K + 1, N_ROLES))
    Y = np.zeros((n_c, K + 1, N_ROLES))
    V = np.empty((n_c, K + 1, N_ROLES))
    A = np.zeros((n_c, K + 1, N_ROLES))
    HEAD = np.zeros((n_c, K + 1, N_ROLES))
    k_merge = np.full(n_c, -1, dtype=np.int64)
    u_safe = np.full(n_c, np.inf)
    u_eff = np.zeros(n_c)
    g = np.zeros((n_c, 5))
    vv0 = np.zeros((n_c, 4))
    vv1 = np.zeros((n_c, 4))
    vv2 = np.zeros((n_c, 4))
    near = np.zeros((n_c, K + 1, N_ROLES * (N_ROLES - 1) // 2), dtype=np.bool_)
    x = np.empty(N_ROLES)
    v = np.empty(N_ROLES)
    a = np.empty(N_ROLES)
    acc = np.zeros(N_ROLES)
    in1 = np.empty(N_ROLES, dtype=np.bool_)
    in2 = np.empty(N_ROLES, dtype=np.bool_)
    coop_vmc = coop[VMC] and present[VMC]
    controlled_vr = cav[VR]
    # VV0 and VV1 start states (Eq. 8 defaults unless a live plan is continued)
    vv0_x, vv0_v = starts[S_VV0_X], starts[S_VV0_V]
    if math.isnan(vv0_x):
        vv0_x = x0[VR] + params[VMF, P_LEN] + equilibrium_gap(params[VR], v0[VR])
        vv0_v = v0[VR]
    vv1_x, vv1_v = starts[S_VV1_X], starts[S_VV1_V]
    if math.isnan(vv1_x):
        vv1_x, vv1_v = x0[VMF], v0[VMF]
    for c in range(n_c):
        H = horizon[c]
        lat = lateral[c] and coop_vmc
        lon = (not lateral[c]) and coop_vmc
        # VV0 ends at VR's future leader (the VMF role) at H, as predicted without the merge
        kh = min(int(round(H / dt)), K)  # noqa: RUF046 (numba typing)
        _cubic(H, vv0_x, vv0_v, Xc[kh, VMF] + Vc[kh, VMF] * (H - kh * dt), Vc[kh, VMF], vv0[c])
        for pass_no in (_PRE, _JOINT):
            x[:] = x0
            v[:] = v0
            a[:] = a0
            vr_started, vr_done = False, False
            vr_t0, vr_x0, vr_xf = 0.0, 0.0, 1.0
            vmc_x0, vmc_xf = x0[VMC], x0[VMC] + max(v0[VMC] * vmc_dur, 3.0 * params[VMC, P_LEN])
            vmc_done = not lat
            for k in range(K + 1):
                t = k * dt
                # lane membership (a changing vehicle occupies both lanes)
                for r in range(N_ROLES):
                    in1[r] = _LANE0[r] == 1
                    in2[r] = _LANE0[r] == 2
                if vr_started:
                    in1[VR] = True
                if lat:
                    in2[VMC] = True
                    if vmc_done:
                        in1[VMC] = False
                if pass_no == _JOINT:
                    for r in range(N_ROLES):
                        X[c, k, r], V[c, k, r], A[c, k, r] = x[r], v[r], a[r]
                    if vr_started and not vr_done:
                        xi = (x[VR] - vr_x0) / (vr_xf - vr_x0)
                        p, dp = quintic(xi)
                        Y[c, k, VR] = -width + width * p
                        HEAD[c, k, VR] = math.atan(width * dp / (vr_xf - vr_x0))
                    else:
                        Y[c, k, VR] = 0.0 if vr_done else -width
                    if lat and not vmc_done:
                        p, dp = quintic((x[VMC] - vmc_x0) / (vmc_xf - vmc_x0))
                        Y[c, k, VMC] = width * p
                        HEAD[c, k, VMC] = math.atan(width * dp / (vmc_xf - vmc_x0))
                    elif lat:
                        Y[c, k, VMC] = width
                    Y[c, k, VNF] = width
                    Y[c, k, VNR] = width
                    _near_pairs(X[c, k], Y[c, k], HEAD[c, k], present, params, near[c, k])
                if pass_no == _PRE and k * dt >= H:
                    # virtual-vehicle end states at the horizon (Eq. 8, 11)
                    _cubic(H, vv1_x, vv1_v, x[VR], v[VR], vv1[c])
                    _cubic(H, x0[VNF], v0[VNF], x[VMC], v[VMC], vv2[c])
                    break
                if k == K:
                    break
                # ---- accelerations from the step-k snapshot
                acc[VMF] = 0.0
                acc[VNF] = 0.0
                # VR
                if not vr_started:
                    acc[VR] = accel(params[VR], np.inf, v[VR], v[VR], 0.0)
                    if controlled_vr:
                        if t <= H:
                            xv, vv, av = _virtual(vv0[c], t)
                        else:
                            xv, vv, av = x[VMF], v[VMF], a[VMF]
                        gap = xv - params[VMF, P_LEN] - x[VR]
                        acc[VR] = min(acc[VR], accel(params[VR], gap, v[VR], vv, av))
                    else:
                        acc[VR] = min(
                            acc[VR], accel(params[VR], accel_end - x[VR], v[VR], 0.0, 0.0)
                        )
                else:
                    lead = VMF if pass_no == _PRE else _leader(VR, 1, x, in1, in2, present)
                    a_new = _behind(VR, lead, x, v, a, params)
                    if vr_done:
                        acc[VR] = a_new
                    else:
                        w = psi(t - vr_t0, vr_dur[c], gamma)
                        a_ori = accel(params[VR], np.inf, v[VR], v[VR], 0.0)
                        acc[VR] = w * a_new + (1.0 - w) * a_ori
                # VMC
                if present[VMC]:
                    if pass_no == _PRE:
                        lead1 = VMF
                        lead2 = VNF
                    else:
                        lead1 = _leader(VMC, 1, x, in1, in2, present)
                        lead2 = _leader(VMC, 2, x, in1, in2, present)
                    if lat:
                        a_new = _behind(VMC, lead2, x, v, a, params)
                        if vmc_done:
                            acc[VMC] = a_new
                        else:
                            w = psi(t, vmc_dur, gamma)
                            acc[VMC] = w * a_new + (1.0 - w) * _behind(VMC, lead1, x, v, a, params)
                    else:
                        acc[VMC] = _behind(VMC, lead1, x, v, a, params)
                        if lon and pass_no == _JOINT and not vr_done:
                            if t <= H:
                                xv, vv, av = _virtual(vv1[c], t)
                            else:
                                xv, vv, av = x[VR], v[VR], a[VR]
                            gap = xv - params[VR, P_LEN] - x[VMC]
                            acc[VMC] = min(acc[VMC], accel(params[VMC], gap, v[VMC], vv, av))
                # VMR and VNR
                if present[VMR]:
                    acc[VMR] = _behind(VMR, _leader(VMR, 1, x, in1, in2, present), x, v, a, params)
                if present[VNR]:
                    acc[VNR] = _behind(VNR, _leader(VNR, 2, x, in1, in2, present), x, v, a, params)
                    if lat and coop[VNR] and pass_no == _JOINT and t <= H:
                        xv, vv, av = _virtual(vv2[c], t)
                        gap = xv - params[VMC, P_LEN] - x[VNR]
                        acc[VNR] = min(acc[VNR], accel(params[VNR], gap, v[VNR], vv, av))
                _integrate(x, v, a, acc, present, dt, emergency)
                # ---- lane-change progress
                if not vr_started and x[VR] >= merge_x[c]:
                    vr_started = True
                    vr_t0, vr_x0 = t + dt, x[VR]
                    vr_xf = x[VR] + max(v[VR] * vr_dur[c], 3.0 * params[VR, P_LEN])
                    if pass_no == _JOINT:
                        g[c, G_OVERRUN] = vr_xf - accel_end
                if vr_started and not vr_done and x[VR] >= vr_xf:
                    vr_done = True
                    if pass_no == _JOINT:
                        k_merge[c] = k + 1
                if lat and not vmc_done and x[VMC] >= vmc_xf:
                    vmc_done = True
            if pass_no == _PRE and k * dt < H:
                # window shorter than the horizon: end states at the window's end
                _cubic(H, vv1_x, vv1_v, x[VR], v[VR], vv1[c])
                _cubic(H, x0[VNF], v0[VNF], x[VMC], v[VMC], vv2[c])
        if not vr_started:
            g[c, G_OVERRUN] = merge_x[c] - accel_end
        # ---- virtual-vehicle feasibility: v >= 0 and a >= -b_max on [0, H]
        worst_vv = -np.inf
        if controlled_vr:
            worst_vv = _cubic_violation(vv0[c], H, consts[C_VV_DECEL])
        if lon:
            worst_vv = max(worst_vv, _cubic_violation(vv1[c], H, consts[C_VV_DECEL]))
        if lat and coop[VNR] and present[VNR]:
            worst_vv = max(worst_vv, _cubic_violation(vv2[c], H, consts[C_VV_DECEL]))
        g[c, G_VIRTUAL] = max(worst_vv, 0.0) if worst_vv > -np.inf else 0.0
        # ---- Eq. 17 accumulated against the counterfactual (every step of the window)
        gain_vr, others = 0.0, 0.0
        for k in range(1, K + 1):
            gain_vr += A[c, k, VR] - Ac[k, VR]
            for r in (VMC, VMR, VNR):
                if present[r]:
                    others += A[c, k, r] - Ac[k, r]
        u_eff[c] = (gain_vr + consts[C_POLITENESS] * others) / K
        km = k_merge[c]
        if km < 0:
            g[c, G_NOT_MERGED] = 1.0
            continue
        u_safe[c] = _created_pairs_safety(X[c, km], V[c, km], Y[c, km], present, cav, params,
                                          lat, consts)  # fmt: skip
        if u_safe[c] == np.inf:
            g[c, G_UNSAFE] = 1.0
    return X, Y, V, A, HEAD, k_merge, u_safe, u_eff, g, vv0, vv1, vv2, near


@njit(cache=True)
def _created_pairs_safety(
    x: np.ndarray,
    v: np.ndarray,
    y: np.ndarray,
    present: np.ndarray,
    cav: np.ndarray,
    params: np.ndarray,
    lat: bool,
    consts: np.ndarray,
) -> float:
    """Eq. 15 over the follower-leader pairs the merge creates, the largest [m/s^2].

    Followers: VR (behind its new leader) and VR's new follower; in lateral mode also VMC
    (behind its lane-2 leader) and VNR (behind VMC). Each follower's leader is the nearest key
    vehicle ahead in its lane at merge completion (VMC counts in lane 2 once its centre has
    crossed the lane line). Pairs the plan does not change do not enter.
    """
    width = consts[C_WIDTH]
    lane_at = np.empty(N_ROLES, dtype=np.int64)
    for r in range(N_ROLES):
        lane_at[r] = _LANE0[r]
    lane_at[VR] = 1
    if lat and y[VMC] >= 0.5 * width:
        lane_at[VMC] = 2
    # VR's new follower: the nearest lane-1 key vehicle behind VR
    new_follower, best = -1, -np.inf
    for r in range(N_ROLES):
        if r != VR and present[r] and lane_at[r] == 1 and best < x[r] < x[VR]:
            new_follower, best = r, x[r]
    followers = np.array([VR, new_follower, VMC if lat else -1, VNR if lat else -1])
    worst = 0.0
    for r in followers:
        if r < 0 or not present[r]:
            continue
        lead, lead_x = -1, np.inf
        for j in range(N_ROLES):
            if j != r and present[j] and lane_at[j] == lane_at[r] and x[r] < x[j] < lead_x:
                lead, lead_x = j, x[j]
        if lead < 0:
            continue
        d = x[lead] - params[lead, P_LEN] - x[r]
        delay = consts[C_DELAY_CAV] if cav[r] else consts[C_DELAY_HDV]
        worst = max(worst, _critical(d, v[r], v[lead], delay, consts[C_D], consts[C_A_MERG]))
    return worst


@functools.cache  # once per process
def warm_up() -> None:
    """Load (or compile) the kernel once per process, so decision times exclude it."""
    params = np.tile(np.array([33.3, 1.0, 2.0, 1.4, 2.0, 4.0, 0.99, 5.0, 1.8]), (N_ROLES, 1))
    consts = np.zeros(N_CONSTS)
    consts[C_DT], consts[C_ACCEL_END], consts[C_WIDTH], consts[C_VMC_DUR] = 0.5, 950, 3.75, 4
    consts[C_GAMMA], consts[C_EMERGENCY], consts[C_VV_DECEL] = 2.3, 9.0, 7.5
    consts[C_D], consts[C_A_MERG], consts[C_DELAY_CAV], consts[C_DELAY_HDV] = 2.0, 7.5, 0.5, 1.0
    x = np.array([400.0, 380.0, 480.0, 300.0, 450.0, 330.0])
    one = np.ones(1)
    flags = np.ones(N_ROLES, dtype=np.bool_)
    v, a = np.full(N_ROLES, 25.0), np.zeros(N_ROLES)
    cf = np.stack(counterfactual(x, v, a, flags, params, consts, 4))
    rollout(x, v, a, flags, flags, flags, params, np.full(N_STARTS, np.nan), one * 800.0,
            one * 4.0, one * 6.0, np.zeros(1, dtype=np.bool_), consts, 4, cf)  # fmt: skip
