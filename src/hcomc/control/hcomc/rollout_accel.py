"""Accelerations of the key vehicles in one prediction step, from the step's snapshot.

The prediction assumptions (module docstring of :mod:`hcomc.control.hcomc.rollout`) in code:
VMF and VNF keep their speed; VR, VMC, VMR and VNR follow the nearest key vehicle ahead in
the lane(s) they occupy; during a lane change the accelerations behind the origin and the
target leader are blended by Eq. 14 (:func:`hcomc.models.transition.transition_psi` and
:func:`~hcomc.models.transition.blend`, their one home); a commanded vehicle also follows its
cubic virtual vehicle. In the pre-pass (``joint`` False) VR follows only VV0 and VMF, VMC only
VMF and VNF, and nobody follows VV1 or VV2 (their end states are not fixed yet).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hcomc.control.hcomc.rollout_layout import (
    L_LATERAL,
    L_VMC_DONE,
    L_VR_DONE,
    L_VR_STARTED,
    L_VR_T0,
    P_LEN,
    VMC,
    VMF,
    VMR,
    VNF,
    VNR,
    VR,
)
from hcomc.control.hcomc.rollout_step import (
    behind,
    behind_virtual,
    follow_role,
    free_road,
    leader,
)
from hcomc.models.transition import blend, transition_psi


@njit(cache=True, inline="always")
def vr_accel(
    x: np.ndarray, v: np.ndarray, a: np.ndarray, t: float, lc: np.ndarray, in1: np.ndarray,
    in2: np.ndarray, present: np.ndarray, params: np.ndarray, vvs: np.ndarray, horizon: float,
    vr_dur: float, controlled: bool, accel_end: float, gamma: float, joint: bool,
) -> float:  # fmt: skip
    """VR: on the ramp free road capped by VV0 (CAV) or the lane end (HDV); while merging the
    Eq. 14 blend from the free road to its lane-1 leader; after the merge that leader."""
    if not lc[L_VR_STARTED]:
        acc = free_road(params, VR, v[VR])
        if not controlled:
            return min(acc, follow_role(params, VR, accel_end - x[VR], v[VR], 0.0, 0.0))
        if t <= horizon:
            vv0 = behind_virtual(params, VR, x[VR], v[VR], vvs, 0, t, params[VMF, P_LEN])
            return min(acc, vv0)
        return min(acc, behind(VR, VMF, x, v, a, params))
    lead = leader(VR, 1, x, in1, in2, present) if joint else VMF
    a_new = behind(VR, lead, x, v, a, params)
    if lc[L_VR_DONE]:
        return a_new
    w = transition_psi(t - lc[L_VR_T0], vr_dur, gamma)
    return blend(free_road(params, VR, v[VR]), a_new, w)


@njit(cache=True, inline="always")
def vmc_accel(
    x: np.ndarray, v: np.ndarray, a: np.ndarray, t: float, lc: np.ndarray, in1: np.ndarray,
    in2: np.ndarray, present: np.ndarray, params: np.ndarray, vvs: np.ndarray, horizon: float,
    vmc_dur: float, gamma: float, longitudinal: bool, joint: bool,
) -> float:  # fmt: skip
    """VMC: its lane-1 leader, capped by VV1 in longitudinal mode until VR's merge ends; in
    lateral mode the Eq. 14 blend from its lane-1 to its lane-2 leader, then the latter."""
    lead1 = leader(VMC, 1, x, in1, in2, present) if joint else VMF
    acc = behind(VMC, lead1, x, v, a, params)
    if lc[L_LATERAL]:
        lead2 = leader(VMC, 2, x, in1, in2, present) if joint else VNF
        a_new = behind(VMC, lead2, x, v, a, params)
        if lc[L_VMC_DONE]:
            return a_new
        return blend(acc, a_new, transition_psi(t, vmc_dur, gamma))
    if not (longitudinal and joint) or lc[L_VR_DONE]:
        return acc
    if t <= horizon:
        vv = behind_virtual(params, VMC, x[VMC], v[VMC], vvs, 1, t, params[VR, P_LEN])
        return min(acc, vv)
    return min(acc, behind(VMC, VR, x, v, a, params))


@njit(cache=True, inline="always")
def vnr_accel(
    x: np.ndarray, v: np.ndarray, a: np.ndarray, t: float, lc: np.ndarray, in1: np.ndarray,
    in2: np.ndarray, present: np.ndarray, params: np.ndarray, vvs: np.ndarray, horizon: float,
    cooperates: bool, joint: bool,
) -> float:  # fmt: skip
    """VNR: its lane-2 leader, capped by VV2 within the horizon when it cooperates in
    lateral mode."""
    acc = behind(VNR, leader(VNR, 2, x, in1, in2, present), x, v, a, params)
    if lc[L_LATERAL] and cooperates and joint and t <= horizon:
        vv = behind_virtual(params, VNR, x[VNR], v[VNR], vvs, 2, t, params[VMC, P_LEN])
        acc = min(acc, vv)
    return acc


@njit(cache=True, inline="always")
def accelerations(
    acc: np.ndarray, x: np.ndarray, v: np.ndarray, a: np.ndarray, t: float, lc: np.ndarray,
    in1: np.ndarray, in2: np.ndarray, present: np.ndarray, coop: np.ndarray,
    params: np.ndarray, vvs: np.ndarray, horizon: float, vr_dur: float, controlled_vr: bool,
    longitudinal: bool, consts: tuple[float, float, float], joint: bool,
) -> None:  # fmt: skip
    """Fill ``acc`` (6,) for the step from ``t``; ``vvs`` (3, 4) holds VV0, VV1 and VV2,
    ``consts`` the acceleration-lane end, VMC's lateral change duration and Eq. 14's gamma."""
    accel_end, vmc_dur, gamma = consts
    acc[VMF] = 0.0
    acc[VNF] = 0.0
    acc[VR] = vr_accel(x, v, a, t, lc, in1, in2, present, params, vvs, horizon, vr_dur,
                       controlled_vr, accel_end, gamma, joint)  # fmt: skip
    if present[VMC]:
        acc[VMC] = vmc_accel(x, v, a, t, lc, in1, in2, present, params, vvs, horizon,
                             vmc_dur, gamma, longitudinal, joint)  # fmt: skip
    if present[VMR]:
        acc[VMR] = behind(VMR, leader(VMR, 1, x, in1, in2, present), x, v, a, params)
    if present[VNR]:
        acc[VNR] = vnr_accel(x, v, a, t, lc, in1, in2, present, params, vvs, horizon,
                             bool(coop[VNR]), joint)  # fmt: skip
