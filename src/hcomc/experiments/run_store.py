"""Where finished runs live: each run's key, and a folder that stores one part per key.

A run (a scenario condition's :class:`~hcomc.experiments.runner.RunSpec` or a corridor's
:class:`~hcomc.experiments.corridor.runs.CorridorSpec`) is identified by a key hashed from
its place in its grid, its fully resolved config (or corridor), the hcomc version and the
code that computes it (:func:`run_key`); a :class:`RunStore` keeps each finished run as
``parts/<key>.parquet`` (one row) plus ``manifests/<key>.json``, written atomically, so that
a killed sweep or comparison rerun skips finished runs and loses nothing, and a rerun after
the inputs or the code changed recomputes instead of mixing.
"""

from __future__ import annotations

import functools
import hashlib
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

import hcomc
from hcomc.config import ScenarioConfig, load_config
from hcomc.control.registry import BUILTIN, controller_source
from hcomc.experiments.corridor.runs import CorridorSpec, key_material
from hcomc.experiments.provenance import code_stamp
from hcomc.experiments.runner import RunSpec
from hcomc.experiments.workers import AnySpec, run_dask, run_local
from hcomc.sim.manifest import atomic_paths, write_json_atomic

__all__ = [
    "TIMING", "RunStore", "SweepStatus", "forget_resolved", "resolved_config", "run_identity",
    "run_key",
]  # fmt: skip

TIMING = ("wall_s", "decision_ms")
"""Fields of a results row that go to the run's manifest, not to its stored row."""


@functools.lru_cache(maxsize=4096)  # one load per cell and configuration, not per seed
def _resolved(condition: str, configuration: str, overrides: str) -> ScenarioConfig:
    run = RunSpec(condition, configuration, 0, json.loads(overrides))
    return load_config(condition, **run.config_overrides())


def forget_resolved() -> None:
    """Drop the resolved configs kept so far (their base files may have changed)."""
    _resolved.cache_clear()


def resolved_config(run: RunSpec) -> ScenarioConfig:
    """The config ``run`` simulates (base + cell + its configuration's controller)."""
    return _resolved(run.condition, run.configuration, json.dumps(run.overrides, sort_keys=True))


def run_identity(run: AnySpec) -> str:
    """What a run is in the grid (base, cell, configuration, seed), whatever its inputs say;
    a corridor's run is marked as such."""
    kind = ["corridor"] if isinstance(run, CorridorSpec) else []
    text = json.dumps(
        [*kind, run.condition, run.configuration, run.seed, run.overrides, run.engine],
        sort_keys=True,
    )
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def outside_source(controller: str) -> str:
    """SHA-256 of the file that defines a controller from outside hcomc ("" for hcomc's own,
    which the package version covers)."""
    if controller == "none" or controller in BUILTIN:
        return ""
    return controller_source(controller)["sha256"]


def run_key(run: AnySpec) -> str:
    """Stable key of a run's result: its identity, resolved config, hcomc version and code.

    A changed preset or base file, another package version, a changed source file of hcomc
    that can change a run (:func:`hcomc.experiments.provenance.code_stamp`) or of a
    controller from outside hcomc gives new keys, so a resumed sweep recomputes those runs
    instead of mixing stale results into the table. A corridor's run hashes the resolved
    corridor, and the scenario it becomes when it runs in the scenario engine
    (:func:`hcomc.experiments.corridor.runs.key_material`), in place of the config.
    """
    if isinstance(run, CorridorSpec):
        *material, controller = key_material(run)
    else:
        config = resolved_config(run)
        material, controller = [config.model_dump(mode="json")], config.control.controller
    text = json.dumps(
        [run_identity(run), *material, hcomc.__version__, code_stamp(),
         outside_source(controller)],
        sort_keys=True,
    )  # fmt: skip
    return hashlib.sha1(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class SweepStatus:
    """What a (re)run of a list of runs into a store will do."""

    total: int
    done: int  # stored with the current config and version: skipped
    new: int  # never run
    changed: int  # stored under an older config or version: recomputed
    stale: int  # stored parts that no run of this list uses (kept, ignored)


@dataclass(frozen=True)
class RunStore:
    """A folder of finished runs, one per key (:func:`run_key`): ``parts/<key>.parquet``
    (the run's results row) and ``manifests/<key>.json`` (its manifest, timing and grid
    identity). A part is written last and atomically, so it exists only for a complete run;
    rerunning a list of runs into the store runs only those without a part."""

    root: Path

    @property
    def parts(self) -> Path:
        """The folder of results rows."""
        return self.root / "parts"

    @property
    def manifests(self) -> Path:
        """The folder of manifests."""
        return self.root / "manifests"

    def part(self, run: AnySpec) -> Path:
        """Where ``run``'s results row is (or will be) stored."""
        return self.parts / f"{run_key(run)}.parquet"

    def status(self, runs: Sequence[AnySpec]) -> SweepStatus:
        """Count the runs of ``runs`` already done here, new, and to recompute."""
        keys = {run_key(r) for r in runs}
        stored = {p.stem for p in self.parts.glob("*.parquet")}
        done = sum(run_key(r) in stored for r in runs)
        old = set()
        for key in stored - keys:
            manifest = self.manifests / f"{key}.json"
            if manifest.is_file():
                old.add(json.loads(manifest.read_text(encoding="utf-8")).get("sweep_identity"))
        changed = sum(run_key(r) not in stored and run_identity(r) in old for r in runs)
        return SweepStatus(len(runs), done, len(runs) - done - changed, changed,
                           len(stored - keys))  # fmt: skip

    def run(
        self,
        runs: Sequence[AnySpec],
        frame: Callable[[int, dict[str, Any]], pd.DataFrame],
        *,
        workers: int = 1,
        scheduler: str | None = None,
        progress: Callable[[int, int], None] | None = None,
        max_pool_restarts: int = 3,
    ) -> None:
        """Run every run of ``runs`` that has no part yet and store it; ``frame(i, row)``
        turns run ``i``'s results row (timings removed, they go to the manifest) into the
        one-row table stored as its part."""
        self.parts.mkdir(parents=True, exist_ok=True)
        self.manifests.mkdir(parents=True, exist_ok=True)
        for stale in [*self.parts.glob(".*.tmp"), *self.manifests.glob(".*.tmp")]:
            stale.unlink(missing_ok=True)  # a temporary file of a killed run, never a result
        keys = [run_key(r) for r in runs]
        todo = [i for i, k in enumerate(keys) if not (self.parts / f"{k}.parquet").exists()]
        done = len(runs) - len(todo)
        if progress is not None:
            progress(done, len(runs))

        def store(i: int, result: tuple[dict[str, Any], dict[str, Any]]) -> None:
            nonlocal done
            row, manifest = result
            timing = {k: row.get(k) for k in TIMING}
            manifest = {**manifest, "timing": timing, "sweep_identity": run_identity(runs[i])}
            write_json_atomic(self.manifests / f"{keys[i]}.json", manifest)
            clean = {k: v for k, v in row.items() if k not in TIMING}
            with atomic_paths(self.parts / f"{keys[i]}.parquet") as (tmp,):  # commits the run
                frame(i, clean).to_parquet(tmp, index=False)
            done += 1
            if progress is not None:
                progress(done, len(runs))

        if scheduler is not None:
            run_dask(scheduler, runs, todo, store)
        else:
            run_local(runs, todo, store, workers, max_pool_restarts)

    def read(self, runs: Sequence[AnySpec]) -> pd.DataFrame:
        """The stored rows of ``runs``, in their order (runs not stored are left out)."""
        paths = [self.part(r) for r in runs]
        frames = [pd.read_parquet(p) for p in paths if p.exists()]
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
