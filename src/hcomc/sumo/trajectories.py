"""Trajectory exchange: a :class:`SimulationLog` to and from SUMO FCD XML, highD-style CSV, CSV.

Coordinates are those of our road (x along the road from the mainline start, y to the left,
lane centres at ``(lane - 1) W``), which is also the Cartesian frame of the exported SUMO
network (:mod:`hcomc.sumo.network`): an FCD file that SUMO writes for an exported scenario
reads back directly.

* **FCD** (SUMO's ``--fcd-output``): :mod:`hcomc.sumo.fcd`.
* **highD** (Krajewski et al. 2018): :mod:`hcomc.sumo.highd`.
* **CSV**: :meth:`SimulationLog.to_frame`, one row per active (step, vehicle) cell
  (:func:`write_csv`).

This module holds what the formats share: their names, and the log a reader allocates
(:func:`_new_log`) and fills with the samples of a file, checking their lanes
(:func:`_fill`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import atomic_paths, build_manifest
from hcomc.sumo import SumoFormatError

__all__ = ["FORMATS", "write_csv"]

FORMATS = ("highd", "fcd", "csv")


def write_csv(log: SimulationLog, path: Path) -> Path:
    """Long-format CSV of every active (step, vehicle) cell."""
    with atomic_paths(path) as (tmp,):
        log.to_frame().to_csv(tmp, index=False)
    return path


def _new_log(
    config: ScenarioConfig, t: np.ndarray, kind: np.ndarray, dt: float, source: Path, fmt: str
) -> SimulationLog:
    """An empty log of ``kind.size`` vehicles at the times ``t`` on the road of ``config``,
    its manifest naming the file and format it is read from."""
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
