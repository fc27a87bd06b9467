"""Tests for hcomc.equations.transition (paper Eq. 14)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hcomc.equations.transition import blend_acceleration, transition_parameters, transition_weight


@pytest.mark.parametrize("duration", [3.0, 4.0, 6.0])
def test_weight_at_start_end_and_midpoint(duration: float) -> None:
    w = transition_weight(np.array([0.0, duration / 2, duration]), duration)
    np.testing.assert_allclose(w[0], 0.01, rtol=1e-12)
    np.testing.assert_allclose(w[1], 0.5, rtol=1e-14)
    np.testing.assert_allclose(w[2], 0.99, rtol=1e-12)


def test_gamma_and_lambda_for_default_tolerance() -> None:
    lam, gamma = transition_parameters(4.0)
    # artanh(0.98) = ln(99)/2 = 2.29756...
    np.testing.assert_allclose(gamma, 2.298, atol=1e-3)
    np.testing.assert_allclose(gamma, 0.5 * math.log(99.0), rtol=1e-14)
    np.testing.assert_allclose(lam, 2.0 * gamma / 4.0, rtol=1e-15)


def test_gamma_for_other_tolerance() -> None:
    _, gamma = transition_parameters(4.0, tolerance=0.02)
    np.testing.assert_allclose(gamma, 1.946, atol=1e-3)  # epsilon = 0.02
    np.testing.assert_allclose(transition_weight(0.0, 4.0, tolerance=0.02), 0.02, rtol=1e-12)


def test_weight_is_strictly_increasing_and_bounded() -> None:
    tau = np.linspace(-2.0, 10.0, 2001)
    w = transition_weight(tau, 4.0)
    assert (np.diff(w) > 0.0).all()
    assert ((w > 0.0) & (w < 1.0)).all()


def test_weight_broadcasts_per_vehicle_durations() -> None:
    durations = np.array([3.0, 4.0, 5.0, 6.0])
    w = transition_weight(durations[:, None] * np.array([0.0, 0.5, 1.0]), durations[:, None])
    assert w.shape == (4, 3)
    np.testing.assert_allclose(w, np.broadcast_to([0.01, 0.5, 0.99], (4, 3)), rtol=1e-12)


def test_blend_endpoints_and_value() -> None:
    assert float(blend_acceleration(-1.0, 2.0, 0.0)) == -1.0
    assert float(blend_acceleration(-1.0, 2.0, 1.0)) == 2.0
    np.testing.assert_allclose(blend_acceleration(-1.0, 2.0, 0.25), -0.25, rtol=1e-15)
    out = blend_acceleration(
        np.zeros(3), np.ones(3), transition_weight(np.array([0.0, 2.0, 4.0]), 4.0)
    )
    np.testing.assert_allclose(out, [0.01, 0.5, 0.99], rtol=1e-12)
    assert out.dtype == np.float64
