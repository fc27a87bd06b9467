"""``hcomc export trajectories``: a run's trajectories as highD-style tracks, SUMO FCD XML,
long CSV or a CommonRoad scenario (:mod:`hcomc.commonroad`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from hcomc.cli.sumo import _fresh_target, _out, export_app, fail
from hcomc.config import ScenarioConfig


def _run_log(run_dir: Path) -> tuple[Any, ScenarioConfig]:
    """The log of a `hcomc simulate --out` directory (or a log file) and its config."""
    from hcomc.config import ConfigError, validate_config
    from hcomc.metrics.corridor.record import is_corridor_run
    from hcomc.viz.inputs import load_log

    if is_corridor_run(run_dir):
        raise fail(
            f"RUN_DIR = '{run_dir}' is a corridor run, whose sampled trajectories "
            "are its trajectories.csv; allowed for it: --format commonroad"
        )
    try:
        log = load_log(run_dir)
        config = validate_config(log.meta["config"], f"{run_dir} (config in the log)")
    except (ValueError, ConfigError, KeyError, OSError) as exc:
        raise fail(f"RUN_DIR = '{run_dir}': {exc}") from None
    return log, config


@export_app.command("trajectories")
def export_trajectories(
    run_dir: Annotated[
        Path, typer.Argument(metavar="RUN_DIR", help="A `hcomc simulate --out` directory or log.")
    ],
    fmt: Annotated[str, typer.Option("--format", help="highd, fcd, csv or commonroad.")],
    out: Annotated[
        Path,
        typer.Option("--out", help="Output file (fcd, csv, commonroad) or directory (highd)."),
    ],
    force: Annotated[bool, typer.Option(help="Overwrite existing output.")] = False,
    planning_problem: Annotated[
        bool,
        typer.Option(
            "--planning-problem",
            help="commonroad: add VR's planning problem (VR is then no obstacle, and time "
            "step 0 is its first state); a corridor run: the first vehicle of its "
            "most upstream on-ramp.",
        ),
    ] = False,
    strict: Annotated[
        bool,
        typer.Option(
            "--strict",
            help="commonroad: leave out the vehicles entering after time step 0, as "
            "CommonRoad's XML schema (2020a) requires; with --planning-problem.",
        ),
    ] = False,
) -> None:
    """Write a run's trajectories as highD-style tracks, SUMO FCD XML, long CSV or a
    CommonRoad scenario (XML)."""
    from hcomc.sumo.fcd import write_fcd
    from hcomc.sumo.highd import write_highd
    from hcomc.sumo.trajectories import FORMATS, write_csv

    if fmt not in (*FORMATS, "commonroad"):
        raise fail(f"option '--format' = '{fmt}': allowed: {', '.join((*FORMATS, 'commonroad'))}")
    if fmt == "commonroad":
        _export_commonroad(run_dir, out, force, planning_problem, strict)
        return
    for option, given in (("--planning-problem", planning_problem), ("--strict", strict)):
        if given:
            raise fail(f"option '{option}': allowed only with --format commonroad")
    _fresh_target(out, "--out", force)
    log, config = _run_log(run_dir)
    if fmt == "fcd":
        written = write_fcd(log, out, config)
    elif fmt == "csv":
        written = write_csv(log, out)
    else:
        if out.exists() and not out.is_dir():
            raise fail(f"option '--out' = '{out}': --format highd writes a directory")
        written = write_highd(log, out, config)
    _out.print(f"wrote {written}")


def _export_commonroad(
    run_dir: Path, out: Path, force: bool, planning_problem: bool, strict: bool
) -> None:
    """`hcomc export trajectories --format commonroad` (:mod:`hcomc.commonroad`)."""
    from hcomc.commonroad import commonroad_missing

    missing = commonroad_missing()
    if missing is not None:
        raise fail(f"option '--format' = 'commonroad': {missing}")
    if strict and not planning_problem:
        raise fail(
            "option '--strict' needs '--planning-problem': CommonRoad's XML schema also "
            "requires a planning problem in every file"
        )
    if out.is_dir() or not out.parent.is_dir():
        raise fail(f"option '--out' = '{out}': allowed: a file (.xml) in an existing directory")
    _fresh_target(out, "--out", force)
    if not run_dir.exists():
        raise fail(f"RUN_DIR = '{run_dir}': does not exist")
    from hcomc.commonroad.export import export_commonroad

    try:
        summary = export_commonroad(run_dir, out, planning_problem=planning_problem, strict=strict)
    except ValueError as exc:
        raise fail(f"RUN_DIR = '{run_dir}': {exc}") from None
    except OSError as exc:
        raise fail(f"option '--out' = '{out}': {exc}") from None
    _out.print(summary.line(), highlight=False, soft_wrap=True)
