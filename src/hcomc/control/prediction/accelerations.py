"""Accelerations of the key vehicles in one prediction step, from the step's snapshot.

The prediction assumptions (module docstring of :mod:`hcomc.control.prediction.population`) in code:
VMF and VNF keep their speed; VR, VMC, VMR and VNR follow the nearest key vehicle ahead in
the lane(s) they occupy; during a lane change the accelerations behind the origin and the
target leader are blended by Eq. 14 (:func:`hcomc.equations.transition.transition_psi` and
:func:`~hcomc.equations.transition.blend`, their one home); a commanded vehicle also follows its
cubic virtual vehicle. In the pre-pass (``joint`` False) VR follows only VV0 and VMF, VMC only
VMF and VNF, and nobody follows VV1 or VV2 (their end states are not fixed yet).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.control.prediction.layout import (
    L_LATERAL,
    L_VMC_DONE,
    L_VR_DONE,
    L_VR_STARTED,
    L_VR_T0,
    P_LEN,
    R_ACC,
    R_PRESENT,
    R_X,
    VMC,
    VMF,
    VMR,
    VNF,
    VNR,
    VR,
)
from hcomc.control.prediction.step import (
    behind,
    behind_virtual,
    follow_role,
    free_road,
    leader,
)
from hcomc.equations.transition import blend, transition_psi


@kernel(inline="always")
def vr_accel(
    S: np.ndarray, lc: np.ndarray, params: np.ndarray, vvs: np.ndarray, t: float,
    horizon: float, vr_dur: float, controlled: bool, accel_end: float, gamma: float,
    joint: bool,
) -> float:  # fmt: skip
    """VR: on the ramp free road capped by VV0 (CAV) or the lane end (HDV); while merging the
    Eq. 14 blend from the free road to its lane-1 leader; after the merge that leader."""
    if not lc[L_VR_STARTED]:
        acc = free_road(S, params, VR)
        if not controlled:
            gap = accel_end - S[R_X, VR]
            return min(acc, follow_role(S, params, VR, gap, 0.0, 0.0))
        if t <= horizon:
            return min(acc, behind_virtual(S, params, VR, vvs, 0, t, params[VMF, P_LEN]))
        return min(acc, behind(S, params, VR, VMF))
    a_new = behind(S, params, VR, leader(S, VR, 1) if joint else VMF)
    if lc[L_VR_DONE]:
        return a_new
    w = transition_psi(t - lc[L_VR_T0], vr_dur, gamma)
    return blend(free_road(S, params, VR), a_new, w)


@kernel(inline="always")
def vmc_accel(
    S: np.ndarray, lc: np.ndarray, params: np.ndarray, vvs: np.ndarray, t: float,
    horizon: float, vmc_dur: float, gamma: float, longitudinal: bool, joint: bool,
) -> float:  # fmt: skip
    """VMC: its lane-1 leader, capped by VV1 in longitudinal mode until VR's merge ends; in
    lateral mode the Eq. 14 blend from its lane-1 to its lane-2 leader, then the latter."""
    acc = behind(S, params, VMC, leader(S, VMC, 1) if joint else VMF)
    if lc[L_LATERAL]:
        a_new = behind(S, params, VMC, leader(S, VMC, 2) if joint else VNF)
        if lc[L_VMC_DONE]:
            return a_new
        return blend(acc, a_new, transition_psi(t, vmc_dur, gamma))
    if not (longitudinal and joint) or lc[L_VR_DONE]:
        return acc
    if t <= horizon:
        return min(acc, behind_virtual(S, params, VMC, vvs, 1, t, params[VR, P_LEN]))
    return min(acc, behind(S, params, VMC, VR))


@kernel(inline="always")
def vnr_accel(
    S: np.ndarray, lc: np.ndarray, params: np.ndarray, vvs: np.ndarray, t: float,
    horizon: float, cooperates: bool, joint: bool,
) -> float:  # fmt: skip
    """VNR: its lane-2 leader, capped by VV2 within the horizon when it cooperates in
    lateral mode."""
    acc = behind(S, params, VNR, leader(S, VNR, 2))
    if lc[L_LATERAL] and cooperates and joint and t <= horizon:
        acc = min(acc, behind_virtual(S, params, VNR, vvs, 2, t, params[VMC, P_LEN]))
    return acc


@kernel(inline="always")
def accelerations(
    S: np.ndarray, lc: np.ndarray, params: np.ndarray, vvs: np.ndarray, t: float,
    horizon: float, vr_dur: float, flags: tuple[bool, bool, bool],
    consts: tuple[float, float, float], joint: bool, vr_known: float, vnr_known: bool,
) -> None:  # fmt: skip
    """Fill ``S[R_ACC]`` for the step from ``t``. ``vvs`` (3, 4) holds VV0, VV1 and VV2;
    ``flags`` whether VR is controlled, VMC follows VV1 (longitudinal mode) and VNR
    cooperates; ``consts`` the acceleration-lane end, VMC's lateral change duration and
    Eq. 14's gamma; ``vr_known`` VR's acceleration when the caller knows it already (NaN:
    compute it); ``vnr_known`` True leaves VNR's to the caller."""
    controlled_vr, longitudinal, coop_vnr = flags
    accel_end, vmc_dur, gamma = consts
    S[R_ACC, VMF] = 0.0
    S[R_ACC, VNF] = 0.0
    if math.isnan(vr_known):
        S[R_ACC, VR] = vr_accel(S, lc, params, vvs, t, horizon, vr_dur, controlled_vr,
                                accel_end, gamma, joint)  # fmt: skip
    else:
        S[R_ACC, VR] = vr_known
    if S[R_PRESENT, VMC]:
        S[R_ACC, VMC] = vmc_accel(S, lc, params, vvs, t, horizon, vmc_dur, gamma,
                                  longitudinal, joint)  # fmt: skip
    if S[R_PRESENT, VMR]:
        S[R_ACC, VMR] = behind(S, params, VMR, leader(S, VMR, 1))
    if S[R_PRESENT, VNR] and not vnr_known:
        S[R_ACC, VNR] = vnr_accel(S, lc, params, vvs, t, horizon, coop_vnr, joint)
