"""Tests for hcomc.equations.fuel (paper Eq. 16, Kamal et al. 2011)."""

from __future__ import annotations

import numpy as np
import pydantic
import pytest

from hcomc.config.fuel import FUEL_DEFAULT, FuelParams
from hcomc.equations.fuel import DEFAULT_COEFFICIENTS, fuel_consumed, fuel_rate

SPEEDS = np.array([20.0, 25.0, 30.0])


def _cruise(v: np.ndarray) -> np.ndarray:
    return 0.1569 + 2.450e-2 * v - 7.415e-4 * v**2 + 5.975e-5 * v**3


def _accel_term(v: np.ndarray) -> np.ndarray:
    return 0.07224 + 9.681e-2 * v + 1.075e-3 * v**2


def test_cruise_rates_match_models_table() -> None:
    rate = fuel_rate(SPEEDS, 0.0)
    np.testing.assert_allclose(rate, [0.83, 1.24, 1.84], atol=0.005)
    # Exact values of the polynomial: 0.8283, 1.23955625, 1.8378
    np.testing.assert_allclose(rate, _cruise(SPEEDS), rtol=1e-14)
    np.testing.assert_allclose(rate, [0.8283, 1.23955625, 1.8378], rtol=1e-12)


def test_acceleration_term_at_one_matches_models_table() -> None:
    added = fuel_rate(SPEEDS, 1.0) - fuel_rate(SPEEDS, 0.0)
    # c0 + c1 v + c2 v^2: 2.43844, 3.164365, 3.94404 (the table column is the added term, not
    # the total rate; totals are 3.26674, 4.40392, 5.78184 mL/s).
    np.testing.assert_allclose(added, [2.44, 3.16, 3.94], atol=0.005)
    np.testing.assert_allclose(added, _accel_term(SPEEDS), rtol=1e-13)
    np.testing.assert_allclose(fuel_rate(SPEEDS, 1.0), [3.26674, 4.40392125, 5.78184], rtol=1e-12)


def test_acceleration_term_is_linear_in_a() -> None:
    np.testing.assert_allclose(
        fuel_rate(25.0, 0.4), _cruise(25.0) + 0.4 * _accel_term(25.0), rtol=1e-14
    )


def test_braking_gives_no_credit_by_default() -> None:
    assert FUEL_DEFAULT.accel_term == "positive"
    a = np.array([-0.1, -1.0, -5.0])
    np.testing.assert_array_equal(fuel_rate(25.0, a), np.full(3, fuel_rate(25.0, 0.0)))


def test_signed_variant_credits_braking_but_clips_at_zero() -> None:
    signed = FuelParams(accel_term="signed")
    np.testing.assert_allclose(
        fuel_rate(25.0, -0.1, signed), _cruise(25.0) - 0.1 * _accel_term(25.0), rtol=1e-14
    )
    # v = 10, a = -1: 0.38750 - 1.14784 < 0 -> 0.
    assert float(fuel_rate(10.0, -1.0, signed)) == 0.0
    np.testing.assert_allclose(fuel_rate(10.0, 1.0, signed), fuel_rate(10.0, 1.0), rtol=1e-15)


def test_rate_nonnegative_over_grid() -> None:
    v, a = np.meshgrid(np.linspace(0.0, 45.0, 91), np.linspace(-8.0, 4.0, 61))
    for params in (FUEL_DEFAULT, FuelParams(accel_term="signed")):
        rate = fuel_rate(v, a, params)
        assert rate.shape == v.shape
        assert (rate >= 0.0).all()


def test_fuel_consumed_constant_speed() -> None:
    dt, duration = 0.1, 60.0
    n = round(duration / dt)
    v = np.full(n, 25.0)
    total = fuel_consumed(v, np.zeros(n), dt)
    np.testing.assert_allclose(total, float(fuel_rate(25.0, 0.0)) * duration / 1000.0, rtol=1e-12)
    np.testing.assert_allclose(total, 1.23955625 * 0.06, rtol=1e-12)  # 0.0743734 L


def test_fuel_consumed_ignores_absent_vehicles_and_sums_along_axis() -> None:
    dt = 0.5
    v = np.array([[20.0, 20.0, np.nan, np.nan], [np.nan, 30.0, 30.0, 30.0]])
    a = np.array([[0.0, 0.0, np.nan, np.nan], [np.nan, 0.0, 0.0, 0.0]])
    per_vehicle = fuel_consumed(v, a, dt)
    assert per_vehicle.shape == (2,)
    expected = np.array([2 * 0.8283, 3 * 1.8378]) * dt / 1000.0
    np.testing.assert_allclose(per_vehicle, expected, rtol=1e-12)
    per_step = fuel_consumed(v, a, dt, axis=0)
    np.testing.assert_allclose(per_step.sum(), expected.sum(), rtol=1e-12)
    assert np.isfinite(per_step).all()


def test_params_are_frozen_and_strict() -> None:
    with pytest.raises(pydantic.ValidationError):
        FuelParams(unknown=1.0)  # type: ignore[call-arg]
    with pytest.raises(pydantic.ValidationError):
        FuelParams(accel_term="both")  # type: ignore[arg-type]
    with pytest.raises(pydantic.ValidationError):
        FuelParams(accel=(1.0, 2.0))  # type: ignore[arg-type]
    with pytest.raises(pydantic.ValidationError):
        FUEL_DEFAULT.accel_term = "signed"  # type: ignore[misc]
    assert FUEL_DEFAULT.cruise == (0.1569, 2.450e-2, -7.415e-4, 5.975e-5)
    assert FUEL_DEFAULT.accel == (0.07224, 9.681e-2, 1.075e-3)
    for name in ("cruise", "accel", "accel_term"):
        assert FuelParams.model_fields[name].description


def test_config_defaults_are_the_kernel_defaults() -> None:
    """The configuration's FuelParams and the equations' FuelCoefficients give the same
    numbers, so fuel_rate's default and the config's default are one model."""
    assert FUEL_DEFAULT.coefficients() == DEFAULT_COEFFICIENTS.coefficients()
    signed = FuelParams(accel_term="signed").coefficients()
    assert signed == DEFAULT_COEFFICIENTS._replace(positive_only=0.0).coefficients()
    np.testing.assert_array_equal(
        fuel_rate(SPEEDS, 1.0, FUEL_DEFAULT), fuel_rate(SPEEDS, 1.0, DEFAULT_COEFFICIENTS)
    )
