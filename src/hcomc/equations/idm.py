r"""The Intelligent Driver Model (IDM), paper Eq. (1): car following of every vehicle.

The paper builds the longitudinal models of both vehicle kinds on the IDM of Treiber,
Hennecke & Helbing (2000):

.. math::
   a_n(s_n, v_n, \Delta v_n) = a\left[1 - \left(\frac{v_n}{v_0}\right)^{\delta}
       - \left(\frac{s^*(v_n, \Delta v_n)}{s_n}\right)^2\right], \qquad
   s^*(v_n, \Delta v_n) = s_0 + \max\left(0,\ v_n T_s + \frac{v_n \Delta v_n}{2\sqrt{ab}}\right)

where, in the paper's words, :math:`a_n` is the desired acceleration, :math:`s_n` the actual
car-following distance, :math:`v_n` the actual speed, :math:`\Delta v_n` the speed difference
between the subject vehicle and its leading vehicle, :math:`a` the maximum desired
acceleration, :math:`v_0` the desired speed, :math:`\delta` the acceleration index,
:math:`s_0` the desired car-following distance (the jam gap), :math:`s^*` the "static safety
distance" (the desired gap), :math:`T_s` the safety time headway and :math:`b` the comfort
deceleration.

Public functions: :func:`desired_gap` (:math:`s^*`), :func:`idm_acceleration` (:math:`a_n`)
and :func:`equilibrium_gap` (the steady state). The improved IDM, offered as a switch, is
:mod:`hcomc.equations.iidm`; the acceleration of either vehicle kind,
:mod:`hcomc.equations.car_following`. The array functions take scalars or arrays (for
example one entry per vehicle, with per-vehicle parameter arrays), broadcast them with numpy's rules
and return ``float64`` arrays; each applies a compiled one-vehicle kernel (``idm_accel``), which the
simulation step and the HCOMC prediction call directly.

Sign conventions: ``s`` is the bumper-to-bumper gap to the leader [m] (``np.inf`` when there
is no leader), ``v`` the own speed [m/s] and ``dv = v - v_leader`` the approach rate [m/s]
(positive when closing in).

References
----------
.. [1] M. Treiber, A. Hennecke and D. Helbing, "Congested traffic states in empirical
   observations and microscopic simulations", Phys. Rev. E 62, 1805-1824 (2000).
.. [2] M. Treiber and A. Kesting, "Traffic Flow Dynamics", Springer (2013), Ch. 11.
.. [3] Wang, Wang, Pan, Jiao and Claudel, "HCOMC: A Hierarchical Cooperative On-Ramp Merging
   Control Framework in Mixed Traffic Environment on Two-Lane Highways", arXiv:2507.11621,
   Section II-B-1, Eq. (1).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["desired_gap", "equilibrium_gap", "idm_acceleration"]

S_MIN: float = 1e-3
"""Lower guard on the gap [m] used in the interaction term (avoids division by zero)."""


def desired_gap(
    v: FloatArray | float,
    dv: FloatArray | float,
    *,
    T: FloatArray | float,
    a: FloatArray | float,
    b: FloatArray | float,
    s0: FloatArray | float,
) -> FloatArray:
    r"""Desired (dynamic safety) gap :math:`s^*` of the IDM, paper Eq. (1).

    .. math::
       :label: eq-1-sstar

       s^*(v, \Delta v) = s_0 + \max\left(0,\; vT + \frac{v\,\Delta v}{2\sqrt{ab}}\right)

    The paper calls :math:`s^*` the static safety distance: the gap the driver wants to keep
    at speed :math:`v` when approaching its leader at :math:`\Delta v`. The
    :math:`\max(0,\cdot)` clamp keeps :math:`s^* \ge s_0` when the leader is much faster
    (large negative ``dv``).

    Parameters
    ----------
    v : float or array_like
        Own speed :math:`v_n` [m/s].
    dv : float or array_like
        Approach rate :math:`\Delta v_n` = ``v - v_leader`` [m/s], positive when closing in.
    T : float or array_like
        Safety time headway :math:`T_s` [s].
    a : float or array_like
        Maximum desired acceleration :math:`a` [m/s^2], > 0.
    b : float or array_like
        Comfort deceleration :math:`b` (positive) [m/s^2], > 0.
    s0 : float or array_like
        Jam gap :math:`s_0` (the paper's "desired car-following distance") [m].

    Returns
    -------
    numpy.ndarray
        Desired gap :math:`s^*` [m], broadcast shape of the inputs, ``float64``.

    References
    ----------
    .. [1] Treiber, Hennecke & Helbing, Phys. Rev. E 62, 1805 (2000).
    .. [2] HCOMC paper (arXiv:2507.11621), Eq. (1).

    Examples
    --------
    >>> float(desired_gap(20.0, 0.0, T=1.5, a=1.0, b=2.0, s0=2.0))
    32.0
    >>> float(desired_gap(20.0, -100.0, T=1.5, a=1.0, b=2.0, s0=2.0))
    2.0
    """
    return broadcast_apply(_desired_gap_array, v, dv, T, a, b, s0)


@kernel
def desired_gap_scalar(v: float, dv: float, T: float, a: float, b: float, s0: float) -> float:
    """:func:`desired_gap` of one vehicle [m]: its compiled kernel (same arguments,
    positional), which the other kernels call."""
    return max(v * T + v * dv / (2.0 * math.sqrt(a * b)), 0.0) + s0


@kernel
def _desired_gap_array(
    v: np.ndarray, dv: np.ndarray, T: np.ndarray, a: np.ndarray, b: np.ndarray, s0: np.ndarray
) -> np.ndarray:
    out = np.empty(v.size)
    for i in range(v.size):
        out[i] = desired_gap_scalar(v[i], dv[i], T[i], a[i], b[i], s0[i])
    return out


def idm_acceleration(
    s: FloatArray | float,
    v: FloatArray | float,
    dv: FloatArray | float,
    *,
    v0: FloatArray | float,
    T: FloatArray | float,
    a: FloatArray | float,
    b: FloatArray | float,
    s0: FloatArray | float,
    delta: FloatArray | float,
) -> FloatArray:
    r"""IDM acceleration, paper Eq. (1).

    .. math::
       :label: eq-1-idm

       \dot v = a\left[1 - \left(\frac{v}{v_0}\right)^{\delta}
                - \left(\frac{s^*(v, \Delta v)}{s}\right)^2\right]

    with :math:`s^*` from :func:`desired_gap`: the free-road term
    :math:`1 - (v/v_0)^\delta` drives the vehicle towards its desired speed, the interaction
    term :math:`(s^*/s)^2` keeps it behind its leader.

    Parameters
    ----------
    s : float or array_like
        Actual car-following distance :math:`s_n`, the bumper-to-bumper gap to the leader
        [m]. ``np.inf`` means no leader (the interaction term is then exactly 0).
    v : float or array_like
        Own speed :math:`v_n` [m/s].
    dv : float or array_like
        Approach rate :math:`\Delta v_n` = ``v - v_leader`` [m/s].
    v0 : float or array_like
        Desired speed :math:`v_0` [m/s], > 0.
    T : float or array_like
        Safety time headway :math:`T_s` [s].
    a : float or array_like
        Maximum desired acceleration :math:`a` [m/s^2], > 0.
    b : float or array_like
        Comfort deceleration :math:`b` (positive) [m/s^2], > 0.
    s0 : float or array_like
        Jam gap :math:`s_0` [m].
    delta : float or array_like
        Acceleration index :math:`\delta` [-] (4 by default).

    Returns
    -------
    numpy.ndarray
        Desired acceleration :math:`a_n` [m/s^2], ``float64``, broadcast shape of the inputs.

    Notes
    -----
    The paper does not say what happens at a gap ``<= 0`` (an overlap after a collision or a
    cut-in): the gap is floored at 1e-3 m (:data:`S_MIN`), which gives a very strong but finite
    deceleration instead of a division by zero. A whole exponent :math:`\delta` (1 to 16) is
    taken by binary powering rather than the C library's ``pow`` (within
    :math:`(\delta - 1)\,2^{-53}` relative, at a fraction of the cost): the power is taken for
    every vehicle at every step of the simulation and of the HCOMC prediction.

    See Also
    --------
    hcomc.equations.iidm.iidm_acceleration : improved IDM with the same parameters.
    equilibrium_gap : steady-state gap at which this acceleration is zero.

    References
    ----------
    .. [1] Treiber, Hennecke & Helbing, Phys. Rev. E 62, 1805 (2000).
    .. [2] HCOMC paper (arXiv:2507.11621), Eq. (1).

    Examples
    --------
    >>> float(idm_acceleration(np.inf, 0.0, 0.0, v0=33.3, T=1.5, a=1.0, b=2.0, s0=2.0, delta=4))
    1.0
    """
    return broadcast_apply(_idm_array, s, v, dv, v0, T, a, b, s0, delta)


@kernel
def idm_accel(
    s: float, v: float, dv: float, v0: float, T: float, a: float, b: float, s0: float, delta: float
) -> float:
    """IDM acceleration of one vehicle, paper Eq. (1) [m/s^2]: the one implementation of
    :func:`idm_acceleration` (same arguments, positional)."""
    return idm_accel_given(s, v, dv, T, a, b, s0, idm_free_power(v, v0, delta))


@kernel(inline="always")
def idm_free_power(v: float, v0: float, delta: float) -> float:
    """The free-road term ``(v / v0)^delta`` of Eq. (1), which depends on the own speed alone."""
    return power(v / v0, delta)


@kernel(inline="always")
def power(base: float, exponent: float) -> float:
    """``base ** exponent``, a whole exponent n in 1 … 16 (the default delta = 4) by binary
    powering: the product of n factors, within (n - 1) 2^-53 of the exact power (2 ulp for
    n = 4), at a fraction of the cost of the C library's ``pow``, which takes the others.

    The car-following powers are taken for every vehicle at every step of the simulation and
    of the HCOMC prediction, so their cost counts.
    """
    if 1.0 <= exponent <= 16.0 and exponent == math.floor(exponent):
        n = int(exponent)
        result = 1.0
        while True:
            if n & 1:
                result *= base
            n >>= 1
            if n == 0:
                return result
            base *= base
    return base**exponent


@kernel
def idm_accel_given(
    s: float, v: float, dv: float, T: float, a: float, b: float, s0: float, power: float
) -> float:
    """:func:`idm_accel` with its free-road term ``power`` = :func:`idm_free_power` given, so
    that a caller evaluating one vehicle behind several leaders takes the power once."""
    z = desired_gap_scalar(v, dv, T, a, b, s0) / max(s, S_MIN)
    return a * (1.0 - power - z * z)


@kernel
def _free_power_array(v: np.ndarray, v0: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """:func:`idm_free_power` of each element: the powers the step takes (C library or exact
    squaring), never numpy's, whose ``power`` is chosen by the CPU."""
    out = np.empty(v.size)
    for i in range(v.size):
        out[i] = idm_free_power(v[i], v0[i], delta[i])
    return out


@kernel
def _idm_array(
    s: np.ndarray, v: np.ndarray, dv: np.ndarray, v0: np.ndarray, T: np.ndarray, a: np.ndarray,
    b: np.ndarray, s0: np.ndarray, delta: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(s.size)
    for i in range(s.size):
        out[i] = idm_accel(s[i], v[i], dv[i], v0[i], T[i], a[i], b[i], s0[i], delta[i])
    return out


def equilibrium_gap(
    v: FloatArray | float,
    *,
    v0: FloatArray | float,
    T: FloatArray | float,
    s0: FloatArray | float,
    delta: FloatArray | float,
) -> FloatArray:
    r"""Steady-state (equilibrium) gap of the IDM for a leader at the same speed.

    Setting :math:`\dot v = 0` and :math:`\Delta v = 0` in Eq. (1):

    .. math::
       :label: eq-1-idm-equilibrium

       s_e(v) = \frac{s_0 + vT}{\sqrt{1 - (v/v_0)^{\delta}}}, \qquad v < v_0

    and :math:`s_e = \infty` for :math:`v \ge v_0` (no finite gap sustains the desired speed).
    It does not depend on ``a`` and ``b``.

    Parameters
    ----------
    v : float or array_like
        Speed [m/s].
    v0 : float or array_like
        Desired speed [m/s].
    T : float or array_like
        Desired time gap [s].
    s0 : float or array_like
        Minimum (jam) gap [m].
    delta : float or array_like
        Acceleration exponent [-].

    Returns
    -------
    numpy.ndarray
        Equilibrium gap [m] (``inf`` where ``v >= v0``), ``float64``.

    References
    ----------
    .. [1] Treiber, Hennecke & Helbing, Phys. Rev. E 62, 1805 (2000).
    .. [2] Treiber & Kesting, Traffic Flow Dynamics (2013), Sec. 11.3.

    Examples
    --------
    >>> round(float(equilibrium_gap(20.0, v0=33.3, T=1.5, s0=2.0, delta=4)), 2)
    34.31
    """
    v = np.asarray(v, dtype=np.float64)
    denom = 1.0 - broadcast_apply(_free_power_array, v, v0, delta)
    valid = denom > 0.0
    gap = (s0 + v * T) / np.sqrt(np.where(valid, denom, 1.0))
    return np.asarray(np.where(valid, gap, np.inf), dtype=np.float64)
