"""The scenario's road as a SUMO network: plain nodes/edges/connections XML -> netconvert.

The road (paper Section II, Fig. 1) is a two-lane mainline with an on-ramp whose lane runs
parallel to lane 1 from ``ramp_start`` and becomes the acceleration lane on
``[accel_lane_start, accel_lane_end]``, where it ends. In SUMO this is four straight edges in a
row along the x axis, so SUMO's Cartesian x *is* our x and its y our lateral position:

=================  ================================  =====  ==================================
edge               x range [m]                       lanes  lane 0 / 1 / 2
=================  ================================  =====  ==================================
``main_up``        0 .. ramp_start                   2      lane 1 / lane 2
``ramp``           ramp_start .. accel_lane_start    3      ramp / lane 1 / lane 2 (no changes
                                                            between ramp and lane 1)
``accel``          accel_lane_start .. accel_lane_end 3     acceleration lane / lane 1 / lane 2
``main_down``      accel_lane_end .. length          2      lane 1 / lane 2
=================  ================================  =====  ==================================

Lanes are spread to the right of the edge line, which lies at y = 1.5 W, so lane centres are
at y = +W (lane 2), 0 (lane 1) and -W (ramp), exactly :func:`hcomc.road.lane_centre`.
Mainline vehicles may not move onto the ramp or acceleration lane (as in our engine).
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path
from xml.sax.saxutils import quoteattr

from hcomc.config import ScenarioConfig
from hcomc.road import Lane
from hcomc.sumo import SumoFormatError, sumo_binary

__all__ = ["NET_FILE", "Edge", "build_network", "road_edges", "sumo_lane_of"]

NET_FILE = "road.net.xml"
_NO_CHANGE = "authority"  # only this vehicle class (none of ours) may change across the line


@dataclass(frozen=True, slots=True)
class Edge:
    """A straight mainline section [x0, x1] and whether it carries the ramp lane."""

    id: str
    x0: float
    x1: float
    has_ramp: bool  # lane 0 is the ramp / acceleration lane
    merge_allowed: bool  # the acceleration lane: ramp -> lane 1 changes allowed

    @property
    def n_lanes(self) -> int:
        """Number of SUMO lanes."""
        return 3 if self.has_ramp else 2


def road_edges(config: ScenarioConfig) -> tuple[Edge, ...]:
    """The four edges of the road, upstream first."""
    r = config.road
    return (
        Edge("main_up", 0.0, r.ramp_start, has_ramp=False, merge_allowed=False),
        Edge("ramp", r.ramp_start, r.accel_lane_start, has_ramp=True, merge_allowed=False),
        Edge("accel", r.accel_lane_start, r.accel_lane_end, has_ramp=True, merge_allowed=True),
        Edge("main_down", r.accel_lane_end, r.length, has_ramp=False, merge_allowed=False),
    )


def sumo_lane_of(edge: Edge, lane: int) -> int:
    """SUMO lane index on ``edge`` of our :class:`~hcomc.road.Lane`."""
    index = int(lane) if edge.has_ramp else int(lane) - 1
    if not 0 <= index < edge.n_lanes:
        raise ValueError(f"lane {Lane(lane).name} does not exist on edge '{edge.id}'")
    return index


def edge_at(config: ScenarioConfig, x: float, lane: int) -> Edge:
    """The edge holding position x of ``lane`` (the downstream one at a boundary)."""
    edges = [e for e in road_edges(config) if e.has_ramp or lane != Lane.RAMP]
    for edge in reversed(edges):
        if x >= edge.x0:
            return edge
    return edges[0]


def _nodes_xml(config: ScenarioConfig) -> str:
    y = 1.5 * config.road.lane_width  # left border of lane 2
    edges = road_edges(config)
    xs = [edges[0].x0, *(e.x1 for e in edges)]
    # radius 0: no junction area, so every edge keeps its exact length
    rows = "\n".join(
        f'    <node id="n{k}" x="{x:.3f}" y="{y:.3f}" type="priority" radius="0"/>'
        for k, x in enumerate(xs)
    )
    return f"<nodes>\n{rows}\n</nodes>\n"


def _edges_xml(config: ScenarioConfig, speed: float) -> str:
    width = config.road.lane_width
    rows = []
    for k, e in enumerate(road_edges(config)):
        rows.append(
            f'    <edge id="{e.id}" from="n{k}" to="n{k + 1}" numLanes="{e.n_lanes}" '
            f'speed="{speed:.3f}" width="{width:.3f}" spreadType="right">'
        )
        if e.has_ramp:
            # lane 0 -> 1 only on the acceleration lane; lane 1 never moves onto lane 0
            ramp_left = "" if e.merge_allowed else f" changeLeft={quoteattr(_NO_CHANGE)}"
            rows.append(f'        <lane index="0"{ramp_left}/>')
            rows.append(f'        <lane index="1" changeRight={quoteattr(_NO_CHANGE)}/>')
        rows.append("    </edge>")
    return "<edges>\n" + "\n".join(rows) + "\n</edges>\n"


def _connections_xml(config: ScenarioConfig) -> str:
    edges = road_edges(config)
    rows = []
    for up, down in pairwise(edges):
        for lane in (Lane.RAMP, Lane.MAIN_1, Lane.MAIN_2):
            if lane == Lane.RAMP and not (up.has_ramp and down.has_ramp):
                continue  # the ramp starts at 'ramp'; the acceleration lane ends with 'accel'
            rows.append(
                f'    <connection from="{up.id}" to="{down.id}" '
                f'fromLane="{sumo_lane_of(up, lane)}" toLane="{sumo_lane_of(down, lane)}"/>'
            )
    return "<connections>\n" + "\n".join(rows) + "\n</connections>\n"


def road_speed(config: ScenarioConfig) -> float:
    """Edge speed limit [m/s]: above every desired speed, so each vType's own v0 governs."""
    return max(config.hdv.desired_speed, config.cav.desired_speed) + 5.0


def build_network(config: ScenarioConfig, out_dir: Path) -> Path:
    """Write plain XML into ``out_dir`` and run netconvert; returns the ``.net.xml`` path."""
    out_dir.mkdir(parents=True, exist_ok=True)
    plain = {
        "road.nod.xml": _nodes_xml(config),
        "road.edg.xml": _edges_xml(config, road_speed(config)),
        "road.con.xml": _connections_xml(config),
    }
    for name, text in plain.items():
        (out_dir / name).write_text('<?xml version="1.0" encoding="UTF-8"?>\n' + text, "utf-8")
    net = out_dir / NET_FILE
    cmd = [
        sumo_binary("netconvert"),
        "--node-files", str(out_dir / "road.nod.xml"),
        "--edge-files", str(out_dir / "road.edg.xml"),
        "--connection-files", str(out_dir / "road.con.xml"),
        "--offset.disable-normalization", "true",  # keep SUMO's x equal to ours
        "--no-turnarounds", "true",
        "--output-file", str(net),
    ]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0 or not net.is_file():
        message = (done.stderr or done.stdout).strip().splitlines()
        raise SumoFormatError(
            f"netconvert failed on {out_dir}: {message[-1] if message else 'no output'}"
        )
    return net
