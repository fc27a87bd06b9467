"""Mainline insertion at the lane's steady-state speed, and the deterministic paper scenario."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.equations.idm import equilibrium_gap
from hcomc.rng import make_rng
from hcomc.road import Kind, Lane
from hcomc.sim.demand import evenly_spread, generate_demand, lane_speed
from hcomc.sim.engine import Simulation


def _needed_spacing(config, v: float) -> float:
    """p (s_CAV + L) + (1 - p) (s_HDV + L), IDM equilibrium gaps, written out by hand."""
    p, length = config.demand.cav_penetration, config.road.vehicle_length

    def s(params) -> float:
        return (params.min_gap + v * params.time_headway) / np.sqrt(
            1.0 - (v / params.desired_speed) ** params.exponent
        )

    return p * (s(config.cav) + length) + (1.0 - p) * (s(config.hdv) + length)


@pytest.mark.parametrize(("condition", "headway"), [("C1", 5.0), ("C2", 7.0), ("C3", 3.0),
                                                    ("C5", 5.0)])  # fmt: skip
def test_equilibrium_speed_is_the_free_flow_steady_state(condition: str, headway: float) -> None:
    config = load_config(condition)
    v = lane_speed(config, headway)
    assert _needed_spacing(config, v) == pytest.approx(headway * v, rel=1e-9)
    v0 = min(config.cav.desired_speed, config.hdv.desired_speed)
    assert 0.9 * v0 < v < v0  # the free-flow root, not the congested one
    # just below v* the demand's spacing is larger than needed: the larger root
    assert _needed_spacing(config, v - 0.05) < headway * (v - 0.05)


def test_equilibrium_speed_mixes_kinds_by_share() -> None:
    pure_cav = load_config("C1", demand={"cav_penetration": 1.0})
    pure_hdv = load_config("C1", demand={"cav_penetration": 0.0})
    v_cav, v_hdv = lane_speed(pure_cav, 5.0), lane_speed(pure_hdv, 5.0)
    gap = float(equilibrium_gap(v_cav, v0=33.3, T=1.0, s0=2.0, delta=4.0))
    assert gap + 5.0 == pytest.approx(5.0 * v_cav, rel=1e-9)
    assert v_hdv < lane_speed(load_config("C1"), 5.0) < v_cav  # T_HDV = 1.5 s > T_CAV = 1 s


def test_fixed_and_iidm_speeds_and_over_capacity_headways() -> None:
    assert lane_speed(load_config("C1", demand={"main_speed": 30.0}), 5.0) == 30.0
    iidm = load_config("C1", cav={"variant": "iidm"}, hdv={"variant": "iidm"})
    assert lane_speed(iidm, 5.0) == pytest.approx(33.3)  # IIDM steady state at v0
    # 1.2 s is below every steady-state time headway of the C5 mix: no free-flow state,
    # so the capacity speed, where the steady-state headway spacing(v)/v is shortest
    config = load_config("C5")
    v_c = lane_speed(config, 1.2)
    headway = [_needed_spacing(config, v) / v for v in (v_c - 0.5, v_c, v_c + 0.5)]
    assert headway[1] > 1.2
    assert headway[1] < min(headway[0], headway[2])
    assert 10.0 < v_c < lane_speed(config, 5.0)
    assert lane_speed(config, 1.2) == lane_speed(config, 1.5)  # both over capacity


def test_demand_inserts_at_the_lane_speed() -> None:
    config = load_config("C2")
    demand = generate_demand(config, make_rng(0))
    for lane, headway in ((Lane.MAIN_1, 5.0), (Lane.MAIN_2, 7.0)):
        np.testing.assert_allclose(demand.v[demand.lane == lane], lane_speed(config, headway))
    assert (demand.v[demand.lane == Lane.RAMP] == config.demand.ramp_speed).all()


def test_undisturbed_traffic_barely_accelerates_at_the_equilibrium_speed() -> None:
    """Without the merge, mainline vehicles inserted at v* accelerate less on average than
    vehicles inserted at the old fixed 30 m/s (a mean |a| reduction of over a third)."""

    def mean_abs_a(main_speed: object) -> float:
        config = load_config("C1", demand={"main_speed": main_speed})
        log = Simulation(config, 0, counterfactual=True).run()
        return float(np.nanmean(np.abs(np.where(log.active, log.a, np.nan))))

    assert mean_abs_a("equilibrium") < 0.6 * mean_abs_a(30.0)


def test_evenly_spread_pattern_has_the_exact_share() -> None:
    assert "".join(str(int(k)) for k in evenly_spread(10, 0.3)) == "0100100010"
    assert "".join(str(int(k)) for k in evenly_spread(5, 0.6)) == "10101"
    for share in (0.0, 0.3, 0.6, 0.9, 1.0):
        kinds = evenly_spread(100, share)
        assert (kinds == Kind.CAV).sum() == round(100 * share)
    assert evenly_spread(1, 0.9)[0] == Kind.CAV  # a lone vehicle takes the likelier kind
    assert evenly_spread(1, 0.3)[0] == Kind.HDV


def test_uniform_pattern_is_deterministic_with_exact_headways() -> None:
    config = load_config("C2", demand={"pattern": "uniform"})
    a = generate_demand(config, make_rng(1))
    b = generate_demand(config, make_rng(2))
    for name in ("t", "x", "v", "lane", "kind"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for lane, mean in ((Lane.MAIN_1, 5.0), (Lane.MAIN_2, 7.0)):
        arrivals = np.sort(a.t[(a.lane == lane) & (a.x == 0.0)])
        np.testing.assert_allclose(np.diff(arrivals), mean, atol=1e-9)
        fill = np.sort(a.x[(a.lane == lane) & (a.t == -config.warmup) & (a.x > 0)])
        np.testing.assert_allclose(np.diff(fill), mean * lane_speed(config, mean), rtol=1e-9)
        kinds = a.kind[a.lane == lane]
        assert abs((kinds == Kind.CAV).sum() - 0.9 * kinds.size) < 1.0
    assert a.kind[a.lane == Lane.RAMP].tolist() == [Kind.CAV]
