"""A comparison's folder: its command line, and the runs it lacks run into it with the
record that claims it. Shared by ``hcomc compare`` on suite cells (:mod:`hcomc.cli.compare`)
and on corridors (:mod:`hcomc.cli.corridor_conditions`)."""

from __future__ import annotations

import shlex
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hcomc.cli._app import _progress
from hcomc.cli.compare_output import OUTPUTS, _say


def _command(args: dict[str, Any]) -> str:
    """The command line of a comparison (what its results depend on; not --workers)."""
    parts = ["hcomc", "compare"]
    for key, value in args.items():
        for item in value if isinstance(value, list) else [value]:
            if item is not None:
                parts += [f"--{key}", str(item)]
    return shlex.join(parts)


@dataclass(frozen=True)
class FilledFolder:
    """A comparison run into its folder: runs, record, status before, wall [s], processes."""

    runs: Any
    record: dict[str, Any]
    before: Any
    wall: float
    workers: int
    target: Path

    def say(self, input_name: str) -> None:
        """The closing line: runs new, done and recomputed (``input_name``, the code or a
        controller file changed), processes, time, files."""
        before = self.before
        counts = [f"{before.new} new", f"{before.done} already done"]
        if before.changed:
            counts.append(f"{before.changed} recomputed because {input_name}, the hcomc code "
                          "or the controller file changed")  # fmt: skip
        _say(
            f"{len(self.runs)} runs ({', '.join(counts)}) on {self.workers} processes in "
            f"{self.wall:.1f} s · written to {self.target}/ ({', '.join(OUTPUTS)}, "
            "compare.json)"
        )


def fill_folder(
    target: Path, comparison: Any, command: str, workers: int,
    folder: tuple[Callable[..., Any], Callable[..., dict[str, Any]], Callable[..., Any]],
) -> FilledFolder:  # fmt: skip
    """Run what ``target`` lacks of ``comparison`` with the ``(status, record,
    run_comparison)`` functions of its kind (a suite's or corridors'): the folder is claimed
    with its record before anything runs, and the record is rewritten with the runs' status
    after."""
    from hcomc.experiments.benchmark import write_record

    status, record, run_comparison = folder
    before = status(comparison, target)
    write_record(target, record(comparison, command, None))  # claims the folder
    start = time.perf_counter()
    with _progress("runs", before.total) as update:
        runs = run_comparison(comparison, target, workers=workers, progress=update)
    wall = time.perf_counter() - start
    content = record(comparison, command, before)
    write_record(target, content)
    return FilledFolder(runs, content, before, wall, workers, target)
