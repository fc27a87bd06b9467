"""Every Table I condition for 10 minutes without a merge controller: no NaN, no negative
speed, no collision of any kind, and every ramp vehicle merges or waits."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import ConfigError, load_config
from hcomc.road import Kind, Lane
from hcomc.sim.engine import simulate
from hcomc.sim.log import EventKind

CONDITIONS = ["C1", "C2", "C3", "C4", "C5"]


def _check_run(log, accel_lane_end: float) -> None:
    finite = log.active
    for name in ("x", "y", "v", "a", "heading"):
        values = getattr(log, name)[finite]
        assert np.isfinite(values).all(), name
    assert (log.v[finite] >= 0).all()
    ev = log.events
    collisions = ev[ev["kind"] == EventKind.COLLISION]
    assert collisions.size == 0, collisions
    # every ramp vehicle merges, or is still on the ramp: waiting at the end (logged) or not
    # yet there
    ramp = np.flatnonzero(((log.lane == Lane.RAMP) & log.active).any(axis=0))
    merged = set(ev["vehicle"][ev["kind"] == EventKind.MERGE].tolist())
    waited = set(ev["vehicle"][ev["kind"] == EventKind.RAMP_WAIT].tolist())
    for i in ramp.tolist():
        if i in merged:
            continue
        assert log.lane[-1, i] == Lane.RAMP
        assert log.active[-1, i]
        assert i in waited or log.x[-1, i] < accel_lane_end - 20.0 or log.v[-1, i] > 0.1


@pytest.mark.parametrize("name", CONDITIONS)
@pytest.mark.parametrize("ramp", ["single", "flow"])
def test_condition_ten_minutes(name, ramp):
    config = load_config(name, duration=600.0, demand={**_demand(name), "ramp": ramp})
    log = simulate(config, seed=7)
    assert log.n_recorded == 6001
    _check_run(log, config.road.accel_lane_end)
    merges = int((log.events["kind"] == EventKind.MERGE).sum())
    assert merges >= (1 if ramp == "single" else 10)


def _demand(name: str) -> dict:
    return load_config(name).demand.model_dump()


def test_same_seed_identical_logs_and_different_seed_differs():
    config = load_config("C4", duration=120.0, demand={**_demand("C4"), "ramp": "flow"})
    a, b, c = simulate(config, seed=11), simulate(config, seed=11), simulate(config, seed=12)
    for name in ("x", "y", "v", "a", "heading", "lane", "active", "kind"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for field in a.events.dtype.names:
        np.testing.assert_array_equal(a.events[field], b.events[field])
    assert a.x.shape != c.x.shape or not np.array_equal(a.x, c.x, equal_nan=True)


def test_demand_matches_condition_headways_and_penetration():
    """Generated arrivals reproduce the Table I mean headways and the CAV share."""
    from hcomc.rng import make_rng
    from hcomc.sim.demand import generate_demand

    config = load_config("C3", duration=20_000.0)
    demand = generate_demand(config, make_rng(5))
    arrivals = demand.x == 0.0
    for lane, mean in ((Lane.MAIN_1, 5.0), (Lane.MAIN_2, 3.0)):
        t = np.sort(demand.t[arrivals & (demand.lane == lane)])
        headways = np.diff(t)
        assert headways.min() >= config.demand.min_headway
        assert headways.mean() == pytest.approx(mean, rel=0.03)
    assert (demand.kind == Kind.CAV).mean() == pytest.approx(0.9, abs=0.01)


def test_a_platoon_that_does_not_fit_is_a_config_error():
    with pytest.raises(ConfigError, match=r"platoon\.followers' = 100000.*allowed: platoon"):
        simulate(load_config("platoon", platoon={"followers": 100_000}))


def test_a_log_over_the_memory_limit_is_refused_with_its_estimate():
    config = load_config("C1", duration=3600.0, log_memory_limit=0.01)
    expected = r"log_memory_limit' = 0.01 GiB: .* needs \d+\.\d\d GiB \(36001 rows"
    with pytest.raises(ConfigError, match=expected):
        simulate(config)
