"""CLI of the SUMO interoperability: ``hcomc export sumo|trajectories`` and ``hcomc metrics``.

Imports of SUMO and of the heavier modules happen inside the commands, so ``hcomc --help``
works without the ``sumo`` extra. Errors print one line and exit with status 2.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from hcomc.config import ConfigError, ScenarioConfig, load_config

export_app = typer.Typer(
    help="Export a scenario to SUMO or a run's trajectories to highD / FCD / CSV.",
    no_args_is_help=True,
)

_out = Console(width=None if sys.stdout.isatty() else 200)
_err = Console(stderr=True, width=None if sys.stderr.isatty() else 200)


def fail(message: str) -> typer.Exit:
    """Print a one-line error and return the exit (status 2) to raise."""
    _err.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True, markup=True)
    return typer.Exit(code=2)


def _config(source: str, **overrides: Any) -> ScenarioConfig:
    try:
        return load_config(source, **{k: v for k, v in overrides.items() if v is not None})
    except ConfigError as exc:
        raise fail(str(exc)) from None


def _fresh_target(path: Path, option: str, force: bool) -> None:
    """Refuse to overwrite existing output unless --force."""
    if path.exists() and not force and (path.is_file() or any(path.iterdir())):
        raise fail(
            f"option '{option}' = '{path}': already exists and is not empty; "
            "allowed: a new path, or --force to overwrite"
        )


@export_app.command("sumo")
def export_sumo(
    condition: Annotated[
        str, typer.Argument(metavar="CONDITION", help="Preset name (C1..C5) or TOML config.")
    ],
    out_dir: Annotated[Path, typer.Option("--out", help="Directory for the SUMO scenario.")],
    seed: Annotated[int | None, typer.Option(help="Demand seed (default: the config's).")] = None,
    duration: Annotated[
        float | None, typer.Option(help="Measured duration [s] (default: the config's).")
    ] = None,
    force: Annotated[bool, typer.Option(help="Overwrite an existing non-empty --out.")] = False,
) -> None:
    """Write the condition as a SUMO scenario (network, routes, .sumocfg): `sumo -c` runs it."""
    from hcomc.sumo import SumoFormatError, SumoMissingError
    from hcomc.sumo.export import export_scenario

    if seed is not None and seed < 0:
        raise fail(f"option '--seed' = {seed}: must be >= 0")
    cfg = _config(condition, duration=duration, seed=seed)
    if out_dir.exists() and not out_dir.is_dir():
        raise fail(f"option '--out' = '{out_dir}': exists and is not a directory")
    _fresh_target(out_dir, "--out", force)
    try:
        scenario = export_scenario(cfg, cfg.seed, out_dir)
    except (SumoMissingError, SumoFormatError, ValueError) as exc:
        raise fail(str(exc)) from None
    _out.print(f"wrote {scenario.directory}/ · run it with: sumo -c {scenario.sumocfg}")
