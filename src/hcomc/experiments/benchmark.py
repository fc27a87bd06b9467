"""Running a benchmark comparison into a folder, and reading result folders back.

A :class:`Comparison` is what ``hcomc compare`` runs: cells of a suite
(:mod:`hcomc.experiments.suite`) x configurations x seeds 0..n-1, with optional overrides
for every cell and an engine. Its runs live in a resumable store
(:class:`hcomc.experiments.run_store.RunStore`): a rerun into the same folder runs only what is
missing, and a changed config, hcomc version or code, or controller file gives new run keys, so such
runs are recomputed instead of mixed in. The folder's record (:data:`RECORD`) names the
suite and its version, the hcomc version and git revision; a folder holding runs of another
suite or version is refused. Every row of the runs table has ``suite``, ``condition`` (the
cell id), ``base`` (the cell's preset) and ``engine`` before the runner's columns.

:func:`load_folder` reads the runs of any results folder (``hcomc compare`` or ``hcomc
reproduce``), and :func:`folder_runs` puts two of them side by side for comparing the
configurations they share.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from hcomc.config import ConfigError, merge_tables
from hcomc.control.registry import check_controller
from hcomc.experiments.run_store import RunStore, SweepStatus, resolved_config
from hcomc.experiments.runner import RunSpec
from hcomc.experiments.suite import Cell, Suite
from hcomc.sim.manifest import build_manifest, write_json_atomic

RECORD = "compare.json"
"""The record of a comparison folder: suite, settings, provenance."""

RUNS = "runs.parquet"
"""The runs table of a results folder (``hcomc compare`` and ``hcomc reproduce``)."""


@dataclass(frozen=True)
class Comparison:
    """Cells x configurations x seeds of one suite, with overrides for every cell."""

    suite: Suite
    cells: tuple[Cell, ...]
    configurations: tuple[str, ...]
    seeds: int
    overrides: dict[str, Any] = field(default_factory=dict, hash=False)
    engine: str = "hcomc"

    def runs(self) -> list[tuple[Cell, RunSpec]]:
        """Every run with its cell, ordered cell, configuration, seed."""
        return [
            (cell, RunSpec(cell.condition, conf, seed,
                           merge_tables(cell.overrides, self.overrides), self.engine))
            for cell in self.cells
            for conf in self.configurations
            for seed in range(self.seeds)
        ]  # fmt: skip

    def row(self, cell: Cell, results: dict[str, Any]) -> dict[str, Any]:
        """A run's results row as the comparison's runs table holds it: ``suite``,
        ``condition`` (the cell id), ``base`` (the cell's preset) and ``engine`` first."""
        head = {"suite": self.suite.name, "condition": cell.id, "base": cell.condition,
                "engine": self.engine}  # fmt: skip
        return {**head, **{k: v for k, v in results.items() if k not in head}}

    def check(self) -> None:
        """Load every cell with every configuration (ConfigError naming the bad value), so
        that nothing runs unless everything can."""
        for cell in self.cells:
            for conf in self.configurations:
                spec = RunSpec(cell.condition, conf, 0,
                               merge_tables(cell.overrides, self.overrides))  # fmt: skip
                config = resolved_config(spec)
                check_controller(config)  # its [control.options] fit its constructor
                if config.scenario != "merge" or config.demand.ramp == "none":
                    raise ConfigError(
                        f"cell '{cell.id}' has no ramp demand with these settings; allowed: "
                        "settings that keep a merge (demand.ramp = 'single' or 'flow')"
                    )


def stored_record(out: Path) -> dict[str, Any] | None:
    """The record of a comparison folder, None if it has none."""
    path = out / RECORD
    if not path.is_file():
        return None
    try:
        record: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError:
        raise ConfigError(f"option '--out' = '{out}': {RECORD} is not valid JSON") from None
    return record


def check_folder(out: Path, suite: Suite) -> None:
    """ConfigError unless ``out`` is a new folder or one holding runs of ``suite`` (same
    name and version): runs of two versions of a suite are never mixed."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"option '--out' = '{out}': exists and is not a directory")
    record = stored_record(out)
    if record is None:
        other = [n for n in ("parts", RUNS) if (out / n).exists()]
        if other:
            raise ConfigError(
                f"option '--out' = '{out}' holds results that are not a comparison ("
                f"{', '.join(other)} but no {RECORD}); allowed: a new folder or one written by "
                "hcomc compare"
            )
        return
    if "corridors" in record:  # hcomc.experiments.corridor.compare's record
        raise ConfigError(
            f"option '--out' = '{out}' holds a comparison on corridors "
            f"({', '.join(record['corridors'])}); allowed: another folder (runs of a suite and "
            "of corridors are never mixed)"
        )
    stored = f"{record.get('suite_id')}-v{record.get('suite_version')}"
    if stored != suite.name:
        raise ConfigError(
            f"option '--out' = '{out}' holds runs of suite '{stored}', not '{suite.name}'; "
            f"allowed: another folder (runs of two suite versions are never mixed)"
        )


def record(comparison: Comparison, command: str, status: SweepStatus | None) -> dict[str, Any]:
    """What a comparison folder records about its runs (written as :data:`RECORD`)."""
    suite = comparison.suite
    return {
        "suite": suite.name,
        "suite_id": suite.id,
        "suite_version": suite.version,
        "cells": [c.id for c in comparison.cells],
        **settings_record(comparison, command, status),
    }


def settings_record(comparison: Any, command: str, status: SweepStatus | None) -> dict[str, Any]:
    """The part of a comparison folder's record every comparison has (of a suite or of
    corridors): configurations with their controllers' sources, seeds, overrides, engine,
    the command, version, git revision and the runs' status."""
    from hcomc.control.registry import controller_source
    from hcomc.experiments.runner import configuration_controller

    manifest = build_manifest(seed=0, config={})
    return {
        "configurations": list(comparison.configurations),
        "controllers": {
            conf: controller_source(configuration_controller(conf)[0])
            for conf in comparison.configurations
        },
        "seeds": comparison.seeds,
        "overrides": comparison.overrides,
        "engine": comparison.engine,
        "command": command,
        "hcomc_version": manifest["hcomc_version"],
        "git_revision": manifest["git_revision"],
        "created_utc": manifest["created_utc"],
        "runs": None if status is None else vars(status),
    }


def write_record(out: Path, content: dict[str, Any]) -> None:
    """Write the folder's record atomically."""
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / RECORD, content)


def run_comparison(
    comparison: Comparison,
    out: Path,
    *,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:
    """Run what ``out`` lacks of ``comparison`` and return its runs table, in run order."""
    pairs = comparison.runs()
    runs = [run for _, run in pairs]
    store = RunStore(out)

    def frame(i: int, row: dict[str, Any]) -> pd.DataFrame:
        return pd.DataFrame([comparison.row(pairs[i][0], row)])

    store.run(runs, frame, workers=workers, progress=progress)
    return store.read(runs)


def status(comparison: Comparison, out: Path) -> SweepStatus:
    """How many runs of ``comparison`` ``out`` holds already, and how many are to run."""
    return RunStore(out).status([run for _, run in comparison.runs()])


def load_folder(path: Path) -> pd.DataFrame:
    """The runs table of a results folder; ConfigError if it holds none."""
    if not path.is_dir():
        raise ConfigError(f"folder '{path}' does not exist; allowed: a results folder")
    table = path / RUNS
    if not table.is_file():
        raise ConfigError(
            f"folder '{path}' holds no {RUNS}; allowed: a folder written by hcomc compare or "
            "hcomc reproduce"
        )
    runs = pd.read_parquet(table)
    missing = [c for c in ("condition", "configuration", "seed") if c not in runs]
    if missing or runs.empty:
        raise ConfigError(f"'{table}' holds no runs (no rows or no {', '.join(missing)})")
    return runs


@dataclass(frozen=True)
class FolderRuns:
    """Two folders' runs side by side: each configuration they share, labelled by folder."""

    runs: pd.DataFrame  # rows of the shared configurations, configuration "X [folder]"
    comparisons: tuple[tuple[str, str], ...]  # (X [second], X [first]) per shared X
    labels: tuple[str, str]
    notes: tuple[str, ...]  # differences of their recorded settings


def folder_labels(paths: Sequence[Path]) -> tuple[str, str]:
    """Names of two folders: their own names, or the paths as given when those are equal."""
    first, second = (p.resolve().name or str(p) for p in paths)
    if first == second:
        first, second = (str(p) for p in paths)
    if first == second:
        raise ConfigError(f"folder '{paths[0]}' is given twice; allowed: two different folders")
    return first, second


def folder_runs(paths: Sequence[Path]) -> FolderRuns:
    """The configurations two folders share, to compare paired by cell and seed (the second
    folder's runs as A, the first's as B). ConfigError if they share none."""
    if len(paths) != 2:
        raise ConfigError(f"{len(paths)} folders given; allowed: two (hcomc compare A/ B/)")
    tables = [load_folder(p) for p in paths]
    labels = folder_labels(paths)
    confs = [pd.unique(t["configuration"]).tolist() for t in tables]
    shared = [c for c in confs[0] if c in confs[1]]
    if not shared:
        raise ConfigError(
            f"folders '{paths[0]}' ({', '.join(map(str, confs[0]))}) and '{paths[1]}' "
            f"({', '.join(map(str, confs[1]))}) share no configuration; allowed: folders that "
            "ran a configuration in common"
        )
    parts = []
    for table, label in zip(tables, labels, strict=True):
        part = table[table["configuration"].isin(shared)].copy()
        part["configuration"] = [f"{c} [{label}]" for c in part["configuration"]]
        part["folder"] = label
        parts.append(part)
    comparisons = tuple((f"{c} [{labels[1]}]", f"{c} [{labels[0]}]") for c in shared)
    return FolderRuns(pd.concat(parts, ignore_index=True), comparisons, labels,
                      _setting_notes(paths, labels))  # fmt: skip


def _setting_notes(paths: Sequence[Path], labels: tuple[str, str]) -> tuple[str, ...]:
    """Settings the two folders' records give differently (the runs may not be comparable)."""
    from hcomc.experiments.digest import RUN_RECORD

    records = []
    for path in paths:
        for name in (RECORD, RUN_RECORD):
            if (path / name).is_file():
                records.append(json.loads((path / name).read_text(encoding="utf-8")))
                break
        else:
            records.append({})
    notes = []
    for key in ("suite", "overrides", "engine", "hcomc_version"):
        values = [r.get(key) for r in records]
        if all(key in r for r in records) and values[0] != values[1]:
            notes.append(
                f"{key} differs: {labels[0]}: {json.dumps(values[0])}, "
                f"{labels[1]}: {json.dumps(values[1])}"
            )
    return tuple(notes)


__all__ = [
    "RECORD",
    "RUNS",
    "Comparison",
    "FolderRuns",
    "check_folder",
    "folder_runs",
    "load_folder",
    "record",
    "run_comparison",
    "status",
    "stored_record",
    "write_record",
]
