"""Command-line interface (typer + rich).

Every command validates its input before anything runs; a bad value prints one line naming
the key, the value and what is allowed, and exits with status 2 (no traceback).
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any, cast

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from hcomc.config import ConfigError, ScenarioConfig, config_to_toml, load_config

app = typer.Typer(
    name="hcomc",
    help="Cooperative on-ramp merging (HCOMC) in mixed traffic on two-lane highways.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: flags shown as flags, "[s]" units kept literally
    context_settings={"help_option_names": ["-h", "--help"]},
)
config_app = typer.Typer(help="Inspect scenario configs.", no_args_is_help=True)
app.add_typer(config_app, name="config")

# piped output (files, CI logs) gets wide tables instead of rich's 80-column default
out = Console(width=None if sys.stdout.isatty() else 200)
err = Console(stderr=True, width=None if sys.stderr.isatty() else 200)

CONTROLLERS = ("none", "fifo", "game", "hcomc")
OPTIMIZERS = ("nsga2", "pso", "sa")

ConfigArg = Annotated[
    str,
    typer.Argument(
        metavar="CONFIG", help="Preset name (C1..C5, platoon) or path to a TOML config file."
    ),
]
SetOption = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        metavar="KEY=VALUE",
        help="Override a config value, e.g. --set cav_penetration=0.5 or "
        "--set demand.mean_headway_main_2=7 (repeatable; VALUE is read as TOML).",
    ),
]
SeedOption = Annotated[int | None, typer.Option(help="Random seed (default: the config's).")]
Optimizer = Annotated[
    str | None, typer.Option(help="HCOMC optimiser: nsga2, pso or sa (default: the config's).")
]


def _show_version(value: bool) -> None:
    if value:
        from hcomc import __version__

        out.print(f"hcomc {__version__}", highlight=False)
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_show_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """Cooperative on-ramp merging (HCOMC) in mixed traffic on two-lane highways."""


@contextmanager
def _progress(label: str, total: int) -> Iterator[Callable[[int, int], None] | None]:
    """A progress-bar callback ``(done, total)`` on a terminal; None when output is piped."""
    if not out.is_terminal:
        yield None
        return
    with Progress(
        TextColumn(f"[bold]{escape(label)}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeRemainingColumn(),
        console=out,
        transient=True,
    ) as bar:
        task = bar.add_task(label, total=total)
        yield lambda done, _total: bar.update(task, completed=done)


def _fail(message: str) -> typer.Exit:
    err.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    return typer.Exit(code=2)


def _load(source: str, **overrides: Any) -> ScenarioConfig:
    try:
        return load_config(source, **overrides)
    except ConfigError as exc:
        raise _fail(str(exc)) from None


def _settings(pairs: list[str] | None) -> dict[str, Any]:
    """``--set KEY=VALUE`` pairs as overrides; VALUE is TOML (a bare word is a string)."""
    import tomllib

    settings: dict[str, Any] = {}
    for pair in pairs or []:
        key, sep, text = pair.partition("=")
        if not sep or not key.strip():
            raise _fail(f"option '--set' = '{pair}': allowed: KEY=VALUE, e.g. duration=60")
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        settings[key.strip()] = value
    return settings


def _with(overrides: dict[str, Any], **options: Any) -> dict[str, Any]:
    """``--set`` overrides plus the command's own options (None = not given)."""
    given = {k: v for k, v in options.items() if v is not None}
    for key, value in given.items():
        if key in overrides and key != "control" and overrides[key] != value:
            raise _fail(
                f"option '--{key}' = {value} conflicts with '--set {key}={overrides[key]}'; "
                "allowed: one of them"
            )
    return {**overrides, **given}


def _choice(option: str, value: str | None, allowed: tuple[str, ...]) -> str | None:
    """``value`` lower-cased if it is one of ``allowed`` (names are case-insensitive)."""
    if value is None or value.lower() in allowed:
        return None if value is None else value.lower()
    key = f"control.{option.removeprefix('--')}"  # the config key the option sets
    raise _fail(f"option '{option}' = '{value}' ({key}): allowed: {', '.join(allowed)}")


def _check_seed(seed: int | None) -> None:
    if seed is not None and seed < 0:
        raise _fail(f"option '--seed' = {seed}: must be >= 0")


def _control(base: ScenarioConfig, controller: str | None, optimizer: str | None) -> dict:
    """The ``[control]`` table with the command's controller/optimiser; an optimiser only
    applies to HCOMC, so passing one to another controller is an error, not ignored."""
    controller = _choice("--controller", controller, CONTROLLERS)
    optimizer = _choice("--optimizer", optimizer, OPTIMIZERS)
    control = base.control.model_dump()
    control.update({k: v for k, v in (("controller", controller), ("optimizer", optimizer)) if v})
    if optimizer is not None and control["controller"] != "hcomc":
        raise _fail(
            f"option '--optimizer' = '{optimizer}' does not apply to controller "
            f"'{control['controller']}'; allowed: only with --controller hcomc"
        )
    return control


@config_app.command("show")
def config_show(config: ConfigArg, settings: SetOption = None) -> None:
    """Print the fully resolved config as TOML, each key with its meaning and unit.

    The output is loadable by every command: hcomc config show C2 > my.toml.
    """
    sys.stdout.write(config_to_toml(_load(config, **_settings(settings)), annotate=True))


def _refuse_overwrite(out_dir: Path | None, names: tuple[str, ...], force: bool) -> None:
    """Stop before a run if ``out_dir`` is a file or already holds a run (unless --force)."""
    if out_dir is None:
        return
    if out_dir.exists() and not out_dir.is_dir():
        raise _fail(f"option '--out' = '{out_dir}': exists and is not a directory")
    existing = [n for n in names if (out_dir / n).exists()]
    if existing and not force:
        raise _fail(
            f"option '--out' = '{out_dir}' already holds a run ({', '.join(existing)}); "
            "allowed: a new directory, or --force to overwrite it"
        )


SIMULATE_FILES = ("log.npz", "manifest.json", "summary.json")
Engine = Annotated[
    str, typer.Option(help="Simulation engine: hcomc, or sumo (SUMO co-simulation, hcomc[sumo]).")
]


def _engine(engine: str, config: ScenarioConfig | None = None) -> str:
    """Validate --engine (SUMO installed and able to run ``config`` when asked for)."""
    from hcomc.sumo.cli import engine_error

    problem = engine_error(engine, config)
    if problem is not None:
        raise _fail(problem)
    return engine


@app.command()
def simulate(
    config: ConfigArg,
    seed: SeedOption = None,
    duration: Annotated[
        float | None, typer.Option(help="Measured duration [s] (default: the config's).")
    ] = None,
    out_dir: Annotated[
        Path | None, typer.Option("--out", help="Write log.npz, manifest.json, summary.json here.")
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Overwrite a run already in the --out directory.")
    ] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
    controller: Annotated[
        str | None,
        typer.Option(help="Merge controller: none, fifo, game, hcomc (default: the config's)."),
    ] = None,
    optimizer: Optimizer = None,
    settings: SetOption = None,
    engine: Engine = "hcomc",
) -> None:
    """Simulate a scenario (merge controller from the config or --controller) and summarise."""
    from hcomc.experiments.runner import make_simulation
    from hcomc.sim.manifest import write_json_atomic
    from hcomc.sim.summary import summarise

    _check_seed(seed)
    overrides = _settings(settings)
    control = _control(_load(config, **overrides), controller, optimizer)
    cfg = _load(config, **_with(overrides, duration=duration, seed=seed, control=control))
    _refuse_overwrite(out_dir, SIMULATE_FILES, force)
    sim = make_simulation(cfg, None, _engine(engine, cfg))
    start = time.perf_counter()
    with _progress(f"{cfg.name} seed {sim.seed}", sim.n_warmup + sim.n_steps) as update:
        log = sim.run(None if as_json else update)
    wall = time.perf_counter() - start
    summary: dict[str, Any] = {
        "scenario": cfg.name,
        "seed": sim.seed,
        "controller": cfg.control.controller,
        "optimizer": cfg.control.optimizer if cfg.control.controller == "hcomc" else None,
        **summarise(log),
    }
    summary["wall_s"] = round(wall, 4)
    summary["vehicle_steps_per_s"] = round(summary["vehicle_steps"] / max(wall, 1e-9))
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        log.save(out_dir / "log.npz")
        write_json_atomic(out_dir / "manifest.json", log.meta)
        write_json_atomic(out_dir / "summary.json", summary)
        summary["out"] = str(out_dir)
    if as_json:
        sys.stdout.write(json.dumps(summary) + "\n")
    else:
        _print_summary(summary)


def _require_merge(cfg: ScenarioConfig, source: str, command: str) -> None:
    """Merge-controller commands need a merge scenario with ramp demand."""
    if cfg.scenario != "merge" or cfg.demand.ramp == "none":
        what = f"scenario = '{cfg.scenario}'" if cfg.scenario != "merge" else "demand.ramp = 'none'"
        raise _fail(
            f"no ramp vehicle entered the control zone: '{source}' has {what}, so '{command}' "
            "has no merge to control; allowed: a merge scenario with ramp demand (C1..C5, or "
            "scenario = 'merge' with demand.ramp = 'single' or 'flow'); use 'hcomc simulate' "
            "otherwise"
        )


@app.command()
def plan(
    config: ConfigArg,
    seed: SeedOption = None,
    optimizer: Optimizer = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the decision as JSON.")] = False,
    settings: SetOption = None,
) -> None:
    """Run until the first ramp vehicle enters the control zone and show HCOMC's decision."""
    from hcomc.control.report import plan_report
    from hcomc.sim.engine import Simulation

    _check_seed(seed)
    overrides = _settings(settings)
    base = _load(config, **overrides)
    _require_merge(base, config, "plan")
    control = _control(base, "hcomc", optimizer)
    cfg = _load(config, **_with(overrides, seed=seed, control=control))
    sim = Simulation(cfg)
    decision = sim.run_until_plan()
    if decision is None:
        raise _fail(
            f"no ramp vehicle entered the control zone within duration = {cfg.duration} s "
            f"of '{config}'; allowed: a longer --set duration=... or an earlier ramp release"
        )
    report = plan_report(sim, decision)
    if as_json:
        sys.stdout.write(json.dumps(report) + "\n")
    else:
        _print_plan(report)


def _print_plan(report: dict[str, Any]) -> None:
    out.print(
        f"[bold]{report['scenario']}[/] seed {report['seed']} · t = {report['t']:.1f} s · "
        f"optimiser {report['optimizer']} · {report['n_eval']} evaluations · "
        f"decision {report['decision_ms']:.1f} ms"
    )
    keys = Table(title="key vehicles (Section II-A)")
    for col in ("role", "id", "kind", "lane", "x [m]", "v [m/s]"):
        keys.add_column(col, justify="right")
    for role, k in report["key_vehicles"].items():
        if k is None:
            keys.add_row(role, "—", "—", "—", "—", "—")
        else:
            keys.add_row(
                role, str(k["id"]), k["kind"], str(k["lane"]), f"{k['x']:.1f}", f"{k['v']:.2f}"
            )
    out.print(keys)
    game = report["game"]
    if game:
        verdict = "admitted" if game["lateral_allowed"] else "not admitted"
        out.print(f"lane-change game (VMC vs VNR): {game['reason']}; lateral mode {verdict}")
    pareto = Table(title="Pareto set (feasible, non-dominated)")
    cols = (
        "#",
        "merge x [m]",
        "VR T_lc [s]",
        "H [s]",
        "mode",
        "U_safe [m/s²]",
        "U_fuel [L]",
        "−U_eff [m/s²]",
    )
    for col in cols:
        pareto.add_column(col, justify="right")
    chosen = report["chosen"]
    for i, p in enumerate(report["pareto"]):
        mark = "★ " if chosen and i == chosen["index"] else ""
        pareto.add_row(
            f"{mark}{i}",
            f"{p['merge_x']:.1f}",
            f"{p['vr_duration']:.2f}",
            f"{p['horizon']:.2f}",
            p["mode"][:3],
            f"{p['safety']:.3f}",
            f"{p['fuel']:.4f}",
            f"{p['efficiency']:.3f}",
        )
    out.print(pareto)
    if chosen is None:
        out.print(f"[yellow]fallback:[/] {report['reason']}")
    else:
        out.print(
            f"chosen (Eq. 19): #{chosen['index']} · mode [bold]{report['mode']}[/] · "
            f"merge at {chosen['merge_x']:.1f} m, T_lc {chosen['vr_duration']:.2f} s, "
            f"H {chosen['horizon']:.2f} s"
        )


CONDITIONS = ("C1", "C2", "C3", "C4", "C5")


def _workers(workers: int | None) -> int:
    import os

    if workers is None:
        return os.cpu_count() or 1
    if workers < 1:
        raise _fail(f"option '--workers' = {workers}: must be >= 1")
    return workers


def _progress_grid(specs: list, workers: int, on_result: Any = None) -> Any:
    from hcomc.experiments.runner import run_grid

    with _progress("runs", len(specs)) as update:
        return run_grid(specs, workers=workers, on_result=on_result, progress=update)


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


def _write_report(out_dir: Path, runs: Any) -> Path:
    """results/report.html with the tables, claims, Fig. 2 for C2 and the metric plots."""
    from hcomc.viz.figures import contour_figure, metrics_figure
    from hcomc.viz.inputs import controller_logs
    from hcomc.viz.report import figure_png, write_report

    seed = int(runs["seed"].min())
    figures = {
        f"Speed contour maps of both lanes as in the paper's Fig. 2: Condition 2, seed {seed}, "
        "FIFO, Game and HCOMC":
            figure_png(contour_figure(controller_logs("C2", seed=seed))),
        "The paper's metrics by condition and configuration (mean, 95 % CI over seeds; a "
        "bar marked n=k rests on the k seeds that give a value)":
            figure_png(metrics_figure(runs)),
    }  # fmt: skip
    return write_report(out_dir, runs, figures=figures)


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
    from hcomc.experiments.paper import PAPER_METRICS
    from hcomc.experiments.runner import ALL_CONFIGURATIONS, grid
    from hcomc.experiments.tables import claims, paper_table, to_markdown
    from hcomc.sim.manifest import atomic_paths, write_json_atomic

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

    both = _progress_grid([*seeded, *uniform], n_workers, on_result=save_manifest)
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
    report = _write_report(out_dir, runs)
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


@app.command()
def plot(
    sources: Annotated[
        list[str],
        typer.Argument(
            metavar="LOG_OR_RESULTS...",
            help="Logs (.npz/.parquet or a simulate --out directory), runs.parquet, plan JSON, "
            "a sweep directory, or a preset name to simulate (see --kind).",
        ),
    ],
    kind: Annotated[
        str,
        typer.Option(help="contour, timespace, trajectories, pareto, metrics or heatmap."),
    ],
    out_file: Annotated[
        Path | None, typer.Option("--out", help="Output file: .png, .svg or .pdf.")
    ] = None,
    seed: Annotated[int | None, typer.Option(help="Seed when simulating a preset.")] = None,
    metric: Annotated[
        str | None, typer.Option(help="Metric of a sweep heatmap (default: lsrv).")
    ] = None,
    raw: Annotated[bool, typer.Option(help="contour: raw bins instead of smoothing.")] = False,
) -> None:
    """Draw a figure of a run, a decision, a results table or a sweep."""
    from hcomc.viz.common import save_figure
    from hcomc.viz.inputs import FIGURE_KINDS, is_scenario, make_figure

    kind = kind.lower()
    target = out_file or Path(f"{kind}.png")
    _check_seed(seed)
    # an option that does not apply to this figure is an error, not silently ignored
    if metric is not None and kind != "heatmap":
        raise _fail(f"option '--metric' = '{metric}' applies to --kind heatmap only")
    if raw and kind != "contour":
        raise _fail(f"option '--raw' applies to --kind contour only, not '{kind}'")
    if seed is not None and not (len(sources) == 1 and is_scenario(sources[0])):
        raise _fail(
            f"option '--seed' = {seed} applies only when a preset or TOML scenario is "
            "simulated; saved logs and tables already have their seed"
        )
    try:
        if kind == "heatmap":
            import pandas as pd

            from hcomc.viz.sweep import heatmap_figure

            if len(sources) != 1:
                raise ValueError(f"--kind heatmap takes one sweep directory, got {len(sources)}")
            path = Path(sources[0])
            table_path = path / "sweep.parquet" if path.is_dir() else path
            if not table_path.is_file():
                raise ValueError(f"'{sources[0]}' is not a sweep directory or sweep.parquet")
            fig = heatmap_figure(pd.read_parquet(table_path), metric or "lsrv")
        elif kind in FIGURE_KINDS:
            options = {"smooth": False} if raw and kind == "contour" else {}
            fig = make_figure(kind, sources, seed=seed, **options)
        else:
            allowed = ", ".join([*FIGURE_KINDS, "heatmap"])
            raise ValueError(f"option '--kind' = '{kind}': allowed: {allowed}")
        written = save_figure(fig, target)
    except (ValueError, ConfigError) as exc:
        raise _fail(str(exc)) from None
    out.print(f"wrote {written}")


@app.command()
def animate(
    log_path: Annotated[Path, typer.Argument(metavar="LOG", help="A saved log (.npz/.parquet).")],
    out_file: Annotated[Path, typer.Option("--out", help="Output .gif or .mp4.")] = Path("run.gif"),
    fps: Annotated[int, typer.Option(help="Frames per second.")] = 10,
    speedup: Annotated[float, typer.Option(help="Simulated seconds per real second.")] = 5.0,
) -> None:
    """Top-down animation of a run: vehicles by kind, key vehicles, virtual vehicles, clock."""
    from hcomc.viz.animation import animate as render
    from hcomc.viz.inputs import load_log

    try:
        written = render(load_log(log_path), out_file, fps=fps, speedup=speedup)
    except (ValueError, ConfigError, OSError) as exc:
        raise _fail(str(exc)) from None
    out.print(f"wrote {written}")


def _print_summary(summary: dict[str, Any]) -> None:
    controller = summary["controller"]
    if summary.get("optimizer"):
        controller += f" ({summary['optimizer']})"
    title = f"{summary['scenario']} · seed {summary['seed']} · controller {controller}"
    table = Table(title=escape(title), show_header=False)
    table.add_column("figure")
    table.add_column("value", justify="right")
    rows = [
        ("merge controller", controller),
        ("measured duration [s]", f"{summary['duration_s']:.1f}"),
        ("vehicles [count] (CAVs)", f"{summary['vehicles']} ({summary['cavs']})"),
        ("merges [count]", str(summary["merges"])),
        ("ramp vehicles waiting at lane end [count]", str(summary["ramp_waits"])),
        ("lane changes [count]", str(summary["lane_changes"])),
        ("collisions [count]", str(summary["collisions"])),
    ]
    for lane, speed in summary["mean_speed"].items():
        rows.append(
            (f"mean speed {lane.replace('_', ' ')} [m/s]", "—" if speed is None else f"{speed:.2f}")
        )
    rows += [
        ("fuel, all vehicles [L]", f"{summary['fuel_l']:.3f}"),
        ("vehicle-steps [count]", f"{summary['vehicle_steps']:,}"),
        ("wall time [s]", f"{summary['wall_s']:.2f}"),
        ("vehicle-steps per second [1/s]", f"{summary['vehicle_steps_per_s']:,}"),
    ]
    if "out" in summary:
        rows.append(("written to", summary["out"]))
    for row in rows:
        table.add_row(*(escape(cell) for cell in row))
    out.print(table)


def _register_sumo() -> None:
    """SUMO interoperability commands (need the optional extra only when they run)."""
    from hcomc.sumo.cli import export_app, metrics

    app.add_typer(export_app, name="export")
    app.command("metrics")(metrics)


_register_sumo()
