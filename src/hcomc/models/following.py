"""Car-following acceleration of one vehicle: Eq. (1) for HDVs, Eq. (3) for CAVs.

HDVs and CAVs share one code path: an HDV is an ACC vehicle with coolness c = 0, for which
Eq. (3) collapses to the IDM of Eq. (1) (its human factors — reaction delays and estimation
errors — act on the inputs, see :mod:`hcomc.sim.perception`). Either vehicle kind may use the
improved IDM instead of the IDM as its base model. The simulation step and the HCOMC
prediction both call :func:`follow_accel`.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray
from hcomc.models._broadcast import broadcast_apply
from hcomc.models.cav import acc_accel, cah_accel
from hcomc.models.idm import idm_accel_given, idm_free_power
from hcomc.models.iidm import iidm_accel_given, iidm_free_accel

__all__ = ["follow_accel", "follow_accel_given", "follow_acceleration", "free_term"]


@kernel
def follow_accel(
    s: float,
    v: float,
    vl: float,
    al: float,
    v0: float,
    T: float,
    s0: float,
    a: float,
    b: float,
    delta: float,
    c: float,
    iidm: bool,
) -> float:
    """Car-following acceleration of one vehicle [m/s^2] (Eq. 1, or Eq. 3 for c > 0).

    Parameters
    ----------
    s : bumper-to-bumper gap to the leader [m], ``inf`` without a leader.
    v, vl : own and leader speed [m/s] (``vl`` is ignored without a leader).
    al : leader acceleration [m/s^2] (used by the CAH of CAVs only).
    v0, T, s0, a, b, delta : IDM parameters of Eq. (1).
    c : coolness of Eq. (3); 0 gives the plain (I)IDM.
    iidm : use the improved IDM as the base model.

    Without a leader the ACC reduces to the free-road (I)IDM: Kesting et al. (2010) define
    the CAH for a leader only.
    """
    free = free_term(v, v0, a, b, delta, iidm)
    return follow_accel_given(s, v, vl, al, v0, T, s0, a, b, c, iidm, free)


@kernel(inline="always")
def free_term(v: float, v0: float, a: float, b: float, delta: float, iidm: bool) -> float:
    """The part of :func:`follow_accel` that depends on the own speed alone: the IDM's
    ``(v / v0)^delta`` or the IIDM's free-road acceleration."""
    return iidm_free_accel(v, v0, a, b, delta) if iidm else idm_free_power(v, v0, delta)


@kernel
def follow_accel_given(
    s: float, v: float, vl: float, al: float, v0: float, T: float, s0: float, a: float,
    b: float, c: float, iidm: bool, free: float,
) -> float:  # fmt: skip
    """:func:`follow_accel` with its :func:`free_term` ``free`` given (the same value): a
    vehicle evaluated behind several leaders at one speed takes the power once."""
    finite = not math.isinf(s)
    dv = v - vl if finite else 0.0
    if iidm:
        acc = iidm_accel_given(s, v, dv, v0, T, a, b, s0, free)
    else:
        acc = idm_accel_given(s, v, dv, T, a, b, s0, free)
    if c > 0.0 and finite:
        acc = acc_accel(acc, cah_accel(s, v, vl, al, a), b, c)
    return acc


@kernel
def _follow_array(
    s: np.ndarray, v: np.ndarray, vl: np.ndarray, al: np.ndarray, v0: np.ndarray, T: np.ndarray,
    s0: np.ndarray, a: np.ndarray, b: np.ndarray, delta: np.ndarray, c: np.ndarray,
    iidm: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(s.size)
    for i in range(s.size):
        out[i] = follow_accel(
            s[i], v[i], vl[i], al[i], v0[i], T[i], s0[i], a[i], b[i], delta[i], c[i], iidm[i] > 0.5
        )
    return out


def follow_acceleration(
    s: FloatArray | float,
    v: FloatArray | float,
    vl: FloatArray | float,
    al: FloatArray | float,
    *,
    v0: FloatArray | float,
    T: FloatArray | float,
    s0: FloatArray | float,
    a: FloatArray | float,
    b: FloatArray | float,
    delta: FloatArray | float,
    c: FloatArray | float,
    iidm: FloatArray | BoolArray | bool,
) -> FloatArray:
    """Array form of :func:`follow_accel` (arguments broadcast) [m/s^2]."""
    return broadcast_apply(_follow_array, s, v, vl, al, v0, T, s0, a, b, delta, c, iidm)
