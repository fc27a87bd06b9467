"""The runs one replay page plays: loaded from what the caller gives, checked to belong on
one page, titled, and the moment to show first.

A run is either a :class:`~hcomc.sim.log.SimulationLog` of the scenario engine (a log, a
saved ``.npz``/``.parquet`` log or a ``hcomc simulate --out`` directory holding one) or a
:class:`~hcomc.metrics.corridor.record.CorridorRecord` of a corridor run (its ``--out``
directory, which must hold ``trajectories.csv``, or a
:class:`~hcomc.metrics.corridor.CorridorRun` in memory). The panels of a page share one clock,
one view of the road and the vehicle ids, so a page plays runs of one engine, and corridor
runs of one corridor road (:func:`check_together`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from hcomc.metrics.corridor.record import (
    CorridorRecord,
    is_corridor_run,
    read_corridor_run,
    record_of,
)
from hcomc.sim.log import SimulationLog
from hcomc.viz.replay.corridor_run import corridor_moment
from hcomc.viz.replay.decisions import moment_of_interest

__all__ = ["ReplayRun", "check_together", "controller_label", "load_run", "moment", "title_of"]

ReplayRun = SimulationLog | CorridorRecord
"""A run the page plays: a scenario-engine log or a corridor-run record."""


def load_run(source: Any) -> ReplayRun:
    """The run of ``source`` (module docstring); ValueError (one line) if it is none, or a
    corridor run without trajectories (saying how to record them)."""
    from hcomc.viz.inputs import load_log

    if isinstance(source, SimulationLog | CorridorRecord):
        return source
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        if is_corridor_run(path):
            record = read_corridor_run(path)
            record.require_trajectories()
            return record
        return load_log(path)
    from hcomc.metrics.corridor import CorridorRun

    if isinstance(source, CorridorRun):
        return record_of(source)
    raise ValueError(f"cannot replay a {type(source).__name__}; allowed: a SimulationLog, a "
                     "CorridorRun, or the path of a run directory or saved log")  # fmt: skip


def check_together(runs: Sequence[ReplayRun], names: Sequence[str]) -> None:
    """ValueError (one line, naming the runs by ``names``) unless ``runs`` are all
    scenario-engine runs or all corridor runs of one corridor road."""
    first = runs[0]
    for run, name in zip(runs[1:], names[1:], strict=True):
        if isinstance(run, CorridorRecord) != isinstance(first, CorridorRecord):
            kinds = ("a corridor run", "a scenario run")
            this, that = kinds if isinstance(run, CorridorRecord) else kinds[::-1]
            raise ValueError(
                f"run '{name}' is {this} and run '{names[0]}' {that}; allowed: runs of one "
                "engine side by side (scenario runs, or corridor runs of one corridor)"
            )
        if (isinstance(run, CorridorRecord) and isinstance(first, CorridorRecord)
                and run.corridor.road != first.corridor.road):  # fmt: skip
            raise ValueError(
                f"run '{name}' is of corridor '{run.corridor.name}', whose road differs from "
                f"that of run '{names[0]}' (corridor '{first.corridor.name}'); allowed: runs "
                "of one corridor side by side"
            )


def controller_label(controller: str, optimizer: str | None) -> str:
    """A controller's name as a title shows it (with HCOMC's optimiser)."""
    names = {"none": "no controller", "fifo": "FIFO", "game": "Game", "hcomc": "HCOMC"}
    label = names.get(controller, controller)
    if controller == "hcomc" and optimizer:
        label += f" ({optimizer})"
    return label


def title_of(run: ReplayRun) -> str:
    """A run's default title: controller (and optimiser), scenario or corridor, and seed."""
    if isinstance(run, CorridorRecord):
        control = run.corridor.control
        label = controller_label(run.controller, control.optimizer)
        return " · ".join([label, run.corridor.name, f"seed {run.seed}"])
    meta = run.meta
    config = meta.get("config") or {}
    control_table = config.get("control") or {}
    controller = str(control_table.get("controller") or "none")
    parts = [controller_label(controller, control_table.get("optimizer")),
             str(config.get("name") or "run")]  # fmt: skip
    if meta.get("seed") is not None:
        parts.append(f"seed {meta['seed']}")
    return " · ".join(parts)


def moment(runs: Sequence[ReplayRun]) -> float:
    """A time worth showing first [s]: the middle of the earliest merge of the runs
    (:func:`hcomc.viz.replay.decisions.moment_of_interest`,
    :func:`hcomc.viz.replay.corridor_run.corridor_moment`)."""
    records = [r for r in runs if isinstance(r, CorridorRecord)]
    logs = [r for r in runs if isinstance(r, SimulationLog)]
    return corridor_moment(records) if records else moment_of_interest(logs)
