"""Corridors as conditions of ``hcomc run`` and ``hcomc compare``.

``hcomc run CORRIDOR`` runs one configuration over seeds on a corridor;
``hcomc compare --conditions CORRIDOR[,CORRIDOR…]`` compares configurations on corridors,
paired by seed, into a resumable folder. A corridor of the paper's layout runs in the
scenario engine and is measured with the paper's metrics; any other runs in the corridor
engine with the configuration's controller at every on-ramp and is measured with the
corridor metrics (:mod:`hcomc.experiments.corridor.runs`). ``--set`` takes dotted corridor
keys (``corridor.duration=600``, ``demand.main.cav_share=0.5``, ``control.replan_period=2``).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.markup import escape

from hcomc.cli._app import _compiled, _engine, _fail, _progress, _settings, out
from hcomc.config import ConfigError

if TYPE_CHECKING:
    from hcomc.cli.compare_output import Presentation

CORRIDOR_SUCCESS = (
    "Merge success — runs in which every ramp vehicle that reached a control zone merged "
    "before the run ended"
)
"""Title of the merge-success table of a comparison on corridors."""

CORRIDOR_PAIRS = "A<B: k of n pairs (both with a value; failed merges are in the values)"
"""How the effects title explains n for the corridor metrics."""

CORRIDOR_NOTE = (
    "corridor metrics: merged = every merge event of the run merged before it ended (merge "
    "success counts these runs); the metrics are paired in every seed in which both runs "
    "have a value, merged or not, and a ramp vehicle that never merged lowers merged_share"
)
"""The note a comparison on corridors prints and puts in its report."""


def corridor_conditions(text: str | None, suite: str | None) -> list[str]:
    """The corridors ``--conditions`` names (presets or corridor files, each once, in the
    order given), or [] when it names cells of a suite; a one-line error for a mixture, a
    corridor file that does not exist, or ``--suite`` with corridors."""
    from hcomc.corridor import is_corridor_source

    items = [item.strip() for item in (text or "").split(",") if item.strip()]
    for item in items:
        if item.endswith(".toml") and not Path(item).is_file():
            raise _fail(f"option '--conditions': corridor file '{item}' does not exist")
    corridors = [item for item in items if is_corridor_source(item)]
    if not corridors:
        return []
    others = [item for item in items if item not in corridors]
    if others:
        raise _fail(
            f"option '--conditions' = '{text}' names corridors ({', '.join(corridors)}) and "
            f"cells of a suite ({', '.join(others)}); allowed: one or the other (--set takes "
            "scenario keys for cells and corridor keys for corridors)"
        )
    if suite is not None:
        raise _fail(
            f"option '--suite' = '{suite}' does not apply to corridor conditions; allowed: "
            "--suite with cells of the suite"
        )
    return list(dict.fromkeys(corridors))


def analysis_of(runs: Any) -> tuple[tuple[str, ...], dict[str, Any]]:
    """The notes and :func:`hcomc.cli.compare_output._analyse` options for a runs table: for runs
    of a corridor run (``kind`` "corridor" in every row) the corridor metrics with their
    wording; none otherwise (the paper's metrics)."""
    from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS

    if "kind" not in runs or not runs["kind"].eq("corridor").all():
        return (), {}
    options = {"metrics": tuple(CORRIDOR_METRICS), "success_title": CORRIDOR_SUCCESS,
               "pairs_note": CORRIDOR_PAIRS}  # fmt: skip
    return (CORRIDOR_NOTE,), options


def _known_engine(engine: str) -> None:
    """A one-line error for an engine name hcomc does not know (whether the engine can run
    a corridor is checked with the corridor)."""
    from hcomc.experiments.runner import ENGINES

    if engine not in ENGINES:
        _engine(engine)


def compare_corridors(
    labels: list[str],
    baseline: str | None,
    corridors: list[str],
    seeds: int | None,
    engine: str | None,
    workers: int,
    out_dir: Path | None,
    settings: list[str],
    presentation: Presentation,
) -> None:
    """``hcomc compare`` on corridors: run what the folder lacks, print and write the
    comparison (as for cells of a suite)."""
    from hcomc.cli.compare_folder import _command, fill_folder
    from hcomc.cli.compare_output import _analyse, _say
    from hcomc.experiments.comparison.effects import pairs
    from hcomc.experiments.corridor.compare import (
        CorridorComparison,
        check_folder,
        record,
        run_comparison,
        status,
    )
    from hcomc.experiments.corridor.runs import resolve
    from hcomc.experiments.suite import LATEST, suite_named

    _known_engine(engine or "hcomc")
    comparison = CorridorComparison(
        tuple(corridors), tuple(labels), seeds or suite_named(LATEST).seeds,
        _settings(settings), engine or "hcomc",
    )  # fmt: skip
    target = out_dir or Path("compare") / "-".join(Path(c).stem for c in corridors)
    try:
        kind = comparison.check()
        check_folder(target)
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    if kind == "scenario":
        _engine(comparison.engine, resolve(comparison.runs()[0]).scenario)
    command = _command({
        "controllers": ",".join(labels), "conditions": ",".join(corridors),
        "seeds": comparison.seeds, "baseline": baseline,
        "engine": None if comparison.engine == "hcomc" else comparison.engine,
        "out": str(target), "set": list(settings),
    })  # fmt: skip
    filled = fill_folder(target, comparison, command, workers, (status, record, run_comparison))
    engine_name = "engine, as corridors" if kind == "corridor" else f"engine {comparison.engine}"
    _say(f"corridors {', '.join(corridors)} · {comparison.seeds} seeds · {', '.join(labels)} "
         f"· {engine_name}")  # fmt: skip
    notes, options = analysis_of(filled.runs)
    _analyse(target, filled.runs, pairs(labels, baseline), labels, filled.record, notes,
             presentation=presentation, **options)  # fmt: skip
    filled.say("the corridor")


def run_corridor_condition(
    source: str,
    controller: str | None,
    optimizer: str | None,
    seeds: int,
    workers: int,
    as_json: bool,
    settings: list[str] | None,
    engine: str,
) -> None:
    """``hcomc run CORRIDOR``: one configuration over seeds 0..n-1; prints each run's metrics
    and their means with 95 % CIs (or the rows as JSON)."""
    from hcomc.cli.run_output import print_merge_runs, run_label
    from hcomc.corridor import load_corridor
    from hcomc.experiments.corridor.runs import CorridorSpec, check
    from hcomc.experiments.workers import run_rows

    _known_engine(engine)
    overrides = _settings(settings)
    try:
        corridor = load_corridor(source, overrides)
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    label = run_label(corridor.control, source, controller, optimizer, overrides, "corridor")
    specs = [CorridorSpec(source, label, seed, overrides, engine) for seed in range(seeds)]
    try:
        resolved = check(specs[0])
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    if resolved.scenario is not None:
        _engine(engine, resolved.scenario)
    _compiled(*(() if resolved.scenario is not None else ("corridor",)))
    with _progress("runs", len(specs)) as update:
        frame = run_rows(specs, workers=workers, progress=update)
    if as_json:
        sys.stdout.write(frame.to_json(orient="records", double_precision=15) + "\n")
    elif resolved.scenario is not None:
        print_merge_runs(frame, f"{source} · {label}", resolved.scenario.duration)
    else:
        print_corridor_runs(frame, f"{source} · {label} at every on-ramp")


def print_corridor_runs(frame: Any, title: str) -> None:
    """Print corridor runs: per seed the merge events and the corridor
    metrics, then each metric's mean with its 95 % CI over the seeds."""
    from hcomc.cli.run_output import mean_line, print_frame
    from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS

    labels = {name: metric.label for name, metric in CORRIDOR_METRICS.items()}
    heads = {"merged": "all merged", "events": "events", "merged_events": "merged events"}
    cols = ["seed", *heads, *labels]
    print_frame(frame[cols].rename(columns={**heads, **labels}), title)
    merged = frame["merged"].astype(bool)
    out.print(
        f"every merge event merged in {int(merged.sum())} of {len(frame)} runs (a ramp vehicle "
        "still on its acceleration lane when the run ends has not merged); merged share over "
        f"all runs: {frame['merged_events'].sum()} of {frame['events'].sum()} events",
        highlight=False,
    )
    for metric, name in labels.items():
        out.print(escape(mean_line(name, frame[metric])), highlight=False)
