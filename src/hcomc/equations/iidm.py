r"""The improved IDM (IIDM), the variant of paper Eq. (1) offered as a switch.

The IIDM of Treiber & Kesting (2013), used by MovSim's ACC model and SUMO's EIDM, keeps the
desired gap :math:`s^*` of Eq. (1) (:func:`hcomc.equations.idm.desired_gap`) and its
parameters, but splits the acceleration by regime so that its equilibrium gap is exactly
:math:`s_0 + vT` below the desired speed (the IDM's grows without bound as
:math:`v \to v_0`). The paper uses the plain IDM; ``variant = "iidm"`` of the vehicle
configuration selects this one for either vehicle kind. The public function is
:func:`iidm_acceleration`; it applies the compiled one-vehicle kernel ``iidm_accel``, which
the simulation step and the HCOMC prediction call. Arguments and sign conventions are those
of :mod:`hcomc.equations.idm`.

References
----------
.. [1] M. Treiber and A. Kesting, "Traffic Flow Dynamics", Springer (2013), Sec. 11.3.
.. [2] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section II-B-1, Eq. (1)
   (the IDM this model improves).
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply
from hcomc.equations.idm import S_MIN, desired_gap_scalar, power

__all__ = ["iidm_acceleration"]

_A_FREE_FLOOR: float = 1e-300
"""Floor on the IIDM free-road acceleration [m/s^2] inside its exponent ``2a/a_free``."""


def iidm_acceleration(
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
    r"""Improved IDM (IIDM) acceleration, the variant of paper Eq. (1).

    With :math:`z = s^*(v, \Delta v)/s` and :math:`a_\mathrm{free}` the free-road term,

    .. math::
       :label: eq-iidm

       \dot v = \begin{cases}
         a_\mathrm{free}\,\left(1 - z^{2a/a_\mathrm{free}}\right) & v \le v_0,\ z < 1 \\
         a\,(1 - z^2) & v \le v_0,\ z \ge 1 \\
         a_\mathrm{free} & v > v_0,\ z < 1 \\
         a_\mathrm{free} + a\,(1 - z^2) & v > v_0,\ z \ge 1
       \end{cases}
       \qquad
       a_\mathrm{free} = \begin{cases}
         a\left[1 - (v/v_0)^{\delta}\right] & v \le v_0 \\
         -b\left[1 - (v_0/v)^{a\delta/b}\right] & v > v_0
       \end{cases}

    with :math:`s^*` the desired gap of Eq. (1). Unlike the IDM, the IIDM equilibrium gap is
    exactly :math:`s_0 + vT` for all :math:`v < v_0`. It is the base of Kesting's ACC/CAH
    model, so it is offered as a switch next to the paper's plain IDM.

    Parameters
    ----------
    s : float or array_like
        Bumper-to-bumper gap [m]. ``np.inf`` gives ``z = 0`` (free road); gaps ``<= 0`` are
        guarded by ``max(s, 1e-3)`` as in :func:`hcomc.equations.idm.idm_acceleration`.
    v : float or array_like
        Own speed [m/s].
    dv : float or array_like
        Approach rate ``v - v_leader`` [m/s].
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
        Acceleration index :math:`\delta` [-].

    Returns
    -------
    numpy.ndarray
        Acceleration [m/s^2], ``float64``, broadcast shape of the inputs.

    Notes
    -----
    At :math:`v = v_0` the exponent :math:`2a/a_\mathrm{free}` is infinite; the free-road term is
    floored at 1e-300 inside the exponent and ``z`` is clipped to 1 there, so the limit
    (:math:`z^{\infty} = 0` for :math:`z < 1`) is reproduced without warnings.

    References
    ----------
    .. [1] M. Treiber and A. Kesting, "Traffic Flow Dynamics", Springer (2013), Sec. 11.3.
    .. [2] MovSim ``ACC.java`` (IIDM branch); SUMO ``MSCFModel_EIDM.cpp``.

    Examples
    --------
    >>> float(iidm_acceleration(32.0, 20.0, 0.0, v0=33.3, T=1.5, a=1.0, b=2.0, s0=2.0, delta=4))
    0.0
    """
    return broadcast_apply(_iidm_array, s, v, dv, v0, T, a, b, s0, delta)


@kernel
def iidm_accel(
    s: float, v: float, dv: float, v0: float, T: float, a: float, b: float, s0: float, delta: float
) -> float:
    """IIDM acceleration of one vehicle [m/s^2]: the one implementation of
    :func:`iidm_acceleration` (same arguments, positional)."""
    return iidm_accel_given(s, v, dv, v0, T, a, b, s0, iidm_free_accel(v, v0, a, b, delta))


@kernel(inline="always")
def iidm_free_accel(v: float, v0: float, a: float, b: float, delta: float) -> float:
    """The IIDM's free-road acceleration [m/s^2], which depends on the own speed alone."""
    if v <= v0:
        return a * (1.0 - power(min(v, v0) / v0, delta))
    return -b * (1.0 - power(v0 / max(v, v0), a / b * delta))


@kernel
def iidm_accel_given(
    s: float, v: float, dv: float, v0: float, T: float, a: float, b: float, s0: float,
    a_free: float,
) -> float:  # fmt: skip
    """:func:`iidm_accel` with its free-road acceleration ``a_free`` =
    :func:`iidm_free_accel` given."""
    z = desired_gap_scalar(v, dv, T, a, b, s0) / max(s, S_MIN)
    if v <= v0:
        if z < 1.0:
            # a_free >= 0 is floored inside the exponent, so z^inf -> 0 at v = v0
            return a_free * (1.0 - min(z, 1.0) ** (a * 2.0 / max(a_free, _A_FREE_FLOOR)))
        return a * (1.0 - z * z)
    if z < 1.0:
        return a_free
    return a_free + a * (1.0 - z * z)


@kernel
def _iidm_array(
    s: np.ndarray, v: np.ndarray, dv: np.ndarray, v0: np.ndarray, T: np.ndarray, a: np.ndarray,
    b: np.ndarray, s0: np.ndarray, delta: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(s.size)
    for i in range(s.size):
        out[i] = iidm_accel(s[i], v[i], dv[i], v0[i], T[i], a[i], b[i], s0[i], delta[i])
    return out
