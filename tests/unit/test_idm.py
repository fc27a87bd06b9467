"""Tests for hcomc.equations.idm (paper Eq. 1)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.equations.idm import desired_gap, equilibrium_gap, idm_acceleration
from hcomc.equations.iidm import iidm_acceleration

# Textbook example: v0 = 33.3 m/s, T = 1.5 s, s0 = 2 m (a, b do not enter s_e).
HDV = {"v0": 33.3, "T": 1.5, "a": 1.0, "b": 2.0, "s0": 2.0, "delta": 4.0}
EQ = {"v0": 33.3, "T": 1.5, "s0": 2.0, "delta": 4.0}
MODELS = [idm_acceleration, iidm_acceleration]


# --------------------------------------------------------------------------------------------
# reference values
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_free_road_from_standstill_gives_max_acceleration(model) -> None:
    acc = model(np.inf, 0.0, 0.0, **HDV)
    assert isinstance(acc, np.ndarray)
    assert acc.dtype == np.float64
    np.testing.assert_allclose(acc, HDV["a"], rtol=1e-15)


@pytest.mark.parametrize("model", MODELS)
def test_free_road_at_desired_speed_is_zero(model) -> None:
    np.testing.assert_allclose(model(np.inf, 33.3, 0.0, **HDV), 0.0, atol=1e-15)


def test_desired_gap_reference_value() -> None:
    # s* = 2 + 20*1.5 + 20*5/(2*sqrt(1*2)) = 32 + 100/(2 sqrt 2) = 67.35533905932738
    np.testing.assert_allclose(
        desired_gap(20.0, 5.0, T=1.5, a=1.0, b=2.0, s0=2.0), 32.0 + 25.0 * np.sqrt(2.0), rtol=1e-14
    )


def test_idm_reference_value() -> None:
    # a[1 - (20/33.3)^4 - (32/40)^2] with 1 m/s^2
    expected = 1.0 - (20.0 / 33.3) ** 4 - 0.8**2
    np.testing.assert_allclose(idm_acceleration(40.0, 20.0, 0.0, **HDV), expected, rtol=1e-14)


@pytest.mark.parametrize(
    ("v", "gap"),
    # Reference tables list 34.3, 47.8 and 80.2 m. The formula with v0 = 33.3 m/s gives 80.45 m at
    # 30 m/s (80.2 is not reproduced; v0 = 120/3.6 would give 80.15), so the values computed
    # from the formula are pinned here.
    [(20.0, 34.30996), (25.0, 47.81911), (30.0, 80.45433)],
)
def test_equilibrium_gap_reference_values(v: float, gap: float) -> None:
    s_e = equilibrium_gap(v, **EQ)
    np.testing.assert_allclose(s_e, gap, atol=1e-4)
    np.testing.assert_allclose(s_e, (2.0 + 1.5 * v) / np.sqrt(1.0 - (v / 33.3) ** 4), rtol=1e-14)


@pytest.mark.parametrize(("v", "rounded"), [(20.0, 34.3), (25.0, 47.8)])
def test_equilibrium_gap_matches_models_table(v: float, rounded: float) -> None:
    np.testing.assert_allclose(equilibrium_gap(v, **EQ), rounded, atol=0.05)


@pytest.mark.parametrize("v", [20.0, 25.0, 30.0])
def test_idm_is_stationary_at_equilibrium_gap(v: float) -> None:
    acc = idm_acceleration(equilibrium_gap(v, **EQ), v, 0.0, **HDV)
    np.testing.assert_allclose(acc, 0.0, atol=1e-12)


def test_equilibrium_gap_infinite_at_and_above_desired_speed() -> None:
    s_e = equilibrium_gap(np.array([0.0, 33.3, 40.0]), **EQ)
    np.testing.assert_allclose(s_e[0], 2.0, rtol=1e-15)
    assert np.isposinf(s_e[1:]).all()


def test_desired_gap_clamp_gives_s0_exactly() -> None:
    # Leader much faster: v T + v dv / (2 sqrt(ab)) = 30 - 20*40/(2 sqrt 2) < 0 -> s* = s0.
    s_star = desired_gap(
        np.array([20.0, 0.0]), np.array([-40.0, -40.0]), T=1.5, a=1.0, b=2.0, s0=2.0
    )
    assert (s_star == 2.0).all()
    # Hence the IDM sees no interaction beyond (s0/s)^2.
    acc = idm_acceleration(100.0, 20.0, -40.0, **HDV)
    np.testing.assert_allclose(acc, 1.0 - (20.0 / 33.3) ** 4 - (2.0 / 100.0) ** 2, rtol=1e-14)


@pytest.mark.parametrize("v", [5.0, 20.0, 25.0, 30.0, 33.0])
def test_iidm_equilibrium_gap_is_s0_plus_v_times_t(v: float) -> None:
    acc = iidm_acceleration(2.0 + 1.5 * v, v, 0.0, **HDV)
    np.testing.assert_allclose(acc, 0.0, atol=1e-12)
    # Slightly larger gap accelerates, slightly smaller brakes.
    assert iidm_acceleration(2.0 + 1.5 * v + 0.5, v, 0.0, **HDV) > 0.0
    assert iidm_acceleration(2.0 + 1.5 * v - 0.5, v, 0.0, **HDV) < 0.0


def test_iidm_four_cases_by_hand() -> None:
    a, b, v0, delta = 1.0, 2.0, 33.3, 4.0
    # v <= v0, z < 1: s* = 32 at v = 20, s = 64 -> z = 0.5
    a_free = a * (1 - (20 / v0) ** delta)
    np.testing.assert_allclose(
        iidm_acceleration(64.0, 20.0, 0.0, **HDV),
        a_free * (1 - 0.5 ** (2 * a / a_free)),
        rtol=1e-13,
    )
    # v <= v0, z >= 1: s = 16 -> z = 2
    np.testing.assert_allclose(iidm_acceleration(16.0, 20.0, 0.0, **HDV), a * (1 - 4.0), rtol=1e-14)
    # v > v0: s* = 2 + 40*1.5 = 62 at v = 40
    a_free_over = -b * (1 - (v0 / 40.0) ** (a * delta / b))
    np.testing.assert_allclose(iidm_acceleration(124.0, 40.0, 0.0, **HDV), a_free_over, rtol=1e-14)
    np.testing.assert_allclose(
        iidm_acceleration(31.0, 40.0, 0.0, **HDV), a_free_over + a * (1 - 4.0), rtol=1e-14
    )
    np.testing.assert_allclose(iidm_acceleration(np.inf, 40.0, 0.0, **HDV), a_free_over, rtol=1e-14)


@pytest.mark.parametrize("model", MODELS)
def test_nonpositive_gap_is_guarded(model) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        acc = model(np.array([0.0, -3.0]), 10.0, 0.0, **HDV)
    assert np.isfinite(acc).all()
    np.testing.assert_allclose(acc[0], acc[1], rtol=1e-15)
    np.testing.assert_allclose(acc, model(1e-3, 10.0, 0.0, **HDV), rtol=1e-15)


@pytest.mark.parametrize("model", MODELS)
def test_scalar_and_array_calls_agree_with_broadcast_parameters(model) -> None:
    rng = np.random.default_rng(1)
    n = 50
    s = np.where(rng.random(n) < 0.2, np.inf, rng.uniform(0.5, 150.0, n))
    v = rng.uniform(0.0, 40.0, n)
    dv = rng.uniform(-10.0, 10.0, n)
    T = rng.uniform(1.0, 2.0, n)
    a = rng.uniform(0.7, 1.5, n)
    params = {"v0": 33.3, "b": 2.0, "s0": 2.0, "delta": 4.0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        batch = model(s, v, dv, T=T, a=a, **params)
    assert batch.shape == (n,)
    assert batch.dtype == np.float64
    assert np.isfinite(batch).all()
    single = np.array(
        [model(s[i], v[i], dv[i], T=T[i], a=a[i], **params) for i in range(n)], dtype=np.float64
    )
    np.testing.assert_allclose(batch, single, rtol=1e-14, atol=1e-15)
    # (n, 1) x (k,) broadcasting: one row per vehicle, one column per parameter value.
    grid = model(s[:, None], v[:, None], dv[:, None], T=np.array([1.0, 1.5, 2.0]), a=1.0, **params)
    assert grid.shape == (n, 3)


def test_equilibrium_gap_scalar_returns_0d_array() -> None:
    s_e = equilibrium_gap(20, v0=33.3, T=1.5, s0=2, delta=4)
    assert isinstance(s_e, np.ndarray)
    assert s_e.shape == ()
    assert s_e.dtype == np.float64


# --------------------------------------------------------------------------------------------
# properties
# --------------------------------------------------------------------------------------------

gaps = st.one_of(st.floats(0.01, 5e3), st.just(np.inf))
speeds = st.floats(0.0, 50.0)
rates = st.floats(-40.0, 40.0)
param_sets = st.fixed_dictionaries(
    {
        "v0": st.floats(10.0, 45.0),
        "T": st.floats(0.5, 2.5),
        "a": st.floats(0.3, 3.0),
        "b": st.floats(0.5, 4.0),
        "s0": st.floats(0.5, 5.0),
        "delta": st.sampled_from([2.0, 4.0, 6.0]),
    }
)


@pytest.mark.parametrize("model", MODELS)
@settings(max_examples=300, deadline=None)
@given(s=gaps, v=speeds, dv=rates, p=param_sets)
def test_acceleration_never_exceeds_a(model, s: float, v: float, dv: float, p: dict) -> None:
    acc = model(s, v, dv, **p)
    assert np.isfinite(acc)
    assert acc <= p["a"] * (1.0 + 1e-12)


@pytest.mark.parametrize("model", MODELS)
@settings(max_examples=300, deadline=None)
@given(s1=gaps, s2=gaps, v=speeds, dv=rates, p=param_sets)
def test_acceleration_non_decreasing_in_gap(
    model, s1: float, s2: float, v: float, dv: float, p: dict
) -> None:
    lo, hi = min(s1, s2), max(s1, s2)
    a_lo, a_hi = model(np.array([lo, hi]), v, dv, **p)
    assert a_lo <= a_hi + 1e-12 * max(1.0, abs(a_hi))


@pytest.mark.parametrize("model", MODELS)
@settings(max_examples=300, deadline=None)
@given(s=gaps, v=speeds, dv1=rates, dv2=rates, p=param_sets)
def test_acceleration_non_increasing_in_approach_rate(
    model, s: float, v: float, dv1: float, dv2: float, p: dict
) -> None:
    lo, hi = min(dv1, dv2), max(dv1, dv2)
    a_lo, a_hi = model(s, v, np.array([lo, hi]), **p)
    assert a_hi <= a_lo + 1e-12 * max(1.0, abs(a_lo))


# --------------------------------------------------------------------------------------------
# the power of the free-road term
# --------------------------------------------------------------------------------------------

_U = 2.0**-53  # unit roundoff of float64


@settings(max_examples=300, deadline=None)
@given(
    base=st.floats(min_value=1e-3, max_value=4.0, allow_nan=False),
    n=st.integers(min_value=1, max_value=16),
)
def test_power_of_a_whole_exponent_is_within_the_product_bound(base: float, n: int) -> None:
    """A whole exponent n is the product of n factors: relative error at most
    gamma_(n-1) = (n-1)u / (1 - (n-1)u) against the exact power (rational arithmetic)."""
    from fractions import Fraction

    from hcomc.equations.idm import power

    exact = Fraction(base) ** n
    error = abs(Fraction(power(base, float(n))) - exact) / exact
    bound = (n - 1) * _U / (1 - (n - 1) * _U)
    assert error <= Fraction(bound)


@given(
    base=st.floats(min_value=0.0, max_value=4.0, allow_nan=False),
    exponent=st.one_of(
        st.floats(min_value=0.01, max_value=20.0).filter(lambda e: e != int(e)),
        st.sampled_from([0.5, 16.5, 17.0, 20.0]),
    ),
)
def test_power_of_other_exponents_is_the_c_librarys(base: float, exponent: float) -> None:
    from hcomc.equations.idm import power

    assert power(base, exponent) == base**exponent  # Python's float power is libm's pow


@pytest.mark.parametrize("base", [0.0, 1.0, 0.5, 2.0])
def test_power_exact_cases(base: float) -> None:
    from hcomc.equations.idm import power

    for n in range(1, 17):
        assert power(base, float(n)) == base**n  # powers of two and 0, 1 are exact
