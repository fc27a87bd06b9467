"""SUMO vehicle types and vehicles from our config and seeded demand.

Vehicle types map our parameters one to one onto SUMO's IDM (``carFollowModel="IDM"``):
v0 -> ``maxSpeed`` (with ``speedFactor`` 1 and an edge limit above every v0, SUMO's IDM desired
speed is exactly v0), T -> ``tau``, s0 -> ``minGap``, a -> ``accel``, b -> ``decel``, delta ->
``delta``, the physical braking limit -> ``emergencyDecel``, length and width from the road.
Lane changes use SUMO's LC2013 model with the politeness as ``lcCooperative`` and overtaking
on the right allowed (``lcOvertakeRight`` 1, as in our model, where car-following sees only
the own lane); a change takes
``lane_change_duration`` seconds (``maxSpeedLat`` = lane width / duration, continuous lane
changes). What SUMO's IDM does not have: the human driver model's reaction delays and
estimation errors (Eq. 2) and the CAVs' constant-acceleration heuristic (Eq. 3).

Vehicles come from :func:`hcomc.sim.demand.generate_demand` with the run's seed, so the same
seed gives the same vehicles, kinds, release times, positions and speeds in both engines. SUMO
time 0 is our t = -warmup. Vehicle ``v{i}`` is our vehicle slot i.
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from hcomc.config import IDMParams, ScenarioConfig
from hcomc.rng import make_rng
from hcomc.road import Kind
from hcomc.sim.demand import Demand, generate_demand
from hcomc.sumo.network import edge_at, road_edges, sumo_lane_of

__all__ = [
    "TYPE_IDS",
    "Departure",
    "departures",
    "routes_xml",
    "sumo_problem",
    "vehicle_id",
    "vtype_attributes",
]

TYPE_IDS = {Kind.HDV: "hdv", Kind.CAV: "cav"}


def vehicle_id(slot: int) -> str:
    """SUMO id of our vehicle slot."""
    return f"v{slot}"


def vtype_attributes(config: ScenarioConfig, kind: Kind) -> dict[str, str]:
    """SUMO ``vType`` attributes of one vehicle kind."""
    params: IDMParams = config.cav if kind == Kind.CAV else config.hdv
    road, lc = config.road, config.lane_change
    if params.variant != "idm":
        raise ValueError(
            f"key '{'cav' if kind == Kind.CAV else 'hdv'}.variant' = '{params.variant}': SUMO "
            "supports only 'idm' (SUMO's IDM; the improved IDM has no SUMO counterpart)"
        )
    attrs = {
        "id": TYPE_IDS[kind],
        "vClass": "passenger",
        "carFollowModel": "IDM",
        "maxSpeed": params.desired_speed,
        "speedFactor": 1.0,
        "speedDev": 0.0,
        "tau": params.time_headway,
        "minGap": params.min_gap,
        "accel": params.max_accel,
        "decel": params.comfort_decel,
        "delta": params.exponent,
        "emergencyDecel": lc.emergency_decel,
        "length": road.vehicle_length,
        "width": road.vehicle_width,
        "laneChangeModel": "LC2013",
        "lcCooperative": lc.politeness,
        # our car-following sees only the own lane: no ban on overtaking on the right (SUMO's
        # default ban couples the lanes and makes lane-1 vehicles' accelerations chatter)
        "lcOvertakeRight": 1.0,
        "maxSpeedLat": road.lane_width / params.lane_change_duration,
        "color": "0,160,255" if kind == Kind.CAV else "200,200,200",
    }
    return {k: (f"{v:.6g}" if isinstance(v, float) else str(v)) for k, v in attrs.items()}


@dataclass(frozen=True, slots=True)
class Departure:
    """One SUMO vehicle: where and when our demand releases it."""

    slot: int
    kind: Kind
    depart: float  # SUMO time [s] (our t + warmup)
    route: str
    lane: int  # SUMO lane index on the route's first edge
    pos: float  # front bumper position on that edge [m]
    speed: float  # [m/s]


def route_id(edge: str) -> str:
    """Id of the route that starts on ``edge`` and runs to the road end."""
    return f"from_{edge}"


def departures(config: ScenarioConfig, demand: Demand) -> list[Departure]:
    """SUMO departures of every demand vehicle, in release order.

    SUMO places a vehicle with its whole body on its first edge, so a front bumper less than
    one vehicle length into an edge is moved forward to one length (at most that far, e.g.
    arrivals at x = 0 enter with their front at x = L).
    """
    out = []
    length = config.road.vehicle_length
    for i in range(demand.n):
        lane = int(demand.lane[i])
        edge = edge_at(config, float(demand.x[i]), lane)
        pos = min(max(float(demand.x[i]) - edge.x0, length), edge.x1 - edge.x0)
        out.append(
            Departure(
                slot=i,
                kind=Kind(int(demand.kind[i])),
                depart=float(demand.t[i]) + config.warmup,
                route=route_id(edge.id),
                lane=sumo_lane_of(edge, lane),
                pos=pos,
                speed=float(demand.v[i]),
            )
        )
    return out


def check_exportable(config: ScenarioConfig) -> None:
    """Raise ValueError (key, value, what is allowed) if SUMO cannot represent ``config``."""
    if config.scenario != "merge":
        raise ValueError(f"key 'scenario' = '{config.scenario}': SUMO supports only 'merge'")
    for kind in (Kind.HDV, Kind.CAV):
        vtype_attributes(config, kind)


def routes_xml(config: ScenarioConfig, seed: int) -> str:
    """The ``.rou.xml`` text: vTypes, one route per starting edge, every demand vehicle."""
    check_exportable(config)
    demand = generate_demand(config, make_rng(seed))
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<routes>"]
    for kind in (Kind.HDV, Kind.CAV):
        attrs = " ".join(f"{k}={quoteattr(v)}" for k, v in vtype_attributes(config, kind).items())
        lines.append(f"    <vType {attrs}/>")
    edges = [e.id for e in road_edges(config)]
    for k, edge in enumerate(edges):
        lines.append(f'    <route id="{route_id(edge)}" edges="{" ".join(edges[k:])}"/>')
    for d in departures(config, demand):
        lines.append(
            f'    <vehicle id="{vehicle_id(d.slot)}" type="{TYPE_IDS[d.kind]}" route="{d.route}" '
            f'depart="{d.depart:.3f}" departLane="{d.lane}" departPos="{d.pos:.3f}" '
            f'departSpeed="{d.speed:.3f}"/>'
        )
    lines.append("</routes>")
    return "\n".join(lines) + "\n"


def sumo_problem(config: ScenarioConfig | None = None) -> str | None:
    """Why the SUMO co-simulation cannot run here, or cannot run ``config`` (one line), or
    None: libsumo and netconvert installed, the scenario exportable."""
    from hcomc.sumo import SumoMissingError, import_libsumo, sumo_binary

    try:
        import_libsumo()
        sumo_binary("netconvert")
        if config is not None:
            check_exportable(config)
    except (SumoMissingError, ValueError) as exc:
        return str(exc)
    return None
