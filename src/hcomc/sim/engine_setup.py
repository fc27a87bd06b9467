"""A run of the engine as it is set up: scenario, seed, random streams, demand, fleet,
controller, the compiled state arrays, the log, and the counters read from them.

:class:`EngineSetup` draws the demand and builds everything a run of
:class:`hcomc.sim.engine.Simulation` starts from (:mod:`hcomc.sim.step.build`), or builds it on
another run's demand, fleet and controller (:meth:`EngineSetup._sibling`: the undisturbed twin
of :mod:`hcomc.sim.twin`). Advancing the run is :class:`~hcomc.sim.engine.Simulation`'s.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any, Self

import numpy as np

from hcomc._typing import IntArray
from hcomc.config import ScenarioConfig
from hcomc.interface import MergeController, MergeGroup, MergePlan, TrafficView
from hcomc.interface.listener import StepListener
from hcomc.rng import make_rng
from hcomc.road import Kind
from hcomc.sim.perception_state import Perception
from hcomc.sim.roads import ramps_of
from hcomc.sim.scene import Scene, SceneMaker, paper_scene
from hcomc.sim.stalled import blocked_lanes, place_stalled, with_stalled
from hcomc.sim.step import state as layout
from hcomc.sim.step.build import allocate_log, build_arrays
from hcomc.sim.step.state import Core

__all__ = ["EngineSetup"]


class EngineSetup:
    """One run of a scenario with one seed, set up (its parameters are those of
    :class:`hcomc.sim.engine.Simulation`, the class to use)."""

    def __init__(
        self,
        config: ScenarioConfig,
        seed: int | None = None,
        controller: MergeController | None = None,
        *,
        counterfactual: bool = False,
        listeners: Sequence[StepListener] = (),
        scene: SceneMaker = paper_scene,
    ) -> None:
        seed = config.seed if seed is None else seed
        rng = make_rng(seed)
        drawn, stalled = with_stalled(scene(config, rng), config)
        if controller is None:
            from hcomc.control.registry import make_controller

            controller = make_controller(config)
        self._build(config, seed, rng, drawn, stalled, controller, counterfactual)
        self.listeners: tuple[StepListener, ...] = tuple(listeners)
        for listener in self.listeners:
            listener.attach(self)  # type: ignore[arg-type]  # Simulation is a ListenedRun
        # nobody in Python waits for key groups: the compiled loop records them itself
        compiled = self.controller is None and not self.listeners
        self.arrays.flags[layout.KEYS_COMPILED] = compiled

    @classmethod
    def _sibling(cls, sim: Self, *, counterfactual: bool) -> Self:
        """The run of ``sim``'s scenario and seed at step 0, built on the demand, fleet and
        controller ``sim`` drew (shared, read-only) instead of drawing them again: its
        generator resumes where ``sim``'s stood after the demand draw. It has no listeners."""
        rng = make_rng(sim.seed)
        rng.bit_generator.state = sim._after_demand
        new = cls.__new__(cls)
        new._build(sim.config, sim.seed, rng, sim.scene, sim.stalled, sim.controller,
                   counterfactual)  # fmt: skip
        return new

    def _build(
        self, config: ScenarioConfig, seed: int, rng: np.random.Generator, scene: Scene,
        stalled: IntArray, controller: MergeController | None, counterfactual: bool,
    ) -> None:  # fmt: skip
        self.config, self.seed, self.rng, self.dt = config, seed, rng, config.dt
        self.scene, self.lanes = scene, scene.lanes
        self.ramps = ramps_of(scene.lanes)  # the road as built, which the controllers see
        self.stalled = stalled  # stalled vehicles (hcomc.sim.stalled), the last indices
        demand, fleet = scene.demand, scene.fleet
        self._after_demand = rng.bit_generator.state  # for _sibling
        self.counterfactual = counterfactual
        self.demand, self.fleet, self.controller = demand, fleet, controller
        self.listeners = ()
        self._key_groups: dict[int, MergeGroup] = {}  # per VR, found at control-zone entry
        self._keys_taken = 0  # rows of the compiled loop's key table taken into it
        self.python_steps = 0  # steps taken in Python (decision events)
        self.decisions: list[MergePlan] = []
        self.requests: list[tuple[TrafficView, MergeGroup]] = []  # what each plan was asked
        self.is_hdv = demand.kind == Kind.HDV
        self.is_hdv[stalled] = False  # it perceives nothing: it stands
        self.perception = Perception(config.hdv, self.is_hdv, self.dt, rng)
        self.n_warmup = round(config.warmup / self.dt)
        self.n_steps = round(config.duration / self.dt)
        self._log_every = round(config.log_interval / self.dt)
        self._decide_every = max(1, round(config.lane_change.decision_interval / self.dt))
        self.log = allocate_log(config, seed, demand, fleet, self.n_steps // self._log_every + 1)
        if stalled.size:
            self.log.meta["stalled"] = stalled.tolist()
        # the engine drives with its own copy of the parameters (``driving``, which a listener
        # may change); ``fleet`` stays what the controllers know
        self.driving = dataclasses.replace(fleet, matrix=fleet.matrix.copy())
        engine_lanes = blocked_lanes(self.lanes, demand, fleet, stalled,
                                     config.lane_change.min_gap)  # fmt: skip
        self.arrays = build_arrays(
            config, engine_lanes, demand, scene.release_last, self.driving, self.perception,
            self.log,
            counterfactual=counterfactual, controlled=controller is not None,
            n_warmup=self.n_warmup, decide_every=self._decide_every, log_every=self._log_every,
        )  # fmt: skip
        place_stalled(self.arrays, stalled, counterfactual=counterfactual)
        # the kernels see the same arrays through one compiled reference, typed as its fields
        self.core: Any = Core(self.arrays)
        c = self.arrays  # the state arrays, by name
        self.x, self.y, self.v, self.a, self.heading = c.x, c.y, c.v, c.a, c.heading
        self.lane, self.origin, self.target = c.lane, c.origin, c.target
        self.lc_t0, self.lc_x0, self.lc_xf, self.lc_dur = c.lc_t0, c.lc_x0, c.lc_xf, c.lc_dur
        self.active, self.waited, self.planned = c.active, c.waited, c.planned
        self._stage = 0

    @property
    def key_groups(self) -> dict[int, MergeGroup]:
        """Each ramp vehicle's key group, found when it entered the control zone (in Python
        at a decision step, or by the compiled loop: :meth:`take_key_groups`), by VR."""
        self.take_key_groups()
        return self._key_groups

    def take_key_groups(self) -> None:
        """Move the key groups the compiled loop recorded since the last call
        (:func:`hcomc.sim.step.loop.record_key_group`) into :attr:`key_groups` and the log's
        ``meta["key_groups"]``, as the Python side records them: at the time of the step,
        in order."""
        found = int(self.arrays.counters[layout.N_KEYS])
        for row in self.arrays.key_table[self._keys_taken : found].tolist():
            t = self.time_at(row[0])
            group = MergeGroup(*row[1:])
            self._key_groups[group.vr] = group
            self.log.meta.setdefault("key_groups", []).append({"t": float(t), **group.as_dict()})
        self._keys_taken = found

    @property
    def t(self) -> float:
        """Current simulation time [s]; logging starts at t = 0 after the warm-up."""
        return self.time_at(self.step_index)

    def time_at(self, step: int) -> float:
        """The time [s] of step ``step`` (warm-up included), as :attr:`t` reads it then."""
        return -self.config.warmup + step * self.dt

    @property
    def step_index(self) -> int:
        """Steps simulated so far (warm-up included)."""
        return int(self.arrays.counters[layout.STEP])

    @property
    def collisions(self) -> int:
        """Collisions (pairs coming into contact) so far; each is a COLLISION event."""
        return int(self.arrays.counters[layout.COLLISIONS])

    @property
    def rows_recorded(self) -> int:
        """Log rows written so far (rows ``[0, rows_recorded)`` of :attr:`log` are final)."""
        return int(self.arrays.counters[layout.ROWS])

    @property
    def vehicle_steps(self) -> int:
        """Sum over the steps simulated so far of the vehicles on the road."""
        return int(self.arrays.counters[layout.VEHICLE_STEPS])
