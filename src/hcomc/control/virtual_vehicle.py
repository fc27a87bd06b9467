"""Cubic virtual vehicles of the hierarchical cooperative planning model (paper Eq. 8-13).

The virtual vehicle VV1 (of VR, in lane 1) moves along a cubic in time from the state of VMF
at t0' to the state of VR at tf' (Eq. 8-10); VMC follows it with its own car-following model,
so its leader morphs smoothly from VMF to VR. VV2 (of VMC, in lane 2) does the same from VNF
to VMC for VNR (Eq. 11-13). Time is taken relative to t0 for numerical conditioning, so the
coefficients ``b = (b1, b2, b3, b4)`` give ``x(t) = b1 + b2 τ + b3 τ² + b4 τ³``
with ``τ = t - t0``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.interface import MergePlan
from hcomc.models._broadcast import broadcast_apply


def cubic_coefficients(
    horizon: ArrayLike, x0: ArrayLike, v0: ArrayLike, xf: ArrayLike, vf: ArrayLike
) -> FloatArray:
    r"""Coefficients (..., 4) of the cubic through (x0, v0) at τ = 0 and (xf, vf) at τ = H.

    Eq. 10 (VV1, between the boundary states of Eq. 8) and Eq. 13 (VV2, between those of
    Eq. 11) with ``t0' = 0``: the 4x4 system has the closed-form solution

    .. math::
       b_1 = x_0,\quad b_2 = v_0,\quad
       b_3 = \frac{3\Delta x - (2 v_0 + v_f) H}{H^2},\quad
       b_4 = \frac{-2\Delta x + (v_0 + v_f) H}{H^3},\qquad \Delta x = x_f - x_0.

    Parameters
    ----------
    horizon : H = tf' - t0' > 0 [s].
    x0, v0 : start position [m] and speed [m/s] (VMF for VV1, VNF for VV2).
    xf, vf : end position [m] and speed [m/s] (VR for VV1, VMC for VV2).
    """
    return broadcast_apply(_coefficients_array, horizon, x0, v0, xf, vf)


@kernel
def cubic_into(h: float, x0: float, v0: float, xf: float, vf: float, out: np.ndarray) -> None:
    """Write the coefficients of one cubic into ``out`` (4,): the one implementation of
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
    """Position [m], speed [m/s] and acceleration [m/s^2] of the cubic at ``tau`` (Eq. 9 for
    VV1, Eq. 12 for VV2)."""
    b = np.asarray(b, dtype=np.float64)
    out = broadcast_apply(_state_array, b[..., 0], b[..., 1], b[..., 2], b[..., 3], tau)
    return out[..., 0], out[..., 1], out[..., 2]


@kernel
def cubic_point(
    b1: float, b2: float, b3: float, b4: float, tau: float
) -> tuple[float, float, float]:
    """Position, speed and acceleration of the cubic (b1, b2, b3, b4) at one ``tau``: the one
    implementation of :func:`cubic_state` (Eq. 9)."""
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
    """Minimum speed [m/s] and minimum acceleration [m/s^2] of the cubic on [0, H].

    The acceleration is linear in τ, so its minimum is at an end; the speed is quadratic, so its
    minimum is at an end or at the vertex ``τ* = -b3 / (3 b4)`` if that lies inside.
    """
    b = np.asarray(b, dtype=np.float64)
    out = broadcast_apply(_extremes_array, b[..., 0], b[..., 1], b[..., 2], b[..., 3], horizon)
    return out[..., 0], out[..., 1]


@kernel
def cubic_minima(b: np.ndarray, h: float) -> tuple[float, float]:
    """Minimum speed and acceleration of the cubic ``b`` (4,) on [0, h]: the one
    implementation of :func:`cubic_extremes`."""
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


def virtual_states(
    plan: MergePlan, t: float, x: FloatArray, v: FloatArray, a: FloatArray
) -> dict[str, tuple[float, float, float]]:
    """State (x, v, a) at time t of each virtual vehicle ``plan`` has ("vv0", "vv1", "vv2").

    Within the horizon a virtual vehicle is its cubic; after it, VV0 is the projection of VR's
    future leader (``group.vmf``, if any) and VV1 that of VR; VV2 ends at the horizon. The
    engine executes exactly these, and a replanning controller continues them.
    """
    g, tau = plan.group, t - plan.t0
    out: dict[str, tuple[float, float, float]] = {}
    after = {"vv0": g.vmf, "vv1": g.vr, "vv2": -1}
    for name, coeffs in (("vv0", plan.vv0), ("vv1", plan.vv1), ("vv2", plan.vv2)):
        if coeffs is None:
            continue
        if tau <= plan.horizon:
            xv, vv, av = cubic_state(coeffs, tau)
            out[name] = (float(xv), float(vv), float(av))
        elif after[name] >= 0:
            j = after[name]
            out[name] = (float(x[j]), float(v[j]), float(a[j]))
    return out
