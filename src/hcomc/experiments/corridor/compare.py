"""Comparing merge controllers on corridors: ``hcomc compare --conditions CORRIDOR ...``.

A :class:`CorridorComparison` is corridors (presets or files, as given) x configurations x
seeds 0..n-1 with dotted corridor overrides for every corridor and an engine, the corridor
counterpart of :class:`hcomc.experiments.benchmark.Comparison`. Its runs live in the same
resumable store (:class:`hcomc.experiments.run_store.RunStore`), keyed by the resolved corridor,
version and code, so a changed corridor file or code revision is recomputed, never mixed in.
Every row of its runs table starts with ``condition`` (the corridor as given: the cell of
the comparison), ``corridor`` (its name), ``kind`` and ``engine``.

The corridors of one comparison are of one kind
(:attr:`~hcomc.experiments.corridor.runs.Resolved.kind`): all of the paper's layout (the
scenario engine: the paper's metrics) or none (a corridor run: the corridor metrics),
since the two kinds have different metrics and a different meaning of ``merged``; a mixture
is refused with a message naming which is which.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from hcomc.config import ConfigError
from hcomc.experiments.corridor.runs import CorridorSpec, check, forget, resolve
from hcomc.experiments.run_store import RunStore, SweepStatus

RECORD = "compare.json"
"""The record of a comparison folder (as a suite comparison's)."""


@dataclass(frozen=True)
class CorridorComparison:
    """Corridors x configurations x seeds, with dotted corridor overrides for every corridor."""

    conditions: tuple[str, ...]
    configurations: tuple[str, ...]
    seeds: int
    overrides: dict[str, Any] = field(default_factory=dict, hash=False)
    engine: str = "hcomc"

    def runs(self) -> list[CorridorSpec]:
        """Every run, ordered corridor, configuration, seed."""
        return [
            CorridorSpec(cond, conf, seed, dict(self.overrides), self.engine)
            for cond in self.conditions
            for conf in self.configurations
            for seed in range(self.seeds)
        ]

    def check(self) -> str:
        """Resolve every corridor with every configuration and check it can run (ConfigError
        naming the bad key, value or option otherwise); the comparison's kind, "scenario" or
        "corridor", the same for every corridor."""
        forget()  # the corridor files may have changed since they were last read
        kinds: dict[str, str] = {}
        for cond in self.conditions:
            for conf in self.configurations:
                kinds[cond] = check(CorridorSpec(cond, conf, 0, self.overrides, self.engine)).kind
        if len(set(kinds.values())) > 1:
            paper = [c for c, k in kinds.items() if k == "scenario"]
            other = [c for c, k in kinds.items() if k == "corridor"]
            raise ConfigError(
                f"option '--conditions': corridors of the paper's layout ({', '.join(paper)}) "
                "run in hcomc's scenario engine (the paper's metrics), the others "
                f"({', '.join(other)}) as a corridor run (corridor metrics); allowed: "
                "corridors of one kind in one comparison (run the two kinds as two)"
            )
        return next(iter(kinds.values()))


def is_corridor_record(record: dict[str, Any]) -> bool:
    """Whether a folder's record is that of a comparison on corridors."""
    return "corridors" in record


def check_folder(out: Path) -> None:
    """ConfigError unless ``out`` is a new folder or one holding a comparison on corridors
    (runs of a suite are never mixed in)."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"option '--out' = '{out}': exists and is not a directory")
    path = out / RECORD
    if path.is_file():
        try:
            content = json.loads(path.read_text(encoding="utf-8"))
        except json.JSONDecodeError:
            raise ConfigError(f"option '--out' = '{out}': {RECORD} is not valid JSON") from None
        if not is_corridor_record(content):
            raise ConfigError(
                f"option '--out' = '{out}' holds runs of suite '{content.get('suite')}'; "
                "allowed: another folder (runs of a suite and of corridors are never mixed)"
            )
        return
    other = [n for n in ("parts", "runs.parquet") if (out / n).exists()]
    if other:
        raise ConfigError(
            f"option '--out' = '{out}' holds results that are not a comparison ("
            f"{', '.join(other)} but no {RECORD}); allowed: a new folder or one written by "
            "hcomc compare"
        )


def record(
    comparison: CorridorComparison, command: str, status: SweepStatus | None
) -> dict[str, Any]:
    """What a comparison folder records about its runs (written as ``compare.json``): the
    corridors as given and resolved (with the overrides, without a controller), settings
    and provenance."""
    from hcomc.corridor import load_corridor
    from hcomc.experiments.benchmark import settings_record

    return {
        "suite": None,
        "corridors": {
            cond: load_corridor(cond, comparison.overrides).model_dump(mode="json")
            for cond in comparison.conditions
        },
        "cells": list(comparison.conditions),
        "kind": resolve(comparison.runs()[0]).kind,
        **settings_record(comparison, command, status),
    }


def status(comparison: CorridorComparison, out: Path) -> SweepStatus:
    """How many runs of ``comparison`` ``out`` holds already, and how many are to run."""
    return RunStore(out).status(comparison.runs())


def run_comparison(
    comparison: CorridorComparison,
    out: Path,
    *,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:
    """Run what ``out`` lacks of ``comparison`` and return its runs table, in run order."""
    runs = comparison.runs()

    def frame(i: int, row: dict[str, Any]) -> pd.DataFrame:
        spec = runs[i]
        resolved = resolve(spec)
        head = {"condition": spec.condition, "corridor": resolved.corridor.name,
                "kind": resolved.kind, "engine": spec.engine}  # fmt: skip
        rest = {k: v for k, v in row.items() if k not in head}
        return pd.DataFrame([{**head, **rest}])

    RunStore(out).run(runs, frame, workers=workers, progress=progress)
    return RunStore(out).read(runs)


__all__ = [
    "CorridorComparison",
    "check_folder",
    "is_corridor_record",
    "record",
    "run_comparison",
    "status",
]
