"""highD-style CSV (Krajewski et al. 2018) to and from a :class:`SimulationLog`.

``tracks.csv``, ``tracksMeta.csv``, ``recordingMeta.csv`` in one directory. ``x, y`` is the
upper-left corner of the bounding box in image axes (y down: ``y_highD = -y``), ``width`` the
vehicle length and ``height`` its width, frames are 1-based, driving direction 2 (towards +x).
``laneId`` counts from the top: 1 = lane 2, 2 = lane 1, 3 = ramp / acceleration lane.
tracksMeta carries an extra ``vehicleKind`` column (HDV/CAV), and the directory the resolved
config (``scenario.toml``: road geometry). ``dhw`` is front-to-front, ``thw = dhw / v``,
``ttc`` = bumper gap / closing speed; 0 where undefined, as in highD. Coordinates are our
road's (:mod:`hcomc.sumo.trajectories`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from hcomc.config import ScenarioConfig, config_to_toml
from hcomc.road import Kind, Lane
from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import atomic_paths
from hcomc.sumo import SumoFormatError
from hcomc.sumo.trajectories import _fill, _new_log

__all__ = ["read_highd", "write_highd"]

HIGHD_FILES = ("tracks.csv", "tracksMeta.csv", "recordingMeta.csv")
_NEIGHBOUR_COLUMNS = (
    "precedingId", "followingId", "leftPrecedingId", "leftAlongsideId", "leftFollowingId",
    "rightPrecedingId", "rightAlongsideId", "rightFollowingId",
)  # fmt: skip


def highd_lane_id(lane: np.ndarray) -> np.ndarray:
    """highD laneId (1 = top = lane 2, 2 = lane 1, 3 = ramp) of our lanes."""
    return (int(Lane.MAIN_2) + 1) - np.asarray(lane, dtype=np.int64)


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
