"""``hcomc export sumo``: a condition as a runnable SUMO scenario directory.

The directory holds the plain XML and ``road.net.xml`` (:mod:`hcomc.sumo.network`),
``vehicles.rou.xml`` (:mod:`hcomc.sumo.routes`), ``<name>.sumocfg`` and, for reproducibility,
the resolved config (``scenario.toml``) and a manifest (seed, package version, git revision).
``sumo -c DIR/<name>.sumocfg`` runs it unchanged. The SUMO options mirror our engine: the step
is ``dt``, positions are updated ballistically (``step-method.ballistic``, as our engine
integrates), lane changes are continuous, collisions are only warned about (the run goes on
and they are counted, as in our engine) and SUMO's random seed is the run's seed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from hcomc.config import ScenarioConfig, config_to_toml
from hcomc.sim.manifest import build_manifest, write_json_atomic
from hcomc.sumo.network import NET_FILE, build_network
from hcomc.sumo.routes import routes_xml

__all__ = [
    "ROUTE_FILE",
    "SUMO_PROCESSING",
    "SumoScenario",
    "export_scenario",
    "sumo_options",
    "sumocfg_xml",
]

ROUTE_FILE = "vehicles.rou.xml"


@dataclass(frozen=True, slots=True)
class SumoScenario:
    """Files of an exported scenario."""

    directory: Path
    sumocfg: Path
    net: Path
    routes: Path


SUMO_PROCESSING = {
    "step-method.ballistic": "true",
    "collision.action": "warn",
    "collision.mingap-factor": "0",
    "collision.check-junctions": "true",
}
"""SUMO's processing options as our engine works: ballistic position updates, collisions
warned about and counted while the run goes on (module docstring)."""

_TIME = ("begin", "end", "step-length")


def sumo_options(config: ScenarioConfig, seed: int) -> dict[str, str]:
    """SUMO options (name -> value) shared by the exported .sumocfg and the co-simulation."""
    return {
        "begin": "0",
        "end": f"{config.warmup + config.duration:.6g}",
        "step-length": f"{config.dt:.6g}",
        **SUMO_PROCESSING,
        "lanechange.duration": f"{config.hdv.lane_change_duration:.6g}",
        "seed": str(seed),
    }


def sumocfg_xml(
    inputs: dict[str, str], options: dict[str, str], outputs: dict[str, str] | None = None
) -> str:
    """A .sumocfg: the ``inputs`` (option -> file), ``begin``, ``end`` and ``step-length`` of
    ``options`` as its time, ``seed`` as its random number seed, every other option as
    processing, and the ``outputs`` (option -> file)."""

    def section(name: str, values: dict[str, str]) -> list[str]:
        rows = [f'        <{k} value="{v}"/>' for k, v in values.items()]
        return [f"    <{name}>", *rows, f"    </{name}>"] if rows else []

    processing = {k: v for k, v in options.items() if k not in (*_TIME, "seed")}
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        "<configuration>",
        *section("input", inputs),
        *section("time", {k: options[k] for k in _TIME}),
        *section("processing", processing),
        *section("output", outputs or {}),
        *section("random_number", {"seed": options["seed"]}),
        "</configuration>",
    ]
    return "\n".join(lines) + "\n"


def export_scenario(config: ScenarioConfig, seed: int, out_dir: Path) -> SumoScenario:
    """Write the SUMO scenario of ``config`` with ``seed`` into ``out_dir``."""
    routes = routes_xml(config, seed)  # validates before anything is written
    net = build_network(config, out_dir)
    route_path = out_dir / ROUTE_FILE
    route_path.write_text(routes, encoding="utf-8")
    cfg_path = out_dir / f"{config.name}.sumocfg"
    inputs = {"net-file": NET_FILE, "route-files": ROUTE_FILE}
    cfg_path.write_text(sumocfg_xml(inputs, sumo_options(config, seed)), encoding="utf-8")
    (out_dir / "scenario.toml").write_text(config_to_toml(config), encoding="utf-8")
    write_json_atomic(
        out_dir / "manifest.json",
        build_manifest(seed=seed, config=config.model_dump(mode="json"), extra={"engine": "sumo"}),
    )
    return SumoScenario(directory=out_dir, sumocfg=cfg_path, net=net, routes=route_path)
