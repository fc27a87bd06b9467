"""HDV perception (hcomc.sim.perception): reaction-delay ring buffer and OU estimation errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import HDVParams
from hcomc.rng import make_rng
from hcomc.sim.perception_state import Perception

LENGTH = 5.0


def _params(tau_s: float, tau_v: float, tau_dv: float, **kw) -> HDVParams:
    return HDVParams(
        reaction_time_gap=tau_s,
        reaction_time_speed=tau_v,
        reaction_time_approach=tau_dv,
        **{"estimation_errors": False, **kw},
    )


def _history(perception: Perception, xs: np.ndarray, vs: np.ndarray, start: int = 0) -> None:
    """Release every vehicle at step ``start`` with state 0 and push the following rows."""
    n = xs.shape[1]
    perception.fill(np.arange(n), xs[0], vs[0])
    for k in range(1, xs.shape[0]):
        perception.push(start + k, xs[k], vs[k])


def _at(z: np.ndarray, k: int) -> np.ndarray:
    """State ``k`` steps after the release; before the release the release state."""
    return z[max(k, 0)]


def _delayed(z: np.ndarray, n: int, j: int, r: float) -> np.ndarray:
    """HDM delay interpolation: z(t - (j + r) dt) = (1 - r) z[n - j] + r z[n - j - 1]."""
    return (1.0 - r) * _at(z, n - j) + r * _at(z, n - j - 1)


_lag = st.tuples(st.integers(0, 5), st.sampled_from([0.0, 0.25, 0.5, 0.75]))


@settings(max_examples=100, deadline=None)
@given(
    dt=st.sampled_from([0.05, 0.1, 0.2, 0.5]),
    lags=st.tuples(_lag, _lag, _lag),
    steps=st.integers(0, 25),
    start=st.integers(0, 50),
    seed=st.integers(0, 2**32 - 1),
)
def test_delayed_gap_and_speeds_interpolate_the_history(dt, lags, steps, start, seed):
    """Gap, speed and approach rate come from the delayed states, each with its own delay."""
    (js, rs), (jv, rv), (jd, rd) = lags
    params = _params((js + rs) * dt, (jv + rv) * dt, (jd + rd) * dt)
    rng = np.random.default_rng(seed)
    n = 4
    perception = Perception(params, np.ones(n, dtype=bool), dt, rng)
    xs = np.cumsum(rng.uniform(0.0, 3.0, (steps + 1, n)), axis=0) + np.array([0, 40, 90, 150])
    vs = rng.uniform(0.0, 30.0, (steps + 1, n))
    _history(perception, xs, vs, start)
    ids = np.array([0, 1, 2, 3])
    leader = np.array([1, 2, 3, -1])
    s, v, vl = perception.perceive(start + steps, ids, leader, np.full(n, LENGTH))

    xd = _delayed(xs, steps, js, rs)
    vv = _delayed(vs, steps, jv, rv)
    vd = _delayed(vs, steps, jd, rd)
    np.testing.assert_allclose(s[:3], xd[1:] - LENGTH - xd[:3], rtol=0, atol=1e-9)
    assert s[3] == np.inf
    np.testing.assert_allclose(v, vv, rtol=0, atol=1e-9)
    # v_leader = v - dv with dv = v_i(t - tau_dv) - v_l(t - tau_dv)
    np.testing.assert_allclose(vl[:3], vv[:3] - (vd[:3] - vd[1:]), rtol=0, atol=1e-9)
    assert vl[3] == pytest.approx(vv[3], abs=1e-12)


@pytest.mark.parametrize("tau", [0.1, 0.3, 0.6, 1.2])
def test_multiple_of_dt_returns_the_exact_state_tau_ago(tau):
    dt = 0.1
    j = round(tau / dt)
    perception = Perception(_params(tau, tau, tau), np.ones(2, dtype=bool), dt, make_rng(0))
    steps = 30
    k = np.arange(steps + 1, dtype=np.float64)[:, None]
    xs = np.hstack([20.0 * k * dt, 50.0 + 25.0 * k * dt])  # constant speeds 20 and 25 m/s
    vs = np.hstack([20.0 + 0.0 * k, 25.0 + 0.1 * k])
    _history(perception, xs, vs)
    s, v, vl = perception.perceive(steps, np.array([0]), np.array([1]), np.array([LENGTH]))
    assert s[0] == pytest.approx(xs[steps - j, 1] - LENGTH - xs[steps - j, 0], abs=1e-9)
    assert v[0] == pytest.approx(20.0, abs=1e-12)
    assert vl[0] == pytest.approx(vs[steps - j, 1], abs=1e-9)


def test_non_multiple_of_dt_interpolates_linearly():
    """tau = 0.25 s, dt = 0.1 s: j = 2, r = 0.5, so the midpoint of z[n-2] and z[n-3]."""
    dt = 0.1
    perception = Perception(_params(0.25, 0.25, 0.25), np.ones(2, dtype=bool), dt, make_rng(0))
    xs = np.array([[0.0, 30.0], [1.0, 31.0], [3.0, 34.0], [6.0, 38.0], [10.0, 43.0], [15.0, 49]])
    vs = np.array([[10.0, 11.0], [11.0, 12.0], [12.0, 14.0], [13.0, 16.0], [14.0, 18.0], [15, 20]])
    _history(perception, xs, vs)
    s, v, vl = perception.perceive(5, np.array([0]), np.array([1]), np.array([LENGTH]))
    # x_0: (3 + 6) / 2 = 4.5, x_1: (34 + 38) / 2 = 36; v_0: 12.5; v_1: 15
    assert s[0] == pytest.approx(36.0 - LENGTH - 4.5, abs=1e-9)
    assert v[0] == pytest.approx(12.5, abs=1e-9)
    assert vl[0] == pytest.approx(15.0, abs=1e-9)


def test_fill_makes_a_new_vehicle_perceive_its_release_state():
    """Before tau of history exists, the delayed state is the release (= current) state."""
    dt = 0.1
    perception = Perception(_params(0.6, 0.6, 0.6), np.ones(3, dtype=bool), dt, make_rng(0))
    # vehicles 0 and 1 have driven for a while; the buffer holds garbage for vehicle 2
    for k in range(1, 20):
        perception.push(k, np.array([10.0 * k, 10.0 * k + 30.0, -999.0]), np.full(3, 7.0))
    x = np.array([200.0, 230.0, 150.0])
    v = np.array([20.0, 20.0, 22.0])
    perception.fill(np.array([2]), x, v)  # vehicle 2 released at step 19
    s, sv, vl = perception.perceive(19, np.array([2]), np.array([0]), np.array([LENGTH]))
    # own state: the release state (no garbage); leader 0: its real state 6 steps ago
    assert sv[0] == pytest.approx(22.0, abs=1e-12)
    assert s[0] == pytest.approx(130.0 - LENGTH - 150.0, abs=1e-9)
    assert vl[0] == pytest.approx(7.0, abs=1e-12)
    # two steps later the own delayed position is still the release position
    for k in (20, 21):
        perception.push(k, np.array([0.0, 0.0, 150.0 + 2.2 * (k - 19)]), np.full(3, 9.0))
    s, sv, _ = perception.perceive(21, np.array([2]), np.array([1]), np.array([LENGTH]))
    assert sv[0] == pytest.approx(22.0, abs=1e-12)
    assert s[0] == pytest.approx(180.0 - LENGTH - 150.0, abs=1e-9)  # leader 1 at step 15


def test_zero_delay_uses_current_state():
    perception = Perception(_params(0.0, 0.0, 0.0), np.ones(2, dtype=bool), 0.1, make_rng(0))
    _history(perception, np.array([[0.0, 20.0], [1.0, 22.5]]), np.array([[10.0, 5.0], [9, 4]]))
    s, v, vl = perception.perceive(1, np.array([0]), np.array([1]), np.array([LENGTH]))
    assert s[0] == pytest.approx(22.5 - LENGTH - 1.0, abs=1e-12)
    assert v[0] == pytest.approx(9.0, abs=1e-12)
    assert vl[0] == pytest.approx(4.0, abs=1e-12)


@pytest.mark.parametrize("errors", [False, True])
def test_no_leader_gives_infinite_gap_and_own_speed(errors):
    params = _params(0.6, 0.3, 0.45, estimation_errors=errors)
    perception = Perception(params, np.ones(3, dtype=bool), 0.1, make_rng(1))
    xs = np.cumsum(np.full((12, 3), 2.0), axis=0)
    vs = np.linspace(10.0, 21.0, 36).reshape(12, 3)
    _history(perception, xs, vs)
    s, v, vl = perception.perceive(11, np.array([0, 1, 2]), np.full(3, -1), np.full(3, LENGTH))
    assert np.isinf(s).all()
    assert (s > 0).all()
    np.testing.assert_allclose(v, _delayed(vs, 11, 3, 0.0), rtol=0, atol=1e-9)
    np.testing.assert_array_equal(vl, v)


# ----------------------------------------------------------------- estimation errors
def test_errors_off_leave_processes_at_zero():
    perception = Perception(_params(0.6, 0.6, 0.6), np.ones(5, dtype=bool), 0.1, make_rng(0))
    assert not perception.errors
    perception.advance_errors(np.arange(5), make_rng(1))
    np.testing.assert_array_equal(perception.w_gap, 0.0)
    np.testing.assert_array_equal(perception.w_ttc, 0.0)
    zero_sizes = _params(0.6, 0.6, 0.6, estimation_errors=True, gap_error=0, inverse_ttc_error=0)
    assert not Perception(zero_sizes, np.ones(5, dtype=bool), 0.1, make_rng(0)).errors


def test_gap_and_inverse_ttc_errors_are_applied_exactly():
    """s_est = s exp(V_s w_s) and dv_est = dv + s sigma_r w_l, given w."""
    params = _params(0.0, 0.0, 0.0, estimation_errors=True, gap_error=0.05, inverse_ttc_error=0.01)
    n = 4
    perception = Perception(params, np.ones(n, dtype=bool), 0.1, make_rng(0))
    x = np.array([0.0, 40.0, 100.0, 130.0])
    v = np.array([25.0, 20.0, 30.0, 10.0])
    _history(perception, x[None, :], v[None, :])
    perception.w_gap[:] = [1.5, -2.0, 0.0, 0.7]
    perception.w_ttc[:] = [-0.5, 3.0, 1.0, 0.0]
    ids = np.array([0, 1, 2])
    s, sv, vl = perception.perceive(0, ids, np.array([1, 2, 3]), np.full(3, LENGTH))
    s_true = x[1:] - LENGTH - x[:3]
    np.testing.assert_allclose(s, s_true * np.exp(0.05 * perception.w_gap[ids]), rtol=1e-14)
    dv_est = (v[:3] - v[1:]) + s_true * 0.01 * perception.w_ttc[ids]
    np.testing.assert_allclose(sv, v[:3], rtol=1e-14)
    np.testing.assert_allclose(vl, v[:3] - dv_est, rtol=1e-14, atol=1e-12)


def test_ou_step_is_the_models_update():
    """w <- exp(-dt/tau~) w + sqrt(2 dt/tau~) xi with xi drawn as (2, N) for all N vehicles."""
    dt, corr = 0.1, 20.0
    params = _params(0.6, 0.6, 0.6, estimation_errors=True, error_correlation_time=corr)
    perception = Perception(params, np.ones(6, dtype=bool), dt, make_rng(3))
    w_gap, w_ttc = perception.w_gap.copy(), perception.w_ttc.copy()
    ids = np.array([1, 2, 4])
    perception.advance_errors(ids, np.random.default_rng(99))
    xi = np.random.default_rng(99).standard_normal((2, 6))[:, ids]
    decay, kick = np.exp(-dt / corr), np.sqrt(2.0 * dt / corr)
    np.testing.assert_allclose(perception.w_gap[ids], decay * w_gap[ids] + kick * xi[0], rtol=1e-14)
    np.testing.assert_allclose(perception.w_ttc[ids], decay * w_ttc[ids] + kick * xi[1], rtol=1e-14)
    others = np.array([0, 3, 5])  # inactive vehicles keep their errors
    np.testing.assert_array_equal(perception.w_gap[others], w_gap[others])
    np.testing.assert_array_equal(perception.w_ttc[others], w_ttc[others])


@pytest.mark.parametrize("corr", [2.0, 20.0])
def test_ou_processes_are_stationary_with_unit_variance(corr):
    """Long run from w = 0: variance -> 2(dt/tau~) / (1 - exp(-2 dt/tau~)) ~ 1, lag-1
    autocorrelation exp(-dt/tau~), the two processes uncorrelated."""
    dt, n = 0.1, 10_000
    params = _params(0.6, 0.6, 0.6, estimation_errors=True, error_correlation_time=corr)
    perception = Perception(params, np.ones(n, dtype=bool), dt, make_rng(11))
    perception.w_gap[:] = 0.0
    perception.w_ttc[:] = 0.0
    rng = make_rng(12)
    ids = np.arange(n)
    burn_in = round(5.0 * corr / dt)  # residual of the start: exp(-10) of the variance
    for _ in range(burn_in):
        perception.advance_errors(ids, rng)
    rows = 200
    gap = np.empty((rows, n))
    ttc = np.empty((rows, n))
    for k in range(rows):
        perception.advance_errors(ids, rng)
        gap[k], ttc[k] = perception.w_gap, perception.w_ttc
    exact_var = (2.0 * dt / corr) / (1.0 - np.exp(-2.0 * dt / corr))
    for w in (gap, ttc):
        var = float(np.mean(w * w))
        assert var == pytest.approx(1.0, rel=0.1)
        assert var == pytest.approx(exact_var, rel=0.04)
        assert float(np.mean(w)) == pytest.approx(0.0, abs=0.1)
        lag1 = float(np.sum(w[1:] * w[:-1]) / np.sum(w[:-1] * w[:-1]))
        assert lag1 == pytest.approx(np.exp(-dt / corr), abs=0.002)
    cross = float(np.mean(gap * ttc) / np.sqrt(np.mean(gap**2) * np.mean(ttc**2)))
    assert cross == pytest.approx(0.0, abs=0.02)


def test_initial_errors_are_standard_normal():
    params = _params(0.6, 0.6, 0.6, estimation_errors=True)
    perception = Perception(params, np.ones(20_000, dtype=bool), 0.1, make_rng(5))
    for w in (perception.w_gap, perception.w_ttc):
        assert float(np.mean(w)) == pytest.approx(0.0, abs=0.03)
        assert float(np.var(w)) == pytest.approx(1.0, rel=0.05)


def test_same_seed_same_errors_different_seed_differs():
    params = _params(0.6, 0.6, 0.6, estimation_errors=True)

    def run(seed: int) -> tuple[np.ndarray, np.ndarray]:
        rng = make_rng(seed)
        perception = Perception(params, np.ones(50, dtype=bool), 0.1, rng)
        for _ in range(30):
            perception.advance_errors(np.arange(0, 50, 2), rng)
        return perception.w_gap.copy(), perception.w_ttc.copy()

    a, b, c = run(4), run(4), run(5)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.allclose(a[0], c[0])
    assert not np.allclose(a[1], c[1])


def test_error_paths_do_not_depend_on_which_vehicles_are_active():
    """Vehicle 0's error path is the same whether vehicle 1 is active, inactive or absent
    from the active set on some steps; the stream advances by 2N normals every step."""
    params = _params(0.6, 0.6, 0.6, estimation_errors=True)

    def run(active_sets: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        rng = make_rng(11)
        perception = Perception(params, np.ones(3, dtype=bool), 0.1, rng)
        for ids in active_sets:
            perception.advance_errors(ids, rng)
        return perception.w_gap.copy(), rng.standard_normal()

    both = [np.array([0, 1, 2])] * 30
    alone = [np.array([0, 2])] * 30
    mixed = [np.array([0, 2])] * 10 + [np.array([0, 1, 2])] * 10 + [np.array([0, 2])] * 10
    (w_both, next_both), (w_alone, next_alone) = run(both), run(alone)
    w_mixed, next_mixed = run(mixed)
    np.testing.assert_array_equal(w_both[[0, 2]], w_alone[[0, 2]])
    np.testing.assert_array_equal(w_both[[0, 2]], w_mixed[[0, 2]])
    assert w_both[1] != w_alone[1]  # vehicle 1 only moves while it is active
    assert next_both == next_alone == next_mixed  # the stream position is the same
    empty = run([np.array([], dtype=int)] * 30)
    assert empty[1] == next_both  # a step with no active HDV still consumes its draws
