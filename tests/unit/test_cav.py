"""Tests for hcomc.equations.cav (CAH and ACC blend; paper Eq. 3)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from hcomc.equations.cav import acc_acceleration, cah_acceleration

A_MAX = 1.4  # [m/s^2], Kesting 2010
B = 2.0  # [m/s^2]
C = 0.99  # coolness


def test_cah_first_branch_by_hand() -> None:
    # s = 20, v = 10, v_l = 5, a_l = -1: v_l (v - v_l) = 25 <= -2 s a_l = 40 -> branch 1:
    # v^2 a_l / (v_l^2 - 2 s a_l) = 100 * (-1) / (25 + 40) = -20/13
    acc = cah_acceleration(20.0, 10.0, 5.0, -1.0, a=A_MAX)
    np.testing.assert_allclose(acc, -20.0 / 13.0, rtol=1e-15)


def test_cah_second_branch_by_hand() -> None:
    # s = 20, v = 20, v_l = 15, a_l = -0.5: 15 * 5 = 75 > 20 -> branch 2:
    # a_l - (v - v_l)^2 / (2 s) = -0.5 - 25/40 = -1.125
    acc = cah_acceleration(20.0, 20.0, 15.0, -0.5, a=A_MAX)
    np.testing.assert_allclose(acc, -1.125, rtol=1e-15)


def test_cah_heaviside_slower_follower_gets_leader_acceleration() -> None:
    # v < v_l and v_l (v - v_l) = -15 > -2 s a_l = -20 -> branch 2 with Theta = 0: a_l.
    acc = cah_acceleration(20.0, 14.0, 15.0, 0.5, a=A_MAX)
    np.testing.assert_allclose(acc, 0.5, rtol=1e-15)


def test_cah_leader_acceleration_capped_at_own_maximum() -> None:
    # a_l = 3 > a = 1.4: same result as with a_l = a (branch 2, Theta = 0 -> 1.4).
    capped = cah_acceleration(20.0, 14.0, 15.0, 3.0, a=A_MAX)
    np.testing.assert_allclose(capped, A_MAX, rtol=1e-15)
    np.testing.assert_allclose(capped, cah_acceleration(20.0, 14.0, 15.0, A_MAX, a=A_MAX))
    # Cap also enters branch 1: s = 10, v = 5, v_l = 10, a_l = 2 -> 1.4:
    # 10 * (-5) = -50 <= -28 -> 25 * 1.4 / (100 - 28) = 35/72
    np.testing.assert_allclose(cah_acceleration(10.0, 5.0, 10.0, 2.0, a=A_MAX), 35.0 / 72.0)


def test_cah_stopped_leader_is_stop_exactly_at_leader() -> None:
    # a_l = 0 and v_l = 0 -> -v^2 / (2 s), whichever branch applies.
    np.testing.assert_allclose(cah_acceleration(50.0, 10.0, 0.0, 0.0, a=A_MAX), -1.0, rtol=1e-15)
    np.testing.assert_allclose(cah_acceleration(50.0, 10.0, 0.0, -3.0, a=A_MAX), -1.0, rtol=1e-15)


def test_cah_no_leader_returns_capped_leader_acceleration() -> None:
    acc = cah_acceleration(np.inf, np.array([10.0, 30.0]), 0.0, np.array([0.3, 5.0]), a=A_MAX)
    np.testing.assert_allclose(acc, [0.3, A_MAX], rtol=1e-15)


def test_cah_degenerate_inputs_are_finite_without_warnings() -> None:
    s = np.array([0.0, -1.0, 0.005, 10.0, 10.0, np.inf, np.inf])
    v = np.array([0.0, 5.0, 10.0, 0.0, 0.0, 0.0, 0.0])
    v_l = np.array([0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0])
    a_l = np.array([0.0, 0.0, -1.0, 0.0, 1.25, 0.0, -2.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        acc = cah_acceleration(s, v, v_l, a_l, a=A_MAX)
    assert np.isfinite(acc).all()
    # s <= 0 is guarded to 0.01 m: -25 / 0.02 for v = 5 against a stopped leader.
    np.testing.assert_allclose(acc[1], -25.0 / 0.02, rtol=1e-14)
    np.testing.assert_allclose(acc[2], -100.0 / 0.02, rtol=1e-14)
    # Denominator v_l^2 - 2 s a_l = 25 - 25 = 0 on branch 1 -> branch 2: a_l.
    np.testing.assert_allclose(acc[4], 1.25, rtol=1e-15)
    np.testing.assert_allclose(acc[5:], [0.0, -2.0], rtol=1e-15)


def test_cah_broadcasts_per_vehicle_parameters() -> None:
    acc = cah_acceleration(
        np.array([20.0, 20.0]),
        np.array([10.0, 20.0]),
        np.array([5.0, 15.0]),
        np.array([-1.0, -0.5]),
        a=np.array([1.4, 1.0]),
    )
    np.testing.assert_allclose(acc, [-20.0 / 13.0, -1.125], rtol=1e-15)


def test_acc_returns_idm_exactly_when_idm_is_not_below_cah() -> None:
    a_idm = np.array([0.5, -1.0, 1.3, -0.7])
    a_cah = np.array([-1.0, -1.0, 1.2, -3.0])
    out = acc_acceleration(a_idm, a_cah, b=B, c=C)
    assert (out == a_idm).all()


def test_acc_coolness_zero_returns_idm() -> None:
    a_idm = np.array([-2.0, -4.0, 0.3])
    a_cah = np.array([-1.0, 0.5, 1.0])
    assert (acc_acceleration(a_idm, a_cah, b=B, c=0.0) == a_idm).all()


def test_acc_blend_by_hand() -> None:
    # a_idm = -2 < a_cah = -1: 0.01 (-2) + 0.99 (-1 + 2 tanh(-0.5)) = -1.92499197143...
    expected = 0.01 * -2.0 + 0.99 * (-1.0 + 2.0 * math.tanh(-0.5))
    np.testing.assert_allclose(expected, -1.9249919714, atol=1e-10)
    np.testing.assert_allclose(acc_acceleration(-2.0, -1.0, b=B, c=C), expected, rtol=1e-15)


def test_acc_blend_is_continuous_at_the_switch() -> None:
    eps = 1e-9
    below = acc_acceleration(-1.0 - eps, -1.0, b=B, c=C)
    np.testing.assert_allclose(below, -1.0, atol=1e-8)


def test_acc_blend_with_coolness_one_is_cah_plus_saturated_difference() -> None:
    # c = 1: a_cah + b tanh((a_idm - a_cah)/b); far below a_cah it saturates near a_cah - b.
    np.testing.assert_allclose(
        acc_acceleration(-50.0, 0.0, b=B, c=1.0), B * math.tanh(-25.0), rtol=1e-15
    )


@pytest.mark.parametrize("shape", [(), (7,), (3, 4)])
def test_acc_returns_float64_arrays(shape: tuple[int, ...]) -> None:
    out = acc_acceleration(np.zeros(shape), np.ones(shape), b=B, c=C)
    assert isinstance(out, np.ndarray)
    assert out.shape == shape
    assert out.dtype == np.float64
