r"""Hyperbolic-tangent acceleration transition at a leader switch, paper Eq. (14).

"During the merging process, VMC changes lane and its leading vehicle shifts from VMF to VNF.
The state differences between VMF and VNF trigger a sudden jump in the output of the IDM-based
model" (Section III-A-2). Eq. (14) blends the accelerations before and after the switch,

.. math:: a_\mathrm{tar} = \Psi(\tau)\,a_\mathrm{new} + (1 - \Psi(\tau))\,a_\mathrm{ori},
          \qquad \Psi(\tau) = \tfrac12\left[\tanh(\lambda\tau - \gamma) + 1\right],

where, in the paper's words, :math:`a_\mathrm{tar}` is the desired acceleration with
transition function, :math:`a_\mathrm{ori}` and :math:`a_\mathrm{new}` the desired
acceleration before and after the lane change, :math:`\tau` "the timing of lane change" (here
the time since its start) and :math:`\gamma`, :math:`\lambda` the phase and speed of the
transition. The paper states :math:`\Psi(t_0) = 0` and :math:`\Psi(t_f) = 1`, which a tanh
cannot reach; the parameters are chosen from a tolerance ε so that
:math:`\Psi(0) = \varepsilon`, :math:`\Psi(T) = 1 - \varepsilon` and the midpoint is at
:math:`T/2` (:func:`transition_parameters`). Every vehicle changing lane, not only VMC, blends
this way. The public functions are :func:`transition_parameters`, :func:`transition_weight`
(Ψ) and :func:`blend_acceleration` (:math:`a_\mathrm{tar}`); their compiled one-vehicle
kernels (``transition_psi``, ``blend``) are what the simulation step and the HCOMC
prediction call.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-A-2,
   Eq. (14).
.. [2] SUMO ``MSCFModel_EIDM.cpp``: the same tanh shape smooths its drive-off.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["blend_acceleration", "transition_parameters", "transition_weight"]

DEFAULT_TOLERANCE: float = 0.01
"""Default ε: Ψ(0) = 0.01 and Ψ(T) = 0.99."""


def transition_parameters(
    duration: FloatArray | float, tolerance: FloatArray | float = DEFAULT_TOLERANCE
) -> tuple[FloatArray, FloatArray]:
    r"""Speed λ and phase γ of the Eq. (14) transition for a duration and tolerance.

    .. math::
       :label: eq-14-params

       \gamma = \operatorname{artanh}(1 - 2\varepsilon), \qquad \lambda = \frac{2\gamma}{T}

    Parameters
    ----------
    duration : float or array_like
        Transition duration T (the lane-change duration T_lc) [s], > 0.
    tolerance : float or array_like, optional
        ε in (0, 0.5) [-]: the weight is ε at τ = 0 and 1 - ε at τ = T. Default 0.01.

    Returns
    -------
    lam : numpy.ndarray
        λ [1/s].
    gamma : numpy.ndarray
        γ [-].

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (14).

    Examples
    --------
    >>> lam, gamma = transition_parameters(4.0)
    >>> round(float(gamma), 4), round(float(lam), 4)
    (2.2976, 1.1488)
    """
    # the C library's artanh (numpy's is chosen by the CPU and may differ in the last bit)
    gamma = np.vectorize(math.atanh, otypes=[np.float64])(
        np.subtract(1.0, np.multiply(2.0, tolerance))
    )
    lam = 2.0 * gamma / np.asarray(duration, dtype=np.float64)
    return np.asarray(lam, dtype=np.float64), np.asarray(gamma, dtype=np.float64)


def transition_weight(
    tau: FloatArray | float,
    duration: FloatArray | float,
    tolerance: FloatArray | float = DEFAULT_TOLERANCE,
) -> FloatArray:
    r"""Transition weight Ψ(τ) of paper Eq. (14).

    .. math::
       :label: eq-14-psi

       \Psi(\tau) = \tfrac12\left[\tanh(\lambda\tau - \gamma) + 1\right]

    with λ, γ from :func:`transition_parameters`, so that :math:`\Psi(0) = \varepsilon`,
    :math:`\Psi(T/2) = 1/2` and :math:`\Psi(T) = 1 - \varepsilon`.

    Parameters
    ----------
    tau : float or array_like
        Time since the start of the transition (lane-change start) [s]. Not clipped: for
        ``tau > duration`` the weight keeps rising towards 1, so callers switch to ``a_new``
        outright once the transition is over.
    duration : float or array_like
        Transition duration T [s], > 0; broadcast against ``tau``.
    tolerance : float or array_like, optional
        ε in (0, 0.5) [-]. Default 0.01.

    Returns
    -------
    numpy.ndarray
        Weight Ψ in (0, 1) [-], ``float64``.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (14).

    Examples
    --------
    >>> [round(float(w), 6) for w in transition_weight(np.array([0.0, 2.0, 4.0]), 4.0)]
    [0.01, 0.5, 0.99]
    """
    _, gamma = transition_parameters(1.0, tolerance)
    return broadcast_apply(_weight_array, tau, duration, gamma)


def transition_gamma(tolerance: float) -> float:
    """γ = artanh(1 − 2ε) of Eq. (14) for the tolerance ε [-], as a float: the phase
    :func:`transition_parameters` gives, which the engines hand to ``transition_psi``."""
    return float(transition_parameters(1.0, tolerance)[1])


@kernel
def transition_psi(tau: float, duration: float, gamma: float) -> float:
    """Ψ(τ) of Eq. (14) for one vehicle, with λ = 2γ/T: the compiled kernel of
    :func:`transition_weight` (γ from :func:`transition_gamma`)."""
    return 0.5 * (math.tanh(2.0 * gamma / duration * tau - gamma) + 1.0)


@kernel
def _weight_array(tau: np.ndarray, duration: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    out = np.empty(tau.size)
    for i in range(tau.size):
        out[i] = transition_psi(tau[i], duration[i], gamma[i])
    return out


def blend_acceleration(
    a_ori: FloatArray | float, a_new: FloatArray | float, weight: FloatArray | float
) -> FloatArray:
    r"""Blend the accelerations before and after a leader switch, paper Eq. (14).

    .. math::
       :label: eq-14-blend

       a_\mathrm{tar} = \Psi\,a_\mathrm{new} + (1 - \Psi)\,a_\mathrm{ori}

    Parameters
    ----------
    a_ori : float or array_like
        Acceleration with the original leader [m/s^2].
    a_new : float or array_like
        Acceleration with the new leader [m/s^2].
    weight : float or array_like
        Ψ from :func:`transition_weight` [-].

    Returns
    -------
    numpy.ndarray
        Target acceleration [m/s^2], ``float64``.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (14).

    Examples
    --------
    >>> float(blend_acceleration(-1.0, 1.0, 0.25))
    -0.5
    """
    return broadcast_apply(_blend_array, a_ori, a_new, weight)


@kernel
def blend(a_ori: float, a_new: float, weight: float) -> float:
    """Eq. (14) blend of one vehicle: the compiled kernel of :func:`blend_acceleration`."""
    return weight * a_new + (1.0 - weight) * a_ori


@kernel
def _blend_array(a_ori: np.ndarray, a_new: np.ndarray, weight: np.ndarray) -> np.ndarray:
    out = np.empty(a_ori.size)
    for i in range(a_ori.size):
        out[i] = blend(a_ori[i], a_new[i], weight[i])
    return out
