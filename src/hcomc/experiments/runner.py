"""Run grids of conditions x configurations x seeds, locally in parallel, into one table.

A *configuration* is a merge controller with its optimiser: the paper's five (FIFO, Game,
HCOMC with NSGA-II, PSO or SA; all plan once, at VR's control-zone entry, as Section III
publishes them), their variants that replan every second ("FIFO-R", "Game-R", "HCOMC-R", not
in the paper), the labelled extension "HCOMC+", HCOMC with the lane-change game's
equilibrium alone admitting lateral cooperation ("HCOMC-eq"), or any controller named as
:mod:`hcomc.control.registry` accepts (a researcher's own). Every run is ``run_one(spec)``:
a pure function of its spec (condition preset or TOML file, configuration, seed, overrides)
that returns one results row and the run's manifest. Seeds are shared across configurations
within a condition (common random numbers: the same traffic for every controller), so
comparisons are paired by seed.

Every run is measured against its undisturbed counterpart: the same condition, overrides and
seed simulated without releasing the ramp vehicle (:mod:`hcomc.metrics`). That run does not
depend on the controller, so it is simulated once per (condition, seed, non-control
overrides) and cached in the worker process. Metrics use the key vehicles the engine fixed
when VR entered the control zone, before any control acted, so every configuration is
measured on the same vehicles. The row order follows the spec order, whatever the number of
workers, so tables are identical for 1 or N workers.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import as_completed
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from hcomc.config import ScenarioConfig, load_config
from hcomc.config.impairment_tables import fault_entries
from hcomc.control.registry import canonical_name, controller_source
from hcomc.experiments.pool import local_pool
from hcomc.experiments.results_row import run_columns
from hcomc.interface import Engine
from hcomc.sim.log import SimulationLog

CONFIGURATIONS: dict[str, tuple[str, str]] = {
    "FIFO": ("fifo", "nsga2"),
    "Game": ("game", "nsga2"),
    "HCOMC": ("hcomc", "nsga2"),
    "HCOMC-PSO": ("hcomc", "pso"),
    "HCOMC-SA": ("hcomc", "sa"),
}
"""The paper's configurations: label -> (controller, optimiser); the optimiser only matters
for HCOMC."""

REPLANNING: dict[str, tuple[str, str]] = {
    "FIFO-R": ("fifo", "nsga2"),
    "Game-R": ("game", "nsga2"),
    "HCOMC-R": ("hcomc", "nsga2"),
}
"""FIFO, Game and HCOMC replanning every second over a receding horizon until VR starts its
lane change (a labelled extension: the paper plans once)."""

EXTENSIONS: dict[str, tuple[str, str]] = {"HCOMC+": ("hcomc", "nsga2")}
"""Labelled extensions of HCOMC, reported beside the faithful method (not in the paper):
HCOMC+ may also choose to leave the mainline alone (``control.no_cooperation``)."""

EQUILIBRIUM_ONLY: dict[str, tuple[str, str]] = {"HCOMC-eq": ("hcomc", "nsga2")}
"""HCOMC whose lateral cooperation only the lane-change game's equilibrium admits
(``control.lateral_safety_rule`` false): the paper's game without the safety rule HCOMC adds,
run beside HCOMC so that what rests on the rule is seen (no claims of its own)."""

ALL_CONFIGURATIONS: dict[str, tuple[str, str]] = {
    **CONFIGURATIONS,
    **REPLANNING,
    **EXTENSIONS,
    **EQUILIBRIUM_ONLY,
}
"""Every configuration label ``run_one`` accepts."""

CONTROL_OVERRIDES: dict[str, dict[str, Any]] = {
    **{label: {"replan_period": 0.0} for label in CONFIGURATIONS},
    **{label: {"replan_period": 1.0} for label in REPLANNING},
    "HCOMC+": {"replan_period": 0.0, "no_cooperation": True},
    "HCOMC-eq": {"replan_period": 0.0, "lateral_safety_rule": False},
}
"""``control`` values a configuration sets beyond its controller and optimiser: the paper's
configurations, HCOMC+ and HCOMC-eq plan once, as published (``replan_period = 0``), the -R
variants replan every second; HCOMC+ adds the mode "none"; HCOMC-eq drops the added safety
rule of the lateral gate."""


def configuration_label(name: str) -> str:
    """The configuration ``name`` stands for: a label of :data:`ALL_CONFIGURATIONS`
    (case-insensitive: ``fifo`` is FIFO, planning once as published), else a controller name
    (:mod:`hcomc.control.registry`: registered, ``package.module:Class`` or
    ``path/to/file.py:Class``) that is a configuration of its own: that controller with the
    config's control values. ConfigError if it is neither."""
    for label in ALL_CONFIGURATIONS:
        if label.lower() == name.lower():
            return label
    return canonical_name(name)


def configuration_of(control: Mapping[str, Any]) -> str:
    """The configuration label a ``[control]`` table's controller and optimiser stand for
    (``fifo`` is FIFO, planning once as published; HCOMC with PSO is HCOMC-PSO), else the
    controller's name: what ``hcomc run`` and :func:`hcomc.run` run."""
    labels = {pair: label for label, pair in CONFIGURATIONS.items()}
    name = control["controller"]
    return labels.get((name, control["optimizer"] if name == "hcomc" else "nsga2"), name)


def configuration_controller(configuration: str) -> tuple[str, str]:
    """(controller, optimiser) of a configuration label; the optimiser is "" unless the
    controller is HCOMC's."""
    controller, optimizer = ALL_CONFIGURATIONS.get(configuration, (configuration, ""))
    return controller, optimizer if controller == "hcomc" else ""


def configuration_overrides(configuration: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """``overrides`` (nested, as :func:`hcomc.config.nest_overrides` gives them) with the
    controller, optimiser and control values of a configuration label: what every run of
    that configuration is loaded with (:meth:`RunSpec.config_overrides`, the report's
    figures). A controller name of its own (:func:`configuration_label`) sets the controller
    alone."""
    if configuration in ALL_CONFIGURATIONS:
        controller, optimizer = ALL_CONFIGURATIONS[configuration]
        own = {"controller": controller, "optimizer": optimizer}
    else:
        own = {"controller": configuration}
    control = {
        **overrides.get("control", {}),
        **CONTROL_OVERRIDES.get(configuration, {}),
        **own,
    }
    return {**overrides, "control": control}


ENGINES = ("hcomc", "sumo")
"""Simulation engines: our own, or SUMO co-simulation (optional extra ``hcomc[sumo]``)."""


@dataclass(frozen=True)
class RunSpec:
    """One run: a condition (preset or TOML path), a configuration, a seed and an engine."""

    condition: str
    configuration: str
    seed: int
    overrides: dict[str, Any] = field(default_factory=dict, hash=False)
    engine: str = "hcomc"

    def config_overrides(self) -> dict[str, Any]:
        """Top-level config overrides, with the configuration's controller and optimiser."""
        return configuration_overrides(self.configuration, self.overrides)

    def reference_key(self) -> tuple[str, int, str]:
        """What the undisturbed run depends on: condition, seed, the overrides of neither the
        controller nor the impairments (the undisturbed run has no ramp vehicle to control or
        to time a fault from, and no listeners), except the stalled vehicles among the faults:
        they are vehicles of the run (:mod:`hcomc.sim.stalled`), which its undisturbed run has
        too, so that both logs have the same vehicle columns."""
        rest = {k: v for k, v in self.overrides.items() if k not in _NOT_UNDISTURBED}
        stalled = [f for f in fault_entries(list(self.overrides.get("faults", ())))
                   if dict(f).get("kind") == "stalled_vehicle"]  # fmt: skip
        if stalled:
            rest["faults"] = stalled
        return self.condition, self.seed, json.dumps(rest, sort_keys=True, default=str)


_NOT_UNDISTURBED = frozenset({"control", "v2x", "faults", "shield"})
"""Override tables an undisturbed run does not depend on."""


def grid(
    conditions: Iterable[str],
    configurations: Iterable[str],
    seeds: Iterable[int],
    overrides: dict[str, Any] | None = None,
) -> list[RunSpec]:
    """The cartesian product, ordered condition, configuration, seed."""
    seeds = list(seeds)
    return [
        RunSpec(cond, conf, seed, dict(overrides or {}))
        for cond in conditions
        for conf in configurations
        for seed in seeds
    ]


def make_simulation(
    config: ScenarioConfig,
    seed: int | None = None,
    engine: str = "hcomc",
    *,
    counterfactual: bool = False,
) -> Engine[SimulationLog]:
    """A run of ``config`` on the named engine (SUMO is imported only when asked for), with
    the listeners of its ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables
    (:func:`hcomc.robustness.impairments.listeners_of`); ``counterfactual``: the undisturbed
    run, the ramp vehicle never released, without them."""
    from hcomc.robustness.impairments import listeners_of

    listeners = [] if counterfactual else listeners_of(config)
    if engine == "sumo":
        from hcomc.sumo.cosim import SumoSimulation

        return SumoSimulation(config, seed, counterfactual=counterfactual, listeners=listeners)
    if engine != "hcomc":
        raise ValueError(f"engine '{engine}'; allowed: {', '.join(ENGINES)}")
    from hcomc.sim.engine import Simulation

    return Simulation(config, seed, counterfactual=counterfactual, listeners=listeners)


_REFERENCES: dict[tuple[str, int, str, str], SimulationLog] = {}
"""Undisturbed runs of this process, by (condition, seed, non-control overrides, engine)."""
_MAX_REFERENCES = 128


def _reference_key(spec: RunSpec) -> tuple[str, int, str, str]:
    return (*spec.reference_key(), spec.engine)


def _remember(key: tuple[str, int, str, str], log: SimulationLog) -> None:
    _REFERENCES[key] = log
    while len(_REFERENCES) > _MAX_REFERENCES:  # forget the oldest
        del _REFERENCES[next(iter(_REFERENCES))]


def _reference_simulation(spec: RunSpec) -> Engine[SimulationLog]:
    condition, seed, overrides_json, engine = _reference_key(spec)
    config = load_config(condition, **json.loads(overrides_json))
    return make_simulation(config, seed, engine, counterfactual=True)


def undisturbed_log(spec: RunSpec) -> SimulationLog:
    """The undisturbed counterpart of ``spec``'s run (same condition, seed, overrides and
    engine), simulated once per process."""
    key = _reference_key(spec)
    if key not in _REFERENCES:
        _remember(key, _reference_simulation(spec).run())
    return _REFERENCES[key]


def run_one(spec: RunSpec) -> tuple[dict[str, Any], dict[str, Any]]:
    """Simulate one run and compute its metrics: ``(row, manifest)``."""
    return run_batch([spec])[0]


def run_batch(
    specs: Sequence[RunSpec], *, threads: int | None = None
) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """Simulate runs as one batch and compute their metrics: ``(row, manifest)`` per spec.

    The runs, with the undisturbed runs they need that this process has not simulated yet,
    run by :func:`hcomc.interface.run_all`: those of our engine together as one ensemble (on
    ``threads`` cores; each run's result is bit-identical to running it alone), SUMO runs one
    after the other. ``wall_s`` is each run's share of the batch's time.
    """
    from hcomc.interface import run_all

    start = time.perf_counter()
    configs = [load_config(spec.condition, **spec.config_overrides()) for spec in specs]
    sims = [make_simulation(c, s.seed, s.engine) for c, s in zip(configs, specs, strict=True)]
    missing: dict[tuple[str, int, str, str], Engine[SimulationLog]] = {}
    for spec in specs:
        key = _reference_key(spec)
        if key not in _REFERENCES and key not in missing:
            missing[key] = _reference_simulation(spec)
    run_all([*sims, *missing.values()], threads=threads)
    for key, sim in missing.items():
        _remember(key, sim.log)
    share = (time.perf_counter() - start) / max(len(specs), 1)
    return [
        _measure(spec, config, sim, share)
        for spec, config, sim in zip(specs, configs, sims, strict=True)
    ]


def _measure(
    spec: RunSpec, config: ScenarioConfig, sim: Engine[SimulationLog], wall: float
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The results row (:func:`~hcomc.experiments.results_row.run_columns`, the metrics against
    the undisturbed run, the time taken) and manifest of a finished run."""
    from hcomc.metrics import compute_metrics, key_window
    from hcomc.robustness.impairments import impairment_columns, impairments_in

    log = sim.log
    start = time.perf_counter()
    controller, optimizer = configuration_controller(spec.configuration)
    row = run_columns(
        sim, condition=config.name, configuration=spec.configuration, controller=controller,
        optimizer=optimizer, seed=spec.seed,
    )  # fmt: skip
    window = key_window(log)
    row["key_vehicles"] = " ".join(str(i) for i in window.key_vehicles.tolist())
    row.update(compute_metrics(log, window, reference=undisturbed_log(spec)))
    row.update(impairment_columns(impairments_in(sim.listeners)))
    if config.demand.ramp == "flow":
        from hcomc.metrics.flow import ramp_delay, throughput

        row.update(throughput=throughput(log), ramp_delay=ramp_delay(log), plans=len(sim.decisions))
    row["wall_s"] = wall + time.perf_counter() - start
    manifest = {
        **log.meta,
        "run": {
            "condition": spec.condition,
            "configuration": spec.configuration,
            "seed": spec.seed,
            "overrides": spec.overrides,
            "engine": spec.engine,
        },
        "controller": controller_source(config.control.controller),
    }
    return row, manifest


def batches(n: int, size: int) -> list[list[int]]:
    """Indices 0..n-1 in consecutive chunks of at most ``size``."""
    size = max(1, size)
    return [list(range(k, min(k + size, n))) for k in range(0, n, size)]


def batches_by_reference(specs: Sequence[RunSpec], size: int) -> list[list[int]]:
    """Indices of ``specs`` in chunks of at most ``size``, runs that share an undisturbed run
    next to each other (in spec order otherwise), so that a worker process simulates each
    undisturbed run once for all of its configurations instead of once per chunk it meets."""
    order = sorted(range(len(specs)), key=lambda i: _reference_key(specs[i]))
    return [[order[k] for k in chunk] for chunk in batches(len(order), size)]


def run_grid(
    specs: Sequence[RunSpec],
    *,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    on_result: Callable[[int, dict[str, Any], dict[str, Any]], None] | None = None,
    batch_size: int = 16,
    after: Sequence[Callable[[], Any]] = (),
    on_after: Callable[[int, Any], None] | None = None,
) -> pd.DataFrame:
    """Run every spec (in ``workers`` processes, ``batch_size`` runs per ensemble) and return
    the rows in spec order.

    ``after`` holds other tasks (picklable, without arguments, e.g. a report figure) queued
    behind the runs: a worker process with no run left takes one while the others finish
    their last runs, instead of the caller doing it alone afterwards. Task ``i``'s result
    goes to ``on_after(i, result)``; a task that raises hands its exception instead, so that
    the runs' rows are returned (and can be saved) either way. With one worker they run after
    the runs.
    """
    rows: list[dict[str, Any] | None] = [None] * len(specs)
    done = 0

    def collect(i: int, result: tuple[dict[str, Any], dict[str, Any]]) -> None:
        nonlocal done
        rows[i] = result[0]
        done += 1
        if on_result is not None:
            on_result(i, *result)
        if progress is not None:
            progress(done, len(specs))

    def deliver(i: int, result: Any) -> None:
        if on_after is not None:
            on_after(i, result)

    chunks = batches_by_reference(specs, batch_size)
    if workers <= 1:
        for chunk in chunks:
            for i, result in zip(chunk, run_batch([specs[i] for i in chunk]), strict=True):
                collect(i, result)
        for i, task in enumerate(after):
            try:
                outcome: Any = task()
            except Exception as failure:  # handed to the caller, as from a worker
                outcome = failure
            deliver(i, outcome)
    else:  # one core per worker process: the processes share the cores
        with local_pool(workers) as pool:
            futures = {
                pool.submit(run_batch, [specs[i] for i in chunk], threads=1): chunk
                for chunk in chunks
            }
            tasks = {pool.submit(task): i for i, task in enumerate(after)}  # queued last
            for future in as_completed(futures):
                for i, result in zip(futures[future], future.result(), strict=True):
                    collect(i, result)
            for task_done in as_completed(tasks):
                raised = task_done.exception()
                deliver(tasks[task_done], task_done.result() if raised is None else raised)
    return pd.DataFrame(rows)
