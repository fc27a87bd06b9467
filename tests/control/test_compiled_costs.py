"""The compiled cost kernels equal the array forms of the same equations, bit for bit.

U_fuel's per-candidate work (:meth:`MergeProblem._fuel_to_distance`) and the lane-change
game's SV simulation (:func:`simulate_sv`) run as numba loops over the scalar model kernels.
The oracles here are the array forms of the same equations (``fuel_rate``,
``idm_acceleration``, ``transition_weight``, ``blend_acceleration``), summing over time in
time order as the kernels do.
"""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import IDMParams, load_config
from hcomc.config.fuel import FUEL_DEFAULT
from hcomc.control.hierarchical.controller import HCOMCController
from hcomc.control.hierarchical.problem_terms import AHEAD, BEHIND
from hcomc.control.lane_change_game.params import GAME_DEFAULT, GameParams
from hcomc.control.lane_change_game.players import GameVehicle, leader_track, simulate_sv
from hcomc.control.prediction.fuel import FuelCoefficients, _fuel_to_distance_kernel
from hcomc.control.prediction.population import VMC, VR
from hcomc.equations.fuel import fuel_rate
from hcomc.equations.idm import idm_acceleration
from hcomc.equations.iidm import iidm_acceleration
from hcomc.equations.transition import blend_acceleration, transition_weight
from hcomc.sim.engine import Simulation


# ---------------------------------------------------------------------------- U_fuel
def _fuel_oracle(cf, roles, X, V, A, dt):
    """The array form: one ``fuel_rate`` call on all samples, summed over time in time order
    (from 0, one sample at a time)."""
    n, (C, K1, _) = len(roles), X.shape
    v, a = np.empty((n, C, K1)), np.empty((n, C, K1))
    for i, r in enumerate(roles):
        v[i, :, :-1], a[i, :, :-1] = V[:, 1:, r], A[:, 1:, r]
        v[i, :, -1], a[i, :, -1] = np.maximum(V[:, -1, r], 1.0), 0.0
    rate = fuel_rate(v, a)
    burnt = np.zeros(rate.shape[:-1])
    for k in range(K1 - 1):
        burnt = burnt + rate[..., k]
    burnt = burnt * dt
    r_ = list(roles)
    rest = (cf[0, -1, r_] - cf[0, 0, r_])[:, None] - (X[:, -1, r_] - X[:, 0, r_]).T
    return burnt + rate[..., -1] * rest / v[..., -1]


@pytest.mark.parametrize("K", [1, 5, 8, 64, 127, 128, 129, 200, 700])
def test_fuel_kernel_equals_array_form(K):
    """Random trajectories with braking, stops (v = 0) and speeds under 1 m/s at the end."""
    rng = np.random.default_rng(K)
    C = 17
    X = np.cumsum(rng.uniform(0.0, 8.0, (C, K + 1, 6)), axis=1)
    V = rng.uniform(0.0, 35.0, (C, K + 1, 6))
    V[::3, -1, :] = rng.uniform(0.0, 1.0, V[::3, -1, :].shape)
    V[1::4, 1 : K // 2 + 1, :] = 0.0
    A = rng.uniform(-6.0, 3.0, (C, K + 1, 6))
    cf = np.cumsum(rng.uniform(0.0, 8.0, (3, K + 1, 6)), axis=1)
    dt = 0.25
    for roles in ((VR,), (VR, VMC), (VMC,)):
        got = _fuel_to_distance_kernel(
            cf, np.array(roles), X, V, A, dt, FuelCoefficients.of(FUEL_DEFAULT)
        )
        np.testing.assert_array_equal(got, _fuel_oracle(cf, roles, X, V, A, dt))


def test_problem_fuel_objective_equals_array_form():
    """On a recorded-style problem (C1, seed 0): U_fuel of every candidate, from the
    predicted trajectories with the array form, equals the objective bit for bit."""
    config = load_config("C1", control={"controller": "hcomc"})
    sim = Simulation(config, 0)
    assert sim.run_until_plan() is not None
    view, group = sim.requests[0]
    problem = HCOMCController(config).problem(view, group)[0]
    rng = np.random.default_rng(5)
    xl, xu = np.asarray(problem.xl), np.asarray(problem.xu)
    cand = xl + rng.random((120, xl.size)) * (xu - xl)
    pred = problem.predict(cand)
    assert set(pred.sequence) == {AHEAD, BEHIND}  # both key groups scored
    for which in (AHEAD, BEHIND):
        rows = np.flatnonzero(pred.sequence == which)
        state, cf = problem.states[which], problem._no_merge[which]
        assert state is not None
        assert cf is not None
        assert bool(state.present[VMC])
        own = _fuel_oracle(cf, (VR, VMC), pred.X[rows], pred.V[rows], pred.A[rows], problem.dt)
        base = _fuel_oracle(cf, (VMC,), *cf[:, None], problem.dt)[0, 0]
        expected = (own[0] + own[1] - base) / 1000.0
        np.testing.assert_array_equal(pred.F[rows, 1], expected)


# ---------------------------------------------------------------------------- the game's SV
def _simulate_sv_oracle(sv, old, new, idm: IDMParams, params: GameParams):
    """The array-form loop over time steps, both actions as a (2,) vector."""
    n, dt = params.n_steps, params.dt
    t_start = dt * np.arange(n, dtype=np.float64)
    old_rear, old_v = leader_track(old, t_start)
    new_rear, new_v = leader_track(new, t_start)
    psi = transition_weight(t_start, params.horizon, params.transition_tolerance)
    weights = np.stack([psi, np.zeros(n)])
    law = iidm_acceleration if idm.variant == "iidm" else idm_acceleration

    def accel(s, v, dv):
        return law(s, v, dv, v0=sv.desired_speed, T=idm.time_headway, a=idm.max_accel,
                   b=idm.comfort_decel, s0=idm.min_gap, delta=idm.exponent)  # fmt: skip

    x, v = np.full(2, float(sv.x)), np.full(2, float(sv.v))
    xs, vs, acc = np.empty((2, n)), np.empty((2, n)), np.empty((2, n))
    for k in range(n):
        a_ori = accel(old_rear[k] - x, v, v - old_v[k])
        a_new = accel(new_rear[k] - x, v, v - new_v[k])
        a = np.maximum(blend_acceleration(a_ori, a_new, weights[:, k]), -params.emergency_decel)
        v_next = v + a * dt
        stops = v_next < 0.0
        dx = np.where(stops, v * v / (2.0 * np.where(stops, -a, 1.0)), v * dt + 0.5 * a * dt * dt)
        v_next = np.maximum(v_next, 0.0)
        acc[:, k] = (v_next - v) / dt
        x, v = x + dx, v_next
        xs[:, k], vs[:, k] = x, v
    return xs, vs, acc


def _vehicle(rng, x: float) -> GameVehicle:
    return GameVehicle(x=x, v=float(rng.uniform(0.0, 35.0)), length=float(rng.uniform(4.0, 12.0)),
                       desired_speed=float(rng.uniform(20.0, 35.0)), is_cav=False)  # fmt: skip


@pytest.mark.parametrize("variant", ["idm", "iidm"])
def test_simulate_sv_equals_array_form(variant):
    """Random scenes, leaders absent or present (also overlapping SV), both IDM variants."""
    rng = np.random.default_rng(11 if variant == "idm" else 12)
    for case in range(150):
        idm = IDMParams(variant=variant, desired_speed=30.0,
                        time_headway=float(rng.uniform(0.8, 2.0)),
                        max_accel=float(rng.uniform(0.5, 2.5)),
                        comfort_decel=float(rng.uniform(1.0, 3.0)),
                        min_gap=float(rng.uniform(1.0, 3.0)),
                        exponent=float(rng.choice([2.0, 4.0])))  # fmt: skip
        sv = GameVehicle(x=0.0, v=float(rng.uniform(0.0, 35.0)), length=5.0,
                         desired_speed=float(rng.uniform(20.0, 35.0)), is_cav=True)  # fmt: skip
        old = None if case % 5 == 0 else _vehicle(rng, float(rng.uniform(-2.0, 60.0)))
        new = None if case % 3 == 0 else _vehicle(rng, float(rng.uniform(-2.0, 60.0)))
        got = simulate_sv(sv, old, new, idm, GAME_DEFAULT)
        for g, e in zip(got, _simulate_sv_oracle(sv, old, new, idm, GAME_DEFAULT), strict=True):
            np.testing.assert_array_equal(g, e)


def test_simulate_sv_stops_behind_a_standing_leader():
    """A slow SV 0.5 m behind a standing leader brakes at the emergency deceleration and stops
    within the first step (the ballistic stop), then stays: the same trajectory as the array
    form, speeds 0 from then on, never negative."""
    idm = IDMParams()
    sv = GameVehicle(x=0.0, v=1.0, length=5.0, desired_speed=30.0, is_cav=True)
    leader = GameVehicle(x=5.5, v=0.0, length=5.0, desired_speed=30.0, is_cav=False)
    xs, vs, acc = simulate_sv(sv, leader, leader, idm, GAME_DEFAULT)
    for g, e in zip((xs, vs, acc), _simulate_sv_oracle(sv, leader, leader, idm, GAME_DEFAULT),
                    strict=True):  # fmt: skip
        np.testing.assert_array_equal(g, e)
    assert GAME_DEFAULT.emergency_decel * GAME_DEFAULT.dt > sv.v  # v < 0 after one step
    for row in range(2):
        np.testing.assert_array_equal(vs[row], 0.0)
        np.testing.assert_array_equal(xs[row], sv.v**2 / (2.0 * GAME_DEFAULT.emergency_decel))
        assert acc[row, 0] == -sv.v / GAME_DEFAULT.dt
        np.testing.assert_array_equal(acc[row, 1:], 0.0)
