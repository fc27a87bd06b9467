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

from hcomc._typing import FloatArray


def cubic_coefficients(
    horizon: ArrayLike, x0: ArrayLike, v0: ArrayLike, xf: ArrayLike, vf: ArrayLike
) -> FloatArray:
    r"""Coefficients (..., 4) of the cubic through (x0, v0) at τ = 0 and (xf, vf) at τ = H.

    Eq. 10 with ``t0' = 0``: the 4x4 system has the closed-form solution

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
    H = np.asarray(horizon, dtype=np.float64)
    x0, v0 = np.asarray(x0, dtype=np.float64), np.asarray(v0, dtype=np.float64)
    dx = np.asarray(xf, dtype=np.float64) - x0
    vf = np.asarray(vf, dtype=np.float64)
    b3 = (3.0 * dx - (2.0 * v0 + vf) * H) / (H * H)
    b4 = (-2.0 * dx + (v0 + vf) * H) / (H * H * H)
    return np.stack(np.broadcast_arrays(x0, v0, b3, b4), axis=-1)


def cubic_state(b: FloatArray, tau: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Position [m], speed [m/s] and acceleration [m/s^2] of the cubic at ``tau`` (Eq. 9)."""
    tau = np.asarray(tau, dtype=np.float64)
    b1, b2, b3, b4 = (b[..., i] for i in range(4))
    x = b1 + tau * (b2 + tau * (b3 + tau * b4))
    v = b2 + tau * (2.0 * b3 + 3.0 * tau * b4)
    a = 2.0 * b3 + 6.0 * tau * b4
    return x, v, a


def cubic_extremes(b: FloatArray, horizon: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Minimum speed [m/s] and minimum acceleration [m/s^2] of the cubic on [0, H].

    The acceleration is linear in τ, so its minimum is at an end; the speed is quadratic, so its
    minimum is at an end or at the vertex ``τ* = -b3 / (3 b4)`` if that lies inside.
    """
    H = np.asarray(horizon, dtype=np.float64)
    _, v_end, a_end = cubic_state(b, H)
    b2, b3, b4 = b[..., 1], b[..., 2], b[..., 3]
    a_min = np.minimum(2.0 * b3, a_end)
    safe_b4 = np.where(b4 == 0.0, 1.0, b4)
    vertex = np.where(b4 > 0.0, -b3 / (3.0 * safe_b4), -1.0)
    inside = (vertex > 0.0) & (vertex < H)
    v_vertex = b2 + vertex * (2.0 * b3 + 3.0 * vertex * b4)
    v_min = np.minimum(np.minimum(b2, v_end), np.where(inside, v_vertex, np.inf))
    return v_min, a_min
