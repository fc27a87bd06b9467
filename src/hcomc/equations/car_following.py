r"""Car-following acceleration of either vehicle kind: Eq. (1) for HDVs, Eq. (3) for CAVs.

The paper adopts the IDM "as the basic model to construct the car-following models of HDVs
and CAVs" (Section II-B-1). Both kinds share one code path here: an HDV is an ACC vehicle with
coolness :math:`c = 0`, for which Eq. (3) collapses to the IDM of Eq. (1); its human factors of
Eq. (2), reaction delays and estimation errors, act on the inputs (the gap and speeds it is
given), which :mod:`hcomc.sim.perception` forms. Either kind may use the improved IDM
(:mod:`hcomc.equations.iidm`) as its base model.

The public function is :func:`follow_acceleration`; its compiled one-vehicle kernel
``follow_accel`` is what the simulation step and the HCOMC prediction
call. ``follow_accel`` is split in two kernels so that a vehicle evaluated behind several
candidate leaders at one speed (MOBIL, the prediction) takes the power of its speed once:
``free_term`` (the part of Eq. 1 that depends on the own speed alone) and
``follow_accel_given`` (the rest, with that term given).

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section II-B-1,
   Eqs. (1)-(3).
.. [2] A. Kesting, M. Treiber and D. Helbing, Phil. Trans. R. Soc. A 368, 4585 (2010).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray
from hcomc.equations._broadcast import broadcast_apply
from hcomc.equations.cav import acc_accel, cah_accel
from hcomc.equations.idm import idm_accel_given, idm_free_power
from hcomc.equations.iidm import iidm_accel_given, iidm_free_accel

__all__ = ["follow_acceleration"]


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
    """Car-following acceleration of one vehicle [m/s^2] (Eq. 1, or Eq. 3 for c > 0): the
    compiled kernel of :func:`follow_acceleration` (same arguments, positional; ``iidm`` a
    bool)."""
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
    r"""Car-following acceleration of HDVs (paper Eq. 1) and CAVs (paper Eq. 3).

    .. math::
       :label: eq-1-3-follow

       a = \begin{cases}
         a_\mathrm{IDM}(s, v, v - v_l) & c = 0 \text{ or no leader} \\
         a_\mathrm{ACC}\big(a_\mathrm{IDM}(s, v, v - v_l),\
           a_\mathrm{CAH}(s, v, v_l, a_l)\big) & c > 0
       \end{cases}

    with :math:`a_\mathrm{IDM}` the IDM of Eq. (1)
    (:func:`~hcomc.equations.idm.idm_acceleration`) or, with ``iidm``, the improved IDM
    (:func:`~hcomc.equations.iidm.iidm_acceleration`), and :math:`a_\mathrm{CAH}`,
    :math:`a_\mathrm{ACC}` the heuristic and the blend of Eq. (3)
    (:func:`~hcomc.equations.cav.cah_acceleration`, :func:`~hcomc.equations.cav.acc_acceleration`).

    Parameters
    ----------
    s : float or array_like
        Bumper-to-bumper gap to the leader [m]; ``np.inf`` without a leader.
    v : float or array_like
        Own speed [m/s].
    vl : float or array_like
        Leader speed [m/s] (ignored without a leader).
    al : float or array_like
        Leader acceleration [m/s^2] (used by the CAH of CAVs only).
    v0 : float or array_like
        Desired speed :math:`v_0` [m/s].
    T : float or array_like
        Safety time headway :math:`T_s` [s].
    s0 : float or array_like
        Jam gap :math:`s_0` [m].
    a : float or array_like
        Maximum desired acceleration :math:`a` [m/s^2].
    b : float or array_like
        Comfort deceleration :math:`b` [m/s^2].
    delta : float or array_like
        Acceleration index :math:`\delta` [-].
    c : float or array_like
        Coolness factor of Eq. (3) [-]: 0 for HDVs (the plain IDM or IIDM), 0.99 for CAVs by
        default.
    iidm : bool or array_like
        Whether the base model is the improved IDM instead of the IDM.

    Returns
    -------
    numpy.ndarray
        Acceleration [m/s^2], ``float64``, broadcast shape of the inputs.

    Notes
    -----
    Without a leader the ACC reduces to the free-road IDM: Kesting et al. (2010) define the
    CAH for a leader only, and the paper is silent. The approach rate is then 0.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eqs. (1) and (3).

    Examples
    --------
    A CAV closing in at 5 m/s on a leader 30 m ahead brakes less than an HDV would:

    >>> kw = dict(v0=33.3, T=1.0, s0=2.0, a=1.4, b=2.0, delta=4)
    >>> hdv = follow_acceleration(30.0, 25.0, 20.0, 0.0, c=0.0, iidm=False, **kw)
    >>> cav = follow_acceleration(30.0, 25.0, 20.0, 0.0, c=0.99, iidm=False, **kw)
    >>> bool(cav > hdv)
    True
    """
    return broadcast_apply(_follow_array, s, v, vl, al, v0, T, s0, a, b, delta, c, iidm)
