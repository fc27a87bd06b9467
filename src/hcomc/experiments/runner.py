"""Run grids of conditions x configurations x seeds, locally in parallel, into one table.

A *configuration* is a merge controller with its optimiser (the paper's five: FIFO, Game,
HCOMC with NSGA-II, PSO or SA). Every run is ``run_one(spec)``: a pure function of its spec
(condition preset or TOML file, configuration, seed, overrides) that returns one results row
and the run's manifest. Seeds are shared across configurations within a condition (common
random numbers: the same traffic for every controller), so comparisons are paired by seed.
The row order follows the spec order, whatever the number of workers, so tables are identical
for 1 or N workers.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from hcomc.config import load_config

CONFIGURATIONS: dict[str, tuple[str, str]] = {
    "FIFO": ("fifo", "nsga2"),
    "Game": ("game", "nsga2"),
    "HCOMC": ("hcomc", "nsga2"),
    "HCOMC-PSO": ("hcomc", "pso"),
    "HCOMC-SA": ("hcomc", "sa"),
}
"""Configuration label -> (controller, optimiser); the optimiser only matters for HCOMC."""


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
        controller, optimizer = CONFIGURATIONS[self.configuration]
        control = {
            **self.overrides.get("control", {}),
            "controller": controller,
            "optimizer": optimizer,
        }
        return {**self.overrides, "control": control}


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


def make_simulation(config: Any, seed: int | None = None, engine: str = "hcomc") -> Any:
    """A run of ``config`` on the named engine (SUMO is imported only when asked for)."""
    if engine == "sumo":
        from hcomc.sumo.cosim import SumoSimulation

        return SumoSimulation(config, seed)
    if engine != "hcomc":
        raise ValueError(f"engine '{engine}'; allowed: {', '.join(ENGINES)}")
    from hcomc.sim.engine import Simulation

    return Simulation(config, seed)


def run_one(spec: RunSpec) -> tuple[dict[str, Any], dict[str, Any]]:
    """Simulate one run and compute its metrics: ``(row, manifest)``."""
    from hcomc.metrics import compute_metrics, merge_window

    config = load_config(spec.condition, **spec.config_overrides())
    start = time.perf_counter()
    sim = make_simulation(config, spec.seed, spec.engine)
    log = sim.run()
    controller, optimizer = CONFIGURATIONS[spec.configuration]
    row: dict[str, Any] = {
        "condition": config.name,
        "configuration": spec.configuration,
        "controller": controller,
        "optimizer": optimizer if controller == "hcomc" else "",
        "seed": spec.seed,
        "mode": "",
        "fallback": False,
        "decision_ms": np.nan,
        "vr_kind": "",
        "vmc_kind": "",
    }
    if sim.decisions:
        plan = sim.decisions[0]
        group = plan.group
        kinds = sim.fleet.kind
        row.update(
            mode=plan.mode.name.lower(),
            fallback=bool(plan.fallback),
            decision_ms=float(plan.decision_ms),
            vr_kind="CAV" if kinds[group.vr] else "HDV",
            vmc_kind="" if group.vmc < 0 else "CAV" if kinds[group.vmc] else "HDV",
        )
        row.update(compute_metrics(log, merge_window(log, group.vr, group.as_dict())))
    if config.demand.ramp == "flow":
        from hcomc.metrics.flow import ramp_delay, throughput

        row.update(throughput=throughput(log), ramp_delay=ramp_delay(log), plans=len(sim.decisions))
    row["wall_s"] = time.perf_counter() - start
    manifest = {
        **log.meta,
        "run": {
            "condition": spec.condition,
            "configuration": spec.configuration,
            "seed": spec.seed,
            "engine": spec.engine,
        },
    }
    return row, manifest


def run_grid(
    specs: Sequence[RunSpec],
    *,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    on_result: Callable[[int, dict[str, Any], dict[str, Any]], None] | None = None,
) -> pd.DataFrame:
    """Run every spec (in ``workers`` processes) and return the rows in spec order."""
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

    if workers <= 1:
        for i, spec in enumerate(specs):
            collect(i, run_one(spec))
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(run_one, spec): i for i, spec in enumerate(specs)}
            for future in as_completed(futures):
                collect(futures[future], future.result())
    return pd.DataFrame(rows)
