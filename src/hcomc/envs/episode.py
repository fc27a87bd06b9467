"""One environment episode: a run and its undisturbed twin, from the moment the ramp vehicle
VR enters the cooperative control zone until its merge is complete, a crash, or a timeout.

The agent's vehicle (VR, or VMC) is driven through :meth:`Simulation.command` and
:meth:`Simulation.start_lane_change`; everything else is the engine's. The twin is the same
scenario and seed without the ramp vehicle (``counterfactual=True``), advanced in lockstep:
Eq. 17's acceleration changes are measured against it, as the metrics' disturbance measures
are. When the agent drives VR, the twin is made only once a ramp vehicle may reach the
acceleration lane: until then the undisturbed run's mainline is the run's own
(:mod:`hcomc.sim.twin`), so the run stands in for it, with the same rewards bit for bit.
:class:`MergeEpisode` is shared by the single, the vector and the multi-agent environments;
they advance many episodes' runs together with :func:`hcomc.sim.ensemble.advance_ensemble`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.envs.batch import (
    N_TERMS,
    P_A_MERG,
    P_DELAY_CAV,
    P_DELAY_HDV,
    P_FUEL,
    P_LOG_DT,
    P_MIN_DIST,
    P_PERIOD,
    T_COLLISIONS,
    T_EFFICIENCY,
    T_FUEL,
    T_ROWS,
    T_SAFETY,
    T_TIME,
    apply_one,
    step_terms,
)
from hcomc.envs.observation import N_OBS, SafetyParams, Scene, observe, pair_safety
from hcomc.envs.options import EnvOptions
from hcomc.envs.reward import fuel_over_rows, gain_over_rows
from hcomc.envs.scoring import outcomes, parameters, rewards
from hcomc.road import Kind, Lane
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.step.ramp_reach import ramp_may_reach, ramp_untouched
from hcomc.sim.twin import can_twin, undisturbed_twin

_END = np.iinfo(np.int64).max


def apply_action(sim: Simulation, params: np.ndarray, i: int, action: np.ndarray) -> None:
    """Drive vehicle i with an action of the environments' action space.

    ``action[0]`` in [-1, 1] is the acceleration as a fraction of the vehicle's maximum
    acceleration (> 0) or of the emergency deceleration (< 0); ``action[1] > 0`` starts a lane
    change unless one is under way: from the acceleration lane (only between its start and
    end) into lane 1, from a main lane to the other. ``params``: :func:`scoring.parameters`.
    """
    apply_one(sim.core, i, float(action[0]), float(action[1]), params)


class NoVMCError(RuntimeError):
    """The agent drives VMC, and VR has none when it enters the control zone (no mainline
    vehicle to merge in front of): this seed's run has no episode for the agent."""


@dataclass(frozen=True, slots=True)
class Outcome:
    """How one environment step ended for one episode."""

    terminated: bool
    truncated: bool
    crashed: bool
    info: dict[str, object]


@dataclass(frozen=True, slots=True)
class StepResult:
    """What one environment step returns for one episode."""

    obs: np.ndarray
    reward: float
    terminated: bool
    truncated: bool
    info: dict[str, object]


def _rows(cells: Any, r0: int, r1: int, i: int) -> np.ndarray:
    """Vehicle i's cells of one (T, N) log array over rows ``[r0, r1)``, as float64."""
    return np.asarray(cells[r0:r1, i], dtype=np.float64)


class MergeEpisode:
    """One episode of ``options`` with ``seed``; call :meth:`start` (or let a batch advance
    :attr:`sim` until its key vehicles, then :meth:`begin`).

    ``defer_twin`` (default: when the agent drives VR) lets :attr:`sim` stand in for the
    twin while no ramp vehicle can have reached the acceleration lane (:attr:`twin_pending`);
    an environment whose agents drive mainline vehicles must not defer it.
    """

    def __init__(
        self, options: EnvOptions, config: ScenarioConfig, seed: int, *,
        defer_twin: bool | None = None,
    ) -> None:  # fmt: skip
        self.options, self.config, self.seed = options, config, int(seed)
        self.sim = Simulation(config, seed)
        self.twin: Simulation = self.sim  # set by make_twin()
        self.twin_pending = False  # sim stands in for the twin (see make_twin)
        driven_vr = options.controller is None and options.agent == "vr"
        self.defer_twin = driven_vr if defer_twin is None else defer_twin
        self._checked_collisions = 0  # collisions when the pending twin was last checked
        self.period_steps = round(options.action_period / config.dt)
        self.is_cav = self.sim.fleet.kind == Kind.CAV
        self.obs = np.zeros(N_OBS, dtype=np.float32)
        self.vr = self.ego = -1
        self.group = np.full(6, -1, dtype=np.int64)
        self.t_start = math.nan
        self.rows_scored = 0  # log rows whose terms are in the rewards so far
        self._events = self._collisions = 0
        self.ramp = self.sim.demand.lane == Lane.RAMP
        self.kernel_params = parameters(config, options.action_period)
        self.done = False

    # ----------------------------------------------------------------- start
    def start(self) -> np.ndarray:
        """Run to VR's control-zone entry and return the first observation (one episode)."""
        self.sim.run_to(_END, until_key_vehicles=True)
        if self.make_twin():
            self.twin.run_to(self.sim.step_index)
        return self.begin()

    def make_twin(self) -> bool:
        """The undisturbed twin, once :attr:`sim` has reached VR's entry: deferred (with
        ``defer_twin``, while :func:`~hcomc.sim.twin.can_twin` holds), else copied from its
        state (:func:`~hcomc.sim.twin.undisturbed_twin`) when that is exact, else a new
        undisturbed run; True when the twin must still be advanced to :attr:`sim`'s step."""
        if self.defer_twin and can_twin(self.sim):
            self.twin, self.twin_pending = self.sim, True
            self._checked_collisions = self.sim.collisions
            return False
        return self._twin_now()

    def _twin_now(self) -> bool:
        """:meth:`make_twin` without deferring it."""
        self.twin_pending = False
        try:
            self.twin = undisturbed_twin(self.sim)
            return False
        except ValueError:  # a ramp vehicle already interacts with the mainline
            self.twin = Simulation(self.config, self.seed, counterfactual=True)
            return True

    def twin_due(self) -> bool:
        """Whether the pending twin must be made before the next period: a ramp vehicle
        might reach the acceleration lane within it
        (:func:`~hcomc.sim.step.ramp_reach.ramp_may_reach`)."""
        return self.twin_pending and ramp_may_reach(self.sim.core, self.options.action_period)

    def make_due_twin(self) -> None:
        """Make the pending twin now (copied from :attr:`sim`'s state: the check after the
        last period passed)."""
        if self._twin_now():
            self.twin.run_to(self.sim.step_index)

    def settle_twin(self, untouched: bool) -> bool:
        """After a period with the twin pending (``untouched``:
        :func:`~hcomc.sim.step.ramp_reach.ramp_untouched` of :attr:`sim` now): keep it pending while
        :func:`~hcomc.sim.twin.can_twin` still holds, which makes the period's rows of
        :attr:`sim` those of the undisturbed run; else simulate the twin anew (True: it must
        be advanced to :attr:`sim`'s step before the period's terms are read)."""
        s = self.sim
        new_collision = s.collisions != self._checked_collisions
        if untouched and not s.finished and (not new_collision or can_twin(s)):
            self._checked_collisions = s.collisions  # none of them involves the ramp
            return False
        self.twin_pending = False
        self.twin = Simulation(self.config, self.seed, counterfactual=True)
        return True

    def run_period(self, target: int) -> None:
        """Advance :attr:`sim` and the twin to step ``target`` (one episode)."""
        self.sim.run_to(target)
        if not self.twin_pending or self.settle_twin(ramp_untouched(self.sim.core)):
            self.twin.run_to(target)

    def begin(self) -> np.ndarray:
        """Pick the agent once :attr:`sim` has identified VR's key vehicles and the twin has
        reached the same step; returns the first observation."""
        group = self.sim.key_group
        made = self.twin_pending or self.twin is not self.sim
        if group is None or not made or self.twin.step_index != self.sim.step_index:
            raise RuntimeError(
                f"seed {self.seed}: no ramp vehicle entered the control zone within the run "
                f"({self.config.duration} s); allowed: a longer 'duration'"
            )
        self.vr = group.vr
        self.ego = group.vr if self.options.agent == "vr" else group.vmc
        if self.ego < 0:
            raise NoVMCError(
                f"seed {self.seed}: VR has no VMC to drive when it enters the control zone"
            )
        self.t_start = self.sim.t
        if self.driven:  # said in the log, for figures and readers of saved episodes
            role = "VR" if self.options.agent == "vr" else "VMC"
            self.sim.log.meta["agent"] = {"role": role, "vehicle": int(self.ego),
                                          "t_start": float(self.t_start)}  # fmt: skip
        self.rows_scored = self.sim.rows_recorded
        self._events = self.sim.log.n_events
        self._collisions = self.sim.collisions
        self._observe()
        return self.obs.copy()

    @property
    def driven(self) -> bool:
        """Whether the agent drives (no controller does)."""
        return self.options.controller is None

    # ------------------------------------------------------------------ step
    def apply(self, action: np.ndarray) -> int:
        """Command the agent's vehicle for the next period (:func:`apply_action`; not used
        when a controller drives VR); returns the step to advance to."""
        if self.twin_due():
            self.make_due_twin()
        if self.driven:
            apply_action(self.sim, self.kernel_params, self.ego, action)
        return self.sim.step_index + self.period_steps

    def evaluate(self) -> StepResult:
        """Observation, reward, end of episode and info after the runs advanced one period."""
        terms = np.empty(N_TERMS)
        self.group = step_terms(self.sim.core, self.twin.core, self.ego, self.vr, self.rows_scored,
                                self.kernel_params, self.obs, terms)  # fmt: skip
        outcome = self.conclude(terms)
        reward = rewards(terms[None, :], np.array([outcome.crashed]),
                         np.array([outcome.truncated]), self.options.reward,
                         self.options.action_period)[0]  # fmt: skip
        return StepResult(self.obs.copy(), float(reward), outcome.terminated,
                          outcome.truncated, outcome.info)  # fmt: skip

    def conclude(self, terms: np.ndarray) -> Outcome:
        """How the step ended, from its terms (:func:`~hcomc.envs.batch.step_terms`); the
        reward is :func:`~hcomc.envs.scoring.rewards` of the terms and this outcome."""
        o = outcomes(
            terms, self._collisions, self.t_start, self.sim.finished,
            lane_end_ends=self.lane_end_ends, max_time=self.options.max_episode_time,
        )  # fmt: skip
        self.record(terms, bool(o.terminated or o.timeout))
        t = float(terms[T_TIME])
        info: dict[str, object] = {
            "t": t, "elapsed": t - self.t_start, "merged": bool(o.merged),
            "collision": bool(o.collision), "lane_end": bool(o.lane_end),
            "timeout": bool(o.timeout), "safety": float(terms[T_SAFETY]),
            "fuel": float(terms[T_FUEL]), "efficiency": float(terms[T_EFFICIENCY]),
            "ego": self.ego, "vr": self.vr, "seed": self.seed,
        }  # fmt: skip
        return Outcome(bool(o.terminated), bool(o.timeout), bool(o.crashed), info)

    def record(self, terms: np.ndarray, done: bool) -> None:
        """Take in a step's terms: the collisions and log rows they counted, and its end."""
        self._collisions, self.rows_scored = int(terms[T_COLLISIONS]), int(terms[T_ROWS])
        self.done = done

    @property
    def lane_end_ends(self) -> bool:
        """Whether VR stuck at the lane end ends the episode as a crash (the agent drives VR;
        a controller or VMC's agent leaves VR to its model, which waits there)."""
        return self.driven and self.options.agent == "vr"

    @property
    def collisions_counted(self) -> int:
        """Collisions counted by the steps so far (a step's new ones are a crash)."""
        return self._collisions

    def _observe(self) -> None:
        self.group = self.observe_into(self.obs, self.ego)

    def observe_into(self, out: np.ndarray, i: int) -> np.ndarray:
        """Write vehicle i's observation (:func:`~hcomc.envs.observation.observe`) into
        ``out``; returns the key vehicles around VR."""
        return observe(out, self.scene(), i, self.vr, self.config.road.accel_lane_end)

    def scene(self) -> Scene:
        """The vehicles of :attr:`sim` as the observation's kernels read them."""
        s = self.sim
        return Scene(s.x, s.v, s.lane, s.active, self.is_cav, s.fleet.length, s.origin,
                     s.target, s.lc_x0, s.lc_xf)  # fmt: skip

    # ------------------------------------------------- pieces of every reward
    def merged(self) -> bool:
        """Whether VR's merge into lane 1 is complete."""
        s, vr = self.sim, self.vr
        return bool(s.lane[vr] == Lane.MAIN_1 and s.origin[vr] == s.target[vr])

    def at_lane_end(self) -> bool:
        """Whether VR is still on the acceleration lane at (or past) its end."""
        s, vr = self.sim, self.vr
        return bool(
            s.lane[vr] == Lane.RAMP
            and s.origin[vr] == s.target[vr]
            and s.x[vr] >= self.config.road.accel_lane_end
        )

    def out_of_time(self) -> bool:
        """Whether the episode has lasted ``max_episode_time`` or the run has ended."""
        elapsed = self.sim.t - self.t_start
        return elapsed >= self.options.max_episode_time - 1e-9 or self.sim.finished

    def collided(self) -> np.ndarray:
        """Vehicles in a collision that began since the last call (sorted, unique)."""
        if self.sim.collisions == self._collisions:
            return np.empty(0, dtype=np.int64)
        self._collisions = self.sim.collisions
        events = self.sim.log.events_since(self._events)
        self._events = self.sim.log.n_events
        hit = events[events["kind"] == EventKind.COLLISION]
        return np.unique(np.concatenate([hit["vehicle"], hit["other"]]))

    def new_rows(self) -> tuple[int, int]:
        """Log rows recorded since the last call: ``[r0, r1)``."""
        rows = self.sim.rows_recorded
        r0, self.rows_scored = self.rows_scored, rows
        return r0, rows

    # Each agent's own terms (the multi-agent environment), from the parameters and kernels
    # that step_terms uses for the single agent.
    def safety_of(self, i: int) -> float:
        """Eq. 15 over vehicle i's pairs now, normalised, times the action period [s]."""
        p = self.kernel_params
        safety = SafetyParams(p[P_DELAY_CAV], p[P_DELAY_HDV], p[P_MIN_DIST], p[P_A_MERG])
        return p[P_PERIOD] * pair_safety(self.scene(), i, safety)

    def fuel_of(self, i: int, r0: int, r1: int) -> float:
        """Eq. 16: vehicle i's fuel over log rows ``[r0, r1)`` [mL] (0 for i < 0)."""
        if i < 0 or r1 <= r0:
            return 0.0
        log, p = self.sim.log, self.kernel_params
        return fuel_over_rows(_rows(log.v, r0, r1, i), _rows(log.a, r0, r1, i), p[P_LOG_DT],
                              p[P_FUEL:])  # fmt: skip

    def gain_of(self, i: int, r0: int, r1: int) -> float:
        """Eq. 17's ``a_new - a_ori`` of vehicle i integrated over log rows ``[r0, r1)``
        [m/s]: against the undisturbed run, or for a ramp vehicle (absent there) against its
        model on a free road (0 for i < 0)."""
        if i < 0 or r1 <= r0:
            return 0.0
        s = self.sim
        return gain_over_rows(
            _rows(s.log.v, r0, r1, i), _rows(s.log.a, r0, r1, i),
            _rows(self.twin.log.a, r0, r1, i), self.kernel_params[P_LOG_DT],
            bool(self.ramp[i]), s.arrays.matrix[:, i], bool(s.arrays.iidm[i]),
        )  # fmt: skip

    # ------------------------------------------------------------------ end
    def finish(self) -> tuple[SimulationLog, SimulationLog]:
        """Hand the agent's vehicle back to its model, run both runs to their end and return
        ``(log, reference)`` for :func:`hcomc.metrics.compute_metrics`."""
        if self.ego >= 0 and self.driven:
            self.sim.command(self.ego, math.nan)
        if self.twin_pending:
            self._twin_now()  # copied, or simulated anew by run_to below
        self.sim.run_to(_END)
        self.twin.run_to(_END)
        return self.sim.log, self.twin.log


SEED_TRIES = 100
"""Drawn seeds an environment tries in a row for one episode before it gives up (a seed whose
VR has no VMC, when the agent drives VMC, is skipped)."""


def start_drawn(
    options: EnvOptions, config: ScenarioConfig, draw: Callable[[], int]
) -> tuple[MergeEpisode, np.ndarray]:
    """A started episode (and its first observation) on the next drawn seed that has one for
    the agent: seeds whose VR has no VMC are skipped when the agent drives VMC."""
    for _ in range(SEED_TRIES):
        episode = MergeEpisode(options, config, draw())
        try:
            return episode, episode.start()
        except NoVMCError:
            continue
    raise NoVMCError(
        f"{SEED_TRIES} drawn seeds in a row: VR has no VMC when it enters the control zone; "
        "allowed: agent 'vr', or a scenario with mainline traffic beside the ramp"
    )


__all__ = ["MergeEpisode", "NoVMCError", "Outcome", "StepResult", "apply_action", "start_drawn"]
