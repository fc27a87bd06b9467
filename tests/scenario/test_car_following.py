"""Closed-loop car-following behaviour in the scripted-leader platoon (HighwayEnv style)."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import RoadParams
from hcomc.equations.idm import equilibrium_gap
from hcomc.sim.engine import simulate
from hcomc.sim.log import EventKind

LONG_ROAD = RoadParams(
    length=50_000.0, accel_lane_start=40_000.0, accel_lane_end=40_500.0, ramp_start=39_000.0
)
STEP = [[0.0, 25.0], [10.0, 25.0], [10.1, 20.0], [100.0, 20.0]]


def _onset(log, vehicle: int) -> float:
    """Start time of the first step in which ``vehicle`` accelerates (|a| > 1e-9)."""
    rows = np.flatnonzero(np.abs(log.a[:, vehicle]) > 1e-9)
    return float(log.t[rows[0]] - log.dt)


@pytest.mark.parametrize("tau", [0.0, 0.3, 0.6, 1.2])
def test_hdv_step_response_lags_by_reaction_time(platoon_config, tau):
    """The follower's first reaction starts exactly tau after the leader's speed changed."""
    delays = dict.fromkeys(
        ("reaction_time_gap", "reaction_time_speed", "reaction_time_approach"), tau
    )
    log = simulate(platoon_config(STEP, hdv=delays), seed=1)
    stimulus = float(log.t[np.flatnonzero(log.v[:, 0] < 25.0)[0]])  # leader speed changed
    assert stimulus == pytest.approx(10.1)
    assert _onset(log, 1) - stimulus == pytest.approx(tau, abs=1e-9)


def test_cav_reacts_in_the_next_step(platoon_config):
    log = simulate(platoon_config(STEP, kind="cav"), seed=1)
    stimulus = float(log.t[np.flatnonzero(log.v[:, 0] < 25.0)[0]])
    assert _onset(log, 1) - stimulus == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("kind", ["hdv", "cav"])
def test_stop_behind_stopped_leader_at_jam_distance(platoon_config, kind):
    """A platoon behind a leader braking to standstill stops about s0 = 2 m behind it.

    The IDM approaches s0 only as v -> 0; braking ends within one ballistic step, so each
    follower stops up to ~0.2 m short of s0 (HighwayEnv's analogous test allows 1 m).
    """
    log = simulate(
        platoon_config(
            [[0.0, 20.0], [10.0, 20.0], [20.0, 0.0]], kind=kind, followers=5, duration=120.0
        ),
        seed=3,
    )
    gaps = log.x[-1, :-1] - log.length[:-1] - log.x[-1, 1:]
    np.testing.assert_allclose(gaps, 1.9, atol=0.1)
    np.testing.assert_allclose(log.v[-1], 0.0, atol=1e-3)
    assert (log.v >= 0).all()
    assert not (log.events["kind"] == EventKind.COLLISION).any()


@pytest.mark.parametrize("kind", ["hdv", "cav"])
def test_steady_platoon_keeps_equilibrium_gap(platoon_config, kind):
    """Started at the IDM equilibrium, a constant-speed platoon stays there (Eq. 1 fixed point)."""
    log = simulate(platoon_config([[0.0, 25.0], [100.0, 25.0]], kind=kind, followers=4), seed=0)
    cfg = platoon_config([[0.0, 25.0]], kind=kind)
    p = cfg.hdv if kind == "hdv" else cfg.cav
    s_e = equilibrium_gap(
        25.0, v0=p.desired_speed, T=p.time_headway, s0=p.min_gap, delta=p.exponent
    )
    gaps = log.x[:, :-1] - log.length[:-1] - log.x[:, 1:]
    np.testing.assert_allclose(gaps, s_e, atol=2e-3)  # float32 log at x ~ 4 km
    np.testing.assert_allclose(log.a[1:], 0.0, atol=1e-9)


@pytest.mark.parametrize("kind", ["hdv", "cav"])
def test_free_road_converges_to_desired_speed(platoon_config, kind):
    """A leader driving away at 60 m/s leaves the follower on a free road: v -> v0."""
    log = simulate(
        platoon_config(
            [[0.0, 20.0], [5.0, 60.0]], kind=kind, duration=200.0, initial_speed=20.0
        ).model_copy(update={"road": LONG_ROAD}),
        seed=0,
    )
    assert log.v[-1, 1] == pytest.approx(33.3, abs=0.05)
