r"""The fuel-consumption model, paper Eq. (16) (Kamal et al. 2011).

The paper's economy index :math:`U_\mathrm{fuel}` is the fuel VMC and VR burn during the
merge, with the rate

.. math::
   \dot f_e = \dot f_\mathrm{cruise} + \dot f_\mathrm{accel}, \qquad
   \dot f_\mathrm{cruise} = [1\ v\ v^2\ v^3]\,Q^T, \qquad
   \dot f_\mathrm{accel} = a\,[1\ v\ v^2]\,R^T

where, in the paper's words, :math:`\dot f_e` denotes the fuel consumption rate, :math:`Q` and
:math:`R` are the fuel consumption parameter matrices for cruising and acceleration and
:math:`\dot f_\mathrm{cruise}`, :math:`\dot f_\mathrm{accel}` the rates during cruising and
acceleration; :math:`U_\mathrm{fuel} = \int \dot f_{e,VR}\,dt + \int \dot f_{e,VMC}\,dt`. With
:math:`Q = (b_0, b_1, b_2, b_3)` and :math:`R = (c_0, c_1, c_2)` [mL/s, with v in m/s and a in
m/s^2], the coefficients are those of Kamal et al. (2011) as used by Rios-Torres &
Malikopoulos (2017) (:class:`FuelCoefficients`, whose defaults they are).

The acceleration term describes engine power demand; applied to braking it would give a fuel
*credit* and even a negative total at low speed. The default therefore applies it for
:math:`a > 0` only (``positive_only = 1``); the unsigned variant (``0``, as in some public
code) is available. Both clip the total rate at 0. The configuration's model of these
coefficients (validated, with the convention as a name) is :class:`hcomc.config.fuel.FuelParams`;
the functions here take either it or a :class:`FuelCoefficients`.

The public functions are :func:`fuel_rate` (the rate) and :func:`fuel_consumed` (its integral);
the compiled one-vehicle kernel ``fuel_rate_scalar`` is what the prediction, the metrics and
the environments call.

References
----------
.. [1] M. A. S. Kamal, M. Mukai, J. Murata and T. Kawabe, "Ecological vehicle control on roads
   with up-down slopes", IEEE Trans. ITS 12(3), 783-794 (2011).
.. [2] J. Rios-Torres and A. A. Malikopoulos, "Automated and cooperative vehicle merging at
   highway on-ramps", IEEE Trans. ITS 18(4), 780-789 (2017).
.. [3] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-C-1, Eq. (16).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["DEFAULT_COEFFICIENTS", "FuelCoefficients", "fuel_consumed", "fuel_rate"]


class SupportsCoefficients(Protocol):
    """Anything that gives the eight numbers of :class:`FuelCoefficients` in order:
    a :class:`FuelCoefficients` or the configuration's ``FuelParams``."""

    def coefficients(self) -> tuple[float, ...]:
        """``(b0, b1, b2, b3, c0, c1, c2, positive_only)``."""
        ...


class FuelCoefficients(NamedTuple):
    """The coefficients of the Eq. (16) fuel-rate polynomial, as the kernels take them.

    Defaults: :math:`Q` and :math:`R` of Kamal et al. (2011) as used by Rios-Torres &
    Malikopoulos (2017) (``SEUChang/CBF_Merging`` ``fuel_consumption.m``), no credit for
    braking. Speeds in m/s, accelerations in m/s^2, rates in mL/s.
    """

    b0: float = 0.1569
    """Cruise rate b0 + b1 v + b2 v^2 + b3 v^3: constant term [mL/s]."""
    b1: float = 2.450e-2
    """[mL/m]."""
    b2: float = -7.415e-4
    """[mL s/m^2]."""
    b3: float = 5.975e-5
    """[mL s^2/m^3]."""
    c0: float = 0.07224
    """Acceleration rate a (c0 + c1 v + c2 v^2): constant factor [mL s/m]."""
    c1: float = 9.681e-2
    """[mL s^2/m^2]."""
    c2: float = 1.075e-3
    """[mL s^3/m^3]."""
    positive_only: float = 1.0
    """1.0: the acceleration term for a > 0 only (no credit for braking); 0.0: for any a."""

    def coefficients(self) -> tuple[float, ...]:
        """``(b0, b1, b2, b3, c0, c1, c2, positive_only)``, the arguments of the kernel after
        ``v`` and ``a``."""
        return tuple(self)

    @classmethod
    def of(cls, params: SupportsCoefficients) -> FuelCoefficients:
        """The coefficients of the fuel model ``params`` (e.g. a configuration's
        ``FuelParams``)."""
        return cls(*(float(c) for c in params.coefficients()))


DEFAULT_COEFFICIENTS = FuelCoefficients()
"""Kamal et al. (2011) coefficients, no credit for braking: the default of every function."""


def fuel_rate(
    v: FloatArray | float,
    a: FloatArray | float,
    params: SupportsCoefficients = DEFAULT_COEFFICIENTS,
) -> FloatArray:
    r"""Instantaneous fuel-consumption rate, paper Eq. (16).

    .. math::
       :label: eq-16-rate

       \dot f_e = \max\left(0,\; [1\ v\ v^2\ v^3]\,Q^T + \tilde a\,[1\ v\ v^2]\,R^T\right),
       \qquad \tilde a = \begin{cases} \max(a, 0) & \text{positive only (default)} \\
                                       a & \text{signed} \end{cases}

    Parameters
    ----------
    v : float or array_like
        Speed [m/s].
    a : float or array_like
        Acceleration [m/s^2].
    params : FuelCoefficients or FuelParams, optional
        Coefficients :math:`Q`, :math:`R` and the acceleration-term convention; default
        :data:`DEFAULT_COEFFICIENTS`.

    Returns
    -------
    numpy.ndarray
        Fuel rate [mL/s], ``float64``, >= 0 (NaN where ``v`` or ``a`` is NaN).

    Notes
    -----
    The paper's Eq. (16) applies the acceleration term with its sign. The default convention
    (``positive_only = 1``) gives no fuel credit for braking, the usual reading of Kamal's
    model; with the signed term the rate would be negative at low speed while braking
    without the clip at 0, which the paper does not mention either.

    References
    ----------
    .. [1] Kamal et al., IEEE Trans. ITS 12(3), 783 (2011).
    .. [2] HCOMC paper (arXiv:2507.11621), Eq. (16).

    Examples
    --------
    >>> round(float(fuel_rate(25.0, 0.0)), 4)
    1.2396
    >>> round(float(fuel_rate(25.0, 1.0)), 4)
    4.4039
    """
    return broadcast_apply(_fuel_array, v, a, *params.coefficients())


@kernel
def fuel_rate_scalar(
    v: float, a: float, b0: float, b1: float, b2: float, b3: float, c0: float, c1: float,
    c2: float, positive_only: float,
) -> float:  # fmt: skip
    """Eq. (16) for one vehicle [mL/s] (NaN if ``v`` or ``a`` is NaN): the compiled kernel of
    :func:`fuel_rate`; ``positive_only`` (1 or 0) applies the acceleration term for a > 0
    only. Arguments in the order of :class:`FuelCoefficients`."""
    if math.isnan(v) or math.isnan(a):
        return math.nan
    a_eff = max(a, 0.0) if positive_only else a
    rate = b0 + v * (b1 + v * (b2 + v * b3)) + a_eff * (c0 + v * (c1 + v * c2))
    return max(rate, 0.0)


@kernel
def _fuel_array(
    v: np.ndarray, a: np.ndarray, b0: np.ndarray, b1: np.ndarray, b2: np.ndarray, b3: np.ndarray,
    c0: np.ndarray, c1: np.ndarray, c2: np.ndarray, positive_only: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(v.size)
    for i in range(v.size):
        out[i] = fuel_rate_scalar(
            v[i], a[i], b0[i], b1[i], b2[i], b3[i], c0[i], c1[i], c2[i], positive_only[i]
        )
    return out


def fuel_consumed(
    v: FloatArray | float,
    a: FloatArray | float,
    dt: float,
    params: SupportsCoefficients = DEFAULT_COEFFICIENTS,
    axis: int | None = -1,
) -> FloatArray:
    r"""Total fuel over sampled trajectories, paper Eq. (16) (:math:`U_\mathrm{fuel}`).

    Rectangle rule on the samples of :func:`fuel_rate`:

    .. math::
       :label: eq-16-total

       F = \frac{\Delta t}{1000} \sum_n \dot f(v_n, a_n) \quad [\mathrm{L}]

    Parameters
    ----------
    v : array_like
        Speeds [m/s], sampled every ``dt`` along ``axis``. NaN marks absent vehicles (not yet
        entered or already left) and counts as zero consumption.
    a : array_like
        Accelerations [m/s^2], same shape as ``v`` (or broadcastable); NaN counts as zero too.
    dt : float
        Sampling step [s].
    params : FuelCoefficients or FuelParams, optional
        Fuel coefficients; default :data:`DEFAULT_COEFFICIENTS`.
    axis : int, optional
        Time axis; default -1.

    Returns
    -------
    numpy.ndarray
        Fuel consumed [L], ``float64``, the input shape without ``axis``.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (16).

    Examples
    --------
    >>> round(float(fuel_consumed(np.full(100, 25.0), np.zeros(100), 0.1)), 6)
    0.012396
    """
    rate = fuel_rate(v, a, params)
    return np.asarray(np.nansum(rate, axis=axis) * (dt / 1000.0), dtype=np.float64)
