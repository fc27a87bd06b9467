"""Runs on corridors: a corridor (preset or TOML file) as a condition of ``hcomc run``,
``hcomc compare`` and ``hcomc sweep``.

A :class:`CorridorSpec` is the corridor counterpart of :class:`~hcomc.experiments.runner.RunSpec`:
a corridor source with dotted overrides (``corridor.duration=120``), a configuration label of
:data:`~hcomc.experiments.runner.ALL_CONFIGURATIONS` (or a controller name) and a seed. The
configuration sets the corridor's ``[control]`` table exactly as it sets a scenario's
(:func:`~hcomc.experiments.runner.configuration_overrides`: FIFO and Game plan once, their -R
variants replan every second, HCOMC-PSO/SA change the optimiser), so every on-ramp gets that
controller. Seeds are shared across configurations: the same vehicles, departures and driver
draws for every controller (common random numbers).

Where a run goes depends on the corridor (:func:`resolve`):

* a corridor of the paper's layout (``paper``; :func:`hcomc.corridor.engine.scenario_of`
  accepts it) runs in hcomc's scenario engine through the experiment runner, measured with the
  paper's metrics of the first merge against its undisturbed run (and throughput and ramp
  delay, its ramp demand being a flow). The runner loads conditions by file, so the scenario
  is written once as TOML, named by the hash of its text, in a cache folder
  (:func:`scenario_file`);
* any other corridor runs as a corridor
  (:func:`hcomc.metrics.corridor.simulate_corridor`), measured with the corridor metrics
  (:mod:`hcomc.experiments.corridor.metrics`).

Each run returns ``(row, manifest)`` as the runner's do; the manifest records the seed, the
resolved corridor (``corridor``; for a corridor run also ``config``), the version and git
revision, and the controller's source.
"""

from __future__ import annotations

import functools
import hashlib
import json
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hcomc.config import ConfigError, ControlParams, ScenarioConfig, config_to_toml, load_config
from hcomc.corridor import Corridor, load_corridor
from hcomc.experiments.corridor.metrics import corridor_metrics
from hcomc.experiments.runner import (
    RunSpec,
    configuration_controller,
    configuration_overrides,
    run_batch,
)
from hcomc.metrics.corridor.record import CORRIDOR_ENGINE

Result = tuple[dict[str, Any], dict[str, Any]]
"""A run's results row and manifest."""


@dataclass(frozen=True)
class CorridorSpec:
    """One run on a corridor: source (preset or TOML file), configuration, seed, engine, and
    dotted corridor overrides (``{"corridor.duration": 120}``)."""

    condition: str
    configuration: str
    seed: int
    overrides: dict[str, Any] = field(default_factory=dict, hash=False)
    engine: str = "hcomc"

    def overrides_json(self) -> str:
        """The overrides as canonical JSON (what a cache or key hashes)."""
        return json.dumps(self.overrides, sort_keys=True, default=str)


@dataclass(frozen=True)
class Resolved:
    """What a :class:`CorridorSpec` runs: the corridor with the configuration's control table
    and, for a corridor of the paper's layout, the scenario it becomes (with the
    corridor's own control table; the runner adds the configuration's)."""

    corridor: Corridor
    scenario: ScenarioConfig | None

    @property
    def kind(self) -> str:
        """Where the run goes: "scenario" (hcomc's scenario engine, the paper's metrics) or
        "corridor" (a corridor run, corridor metrics)."""
        return "corridor" if self.scenario is None else "scenario"


def with_configuration(corridor: Corridor, configuration: str) -> Corridor:
    """``corridor`` with a configuration's controller, optimiser and control values in its
    ``[control]`` table (as :func:`~hcomc.experiments.runner.configuration_overrides` sets
    them in a scenario's)."""
    nested = configuration_overrides(configuration, {"control": corridor.control.model_dump()})
    return corridor.model_copy(update={"control": ControlParams.model_validate(nested["control"])})


def paper_scenario(corridor: Corridor) -> ScenarioConfig | None:
    """The scenario of a corridor of the paper's layout, with the corridor's control table;
    None for any other corridor (the scenario engine refuses it)."""
    from hcomc.corridor.engine import scenario_of

    try:
        return scenario_of(corridor, control=corridor.control.model_dump())
    except ConfigError:
        return None


@functools.lru_cache(maxsize=1024)  # one load per condition, configuration and overrides
def _resolved(condition: str, configuration: str, overrides: str) -> Resolved:
    corridor = load_corridor(condition, json.loads(overrides))
    return Resolved(with_configuration(corridor, configuration), paper_scenario(corridor))


def resolve(spec: CorridorSpec) -> Resolved:
    """The corridor (and scenario) ``spec`` runs; ConfigError naming a bad key or value."""
    return _resolved(spec.condition, spec.configuration, spec.overrides_json())


def forget() -> None:
    """Drop the resolved corridors of this process (their files may have changed)."""
    _resolved.cache_clear()


def check(spec: CorridorSpec) -> Resolved:
    """Resolve ``spec`` and check that it can run: its engine, its controller and the
    controller's options; ConfigError otherwise, before anything runs."""
    from hcomc.control.registry import check_controller
    from hcomc.sim.corridor_scene import corridor_config

    resolved = resolve(spec)
    corridor = resolved.corridor
    if resolved.scenario is not None:
        check_controller(load_config(_scenario_path(resolved.scenario), **_runner_overrides(spec)))
    elif spec.engine != "hcomc":
        raise ConfigError(
            f"option '--engine' = '{spec.engine}': corridor '{spec.condition}' runs in the "
            "engine as a corridor (it is not of the paper's layout); allowed: hcomc (to run "
            "it in SUMO: hcomc export sumo)"
        )
    else:
        _refuse_scenario_keys(spec, corridor)
        check_controller(corridor_config(corridor))
    return resolved


def _refuse_scenario_keys(spec: CorridorSpec, corridor: Corridor) -> None:
    """ConfigError naming a key only the scenario engine runs (a warm-up, lane flows, a single
    release) in a corridor that engine does not run, with why it does not."""
    from hcomc.corridor.engine import scenario_of, scenario_only

    found = scenario_only(corridor)
    if found is None:
        return
    try:
        scenario_of(corridor)
        why = ""
    except ConfigError as exc:
        why = f": {exc}"
    key, value = found
    raise ConfigError(
        f"corridor '{spec.condition}': key '{key}' = {value!r} runs only in hcomc's scenario "
        f"engine, which does not run this corridor{why}"
    )


def scenario_folder() -> Path:
    """Where the scenarios of paper-layout corridors are written for the runner to load."""
    return Path(tempfile.gettempdir()) / "hcomc-corridor-scenarios"


def scenario_file(scenario: ScenarioConfig, folder: Path | None = None) -> Path:
    """``scenario`` as a TOML file :func:`hcomc.config.load_config` reads back, named by the
    hash of its text (written once, atomically; any process may write it)."""
    from hcomc.sim.manifest import atomic_paths

    text = config_to_toml(scenario)
    folder = folder or scenario_folder()
    path = folder / f"{scenario.name}-{hashlib.sha256(text.encode()).hexdigest()[:16]}.toml"
    if not path.is_file():
        folder.mkdir(parents=True, exist_ok=True)
        with atomic_paths(path) as (tmp,):
            tmp.write_text(text, encoding="utf-8")
    return path


def _scenario_path(scenario: ScenarioConfig) -> str:
    return str(scenario_file(scenario))


def _runner_overrides(spec: CorridorSpec) -> dict[str, Any]:
    """The scenario overrides of ``spec``'s configuration (the runner's)."""
    return RunSpec("", spec.configuration, spec.seed).config_overrides()


def runner_spec(spec: CorridorSpec) -> RunSpec:
    """The runner's spec of a paper-layout corridor's run (its scenario file, no overrides)."""
    scenario = resolve(spec).scenario
    if scenario is None:
        raise ValueError(f"corridor '{spec.condition}' does not run in the scenario engine")
    return RunSpec(_scenario_path(scenario), spec.configuration, spec.seed, {}, spec.engine)


def key_material(spec: CorridorSpec) -> list[Any]:
    """What a stored run's key hashes besides its identity and the code: the resolved corridor
    with the configuration's control, the scenario it becomes (None for a corridor run)
    and the controller's name."""
    resolved = resolve(spec)
    scenario = None
    if resolved.scenario is not None:
        config = load_config(_scenario_path(resolved.scenario), **_runner_overrides(spec))
        scenario = config.model_dump(mode="json")
    corridor = resolved.corridor
    return [corridor.model_dump(mode="json"), scenario, corridor.control.controller]


def reference_group(spec: CorridorSpec) -> tuple[str, str, int, str]:
    """Runs that share work when batched together: those of one paper-layout corridor and
    seed (one undisturbed run); a corridor run shares nothing."""
    kind = resolve(spec).kind
    extra = "" if kind == "scenario" else spec.configuration
    return kind, spec.condition + spec.overrides_json(), spec.seed, extra


def run_corridor_batch(
    specs: Sequence[CorridorSpec], *, threads: int | None = None
) -> list[Result]:
    """Simulate runs on corridors and measure them: ``(row, manifest)`` per spec, in order.
    Paper-layout corridors go to the runner together
    (:func:`~hcomc.experiments.runner.run_batch`, one ensemble on ``threads`` cores); the
    others run one after the other as a corridor run. The corridors are read afresh:
    a long-lived worker (a Dask cluster's) never runs a corridor file as it was before an
    edit."""
    forget()
    results: list[Result | None] = [None] * len(specs)
    scenario = [i for i, s in enumerate(specs) if resolve(s).scenario is not None]
    if scenario:
        ran = run_batch([runner_spec(specs[i]) for i in scenario], threads=threads)
        for i, (row, manifest) in zip(scenario, ran, strict=True):
            results[i] = _scenario_result(specs[i], row, manifest)
    for i, spec in enumerate(specs):
        if results[i] is None:
            results[i] = run_on_corridor(spec)
    return [r for r in results if r is not None]


def _run_record(spec: CorridorSpec) -> dict[str, Any]:
    return {"condition": spec.condition, "configuration": spec.configuration, "seed": spec.seed,
            "overrides": spec.overrides, "engine": spec.engine}  # fmt: skip


def _scenario_result(spec: CorridorSpec, row: dict[str, Any], manifest: dict[str, Any]) -> Result:
    """The runner's result of a paper-layout corridor, its manifest with the corridor."""
    corridor = resolve(spec).corridor
    run = {**_run_record(spec), "scenario_file": manifest["run"]["condition"]}
    extra = {"corridor": corridor.model_dump(mode="json"), "run": run}
    return {**row, "condition": corridor.name}, {**manifest, **extra}


def run_on_corridor(spec: CorridorSpec) -> Result:
    """Simulate one corridor run and measure it: ``(row, manifest)``."""
    from hcomc.control.registry import controller_source
    from hcomc.metrics.corridor import simulate_corridor
    from hcomc.robustness.impairments import impairment_columns, impairments_in, listeners_of
    from hcomc.sim.manifest import build_manifest

    corridor = resolve(spec).corridor
    start = time.perf_counter()
    try:
        listeners = listeners_of(corridor)
        run = simulate_corridor(corridor, seed=spec.seed, listeners=listeners)
    except ValueError as exc:  # a key a corridor run does not take
        raise ConfigError(f"corridor '{spec.condition}': {exc}") from None
    controller, optimizer = configuration_controller(spec.configuration)
    row: dict[str, Any] = {
        "condition": corridor.name,
        "configuration": spec.configuration,
        "controller": controller,
        "optimizer": optimizer,
        "seed": spec.seed,
        **corridor_metrics(run.trips, run.merges, run.collision_count),
        "duration": run.duration,
        "decisions": run.decisions,
        **impairment_columns(impairments_in(listeners)),
        "decision_ms": 1000.0 * run.decision_seconds / run.decisions if run.decisions else 0.0,
        "wall_s": time.perf_counter() - start,
    }
    resolved = corridor.model_dump(mode="json")  # as "config" and, as for any run, "corridor"
    manifest = build_manifest(
        seed=spec.seed, config=resolved,
        extra={"engine": CORRIDOR_ENGINE, "duration": run.duration, "run": _run_record(spec),
               "corridor": resolved, "controller": controller_source(corridor.control.controller)},
    )  # fmt: skip
    return row, manifest


__all__ = [
    "CORRIDOR_ENGINE",
    "CorridorSpec",
    "Resolved",
    "check",
    "forget",
    "key_material",
    "reference_group",
    "resolve",
    "run_corridor_batch",
    "run_on_corridor",
    "runner_spec",
    "scenario_file",
    "with_configuration",
]
