"""``hcomc plot`` and ``hcomc animate``: figures and animations of runs."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from hcomc.cli._app import (
    Force,
    _check_seed,
    _fail,
    _refuse_existing_file,
    app,
    out,
)
from hcomc.config import ConfigError


@app.command()
def plot(
    sources: Annotated[
        list[str],
        typer.Argument(
            metavar="LOG_OR_RESULTS...",
            help="Logs (.npz/.parquet or a simulate --out directory), runs.parquet, plan JSON, "
            "a sweep directory, a corridor run (simulate CORRIDOR --out directory), or a "
            "preset name or TOML file (scenario or corridor) to simulate (see --kind).",
        ),
    ],
    kind: Annotated[
        str,
        typer.Option(
            help="Of scenario runs: contour, timespace, trajectories, pareto, metrics or "
            "heatmap (a sweep). Of corridor runs or corridors: speed_heatmap, flow_density "
            "or travel_times."
        ),
    ],
    out_file: Annotated[
        Path | None, typer.Option("--out", help="Output file: .png, .svg or .pdf.")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(help="Seed when simulating a preset or TOML file.")
    ] = None,
    metric: Annotated[
        str | None, typer.Option(help="Metric of a sweep heatmap (default: lsrv).")
    ] = None,
    raw: Annotated[bool, typer.Option(help="contour: raw bins instead of smoothing.")] = False,
    force: Force = False,
) -> None:
    """Draw a figure of a run, a decision, a results table, a sweep or a corridor run.

    A corridor of the paper's layout (e.g. 'paper') runs in the scenario engine, as 'hcomc
    simulate' runs it: the scenario kinds draw it and the corridor kinds refuse it.
    """
    from hcomc.viz.common import save_figure
    from hcomc.viz.corridor import CORRIDOR_KINDS
    from hcomc.viz.corridor_inputs import make_corridor_figure, refuse_corridor_input
    from hcomc.viz.inputs import FIGURE_KINDS, make_figure
    from hcomc.viz.sources import is_scenario

    kind = kind.lower()
    target = out_file or Path(f"{kind}.png")
    _check_seed(seed)
    _refuse_existing_file(target, "--out", force)
    # an option that does not apply to this figure is an error, not silently ignored
    if metric is not None and kind != "heatmap":
        raise _fail(f"option '--metric' = '{metric}' applies to --kind heatmap only")
    if raw and kind != "contour":
        raise _fail(f"option '--raw' applies to --kind contour only, not '{kind}'")
    if seed is not None and not (len(sources) == 1 and is_scenario(sources[0])):
        raise _fail(
            f"option '--seed' = {seed} applies only when a preset or TOML file (scenario or "
            "corridor) is simulated; saved logs, runs and tables already have their seed"
        )
    try:
        if kind in CORRIDOR_KINDS:
            fig = make_corridor_figure(kind, sources, seed=seed)
        elif kind == "heatmap":
            import pandas as pd

            from hcomc.viz.sweep import heatmap_figure

            refuse_corridor_input(kind, sources)
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
            allowed = ", ".join([*FIGURE_KINDS, "heatmap", *CORRIDOR_KINDS])
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
    force: Force = False,
) -> None:
    """Top-down animation of a run: vehicles by kind, key vehicles, virtual vehicles, clock."""
    from hcomc.viz.animation import animate as render
    from hcomc.viz.inputs import load_log

    _refuse_existing_file(out_file, "--out", force)
    try:
        written = render(load_log(log_path), out_file, fps=fps, speedup=speedup)
    except (ValueError, ConfigError, OSError) as exc:
        raise _fail(str(exc)) from None
    out.print(f"wrote {written}")
