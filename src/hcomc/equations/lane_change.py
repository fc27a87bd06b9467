r"""The quintic lane-change path, paper Eqs. (4)-(6).

"Quintic polynomial curve is adopted as the basic model to construct the lane-changing
trajectories of HDVs and CAVs" (Section II-B-2): the lateral displacement :math:`y` is a
quintic of the longitudinal displacement :math:`x`,

.. math:: y(x) = a_0 + a_1 x + a_2 x^2 + a_3 x^3 + a_4 x^4 + a_5 x^5, \qquad x \in [x_0, x_f]

(Eq. 4; :math:`a_i` the polynomial coefficients, :math:`x_0` and :math:`x_f` the longitudinal
displacement at the beginning and end of the lane change). The longitudinal motion during the
change is the vehicle's own car-following model, Eq. (2) for HDVs (Eq. 5) and Eq. (3) for CAVs
(Eq. 6), integrated by :func:`hcomc.equations.integrate.ballistic_step`; the lateral position
is then :math:`y(x(t))`. The simulation evaluates it every step with :func:`lateral_offset`, the
normalised rest-to-rest closed form :math:`y_0 + W\,p(\xi)` with
:math:`p(\xi) = 10\xi^3 - 15\xi^4 + 6\xi^5`; :func:`quintic_coefficients` solves the general
6x6 boundary-value problem of Eq. (4) for non-zero end states. The peaks of the
time-parametrised change, which choose its duration, are in
:mod:`hcomc.equations.lane_change_peaks`; the acceleration transition during the change,
Eq. (14), in :mod:`hcomc.equations.transition`.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section II-B-2,
   Eqs. (4)-(6).
"""

from __future__ import annotations

from math import comb

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["lateral_offset", "quintic_coefficients", "quintic_shape"]

_MIN_LENGTH: float = 1e-9
"""Guard on the manoeuvre length xf - x0 [m] in :func:`lateral_offset`."""

# Boundary system in the normalised variable ξ = (x - x0)/L: rows are p(0), p'(0), p''(0),
# p(1), p'(1), p''(1) applied to the monomials ξ^0 .. ξ^5.
_BC_MATRIX = np.array(
    [
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 2.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
        [0.0, 1.0, 2.0, 3.0, 4.0, 5.0],
        [0.0, 0.0, 2.0, 6.0, 12.0, 20.0],
    ]
)
# Taylor-shift tables: a_j = sum_k C(k, j) (-x0)^(k-j) d_k for the monomials in (x - x0).
_BINOM = np.array([[comb(k, j) for k in range(6)] for j in range(6)], dtype=np.float64)
_SHIFT_POW = np.array([[max(k - j, 0) for k in range(6)] for j in range(6)], dtype=np.intp)


def quintic_coefficients(
    x0: FloatArray | float,
    xf: FloatArray | float,
    y0: FloatArray | float,
    yf: FloatArray | float,
    dy0: FloatArray | float = 0.0,
    ddy0: FloatArray | float = 0.0,
    dyf: FloatArray | float = 0.0,
    ddyf: FloatArray | float = 0.0,
) -> FloatArray:
    r"""Coefficients :math:`a_0 \ldots a_5` of the lane-change quintic, paper Eq. (4).

    Solves the boundary-value problem

    .. math::
       :label: eq-4-quintic

       y(x) = \sum_{k=0}^{5} a_k x^k, \quad
       y(x_0) = y_0,\ y'(x_0) = y'_0,\ y''(x_0) = y''_0,\quad
       y(x_f) = y_f,\ y'(x_f) = y'_f,\ y''(x_f) = y''_f.

    Parameters
    ----------
    x0, xf : float or array_like
        Longitudinal start and end positions [m] (``xf != x0``).
    y0, yf : float or array_like
        Lateral start and end positions [m].
    dy0, dyf : float or array_like, optional
        Slopes :math:`dy/dx` at the start and end [-] (default 0).
    ddy0, ddyf : float or array_like, optional
        Curvatures :math:`d^2y/dx^2` at the start and end [1/m] (default 0).

    Returns
    -------
    numpy.ndarray
        Shape ``(..., 6)``: ``[a0, a1, a2, a3, a4, a5]`` in the absolute coordinate ``x``
        (units [m], [-], [1/m], [1/m^2], [1/m^3], [1/m^4]); ``...`` is the broadcast shape of
        the inputs. Evaluate with ``numpy.polynomial.polynomial.polyval(x, a.T)`` or similar.

    Notes
    -----
    The 6x6 system is solved for all boundary sets at once (one ``numpy.linalg.solve`` call with
    the batch as right-hand-side columns) in the normalised variable
    :math:`\xi = (x - x_0)/(x_f - x_0)`, whose matrix is constant and well conditioned, and the
    solution is mapped exactly to the monomials of Eq. (4) by scaling and a Taylor (binomial)
    shift. Solving the Vandermonde-type system directly in absolute ``x`` is numerically
    hopeless at highway positions of hundreds of metres. For the same reason, coefficients in
    absolute ``x`` lose accuracy by cancellation when ``|x0|`` is much larger than
    ``xf - x0``; the engine uses :func:`lateral_offset` (closed form in ξ) instead.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (4).

    Examples
    --------
    Rest-to-rest change of 3.75 m over 100 m starting at x = 0:
    ``W (10 ξ^3 - 15 ξ^4 + 6 ξ^5)`` with ξ = x/100.

    >>> np.round(quintic_coefficients(0.0, 100.0, 0.0, 3.75) * [1, 1, 1, 1e6, 1e8, 1e10], 12)
    array([  0.  ,   0.  ,   0.  ,  37.5 , -56.25,  22.5 ])
    """
    x0_, xf_, y0_, yf_, dy0_, ddy0_, dyf_, ddyf_ = np.broadcast_arrays(
        *(np.asarray(q, dtype=np.float64) for q in (x0, xf, y0, yf, dy0, ddy0, dyf, ddyf))
    )
    length = xf_ - x0_
    length2 = length * length
    rhs = np.stack(
        (y0_, dy0_ * length, ddy0_ * length2, yf_, dyf_ * length, ddyf_ * length2), axis=-1
    )
    shape = rhs.shape
    # Coefficients c_k of the monomials xi^k, solved for the whole batch at once.
    c = np.linalg.solve(_BC_MATRIX, rhs.reshape(-1, 6).T).T.reshape(shape)
    # d_k = c_k / L^k: coefficients of (x - x0)^k.
    d = c / _powers(length)
    # Taylor shift to absolute x: a_j = sum_k C(k, j) (-x0)^(k-j) d_k.
    neg_x0_pow = _powers(-x0_)
    return np.einsum("jk,...jk,...k->...j", _BINOM, neg_x0_pow[..., _SHIFT_POW], d)


def _powers(base: FloatArray) -> FloatArray:
    """``base^0 … base^5`` along a new last axis, by repeated multiplication (numpy's ``power``
    is chosen by the CPU and may differ in the last bit)."""
    factors = np.repeat(base[..., None], 6, axis=-1)
    factors[..., 0] = 1.0
    powers: FloatArray = np.cumprod(factors, axis=-1, dtype=np.float64)
    return powers


def quintic_shape(xi: FloatArray | float) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Normalised rest-to-rest quintic and its first two derivatives.

    .. math::
       :label: eq-4-shape

       p(\xi) = 10\xi^3 - 15\xi^4 + 6\xi^5, \quad
       p'(\xi) = 30\xi^2(1 - \xi)^2, \quad
       p''(\xi) = 60\xi(1 - \xi)(1 - 2\xi)

    This is Eq. (4) with the boundary conditions :math:`p(0) = p'(0) = p''(0) = 0`,
    :math:`p(1) = 1`, :math:`p'(1) = p''(1) = 0`.

    Parameters
    ----------
    xi : float or array_like
        Normalised progress ξ [-]; clipped to [0, 1], so that the path is constant (and its
        derivatives zero) before the start and after the end of the manoeuvre.

    Returns
    -------
    p, dp, ddp : numpy.ndarray
        :math:`p(\xi)`, :math:`dp/d\xi` and :math:`d^2p/d\xi^2` [-], ``float64``.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (4).

    Examples
    --------
    >>> [float(q) for q in quintic_shape(0.5)]
    [0.5, 1.875, 0.0]
    """
    xi = np.asarray(xi, dtype=np.float64)
    p, dp, ddp = _shape_array(np.ascontiguousarray(xi).reshape(-1))
    return p.reshape(xi.shape), dp.reshape(xi.shape), ddp.reshape(xi.shape)


@kernel
def quintic_shape_scalar(xi: float) -> tuple[float, float, float]:
    """:func:`quintic_shape` of one ξ (clipped to [0, 1]), its compiled kernel: Eq. (4)'s
    normalised polynomial 10ξ³ − 15ξ⁴ + 6ξ⁵ and its first two derivatives."""
    xi = min(max(xi, 0.0), 1.0)
    xi2 = xi * xi
    om = 1.0 - xi
    p = xi2 * xi * (10.0 + xi * (6.0 * xi - 15.0))
    dp = 30.0 * xi2 * om * om
    ddp = 60.0 * xi * om * (1.0 - 2.0 * xi)
    return p, dp, ddp


@kernel
def _shape_array(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p, dp, ddp = np.empty(xi.size), np.empty(xi.size), np.empty(xi.size)
    for i in range(xi.size):
        p[i], dp[i], ddp[i] = quintic_shape_scalar(xi[i])
    return p, dp, ddp


@kernel
def lateral_state(
    x: float, x0: float, xf: float, y0: float, yf: float
) -> tuple[float, float, float]:
    """y [m], dy/dx [-] and d²y/dx² [1/m] of one vehicle at x on the quintic path from
    (x0, y0) to (xf, yf) (Eqs. 4-6): the compiled kernel of :func:`lateral_offset` (same
    arguments), which the simulation step and the HCOMC prediction call."""
    length = max(xf - x0, _MIN_LENGTH)
    width = yf - y0
    p, dp, ddp = quintic_shape_scalar((x - x0) / length)
    slope = width / length
    return y0 + width * p, slope * dp, slope / length * ddp


def lateral_offset(
    x: FloatArray | float,
    x0: FloatArray | float,
    xf: FloatArray | float,
    y0: FloatArray | float,
    yf: FloatArray | float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Lateral position and its x-derivatives on a rest-to-rest lane change, Eqs. (4)-(6).

    .. math::
       :label: eq-4-6-lateral

       y(x) = y_0 + W p(\xi),\quad
       \frac{dy}{dx} = \frac{W}{L} p'(\xi),\quad
       \frac{d^2y}{dx^2} = \frac{W}{L^2} p''(\xi),\qquad
       \xi = \frac{x - x_0}{L},\ L = x_f - x_0,\ W = y_f - y_0

    with :math:`p` from :func:`quintic_shape`: Eq. (4) with zero lateral speed and
    acceleration at both ends, evaluated at the vehicle's longitudinal position :math:`x(t)`
    as Eqs. (5) (HDV) and (6) (CAV) prescribe. Time derivatives follow from the chain rule:
    :math:`\dot y = y'\dot x` and :math:`\ddot y = y''\dot x^2 + y'\ddot x`.

    Parameters
    ----------
    x : float or array_like
        Current longitudinal position [m]; clamped to ``[x0, xf]``.
    x0, xf : float or array_like
        Longitudinal start :math:`x_0` and (predicted) end :math:`x_f` of the manoeuvre [m],
        ``xf > x0``. A length
        ``xf - x0`` below 1e-9 m is raised to 1e-9 m (an instantaneous change), so the result
        stays finite.
    y0, yf : float or array_like
        Lateral start and target positions [m]; ``yf < y0`` changes lane to the other side.

    Returns
    -------
    y : numpy.ndarray
        Lateral position [m].
    dy_dx : numpy.ndarray
        Slope :math:`dy/dx` [-].
    d2y_dx2 : numpy.ndarray
        Curvature term :math:`d^2y/dx^2` [1/m].

    Notes
    -----
    The paper fixes neither the boundary conditions nor :math:`x_f`. Rest to rest (no
    lateral speed or acceleration at either end) is the usual choice and makes the path a
    function of the progress :math:`\xi` alone. The end :math:`x_f` is predicted by the caller
    when the change starts (from the speed and the lane-change duration) and then held, so the
    path is fixed for the whole manoeuvre while :math:`x(t)` follows the car-following model.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eqs. (4)-(6).

    Examples
    --------
    >>> [round(float(q), 6) for q in lateral_offset(50.0, 0.0, 100.0, 0.0, 3.75)]
    [1.875, 0.070312, 0.0]
    """
    out = broadcast_apply(_lateral_array, x, x0, xf, y0, yf)
    return out[..., 0], out[..., 1], out[..., 2]


@kernel
def _lateral_array(
    x: np.ndarray, x0: np.ndarray, xf: np.ndarray, y0: np.ndarray, yf: np.ndarray
) -> np.ndarray:
    out = np.empty((x.size, 3))
    for i in range(x.size):
        out[i, 0], out[i, 1], out[i, 2] = lateral_state(x[i], x0[i], xf[i], y0[i], yf[i])
    return out
