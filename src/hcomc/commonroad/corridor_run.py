"""Tracks of a corridor-engine run (``hcomc simulate CORRIDOR --trajectory-interval S --out``).

The corridor engine writes sampled trajectories (``trajectories.csv``: time, vehicle, front
position ``x`` along the mainline, lane, lane code, speed, acceleration), the vehicles' classes
(``trips.csv``) and the corridor (``manifest.json``). It has no lateral motion: a vehicle
drives on its lane's centre line and switches lane half-way through a lane change. So its
tracks here are drawn on the centre lines of :func:`hcomc.commonroad.lanes.corridor_strips`
with the lanes' headings (0 on the mainline, the ramp's slope on a ramp road), and a lane
change shows as a lateral jump of one lane width between two samples; the speed is the
engine's, along the lane. Time step k is sample k (``t = k S``); the body comes from the
vehicle class (length, width, CommonRoad obstacle type).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from pydantic import ValidationError

from hcomc.commonroad.lanes import ramp_road_pose
from hcomc.commonroad.tracks import Track, body_centre
from hcomc.corridor import Corridor, OnRamp, VehicleClass
from hcomc.sim.corridor.layout import KIND_MAIN, KIND_OFF, KIND_ON
from hcomc.sim.corridor.setup import build_layout

__all__ = ["CORRIDOR_ENGINE", "CorridorTracks", "corridor_tracks", "is_corridor_run"]

CORRIDOR_ENGINE = "hcomc-corridor"
"""The ``engine`` a corridor-engine run's manifest names."""

_VEHICLE_TYPES = {"truck": "truck", "trailer": "truck", "delivery": "truck", "bus": "bus",
                  "coach": "bus", "motorcycle": "motorcycle"}  # fmt: skip
"""SUMO vehicle class -> CommonRoad obstacle type ("car" for any other)."""


@dataclass(frozen=True, slots=True)
class CorridorTracks:
    """What a corridor-engine directory holds for the export: the corridor, the sampling
    interval [s], the tracks, the trips (one row per vehicle, index: id) and the manifest."""

    corridor: Corridor
    dt: float
    tracks: tuple[Track, ...]
    trips: pd.DataFrame
    manifest: dict[str, Any]


def is_corridor_run(run_dir: Path) -> bool:
    """Whether ``run_dir`` is the ``--out`` directory of a corridor-engine run."""
    manifest = run_dir / "manifest.json"
    if not (run_dir.is_dir() and manifest.is_file()):
        return False
    try:
        return json.loads(manifest.read_text(encoding="utf-8")).get("engine") == CORRIDOR_ENGINE
    except (json.JSONDecodeError, AttributeError):
        return False


def corridor_tracks(run_dir: Path) -> CorridorTracks:
    """The tracks of a corridor-engine run; ``ValueError`` naming what is missing."""
    manifest = json.loads((run_dir / "manifest.json").read_text(encoding="utf-8"))
    try:
        corridor = Corridor.model_validate(manifest["config"])
    except (KeyError, ValidationError) as exc:
        raise ValueError(f"{run_dir}/manifest.json: no valid corridor in 'config' "
                         f"({str(exc).splitlines()[0]})") from None  # fmt: skip
    samples_file = run_dir / "trajectories.csv"
    if not samples_file.is_file():
        raise ValueError(
            f"{run_dir}: no trajectories.csv (the corridor engine samples trajectories only "
            "when asked); allowed: a run of `hcomc simulate CORRIDOR --trajectory-interval S "
            "--out DIR` with S > 0 (the step length for every step)"
        )
    samples = pd.read_csv(samples_file)
    trips = pd.read_csv(run_dir / "trips.csv").set_index("id")
    if samples.empty:
        raise ValueError(f"{samples_file}: no samples (no vehicle on the road when sampled)")
    dt = _interval(samples["t"].to_numpy())
    px, py, heading = _poses(corridor, samples["x"].to_numpy(), samples["code"].to_numpy())
    samples = samples.assign(px=px, py=py, heading=heading)
    tracks = tuple(
        _track(corridor, int(vid), rows, trips.loc[int(vid)], dt)
        for vid, rows in samples.groupby("id", sort=True)
        if len(rows) >= 2
    )
    return CorridorTracks(corridor, dt, tracks, trips, manifest)


def _interval(times: np.ndarray) -> float:
    """The sampling interval [s]: the step between distinct sample times."""
    distinct = np.unique(times)
    if distinct.size < 2:
        raise ValueError("trajectories.csv: samples at one time only; a trajectory needs two")
    return float(np.min(np.diff(distinct)))


def _track(corridor: Corridor, vid: int, rows: pd.DataFrame, trip: pd.Series,
           dt: float) -> Track:  # fmt: skip
    """One vehicle's samples as a track (module docstring)."""
    steps = np.rint(rows["t"].to_numpy() / dt).astype(np.int64)
    if np.any(np.diff(steps) != 1):
        raise ValueError(f"vehicle {vid}: its samples are not one per interval of {dt:g} s")
    vclass: VehicleClass = corridor.vehicles[str(trip["vclass"])]
    x, y, heading = (rows[name].to_numpy(dtype=np.float64) for name in ("px", "py", "heading"))
    v, a = rows["v"].to_numpy(dtype=np.float64), rows["a"].to_numpy(dtype=np.float64)
    # the engine's speed is along its lane (the ramp road's too): it is the speed along the
    # heading already, so body_centre's division by cos h is undone
    states = replace(body_centre(x, y, heading, v, a, vclass.length), velocity=v, acceleration=a)
    return Track(
        vehicle=vid, cav=bool(trip["cav"]), length=vclass.length, width=vclass.width,
        vehicle_class=_VEHICLE_TYPES.get(vclass.vclass, "car"), first_step=int(steps[0]),
        states=states,
    )  # fmt: skip


def _poses(corridor: Corridor, x: np.ndarray, code: np.ndarray) -> tuple[np.ndarray, ...]:
    """Front bumper centre [m] and heading [rad] of samples at mainline position ``x`` [m]
    in lane ``code`` (:mod:`hcomc.sim.corridor.layout`): the lane's centre line, on a ramp
    road ``|x - junction|`` along it (the corridor engine continues x along ramp roads)."""
    layout = build_layout(corridor)
    width = corridor.road.lane_width
    n_main = layout.n_main
    ramps = corridor.road.ramps
    px, py, heading = x.astype(np.float64).copy(), np.zeros(x.size), np.zeros(x.size)
    main = layout.code_kind[code] == KIND_MAIN
    py[main] = (code[main] + 0.5) * width
    for index in np.unique(code[~main]).tolist():
        ramp = ramps[(index - n_main) // 2]
        j = (index - n_main) % 2
        on = code == index
        py[on] = -(j + 0.5) * width
        kind = layout.code_kind[index]
        junction = ramp.x if kind == KIND_ON else ramp.end
        away = x[on] < junction if isinstance(ramp, OnRamp) else x[on] > junction
        if kind not in (KIND_ON, KIND_OFF) or not away.any():
            continue
        where = np.flatnonzero(on)[away]
        dx, dy, h = ramp_road_pose(ramp, np.abs(x[where] - junction))
        px[where], py[where], heading[where] = junction + dx, py[where] + dy, h
    return px, py, heading
