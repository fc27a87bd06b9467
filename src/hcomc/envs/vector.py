"""A native vector environment of ``hcomc/Merge-v0``: many episodes advanced together on the
ensemble engine (one compiled call per step for all runs, parallel over cores), not a pool of
processes.

Sub-environment k behaves exactly as a :class:`~hcomc.envs.merge_env.MergeEnv` reset with
seed ``seed + k`` and then reset without a seed after each episode: the same observations,
rewards and episode ends, bit for bit. Episodes end independently and restart on the next
step (gymnasium's default "next step" autoreset: that step ignores the sub-environment's
action and returns its first observation with reward 0).

    envs = gymnasium.make_vec(
        "hcomc/Merge-v0", num_envs=64, vectorization_mode="vector_entry_point"
    )
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from hcomc.envs.batch import N_TERMS, apply_batch, ramps_untouched, step_terms_batch, twins_due
from hcomc.envs.episode import MergeEpisode, NoVMCError, start_drawn
from hcomc.envs.merge_env import MergeEnv
from hcomc.envs.render import RENDER_MODES, render_frame
from hcomc.envs.scoring import outcomes, parameters
from hcomc.envs.scoring import rewards as step_rewards
from hcomc.rng import draw_seed
from hcomc.road import N_ROLES
from hcomc.sim.ensemble import advance_ensemble
from hcomc.sim.typed_lists import TypedListCache

if TYPE_CHECKING:
    from numba.typed import List

_END = np.iinfo(np.int64).max
_INFO_KEYS = ("seed", "merged", "collision", "lane_end", "timeout")
_INFO_ORDER = [k for key in _INFO_KEYS for k in (key, f"_{key}")]


class MergeVectorEnv(VectorEnv):
    """``num_envs`` merge episodes stepped together.

    Parameters
    ----------
    num_envs : number of sub-environments.
    threads : cores for the ensemble (default: all numba may use).
    **kwargs : the options of :class:`~hcomc.envs.merge_env.MergeEnv`.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012
        "autoreset_mode": AutoresetMode.NEXT_STEP,
        "render_modes": list(RENDER_MODES),
    }

    def __init__(self, num_envs: int = 8, *, threads: int | None = None, **kwargs: Any) -> None:
        if int(num_envs) < 1:
            raise ValueError(f"key 'num_envs' = {num_envs}: allowed: an integer >= 1")
        template = MergeEnv(**kwargs)
        self.options, self.config = template.options, template.config
        self.render_mode = template.render_mode
        self.num_envs = int(num_envs)
        self.threads = threads
        self.single_observation_space = template.observation_space
        self.single_action_space = template.action_space
        self._obs_shape: tuple[int, ...] = template.observation_space.shape or (0,)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.episodes: list[MergeEpisode | None] = [None] * self.num_envs
        self._params = parameters(self.config, self.options.action_period)
        self._runs = TypedListCache()  # the episodes' runs and twins, for the kernels
        self._rngs = [seeding.np_random(k)[0] for k in range(self.num_envs)]
        self._ended = np.zeros(self.num_envs, dtype=bool)

    # -------------------------------------------------------------------- reset
    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start every sub-environment (``seed``: an int gives seed + k to sub-environment k,
        a list one seed each)."""
        if seed is not None:
            seeds = [seed + k for k in range(self.num_envs)] if isinstance(seed, int) else seed
            if len(seeds) != self.num_envs:
                raise ValueError(f"reset: {len(seeds)} seeds for {self.num_envs} environments")
            self._rngs = [seeding.np_random(int(s))[0] for s in seeds]
        run_seeds = [
            int(s) if seed is not None else self._next_seed(k)
            for k, s in enumerate(seeds if seed is not None else range(self.num_envs))
        ]
        obs = self._start(list(range(self.num_envs)), run_seeds, drawn=seed is None)
        self._ended[:] = False
        infos = self._infos([{"seed": e.seed} for e in self._current()])
        return np.stack(obs), infos

    def _next_seed(self, k: int) -> int:
        return draw_seed(self._rngs[k])

    def _start(self, which: list[int], seeds: list[int], *, drawn: bool) -> list[np.ndarray]:
        """New episodes for sub-environments ``which``, advanced together to their start."""
        new = [MergeEpisode(self.options, self.config, s) for s in seeds]
        advance_ensemble([e.sim for e in new], [_END] * len(new),
                         until_key_vehicles=[True] * len(new), threads=self.threads)  # fmt: skip
        return self._begin(which, new, drawn=drawn)

    def _begin(self, which: list[int], new: list[MergeEpisode], *, drawn: bool) -> list[np.ndarray]:
        """Twins and first observations of new episodes that reached VR's entry. An episode
        on a ``drawn`` seed without a VMC for the agent is replaced by one on the next drawn
        seed, as :meth:`MergeEnv.reset` does."""
        behind = [e for e in new if e.make_twin()]  # twins that are not copies
        advance_ensemble([e.twin for e in behind], [e.sim.step_index for e in behind],
                         threads=self.threads)  # fmt: skip
        firsts = []
        for k, fresh in zip(which, new, strict=True):
            episode = fresh
            try:
                first = episode.begin()
            except NoVMCError:
                if not drawn:
                    raise
                draw = functools.partial(self._next_seed, k)
                episode, first = start_drawn(self.options, self.config, draw)
            self.episodes[k] = episode
            firsts.append(first)
        return firsts

    # --------------------------------------------------------------------- step
    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One action period of every sub-environment (restarting those that ended).

        All runs advance in one compiled call: each sub-environment's run (a restarting one:
        its new run) in the same place every step, then the twins that are made.
        """
        actions = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, -1)
        n = self.num_envs
        restart = np.flatnonzero(self._ended).tolist()
        new = {k: MergeEpisode(self.options, self.config, self._next_seed(k)) for k in restart}
        episodes = self._current()
        going = np.ones(n, dtype=bool)
        going[restart] = False  # a restarting sub-environment: its old episode has ended
        self._make_due_twins(episodes, going)
        mains, _ = self._lists(episodes)
        drive = np.array([e.driven for e in episodes]) & going
        egos = np.array([e.ego for e in episodes], dtype=np.int64)
        apply_batch(mains, egos, actions, drive, self._params)
        targets = [e.sim.step_index + e.period_steps for e in episodes]
        runs = [new[k].sim if k in new else e.sim for k, e in enumerate(episodes)]
        goals = [_END if k in new else targets[k] for k in range(n)]
        keys = [k in new for k in range(n)]
        for k in np.flatnonzero(going).tolist():
            if not episodes[k].twin_pending:
                runs.append(episodes[k].twin)
                goals.append(targets[k])
                keys.append(False)
        advance_ensemble(runs, goals, until_key_vehicles=keys, threads=self.threads,
                         flush=False)  # the episodes count collisions, not events  # fmt: skip
        self._settle_twins(episodes, going, targets)
        mains, twins = self._lists(episodes)
        vrs = np.array([e.vr for e in episodes], dtype=np.int64)
        r0s = np.array([e.rows_scored for e in episodes], dtype=np.int64)
        obs = np.zeros((n, *self._obs_shape), dtype=np.float32)
        terms = np.zeros((n, N_TERMS))
        groups = np.zeros((n, N_ROLES), dtype=np.int64)
        step_terms_batch(mains, twins, egos, vrs, r0s, self._params, obs, terms, groups)
        before = np.array([e.collisions_counted for e in episodes])
        t_start = np.array([e.t_start for e in episodes])
        finished = np.array([e.sim.finished for e in episodes])
        o = outcomes(terms, before, t_start, finished, lane_end_ends=episodes[0].lane_end_ends,
                     max_time=self.options.max_episode_time)  # fmt: skip
        firsts = self._begin(restart, [new[k] for k in restart], drawn=True)
        for k in np.flatnonzero(going).tolist():
            episode = episodes[k]
            episode.obs[:], episode.group = obs[k], groups[k]
            episode.record(terms[k], bool(o.terminated[k] or o.timeout[k]))
        terminated, truncated = o.terminated & going, o.timeout & going
        reward = step_rewards(terms, o.crashed & going, truncated, self.options.reward,
                              self.options.action_period)  # fmt: skip
        reward[restart] = 0.0  # a restarting sub-environment's first observation
        if restart:
            obs[restart] = np.stack(firsts)
        self._ended = terminated | truncated
        info = {"merged": o.merged, "collision": o.collision, "lane_end": o.lane_end,
                "timeout": o.timeout}  # fmt: skip
        seeds = np.array([e.seed for e in self._current()])
        return obs, reward, terminated, truncated, self._step_infos(info, going, seeds)

    def _make_due_twins(self, episodes: list[MergeEpisode], going: np.ndarray) -> None:
        """Make the pending twins of the going episodes that a ramp vehicle might reach the
        acceleration lane in within the coming period (:meth:`MergeEpisode.twin_due`)."""
        pending = going & np.array([e.twin_pending for e in episodes])
        if not pending.any():
            return
        mains, _ = self._lists(episodes)
        due = np.zeros(self.num_envs, dtype=bool)
        twins_due(mains, pending, self.options.action_period, due)
        for k in np.flatnonzero(due).tolist():
            episodes[k].make_due_twin()

    def _settle_twins(
        self, episodes: list[MergeEpisode], going: np.ndarray, targets: list[int]
    ) -> None:
        """After the period: :meth:`MergeEpisode.settle_twin` of the going episodes whose
        twin is pending; the twins it had to simulate anew advance together to the period's
        end."""
        pending = going & np.array([e.twin_pending for e in episodes])
        if not pending.any():
            return
        mains, _ = self._lists(episodes)
        untouched = np.zeros(self.num_envs, dtype=bool)
        ramps_untouched(mains, pending, untouched)
        behind = [k for k in np.flatnonzero(pending).tolist()
                  if episodes[k].settle_twin(bool(untouched[k]))]  # fmt: skip
        advance_ensemble([episodes[k].twin for k in behind], [targets[k] for k in behind],
                         threads=self.threads)  # fmt: skip

    def _current(self) -> list[MergeEpisode]:
        episodes = [e for e in self.episodes if e is not None]
        if len(episodes) != self.num_envs:
            raise RuntimeError("call reset() before step()")
        return episodes

    def _lists(self, episodes: list[MergeEpisode]) -> tuple[List, List]:
        """Compiled lists of the episodes' runs and twins, kept between steps: only the
        places of new episodes are replaced."""
        mains, twins = self._runs.lists(episodes, lambda e: e.sim.core, lambda e: e.twin.core)
        return mains, twins

    @staticmethod
    def _step_infos(
        outcome: dict[str, np.ndarray], going: np.ndarray, seeds: np.ndarray
    ) -> dict[str, Any]:
        """:meth:`_infos` of a step: every sub-environment's episode seed, and the outcome of
        the going ones (a restarted one's step is its new episode's first observation)."""
        out: dict[str, Any] = {"seed": seeds, "_seed": np.ones(seeds.size, dtype=bool)}
        if going.any():
            for key, values in outcome.items():
                out[key], out[f"_{key}"] = np.where(going, values, False), going.copy()
        return {key: out[key] for key in sorted(out, key=_INFO_ORDER.index)}

    def _infos(self, details: list[dict[str, Any]]) -> dict[str, Any]:
        """Gymnasium's vector info layout: one array per key and a ``_key`` mask."""
        out: dict[str, Any] = {}
        for key in _INFO_KEYS:
            mask = np.array([key in d for d in details])
            if mask.any():
                out[key] = np.array([d.get(key, 0) for d in details])
                out[f"_{key}"] = mask
        return out

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Each sub-environment's frame now (``render_mode="rgb_array"``, as
        :meth:`MergeEnv.render`); None without a render mode."""
        if self.render_mode is None:
            return None
        episodes = self._current()
        return tuple(render_frame(e.sim, self.config, e.ego) for e in episodes)

    def episode_logs(self, k: int) -> tuple[Any, Any]:
        """Log and undisturbed reference of sub-environment k's current episode, run to the
        scenario's end (see :meth:`MergeEnv.episode_logs`)."""
        episode = self.episodes[k]
        if episode is None:
            raise RuntimeError("no episode: call reset() first")
        return episode.finish()
