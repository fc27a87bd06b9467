"""``hcomc simulate CORRIDOR`` for a corridor that is not one of the paper's conditions: the
engine on the corridor's road (:mod:`hcomc.metrics.corridor`), with the merge controller of the
corridor's ``[control]`` table (or ``--controller``) at every on-ramp."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pandas as pd

from hcomc.cli._app import _compiled, _control, _fail, _progress, _refuse_overwrite, out
from hcomc.config import ControlParams
from hcomc.corridor import Corridor, corridor_to_toml
from hcomc.viz.text_tables import TextTable, print_fitted

CORRIDOR_FILES = (
    "summary.json", "manifest.json", "corridor.toml", "trips.csv", "detectors.csv", "grid.csv",
    "backlog.csv", "collisions.csv", "merges.csv", "trajectories.csv", "corridor.html",
    "speed_heatmap.png", "flow_density.png", "travel_times.png",
)  # fmt: skip
"""What ``--out`` receives from a corridor run."""


def refuse_options(corridor: Corridor, why: str, options: dict[str, Any]) -> None:
    """A one-line error (exit 2) if an option the engine does not take is given."""
    for name, (value, allowed) in options.items():
        if value is not None and value != allowed:
            raise _fail(
                f"option '{name}' = {value!r}: allowed: {allowed!r} for corridor "
                f"'{corridor.name}' ({why}; it runs as a corridor)"
            )


def with_control(corridor: Corridor, controller: str | None, optimizer: str | None) -> Corridor:
    """``corridor`` with the command's ``--controller`` / ``--optimizer`` in its ``[control]``
    table (checked as for a scenario: a one-line error naming the option)."""
    if controller is None and optimizer is None:
        return corridor
    control = ControlParams(**_control(corridor.control, controller, optimizer))
    return corridor.model_copy(update={"control": control})


def run_corridor(
    corridor: Corridor, *, seed: int | None, duration: float | None, out_dir: Path | None,
    force: bool, as_json: bool, trajectory_interval: float,
) -> None:  # fmt: skip
    """Simulate ``corridor``, print its summary and write its tables to ``out_dir``."""
    from hcomc.metrics.corridor import simulate_corridor
    from hcomc.metrics.corridor.record import CORRIDOR_ENGINE
    from hcomc.robustness.impairments import impairment_summary, listeners_of
    from hcomc.sim.manifest import build_manifest, write_json_atomic
    from hcomc.viz.corridor import corridor_report_html, write_corridor_figures

    _refuse_overwrite(out_dir, CORRIDOR_FILES, force)
    _compiled("corridor")
    total = duration if duration is not None else corridor.corridor.duration
    steps = round(total / corridor.corridor.step_length)
    listeners = listeners_of(corridor)
    with _progress(f"{corridor.name}", steps) as update:
        tick = None if (as_json or update is None) else (
            lambda t, d: update(round(t / corridor.corridor.step_length), steps)
        )  # fmt: skip
        try:
            run = simulate_corridor(
                corridor, seed=seed, duration=duration,
                trajectory_interval=trajectory_interval, progress=tick, listeners=listeners,
            )  # fmt: skip
        except ValueError as exc:
            raise _fail(str(exc)) from None
    summary = run.summary()
    summary["vehicle_steps_per_s"] = round(run.vehicle_steps / max(run.wall_seconds, 1e-9))
    summary["detectors"] = _detector_summary(run.detectors)
    summary.update(impairment_summary(listeners))
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        manifest = build_manifest(
            seed=run.seed, config=corridor.model_dump(mode="json"),
            extra={"engine": CORRIDOR_ENGINE, "duration": run.duration,
                   "controller": run.controller, "trajectory_interval": trajectory_interval},
        )  # fmt: skip
        write_json_atomic(out_dir / "manifest.json", manifest)
        (out_dir / "corridor.toml").write_text(corridor_to_toml(corridor), encoding="utf-8")
        tables = {"trips": run.trips, "detectors": run.detectors, "grid": run.grid,
                  "backlog": run.backlog, "collisions": run.collisions,
                  "merges": run.merges}  # fmt: skip
        if run.trajectories is not None:
            tables["trajectories"] = run.trajectories
        for name, table in tables.items():
            table.to_csv(out_dir / f"{name}.csv", index=False)
        write_corridor_figures(run.grid, run.detectors, run.trips, out_dir)
        title = f"{corridor.name}, seed {run.seed}, {run.duration:g} s"
        corridor_report_html(run.grid, run.detectors, run.trips, out_dir, title=title,
                             merges=run.merges)  # fmt: skip
        summary["out"] = str(out_dir)
        write_json_atomic(out_dir / "summary.json", summary)
    if as_json:
        sys.stdout.write(json.dumps(summary) + "\n")
    else:
        _print(summary)


def _detector_summary(detectors: Any) -> list[dict[str, float]]:
    """Per cross-section: vehicles counted, mean flow [veh/h] and flow-weighted mean speed."""
    rows = []
    for x, at in detectors.groupby("x"):
        count = float(at["count"].sum())
        span = float(at.end.max() - at.begin.min())
        speed = (at.speed * at["count"]).sum() / count if count else float("nan")
        rows.append({"x": float(x), "count": int(count), "flow": 3600.0 * count / span,
                     "speed": float(speed)})  # fmt: skip
    return rows


def _print(summary: dict[str, Any]) -> None:
    out.print(
        f"[bold]{summary['corridor']}[/] seed {summary['seed']} · {summary['duration']:g} s · "
        f"{summary['vehicles']} vehicles: {summary['arrived']} arrived, "
        f"{summary['missed_exit']} missed their exit, {summary['on_road']} on the road, "
        f"{summary['not_inserted']} waiting to enter · {summary['collisions']} collisions · "
        f"{summary['vehicle_steps_per_s']:,} vehicle-steps/s"
    )
    origins = pd.DataFrame(
        [
            (origin, str(row["vehicles"]), str(row["arrived"]), _num(row["mean_travel_time"]),
             _num(row["mean_delay"]), str(row["max_backlog"]))
            for origin, row in summary["origins"].items()
        ],
        columns=["origin", "vehicles", "arrived", "travel time [s]", "delay [s]",
                 "max backlog [veh]"],
    )  # fmt: skip
    legend = "travel time and delay: means over the arrived trips"
    print_fitted(out, TextTable(origins, "Per origin", legend, tuple(origins.columns[1:])), 1)
    ramps = pd.DataFrame(
        [_ramp_row(ramp, row) for ramp, row in summary["on_ramps"].items()], columns=RAMP_COLUMNS
    )
    title = f"Per on-ramp (controller: {summary['controller']})"
    print_fitted(out, TextTable(ramps, title, RAMP_LEGEND, RAMP_COLUMNS[1:]), 1)


RAMP_COLUMNS = (
    "ramp", "entered", "merged", "merges/h", "merge position [m]", "zone to merge [s]",
    "least TTC, 5 % [s]", "max DRAC [m/s²]", "hardest braking [m/s²]", "plans", "fallbacks",
)  # fmt: skip
"""The columns of the per-on-ramp table."""

RAMP_LEGEND = (
    "merge position: mean distance of the merges from the start of the acceleration lane; "
    "zone to merge: mean "
    "time from entering the control zone to the merge; least TTC, 5 %: 5th percentile over "
    "the merges of each merge's least time to collision; max DRAC and hardest braking: the "
    "largest over every merge's key vehicles; plans, fallbacks: the controller's plans and "
    "those that fell back to car following"
)
"""What the per-on-ramp table's columns mean."""


def _ramp_row(ramp: str, row: dict[str, Any]) -> tuple[str, ...]:
    ev = row["merge_events"]
    return (
        ramp, str(row["entered"]), str(row["merged"]), f"{row['merges_per_hour']:.0f}",
        _num(row["mean_merge_position"]), _num(ev["mean_time_to_merge"]),
        _num(ev["min_ttc_p05"]), _num(ev["max_drac"]), _num(ev["max_decel"]),
        str(ev["plans"]), str(ev["fallbacks"]),
    )  # fmt: skip


def _num(value: float | None) -> str:
    return "–" if value is None else f"{value:.1f}"
