"""Trajectory exchange: a :class:`SimulationLog` to and from SUMO FCD XML, highD-style CSV, CSV.

Coordinates are those of our road (x along the road from the mainline start, y to the left,
lane centres at ``(lane - 1) W``), which is also the Cartesian frame of the exported SUMO
network (:mod:`hcomc.sumo.network`): an FCD file that SUMO writes for an exported scenario
reads back directly.

* **FCD** (SUMO's ``--fcd-output``): ``<fcd-export><timestep time><vehicle id x y angle type
  speed pos lane slope acceleration/>``. ``x, y`` is the front bumper centre, ``angle`` the
  navigation angle in degrees (90 = along +x), ``time`` SUMO's clock (our t + warmup), ``id``
  ``v<slot>``, ``type`` ``hdv``/``cav``. Reading takes the vehicle kind from ``type`` (a type
  id containing "cav" is a CAV), the lane from y (a vehicle exactly on a lane line is in the
  lane it moves into, as in the engine), drops the warm-up rows (t < 0) and derives the
  acceleration from the speeds when the file has none.
* **highD** (Krajewski et al. 2018): ``tracks.csv``, ``tracksMeta.csv``, ``recordingMeta.csv``
  in one directory. ``x, y`` is the upper-left corner of the bounding box in image axes (y
  down: ``y_highD = -y``), ``width`` the vehicle length and ``height`` its width, frames are
  1-based, driving direction 2 (towards +x). ``laneId`` counts from the top: 1 = lane 2,
  2 = lane 1, 3 = ramp / acceleration lane. tracksMeta carries an extra ``vehicleKind``
  column (HDV/CAV), and the directory the resolved config (``scenario.toml``: road geometry).
  ``dhw`` is front-to-front, ``thw = dhw / v``, ``ttc`` = bumper gap / closing speed; 0 where
  undefined, as in highD.
* **CSV**: :meth:`SimulationLog.to_frame`, one row per active (step, vehicle) cell.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd

from hcomc.config import ScenarioConfig, config_to_toml
from hcomc.road import Kind, Lane
from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import atomic_paths, build_manifest
from hcomc.sumo import SumoFormatError
from hcomc.sumo.network import edge_at, sumo_lane_of

__all__ = [
    "FORMATS",
    "read_fcd",
    "read_highd",
    "write_csv",
    "write_fcd",
    "write_highd",
]

FORMATS = ("highd", "fcd", "csv")
HIGHD_FILES = ("tracks.csv", "tracksMeta.csv", "recordingMeta.csv")
_NEIGHBOUR_COLUMNS = (
    "precedingId", "followingId", "leftPrecedingId", "leftAlongsideId", "leftFollowingId",
    "rightPrecedingId", "rightAlongsideId", "rightFollowingId",
)  # fmt: skip


def highd_lane_id(lane: np.ndarray) -> np.ndarray:
    """highD laneId (1 = top = lane 2, 2 = lane 1, 3 = ramp) of our lanes."""
    return (int(Lane.MAIN_2) + 1) - np.asarray(lane, dtype=np.int64)


# --------------------------------------------------------------------------- writing
def write_csv(log: SimulationLog, path: Path) -> Path:
    """Long-format CSV of every active (step, vehicle) cell."""
    with atomic_paths(path) as (tmp,):
        log.to_frame().to_csv(tmp, index=False)
    return path


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


# (preceding, following, alongside) columns and lane offset: own lane, left (+1), right (-1)
_SIDES = (
    ("precedingId", "followingId", None, 0),
    ("leftPrecedingId", "leftFollowingId", "leftAlongsideId", 1),
    ("rightPrecedingId", "rightFollowingId", "rightAlongsideId", -1),
)


def _neighbours(log: SimulationLog, k: int) -> dict[str, np.ndarray]:
    """highD neighbour ids (0 = none) and headways of the active vehicles of row k.

    In the own lane the preceding vehicle is the nearest one ahead; in a neighbouring lane it
    is the nearest one entirely ahead, the following one the nearest entirely behind, and the
    alongside one any vehicle overlapping in x.
    """
    ids = np.flatnonzero(log.active[k])
    x = log.x[k, ids].astype(np.float64)
    v = log.v[k, ids].astype(np.float64)
    lane = log.lane[k, ids].astype(np.int64)
    length = log.length[ids].astype(np.float64)
    rear = x - length
    out = {name: np.zeros(ids.size, dtype=np.int64) for name in _NEIGHBOUR_COLUMNS}
    dhw, thw, ttc = np.zeros(ids.size), np.zeros(ids.size), np.zeros(ids.size)
    for j in range(ids.size):
        for preceding, following, alongside, offset in _SIDES:
            other = np.flatnonzero((lane == lane[j] + offset) & (np.arange(ids.size) != j))
            if offset == 0:
                ahead, behind = other[x[other] > x[j]], other[x[other] <= x[j]]
            else:
                ahead, behind = other[rear[other] > x[j]], other[x[other] < rear[j]]
                along = other[(x[other] >= rear[j]) & (rear[other] <= x[j])]
                if along.size and alongside is not None:
                    out[alongside][j] = ids[along[0]] + 1
            if behind.size:
                out[following][j] = ids[behind[np.argmax(x[behind])]] + 1
            if ahead.size:
                p = ahead[np.argmin(x[ahead])]
                out[preceding][j] = ids[p] + 1
                if offset == 0:
                    dhw[j] = x[p] - x[j]
                    thw[j] = dhw[j] / v[j] if v[j] > 0 else 0.0
                    closing = v[j] - v[p]
                    ttc[j] = (x[p] - length[p] - x[j]) / closing if closing > 0 else 0.0
    return {**out, "dhw": dhw, "thw": thw, "ttc": ttc}


def _tracks(log: SimulationLog, road_length: float) -> pd.DataFrame:
    frames = []
    for k in range(log.n_recorded):
        ids = np.flatnonzero(log.active[k])
        if ids.size == 0:
            continue
        x = log.x[k, ids].astype(np.float64)
        y = log.y[k, ids].astype(np.float64)
        h = log.heading[k, ids].astype(np.float64)
        v = log.v[k, ids].astype(np.float64)
        a = log.a[k, ids].astype(np.float64)
        length = log.length[ids].astype(np.float64)
        width = log.width[ids].astype(np.float64)
        frame = {
            "frame": np.full(ids.size, k + 1),
            "id": ids + 1,
            "x": x - length,
            "y": -y - 0.5 * width,
            "width": length,
            "height": width,
            "xVelocity": v * np.cos(h),
            "yVelocity": -v * np.sin(h),
            "xAcceleration": a * np.cos(h),
            "yAcceleration": -a * np.sin(h),
            "frontSightDistance": road_length - x,
            "backSightDistance": x - length,
        }
        frame.update(_neighbours(log, k))
        frame["precedingXVelocity"] = np.where(
            frame["precedingId"] > 0,
            log.v[k, np.maximum(frame["precedingId"] - 1, 0)].astype(np.float64),
            0.0,
        )
        frame["laneId"] = highd_lane_id(log.lane[k, ids])
        frames.append(pd.DataFrame(frame))
    columns = [
        "frame", "id", "x", "y", "width", "height", "xVelocity", "yVelocity", "xAcceleration",
        "yAcceleration", "frontSightDistance", "backSightDistance", "dhw", "thw", "ttc",
        "precedingXVelocity", *_NEIGHBOUR_COLUMNS, "laneId",
    ]  # fmt: skip
    if not frames:
        return pd.DataFrame(columns=columns)
    return pd.concat(frames, ignore_index=True)[columns]


def _tracks_meta(log: SimulationLog, tracks: pd.DataFrame) -> pd.DataFrame:
    rows = []
    for vid, track in tracks.groupby("id", sort=True):
        i = int(vid) - 1
        lanes = track["laneId"].to_numpy()
        positive = track["dhw"].to_numpy() > 0
        rows.append(
            {
                "id": int(vid),
                "width": float(log.length[i]),
                "height": float(log.width[i]),
                "initialFrame": int(track["frame"].min()),
                "finalFrame": int(track["frame"].max()),
                "numFrames": len(track),
                "class": "Car",
                "drivingDirection": 2,
                "traveledDistance": float(track["x"].iloc[-1] - track["x"].iloc[0]),
                "minXVelocity": float(track["xVelocity"].min()),
                "maxXVelocity": float(track["xVelocity"].max()),
                "meanXVelocity": float(track["xVelocity"].mean()),
                "minDHW": float(track["dhw"][positive].min()) if positive.any() else -1.0,
                "minTHW": float(track["thw"][positive].min()) if positive.any() else -1.0,
                "minTTC": float(track["ttc"][track["ttc"] > 0].min())
                if (track["ttc"] > 0).any()
                else -1.0,
                "numLaneChanges": int(np.count_nonzero(np.diff(lanes))),
                "vehicleKind": "CAV" if log.kind[i] == Kind.CAV else "HDV",
            }
        )
    return pd.DataFrame(rows)


def write_highd(log: SimulationLog, out_dir: Path, config: ScenarioConfig) -> Path:
    """highD-style ``tracks.csv``, ``tracksMeta.csv``, ``recordingMeta.csv`` in ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    tracks = _tracks(log, config.road.length)
    meta = _tracks_meta(log, tracks)
    recording = pd.DataFrame(
        [
            {
                "id": 1,
                "frameRate": round(1.0 / log.dt, 9),
                "startTime": float(log.t[0]) if log.n_recorded else 0.0,
                "duration": float(log.n_recorded * log.dt),
                "numVehicles": len(meta),
                "numCars": len(meta),
                "numTrucks": 0,
                "upperLaneMarkings": "",
                "lowerLaneMarkings": ";".join(
                    f"{-(lane - 0.5) * config.road.lane_width:.3f}" for lane in (2, 1, 0, -1)
                ),
                "scenario": config.name,
            }
        ]
    )
    paths = [out_dir / name for name in (*HIGHD_FILES, "scenario.toml")]
    with atomic_paths(*paths) as tmp:
        for frame, target in zip((tracks, meta, recording), tmp, strict=False):
            frame.to_csv(target, index=False)
        tmp[-1].write_text(config_to_toml(config), encoding="utf-8")  # the road's geometry
    return out_dir


# --------------------------------------------------------------------------- reading
def _new_log(
    config: ScenarioConfig, t: np.ndarray, kind: np.ndarray, dt: float, source: Path, fmt: str
) -> SimulationLog:
    n = kind.size
    meta = build_manifest(
        seed=config.seed,
        config=config.model_dump(mode="json"),
        extra={"source": {"file": str(source), "format": fmt}},
    )
    log = SimulationLog.allocate(
        t.size,
        n,
        dt=dt,
        kind=kind,
        length=np.full(n, config.road.vehicle_length),
        width=np.full(n, config.road.vehicle_width),
        meta=meta,
    )
    log.t[:] = t
    return log


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


def _fill(
    log: SimulationLog,
    row: np.ndarray,
    col: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    v: np.ndarray,
    heading: np.ndarray,
    a: np.ndarray,
    lane: np.ndarray,
    path: Path,
    config: ScenarioConfig,
) -> None:
    """Write cells into the log; check the lanes; derive missing accelerations."""
    bad = (lane < Lane.RAMP) | (lane > Lane.MAIN_2)
    if bad.any():
        k = int(np.argmax(bad))
        raise SumoFormatError(
            f"{path}: vehicle slot {int(col[k])} at x = {x[k]:.2f} m, y = {y[k]:.2f} m is off "
            f"the road (lane {int(lane[k])}); expected the lanes of our road: centres at y = "
            f"{-config.road.lane_width:.2f} (ramp), 0 (lane 1), {config.road.lane_width:.2f} "
            "(lane 2), each one lane width wide"
        )
    log.active[row, col] = True
    log.x[row, col], log.y[row, col], log.v[row, col] = x, y, v
    log.heading[row, col] = heading
    log.lane[row, col] = lane
    log.a[row, col] = a
    missing = log.active & np.isnan(log.a)
    if missing.any():  # central differences of the speed where the file has no acceleration
        grad = np.gradient(log.v.astype(np.float64), log.dt, axis=0) if log.n_steps > 1 else 0.0
        log.a[missing] = np.nan_to_num(np.asarray(grad)[missing] if log.n_steps > 1 else 0.0)
    log._n_recorded = log.n_steps


def read_highd(source: Path, config: ScenarioConfig) -> tuple[SimulationLog, dict[str, int]]:
    """A log from a highD-style directory (or its ``tracks.csv``) on our road."""
    directory = source if source.is_dir() else source.parent
    tracks_path = directory / "tracks.csv" if source.is_dir() else source
    if not tracks_path.is_file():
        raise SumoFormatError(f"{source}: no tracks.csv; expected a highD-style directory")
    tracks = pd.read_csv(tracks_path)
    need = ("frame", "id", "x", "y", "width", "height", "xVelocity", "yVelocity",
            "xAcceleration", "yAcceleration", "laneId")  # fmt: skip
    missing = [c for c in need if c not in tracks.columns]
    if missing:
        raise SumoFormatError(
            f"{tracks_path}: missing column(s) {', '.join(missing)}; expected highD tracks "
            f"columns {', '.join(need)}"
        )
    rate, start, duration = 25.0, 0.0, 0.0  # highD's frame rate unless recordingMeta says
    recording = directory / "recordingMeta.csv"
    if recording.is_file():
        meta_row = pd.read_csv(recording).iloc[0]
        rate = float(meta_row.get("frameRate", rate))
        duration = float(meta_row.get("duration", 0.0))
        start = pd.to_numeric(meta_row.get("startTime"), errors="coerce")  # highD: clock time
        start = float(start) if np.isfinite(start) else 0.0
    kind_of: dict[int, int] = {}
    meta_path = directory / "tracksMeta.csv"
    if meta_path.is_file():
        meta = pd.read_csv(meta_path)
        if "vehicleKind" in meta.columns:
            kind_of = {
                int(i): int(Kind.CAV if k == "CAV" else Kind.HDV)
                for i, k in zip(meta["id"], meta["vehicleKind"], strict=True)
            }
    frames = tracks["frame"].to_numpy(dtype=np.int64)
    first = int(frames.min())
    last = max(int(frames.max()), round(duration * rate))  # trailing empty frames too
    dt = 1.0 / rate
    t = start + (np.arange(first, last + 1) - 1) * dt
    ids = sorted(int(i) for i in tracks["id"].unique())
    if ids[0] < 1:
        raise SumoFormatError(f"{tracks_path}: column 'id' = {ids[0]}; highD ids start at 1")
    slots = {str(i): i - 1 for i in ids}
    n = ids[-1]
    kind = np.array([kind_of.get(i + 1, int(Kind.HDV)) for i in range(n)], dtype=np.int64)
    log = _new_log(config, t, kind, dt, tracks_path, "highd")
    length, width = tracks["width"].to_numpy(), tracks["height"].to_numpy()
    col = tracks["id"].to_numpy(dtype=np.int64) - 1
    log.length[col], log.width[col] = length, width
    vx, vy = tracks["xVelocity"].to_numpy(), tracks["yVelocity"].to_numpy()
    ax, ay = tracks["xAcceleration"].to_numpy(), tracks["yAcceleration"].to_numpy()
    heading = np.arctan2(-vy, vx)
    lane = (int(Lane.MAIN_2) + 1) - tracks["laneId"].to_numpy(dtype=np.int64)
    _fill(
        log, frames - first, col, tracks["x"].to_numpy() + length,
        -(tracks["y"].to_numpy() + 0.5 * width),
        vx * np.cos(heading) - vy * np.sin(heading), heading,
        ax * np.cos(heading) - ay * np.sin(heading), lane, tracks_path, config,
    )  # fmt: skip
    return log, slots
