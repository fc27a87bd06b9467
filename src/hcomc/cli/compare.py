"""``hcomc compare``: merge controllers side by side on a benchmark suite, paired by seed.

Two forms: ``hcomc compare --controllers fifo,game,mine ...`` runs what its folder lacks of
suite cells x controllers x seeds (resumable) and compares them; ``hcomc compare A/ B/``
compares the configurations two existing results folders share. Both print merge success,
its paired comparison and the paired effects, and write the tables and an HTML report
(:mod:`hcomc.cli.compare_output`). ``--conditions`` may name corridors instead of suite cells
(:mod:`hcomc.cli.corridor_conditions`).
"""

from __future__ import annotations

import shlex
import sys
from contextlib import nullcontext, redirect_stdout
from pathlib import Path
from typing import Annotated

import typer

from hcomc.cli._app import (
    SetOption,
    _engine,
    _fail,
    _settings,
    app,
)
from hcomc.cli.compare_folder import _command, fill_folder
from hcomc.cli.compare_output import FORMATS, OUTPUTS, Presentation, _analyse, _say
from hcomc.cli.experiments import _workers
from hcomc.config import ConfigError


def _labels(names: str | None) -> list[str]:
    """``--controllers``: configuration labels or controller names, each checked now
    (:func:`hcomc.experiments.controller_arguments.configuration_labels`)."""
    from hcomc.experiments.controller_arguments import configuration_labels

    if names is None:
        raise _fail("option '--controllers' is missing; allowed: two or more, e.g. fifo,game,hcomc")
    try:
        return configuration_labels(names, key="option '--controllers'")
    except ConfigError as exc:
        raise _fail(str(exc)) from None


def _baseline(value: str | None, labels: list[str]) -> str | None:
    """``--baseline``: one of the compared configurations, checked now."""
    from hcomc.experiments.controller_arguments import baseline_label

    if value is None:
        return None
    try:
        return baseline_label(value, labels, key="option '--baseline'")
    except ConfigError as exc:
        raise _fail(str(exc)) from None


@app.command()
def compare(
    folders: Annotated[
        list[Path] | None,
        typer.Argument(
            metavar="A/ B/",
            help="Two results folders (of hcomc compare or hcomc reproduce) to compare instead "
            "of running: the configurations they share, paired by cell and seed.",
        ),
    ] = None,
    controllers: Annotated[
        str | None,
        typer.Option(
            help="Configurations to compare, comma-separated: fifo, game, hcomc (and the "
            "other labels of hcomc reproduce), a registered name, package.module:Class or "
            "path/to/file.py:Class."
        ),
    ] = None,
    conditions: Annotated[
        str | None,
        typer.Option(
            help="Cells of the suite: ids and ranges, e.g. C1,C2 or C1..C5 (default: all); or "
            "corridors: presets or corridor files, e.g. corridor or my_road.toml (--set then "
            "takes dotted corridor keys, e.g. corridor.duration=600)."
        ),
    ] = None,
    seeds: Annotated[
        int | None, typer.Option(help="Seeds 0..N-1 per cell (default: the suite's, 30).")
    ] = None,
    suite: Annotated[str | None, typer.Option(help="Benchmark suite (default: merge-v1).")] = None,
    baseline: Annotated[
        str | None,
        typer.Option(help="Compare every configuration with this one only (default: every pair)."),
    ] = None,
    engine: Annotated[
        str | None,
        typer.Option(help="Simulation engine: hcomc, or sumo (SUMO co-simulation, hcomc[sumo])."),
    ] = None,
    workers: Annotated[int | None, typer.Option(help="Processes (default: all cores).")] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option("--out", help="Results folder (default: compare/SUITE, or compare/A-vs-B)."),
    ] = None,
    settings: SetOption = None,
    fmt: Annotated[
        str,
        typer.Option(
            "--format",
            help="How the tables print: console (fitted to 120 columns), markdown or latex "
            "(one document on stdout, also written to tables.md / tables.tex; the other lines "
            "go to stderr).",
        ),
    ] = "console",
    wide: Annotated[
        bool,
        typer.Option(
            help="Console tables on one line each, every column (all comparisons in "
            "one effects table)."
        ),
    ] = False,
) -> None:
    """Compare merge controllers on a benchmark suite, paired by seed; rerun to resume.

    Prints merge success, each controller's means ± 95 % CI and safety extremes (least TTC,
    largest DRAC, collisions) and the paired effects on the paper's five metrics (median
    difference with its 95 % CI, sign test with Holm's correction, the controller each
    favours) and writes runs.parquet, runs.csv, effects.csv, success.csv, success_pairs.csv,
    means.csv, safety.csv, compare.json and report.html."""
    if fmt not in FORMATS:
        raise _fail(f"option '--format' = '{fmt}': allowed: {', '.join(FORMATS)}")
    if wide and fmt != "console":
        raise _fail(f"option '--wide' applies to --format console, not '{fmt}'")
    presentation = Presentation(fmt, wide, None if fmt == "console" else sys.stdout)
    with redirect_stdout(sys.stderr) if presentation.document else nullcontext():
        if folders:
            given = {"--controllers": controllers, "--conditions": conditions, "--seeds": seeds,
                     "--suite": suite, "--baseline": baseline, "--engine": engine,
                     "--workers": workers, "--set": settings}  # fmt: skip
            extra = [k for k, v in given.items() if v]
            if extra:
                raise _fail(
                    f"option '{extra[0]}' does not apply when comparing folders; allowed: "
                    "hcomc compare A/ B/ [--out DIR]"
                )
            _compare_folders(folders, out_dir, presentation)
            return
        _compare_controllers(
            controllers,
            conditions,
            seeds,
            suite,
            baseline,
            engine,
            workers,
            out_dir,
            settings,
            presentation,
        )


def _compare_controllers(
    controllers: str | None,
    conditions: str | None,
    seeds: int | None,
    suite_name: str | None,
    baseline: str | None,
    engine: str | None,
    workers: int | None,
    out_dir: Path | None,
    settings: list[str] | None,
    presentation: Presentation,
) -> None:
    from hcomc.cli.corridor_conditions import compare_corridors, corridor_conditions
    from hcomc.config import nest_overrides
    from hcomc.experiments.benchmark import (
        Comparison,
        check_folder,
        record,
        run_comparison,
        status,
    )
    from hcomc.experiments.comparison.effects import pairs
    from hcomc.experiments.suite import LATEST, suite_named

    labels = _labels(controllers)
    chosen = _baseline(baseline, labels)
    if seeds is not None and seeds < 1:
        raise _fail(f"option '--seeds' = {seeds}: must be >= 1")
    n_workers = _workers(workers)
    corridors = corridor_conditions(conditions, suite_name)
    if corridors:
        compare_corridors(
            labels,
            chosen,
            corridors,
            seeds,
            engine,
            n_workers,
            out_dir,
            settings or [],
            presentation,
        )
        return
    try:
        bench = suite_named(suite_name or LATEST)
        cells = bench.select(conditions)
        comparison = Comparison(
            bench, cells, tuple(labels), seeds or bench.seeds,
            nest_overrides(_settings(settings)), _engine(engine or "hcomc"),
        )  # fmt: skip
        comparison.check()
        if comparison.engine != "hcomc":
            _engine(comparison.engine, cells[0].config(**comparison.overrides))
        target = out_dir or Path("compare") / bench.name
        check_folder(target, bench)
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    command = _command({
        "controllers": ",".join(labels), "conditions": ",".join(c.id for c in cells),
        "seeds": comparison.seeds, "suite": bench.name, "baseline": chosen,
        "engine": None if comparison.engine == "hcomc" else comparison.engine,
        "out": str(target), "set": list(settings or []),
    })  # fmt: skip
    filled = fill_folder(target, comparison, command, n_workers,
                         (status, record, run_comparison))  # fmt: skip
    _say(
        f"suite {bench.name} · cells {', '.join(c.id for c in cells)} · {comparison.seeds} "
        f"seeds · {', '.join(labels)} · engine {comparison.engine}",
    )
    _analyse(target, filled.runs, pairs(labels, chosen), labels, filled.record,
             presentation=presentation)  # fmt: skip
    filled.say("the config")


def _compare_folders(folders: list[Path], out_dir: Path | None, presentation: Presentation) -> None:
    from hcomc.cli.corridor_conditions import analysis_of
    from hcomc.experiments.benchmark import folder_runs, stored_record
    from hcomc.sim.manifest import build_manifest

    try:
        both = folder_runs(folders)
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    name = "-vs-".join(label.strip("/").replace("/", "_") for label in both.labels)
    target = out_dir or Path("compare") / name
    if target.exists() and not target.is_dir():
        raise _fail(f"option '--out' = '{target}': exists and is not a directory")
    if target.resolve() in {f.resolve() for f in folders}:
        raise _fail(f"option '--out' = '{target}' is a compared folder; allowed: another folder")
    if (target / "parts").exists() or stored_record(target) is not None:
        raise _fail(
            f"option '--out' = '{target}' holds runs of a comparison; allowed: another folder"
        )
    manifest = build_manifest(seed=0, config={})
    content = {
        "command": shlex.join(["hcomc", "compare", *map(str, folders), "--out", str(target)]),
        "folders": [str(f) for f in folders],
        "hcomc_version": manifest["hcomc_version"],
        "git_revision": manifest["git_revision"],
        "created_utc": manifest["created_utc"],
    }
    target.mkdir(parents=True, exist_ok=True)
    confs = [c for pair in both.comparisons for c in pair]
    _say(
        f"comparing {both.labels[1]} (A) with {both.labels[0]} (B): "
        + ", ".join(f"{a} vs {b}" for a, b in both.comparisons),
    )
    notes, options = analysis_of(both.runs)  # corridor runs: the corridor metrics
    _analyse(target, both.runs, list(both.comparisons), confs, content, (*both.notes, *notes),
             presentation=presentation, **options)  # fmt: skip
    _say(f"written to {target}/ ({', '.join(OUTPUTS)})")
