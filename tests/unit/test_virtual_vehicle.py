"""Cubic virtual vehicles (Eq. 8-13) and the Eq. 15 critical acceleration."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.equations.safety import critical_acceleration
from hcomc.equations.virtual_vehicle import cubic_coefficients, cubic_extremes, cubic_state


def test_cubic_meets_eq10_boundary_conditions():
    rng = np.random.default_rng(0)
    n = 500
    H = rng.uniform(4.0, 10.0, n)
    x0, xf = rng.uniform(0, 1500, n), rng.uniform(0, 1500, n)
    v0, vf = rng.uniform(0, 35, n), rng.uniform(0, 35, n)
    b = cubic_coefficients(H, x0, v0, xf, vf)
    xs, vs, _ = cubic_state(b, 0.0)
    xe, ve, _ = cubic_state(b, H)
    np.testing.assert_allclose(xs, x0, atol=1e-9)
    np.testing.assert_allclose(vs, v0, atol=1e-9)
    np.testing.assert_allclose(xe, xf, atol=1e-9)
    np.testing.assert_allclose(ve, vf, atol=1e-9)


def test_cubic_equals_the_eq10_matrix_solution_at_absolute_times():
    """Solve Eq. 10's 4x4 system at t0' = 37 s and compare with the relative-time form."""
    t0, H = 37.0, 6.5
    tf = t0 + H
    x0, v0, xf, vf = 512.0, 28.0, 690.0, 24.0
    M = np.array([
        [1, t0, t0**2, t0**3],
        [1, tf, tf**2, tf**3],
        [0, 1, 2 * t0, 3 * t0**2],
        [0, 1, 2 * tf, 3 * tf**2],
    ])  # fmt: skip
    coef = np.linalg.solve(M, [x0, xf, v0, vf])
    b = cubic_coefficients(H, x0, v0, xf, vf)
    for t in np.linspace(t0, tf, 11):
        x_abs = coef @ [1, t, t**2, t**3]
        v_abs = coef[1:] @ [1, 2 * t, 3 * t**2]
        x_rel, v_rel, _ = cubic_state(b, t - t0)
        assert x_rel == pytest.approx(x_abs, abs=1e-6)
        assert v_rel == pytest.approx(v_abs, abs=1e-6)


def test_cubic_extremes_match_dense_sampling():
    rng = np.random.default_rng(1)
    H = rng.uniform(4, 10, 300)
    b = cubic_coefficients(H, 0.0, rng.uniform(0, 35, 300), rng.uniform(20, 300, 300),
                           rng.uniform(0, 35, 300))  # fmt: skip
    v_min, a_min = cubic_extremes(b, H)
    tau = np.linspace(0.0, 1.0, 20001)[:, None] * H
    _, v, a = cubic_state(b, tau)
    np.testing.assert_allclose(v_min, v.min(axis=0), atol=1e-6)
    np.testing.assert_allclose(a_min, a.min(axis=0), atol=1e-9)


EQ15 = {"min_distance": 2.0, "emergency_decel": 7.5}  # D [m] and a_merg [m/s^2] of the example


@pytest.mark.parametrize(("d", "expected"), [(30, 7.0), (50, 4.8), (80, 3.3), (110, 2.5)])
def test_critical_acceleration_models_table(d, expected):
    """Eq. 15 worked example: v_r = v_f = 25 m/s, T = 1 s, D = 2 m, a_merg = 7.5 m/s^2."""
    assert float(critical_acceleration(d, 25.0, 25.0, delay=1.0, **EQ15)) == pytest.approx(
        expected, abs=0.05
    )


def test_critical_acceleration_closed_form_and_infinite_case():
    d, vr, vf, T = 40.0, 30.0, 20.0, 0.5
    expected = vr**2 / (2 * (d - 2.0 - vr * T + vf**2 / 15.0))
    a_cr = float(critical_acceleration(d, vr, vf, delay=T, **EQ15))
    assert a_cr == pytest.approx(expected, rel=1e-12)
    # a 5 m gap at 30 m/s behind a standing vehicle: no deceleration avoids the crash
    assert np.isinf(critical_acceleration(5.0, 30.0, 0.0, delay=1.0, **EQ15))
    out = critical_acceleration(
        np.array([5.0, 80.0]), 30.0, 0.0, delay=np.array([1.0, 0.5]), **EQ15
    )
    assert np.isinf(out[0])
    assert np.isfinite(out[1])
