"""``hcomc run`` and ``hcomc sweep``: many runs in parallel (``hcomc reproduce``:
:mod:`hcomc.cli.reproduce`)."""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer

from hcomc.cli._app import (
    ConfigArg,
    Engine,
    Optimizer,
    SetOption,
    _compiled,
    _engine,
    _fail,
    _load,
    _progress,
    _require_merge,
    _settings,
    app,
    out,
)
from hcomc.cli.run_output import print_merge_runs, run_label
from hcomc.config import ConfigError

CONDITIONS = ("C1", "C2", "C3", "C4", "C5")


def _workers(workers: int | None) -> int:
    import os

    if workers is None:
        return os.cpu_count() or 1
    if workers < 1:
        raise _fail(f"option '--workers' = {workers}: must be >= 1")
    return workers


def _progress_grid(
    specs: list, workers: int, on_result: Any = None, after: Any = (), on_after: Any = None
) -> Any:
    from hcomc.experiments.runner import run_grid

    _compiled()
    with _progress("runs", len(specs)) as update:
        return run_grid(
            specs, workers=workers, on_result=on_result, progress=update, after=after,
            on_after=on_after,
        )  # fmt: skip


@app.command()
def run(
    config: ConfigArg,
    controller: Annotated[
        str | None,
        typer.Option(
            help="Merge controller: fifo, game, hcomc (the paper's configurations), another "
            "registered name, package.module:Class or path/to/file.py:Class (default: the "
            "config's control.controller)."
        ),
    ] = None,
    optimizer: Optimizer = None,
    seeds: Annotated[int, typer.Option(help="Number of seeds (0 .. N-1).")] = 1,
    workers: Annotated[int | None, typer.Option(help="Processes (default: all cores).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the rows as JSON.")] = False,
    settings: SetOption = None,
    engine: Engine = "hcomc",
) -> None:
    """Run one scenario with one merge controller over seeds and print the paper's metrics.

    A corridor (preset or file) runs too: one of the paper's layout in the scenario engine
    (the paper's metrics), any other as a corridor run with the controller at every
    on-ramp (the corridor metrics); --set takes its dotted keys (corridor.duration=600)."""
    from hcomc.config import nest_overrides
    from hcomc.corridor import is_corridor_source
    from hcomc.experiments.runner import grid

    if seeds < 1:
        raise _fail(f"option '--seeds' = {seeds}: must be >= 1")
    if is_corridor_source(config):
        from hcomc.cli.corridor_conditions import run_corridor_condition

        run_corridor_condition(
            config, controller, optimizer, seeds, _workers(workers), as_json, settings, engine
        )
        return
    overrides = _settings(settings)
    base = _load(config, **overrides)  # validate before anything runs
    _require_merge(base, config, "run")
    engine = _engine(engine, base)
    label = run_label(base.control, config, controller, optimizer, overrides, "config")
    specs = [
        replace(s, engine=engine)
        for s in grid([config], [label], range(seeds), nest_overrides(overrides))
    ]
    frame = _progress_grid(specs, _workers(workers))
    if as_json:
        sys.stdout.write(frame.to_json(orient="records", double_precision=15) + "\n")
        return
    print_merge_runs(frame, f"{config} · {label}", base.duration)


@app.command()
def sweep(
    spec: Annotated[Path, typer.Argument(metavar="SPEC", help="Sweep spec (TOML).")],
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler address (default: local processes).")
    ] = None,
    workers: Annotated[
        int | None, typer.Option(help="Local processes (default: all cores).")
    ] = None,
    out_dir: Annotated[
        Path | None, typer.Option("--out", help="Results store (default: sweeps/NAME).")
    ] = None,
    engine: Annotated[
        str | None,
        typer.Option(help="Simulation engine: hcomc or sumo (default: the spec's, hcomc)."),
    ] = None,
) -> None:
    """Run a density x penetration x configuration x seed grid; rerun to resume.

    A spec whose base is a corridor sweeps its [corridor_grid] of dotted corridor keys."""
    from hcomc.experiments.sweep import expand, load_sweep, run_sweep, sweep_status
    from hcomc.experiments.workers import connect

    if scheduler is not None and workers is not None:
        raise _fail(
            f"option '--workers' = {workers} does not apply with '--scheduler': the Dask "
            "cluster's workers run the sweep"
        )
    try:
        plan = load_sweep(spec)
        if engine is not None:
            plan = plan.model_copy(update={"engine": _engine(engine)})
            expand(plan)  # every run can run on that engine
        if scheduler is not None:
            connect(scheduler).close()  # reachable before anything runs
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    n_workers = _workers(workers)
    target = out_dir or Path("sweeps") / plan.name
    if target.exists() and not target.is_dir():
        raise _fail(f"option '--out' = '{target}': exists and is not a directory")
    status = sweep_status(plan, target)
    if scheduler is None:
        _compiled()
    start = time.perf_counter()
    with _progress("sweep", status.total) as update:
        table = run_sweep(plan, target, workers=n_workers, scheduler=scheduler, progress=update)
    backend = scheduler or f"{n_workers} local processes"
    notes = [f"{status.new} new", f"{status.done} already done"]
    if status.changed:
        notes.append(f"{status.changed} recomputed because the config or the hcomc code changed")
    if status.stale:
        notes.append(f"{status.stale} stored parts of other configs ignored (kept)")
    out.print(
        f"{len(table)} runs ({', '.join(notes)}) on {backend} in "
        f"{time.perf_counter() - start:.1f} s · {target}/sweep.parquet, summary.csv",
        highlight=False,
    )
