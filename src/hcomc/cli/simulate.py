"""``hcomc config show`` and ``hcomc simulate``: one scenario, one run, its summary."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from hcomc.cli._app import (
    ConfigArg,
    Engine,
    Optimizer,
    SeedOption,
    SetOption,
    _check_seed,
    _compiled,
    _control,
    _engine,
    _fail,
    _load,
    _progress,
    _refuse_overwrite,
    _settings,
    _with,
    app,
    config_app,
    out,
)
from hcomc.config import ConfigError, ScenarioConfig, config_to_toml


@config_app.command("show")
def config_show(config: ConfigArg, settings: SetOption = None) -> None:
    """Print the fully resolved config as TOML, each key with its meaning and unit.

    The output is loadable by every command: hcomc config show C2 > my.toml.
    """
    sys.stdout.write(config_to_toml(_load(config, **_settings(settings)), annotate=True))


SIMULATE_FILES = ("log.npz", "manifest.json", "summary.json", "detectors.csv")


def _positions(text: str | None, road_length: float) -> list[float]:
    """``--detectors "400,1200"`` as positions [m] on the road, or a one-line error."""
    if text is None:
        return []
    try:
        positions = [float(p) for p in text.split(",") if p.strip()]
    except ValueError:
        raise _fail(
            f"'--detectors' = {text!r}: allowed: positions in m separated by commas"
        ) from None
    wrong = [p for p in positions if not 0.0 < p < road_length]
    if wrong or not positions:
        raise _fail(
            f"'--detectors' = {text!r}: allowed: positions in (0, {road_length:g}) m, "
            "the road's length, separated by commas"
        )
    return positions


def _scenario(source: str, overrides: dict[str, Any]) -> ScenarioConfig:
    """The scenario of a condition or config file, or of a corridor of the paper's layout
    (:func:`hcomc.corridor.engine.scenario_of`); a one-line error otherwise."""
    from hcomc.corridor import is_corridor_source, load_corridor
    from hcomc.corridor.engine import scenario_of

    if not is_corridor_source(source):
        return _load(source, **overrides)
    try:
        return scenario_of(load_corridor(source, {}), **overrides)
    except ConfigError as exc:
        raise _fail(str(exc)) from None


def _general_corridor(source: str, overrides: dict[str, Any]) -> tuple[Any, str] | None:
    """The corridor named by ``source`` and why the scenario engine refuses it, if it is a
    corridor that engine does not run; None otherwise."""
    from hcomc.corridor import is_corridor_source, load_corridor
    from hcomc.corridor.engine import scenario_of

    if not is_corridor_source(source):
        return None
    try:
        corridor = load_corridor(source, overrides)
    except ConfigError as exc:
        raise _fail(str(exc)) from None
    try:
        scenario_of(corridor)
    except ConfigError as exc:
        return corridor, str(exc).split(":")[0]
    return None


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
        typer.Option(
            help="Merge controller: none, fifo, game, hcomc, another registered name, "
            "package.module:Class or path/to/file.py:Class (default: the config's)."
        ),
    ] = None,
    optimizer: Optimizer = None,
    settings: SetOption = None,
    engine: Engine = "hcomc",
    detectors: Annotated[
        str | None,
        typer.Option(
            help="Virtual induction loops at these positions [m], e.g. 400,1200: count, flow, "
            "speeds and occupancy per lane and interval (as SUMO's E1 detectors)."
        ),
    ] = None,
    detector_interval: Annotated[
        float, typer.Option(help="Aggregation interval of --detectors [s].", min=0.1)
    ] = 60.0,
    trajectory_interval: Annotated[
        float,
        typer.Option(
            help="Corridor engine: sample every vehicle this often [s] into "
            "trajectories.csv (0: none; the step length: the full log).",
            min=0.0,
        ),
    ] = 0.0,
) -> None:
    """Simulate a scenario (merge controller from the config or --controller) and summarise.

    A corridor other than the paper's layout (e.g. the preset 'corridor') runs as a corridor
    (the same engine on its road): detectors, travel times and merges from its own
    [detectors] table;
    --set takes its dotted keys (corridor.duration=600).
    """
    from hcomc.cli.corridor import refuse_options, run_corridor, with_control

    general = _general_corridor(config, _settings(settings))
    if general is not None:
        corridor, why = general
        refuse_options(corridor, why, {
            "--engine": (engine, "hcomc"), "--detectors": (detectors, None),
        })  # fmt: skip
        _check_seed(seed)
        run_corridor(with_control(corridor, controller, optimizer), seed=seed,
                     duration=duration, out_dir=out_dir, force=force, as_json=as_json,
                     trajectory_interval=trajectory_interval)  # fmt: skip
        return
    if trajectory_interval:
        raise _fail(
            f"option '--trajectory-interval' = {trajectory_interval:g}: allowed: 0 for "
            f"'{config}' (an option of corridor runs; a condition's run logs every step)"
        )
    from hcomc.experiments.runner import make_simulation
    from hcomc.metrics.detectors import detector_table
    from hcomc.metrics.ramp import ramp_summary
    from hcomc.metrics.travel import travel_summary
    from hcomc.robustness.impairments import impairment_summary
    from hcomc.sim.manifest import write_json_atomic
    from hcomc.sim.summary import summarise

    _check_seed(seed)
    overrides = _settings(settings)
    control = _control(_scenario(config, overrides).control, controller, optimizer)
    cfg = _scenario(config, _with(overrides, duration=duration, seed=seed, control=control))
    positions = _positions(detectors, cfg.road.length)
    _refuse_overwrite(out_dir, SIMULATE_FILES, force)
    engine = _engine(engine, cfg)
    _compiled()
    sim = make_simulation(cfg, None, engine)
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
        "travel_times": travel_summary(log),
        "ramp": ramp_summary(log),
        **impairment_summary(sim.listeners),  # what the [v2x], [[faults]], [shield] did
        "wall_s": round(wall, 4),
    }
    summary["vehicle_steps_per_s"] = round(summary["vehicle_steps"] / max(wall, 1e-9))
    table = detector_table(log, positions, detector_interval) if positions else None
    if table is not None:
        summary["detectors"] = json.loads(table.to_json(orient="records"))
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        log.save(out_dir / "log.npz")
        write_json_atomic(out_dir / "manifest.json", log.meta)
        write_json_atomic(out_dir / "summary.json", summary)
        if table is not None:
            table.to_csv(out_dir / "detectors.csv", index=False)
        summary["out"] = str(out_dir)
    if as_json:
        sys.stdout.write(json.dumps(summary) + "\n")
    else:
        _print_summary(summary)
        if table is not None:
            out.print(_detectors_view(table))


def _impairment_rows(done: dict[str, Any]) -> list[tuple[str, str]]:
    """What the ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables did, as summary rows."""
    rows = [
        ("V2X: plans lost, CAV steps with the degraded headway",
         f"{done['plans_lost']}, {done['degraded_steps']}"),
        ("shield: brakes, held lane changes, releases [steps]",
         f"{done['shield_brake']}, {done['shield_hold_change']}, {done['shield_release']}"),
    ]  # fmt: skip
    for k, fault in enumerate(done["faults"]):
        start = "never began" if fault["start"] is None else f"from {fault['start']:.2f} s"
        who = ", ".join(map(str, fault["vehicles"])) or "no vehicle"
        rows.append((f"fault {k}: {fault['kind']}", f"{who}, {start}"))
    return rows


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
    for origin, trips in summary["travel_times"].items():
        if trips["trips"]:
            rows.append((
                f"trips from {origin}: count, mean travel time [s], mean delay [s]",
                f"{trips['trips']}, {trips['mean_s']:.1f}, {trips['mean_delay_s']:.1f}",
            ))  # fmt: skip
    ramp = summary["ramp"]
    if ramp["vehicles"]:
        rows.append((
            "ramp vehicles: entered, merged, longest queue, mean time standing [s]",
            f"{ramp['vehicles']}, {ramp['merged']}, {ramp['max_queue']}, "
            f"{ramp['mean_standing_s']:.1f}",
        ))  # fmt: skip
    if "impairments" in summary:
        rows += _impairment_rows(summary["impairments"])
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


def _detectors_view(frame: Any) -> Table:
    """The detector table for the terminal, a row per detector, lane and interval."""
    view = Table(title="virtual induction loops (per lane and interval)")
    heads = ("x [m]", "lane", "from [s]", "to [s]", "count", "flow [veh/h]", "speed [m/s]",
             "harmonic [m/s]", "occupancy [%]")  # fmt: skip
    for head in heads:
        view.add_column(head, justify="right")
    for r in frame.itertuples():
        cells = (f"{r.x:g}", str(r.lane), f"{r.begin:g}", f"{r.end:g}", str(r.count),
                 f"{r.flow:.0f}", f"{r.speed:.2f}", f"{r.harmonic_speed:.2f}",
                 f"{r.occupancy:.1f}")  # fmt: skip
        view.add_row(*(c.replace("nan", "—") for c in cells))
    return view
