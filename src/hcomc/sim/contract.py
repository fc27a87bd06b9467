"""The engine contract: what every implementation of :class:`hcomc.interface.Engine` promises,
as a function that checks one, the way scikit-learn's ``check_estimator`` checks an estimator.

Experiments, metrics and reports rely on these promises alone, so an engine that passes
:func:`check_engine` runs under all of them. The test suite runs it on our engine
(:class:`hcomc.sim.engine.Simulation`) and on the SUMO co-simulation
(:class:`hcomc.sumo.cosim.SumoSimulation`). Each broken promise is an AssertionError that
names it.

The promises:

1. **Identity**: the engine keeps the scenario and seed it was made with and the controller
   it was given; its state arrays (``x``, ``v``, ``lane``, ``active``) and the fleet's
   per-vehicle constants have one entry per vehicle of the run.
2. **A run**: :meth:`~hcomc.interface.Engine.run` warms up and simulates the scenario's
   duration, reports its progress as ``(done, total)`` ending at ``(total, total)`` with
   ``total = n_warmup + n_steps``, and returns its log, which is ``engine.log``; the clock
   then reads the duration.
3. **A log**: a :class:`~hcomc.sim.log.SimulationLog` of the run's vehicles, one row per
   logging interval from t = 0 to the duration, recording the seed and the scenario in its
   metadata.
4. **Decisions**: every decision is a :class:`~hcomc.interface.MergePlan` with the request
   (view and key vehicles) it answered, in order; the key groups are those of ramp vehicles
   that entered the control zone, the first of them ``key_group``.
5. **Reproducible**: the same scenario and seed give the same log, bit for bit, and the same
   decisions; another seed gives another traffic.
6. **Listeners** (:class:`~hcomc.interface.listener.StepListener`): an engine made with
   ``listeners`` keeps them, attaches each once before its first step, calls ``before_step``
   once before every step from the end of the warm-up on (with the step's time) and
   ``on_key_vehicles`` once per key group; listeners that only watch leave the run as it
   is, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.interface import Engine, MergeController, MergeGroup, MergePlan, TrafficView
from hcomc.interface.listener import ListenedRun, StepListener
from hcomc.sim.log import SimulationLog

__all__ = ["EngineMaker", "check_engine"]


class EngineMaker(Protocol):
    """Makes an engine for a scenario, a seed, a controller (None: the config's) and step
    listeners (an engine class is one: ``Simulation``, ``SumoSimulation``)."""

    def __call__(
        self,
        config: ScenarioConfig,
        seed: int | None = None,
        controller: MergeController | None = None,
        *,
        listeners: Sequence[StepListener] = (),
    ) -> Engine[Any]: ...


class _Watcher(StepListener):
    """A listener that records when it is called and acts on nothing."""

    def __init__(self) -> None:
        self.attached: list[Any] = []
        self.steps: list[tuple[int, float]] = []
        self.groups: list[int] = []

    def attach(self, run: ListenedRun) -> None:
        self.attached.append(run)

    def before_step(self, run: ListenedRun, t: float) -> None:
        self.steps.append((run.step_index, t))

    def on_key_vehicles(self, run: ListenedRun, group: MergeGroup, t: float) -> None:
        self.groups.append(group.vr)


_STATE = ("x", "v", "lane", "active")
"""The state arrays of the protocol, one entry per vehicle."""


def check_engine(make: EngineMaker, config: ScenarioConfig, seed: int = 3) -> None:
    """Check the engine ``make`` builds against every promise of the module docstring, on
    ``config`` (a scenario that names a merge controller and in which a ramp vehicle enters
    the control zone, so that the controller decides) and ``seed``. Runs the scenario four
    times."""
    from hcomc.control.registry import make_controller

    controller = make_controller(config)
    assert controller is not None, "check an engine on a scenario that names a controller"
    engine = make(config, seed, controller)
    _check_identity(engine, config, seed, controller)
    log = _check_run(engine, config)
    _check_log(log, engine, seed)
    _check_decisions(engine)
    _check_reproducible(make, config, seed, engine)
    _check_listeners(make, config, seed, engine)


def _check_identity(
    engine: Engine[Any], config: ScenarioConfig, seed: int, controller: MergeController
) -> None:
    assert engine.config == config, "the engine keeps the scenario it was made with"
    assert engine.seed == seed, f"the engine's seed is {engine.seed}, made with {seed}"
    assert engine.controller is controller, "the engine keeps the controller it was given"
    n = len(engine.fleet.length)
    for name in _STATE:
        shape = np.shape(getattr(engine, name))
        assert shape == (n,), f"{name} has shape {shape}: one entry per vehicle, {n}"
    assert engine.n_warmup >= 0, f"n_warmup = {engine.n_warmup}"
    assert engine.n_steps == round(config.duration / config.dt), (
        f"n_steps = {engine.n_steps} for a duration of {config.duration} s"
    )


def _check_run(engine: Engine[Any], config: ScenarioConfig) -> SimulationLog:
    calls: list[tuple[int, int]] = []
    log = engine.run(lambda done, total: calls.append((done, total)))
    total = engine.n_warmup + engine.n_steps
    assert calls, "run reports its progress"
    assert calls[-1] == (total, total), f"the last progress is {calls[-1]}, not the end"
    assert all(t == total for _, t in calls), "progress counts every step, warm-up included"
    assert [d for d, _ in calls] == sorted(d for d, _ in calls), "progress never goes back"
    assert log is engine.log, "run returns the engine's log"
    assert isinstance(log, SimulationLog), f"the log is a {type(log).__name__}"
    assert math.isclose(engine.t, config.duration, abs_tol=config.dt / 2), (
        f"after the run the clock reads {engine.t} s, not the duration {config.duration} s"
    )
    return log


def _check_log(log: SimulationLog, engine: Engine[Any], seed: int) -> None:
    config = engine.config
    rows = round(config.duration / config.log_interval) + 1
    assert log.n_recorded == rows, f"{log.n_recorded} rows logged, {rows} intervals"
    assert log.n_vehicles == len(engine.fleet.length), "the log holds every vehicle of the run"
    assert log.meta.get("seed") == seed, f"the log records seed {log.meta.get('seed')}"
    scenario = (log.meta.get("config") or {}).get("name")
    assert scenario == config.name, f"the log records the scenario {scenario!r}"
    t = np.asarray(log.t[: log.n_recorded])
    assert t[0] == 0.0, f"the log starts at t = {t[0]}, not at the end of the warm-up"
    assert math.isclose(t[-1], config.duration, abs_tol=config.dt / 2), "the log ends at the end"


def _check_decisions(engine: Engine[Any]) -> None:
    decisions, requests, groups = engine.decisions, engine.requests, engine.key_groups
    assert groups, "a ramp vehicle entered the control zone: its key vehicles are known"
    assert all(isinstance(g, MergeGroup) for g in groups.values()), "key groups are MergeGroups"
    assert engine.key_group == next(iter(groups.values())), "key_group is the first group"
    assert decisions, "the controller decided for the ramp vehicle in the control zone"
    assert len(requests) == len(decisions), "each decision has the request it answered"
    for plan, (view, group) in zip(decisions, requests, strict=True):
        assert isinstance(plan, MergePlan), f"a decision is a {type(plan).__name__}"
        assert isinstance(view, TrafficView), f"a request's view is a {type(view).__name__}"
        assert plan.group.vr == group.vr, "a plan is for the ramp vehicle it was asked about"


def _decision(plan: MergePlan) -> tuple[Any, ...]:
    """What a decision decided: when, for whom, the mode and the merge position (NaN-safe)."""
    merge_x = None if math.isnan(plan.merge_x) else plan.merge_x
    return plan.t0, plan.group.vr, plan.mode, merge_x, plan.fallback


def _check_reproducible(
    make: EngineMaker, config: ScenarioConfig, seed: int, first: Engine[Any]
) -> None:
    from hcomc.control.registry import make_controller

    again = make(config, seed, make_controller(config))
    again.run()
    for name in ("x", "v", "lane", "active"):
        a = np.asarray(getattr(first.log, name))
        b = np.asarray(getattr(again.log, name))
        assert np.array_equal(a, b, equal_nan=True), f"the same seed gives another log ({name})"
    assert [_decision(p) for p in again.decisions] == [_decision(p) for p in first.decisions], (
        "the same seed gives other decisions"
    )
    other = make(config, seed + 1, make_controller(config))
    other.run()
    rows = min(first.log.n_recorded, other.log.n_recorded)
    differ = first.log.n_vehicles != other.log.n_vehicles or not np.array_equal(
        np.asarray(first.log.x[:rows]), np.asarray(other.log.x[:rows]), equal_nan=True
    )
    assert differ, "another seed gives the same traffic"


def _check_listeners(
    make: EngineMaker, config: ScenarioConfig, seed: int, first: Engine[Any]
) -> None:
    from hcomc.control.registry import make_controller

    watcher = _Watcher()
    engine = make(config, seed, make_controller(config), listeners=[watcher])
    assert tuple(engine.listeners) == (watcher,), "the engine keeps the listeners it was given"
    assert watcher.attached == [engine], "each listener is attached once, to its engine"
    engine.run()
    steps = list(range(engine.n_warmup, engine.n_warmup + engine.n_steps))
    called = [k for k, _ in watcher.steps]
    assert called == steps, (
        f"before_step was called at steps {called[:3]}...{called[-3:]} ({len(called)} calls), "
        f"not once before each step from the warm-up's end ({len(steps)})"
    )
    times = np.array([t for _, t in watcher.steps])
    assert np.allclose(times, (np.array(steps) - engine.n_warmup) * config.dt), (
        "before_step is given the time of the step about to be taken"
    )
    assert watcher.groups == list(engine.key_groups), "on_key_vehicles once per key group"
    for name in _STATE:
        a, b = np.asarray(getattr(first.log, name)), np.asarray(getattr(engine.log, name))
        assert np.array_equal(a, b, equal_nan=True), f"a watching listener changed the log ({name})"
    assert [_decision(p) for p in engine.decisions] == [_decision(p) for p in first.decisions], (
        "a watching listener changed the decisions"
    )
