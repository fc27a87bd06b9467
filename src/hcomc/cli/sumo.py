"""CLI of the SUMO interoperability: ``hcomc export sumo`` and ``hcomc metrics`` (``hcomc
export trajectories``: :mod:`hcomc.cli.trajectories`).

Imports of SUMO and of the heavier modules happen inside the commands, so ``hcomc --help``
works without the ``sumo`` extra. Errors print one line and exit with status 2.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape

from hcomc.config import ConfigError, ScenarioConfig, load_config

export_app = typer.Typer(
    help="Export a scenario to SUMO or a run's trajectories to highD / FCD / CSV / CommonRoad.",
    no_args_is_help=True,
)

_out = Console(width=None if sys.stdout.isatty() else 200)
_err = Console(stderr=True, width=None if sys.stderr.isatty() else 200)


def fail(message: str) -> typer.Exit:
    """Print a one-line error and return the exit (status 2) to raise."""
    _err.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
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
        str,
        typer.Argument(
            metavar="SOURCE",
            help="Condition preset (C1..C5) or TOML config; or a corridor: preset (corridor, "
            "paper) or TOML file with a [corridor] table.",
        ),
    ],
    out_dir: Annotated[Path, typer.Option("--out", help="Directory for the SUMO scenario.")],
    seed: Annotated[int | None, typer.Option(help="Demand seed (default: the config's).")] = None,
    duration: Annotated[
        float | None,
        typer.Option(
            help="Measured duration [s] of a condition, simulated duration of a corridor "
            "(default: the file's)."
        ),
    ] = None,
    force: Annotated[bool, typer.Option(help="Overwrite an existing non-empty --out.")] = False,
) -> None:
    """Write a condition or a corridor as a SUMO scenario (network, routes, .sumocfg): `sumo -c`
    runs it."""
    from hcomc.corridor import is_corridor_source
    from hcomc.sumo import SumoFormatError, SumoMissingError
    from hcomc.sumo.export import export_scenario

    if seed is not None and seed < 0:
        raise fail(f"option '--seed' = {seed}: must be >= 0")
    if is_corridor_source(condition):
        _export_corridor(condition, out_dir, seed, duration, force)
        return
    if not condition.endswith(".toml") and not Path(condition).exists():
        from hcomc.config import preset_names
        from hcomc.corridor import corridor_preset_names

        if condition.lower() not in {n.lower() for n in preset_names()}:
            raise fail(
                f"SOURCE = '{condition}': no such preset; allowed: a condition "
                f"({', '.join(preset_names())}), a corridor "
                f"({', '.join(corridor_preset_names())}) or a .toml file"
            )
    cfg = _config(condition, duration=duration, seed=seed)
    if out_dir.exists() and not out_dir.is_dir():
        raise fail(f"option '--out' = '{out_dir}': exists and is not a directory")
    _fresh_target(out_dir, "--out", force)
    try:
        scenario = export_scenario(cfg, cfg.seed, out_dir)
    except (SumoMissingError, SumoFormatError, ValueError) as exc:
        raise fail(str(exc)) from None
    _out.print(f"wrote {scenario.directory}/ · run it with: sumo -c {scenario.sumocfg}")


def _export_corridor(
    source: str, out_dir: Path, seed: int | None, duration: float | None, force: bool
) -> None:
    """`hcomc export sumo` of a corridor: validate everything, then write the directory."""
    from hcomc.corridor import load_corridor
    from hcomc.corridor.engine import scenario_of, scenario_only
    from hcomc.sumo import SumoFormatError, SumoMissingError
    from hcomc.sumo.corridor import export_corridor
    from hcomc.sumo.export import export_scenario

    try:
        corridor = load_corridor(source, {"corridor.seed": seed, "corridor.duration": duration})
        # a warm-up, lane flows or a single release: the scenario it stands for is exported
        config = scenario_of(corridor) if scenario_only(corridor) else None
    except ConfigError as exc:
        raise fail(str(exc)) from None
    if out_dir.exists() and not out_dir.is_dir():
        raise fail(f"option '--out' = '{out_dir}': exists and is not a directory")
    _fresh_target(out_dir, "--out", force)
    try:
        written = (
            export_corridor(corridor, out_dir) if config is None
            else export_scenario(config, config.seed, out_dir)
        )  # fmt: skip
    except (SumoMissingError, SumoFormatError, OSError) as exc:
        raise fail(str(exc)) from None
    _out.print(f"wrote {written.directory}/ · run it with: sumo -c {written.sumocfg}")


def _file_config(path: Path, source: str | None) -> ScenarioConfig:
    """--config, else the scenario.toml / manifest.json / log beside the file."""
    from hcomc.config import validate_config

    if source is not None:
        return _config(source)
    folder = path if path.is_dir() else path.parent
    if (folder / "scenario.toml").is_file():
        return _config(str(folder / "scenario.toml"))
    manifest = folder / "manifest.json"
    if manifest.is_file():
        data = json.loads(manifest.read_text(encoding="utf-8"))
        if "config" in data:
            try:
                return validate_config(data["config"], str(manifest))
            except ConfigError as exc:
                raise fail(str(exc)) from None
    raise fail(
        f"FILE = '{path}': no road geometry found (no scenario.toml or manifest.json beside "
        "it); allowed: --config with a preset name (C1..C5) or TOML file"
    )


def _role_ids(values: dict[str, str | None], ids: dict[str, int]) -> dict[str, int]:
    out = {}
    for role, value in values.items():
        if value is None:
            continue
        if value not in ids:
            shown = ", ".join(list(ids)[:5])
            raise fail(
                f"option '--{role.lower()}' = '{value}': no such vehicle in the file; "
                f"allowed: its vehicle ids (e.g. {shown})"
            )
        out[role] = ids[value]
    return out


def metrics(
    file: Annotated[
        Path, typer.Argument(metavar="FILE", help="SUMO FCD XML, or a highD-style directory.")
    ],
    config: Annotated[
        str | None,
        typer.Option(help="Road geometry: preset or TOML (default: scenario.toml beside FILE)."),
    ] = None,
    vr: Annotated[str | None, typer.Option(help="Id of the merging vehicle VR.")] = None,
    vmc: Annotated[str | None, typer.Option(help="Id of VMC (default: found).")] = None,
    vmf: Annotated[str | None, typer.Option(help="Id of VMF (default: found).")] = None,
    vmr: Annotated[str | None, typer.Option(help="Id of VMR (default: found).")] = None,
    vnf: Annotated[str | None, typer.Option(help="Id of VNF (default: found).")] = None,
    vnr: Annotated[str | None, typer.Option(help="Id of VNR (default: found).")] = None,
    log_out: Annotated[
        Path | None,
        typer.Option("--log-out", help="Also save the trajectories as a log (.npz) for plot."),
    ] = None,
    figures: Annotated[
        Path | None, typer.Option(help="Write timespace and contour figures (PNG) here.")
    ] = None,
    reference: Annotated[
        Path | None,
        typer.Option(
            help="The same scenario without the ramp vehicle (same format): the undisturbed "
            "run the metrics that compare with it need (average acceleration, stabilisation "
            "times, LSRV, fuel)."
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the rows as JSON.")] = False,
) -> None:
    """Our merge metrics from an external FCD or highD-style trajectory file."""
    from hcomc.sumo import SumoFormatError
    from hcomc.sumo.external import derive_events, score_merges
    from hcomc.sumo.fcd import read_fcd
    from hcomc.sumo.highd import read_highd

    cfg = _file_config(file, config) if file.exists() else None
    if cfg is None:
        raise fail(f"FILE = '{file}': does not exist")

    def read(path: Path) -> tuple[Any, dict[str, int]]:
        if not path.exists():
            raise fail(f"option '--reference' = '{path}': does not exist")
        try:
            if path.is_dir() or path.suffix.lower() == ".csv":
                return read_highd(path, cfg)
            if path.suffix.lower() == ".xml":
                return read_fcd(path, cfg)
            raise SumoFormatError(
                f"{path}: unknown trajectory format; allowed: SUMO FCD (.xml) or a highD-style "
                "directory / tracks.csv"
            )
        except SumoFormatError as exc:
            raise fail(str(exc)) from None

    log, ids = read(file)
    undisturbed = None
    if reference is not None:
        from hcomc.sumo.external import aligned_reference

        ref_log, ref_ids = read(reference)
        if ref_log.n_recorded != log.n_recorded:
            raise fail(
                f"option '--reference' = '{reference}': {ref_log.n_recorded} time steps, "
                f"expected {log.n_recorded} (the same scenario and duration as FILE)"
            )
        undisturbed = aligned_reference(ref_log, ref_ids, ids, log.n_vehicles)
    derive_events(log, cfg)
    roles = {"VMC": vmc, "VMF": vmf, "VMR": vmr, "VNF": vnf, "VNR": vnr}
    if vr is None and any(roles.values()):
        raise fail("options '--vmc' ... '--vnr' need '--vr' (the merging vehicle they belong to)")
    groups = None
    if vr is not None:
        groups = {_role_ids({"VR": vr}, ids)["VR"]: _role_ids(roles, ids)}
    scores = score_merges(log, cfg, groups, undisturbed)
    names = {slot: vid for vid, slot in ids.items()}
    rows = []
    for s in scores:
        log.meta.setdefault("key_groups", []).append(s.group.as_dict())
        keys = {r: names.get(i, "") for r, i in s.group.as_dict().items()}
        rows.append({**{f"{r.lower()}": k for r, k in keys.items()}, **s.metrics})
    if log_out is not None:
        log.save(log_out)
    if figures is not None:
        _figures(log, figures)
    if as_json:
        sys.stdout.write(json.dumps(rows, default=float) + "\n")
        return
    _print_rows(rows, file)


def _figures(log: Any, folder: Path) -> None:
    from hcomc.viz.common import save_figure
    from hcomc.viz.figures import contour_figure, timespace_figure

    folder.mkdir(parents=True, exist_ok=True)
    save_figure(timespace_figure(log), folder / "timespace.png")
    save_figure(contour_figure({"external": log}), folder / "contour.png")
    _err.print(f"wrote {folder}/timespace.png, contour.png")  # stdout may carry --json


def _print_rows(rows: list[dict[str, Any]], file: Path) -> None:
    from rich.table import Table

    if not rows:
        _out.print(f"{file}: no ramp vehicle (first seen on the ramp lane) to score")
        return
    table = Table(title=f"merge metrics · {file}")
    for col in rows[0]:
        table.add_column(col, justify="right")
    for row in rows:
        table.add_row(*(f"{v:.4g}" if isinstance(v, float) else str(v) for v in row.values()))
    _out.print(table)


def engine_error(engine: str, config: ScenarioConfig | None = None) -> str | None:
    """Why ``--engine`` cannot run here or cannot run ``config`` (one line), or None."""
    from hcomc.experiments.runner import ENGINES

    if engine not in ENGINES:
        return f"option '--engine' = '{engine}': allowed: {', '.join(ENGINES)}"
    if engine == "sumo":
        from hcomc.sumo.routes import sumo_problem

        problem = sumo_problem(config)
        if problem is not None:
            return f"option '--engine' = 'sumo': {problem}"
    return None
