"""hcomc/CorridorMerge-v0 and the corridor's PettingZoo environment: agents drive ramp CAVs
of a corridor on the engine. API checks, the engine's run up to the episode against
simulate_corridor, the commanded acceleration against the ballistic closed form, the
episode's outcomes, the observation's key vehicles against the engine's merge events, the
safety term against an independent Eq. 15 computation, determinism, and the errors."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import hcomc.envs  # noqa: F401 (registers hcomc/CorridorMerge-v0)
from hcomc.config import ConfigError
from hcomc.corridor.layout import ramp_codes
from hcomc.envs.corridor.env import CorridorMergeEnv
from hcomc.envs.corridor.multi_agent import CorridorParallelEnv
from hcomc.envs.observation import N_EGO, N_ROLE
from hcomc.equations.safety import critical_acceleration
from hcomc.metrics.corridor import simulate_corridor
from hcomc.sim.lane_table import KIND_ON, L_END, L_KIND
from hcomc.sim.log import EventKind

FAST: dict[str, Any] = {"start_after": 60.0, "max_episode_time": 30.0}
"""Episodes early in the corridor preset's hour: a short run to the agent's entry."""


def make(**kw: object) -> CorridorMergeEnv:
    return CorridorMergeEnv("corridor", **{**FAST, **kw})


def run(env: CorridorMergeEnv, seed: int, policy) -> list[tuple]:
    obs, _ = env.reset(seed=seed)
    out, done = [], False
    while not done:
        obs, r, term, trunc, info = env.step(policy(obs))
        out.append((obs, r, term, trunc, info))
        done = term or trunc
    return out


def merge_when_clear(obs: np.ndarray) -> np.ndarray:
    """Keep speed; change lane once on the acceleration lane (lane-end distance < 250 m)."""
    return np.array([0.0, 1.0 if obs[2] < 240.0 else -1.0], dtype=np.float32)


def test_gymnasium_env_checker_passes() -> None:
    check_env(gym.make("hcomc/CorridorMerge-v0", **FAST).unwrapped, skip_render_check=True)


def test_the_run_before_the_episode_is_the_corridor_engines_own() -> None:
    """Until the ego enters its control zone nothing is commanded: every vehicle's position
    and speed equal those of ``simulate_corridor`` with the same seed at that time."""
    env = make(ramp="on2", overrides={"corridor.duration": 240.0})  # the same fleet in both
    env.reset(seed=3)
    e = env.episode
    assert e is not None
    t0 = e.t
    ref = simulate_corridor(env.corridor, seed=3, trajectory_interval=0.1)
    assert ref.trajectories is not None
    at = ref.trajectories[np.isclose(ref.trajectories["t"], t0)].set_index("id")
    sim = e.run.sim
    on_road = np.flatnonzero(sim.active)
    assert set(on_road.tolist()) <= set(at.index)
    assert len(on_road) > 100
    as_logged = sim.x[on_road].astype(np.float32), sim.v[on_road].astype(np.float32)
    np.testing.assert_array_equal(at.loc[on_road, "x"].to_numpy(), as_logged[0])
    np.testing.assert_array_equal(at.loc[on_road, "v"].to_numpy(), as_logged[1])
    assert e.ego in sim.key_groups  # it entered its control zone in the last step
    entered = {g["VR"]: g["t"] for g in sim.log.meta["key_groups"]}
    assert entered[e.ego] == pytest.approx(t0 - 0.1)
    assert int(sim.demand.lane[e.ego]) == ramp_codes(env.corridor.road)["on2"]
    assert e.run.is_cav[e.ego]
    assert e.run.depart(e.ego) >= 60.0


def test_the_commanded_acceleration_follows_the_ballistic_closed_form() -> None:
    env = make()
    env.reset(seed=1)
    e = env.episode
    assert e is not None
    i = e.ego
    sim = e.run.sim
    x0, v0, a_max = float(sim.x[i]), float(sim.v[i]), float(sim.fleet.matrix[3, i])
    env.step(np.array([0.5, -1.0], dtype=np.float32))
    acc, period = 0.5 * a_max, env.settings.action_period
    assert sim.v[i] == pytest.approx(v0 + acc * period, abs=1e-9)
    assert sim.x[i] == pytest.approx(x0 + v0 * period + 0.5 * acc * period**2, abs=1e-9)
    v1 = float(sim.v[i])
    env.step(np.array([-1.0, -1.0], dtype=np.float32))  # the emergency deceleration
    b = env.corridor.lane_change.emergency_decel
    assert sim.v[i] == pytest.approx(max(v1 - b * period, 0.0), abs=1e-9)


def test_a_merge_ends_the_episode_with_the_engines_merge() -> None:
    env = make()
    steps = run(env, 2, merge_when_clear)
    *_, (_obs, _, term, trunc, info) = steps
    e = env.episode
    assert e is not None
    assert term
    assert not trunc
    assert info["outcome"] == "merged"
    assert info["merged"]
    sim = e.run.sim
    merge = sim.log.events_of(EventKind.MERGE)
    merge = merge[merge["vehicle"] == e.ego]
    assert merge.size == 1
    code = int(sim.demand.lane[e.ego])
    assert sim.lane[e.ego] == sim.lanes.n_lanes - sim.lanes.n_main  # mainline lane 0
    assert merge["x"][0] <= sim.lanes.floats[L_END, code] + 1e-9
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(np.zeros(2, dtype=np.float32))


def test_driving_past_the_lane_end_is_a_crash() -> None:
    env = make()
    steps = run(env, 2, lambda obs: np.array([1.0, -1.0], dtype=np.float32))
    *_, (_, reward, term, _, info) = steps
    assert term
    assert info["crashed"]
    assert info["outcome"] == "lane end"
    assert reward < -env.settings.reward.collision + 1.0


def test_standing_still_times_out() -> None:
    env = make(max_episode_time=5.0)
    steps = run(env, 2, lambda obs: np.array([-1.0, -1.0], dtype=np.float32))
    assert len(steps) == 10
    *_, (_, reward, term, trunc, info) = steps
    assert trunc
    assert not term
    assert info["outcome"] == "timeout"
    assert reward < -env.settings.reward.timeout + 1.0


def test_observation_names_the_engines_key_vehicles() -> None:
    env = make(ramp="on3")
    obs, _info = env.reset(seed=4)
    e = env.episode
    assert e is not None
    sim = e.run.sim
    group = sim.key_groups[e.ego].as_array()
    np.testing.assert_array_equal(e.group, group)
    for r, j in enumerate(group):
        k = N_EGO + N_ROLE * r
        if j < 0:
            assert obs[k] == 0
            assert obs[k + 3] == -1
            continue
        assert obs[k] == 1
        assert obs[k + 1] == pytest.approx(sim.x[j] - sim.x[e.ego], abs=1e-3)
        assert obs[k + 2] == pytest.approx(sim.v[j] - sim.v[e.ego], abs=1e-4)
        assert obs[k + 4] == float(e.run.is_cav[j])
    assert obs[0] == pytest.approx(sim.v[e.ego], abs=1e-5)
    assert obs[2] == pytest.approx(e.run.lane_end(e.ego) - sim.x[e.ego], abs=1e-3)
    assert env.observation_space.contains(obs)


def eq15(d: float, v_rear: float, v_front: float, delay: float, ctl) -> float:
    """Eq. 15 by the library's vectorised form, for one pair."""
    return float(
        critical_acceleration(d, v_rear, v_front, delay=delay,
                              min_distance=ctl.safety_min_distance,
                              emergency_decel=ctl.safety_emergency_decel)
    )  # fmt: skip


def test_safety_term_is_eq15_of_the_egos_pairs() -> None:
    """The period's safety term equals the period times Eq. 15 (vectorised form) of the ego
    behind its leader and its follower behind it on the ramp lane, over a_merg."""
    env = make()
    env.reset(seed=5)
    e = env.episode
    assert e is not None
    _, _, _, _, info = env.step(np.array([0.3, -1.0], dtype=np.float32))
    s, i, ctl = e.run.sim, e.ego, env.corridor.control
    assert s.origin[i] == s.target[i]  # keeping its lane: its pairs are in that lane only
    length = s.fleet.length
    same = np.flatnonzero(s.active & (s.lane == s.lane[i]) & (np.arange(s.x.size) != i))
    ahead, behind = same[s.x[same] > s.x[i]], same[s.x[same] <= s.x[i]]
    worst = 0.0
    if ahead.size:
        lead = ahead[np.argmin(s.x[ahead])]
        d = s.x[lead] - length[lead] - s.x[i]
        worst = max(worst, eq15(d, s.v[i], s.v[lead], ctl.safety_delay_cav, ctl))
    if behind.size:
        fol = behind[np.argmax(s.x[behind])]
        delay = ctl.safety_delay_cav if e.run.is_cav[fol] else ctl.safety_delay_hdv
        d = s.x[i] - length[i] - s.x[fol]
        worst = max(worst, eq15(d, s.v[fol], s.v[i], delay, ctl))
    expected = env.settings.action_period * min(worst / ctl.safety_emergency_decel, 1.0)
    assert info["safety"] == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_episodes_are_deterministic_and_work_on_a_four_lane_corridor() -> None:
    first = run(make(), 6, merge_when_clear)
    again = run(make(), 6, merge_when_clear)
    assert len(first) == len(again)
    for (o1, r1, *_), (o2, r2, *_) in zip(first, again, strict=True):
        np.testing.assert_array_equal(o1, o2)
        assert r1 == r2
    wide = make(overrides={"road.lanes": 4}, ramp="on4")
    steps = run(wide, 6, merge_when_clear)
    assert steps[-1][4]["outcome"] in ("merged", "collision", "lane end")
    assert wide.corridor.road.lanes == 4


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"ramp": "nope"}, "key 'ramp' = 'nope': allowed: on1, on2, on3, on4, on5"),
        ({"corridor": "paper-C3"}, "key 'corridor.warmup' = 30.0: a corridor episode does not"),
        ({"start_after": 1e9}, "key 'start_after' = 1000000000.0: allowed: 0 <= start_after"),
        ({"action_period": 0.15}, "key 'action_period' = 0.15: allowed: a multiple of the step"),
        ({"max_episode_time": 0}, "key 'max_episode_time' = 0: allowed: a number > 0"),
        ({"render_mode": "rgb_array"}, "key 'render_mode' = 'rgb_array': allowed: None"),
        ({"overrides": {"road.lanes": 0}}, "road.lanes"),
    ],
)
def test_bad_options_name_the_key(kwargs: dict, message: str) -> None:
    corridor = kwargs.pop("corridor", "corridor")
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(".", r"\.")):
        CorridorMergeEnv(corridor, **kwargs)


def test_a_ramp_without_connected_vehicles_is_named_at_reset() -> None:
    env = make(overrides={"demand.on1.cav_share": 0.0})
    with pytest.raises(ConfigError, match="no CAV departs from on-ramp 'on1'"):
        env.reset(seed=0)


# --------------------------------------------------------------- every ramp CAV an agent
def play(env: CorridorParallelEnv, seed: int, policy=merge_when_clear) -> tuple[set, list]:
    """The agents seen and the steps of one episode."""
    obs, _ = env.reset(seed=seed)
    seen, out = set(obs), []
    while env.agents:
        step = env.step({a: policy(obs[a]) for a in env.agents})
        obs = step[0]
        seen |= set(obs)
        out.append(step)
    return {int(name[4:]) for name in seen}, out


def test_pettingzoo_parallel_api_test_passes() -> None:
    parallel_api_test(CorridorParallelEnv("corridor", **FAST), num_cycles=40)


def test_every_ramp_cav_in_a_zone_is_an_agent_until_its_merge() -> None:
    env = CorridorParallelEnv("corridor", start_after=300.0, max_episode_time=40.0)
    seen, steps = play(env, 1)
    run = env.run
    assert run is not None
    sim = run.sim
    assert len({int(sim.demand.lane[i]) for i in seen}) >= 3  # several ramps
    merged_at = set(sim.log.events_of(EventKind.MERGE)["vehicle"].tolist())
    for i in seen:
        assert run.is_cav[i]
        assert sim.lanes.ints[L_KIND, sim.demand.lane[i]] == KIND_ON  # a ramp vehicle
        assert i in sim.key_groups  # that entered its control zone
    merged = 0
    for *_, term, _, info in steps:
        for name, done in term.items():
            i = int(name[4:])
            if done and info[name]["outcome"] == "merged":
                assert i in merged_at
                assert np.isnan(sim.arrays.a_cmd[i])  # handed back to its model
                merged += 1
    assert merged > 0
    assert not run.agents


def test_a_joining_agent_sees_the_key_vehicles_of_its_merge_event() -> None:
    env = CorridorParallelEnv("corridor", start_after=300.0, max_episode_time=60.0,
                              action_period=0.1)  # one step: a joiner entered in it  # fmt: skip
    obs, _ = env.reset(seed=2)
    run = env.run
    assert run is not None
    checked = 0
    while env.agents and checked < 5:
        obs, _, _, _, info = env.step({a: merge_when_clear(obs[a]) for a in env.agents})
        for data in info.values():
            i = data["vehicle"]
            if data.get("joined"):
                entered = {g["VR"]: g["t"] for g in run.sim.log.meta["key_groups"]}
                assert entered[i] == pytest.approx(run.t - 0.1)  # in the step just taken
                np.testing.assert_array_equal(env._groups[i], run.sim.key_groups[i].as_array())
                checked += 1
    assert checked > 0


def test_multi_agent_episodes_are_deterministic() -> None:
    _, a = play(CorridorParallelEnv("corridor", **FAST), 3)
    _, b = play(CorridorParallelEnv("corridor", **FAST), 3)
    assert len(a) == len(b)
    for (o1, r1, *_), (o2, r2, *_) in zip(a, b, strict=True):
        assert o1.keys() == o2.keys()
        assert r1 == r2
        for k in o1:
            np.testing.assert_array_equal(o1[k], o2[k])
