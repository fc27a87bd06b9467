"""``hcomc replay``: an interactive replay of runs in the browser."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from hcomc.cli._app import Force, _compiled, _fail, _refuse_existing_file, app, out
from hcomc.config import ConfigError

if TYPE_CHECKING:
    from hcomc.viz.replay.runs import ReplayRun


def _load_run(path: Path) -> ReplayRun:
    """The run of a run directory (a scenario run's log, a corridor run's trajectories) or a
    saved log file; a one-line error without one."""
    from hcomc.metrics.corridor.record import is_corridor_run
    from hcomc.sim.log import LOG_FILES
    from hcomc.viz.replay.runs import load_run

    if (
        path.is_dir()
        and not is_corridor_run(path)
        and not any((path / name).is_file() for name in LOG_FILES)
    ):
        raise _fail(
            f"run directory '{path}' holds no log.npz or log.parquet and is no corridor run; "
            "allowed: the --out directory of 'hcomc simulate SCENARIO', or of 'hcomc simulate "
            "CORRIDOR --trajectory-interval S', or a saved log file"
        )
    try:
        return load_run(path)
    except (ValueError, OSError) as exc:
        raise _fail(str(exc)) from None


@app.command()
def replay(
    runs: Annotated[
        list[Path],
        typer.Argument(
            metavar="RUN_DIR...",
            help="Runs to play side by side on one clock: 'hcomc simulate --out' directories "
            "(or saved logs), e.g. the same seed with FIFO, Game and HCOMC; corridor runs "
            "need --trajectory-interval.",
        ),
    ],
    out_file: Annotated[
        Path, typer.Option("--out", help="The self-contained HTML page to write.")
    ] = Path("replay.html"),
    titles: Annotated[
        list[str] | None,
        typer.Option(
            "--title",
            help="A run's title, once per run in order (default: controller, scenario, seed).",
        ),
    ] = None,
    screenshot: Annotated[
        Path | None,
        typer.Option(help="Also write a PNG of the page in headless Chromium (needs chromium)."),
    ] = None,
    at: Annotated[
        float | None,
        typer.Option(help="--screenshot: time shown [s] (default: middle of the earliest merge)."),
    ] = None,
    width: Annotated[int, typer.Option(help="--screenshot: page width [px].")] = 1280,
    force: Force = False,
) -> None:
    """Write an interactive replay of runs: one HTML file that plays offline in a browser."""
    from hcomc.viz.replay import replay as build
    from hcomc.viz.replay.browser import BrowserError, find_chromium, replay_screenshot
    from hcomc.viz.replay.runs import check_together, moment

    if titles is not None and len(titles) != len(runs):
        raise _fail(f"option '--title' given {len(titles)} times for {len(runs)} runs; "
                    "allowed: once per run, or not at all")  # fmt: skip
    if (at is not None or width != 1280) and screenshot is None:
        raise _fail("options '--at' and '--width' apply only with --screenshot")
    if screenshot is not None and find_chromium() is None:
        raise _fail("option '--screenshot' needs Chromium, which is not installed "
                    "(e.g. apt-get install chromium)")  # fmt: skip
    if not 320 <= width <= 4096:
        raise _fail(f"option '--width' = {width}: allowed: 320 to 4096 px")
    _refuse_existing_file(out_file, "--out", force)
    if screenshot is not None:
        _refuse_existing_file(screenshot, "--screenshot", force)
    logs = [_load_run(path) for path in runs]
    try:
        check_together(logs, [str(path) for path in runs])
    except ValueError as exc:
        raise _fail(str(exc)) from None
    _compiled("replay")
    try:
        page = build(logs, titles=titles, out=out_file)
    except (ValueError, ConfigError, OSError) as exc:
        raise _fail(str(exc)) from None
    out.print(f"wrote {out_file} ({page.nbytes / 1e6:.2f} MB, {len(logs)} run(s))")
    if screenshot is None:
        return
    shown = moment(logs) if at is None else at
    try:
        replay_screenshot(out_file, screenshot, t=shown, width=width)
    except (BrowserError, OSError) as exc:
        raise _fail(f"screenshot failed: {exc}") from None
    out.print(f"wrote {screenshot} (t = {shown:.1f} s)")
