"""Tests for hcomc.equations.lane_change (paper Eqs. 4-6)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from numpy.polynomial import polynomial as poly

from hcomc.equations.lane_change import lateral_offset, quintic_coefficients, quintic_shape
from hcomc.equations.lane_change_peaks import (
    min_duration,
    peak_lateral_accel,
    peak_lateral_jerk,
    peak_lateral_speed,
)

W = 3.75  # lane width [m]


def _eval(coef: np.ndarray, x: np.ndarray, order: int) -> np.ndarray:
    """Evaluate the ``order``-th derivative of the batched polynomials ``coef`` (N, 6) at x (N,)."""
    c = poly.polyder(coef.T, m=order, axis=0) if order else coef.T
    return poly.polyval(x, c, tensor=False)


# --------------------------------------------------------------------------------------------
# coefficients (Eq. 4)
# --------------------------------------------------------------------------------------------


def test_coefficients_rest_to_rest_from_origin_by_hand() -> None:
    coef = quintic_coefficients(0.0, 100.0, 0.0, W)
    assert coef.shape == (6,)
    expected = [0.0, 0.0, 0.0, 10 * W / 100**3, -15 * W / 100**4, 6 * W / 100**5]
    np.testing.assert_allclose(coef, expected, rtol=1e-12, atol=1e-18)


def test_coefficients_rest_to_rest_boundary_conditions() -> None:
    x0, xf, y0, yf = 40.0, 130.0, 1.875, 5.625
    coef = quintic_coefficients(x0, xf, y0, yf)[None, :]
    ends = np.array([x0, xf])
    coef2 = np.repeat(coef, 2, axis=0)
    np.testing.assert_allclose(_eval(coef2, ends, 0), [y0, yf], atol=1e-9)
    np.testing.assert_allclose(_eval(coef2, ends, 1), [0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(_eval(coef2, ends, 2), [0.0, 0.0], atol=1e-9)


def test_coefficients_random_boundary_values_batched() -> None:
    rng = np.random.default_rng(20250711)
    n = 200
    x0 = rng.uniform(-100.0, 100.0, n)
    xf = x0 + rng.uniform(30.0, 150.0, n)
    y0 = rng.uniform(-5.0, 5.0, n)
    yf = rng.uniform(-5.0, 5.0, n)
    dy0, dyf = rng.uniform(-0.1, 0.1, (2, n))
    ddy0, ddyf = rng.uniform(-0.01, 0.01, (2, n))
    coef = quintic_coefficients(x0, xf, y0, yf, dy0, ddy0, dyf, ddyf)
    assert coef.shape == (n, 6)
    assert coef.dtype == np.float64
    np.testing.assert_allclose(_eval(coef, x0, 0), y0, atol=1e-9)
    np.testing.assert_allclose(_eval(coef, xf, 0), yf, atol=1e-9)
    np.testing.assert_allclose(_eval(coef, x0, 1), dy0, atol=1e-9)
    np.testing.assert_allclose(_eval(coef, xf, 1), dyf, atol=1e-9)
    np.testing.assert_allclose(_eval(coef, x0, 2), ddy0, atol=1e-9)
    np.testing.assert_allclose(_eval(coef, xf, 2), ddyf, atol=1e-9)
    # Batched result equals one-at-a-time solutions.
    for i in (0, 17, n - 1):
        single = quintic_coefficients(x0[i], xf[i], y0[i], yf[i], dy0[i], ddy0[i], dyf[i], ddyf[i])
        np.testing.assert_allclose(coef[i], single, rtol=1e-12, atol=1e-20)


def test_coefficients_broadcast_scalar_and_array_boundaries() -> None:
    coef = quintic_coefficients(0.0, np.array([[50.0], [100.0]]), 0.0, np.array([W, -W, 2 * W]))
    assert coef.shape == (2, 3, 6)
    np.testing.assert_allclose(coef[1, 0], quintic_coefficients(0.0, 100.0, 0.0, W), rtol=1e-14)


def test_closed_form_agrees_with_coefficient_polynomial() -> None:
    x0, xf, y0, yf = 250.0, 350.0, 0.0, W
    coef = quintic_coefficients(x0, xf, y0, yf)
    x = np.linspace(x0, xf, 101)
    xi = (x - x0) / (xf - x0)
    closed = W * (10 * xi**3 - 15 * xi**4 + 6 * xi**5)
    np.testing.assert_allclose(poly.polyval(x, coef), closed, atol=1e-8)
    y, dy, ddy = lateral_offset(x, x0, xf, y0, yf)
    np.testing.assert_allclose(y, closed, atol=1e-13)
    np.testing.assert_allclose(dy, poly.polyval(x, poly.polyder(coef)), atol=1e-9)
    np.testing.assert_allclose(ddy, poly.polyval(x, poly.polyder(coef, 2)), atol=1e-9)


# --------------------------------------------------------------------------------------------
# shape and lateral offset
# --------------------------------------------------------------------------------------------


def test_shape_values_and_clipping() -> None:
    p, dp, ddp = quintic_shape(np.array([-0.5, 0.0, 0.5, 1.0, 1.7]))
    np.testing.assert_allclose(p, [0.0, 0.0, 0.5, 1.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(dp, [0.0, 0.0, 1.875, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(ddp, [0.0, 0.0, 0.0, 0.0, 0.0], atol=1e-15)


def test_shape_derivatives_match_finite_differences() -> None:
    xi = np.linspace(0.05, 0.95, 37)
    h = 1e-6
    p_hi, dp_hi, _ = quintic_shape(xi + h)
    p_lo, dp_lo, _ = quintic_shape(xi - h)
    _, dp, ddp = quintic_shape(xi)
    np.testing.assert_allclose(dp, (p_hi - p_lo) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(ddp, (dp_hi - dp_lo) / (2 * h), atol=1e-7)


def test_lateral_offset_clamps_outside_the_manoeuvre() -> None:
    y, dy, ddy = lateral_offset(np.array([-10.0, 0.0, 120.0]), 0.0, 100.0, 3.75, 0.0)
    np.testing.assert_allclose(y, [3.75, 3.75, 0.0], atol=1e-15)
    assert (dy == 0.0).all()
    assert (ddy == 0.0).all()


def test_lateral_offset_midpoint_and_per_vehicle_broadcast() -> None:
    x0 = np.array([0.0, 500.0])
    xf = x0 + np.array([100.0, 120.0])
    y, dy, ddy = lateral_offset(
        0.5 * (x0 + xf), x0, xf, np.array([0.0, 3.75]), np.array([3.75, 0.0])
    )
    np.testing.assert_allclose(y, [1.875, 1.875], rtol=1e-15)
    np.testing.assert_allclose(dy, [1.875 * 3.75 / 100.0, -1.875 * 3.75 / 120.0], rtol=1e-15)
    np.testing.assert_allclose(ddy, 0.0, atol=1e-15)


def test_lateral_offset_degenerate_length_is_finite() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = lateral_offset(np.array([9.0, 10.0, 11.0]), 10.0, 10.0, 0.0, W)
    for q in out:
        assert np.isfinite(q).all()
    np.testing.assert_allclose(out[0], [0.0, 0.0, W])


# --------------------------------------------------------------------------------------------
# time-parametrised peaks
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("duration", [3.0, 4.0, 5.0, 6.0])
def test_sampled_peaks_match_closed_forms(duration: float) -> None:
    u = 25.0  # [m/s], constant longitudinal speed: x = u t
    t = np.linspace(0.0, duration, 400_001)
    _, dy_dx, d2y_dx2 = lateral_offset(u * t, 0.0, u * duration, 0.0, W)
    speed = dy_dx * u
    accel = d2y_dx2 * u * u
    np.testing.assert_allclose(np.abs(speed).max(), peak_lateral_speed(W, duration), rtol=1e-4)
    np.testing.assert_allclose(np.abs(accel).max(), peak_lateral_accel(W, duration), rtol=1e-4)
    jerk = np.gradient(accel, t)
    np.testing.assert_allclose(np.abs(jerk).max(), peak_lateral_jerk(W, duration), rtol=1e-3)


@pytest.mark.parametrize(
    ("duration", "speed", "accel", "jerk"),
    [
        (3.0, 2.34, 2.41, 8.33),
        (4.0, 1.76, 1.35, 3.52),
        (5.0, 1.41, 0.87, 1.80),
        (6.0, 1.17, 0.60, 1.04),
    ],
)
def test_peaks_match_models_table(duration: float, speed: float, accel: float, jerk: float) -> None:
    assert float(peak_lateral_speed(W, duration)) == pytest.approx(speed, abs=0.005)
    assert float(peak_lateral_accel(W, duration)) == pytest.approx(accel, abs=0.005)
    assert float(peak_lateral_jerk(W, duration)) == pytest.approx(jerk, abs=0.005)


def test_peak_constants_are_exact() -> None:
    np.testing.assert_allclose(peak_lateral_speed(1.0, 1.0), 1.875, rtol=1e-15)
    np.testing.assert_allclose(peak_lateral_accel(1.0, 1.0), 10.0 / math.sqrt(3.0), rtol=1e-15)
    np.testing.assert_allclose(peak_lateral_accel(1.0, 1.0), 5.7735, atol=1e-4)
    np.testing.assert_allclose(peak_lateral_jerk(1.0, 1.0), 60.0, rtol=1e-15)


def test_min_duration_jerk_limited_by_hand() -> None:
    # sqrt(5.7735 * 3.75 / 2) = 3.2902 s (acceleration) < (60 * 3.75 / 5)^(1/3) = 45^(1/3)
    # = 3.5569 s (jerk): the jerk limit governs.
    t_min = min_duration(W, 2.0, 5.0)
    np.testing.assert_allclose(t_min, 45.0 ** (1.0 / 3.0), rtol=1e-14)
    np.testing.assert_allclose(t_min, 3.5569, atol=1e-4)
    # The limits are met exactly at T_min (the binding one with equality).
    assert peak_lateral_accel(W, t_min) <= 2.0
    np.testing.assert_allclose(peak_lateral_jerk(W, t_min), 5.0, rtol=1e-13)


def test_min_duration_acceleration_limited_by_hand() -> None:
    # j_max = 50: jerk bound 4.5^(1/3) = 1.651 s < sqrt(10/sqrt(3) * 3.75 / 2) = 3.2902 s.
    t_min = min_duration(W, 2.0, 50.0)
    np.testing.assert_allclose(t_min, math.sqrt(10.0 / math.sqrt(3.0) * W / 2.0), rtol=1e-14)
    np.testing.assert_allclose(t_min, 3.2902, atol=1e-4)
    np.testing.assert_allclose(peak_lateral_accel(W, t_min), 2.0, rtol=1e-13)


def test_min_duration_broadcasts() -> None:
    t_min = min_duration(np.array([3.5, 3.75]), np.array([[2.0], [2.943]]), 5.0)
    assert t_min.shape == (2, 2)
    assert t_min.dtype == np.float64
