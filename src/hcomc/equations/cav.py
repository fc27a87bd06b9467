r"""The CAV car-following model, paper Eq. (3): ACC with the constant-acceleration heuristic.

The paper models connected and automated vehicles by integrating "the constant acceleration
heuristic into IDM" (the ACC model of Kesting, Treiber & Helbing 2010):

.. math::
   a_n^{CAV} = (1 - c)\,a_\mathrm{IDM}
       + c\left[a_\mathrm{CAH} + b\tanh\left(\frac{a_\mathrm{IDM} - a_\mathrm{CAH}}{b}\right)\right]

where, in the paper's words, :math:`a_\mathrm{CAH}` denotes the maximum acceleration leading to
no crashes, :math:`a_\mathrm{IDM}` the acceleration of the traditional IDM (Eq. 1,
:mod:`hcomc.equations.idm`) and :math:`c` the cooling factor (Kesting's "coolness"). The
public functions are :func:`cah_acceleration` (:math:`a_\mathrm{CAH}`) and
:func:`acc_acceleration` (the blend); each applies a compiled one-vehicle kernel
(``cah_accel``, ``acc_accel``), which :func:`hcomc.equations.car_following.follow_acceleration`
and the simulation step call.

Sign conventions as in :mod:`hcomc.equations.idm`: ``s`` is the bumper-to-bumper gap [m]
(``np.inf`` for no leader), ``v`` the own speed and ``v_l`` the leader speed [m/s], ``a_l``
the leader acceleration [m/s^2] (in a connected setting, the leader's broadcast acceleration).

References
----------
.. [1] A. Kesting, M. Treiber and D. Helbing, "Enhanced intelligent driver model to access the
   impact of driving strategies on traffic capacity", Phil. Trans. R. Soc. A 368, 4585-4605
   (2010), arXiv:0912.3613.
.. [2] MovSim ``ACC.java``; SUMO ``MSCFModel_EIDM.cpp`` (same CAH and blend).
.. [3] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section II-B-1, Eq. (3).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["acc_acceleration", "cah_acceleration"]

S_MIN_CAH: float = 0.01
"""Lower guard on the gap [m] in the CAH (as in MovSim and SUMO)."""


def cah_acceleration(
    s: FloatArray | float,
    v: FloatArray | float,
    v_l: FloatArray | float,
    a_l: FloatArray | float,
    *,
    a: FloatArray | float,
) -> FloatArray:
    r"""Constant-acceleration heuristic (CAH), :math:`a_\mathrm{CAH}` of paper Eq. (3).

    With the leader acceleration capped at the own maximum acceleration,
    :math:`\tilde a_l = \min(a_l, a)`,

    .. math::
       :label: eq-3-cah

       a_\mathrm{CAH} = \begin{cases}
         \dfrac{v^2\,\tilde a_l}{v_l^2 - 2 s \tilde a_l}
           & v_l\,(v - v_l) \le -2 s \tilde a_l \\[1ex]
         \tilde a_l - \dfrac{(v - v_l)^2\,\Theta(v - v_l)}{2 s} & \text{otherwise}
       \end{cases}

    where :math:`\Theta` is the Heaviside step function: the largest acceleration that avoids
    a crash if the leader keeps its current acceleration (the paper's "maximum acceleration
    leading to no crashes"). The first branch is the case in which both vehicles would come
    to a stop before the gap closes.

    Parameters
    ----------
    s : float or array_like
        Bumper-to-bumper gap [m], guarded by ``s >= 0.01`` (:data:`S_MIN_CAH`). ``np.inf`` means
        no leader; the result is then :math:`\tilde a_l` (so pass the own acceleration, as
        MovSim does, or 0 as ``a_l`` for vehicles without a leader).
    v : float or array_like
        Own speed [m/s].
    v_l : float or array_like
        Leader speed [m/s].
    a_l : float or array_like
        Leader acceleration [m/s^2].
    a : float or array_like
        Own maximum acceleration [m/s^2], the cap on ``a_l``.

    Returns
    -------
    numpy.ndarray
        CAH acceleration [m/s^2], ``float64``, broadcast shape of the inputs.

    Notes
    -----
    The paper does not state the CAH; this is Kesting et al.'s (2010), with the leader's
    acceleration capped at the own maximum. The first branch is only used where its
    denominator :math:`v_l^2 - 2 s \tilde a_l` is strictly positive. Under the branch condition the
    denominator is :math:`\ge v\,v_l \ge 0` and vanishes only in the degenerate cases ``v = 0`` or
    ``v_l = 0 = a_l``; there the second
    branch is used instead, as MovSim does (``denomCAH != 0``). No division by zero or runtime
    warning occurs for any finite input.

    References
    ----------
    .. [1] Kesting, Treiber & Helbing, Phil. Trans. R. Soc. A 368, 4585 (2010).
    .. [2] MovSim ``ACC.java`` (``calcAcc``); SUMO ``MSCFModel_EIDM.cpp``.

    Examples
    --------
    Stopped leader (``a_l = 0``), closing at 10 m/s from 50 m: deceleration to stop exactly at
    the leader, -v^2/(2s).

    >>> float(cah_acceleration(50.0, 10.0, 0.0, 0.0, a=1.4))
    -1.0
    """
    return broadcast_apply(_cah_array, s, v, v_l, a_l, a)


@kernel
def cah_accel(s: float, v: float, v_l: float, a_l: float, a: float) -> float:
    """CAH acceleration of one vehicle [m/s^2]: the one implementation of
    :func:`cah_acceleration` (same arguments, positional)."""
    a_lt = min(a_l, a)
    if math.isinf(s):
        return a_lt
    s_g = max(s, S_MIN_CAH)
    two_s_a = 2.0 * s_g * a_lt
    denom = v_l * v_l - two_s_a
    if v_l * (v - v_l) <= -two_s_a and denom > 0.0:
        return v * v * a_lt / denom
    dvp = max(v - v_l, 0.0)
    return a_lt - dvp * dvp / (2.0 * s_g)


@kernel
def _cah_array(
    s: np.ndarray, v: np.ndarray, v_l: np.ndarray, a_l: np.ndarray, a: np.ndarray
) -> np.ndarray:
    out = np.empty(s.size)
    for i in range(s.size):
        out[i] = cah_accel(s[i], v[i], v_l[i], a_l[i], a[i])
    return out


def acc_acceleration(
    a_idm: FloatArray | float,
    a_cah: FloatArray | float,
    *,
    b: FloatArray | float,
    c: FloatArray | float,
) -> FloatArray:
    r"""ACC acceleration: IDM/CAH blend with coolness factor, paper Eq. (3).

    .. math::
       :label: eq-3-acc

       a_\mathrm{ACC} = \begin{cases}
         a_\mathrm{IDM} & a_\mathrm{IDM} \ge a_\mathrm{CAH} \\
         (1 - c)\,a_\mathrm{IDM} + c\left[a_\mathrm{CAH}
           + b \tanh\left(\dfrac{a_\mathrm{IDM} - a_\mathrm{CAH}}{b}\right)\right]
           & \text{otherwise}
       \end{cases}

    The paper's Eq. (3) prints only the second branch; the first branch of Kesting et al. (2010)
    is restored here. Without it, a large :math:`a_\mathrm{IDM}`
    would be capped near :math:`a_\mathrm{CAH} + b`.

    Parameters
    ----------
    a_idm : float or array_like
        :math:`a_\mathrm{IDM}`, the IDM (or IIDM) acceleration of Eq. (1) [m/s^2].
    a_cah : float or array_like
        CAH acceleration from :func:`cah_acceleration` [m/s^2].
    b : float or array_like
        Comfort deceleration :math:`b` (positive) [m/s^2], > 0.
    c : float or array_like
        Coolness factor :math:`c` [-] in [0, 1] (the paper's "cooling factor"); 0 recovers
        the IDM, Kesting's default is 0.99.

    Returns
    -------
    numpy.ndarray
        ACC acceleration [m/s^2], ``float64``, broadcast shape of the inputs.

    References
    ----------
    .. [1] Kesting, Treiber & Helbing, Phil. Trans. R. Soc. A 368, 4585 (2010).
    .. [2] HCOMC paper (arXiv:2507.11621), Eq. (3).

    Examples
    --------
    >>> float(acc_acceleration(0.5, -1.0, b=2.0, c=0.99))
    0.5
    """
    return broadcast_apply(_acc_array, a_idm, a_cah, b, c)


@kernel
def acc_accel(a_idm: float, a_cah: float, b: float, c: float) -> float:
    """ACC acceleration of one vehicle, Eq. (3) [m/s^2]: the one implementation of
    :func:`acc_acceleration` (same arguments, positional)."""
    if a_idm >= a_cah:
        return a_idm
    return (1.0 - c) * a_idm + c * (a_cah + b * math.tanh((a_idm - a_cah) / b))


@kernel
def _acc_array(a_idm: np.ndarray, a_cah: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    out = np.empty(a_idm.size)
    for i in range(a_idm.size):
        out[i] = acc_accel(a_idm[i], a_cah[i], b[i], c[i])
    return out
