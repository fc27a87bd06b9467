r"""Polynomial fuel-consumption model, paper Eq. (16) (Kamal et al. 2011).

.. math::
   \dot f = \underbrace{b_0 + b_1 v + b_2 v^2 + b_3 v^3}_{\dot f_\mathrm{cruise}}
          + \underbrace{a\,(c_0 + c_1 v + c_2 v^2)}_{\dot f_\mathrm{accel}}
   \quad [\mathrm{mL/s}], \qquad v\ [\mathrm{m/s}],\ a\ [\mathrm{m/s^2}]

with the coefficient vectors ``Q = (b0, b1, b2, b3)`` and ``R = (c0, c1, c2)`` of Kamal et al.
as used by Rios-Torres & Malikopoulos. The acceleration term describes engine
power demand; applied to braking it would give a fuel *credit* and even a negative total at low
speed. The default therefore applies it for ``a > 0`` only (``accel_term="positive"``); the
unsigned variant (``"signed"``, as in some public code) is available. Both clip the total rate
at 0.

References
----------
.. [1] M. A. S. Kamal, M. Mukai, J. Murata and T. Kawabe, "Ecological vehicle control on roads
   with up-down slopes", IEEE Trans. ITS 12(3), 783-794 (2011).
.. [2] J. Rios-Torres and A. A. Malikopoulos, "Automated and cooperative vehicle merging at
   highway on-ramps", IEEE Trans. ITS 18(4), 780-789 (2017).
.. [3] HCOMC paper (arXiv:2507.11621), Eq. (16).
"""

from __future__ import annotations

import math
from typing import Literal, NamedTuple

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.models._broadcast import broadcast_apply

__all__ = [
    "FUEL_DEFAULT",
    "FuelCoefficients",
    "FuelParams",
    "fuel_consumed",
    "fuel_rate",
    "fuel_rate_scalar",
]


class FuelParams(BaseModel):
    """Coefficients of the Eq. (16) fuel-rate polynomial (Kamal et al. 2011).

    Defaults: Q and R of Kamal et al. (2011) as used by Rios-Torres & Malikopoulos (2017)
    (``SEUChang/CBF_Merging`` ``fuel_consumption.m``).
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    cruise: tuple[float, float, float, float] = Field(
        default=(0.1569, 2.450e-2, -7.415e-4, 5.975e-5),
        description=(
            "Q = (b0, b1, b2, b3) of the cruise rate b0 + b1 v + b2 v^2 + b3 v^3, units "
            "[mL/s], [mL/m], [mL s/m^2], [mL s^2/m^3] (v in m/s)."
        ),
    )
    accel: tuple[float, float, float] = Field(
        default=(0.07224, 9.681e-2, 1.075e-3),
        description=(
            "R = (c0, c1, c2) of the acceleration rate a (c0 + c1 v + c2 v^2), units "
            "[mL s/m], [mL s^2/m^2], [mL s^3/m^3] (v in m/s, a in m/s^2)."
        ),
    )
    accel_term: Literal["positive", "signed"] = Field(
        default="positive",
        description=(
            "'positive': acceleration term for a > 0 only, no fuel credit for braking "
            "(default); 'signed': term applied for any sign of a. The total rate "
            "[mL/s] is clipped at 0 in both cases."
        ),
    )

    def coefficients(self) -> tuple[float, ...]:
        """``(b0, b1, b2, b3, c0, c1, c2, positive_only)``, the arguments of
        :func:`fuel_rate_scalar` after ``v`` and ``a``."""
        positive = 1.0 if self.accel_term == "positive" else 0.0
        return (*self.cruise, *self.accel, positive)


class FuelCoefficients(NamedTuple):
    """The coefficients of the Eq. 16 fuel-rate polynomial as the kernels take them
    (:func:`~hcomc.models.fuel.fuel_rate_scalar`'s, in the order of
    :meth:`~hcomc.models.fuel.FuelParams.coefficients`; v in m/s, a in m/s^2, rates in mL/s).
    """

    b0: float  # cruise rate b0 + b1 v + b2 v^2 + b3 v^3: [mL/s]
    b1: float  # [mL/m]
    b2: float  # [mL s/m^2]
    b3: float  # [mL s^2/m^3]
    c0: float  # acceleration rate a (c0 + c1 v + c2 v^2): [mL s/m]
    c1: float  # [mL s^2/m^2]
    c2: float  # [mL s^3/m^3]
    positive_only: float  # 1.0: the acceleration term for a > 0 only; 0.0: for any a

    @classmethod
    def of(cls, params: FuelParams) -> FuelCoefficients:
        """The coefficients of the fuel model ``params``."""
        return cls(*(float(c) for c in params.coefficients()))


FUEL_DEFAULT = FuelParams()
"""Default :class:`FuelParams`: Kamal et al. (2011) coefficients, no credit for braking."""


def fuel_rate(
    v: FloatArray | float, a: FloatArray | float, params: FuelParams = FUEL_DEFAULT
) -> FloatArray:
    r"""Instantaneous fuel-consumption rate, paper Eq. (16).

    .. math::
       :label: eq-16-rate

       \dot f = \max\left(0,\; [1\ v\ v^2\ v^3]\,Q^T + \tilde a\,[1\ v\ v^2]\,R^T\right),
       \qquad \tilde a = \begin{cases} \max(a, 0) & \texttt{"positive"} \\
                                       a & \texttt{"signed"} \end{cases}

    Parameters
    ----------
    v : float or array_like
        Speed [m/s].
    a : float or array_like
        Acceleration [m/s^2].
    params : FuelParams, optional
        Coefficients and the acceleration-term convention; default :data:`FUEL_DEFAULT`.

    Returns
    -------
    numpy.ndarray
        Fuel rate [mL/s], ``float64``, >= 0 (NaN where ``v`` or ``a`` is NaN).

    Notes
    -----
    The paper's Eq. (16) applies the acceleration term with its sign. The default
    ``"positive"`` convention gives no fuel credit for braking, the usual reading of Kamal's
    model; with ``"signed"`` the rate would be negative at low speed
    while braking without the clip at 0.

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
    """Eq. (16) for one vehicle [mL/s] (NaN if ``v`` or ``a`` is NaN): the one implementation
    behind :func:`fuel_rate`; ``positive_only`` (1 or 0) applies the acceleration term for
    a > 0 only. Arguments as :meth:`FuelParams.coefficients` orders them."""
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
    params: FuelParams = FUEL_DEFAULT,
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
    params : FuelParams, optional
        Fuel coefficients; default :data:`FUEL_DEFAULT`.
    axis : int, optional
        Time axis; default -1.

    Returns
    -------
    numpy.ndarray
        Fuel consumed [L], ``float64``, the input shape without ``axis``.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (16); docs/models.md (fuel; the Fuel Cons. metric).

    Examples
    --------
    >>> round(float(fuel_consumed(np.full(100, 25.0), np.zeros(100), 0.1)), 6)
    0.012396
    """
    rate = fuel_rate(v, a, params)
    return np.asarray(np.nansum(rate, axis=axis) * (dt / 1000.0), dtype=np.float64)
