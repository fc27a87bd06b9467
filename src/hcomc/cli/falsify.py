"""``hcomc falsify``: a search for the worst case of a controller (least TTC of a commanded
vehicle, or a collision) over faults, the V2X channel, human drivers and the seed."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from hcomc.cli._app import _compiled, _fail, _progress, _refuse_overwrite, app, out
from hcomc.config import ConfigError
from hcomc.robustness.falsify import FalsifySpec

_MAX_BUDGET = 100_000
FALSIFY_FILES = ("falsify.json", "summary.csv")


@app.command()
def falsify(
    controllers: Annotated[
        str | None,
        typer.Option(
            "--controllers",
            "--controller",
            help="Controllers, comma-separated, as 'hcomc run' takes them, each searched on "
            "its own (default: hcomc, or the search file's).",
        ),
    ] = None,
    condition: Annotated[
        str | None,
        typer.Option(help="Condition preset or scenario file (default: C2, or the search file's)."),
    ] = None,
    budget: Annotated[int, typer.Option(help="Runs each search may make.")] = 200,
    space: Annotated[
        Path | None,
        typer.Option(
            help="Search file (TOML): condition, controller, faults, shield, "
            'overrides and [space] of "dotted.key" = [low, high] (default: VMF\'s '
            "braking, aggressive drivers, the channel, reaction times, the seed)."
        ),
    ] = None,
    shield: Annotated[
        str | None,
        typer.Option(
            help="The safety shield: off, on, or both (one search each; default: "
            "off, or the search file's)."
        ),
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the search itself.")] = 0,
    top: Annotated[int, typer.Option(help="Worst cases to write (config and replay).")] = 3,
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path(
        "results/falsify"
    ),
    force: Annotated[bool, typer.Option(help="Overwrite an earlier search in --out.")] = False,
    docs: Annotated[
        Path | None, typer.Option(help="Also write DOCS/robustness.md's falsification table.")
    ] = None,
) -> None:
    """Search for the worst case of a controller: pymoo's genetic algorithm varies fault
    timing and magnitude, channel latency and loss, human drivers' reaction time and headway
    and the seed to minimise the least TTC of a vehicle a live plan commands (a collision:
    0). Writes every evaluation, and each of the --top worst as a config that 'hcomc
    simulate' runs again and as a replay, per controller and shield setting."""
    import dataclasses
    import sys

    from hcomc.robustness.falsify import falsify as search
    from hcomc.robustness.falsify import load_spec
    from hcomc.viz.falsify_report import MARKERS, Searched, publish, write_search

    if not 1 <= budget <= _MAX_BUDGET:
        raise _fail(f"option '--budget' = {budget}: allowed 1 .. {_MAX_BUDGET}")
    if not 1 <= top <= min(budget, 100):
        raise _fail(f"option '--top' = {top}: allowed 1 .. {min(budget, 100)}")
    if shield not in (None, "off", "on", "both"):
        raise _fail(f"option '--shield' = '{shield}': allowed: off, on, both")
    _refuse_overwrite(out_dir, FALSIFY_FILES, force)
    try:
        base = load_spec(space, condition=condition) if space else FalsifySpec()
        if condition and not space:
            base = dataclasses.replace(base, condition=condition)
        names = [c.strip() for c in (controllers or base.controller).split(",") if c.strip()]
        shields = {None: [base.shield], "off": [False], "on": [True], "both": [False, True]}
        specs = [dataclasses.replace(base, controller=name, shield=on)
                 for name in names for on in shields[shield]]  # fmt: skip
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    page = None if docs is None else docs / "robustness.md"
    if page is not None and MARKERS[0] not in (page.read_text(encoding="utf-8")
                                               if page.is_file() else ""):  # fmt: skip
        raise _fail(f"option '--docs' = '{docs}': no robustness.md with a '{MARKERS[0]}' "
                    "section there")  # fmt: skip
    _compiled()
    searches = []
    for spec in specs:
        label = f"{spec.controller}, shield {'on' if spec.shield else 'off'}, {spec.condition}"
        with _progress(f"falsify {label}", budget) as update:
            found = search(spec, budget, search_seed=seed, progress=update)
        searches.append(Searched(spec, found, top))
    command = (
        " ".join(["hcomc", *sys.argv[1:]]) if sys.argv[1:2] == ["falsify"] else "hcomc falsify"
    )
    write_search(out_dir, searches, seed, command)
    _print(out_dir, searches)
    if docs is not None:
        out.print(f"wrote {publish(out_dir, docs)}")


def _print(out_dir: Path, searches: list[Any]) -> None:
    """The worst case of each setting, with the command that runs it again."""
    from rich.table import Table

    from hcomc.viz.falsify_report import setting_dir

    table = Table(title=f"worst cases in {len(searches[0].found)} runs per setting")
    for column in ("controller", "shield", "commanded collisions", "least TTC [s]", "reproduce"):
        table.add_column(column)
    for s in searches:
        first = s.cases[0]
        hits = sum(c.collisions > 0 for c in s.found)
        ttc = "collision" if first.collisions else f"{first.least_ttc:.2f}"
        where = setting_dir(out_dir, s.spec) / "worst-1.toml"
        table.add_row(s.spec.controller, "on" if s.spec.shield else "off",
                      f"{hits} of {len(s.found)}", ttc, f"hcomc simulate {where}")  # fmt: skip
    out.print(table)
    out.print(f"written to {out_dir}")
