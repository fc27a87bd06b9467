r"""Cubic virtual vehicles of the hierarchical cooperative planning model, paper Eqs. (8)-(13).

First-order longitudinal planning (Section III-A-1): the virtual vehicle VV1 of VR, in main
lane 1, starts in the state of VMF at the beginning :math:`t_0'` of VR's planning and ends in
the state of VR at its end :math:`t_f'` (Eq. 8),

.. math::
   x_{VV1}(t_0') = x_{VMF}(t_0'),\quad v_{VV1}(t_0') = v_{VMF}(t_0'),\quad
   x_{VV1}(t_f') = x_{VR}(t_f'),\quad v_{VV1}(t_f') = v_{VR}(t_f'),

and moves along a cubic in time between them (Eq. 9, "the longitudinal motion trajectory
equation and the speed equation"),

.. math::
   x_{VV1}(t) = b_{11} + b_{12} t + b_{13} t^2 + b_{14} t^3, \qquad
   v_{VV1}(t) = b_{12} + 2 b_{13} t + 3 b_{14} t^2,

whose coefficients solve the 4x4 linear system of the four boundary states (Eq. 10). VMC
follows VV1 with its own car-following model, so that its leader morphs smoothly from VMF to
VR. Second-order lateral planning (Section III-A-2) gives VMC a virtual vehicle VV2 in main
lane 2 in the same way, from VNF at :math:`t_0''` to VMC at :math:`t_f''`, with coefficients
:math:`c_{11} \ldots c_{14}` (Eqs. 11-13), which VNR follows.

Time is taken relative to the start of the plan, :math:`\tau = t - t_0'`, for numerical
conditioning, so the coefficients ``b = (b1, b2, b3, b4)`` give
:math:`x(\tau) = b_1 + b_2\tau + b_3\tau^2 + b_4\tau^3`; the cubic is the same as the
paper's in absolute time. The public functions are :func:`cubic_coefficients` (Eqs. 10, 13),
:func:`cubic_state` (Eqs. 9, 12) and :func:`cubic_extremes` (the cubic's minimum speed and
acceleration, which the planner checks); their compiled kernels (``cubic_into``,
``cubic_point``, ``cubic_minima``) are what the HCOMC prediction and the engine call. Which
vehicles' states a plan takes for the boundary states of Eqs. (8) and (11) is the controller's
choice (:mod:`hcomc.control.prediction.population`); the states of a plan's virtual vehicles
after its horizon, :func:`hcomc.control.hierarchical.controller.virtual_states`.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-A,
   Eqs. (8)-(13).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["cubic_coefficients", "cubic_extremes", "cubic_state"]


def cubic_coefficients(
    horizon: ArrayLike, x0: ArrayLike, v0: ArrayLike, xf: ArrayLike, vf: ArrayLike
) -> FloatArray:
    r"""Coefficients of a virtual vehicle's cubic, paper Eq. (10) (VV1) and Eq. (13) (VV2).

    The cubic through :math:`(x_0, v_0)` at :math:`\tau = 0` and :math:`(x_f, v_f)` at
    :math:`\tau = H`: Eq. (10) (VV1, between the boundary states of Eq. 8) and Eq. (13) (VV2,
    between those of Eq. 11) with the plan's start as the origin of time,
    :math:`t_0' = 0`, where the 4x4 system has the closed-form solution

    .. math::
       :label: eq-10-13-cubic

       b_1 = x_0,\quad b_2 = v_0,\quad
       b_3 = \frac{3\Delta x - (2 v_0 + v_f) H}{H^2},\quad
       b_4 = \frac{-2\Delta x + (v_0 + v_f) H}{H^3},\qquad \Delta x = x_f - x_0.

    Parameters
    ----------
    horizon : array_like
        Planning horizon :math:`H = t_f' - t_0'` [s], > 0.
    x0 : array_like
        Start position [m]: :math:`x_{VMF}(t_0')` for VV1, :math:`x_{VNF}(t_0'')` for VV2.
    v0 : array_like
        Start speed [m/s]: :math:`v_{VMF}(t_0')` for VV1, :math:`v_{VNF}(t_0'')` for VV2.
    xf : array_like
        End position [m]: :math:`x_{VR}(t_f')` for VV1, :math:`x_{VMC}(t_f'')` for VV2.
    vf : array_like
        End speed [m/s]: :math:`v_{VR}(t_f')` for VV1, :math:`v_{VMC}(t_f'')` for VV2.

    Returns
    -------
    numpy.ndarray
        Shape ``(..., 4)``: :math:`(b_1, b_2, b_3, b_4)` [m, m/s, m/s^2, m/s^3] of
        :math:`x(\tau)`, ``...`` the broadcast shape of the inputs.

    Notes
    -----
    The paper solves Eq. (10) by inverting the matrix in absolute time. Relative time gives
    the same cubic with a well-conditioned system (absolute times of hundreds of seconds
    make the matrix nearly singular), and the closed form spares the solve.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eqs. (8)-(13).

    Examples
    --------
    Constant speed: a cubic that is a straight line.

    >>> cubic_coefficients(4.0, 0.0, 20.0, 80.0, 20.0).tolist()
    [0.0, 20.0, 0.0, 0.0]
    """
    return broadcast_apply(_coefficients_array, horizon, x0, v0, xf, vf)


@kernel
def cubic_into(h: float, x0: float, v0: float, xf: float, vf: float, out: np.ndarray) -> None:
    """Write the coefficients of one cubic into ``out`` (4,): the compiled kernel of
    :func:`cubic_coefficients` (Eq. 10)."""
    dx = xf - x0
    out[0], out[1] = x0, v0
    out[2] = (3.0 * dx - (2.0 * v0 + vf) * h) / (h * h)
    out[3] = (-2.0 * dx + (v0 + vf) * h) / (h * h * h)


@kernel
def _coefficients_array(
    h: np.ndarray, x0: np.ndarray, v0: np.ndarray, xf: np.ndarray, vf: np.ndarray
) -> np.ndarray:
    out = np.empty((h.size, 4))
    for i in range(h.size):
        cubic_into(h[i], x0[i], v0[i], xf[i], vf[i], out[i])
    return out


def cubic_state(b: FloatArray, tau: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Position, speed and acceleration of a virtual vehicle, paper Eq. (9) and Eq. (12).

    .. math::
       :label: eq-9-12-state

       x(\tau) = b_1 + b_2\tau + b_3\tau^2 + b_4\tau^3,\quad
       v(\tau) = b_2 + 2 b_3\tau + 3 b_4\tau^2,\quad
       a(\tau) = 2 b_3 + 6 b_4\tau

    (Eq. 9 for VV1, Eq. 12 for VV2; the acceleration, which the paper obtains "by
    derivation", is the one the following vehicle's car-following model sees).

    Parameters
    ----------
    b : array_like
        Coefficients, shape ``(..., 4)``, from :func:`cubic_coefficients`.
    tau : array_like
        Time since the start of the plan [s]; broadcast against ``b[..., 0]``.

    Returns
    -------
    x : numpy.ndarray
        Position [m].
    v : numpy.ndarray
        Speed [m/s].
    a : numpy.ndarray
        Acceleration [m/s^2].

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (9) and Eq. (12).

    Examples
    --------
    >>> b = cubic_coefficients(4.0, 0.0, 20.0, 88.0, 24.0)
    >>> [float(q) for q in cubic_state(b, 4.0)]
    [88.0, 24.0, 1.0]
    """
    b = np.asarray(b, dtype=np.float64)
    out = broadcast_apply(_state_array, b[..., 0], b[..., 1], b[..., 2], b[..., 3], tau)
    return out[..., 0], out[..., 1], out[..., 2]


@kernel
def cubic_point(
    b1: float, b2: float, b3: float, b4: float, tau: float
) -> tuple[float, float, float]:
    """Position, speed and acceleration of the cubic (b1, b2, b3, b4) at one ``tau``: the
    compiled kernel of :func:`cubic_state` (Eq. 9)."""
    x = b1 + tau * (b2 + tau * (b3 + tau * b4))
    v = b2 + tau * (2.0 * b3 + 3.0 * tau * b4)
    return x, v, 2.0 * b3 + 6.0 * tau * b4


@kernel
def _state_array(
    b1: np.ndarray, b2: np.ndarray, b3: np.ndarray, b4: np.ndarray, tau: np.ndarray
) -> np.ndarray:
    out = np.empty((tau.size, 3))
    for i in range(tau.size):
        out[i, 0], out[i, 1], out[i, 2] = cubic_point(b1[i], b2[i], b3[i], b4[i], tau[i])
    return out


def cubic_extremes(b: FloatArray, horizon: ArrayLike) -> tuple[FloatArray, FloatArray]:
    r"""Minimum speed and minimum acceleration of a virtual vehicle's cubic on :math:`[0, H]`.

    The acceleration is linear in :math:`\tau`, so its minimum is at an end; the speed is
    quadratic, so its minimum is at an end or at the vertex
    :math:`\tau^* = -b_3 / (3 b_4)` if that lies inside. The paper does not bound the virtual
    vehicles; the planner rejects a cubic that would reverse or brake harder than a vehicle
    can, with these.

    Parameters
    ----------
    b : array_like
        Coefficients, shape ``(..., 4)``, from :func:`cubic_coefficients` (Eqs. 10, 13).
    horizon : array_like
        Horizon :math:`H` [s], > 0.

    Returns
    -------
    v_min : numpy.ndarray
        Minimum speed [m/s].
    a_min : numpy.ndarray
        Minimum acceleration [m/s^2].

    Examples
    --------
    >>> b = cubic_coefficients(4.0, 0.0, 20.0, 72.0, 20.0)
    >>> [round(float(q), 6) for q in cubic_extremes(b, 4.0)]
    [17.0, -3.0]
    """
    b = np.asarray(b, dtype=np.float64)
    out = broadcast_apply(_extremes_array, b[..., 0], b[..., 1], b[..., 2], b[..., 3], horizon)
    return out[..., 0], out[..., 1]


@kernel
def cubic_minima(b: np.ndarray, h: float) -> tuple[float, float]:
    """Minimum speed and acceleration of the cubic ``b`` (4,) on [0, h]: the compiled kernel
    of :func:`cubic_extremes`."""
    a_min = min(2.0 * b[2], 2.0 * b[2] + 6.0 * h * b[3])
    v_min = min(b[1], b[1] + h * (2.0 * b[2] + 3.0 * h * b[3]))
    if b[3] > 0.0:
        vertex = -b[2] / (3.0 * b[3])
        if 0.0 < vertex < h:
            v_min = min(v_min, b[1] + vertex * (2.0 * b[2] + 3.0 * vertex * b[3]))
    return v_min, a_min


@kernel
def _extremes_array(
    b1: np.ndarray, b2: np.ndarray, b3: np.ndarray, b4: np.ndarray, h: np.ndarray
) -> np.ndarray:
    out = np.empty((h.size, 2))
    b = np.empty(4)
    for i in range(h.size):
        b[0], b[1], b[2], b[3] = b1[i], b2[i], b3[i], b4[i]
        out[i, 0], out[i, 1] = cubic_minima(b, h[i])
    return out
