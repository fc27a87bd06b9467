"""hcomc/Merge-v0, its vector form and the multi-agent environment: API checks, determinism,
bit-identity of the vector environment, observation and reward against independent
computations, and the controllers as policies."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import hcomc.envs  # noqa: F401 (registers hcomc/Merge-v0)
from hcomc.config import ConfigError, load_config
from hcomc.control.key_group import find_key_vehicles
from hcomc.envs import MergeEnv
from hcomc.envs import episode as episode_module
from hcomc.envs import vector as vector_module
from hcomc.envs.episode import SEED_TRIES, MergeEpisode, NoVMCError
from hcomc.envs.multi_agent import MergeParallelEnv
from hcomc.envs.observation import N_EGO, N_OBS, N_ROLE, OBS_NAMES
from hcomc.envs.policies import FIFO, HCOMC, evaluate_policies, policy_summary
from hcomc.envs.vector import MergeVectorEnv
from hcomc.equations.fuel import fuel_rate
from hcomc.equations.safety import critical_acceleration
from hcomc.metrics import compute_metrics
from hcomc.road import KEY_ROLES, Kind
from hcomc.sim.engine import Simulation


def drive(obs: np.ndarray) -> np.ndarray:
    """A simple fixed policy: mild acceleration, merge 150 m before the lane end."""
    return np.array([0.2, 1.0 if obs[2] < 150 else -1.0], dtype=np.float32)


def rollout(env: MergeEnv, seed: int, policy=drive) -> list[tuple[np.ndarray, float, bool, bool]]:
    obs, _ = env.reset(seed=seed)
    out, done = [], False
    while not done:
        obs, r, term, trunc, _ = env.step(policy(obs))
        out.append((obs, r, term, trunc))
        done = term or trunc
    return out


def test_gymnasium_env_checker_passes() -> None:
    check_env(gym.make("hcomc/Merge-v0").unwrapped, skip_render_check=True)
    check_env(MergeEnv("C2", agent="vmc"), skip_render_check=True)


NO_VMC_SEED = 35
"""A C1 seed whose VR has no VMC when it enters the control zone."""


def test_a_seed_without_vmc_is_skipped_only_when_drawn(monkeypatch: pytest.MonkeyPatch) -> None:
    env = MergeEnv("C1", agent="vmc")
    with pytest.raises(NoVMCError, match=f"seed {NO_VMC_SEED}: VR has no VMC"):
        env.reset(seed=NO_VMC_SEED)
    expected, _ = MergeEnv("C1", agent="vmc").reset(seed=5)
    drawn = iter([NO_VMC_SEED, 5])
    monkeypatch.setattr("hcomc.envs.merge_env.draw_seed", lambda rng: next(drawn))
    obs, info = env.reset()
    assert info["seed"] == 5
    np.testing.assert_array_equal(obs, expected)
    monkeypatch.setattr("hcomc.envs.merge_env.draw_seed", lambda rng: NO_VMC_SEED)
    with pytest.raises(NoVMCError, match=f"{SEED_TRIES} drawn seeds in a row"):
        env.reset()


def test_vector_env_skips_drawn_seeds_without_vmc(monkeypatch: pytest.MonkeyPatch) -> None:
    envs = MergeVectorEnv(2, agent="vmc")
    drawn = iter([NO_VMC_SEED, 7, 5])  # both runs' seeds, then sub-environment 0's next
    monkeypatch.setattr("hcomc.envs.vector.draw_seed", lambda rng: next(drawn))
    obs, info = envs.reset()
    assert info["seed"].tolist() == [5, 7]
    for k, seed in enumerate((5, 7)):
        np.testing.assert_array_equal(obs[k], MergeEnv("C1", agent="vmc").reset(seed=seed)[0])
    with pytest.raises(NoVMCError):
        envs.reset(seed=[NO_VMC_SEED, 7])  # given seeds are not replaced


def test_pettingzoo_parallel_api_test_passes() -> None:
    parallel_api_test(MergeParallelEnv("C1"), num_cycles=300)


def test_spaces_and_names() -> None:
    env = MergeEnv("C1")
    assert env.observation_space.shape == (N_OBS,) == (len(OBS_NAMES),)
    assert env.action_space.shape == (2,)
    assert OBS_NAMES[N_EGO + N_ROLE] == f"{KEY_ROLES[1]}.present"


def test_same_seed_same_episode_bit_for_bit() -> None:
    a, b = rollout(MergeEnv("C3"), 4), rollout(MergeEnv("C3"), 4)
    assert len(a) == len(b)
    for (oa, ra, *_), (ob, rb, *_) in zip(a, b, strict=True):
        np.testing.assert_array_equal(oa, ob)
        assert ra == rb
    c = rollout(MergeEnv("C3"), 5)
    assert not all(np.array_equal(x[0], y[0]) for x, y in zip(a, c, strict=False))


def test_observation_is_the_key_vehicles_relative_to_the_agent() -> None:
    env = MergeEnv("C1")
    env.reset(seed=2)
    obs, *_ = env.step(np.array([0.5, -1.0]))
    sim, ep = env.episode.sim, env.episode
    group = find_key_vehicles(sim.view(sim.t), ep.vr).as_array()
    ego = ep.ego
    assert obs[0] == np.float32(sim.v[ego])
    assert obs[2] == np.float32(sim.config.road.accel_lane_end - sim.x[ego])
    for r, j in enumerate(group):
        block = obs[N_EGO + N_ROLE * r : N_EGO + N_ROLE * (r + 1)]
        if j < 0:
            assert block.tolist() == [0, 0, 0, -1, 0]
        else:
            expect = [1, sim.x[j] - sim.x[ego], sim.v[j] - sim.v[ego], sim.lane[j],
                      sim.fleet.kind[j] == Kind.CAV]  # fmt: skip
            np.testing.assert_allclose(block, np.float32(expect), rtol=0, atol=1e-4)


def test_reward_terms_against_independent_computations() -> None:
    """Eq. 16 from the fuel model over the log rows, Eq. 17 from the two logs, Eq. 15 from
    the public critical-acceleration function, and the reward as their weighted sum."""
    env = MergeEnv("C1", reward={"safety": 2.0, "fuel": 0.3, "efficiency": 0.7})
    obs, _ = env.reset(seed=1)
    ep = env.episode
    for _ in range(12):
        obs, reward, _term, _trunc, info = env.step(drive(obs))
    sim, g, cfg = ep.sim, ep.group, env.config
    twin = Simulation(cfg, 1, counterfactual=True)  # the undisturbed run, simulated
    twin.run_to(sim.step_index)
    r1 = sim.rows_recorded
    r0 = r1 - round(env.options.action_period / cfg.log_interval)
    dt = cfg.log_interval

    def fuel(i: int) -> float:
        return float(fuel_rate(sim.log.v[r0:r1, i], sim.log.a[r0:r1, i]).sum() * dt)

    assert info["fuel"] == pytest.approx(fuel(ep.vr) + fuel(int(g[1])), rel=1e-12)
    eta = cfg.lane_change.politeness
    others = sum(
        float((sim.log.a[r0:r1, i].astype(float) - twin.log.a[r0:r1, i]).sum() * dt)
        for i in (int(g[1]), int(g[3]), int(g[5])) if i >= 0
    )  # fmt: skip
    p = sim.fleet
    v, a = sim.log.v[r0:r1, ep.vr].astype(float), sim.log.a[r0:r1, ep.vr].astype(float)
    free = p.a[ep.vr] * (1 - (v / p.v0[ep.vr]) ** p.delta[ep.vr])  # IDM on a free road
    assert info["efficiency"] == pytest.approx(float((a - free).sum() * dt) + eta * others)
    ctl = cfg.control
    vr = ep.vr
    in_lane = [i for i in np.flatnonzero(sim.active) if sim.lane[i] == sim.lane[vr] and i != vr]
    ahead = [i for i in in_lane if sim.x[i] > sim.x[vr]]
    behind = [i for i in in_lane if sim.x[i] <= sim.x[vr]]

    def critical(follower: int, leader: int, delay: float) -> float:  # Eq. 15 of one pair
        gap = sim.x[leader] - p.length[leader] - sim.x[follower]
        return float(critical_acceleration(
            gap, sim.v[follower], sim.v[leader], delay=delay,
            min_distance=ctl.safety_min_distance, emergency_decel=ctl.safety_emergency_decel,
        ))  # fmt: skip

    u = 0.0
    if ahead:
        u = max(u, critical(vr, min(ahead, key=lambda i: sim.x[i]), ctl.safety_delay_cav))
    if behind:
        f = max(behind, key=lambda i: sim.x[i])
        delay = ctl.safety_delay_cav if p.kind[f] == Kind.CAV else ctl.safety_delay_hdv
        u = max(u, critical(f, vr, delay))
    expect_safety = env.options.action_period * min(u / ctl.safety_emergency_decel, 1.0)
    if sim.origin[vr] == sim.target[vr]:
        assert info["safety"] == pytest.approx(expect_safety)
    w = env.options.reward
    total = -w.safety * info["safety"] - w.fuel * info["fuel"] + w.efficiency * info["efficiency"]
    assert reward == pytest.approx(total - w.time * env.options.action_period)


def test_lane_end_and_timeout_end_the_episode_with_their_penalties() -> None:
    env = MergeEnv("C1")
    steps = rollout(env, 0, policy=lambda o: np.array([0.5, -1.0]))
    obs, reward, term, trunc = steps[-1]
    assert term
    assert not trunc
    assert obs[2] <= 0
    assert reward < -env.options.reward.collision + 1
    short = MergeEnv("C1", max_episode_time=3.0)
    steps = rollout(short, 0, policy=lambda o: np.array([0.0, -1.0]))
    assert len(steps) == 6
    assert steps[-1][3]
    assert not steps[-1][2]


@pytest.mark.parametrize("late_twins", [False, True])
def test_vector_env_is_bit_identical_to_single_envs_with_autoreset(
    late_twins: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The twins deferred while VR is short of the acceleration lane are made ahead of the
    period it may reach the lane in; with ``late_twins`` none is made ahead, so they are
    simulated anew after that period. Either way the episodes are the single ones."""
    made_late: list[bool] = []
    if late_twins:
        monkeypatch.setattr(episode_module, "ramp_may_reach", lambda c, horizon: False)
        monkeypatch.setattr(vector_module, "twins_due", lambda *args: None)
    settle, make_due = MergeEpisode.settle_twin, MergeEpisode.make_due_twin

    def settle_spy(episode: MergeEpisode, untouched: bool) -> bool:
        made_late.append(settle(episode, untouched))  # True: simulated anew
        return made_late[-1]

    def make_due_spy(episode: MergeEpisode) -> None:
        made_late.append(True)
        make_due(episode)

    monkeypatch.setattr(MergeEpisode, "settle_twin", settle_spy)
    monkeypatch.setattr(MergeEpisode, "make_due_twin", make_due_spy)
    n = 3
    envs = gym.make_vec("hcomc/Merge-v0", num_envs=n, vectorization_mode="vector_entry_point",
                        action_period=1.0, max_episode_time=10.0)  # fmt: skip
    assert isinstance(envs, MergeVectorEnv)
    obs, _ = envs.reset(seed=10)
    singles = [MergeEnv("C1", action_period=1.0, max_episode_time=10.0) for _ in range(n)]
    first = [e.reset(seed=10 + k)[0] for k, e in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(first))
    rng = np.random.default_rng(0)
    ended = [False] * n
    episodes = 0
    for _ in range(40):
        actions = rng.uniform([0, -1], [1, 1], (n, 2)).astype(np.float32)  # VR drives on
        vobs, vrew, vterm, vtrunc, vinfo = envs.step(actions)
        for k, env in enumerate(singles):
            if ended[k]:
                o, info = env.reset()
                r, te, tr = 0.0, False, False
            else:
                o, r, te, tr, info = env.step(actions[k])
            np.testing.assert_array_equal(vobs[k], o)
            assert vrew[k] == r
            assert vterm[k] == te
            assert vtrunc[k] == tr
            assert vinfo["_seed"][k]
            assert vinfo["seed"][k] == info["seed"]
            for key in ("merged", "collision", "lane_end", "timeout"):  # a step's outcome
                shown = key in vinfo and vinfo[f"_{key}"][k]
                assert shown == (key in info)
                assert not shown or vinfo[key][k] == info[key]
            ended[k] = te or tr
            episodes += te or tr
    assert episodes >= 3 * n  # the autoreset was exercised
    assert any(made_late)  # twins were deferred, and made when VR drew near the lane
    assert not all(made_late)


def test_controller_policy_episode_is_the_controllers_run() -> None:
    """With FIFO driving, the episode's log is the log of the plain FIFO run of that seed."""
    env = MergeEnv("C2", controller="fifo")
    rollout(env, 3, policy=FIFO)
    log, reference = env.episode_logs()
    plain = Simulation(load_config("C2", control={"controller": "fifo"}), 3).run()
    undisturbed = Simulation(load_config("C2"), 3, counterfactual=True).run()
    for name in ("x", "v", "a", "lane"):
        np.testing.assert_array_equal(getattr(log, name), getattr(plain, name))
        np.testing.assert_array_equal(getattr(reference, name), getattr(undisturbed, name))
    m = compute_metrics(log, reference=reference)
    assert m == compute_metrics(plain, reference=undisturbed) or all(
        (math.isnan(a) and math.isnan(b)) or a == b
        for a, b in zip(m.values(), compute_metrics(plain, reference=undisturbed).values(),
                        strict=True)
    )  # fmt: skip


def test_evaluate_compares_policies_on_the_same_seeds() -> None:
    results = evaluate_policies({"drive": drive, "HCOMC": HCOMC}, seeds=[0, 1], scenario="C1")
    assert [(r.policy, r.seed) for r in results] == [
        ("drive", 0),
        ("drive", 1),
        ("HCOMC", 0),
        ("HCOMC", 1),
    ]
    assert all(math.isfinite(r.metrics["critical_distance"]) for r in results)
    table = policy_summary(results)
    assert table.loc["HCOMC", "episodes"] == 2
    assert table.loc["HCOMC", "collision"] == 0


def test_bad_options_are_one_line_errors() -> None:
    with pytest.raises(ConfigError, match="key 'agent' = 'vx'"):
        MergeEnv("C1", agent="vx")
    with pytest.raises(ConfigError, match=r"key 'action_period' = 0\.25"):
        MergeEnv("C1", action_period=0.25, overrides={"dt": 0.5, "log_interval": 0.5})
    with pytest.raises(ConfigError, match="allowed only with agent 'vr'"):
        MergeEnv("C1", agent="vmc", controller="hcomc")
    with pytest.raises(ConfigError, match=r"key 'reward\.fuel'"):
        MergeEnv("C1", reward={"fuel": -1.0})
    with pytest.raises(ConfigError, match="platoon"):
        MergeEnv("platoon")


def test_multi_agent_rewards_and_membership() -> None:
    env = MergeParallelEnv("C4")
    obs, _ = env.reset(seed=0)
    assert obs
    assert all(o.shape == (N_OBS,) for o in obs.values())
    members = {int(a.split("_")[1]) for a in env.agents}
    sim = env.episode.sim
    road = env.config.road
    assert all(sim.fleet.kind[i] == Kind.CAV for i in members)
    assert all(road.control_zone_start <= sim.x[i] <= road.accel_lane_end for i in members)
    seen, steps = set(env.agents), 0
    while env.agents:
        acts = {a: np.array([0.1, 1.0 if obs[a][2] < 120 and obs[a][1] == 0 else -1.0])
                for a in env.agents}  # fmt: skip
        obs, rew, term, _trunc, _info = env.step(acts)
        seen |= set(obs)
        steps += 1
        assert set(rew) == set(obs) == set(term)
    assert steps > 5
    assert len(seen) > len(members)


def test_episode_log_works_with_metrics_files_and_figures(tmp_path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from hcomc.sim.log import SimulationLog
    from hcomc.viz.figures.trajectories import trajectories_figure

    env = MergeEnv("C1")
    rollout(env, 2)
    log, reference = env.episode_logs()
    assert log.meta["agent"]["role"] == "VR"
    assert log.meta["key_groups"][0]["VR"] == env.episode.vr
    log.save(tmp_path / "log.npz")
    again = SimulationLog.load(tmp_path / "log.npz")
    m = compute_metrics(again, reference=reference)
    assert math.isfinite(m["critical_distance"])
    assert m["collisions"] == 0
    fig = trajectories_figure(again)
    assert "driven by a learning agent" in fig.get_suptitle()


def test_any_scenario_toml_and_overrides(tmp_path) -> None:
    path = tmp_path / "half.toml"
    path.write_text('base = "C2"\n[demand]\ncav_penetration = 0.5\n')
    env = MergeEnv(str(path), overrides={"duration": 120.0})
    assert env.config.demand.cav_penetration == 0.5
    assert env.config.duration == 120.0
    assert env.config.control.controller == "none"  # the agent drives, not a controller
    obs, info = env.reset(seed=1)
    assert info["ego"] == env.episode.vr
    assert obs.shape == (N_OBS,)


def test_a_corridor_of_the_papers_layout_is_its_condition() -> None:
    a, b = rollout(MergeEnv("paper-C3"), 4), rollout(MergeEnv("C3"), 4)
    assert len(a) == len(b) > 5
    for (oa, ra, *_), (ob, rb, *_) in zip(a, b, strict=True):
        np.testing.assert_array_equal(oa, ob)
        assert ra == rb
    # a general corridor runs in the corridor engine, not in an environment: refused by name
    with pytest.raises(ConfigError, match=r"key 'road\.lanes' = 3"):
        MergeEnv("corridor")
