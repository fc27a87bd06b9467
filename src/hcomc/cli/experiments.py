"""``hcomc run``, ``hcomc reproduce`` and ``hcomc sweep``: many runs in parallel."""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Annotated, Any, cast

import typer
from rich.markup import escape
from rich.table import Table

from hcomc.cli._app import (
    CONTROLLERS,
    ConfigArg,
    Engine,
    Optimizer,
    SetOption,
    _choice,
    _control,
    _engine,
    _fail,
    _load,
    _progress,
    _refuse_overwrite,
    _require_merge,
    _settings,
    app,
    out,
)
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

    with _progress("runs", len(specs)) as update:
        return run_grid(
            specs, workers=workers, on_result=on_result, progress=update, after=after,
            on_after=on_after,
        )  # fmt: skip


def _frame_table(frame: Any, title: str) -> Table:
    table = Table(title=escape(title))
    for col in frame.columns:
        table.add_column(escape(str(col)), justify="left" if col in ("claim", "Model") else "right")
    for _, row in frame.iterrows():
        table.add_row(*(escape(f"{v:.2f}" if isinstance(v, float) else str(v)) for v in row))
    return table


@app.command()
def run(
    config: ConfigArg,
    controller: Annotated[str, typer.Option(help="Merge controller: fifo, game or hcomc.")],
    optimizer: Optimizer = None,
    seeds: Annotated[int, typer.Option(help="Number of seeds (0 .. N-1).")] = 1,
    workers: Annotated[int | None, typer.Option(help="Processes (default: all cores).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the rows as JSON.")] = False,
    settings: SetOption = None,
    engine: Engine = "hcomc",
) -> None:
    """Run one scenario with one merge controller over seeds and print the paper's metrics."""
    from hcomc.config import nest_overrides
    from hcomc.experiments.runner import CONFIGURATIONS, grid
    from hcomc.experiments.tables import LABELS, mean_ci

    chosen = _choice("--controller", controller, CONTROLLERS[1:])
    assert chosen is not None  # a required option
    controller = chosen
    if seeds < 1:
        raise _fail(f"option '--seeds' = {seeds}: must be >= 1")
    overrides = _settings(settings)
    base = _load(config, **overrides)  # validate before anything runs
    _require_merge(base, config, "run")
    engine = _engine(engine, base)
    control = _control(base, controller, optimizer)
    labels = {pair: label for label, pair in CONFIGURATIONS.items()}
    label = labels[(controller, control["optimizer"] if controller == "hcomc" else "nsga2")]
    specs = [
        replace(s, engine=engine)
        for s in grid([config], [label], range(seeds), nest_overrides(overrides))
    ]
    frame = _progress_grid(specs, _workers(workers))
    if as_json:
        sys.stdout.write(frame.to_json(orient="records") + "\n")
        return
    frame = frame.reindex(columns=[*frame.columns, *(m for m in LABELS if m not in frame)])
    cols = ["seed", "mode", "decision_ms", *LABELS]
    out.print(_frame_table(frame[cols].rename(columns=LABELS), f"{config} · {label}"))
    unplanned = frame.loc[frame["mode"] == "", "seed"].tolist()
    if unplanned:
        out.print(
            f"no merge planned in seed(s) {unplanned}: no ramp vehicle entered the control "
            f"zone within duration = {base.duration} s, so these seeds have no metrics"
        )
    for metric, name in LABELS.items():
        mean, half, n = mean_ci(frame[metric].dropna())
        out.print(escape(f"{name}: {mean:.4g} ± {half:.2g} (95 % CI, n = {n})"))


CONTOUR_CONDITION = "C2"
"""The condition of the report's speed contour maps (the paper's Fig. 2)."""


def _write_report(out_dir: Path, runs: Any, claim_frame: Any, contour: Any) -> Path:
    """results/report.html with the tables, claims, Fig. 2 (``contour``: the PNG of
    :func:`hcomc.viz.report.contour_png` for the first seed, or the exception it raised in
    its worker, raised here once the tables are saved) and the metric plots."""
    from hcomc.viz.figures import metrics_figure
    from hcomc.viz.report import figure_png, write_report

    if isinstance(contour, BaseException):
        raise contour

    seed = int(runs["seed"].min())
    figures = {
        f"Speed contour maps of both lanes as in the paper's Fig. 2: Condition 2, seed {seed}, "
        "FIFO, Game and HCOMC":
            contour,
        "The paper's metrics by condition and configuration (mean, 95 % CI over seeds; a "
        "bar marked n=k rests on the k seeds that give a value)":
            figure_png(metrics_figure(runs)),
    }  # fmt: skip
    return write_report(out_dir, runs, figures=figures, claim_frame=claim_frame)


PAPER_SCENARIO: dict[str, dict[str, Any]] = {
    "demand": {"pattern": "uniform"},
    "hdv": {"estimation_errors": False},
}
"""Overrides of the deterministic paper scenario: every headway equal to its mean, CAVs
spread evenly, no HDV estimation errors (reaction delays stay); seed 0 seeds the optimisers."""


def _claims_view(frame: Any) -> Any:
    """The claims with numbers formatted for the terminal (4 significant digits)."""
    view = frame.drop(columns=["share", "metric", "paper_diff"], errors="ignore").copy()
    for col in ("median_diff", "ci_low", "ci_high"):
        view[col] = [f"{v:.4g}" for v in frame[col]]
    view["holds"] = [f"{k} of {n}" for k, n in zip(frame["holds"], frame["n"], strict=True)]
    return view.drop(columns=["n"])


REPRODUCE_FILES = ("runs.csv", "claims.csv", "table2.md", "table3.md")


@app.command()
def reproduce(
    seeds: Annotated[int, typer.Option(help="Seeds per condition and configuration.")] = 30,
    workers: Annotated[int | None, typer.Option(help="Processes (default: all cores).")] = None,
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path("results"),
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite results already in the --out directory.")
    ] = False,
    settings: SetOption = None,
    engine: Engine = "hcomc",
) -> None:
    """Reproduce the paper: Table I conditions x (FIFO, Game, HCOMC with NSGA-II, PSO, SA,
    and the replanning baselines FIFO-R, Game-R), seeded runs plus the deterministic paper
    scenario. --set changes a config value for every run (e.g. a sensitivity check)."""
    from hcomc.config import nest_overrides
    from hcomc.experiments.claims import claims
    from hcomc.experiments.paper import PAPER_METRICS
    from hcomc.experiments.runner import ALL_CONFIGURATIONS, grid
    from hcomc.experiments.tables import paper_table, to_markdown
    from hcomc.sim.manifest import atomic_paths, write_json_atomic
    from hcomc.viz.report import contour_png

    if seeds < 1:
        raise _fail(f"option '--seeds' = {seeds}: must be >= 1")
    _refuse_overwrite(out_dir, REPRODUCE_FILES, force)
    overrides = nest_overrides(_settings(settings))
    for condition in CONDITIONS:  # validate before anything runs
        _load(condition, **overrides)
    n_workers, engine = _workers(workers), _engine(engine)
    start = time.perf_counter()
    seeded = [
        replace(s, engine=engine)
        for s in grid(CONDITIONS, ALL_CONFIGURATIONS, range(seeds), overrides)
    ]
    paper = {**overrides}
    for table, values in PAPER_SCENARIO.items():
        paper[table] = {**cast(dict[str, Any], overrides.get(table, {})), **values}
    uniform = [replace(s, engine=engine) for s in grid(CONDITIONS, ALL_CONFIGURATIONS, [0], paper)]
    (out_dir / "manifests").mkdir(parents=True, exist_ok=True)

    def save_manifest(i: int, row: dict[str, Any], manifest: dict[str, Any]) -> None:
        tag = f"seed{row['seed']}" if i < len(seeded) else "uniform"
        name = f"{row['condition']}-{row['configuration']}-{tag}.json"
        write_json_atomic(out_dir / "manifests" / name, manifest)

    # the report's Fig. 2 is drawn by a worker process while the last runs finish
    contour: dict[int, Any] = {}  # the PNG, or the exception drawing it raised
    figure_2 = partial(contour_png, CONTOUR_CONDITION, min(s.seed for s in seeded), overrides)
    both = _progress_grid(
        [*seeded, *uniform], n_workers, on_result=save_manifest, after=[figure_2],
        on_after=contour.__setitem__,
    )  # fmt: skip
    runs = both.iloc[: len(seeded)].reset_index(drop=True)
    paper_runs = both.iloc[len(seeded) :].reset_index(drop=True)
    table2, table3 = paper_table(runs, "II"), paper_table(runs, "III")
    claim_rows = claims(runs, paper_runs)
    scenario_cols = ["condition", "configuration", "mode", "sequence", *PAPER_METRICS]
    scenario = paper_runs[scenario_cols]
    with atomic_paths(
        out_dir / "runs.csv",
        out_dir / "runs.parquet",
        out_dir / "table2.md",
        out_dir / "table3.md",
        out_dir / "claims.csv",
        out_dir / "paper_scenario.csv",
    ) as tmp:
        runs.to_csv(tmp[0], index=False)
        runs.to_parquet(tmp[1], index=False)
        tmp[2].write_text(to_markdown(table2), encoding="utf-8")
        tmp[3].write_text(to_markdown(table3), encoding="utf-8")
        claim_rows.to_csv(tmp[4], index=False)
        paper_runs.to_csv(tmp[5], index=False)
    report = _write_report(out_dir, runs, claim_rows, contour[0])
    note = "ours: mean ± 95 % CI over seeds (paper value)"
    out.print(_frame_table(table2, f"Table II — optimisers · {note}"))
    out.print(_frame_table(table3, f"Table III — controllers · {note}"))
    view = scenario.assign(**{m: [f"{v:.4g}" for v in scenario[m]] for m in PAPER_METRICS})
    out.print(_frame_table(view, "Paper scenario — deterministic demand, one run each"))
    title = "Claims of Section IV — median paired difference A - B [95 % bootstrap CI]"
    out.print(_frame_table(_claims_view(claim_rows), title))
    held = int((claim_rows["share"] > 0.5).sum())
    out.print(f"report: {report}")
    out.print(
        f"{held} of {len(claim_rows)} claims hold in a majority of seeds · {len(both)} runs "
        f"· {n_workers} workers · {time.perf_counter() - start:.1f} s · written to "
        f"{out_dir}/"
    )


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
    """Run a density x penetration x configuration x seed grid; rerun to resume."""
    from hcomc.experiments.sweep import connect, load_sweep, run_sweep, sweep_status

    if scheduler is not None and workers is not None:
        raise _fail(
            f"option '--workers' = {workers} does not apply with '--scheduler': the Dask "
            "cluster's workers run the sweep"
        )
    try:
        plan = load_sweep(spec)
        if engine is not None:
            plan = plan.model_copy(update={"engine": _engine(engine)})
        if scheduler is not None:
            connect(scheduler).close()  # reachable before anything runs
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    n_workers = _workers(workers)
    target = out_dir or Path("sweeps") / plan.name
    if target.exists() and not target.is_dir():
        raise _fail(f"option '--out' = '{target}': exists and is not a directory")
    status = sweep_status(plan, target)
    start = time.perf_counter()
    with _progress("sweep", status.total) as update:
        table = run_sweep(plan, target, workers=n_workers, scheduler=scheduler, progress=update)
    backend = scheduler or f"{n_workers} local processes"
    notes = [f"{status.new} new", f"{status.done} already done"]
    if status.changed:
        notes.append(f"{status.changed} recomputed because the config or hcomc version changed")
    if status.stale:
        notes.append(f"{status.stale} stored parts of other configs ignored (kept)")
    out.print(
        f"{len(table)} runs ({', '.join(notes)}) on {backend} in "
        f"{time.perf_counter() - start:.1f} s · {target}/sweep.parquet, summary.csv",
        highlight=False,
    )
