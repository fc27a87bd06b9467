"""``hcomc faults``: the robustness campaign (V2X channel x injected faults x shield)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any

import typer

from hcomc.cli._app import Engine, _compiled, _engine, _fail, _progress, app, out
from hcomc.config.impairment_tables import CHANNELS, FAULTS

_MAX_SEEDS = 100_000


def _names(option: str, value: str | None, allowed: list[str]) -> tuple[str, ...] | None:
    """A comma-separated list of ``allowed`` names, or None (all)."""
    if value is None:
        return None
    names = tuple(v.strip() for v in value.split(",") if v.strip())
    bad = [n for n in names if n not in allowed]
    if bad or not names:
        raise _fail(f"option '{option}' = '{value}'; allowed: a comma-separated list of "
                    f"{', '.join(allowed)}")  # fmt: skip
    return names


def _conditions(value: str | None, presets: list[str]) -> tuple[str, ...] | None:
    """``--conditions``: the paper's conditions and corridors (presets or files that a
    corridor run takes), or None (the paper's conditions)."""
    from hcomc.corridor import is_corridor_source, load_corridor
    from hcomc.corridor.engine import scenario_only

    if value is None:
        return None
    names = tuple(v.strip() for v in value.split(",") if v.strip())
    for name in names:
        if name in presets:
            continue
        if not is_corridor_source(name):
            raise _fail(f"option '--conditions' = '{value}': '{name}' is neither a condition "
                        f"({', '.join(presets)}) nor a corridor preset or file")  # fmt: skip
        found = scenario_only(load_corridor(name))
        if found is not None:
            raise _fail(f"option '--conditions': corridor '{name}' has key '{found[0]}' = "
                        f"{found[1]!r}, which only the paper's conditions take; allowed: it "
                        "unset, or the condition itself (C1 ... C5)")  # fmt: skip
    if not names:
        raise _fail(f"option '--conditions' = '{value}'; allowed: a comma-separated list of "
                    f"{', '.join(presets)} or corridors")  # fmt: skip
    return names


@app.command()
def faults(
    seeds: Annotated[int, typer.Option(help="Seeds 0 .. N-1 of every cell.")] = 10,
    conditions: Annotated[
        str | None,
        typer.Option(
            help="Conditions (default: C1,...,C5), or corridors: presets or corridor "
            "files, e.g. corridor or my_road.toml (the controller at every on-ramp)."
        ),
    ] = None,
    configurations: Annotated[
        str | None,
        typer.Option(
            "--configurations",
            "--controllers",
            help="Configurations or controllers, as 'hcomc compare' takes them: "
            "registered names, module:Class or file.py:Class "
            "(default: FIFO,Game,HCOMC).",
        ),
    ] = None,
    fault: Annotated[
        str | None, typer.Option("--faults", help=f"Faults: {', '.join(FAULTS)} (default: all).")
    ] = None,
    channel: Annotated[
        str | None,
        typer.Option("--channels", help=f"Channel settings: {', '.join(CHANNELS)} (default: all)."),
    ] = None,
    out_dir: Annotated[Path, typer.Option("--out", help="Campaign directory.")] = Path(
        "results/faults"
    ),
    workers: Annotated[int | None, typer.Option(help="Processes (default: all cores).")] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler address (default: local processes).")
    ] = None,
    force: Annotated[bool, typer.Option(help="Start the campaign in --out afresh.")] = False,
    docs: Annotated[
        Path | None, typer.Option(help="Also write DOCS/robustness.md and its data.")
    ] = None,
    engine: Engine = "hcomc",
) -> None:
    """Run the robustness campaign: conditions x configurations x faults x V2X channels x
    shield off/on x seeds, in our engine or in SUMO, with the nominal cell each is paired
    with; rerun to resume. Writes runs.csv and summary.csv (one row per cell, with its
    paired effects against the nominal runs) under --out."""
    from hcomc.config import preset_names
    from hcomc.experiments.controller_arguments import configuration_labels
    from hcomc.robustness.campaign import CampaignSpec, run_campaign

    if not 1 <= seeds <= _MAX_SEEDS:
        raise _fail(f"option '--seeds' = {seeds}: allowed 1 .. {_MAX_SEEDS}")
    if workers is not None and not 1 <= workers <= 256:
        raise _fail(f"option '--workers' = {workers}: allowed 1 .. 256")
    if workers is not None and scheduler is not None:
        raise _fail(f"option '--workers' = {workers} does not apply with '--scheduler': the "
                    "Dask cluster's workers run the campaign")  # fmt: skip
    scenario_presets = [p for p in preset_names() if p != "platoon"]
    axes: dict[str, Any] = {
        k: v for k, v in {
            "conditions": _conditions(conditions, scenario_presets),
            "configurations": None if configurations is None else tuple(configuration_labels(
                configurations, key="option '--configurations'", least=1)),
            "faults": _names("--faults", fault, list(FAULTS)),
            "channels": _names("--channels", channel, list(CHANNELS)),
        }.items() if v is not None
    }  # fmt: skip
    spec = CampaignSpec(**axes, seeds=tuple(range(seeds)), engine=_engine(engine))
    _compiled()
    n_workers = workers or os.cpu_count() or 1
    with _progress("cells", len(spec.cells())) as update:
        runs = run_campaign(spec, out_dir, workers=n_workers, scheduler=scheduler, force=force,
                            progress=update)  # fmt: skip
    from hcomc.robustness.tables import OVERVIEW, overview_view, summarise, verdicts

    overview = summarise(runs, OVERVIEW)
    out.print(overview_view(overview).to_string(index=False))
    out.print(verdicts(overview))
    from hcomc.viz.campaign_report import write_report

    if spec.engine == "hcomc":
        out.print(f"report: {write_report(out_dir, runs, spec.corridors())}")
    out.print(f"{len(runs)} runs; tables in {out_dir}")
    if docs is not None:
        from hcomc.robustness.publish import publish

        page = publish(out_dir, docs)
        out.print(f"wrote {page}")
