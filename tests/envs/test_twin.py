"""The undisturbed twin copied from a run equals the simulated undisturbed run, bit for bit,
to the end of the run; an episode whose twin is deferred is the episode whose twin was made
at once."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.envs import episode as episode_module
from hcomc.envs.episode import MergeEpisode
from hcomc.envs.merge_env import MergeEnv
from hcomc.sim.engine import Simulation
from hcomc.sim.step.ramp_reach import ramp_may_reach, ramp_untouched
from hcomc.sim.twin import can_twin, undisturbed_twin

END = 10**12
FIELDS = ("t", "x", "y", "v", "a", "heading", "lane", "active")


@pytest.mark.parametrize(("condition", "seed", "ramp"), [("C1", 0, "single"), ("C2", 3, "single"),
                                                          ("C4", 1, "flow")])  # fmt: skip
def test_twin_equals_the_simulated_undisturbed_run(condition: str, seed: int, ramp: str) -> None:
    config = load_config(condition, control={"controller": "none"}, demand={"ramp": ramp})
    sim = Simulation(config, seed)
    sim.run_to(END, until_key_vehicles=True)
    assert can_twin(sim)
    twin = undisturbed_twin(sim)
    simulated = Simulation(config, seed, counterfactual=True)
    simulated.run_to(sim.step_index)
    for name in ("x", "v", "a", "lane", "active", "x_hist", "w_gap", "counters", "queue_pos"):
        np.testing.assert_array_equal(getattr(twin.arrays, name),
                                      getattr(simulated.arrays, name), err_msg=name)  # fmt: skip
    a, b = twin.run(), simulated.run()
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name in a.events.dtype.names:  # field by field: NaN payloads compare equal
        np.testing.assert_array_equal(a.events[name], b.events[name], err_msg=name)
    assert a.meta["vehicle_steps"] == b.meta["vehicle_steps"]


def test_no_twin_once_the_ramp_vehicle_reaches_the_acceleration_lane() -> None:
    sim = Simulation(load_config("C1", control={"controller": "none"}), 0)
    sim.run_to(END, until_key_vehicles=True)
    vr = sim.key_group.vr
    while sim.x[vr] < sim.config.road.accel_lane_start:
        sim.run_to(sim.step_index + 5)
    assert not can_twin(sim)
    with pytest.raises(ValueError, match="cannot be copied"):
        undisturbed_twin(sim)
    planned = Simulation(load_config("C1", control={"controller": "fifo"}), 0)
    planned.run_to(END, until_key_vehicles=True)
    assert not can_twin(planned)  # the plan acts from the step it is made


@pytest.mark.parametrize("counterfactual", [True, False])
def test_a_run_built_on_drawn_demand_is_the_run_of_its_seed(counterfactual: bool) -> None:
    """``Simulation._sibling`` (the twin's frame: another run's demand and fleet, not drawn
    again) gives the run a new ``Simulation`` of the same seed gives, from a run that has
    already advanced."""
    config = load_config("C2", control={"controller": "none"})
    sim = Simulation(config, 5)
    sim.run_to(400)  # the source's generator has moved on: the sibling must not start there
    a = Simulation._sibling(sim, counterfactual=counterfactual).run()
    b = Simulation(config, 5, counterfactual=counterfactual).run()
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.meta["config"] == b.meta["config"]
    assert a.meta["seed"] == b.meta["seed"]


# ---------------------------------------------------------------- the deferred twin
def _play(seed: int, policy, *, defer: bool) -> tuple[list, MergeEpisode]:
    """One episode of hcomc/Merge-v0 (C1, 1 s periods) with the twin deferred or not: its
    observations, rewards and ends."""
    env = MergeEnv("C1", action_period=1.0)
    episode = MergeEpisode(env.options, env.config, seed, defer_twin=defer)
    obs = episode.start()
    steps = []
    while True:
        episode.run_period(episode.apply(policy(obs)))
        r = episode.evaluate()
        steps.append((r.obs, r.reward, r.terminated, r.truncated, r.info))
        if r.terminated or r.truncated:
            return steps, episode
        obs = r.obs


def _random(seed: int):
    rng = np.random.default_rng(seed)
    return lambda obs: rng.uniform(-1, 1, 2)


def _merging(obs: np.ndarray) -> np.ndarray:
    return np.array([0.3, 1.0])  # accelerate, and merge as soon as the lane allows


def _assert_same_episode(a: list, b: list) -> None:
    assert len(a) == len(b)
    for (oa, ra, ta, ua, ia), (ob, rb, tb, ub, ib) in zip(a, b, strict=True):
        np.testing.assert_array_equal(oa, ob)
        assert (ra, ta, ua) == (rb, tb, ub)
        assert ia == ib


@pytest.mark.parametrize("seed", [0, 3, 7])
@pytest.mark.parametrize("policy", ["random", "merging"])
def test_a_deferred_twin_gives_the_episode_of_the_twin_made_at_once(
    seed: int, policy: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Bit for bit: observations, rewards, ends, infos, and both logs run to the end. The
    twin is made before the period a ramp vehicle might reach the acceleration lane in, or
    (the check before the period disabled) simulated anew after the period that broke the
    standing-in: all three ways give the same episode."""
    pick = (lambda: _random(seed)) if policy == "random" else (lambda: _merging)
    eager, e_ep = _play(seed, pick(), defer=False)
    deferred, d_ep = _play(seed, pick(), defer=True)
    _assert_same_episode(eager, deferred)
    made: list[bool] = []
    original = MergeEpisode.settle_twin

    def spy(self: MergeEpisode, untouched: bool) -> bool:
        made.append(original(self, untouched))
        return made[-1]

    monkeypatch.setattr(MergeEpisode, "settle_twin", spy)
    monkeypatch.setattr(episode_module, "ramp_may_reach", lambda c, horizon: False)
    late, l_ep = _play(seed, pick(), defer=True)
    _assert_same_episode(eager, late)
    assert made  # the twin was pending for at least one period
    if policy == "merging":
        assert any(made)  # ... and simulated anew once VR reached the acceleration lane
        assert not d_ep.twin_pending
    expected = e_ep.finish()  # the logs run to the end, the agent's vehicle back on its model
    for ep in (d_ep, l_ep):
        for got, want in zip(ep.finish(), expected, strict=True):
            for name in FIELDS:
                np.testing.assert_array_equal(getattr(got, name), getattr(want, name))


@pytest.mark.parametrize("seed", [1, 2])
def test_no_ramp_vehicle_gets_further_than_ramp_may_reach_allows(seed: int) -> None:
    """Whenever :func:`ramp_may_reach` says no ramp vehicle can reach the acceleration lane
    within the next period, none does (random actions, every period of an episode)."""
    env = MergeEnv("C1", action_period=1.0)
    episode = MergeEpisode(env.options, env.config, seed, defer_twin=False)
    episode.start()
    rng = np.random.default_rng(seed)
    sim, said_no, period = episode.sim, 0, env.options.action_period
    for _ in range(40):
        safe = not ramp_may_reach(sim.core, period)
        episode.run_period(episode.apply(rng.uniform(-0.2, 1, 2)))
        if safe:
            said_no += 1
            assert ramp_untouched(sim.core)
        result = episode.evaluate()
        if result.terminated or result.truncated:
            break
    assert said_no >= 3
    assert not ramp_untouched(sim.core)  # VR did reach the acceleration lane
