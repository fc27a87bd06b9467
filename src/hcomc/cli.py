"""Command-line interface (typer + rich).

Every command validates its input before anything runs; a bad value prints one line naming
the key, the value and what is allowed, and exits with status 2 (no traceback).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from hcomc.config import ConfigError, ScenarioConfig, config_to_toml, load_config

app = typer.Typer(
    name="hcomc",
    help="Cooperative on-ramp merging (HCOMC) in mixed traffic on two-lane highways.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
config_app = typer.Typer(help="Inspect scenario configs.", no_args_is_help=True)
app.add_typer(config_app, name="config")

out = Console()
err = Console(stderr=True)

ConfigArg = Annotated[
    str,
    typer.Argument(
        metavar="CONFIG", help="Preset name (C1..C5, platoon) or path to a TOML config file."
    ),
]


def _fail(message: str) -> typer.Exit:
    err.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    return typer.Exit(code=2)


def _load(source: str, **overrides: Any) -> ScenarioConfig:
    try:
        return load_config(source, **overrides)
    except ConfigError as exc:
        raise _fail(str(exc)) from None


@config_app.command("show")
def config_show(config: ConfigArg) -> None:
    """Print the fully resolved config as TOML (loadable by every command)."""
    sys.stdout.write(config_to_toml(_load(config)))


@app.command()
def simulate(
    config: ConfigArg,
    seed: Annotated[int | None, typer.Option(help="Random seed (default: the config's).")] = None,
    duration: Annotated[
        float | None, typer.Option(help="Measured duration [s] (default: the config's).")
    ] = None,
    out_dir: Annotated[
        Path | None, typer.Option("--out", help="Write log.npz, manifest.json, summary.json here.")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
) -> None:
    """Simulate a scenario without a merge controller and print a summary."""
    from hcomc.sim.engine import Simulation
    from hcomc.sim.manifest import write_json_atomic
    from hcomc.sim.summary import summarise

    if seed is not None and seed < 0:
        raise _fail(f"option '--seed' = {seed}: must be >= 0")
    cfg = _load(config, duration=duration, seed=seed)
    if out_dir is not None and out_dir.exists() and not out_dir.is_dir():
        raise _fail(f"option '--out' = '{out_dir}': exists and is not a directory")
    sim = Simulation(cfg)
    start = time.perf_counter()
    if as_json or not out.is_terminal:
        log = sim.run()
    else:
        with Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeRemainingColumn(),
            console=out,
            transient=True,
        ) as bar:
            task = bar.add_task(f"{cfg.name} seed {sim.seed}", total=sim.n_warmup + sim.n_steps)
            log = sim.run(lambda done, total: bar.update(task, completed=done))
    wall = time.perf_counter() - start
    summary: dict[str, Any] = {"scenario": cfg.name, "seed": sim.seed, **summarise(log)}
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


Optimizer = Annotated[
    str | None, typer.Option(help="HCOMC optimiser: nsga2, pso or sa (default: the config's).")
]


@app.command()
def plan(
    config: ConfigArg,
    seed: Annotated[int | None, typer.Option(help="Random seed (default: the config's).")] = None,
    optimizer: Optimizer = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the decision as JSON.")] = False,
) -> None:
    """Run until the first ramp vehicle enters the control zone and show HCOMC's decision."""
    from hcomc.control.report import plan_report
    from hcomc.sim.engine import Simulation

    if seed is not None and seed < 0:
        raise _fail(f"option '--seed' = {seed}: must be >= 0")
    base = _load(config)
    control = {**base.control.model_dump(), "controller": "hcomc"}
    if optimizer is not None:
        control["optimizer"] = optimizer
    cfg = _load(config, seed=seed, control=control)
    sim = Simulation(cfg)
    decision = sim.run_until_plan()
    if decision is None:
        raise _fail(
            f"no ramp vehicle entered the control zone within duration = {cfg.duration} s "
            f"of '{config}'; allowed: a scenario with ramp demand ('single' or 'flow')"
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
            keys.add_row(role, str(k["id"]), k["kind"], str(k["lane"]), f"{k['x']:.1f}",
                         f"{k['v']:.2f}")  # fmt: skip
    out.print(keys)
    game = report["game"]
    if game:
        verdict = "admitted" if game["lateral_allowed"] else "not admitted"
        out.print(f"lane-change game (VMC vs VNR): {game['reason']}; lateral mode {verdict}")
    pareto = Table(title="Pareto set (feasible, non-dominated)")
    cols = ("#", "merge x [m]", "VR T_lc [s]", "H [s]", "mode", "U_safe [m/s²]", "U_fuel [L]",
            "−U_eff [m/s²]")  # fmt: skip
    for col in cols:
        pareto.add_column(col, justify="right")
    chosen = report["chosen"]
    for i, p in enumerate(report["pareto"]):
        mark = "★ " if chosen and i == chosen["index"] else ""
        pareto.add_row(f"{mark}{i}", f"{p['merge_x']:.1f}", f"{p['vr_duration']:.2f}",
                       f"{p['horizon']:.2f}", p["mode"][:3], f"{p['safety']:.3f}",
                       f"{p['fuel']:.4f}", f"{p['efficiency']:.3f}")  # fmt: skip
    out.print(pareto)
    if chosen is None:
        out.print(f"[yellow]fallback:[/] {report['reason']}")
    else:
        out.print(f"chosen (Eq. 19): #{chosen['index']} · mode [bold]{report['mode']}[/] · "
                  f"merge at {chosen['merge_x']:.1f} m, T_lc {chosen['vr_duration']:.2f} s, "
                  f"H {chosen['horizon']:.2f} s")  # fmt: skip


def _print_summary(summary: dict[str, Any]) -> None:
    table = Table(title=f"{summary['scenario']} · seed {summary['seed']}", show_header=False)
    table.add_column("figure")
    table.add_column("value", justify="right")
    rows = [
        ("vehicles (CAVs)", f"{summary['vehicles']} ({summary['cavs']})"),
        ("merges", str(summary["merges"])),
        ("ramp vehicles waiting at lane end", str(summary["ramp_waits"])),
        ("lane changes", str(summary["lane_changes"])),
        ("collisions", str(summary["collisions"])),
    ]
    for lane, speed in summary["mean_speed"].items():
        rows.append(
            (f"mean speed {lane.replace('_', ' ')} [m/s]", "—" if speed is None else f"{speed:.2f}")
        )
    rows += [
        ("fuel, all vehicles [L]", f"{summary['fuel_l']:.3f}"),
        ("vehicle-steps", f"{summary['vehicle_steps']:,}"),
        ("wall time [s]", f"{summary['wall_s']:.2f}"),
        ("vehicle-steps per second", f"{summary['vehicle_steps_per_s']:,}"),
    ]
    if "out" in summary:
        rows.append(("written to", summary["out"]))
    for row in rows:
        table.add_row(*row)
    out.print(table)


def main() -> None:  # pragma: no cover - console entry point alias
    """Entry point."""
    app()
