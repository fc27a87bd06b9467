"""The replay page: one self-contained HTML file holding the runs' data and the player.

The page template, its stylesheet and scripts are package data (``assets/``); the runs go
into a ``<script type="application/json">`` block (the per-cell arrays as base64 typed
arrays, :mod:`hcomc.viz.replay.pack`; the plans, roles and events as JSON,
:mod:`hcomc.viz.replay.decisions`; a corridor run's from
:mod:`hcomc.viz.replay.corridor_run`). Nothing is loaded from anywhere else, so the file opens
offline from disk.
"""

from __future__ import annotations

import html
import json
import re
from collections.abc import Sequence
from importlib import resources
from typing import Any

from hcomc.metrics import road_of
from hcomc.sim.log import SimulationLog
from hcomc.viz.replay.corridor_run import corridor_run_json
from hcomc.viz.replay.decisions import decisions_json
from hcomc.viz.replay.geometry import road_shapes
from hcomc.viz.replay.pack import columns_of, pack_cells, pack_vehicles
from hcomc.viz.replay.runs import ReplayRun

__all__ = ["SCRIPTS", "page_html", "run_json"]

SCRIPTS = ("core.js", "draw.js", "timeline.js", "ui.js")
"""The player's scripts (package data), in the order the page runs them."""

_SLOT = re.compile(r"\{\{(\w+)\}\}")


def _asset(name: str) -> str:
    return (resources.files("hcomc.viz.replay") / "assets" / name).read_text(encoding="utf-8")


def run_json(log: SimulationLog, title: str) -> dict[str, Any]:
    """Everything the page needs of one run, JSON-ready.

    Raises
    ------
    ValueError
        If the log has no recorded rows or no road geometry in its metadata.
    """
    if log.n_recorded == 0:
        raise ValueError(f"run '{title}' has no recorded rows; allowed: a log with rows")
    road = road_of(log)
    layout = columns_of(log)
    arrays = {**pack_cells(log, layout), **pack_vehicles(log, layout)}
    shapes = road_shapes(road).to_json()
    shapes.update(vehicle_length=road.vehicle_length, vehicle_width=road.vehicle_width)
    return {
        "title": title,
        "seed": log.meta.get("seed"),
        "dt": log.dt,
        "rows": log.n_recorded,
        "columns": max(layout.n_columns, 1),
        "vehicles": log.n_vehicles,
        "road": shapes,
        "arrays": arrays,
        **decisions_json(log, road.lane_width),
    }


def _json_for_script(data: Any) -> str:
    """JSON that cannot end its ``<script>`` element early (``<`` written as ``\\u003c``)."""
    text = json.dumps(data, allow_nan=False, separators=(",", ":"), ensure_ascii=False)
    return text.replace("<", "\\u003c")


def page_html(logs: Sequence[ReplayRun], titles: Sequence[str], page_title: str) -> str:
    """The page playing ``logs`` (scenario-engine logs or corridor records,
    :mod:`hcomc.viz.replay.runs`) side by side (time-synced), each under its title."""
    if not logs:
        raise ValueError("no runs to replay; allowed: one log or more")
    if len(titles) != len(logs):
        raise ValueError(f"{len(titles)} titles for {len(logs)} runs; allowed: one per run")
    runs = [
        run_json(log, title) if isinstance(log, SimulationLog) else corridor_run_json(log, title)
        for log, title in zip(logs, titles, strict=True)
    ]
    data = {"version": 1, "title": page_title, "runs": runs}
    parts = {
        "title": html.escape(page_title),
        "css": _asset("replay.css"),
        "js": "\n".join(_asset(name) for name in SCRIPTS),
        "data": _json_for_script(data),
    }
    return _SLOT.sub(lambda m: parts[m.group(1)], _asset("page.html"))
