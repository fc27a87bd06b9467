"""SUMO FCD XML (``--fcd-output``) to and from a :class:`SimulationLog`.

``<fcd-export><timestep time><vehicle id x y angle type speed pos lane slope
acceleration/>``. ``x, y`` is the front bumper centre, ``angle`` the navigation angle in
degrees (90 = along +x), ``time`` SUMO's clock (our t + warmup), ``id`` ``v<slot>``, ``type``
``hdv``/``cav``. Reading takes the vehicle kind from ``type`` (a type id containing "cav" is a
CAV), the lane from y (a vehicle exactly on a lane line is in the lane it moves into, as in the
engine), drops the warm-up rows (t < 0) and derives the acceleration from the speeds when the
file has none. Coordinates are our road's (:mod:`hcomc.sumo.trajectories`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd

from hcomc.config import ScenarioConfig
from hcomc.road import Kind
from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import atomic_paths
from hcomc.sumo import SumoFormatError
from hcomc.sumo.network import edge_at, sumo_lane_of
from hcomc.sumo.trajectories import _fill, _new_log

__all__ = ["read_fcd", "write_fcd"]


def write_fcd(log: SimulationLog, path: Path, config: ScenarioConfig) -> Path:
    """SUMO FCD XML of the log (SUMO clock: t + warmup; lanes of the exported network)."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<fcd-export>"]
    types = {int(Kind.HDV): "hdv", int(Kind.CAV): "cav"}
    for k in range(log.n_recorded):
        lines.append(f'    <timestep time="{log.t[k] + config.warmup:.3f}">')
        xs, ys, lanes, headings = log.x[k], log.y[k], log.lane[k], log.heading[k]
        vs, accs = log.v[k], log.a[k]  # each row read once
        for i in np.flatnonzero(log.active[k]).tolist():
            x, y = float(xs[i]), float(ys[i])
            lane = int(lanes[i])
            edge = edge_at(config, x, lane)
            angle = 90.0 - math.degrees(float(headings[i]))
            lines.append(
                f'        <vehicle id="v{i}" x="{x:.4f}" y="{y:.4f}" angle="{angle:.6f}" '
                f'type="{types[int(log.kind[i])]}" speed="{float(vs[i]):.6f}" '
                f'pos="{x - edge.x0:.4f}" lane="{edge.id}_{sumo_lane_of(edge, lane)}" '
                f'slope="0.00" acceleration="{float(accs[i]):.6f}"/>'
            )
        lines.append("    </timestep>")
    lines.append("</fcd-export>")
    with atomic_paths(path) as (tmp,):
        tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _uniform_dt(times: np.ndarray, source: Path, element: str) -> float:
    if times.size < 2:
        raise SumoFormatError(f"{source}: need at least two {element} elements, got {times.size}")
    steps = np.diff(times)
    dt = float(np.median(steps))
    if dt <= 0 or np.max(np.abs(steps - dt)) > 1e-6 * max(1.0, dt):
        raise SumoFormatError(
            f"{source}: {element} times must be increasing with one constant step, got steps "
            f"from {steps.min():.6g} to {steps.max():.6g} s"
        )
    return dt


def _lane_of_y(
    y: np.ndarray, vehicle: np.ndarray, row: np.ndarray, heading: np.ndarray,
    config: ScenarioConfig,
) -> np.ndarray:  # fmt: skip
    """Lane of each sample from its lateral position ``y`` [m], as the engine assigns it:
    the nearest lane centre, and a sample exactly on a lane line in the lane the vehicle is
    moving into (the engine switches a changing vehicle's lane when its centre reaches the
    line). The direction is that of the vehicle's lateral motion between its samples before
    and after (``vehicle``, ``row`` identify them), or of its ``heading`` [rad] where those
    do not tell; a sample on a line without either keeps the nearest even lane index."""
    u = y / config.road.lane_width
    lane = np.rint(u)
    tie = u - np.floor(u) == 0.5
    if tie.any():
        moving = _lateral_motion(y, vehicle, row)
        moving = np.where(moving == 0.0, np.sign(heading), moving)
        lane = np.where(tie & (moving > 0), np.ceil(u), lane)
        lane = np.where(tie & (moving < 0), np.floor(u), lane)
    return lane.astype(np.int64) + 1


def _lateral_motion(y: np.ndarray, vehicle: np.ndarray, row: np.ndarray) -> np.ndarray:
    """Sign of each sample's lateral motion: ``y`` of the vehicle's next sample minus that
    of its previous one (the sample itself where there is none)."""
    order = np.lexsort((row, vehicle))
    ys, vs = y[order], vehicle[order]
    before, after = ys.copy(), ys.copy()
    same = vs[1:] == vs[:-1]
    before[1:][same], after[:-1][same] = ys[:-1][same], ys[1:][same]
    out = np.empty_like(y, dtype=np.float64)
    out[order] = np.sign(after - before)
    return out


def _slot_ids(names: list[str]) -> dict[str, int]:
    """Vehicle id -> slot: ``v<slot>`` keeps our slots, other ids are numbered in order."""
    if all(n.startswith("v") and n[1:].isdigit() for n in names):
        return {n: int(n[1:]) for n in names}
    return {n: k for k, n in enumerate(names)}


def read_fcd(path: Path, config: ScenarioConfig) -> tuple[SimulationLog, dict[str, int]]:
    """A log from SUMO FCD XML on our road; also the vehicle id -> slot mapping."""
    records: list[tuple[float, str, float, float, float, float, float, str]] = []
    times: list[float] = []
    try:
        for _, elem in ET.iterparse(path, events=("end",)):
            if elem.tag == "timestep":
                times.append(_number(elem, "time", path))
                for veh in elem.iter("vehicle"):
                    vid = veh.get("id")
                    if vid is None:
                        raise SumoFormatError(f"{path}: <vehicle> without 'id' at {times[-1]} s")
                    acc = veh.get("acceleration")
                    records.append((
                        times[-1], vid, _number(veh, "x", path), _number(veh, "y", path),
                        _number(veh, "speed", path), _number(veh, "angle", path),
                        math.nan if acc is None else float(acc), veh.get("type", ""),
                    ))  # fmt: skip
                elem.clear()
            elif elem.tag not in ("vehicle", "fcd-export", "person", "container"):
                raise SumoFormatError(
                    f"{path}: unexpected element <{elem.tag}>; expected SUMO FCD output "
                    "(<fcd-export><timestep><vehicle .../>)"
                )
    except ET.ParseError as exc:
        raise SumoFormatError(f"{path}: not well-formed XML ({exc})") from None
    if not times:
        raise SumoFormatError(f"{path}: no <timestep> element; expected SUMO FCD output")
    t_all = np.asarray(times) - config.warmup  # SUMO time 0 is our t = -warmup
    keep = t_all >= -1e-9  # the warm-up is not logged (as in our engine)
    t = t_all[keep]
    if t.size < 2:
        raise SumoFormatError(
            f"{path}: need at least two <timestep> elements at or after the warm-up (time >= "
            f"{config.warmup:g} s, our t = 0), got {t.size}"
        )
    dt = _uniform_dt(t, path, "<timestep>")
    frame = pd.DataFrame(records, columns=["time", "id", "x", "y", "v", "angle", "a", "type"])
    ids = list(dict.fromkeys(frame["id"]))
    slots = _slot_ids(ids)
    n = max(slots.values()) + 1
    kind = np.zeros(n, dtype=np.int64)
    for vid, vtype in frame.groupby("id", sort=False)["type"].first().items():
        kind[slots[vid]] = Kind.CAV if "cav" in str(vtype).lower() else Kind.HDV
    log = _new_log(config, t, kind, dt, path, "fcd")
    row = np.rint((frame["time"].to_numpy() - config.warmup - t[0]) / dt).astype(np.int64)
    inside = (row >= 0) & (row < t.size)
    frame, row = frame[inside], row[inside]
    col = frame["id"].map(slots).to_numpy()
    heading = np.radians(90.0 - frame["angle"].to_numpy())
    y = frame["y"].to_numpy()
    lane = _lane_of_y(y, col, row, heading, config)
    _fill(log, row, col, frame["x"].to_numpy(), y, frame["v"].to_numpy(), heading,
          frame["a"].to_numpy(), lane, path, config)  # fmt: skip
    return log, {vid: slots[vid] for vid in ids}


def _number(elem: ET.Element, name: str, path: Path) -> float:
    raw = elem.get(name)
    try:
        return float(raw)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        where = f" id '{elem.get('id')}'" if elem.get("id") else ""
        raise SumoFormatError(
            f"{path}: <{elem.tag}>{where} attribute '{name}' = {raw!r}; expected a number"
        ) from None
