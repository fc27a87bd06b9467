"""A corridor's road as a SUMO network: plain nodes/edges/connections XML -> netconvert.

The mainline runs along the x axis, so SUMO's x is the corridor's x. Each section of
:func:`hcomc.corridor.road.sections` is one edge ``main_<i>`` (upstream first) with the
section's mainline lanes plus its ramp lanes, which are the rightmost SUMO lanes (index 0 ..
ramp_lanes - 1): mainline lane k, counted from the right, is SUMO lane ``ramp_lanes + k``. The
right border of the mainline lies on y = 0 everywhere, so a lane keeps its place across
sections, ramp lanes lie at y < 0 and, at a lane drop, the leftmost lanes end (or start).

An on-ramp is an edge named by its id from the ramp's start to the mainline node at ``x``;
its lanes continue as the acceleration lanes, which end (no successor) at ``x +
accel_length``, so ramp vehicles must change left on them; mainline vehicles may not change
onto them. An off-ramp is an edge named by its id leaving at ``x + decel_length`` from the
deceleration lanes, which open at ``x`` and are reached by changing right. Ramp edges are
drawn at a slight angle to the mainline (:data:`hcomc.corridor.layout.RAMP_SLOPE`, the slope
the CommonRoad export and the browser replay draw) and have their exact ``ramp_length``.
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

from hcomc.corridor import Corridor, Section, sections
from hcomc.corridor.layout import RAMP_SLOPE
from hcomc.sumo import SumoFormatError, sumo_binary

__all__ = ["NET_FILE", "CorridorEdge", "build_corridor_network", "corridor_edges", "route_edges"]

NET_FILE = "net.xml"
_PLAIN = ("corridor.nod.xml", "corridor.edg.xml", "corridor.con.xml")
_NO_CHANGE = "authority"  # only this vehicle class (none of ours) may change across the line
_STRAIGHT = 20.0  # [m] of a ramp run parallel to the mainline at the junction, which keeps
# the junction a point (an angled edge would give it an area and shorten the mainline edges)


@dataclass(frozen=True, slots=True)
class CorridorEdge:
    """A mainline edge: the section it is, its id and its end nodes."""

    id: str
    section: Section
    from_node: str
    to_node: str

    def main_lane(self, k: int) -> int:
        """SUMO lane index of mainline lane k (0 = rightmost mainline lane)."""
        return self.section.ramp_lanes + k


def corridor_edges(corridor: Corridor) -> tuple[CorridorEdge, ...]:
    """The mainline edges, upstream first."""
    return tuple(
        CorridorEdge(f"main_{i}", s, f"n{i}", f"n{i + 1}")
        for i, s in enumerate(sections(corridor.road))
    )


def _node_at(edges: tuple[CorridorEdge, ...], x: float) -> str:
    for e in edges:
        if abs(e.section.x0 - x) < 1e-6:
            return e.from_node
    return edges[-1].to_node


def route_edges(corridor: Corridor, origin: str, destination: str) -> list[str]:
    """Edge ids from ``origin`` (``main`` or an on-ramp id) to ``destination`` (``exit`` or an
    off-ramp id)."""
    edges = corridor_edges(corridor)
    start = corridor.origin_x(origin)
    out = [] if origin == "main" else [origin]
    off = next((r for r in corridor.road.off_ramps if r.id == destination), None)
    end = corridor.road.length if off is None else off.end
    out += [e.id for e in edges if e.section.x0 >= start - 1e-6 and e.section.x1 <= end + 1e-6]
    return out if off is None else [*out, off.id]


def _nodes_xml(corridor: Corridor, edges: tuple[CorridorEdge, ...]) -> str:
    rows = [
        f'    <node id="{e.from_node}" x="{e.section.x0:.3f}" y="0.000" type="priority" '
        'radius="0"/>'
        for e in edges
    ]
    rows.append(
        f'    <node id="{edges[-1].to_node}" x="{corridor.road.length:.3f}" y="0.000" '
        'type="priority" radius="0"/>'
    )
    for ramp in corridor.road.on_ramps:
        x, y = ramp.x - ramp.ramp_length, -RAMP_SLOPE * ramp.ramp_length
        rows.append(f'    <node id="{ramp.id}_start" x="{x:.3f}" y="{y:.3f}" type="priority"/>')
    for off in corridor.road.off_ramps:
        x, y = off.end + off.ramp_length, -RAMP_SLOPE * off.ramp_length
        rows.append(f'    <node id="{off.id}_end" x="{x:.3f}" y="{y:.3f}" type="priority"/>')
    return "<nodes>\n" + "\n".join(rows) + "\n</nodes>\n"


def _edges_xml(corridor: Corridor, edges: tuple[CorridorEdge, ...]) -> str:
    road, width = corridor.road, corridor.road.lane_width
    rows = []
    for e in edges:
        s = e.section
        top = s.lanes * width  # left border of the leftmost lane; lanes spread to its right
        rows.append(
            f'    <edge id="{e.id}" from="{e.from_node}" to="{e.to_node}" '
            f'numLanes="{s.total_lanes}" speed="{s.speed_limit:.3f}" width="{width:.3f}" '
            f'spreadType="right" shape="{s.x0:.3f},{top:.3f} {s.x1:.3f},{top:.3f}">'
        )
        if s.kind == "accel":  # mainline vehicles stay off the acceleration lanes
            rows.append(f'        <lane index="{s.ramp_lanes}" changeRight="{_NO_CHANGE}"/>')
        rows.append("    </edge>")
    for ramp in road.on_ramps:
        start_y = -RAMP_SLOPE * ramp.ramp_length  # its left border meets y = 0 at x
        rows.append(
            f'    <edge id="{ramp.id}" from="{ramp.id}_start" to="{_node_at(edges, ramp.x)}" '
            f'numLanes="{ramp.lanes}" speed="{road.speed_at(ramp.x):.3f}" width="{width:.3f}" '
            f'spreadType="right" length="{ramp.ramp_length:.3f}" shape="'
            f"{ramp.x - ramp.ramp_length:.3f},{start_y:.3f} {ramp.x - _STRAIGHT:.3f},0.000 "
            f'{ramp.x:.3f},0.000"/>'
        )
    for off in road.off_ramps:
        end_y = -RAMP_SLOPE * off.ramp_length
        rows.append(
            f'    <edge id="{off.id}" from="{_node_at(edges, off.end)}" to="{off.id}_end" '
            f'numLanes="{off.lanes}" speed="{road.speed_at(off.x):.3f}" width="{width:.3f}" '
            f'spreadType="right" length="{off.ramp_length:.3f}" shape="'
            f"{off.end:.3f},0.000 {off.end + _STRAIGHT:.3f},0.000 "
            f'{off.end + off.ramp_length:.3f},{end_y:.3f}"/>'
        )
    return "<edges>\n" + "\n".join(rows) + "\n</edges>\n"


def _connection(src: str, dst: str, from_lane: int, to_lane: int) -> str:
    return f'    <connection from="{src}" to="{dst}" fromLane="{from_lane}" toLane="{to_lane}"/>'


def _connections_xml(corridor: Corridor, edges: tuple[CorridorEdge, ...]) -> str:
    rows = []
    for up, down in pairwise(edges):
        for k in range(min(up.section.lanes, down.section.lanes)):
            rows.append(_connection(up.id, down.id, up.main_lane(k), down.main_lane(k)))
        if up.section.ramp is not None and up.section.ramp == down.section.ramp:
            for j in range(up.section.ramp_lanes):  # ramp lanes cut by a speed-zone boundary
                rows.append(_connection(up.id, down.id, j, j))
    for ramp in corridor.road.on_ramps:
        first = next(e for e in edges if e.section.ramp == ramp.id)
        rows += [_connection(ramp.id, first.id, j, j) for j in range(ramp.lanes)]
    for off in corridor.road.off_ramps:
        last = [e for e in edges if e.section.ramp == off.id][-1]
        rows += [_connection(last.id, off.id, j, j) for j in range(off.lanes)]
    return "<connections>\n" + "\n".join(rows) + "\n</connections>\n"


def build_corridor_network(corridor: Corridor, out_dir: Path) -> Path:
    """Write the plain XML into ``out_dir`` and run netconvert; returns the net file."""
    edges = corridor_edges(corridor)
    texts = (
        _nodes_xml(corridor, edges),
        _edges_xml(corridor, edges),
        _connections_xml(corridor, edges),
    )
    for name, text in zip(_PLAIN, texts, strict=True):
        (out_dir / name).write_text('<?xml version="1.0" encoding="UTF-8"?>\n' + text, "utf-8")
    cmd = [
        sumo_binary("netconvert"),
        "--node-files", _PLAIN[0],
        "--edge-files", _PLAIN[1],
        "--connection-files", _PLAIN[2],
        "--offset.disable-normalization", "true",  # keep SUMO's x equal to the corridor's
        "--no-turnarounds", "true",
        "--output-file", NET_FILE,
    ]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=out_dir)
    net = out_dir / NET_FILE
    if done.returncode != 0 or not net.is_file():
        message = (done.stderr or done.stdout).strip().splitlines()
        raise SumoFormatError(
            f"netconvert failed on {out_dir}: {message[-1] if message else 'no output'}"
        )
    return net
