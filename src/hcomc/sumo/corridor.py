"""``hcomc export sumo corridor``: a corridor as a runnable SUMO scenario directory.

The directory holds the network (:mod:`hcomc.sumo.corridor_network`, ``net.xml``), the
demand (``routes.rou.xml``), induction loops (``detectors.add.xml``, writing
``detectors.out.xml``), ``corridor.sumocfg``, the resolved corridor (``corridor.toml``) and a
manifest. ``sumo -c DIR/corridor.sumocfg`` runs it unchanged and writes ``statistics.xml``
(teleports, collisions, trip statistics).

**Vehicle types.** One vType per class and automation, ``<class>_hdv`` and ``<class>_cav``,
all on SUMO's IDM (``carFollowModel="IDM"``): desired speed v0 -> ``desiredMaxSpeed`` (with
``speedFactor`` 1, ``speedDev`` 0 a vehicle drives at most min(v0, speed limit, max_speed)),
T -> ``tau``, s0 -> ``minGap``, a -> ``accel``, b -> ``decel``, delta -> ``delta``. CAVs use
the same IDM with their class's ``cav`` values (by default a shorter time headway), not SUMO's
``ACC`` model: that is a different controller (Milanés & Shladover 2014) with gains of its own,
while keeping both kinds on the IDM keeps SUMO's runs comparable with the IDM family hcomc's
engine uses. Each origin draws its vehicles' types from a ``vTypeDistribution`` with the
probabilities class share x (CAV share or 1 - CAV share).

**Flows.** One ``<flow>`` per flow of the departure schedule
(:func:`hcomc.corridor.schedule.flows`: per origin, destination and profile interval, evenly
spaced departures), with ``departLane="best"``, ``departSpeed="max"`` and SUMO's default
``departPos``; hcomc departs the same vehicles at the same times.
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from hcomc.corridor import Corridor, corridor_to_toml, detector_positions
from hcomc.corridor.schedule import flows
from hcomc.sim.manifest import build_manifest, write_json_atomic
from hcomc.sumo.corridor_network import (
    NET_FILE,
    build_corridor_network,
    corridor_edges,
    route_edges,
)
from hcomc.sumo.export import SUMO_PROCESSING, SumoScenario, sumocfg_xml

__all__ = [
    "CFG_FILE",
    "DETECTOR_OUTPUT",
    "CorridorScenario",
    "detectors_xml",
    "export_corridor",
    "flow_id",
    "routes_xml",
]

CFG_FILE = "corridor.sumocfg"
ROUTE_FILE = "routes.rou.xml"
DETECTOR_FILE = "detectors.add.xml"
DETECTOR_OUTPUT = "detectors.out.xml"
STATISTICS_FILE = "statistics.xml"


@dataclass(frozen=True, slots=True)
class CorridorScenario(SumoScenario):
    """Files of an exported corridor: those of any exported scenario and its loops."""

    detectors: Path


def flow_id(origin: str, destination: str, k: int) -> str:
    """Id of a flow; SUMO names its vehicles ``<flow id>.<n>``. Ramp ids contain no ``_``."""
    return f"{origin}_{destination}_{k}"


def _attrs(values: dict[str, object]) -> str:
    return " ".join(
        f"{k}={quoteattr(f'{v:.6g}' if isinstance(v, float) else str(v))}"
        for k, v in values.items()
    )


def _vtypes(c: Corridor) -> list[str]:
    lane_change = c.corridor.lane_change_duration
    rows = []
    for name, cls in c.vehicles.items():
        for cav in (False, True):
            idm = cls.idm(cav)
            attrs: dict[str, object] = {
                "id": f"{name}_{'cav' if cav else 'hdv'}",
                "vClass": cls.vclass,
                "carFollowModel": "IDM",
                "length": cls.length,
                "width": cls.width,
                "maxSpeed": cls.max_speed,
                "desiredMaxSpeed": idm["desired_speed"],
                "speedFactor": 1.0,
                "speedDev": 0.0,
                "tau": idm["time_headway"],
                "minGap": idm["min_gap"],
                "accel": idm["max_accel"],
                "decel": idm["comfort_decel"],
                "delta": idm["exponent"],
                "emergencyDecel": 9.0,
                "laneChangeModel": "LC2013",
                "color": "0,160,255" if cav else "200,200,200",
            }
            if lane_change > 0:
                attrs["maxSpeedLat"] = c.road.lane_width / lane_change
            rows.append(f"    <vType {_attrs(attrs)}/>")
    return rows


def _mixes(c: Corridor) -> list[str]:
    rows = []
    for origin, demand in c.demand.items():
        types, probs = [], []
        for name, share in demand.classes.items():
            for kind, p in (("hdv", 1 - demand.cav_share), ("cav", demand.cav_share)):
                if share * p > 0:
                    types.append(f"{name}_{kind}")
                    probs.append(f"{share * p:.6g}")
        rows.append(
            f'    <vTypeDistribution id="{origin}_mix" vTypes="{" ".join(types)}" '
            f'probabilities="{" ".join(probs)}"/>'
        )
    return rows


def _flows(c: Corridor) -> list[str]:
    """The ``<flow>`` line of every flow of the departure schedule, by ``begin``."""
    return [
        f'    <flow id="{flow_id(f.origin, f.destination, f.interval)}" type="{f.origin}_mix" '
        f'route="{f.origin}_{f.destination}" begin="{f.begin:.3f}" end="{f.end:.3f}" '
        f'vehsPerHour="{f.rate:.6g}" departLane="best" departSpeed="max"/>'
        for f in flows(c)
    ]


def routes_xml(c: Corridor) -> str:
    """The ``.rou.xml`` text: vTypes, one type mix and route per origin, the flows."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<routes>", *_vtypes(c), *_mixes(c)]
    for origin, demand in c.demand.items():
        for dest in demand.destinations:
            edges = " ".join(route_edges(c, origin, dest))
            lines.append(f'    <route id="{origin}_{dest}" edges="{edges}"/>')
    lines += _flows(c)
    lines.append("</routes>")
    return "\n".join(lines) + "\n"


def detectors_xml(c: Corridor) -> str:
    """The additional file: an E1 induction loop on every mainline lane at each position of
    :func:`~hcomc.corridor.model.detector_positions` (id ``det_<x>_<k>``, k = 0 the rightmost
    mainline lane)."""
    edges = corridor_edges(c)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<additional>"]
    for x in detector_positions(c):
        edge = next(e for e in reversed(edges) if e.section.x0 <= x)
        for k in range(edge.section.lanes):
            attrs = {
                "id": f"det_{x:g}_{k}",
                "lane": f"{edge.id}_{edge.main_lane(k)}",
                "pos": round(x - edge.section.x0, 3),
                "period": c.detectors.period,
                "file": DETECTOR_OUTPUT,
                "friendlyPos": "true",
            }
            lines.append(f"    <inductionLoop {_attrs(attrs)}/>")
    lines.append("</additional>")
    return "\n".join(lines) + "\n"


def _sumocfg(c: Corridor) -> str:
    run = c.corridor
    options = {"begin": "0", "end": f"{run.duration:.6g}",
               "step-length": f"{run.step_length:.6g}", **SUMO_PROCESSING}  # fmt: skip
    if run.lane_change_duration > 0:
        options["lanechange.duration"] = f"{run.lane_change_duration:.6g}"
    options["seed"] = str(run.seed)
    inputs = {"net-file": NET_FILE, "route-files": ROUTE_FILE, "additional-files": DETECTOR_FILE}
    return sumocfg_xml(inputs, options, {"statistic-output": STATISTICS_FILE})


def export_corridor(c: Corridor, out_dir: Path) -> CorridorScenario:
    """Write the SUMO scenario of corridor ``c`` into ``out_dir``.

    Everything is built in a temporary directory beside ``out_dir`` and moved into place only
    once netconvert has succeeded, so a failure leaves ``out_dir`` as it was.
    """
    texts = {ROUTE_FILE: routes_xml(c), DETECTOR_FILE: detectors_xml(c), CFG_FILE: _sumocfg(c)}
    texts["corridor.toml"] = corridor_to_toml(c)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out_dir.parent, prefix=".corridor-") as tmp:
        work = Path(tmp)
        build_corridor_network(c, work)
        for name, text in texts.items():
            (work / name).write_text(text, encoding="utf-8")
        write_json_atomic(
            work / "manifest.json",
            build_manifest(
                seed=c.corridor.seed, config=c.model_dump(mode="json"), extra={"engine": "sumo"}
            ),
        )
        out_dir.mkdir(exist_ok=True)
        for path in work.iterdir():
            shutil.move(str(path), out_dir / path.name)
    return CorridorScenario(
        directory=out_dir,
        sumocfg=out_dir / CFG_FILE,
        net=out_dir / NET_FILE,
        routes=out_dir / ROUTE_FILE,
        detectors=out_dir / DETECTOR_FILE,
    )
