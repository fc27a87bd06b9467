"""Interactive replay of runs in the browser: one self-contained HTML page per call.

The page plays one run, or several runs of the same scenario side by side on one clock (for
example FIFO, Game and HCOMC on the same seed): the road to scale with pan and zoom, every
vehicle as a rectangle of its size and heading coloured by kind, the key vehicles labelled,
the live plan's virtual vehicles as ghosts with its predicted path, a timeline of the
events and plans, a panel and a speed/acceleration chart of the vehicle under the pointer or
selected. Its controls are described in docs/replay.md.

Corridor runs play too (``hcomc simulate CORRIDOR --trajectory-interval S
--out DIR``): the corridor's road with every lane, ramp and lane drop, the sampled vehicles
on it, and the merge events of ``merges.csv`` on the timeline
(:mod:`hcomc.viz.replay.corridor_run`). One page plays runs of one engine, and corridor runs
of one corridor (:mod:`hcomc.viz.replay.runs`).

:func:`replay` builds the page from logs (or saved runs) for notebooks and scripts,
:func:`write_replay` writes it for other writers (the HTML report links each run's page);
``hcomc replay`` is the command line. :mod:`hcomc.viz.replay.browser` drives headless
Chromium to check a page or take a screenshot of it.

This module imports only the standard library; the work is done on first call.
"""

from __future__ import annotations

import html
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Union

if TYPE_CHECKING:
    from hcomc.metrics.corridor import CorridorRun
    from hcomc.metrics.corridor.record import CorridorRecord
    from hcomc.sim.log import SimulationLog
    from hcomc.viz.replay.runs import ReplayRun

__all__ = ["ReplayPage", "replay", "write_replay"]

Source = Union["SimulationLog", "CorridorRun", "CorridorRecord", str, os.PathLike[str]]
"""A log, a saved log file (.npz/.parquet) or a ``hcomc simulate --out`` directory; a
corridor run (in memory, or its ``--out`` directory with ``trajectories.csv``)."""


@dataclass(frozen=True)
class ReplayPage:
    """A built replay page: its HTML text. Shown inline in Jupyter; :meth:`save` writes it."""

    html: str

    @property
    def nbytes(self) -> int:
        """Size of the page as UTF-8 [bytes]."""
        return len(self.html.encode("utf-8"))

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the page to ``path`` atomically (the directory must exist); returns it."""
        from hcomc.sim.manifest import atomic_paths

        target = Path(path)
        with atomic_paths(target) as (tmp,):
            tmp.write_text(self.html, encoding="utf-8")
        return target

    def _repr_html_(self) -> str:
        """The page in an isolated frame (Jupyter runs it as it runs the file)."""
        return (
            f'<iframe srcdoc="{html.escape(self.html, quote=True)}" '
            'style="width:100%;height:760px;border:1px solid #ccc"></iframe>'
        )


def _load(source: Source) -> ReplayRun:
    from hcomc.viz.replay.runs import load_run

    return load_run(source)


def replay(
    logs: Source | Sequence[Source],
    *,
    titles: Sequence[str] | None = None,
    title: str = "hcomc replay",
    out: str | os.PathLike[str] | None = None,
) -> ReplayPage:
    """The replay page of one run or of several runs side by side (time-synced).

    Parameters
    ----------
    logs : SimulationLog, CorridorRun, path, or a sequence of them
        The runs: logs, saved log files or ``hcomc simulate --out`` directories, of the
        scenario engine or (all of them) of a corridor run on one corridor.
    titles : sequence of str, optional
        One title per run; default: controller, scenario or corridor, and seed.
    title : str
        The page's title.
    out : path, optional
        Also write the page there (atomically).

    Raises
    ------
    ValueError
        If a source holds no log, a log has no rows or no road geometry, a corridor run has
        no trajectories, scenario and corridor runs (or runs of two corridor roads) are
        mixed, or the titles do not match the runs.
    """
    from hcomc.viz.replay.page import page_html
    from hcomc.viz.replay.runs import check_together, title_of

    items = logs if isinstance(logs, Sequence) and not isinstance(logs, str) else [logs]
    loaded = [_load(s) for s in items]
    names = [title_of(run) for run in loaded] if titles is None else list(titles)
    check_together(loaded, [str(s) if isinstance(s, str | os.PathLike) else title_of(run)
                            for s, run in zip(items, loaded, strict=True)])  # fmt: skip
    page = ReplayPage(page_html(loaded, names, title))
    if out is not None:
        page.save(out)
    return page


def write_replay(
    path: str | os.PathLike[str],
    logs: Source | Sequence[Source],
    titles: Sequence[str] | None = None,
) -> Path:
    """Write the replay page of ``logs`` to ``path`` (for the HTML report: one page per run
    or per group of runs, linked from the report); returns the path."""
    page = replay(logs, titles=titles, title=" | ".join(titles) if titles else "hcomc replay")
    return page.save(path)
