"""Tracks of a corridor run (``hcomc simulate CORRIDOR --trajectory-interval S --out``).

A corridor run writes sampled trajectories (``trajectories.csv``: time, vehicle, front
position ``x`` along the mainline, lane, lane code, speed, acceleration), the vehicles' classes
(``trips.csv``) and the corridor (``manifest.json``), read by
:mod:`hcomc.metrics.corridor.record`. It has no lateral motion: a vehicle drives on its lane's
centre line and switches lane half-way through a lane change. So its tracks here are drawn on
the centre lines of :func:`hcomc.commonroad.lanes.corridor_strips`, placed by
:func:`hcomc.corridor.layout.code_poses` with the lanes' headings (0 on the mainline, the
ramp's slope on a ramp road), and a lane change shows as a lateral jump of one lane width
between two samples; the speed is the engine's, along the lane. Time step k is sample k
(``t = k S``); the body comes from the vehicle class (length, width, CommonRoad obstacle
type).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pandas as pd

from hcomc.commonroad.tracks import Track, body_centre
from hcomc.corridor import Corridor, VehicleClass
from hcomc.corridor.layout import code_poses
from hcomc.metrics.corridor.record import read_corridor_run

__all__ = ["CorridorTracks", "corridor_tracks"]

_VEHICLE_TYPES = {"truck": "truck", "trailer": "truck", "delivery": "truck", "bus": "bus",
                  "coach": "bus", "motorcycle": "motorcycle"}  # fmt: skip
"""SUMO vehicle class -> CommonRoad obstacle type ("car" for any other)."""


@dataclass(frozen=True, slots=True)
class CorridorTracks:
    """What a corridor-run directory holds for the export: the corridor, the sampling
    interval [s], the tracks, the trips (one row per vehicle, index: id) and the manifest."""

    corridor: Corridor
    dt: float
    tracks: tuple[Track, ...]
    trips: pd.DataFrame
    manifest: dict[str, Any]


def corridor_tracks(run_dir: Path) -> CorridorTracks:
    """The tracks of a corridor run (read by
    :func:`hcomc.metrics.corridor.record.read_corridor_run`); ``ValueError`` naming what is
    missing."""
    record = read_corridor_run(run_dir)
    samples = record.require_trajectories()
    corridor = record.corridor
    px, py, heading = code_poses(corridor.road, samples.x, samples.code)
    classes = record.vehicle_classes()
    tracks = []
    for vid, start, stop in zip(samples.ids.tolist(), samples.start.tolist(),
                                samples.stop.tolist(), strict=True):  # fmt: skip
        if stop - start < 2:
            continue
        vclass: VehicleClass = classes[vid]
        rows = slice(start, stop)
        v, a = samples.v[rows], samples.a[rows]
        # the engine's speed is along its lane (the ramp road's too): it is the speed along
        # the heading already, so body_centre's division by cos h is undone
        states = replace(body_centre(px[rows], py[rows], heading[rows], v, a, vclass.length),
                         velocity=v, acceleration=a)  # fmt: skip
        tracks.append(Track(
            vehicle=vid, cav=bool(record.trips.loc[vid, "cav"]), length=vclass.length,
            width=vclass.width, vehicle_class=_VEHICLE_TYPES.get(vclass.vclass, "car"),
            first_step=int(samples.step[start]), states=states,
        ))  # fmt: skip
    return CorridorTracks(corridor, samples.interval, tuple(tracks), record.trips,
                          record.manifest)  # fmt: skip
