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
