"""What a corridor run leaves to look at afterwards: :class:`CorridorRecord`, read back.

``hcomc simulate CORRIDOR --out DIR`` writes the corridor (``manifest.json``'s ``config``),
one row per vehicle (``trips.csv``), per merge event (``merges.csv``), per collision
(``collisions.csv``) and, with ``--trajectory-interval S``, every vehicle's state every S
seconds (``trajectories.csv``). :func:`read_corridor_run` reads such a directory and
:func:`record_of` takes the same from a :class:`~hcomc.metrics.corridor.CorridorRun` in memory;
the views of a run (the CommonRoad export, the browser replay) read the record, so that a
run directory is read in one place and every view sees the same vehicles.

:class:`Trajectories` holds the samples as arrays sorted by vehicle, then time, with each
vehicle's span. Sample step k is time ``k S``; the engine samples every vehicle on the road,
so a vehicle's samples are one per step from its first to its last, which reading checks.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from pydantic import ValidationError

from hcomc.corridor import Corridor
from hcomc.metrics.corridor.events import EVENT_COLUMNS
from hcomc.metrics.corridor.measure import COLLISION_COLUMNS, TRAJECTORY_COLUMNS

if TYPE_CHECKING:
    from hcomc.metrics.corridor.run import CorridorRun

__all__ = [
    "CORRIDOR_ENGINE",
    "CorridorRecord",
    "Trajectories",
    "is_corridor_run",
    "read_corridor_run",
    "record_of",
    "trajectories_of",
]

CORRIDOR_ENGINE = "hcomc-corridor"
"""The ``engine`` a corridor run's manifest names."""

NO_TRAJECTORIES = (
    "no trajectories.csv (a corridor run writes them only when asked); "
    "allowed: a run of 'hcomc simulate CORRIDOR --trajectory-interval S --out DIR' with S > 0 "
    "(e.g. 0.5 s): rerun it with --trajectory-interval"
)
"""Why a view that draws vehicles cannot use a corridor run without samples, and the fix."""


@dataclass(frozen=True, slots=True)
class Trajectories:
    """Samples sorted by vehicle, then time (module docstring).

    Per sample (n,): ``vehicle``, ``step`` (its time is ``step * interval``), ``t`` [s] as
    recorded, ``x`` [m] along the mainline (continued along ramp roads), ``lane`` (k >= 0
    mainline lane k from the right, ``-1 - j`` ramp lane j), ``code`` (the engine's lane
    code, :mod:`hcomc.corridor.layout`), ``v`` [m/s] and ``a`` [m/s^2] along the lane. Per
    sampled vehicle (m,): ``ids`` in increasing order and the ``start`` and ``stop`` (one
    past the last) of its samples."""

    interval: float
    vehicle: np.ndarray
    step: np.ndarray
    t: np.ndarray
    x: np.ndarray
    lane: np.ndarray
    code: np.ndarray
    v: np.ndarray
    a: np.ndarray
    ids: np.ndarray
    start: np.ndarray
    stop: np.ndarray


@dataclass(frozen=True)
class CorridorRecord:
    """A corridor run as its views read it (module docstring): the corridor, its seed and
    controller, the trips (index: vehicle id), merge events and collisions as written, the
    trajectories (None when not sampled), the manifest (empty in memory) and where it was
    read from (``""`` in memory)."""

    corridor: Corridor
    seed: int
    controller: str
    trips: pd.DataFrame
    merges: pd.DataFrame
    collisions: pd.DataFrame
    trajectories: Trajectories | None
    manifest: dict[str, Any]
    source: str = ""

    def vehicle_classes(self) -> pd.Series:
        """Each vehicle's class (:class:`~hcomc.corridor.VehicleClass`), by vehicle id;
        ValueError naming a class the corridor does not define."""
        names = self.trips["vclass"].astype(str)
        unknown = sorted(set(names) - set(self.corridor.vehicles))
        if unknown:
            raise ValueError(f"corridor run '{self.source}': vehicles of class '{unknown[0]}', "
                             "which its corridor does not define")  # fmt: skip
        return names.map(self.corridor.vehicles)

    def require_trajectories(self) -> Trajectories:
        """The trajectories; ValueError (one line, with the fix) when the run has none."""
        if self.trajectories is None:
            where = f"corridor run '{self.source}'" if self.source else "the corridor run"
            raise ValueError(f"{where} has {NO_TRAJECTORIES}")
        return self.trajectories


def is_corridor_run(run_dir: str | Path) -> bool:
    """Whether ``run_dir`` is the ``--out`` directory of a corridor run (its manifest
    names :data:`CORRIDOR_ENGINE`)."""
    manifest = Path(run_dir) / "manifest.json"
    if not (Path(run_dir).is_dir() and manifest.is_file()):
        return False
    try:
        return json.loads(manifest.read_text(encoding="utf-8")).get("engine") == CORRIDOR_ENGINE
    except (json.JSONDecodeError, UnicodeDecodeError, AttributeError):
        return False


def read_corridor_run(run_dir: str | Path) -> CorridorRecord:
    """The record of a corridor-run ``--out`` directory; ValueError naming what is
    missing or malformed. Trajectories may be absent
    (:meth:`CorridorRecord.require_trajectories` says how to get them)."""
    run_dir = Path(run_dir)
    if not is_corridor_run(run_dir):
        raise ValueError(f"'{run_dir}' is not a corridor run (no manifest.json naming engine "
                         f"'{CORRIDOR_ENGINE}')")  # fmt: skip
    manifest = json.loads((run_dir / "manifest.json").read_text(encoding="utf-8"))
    try:
        corridor = Corridor.model_validate(manifest["config"])
    except (KeyError, ValidationError) as exc:
        raise ValueError(f"{run_dir}/manifest.json: no valid corridor in 'config' "
                         f"({str(exc).splitlines()[0]})") from None  # fmt: skip
    trips = _table(run_dir / "trips.csv", None)
    merges = _table(run_dir / "merges.csv", EVENT_COLUMNS)
    collisions = _table(run_dir / "collisions.csv", COLLISION_COLUMNS)
    samples_file = run_dir / "trajectories.csv"
    samples = pd.read_csv(samples_file) if samples_file.is_file() else None
    return CorridorRecord(
        corridor=corridor, seed=int(manifest.get("seed", corridor.corridor.seed)),
        controller=str(manifest.get("controller") or corridor.control.controller),
        trips=trips.set_index("id"), merges=merges, collisions=collisions,
        trajectories=None if samples is None else trajectories_of(samples, str(samples_file)),
        manifest=manifest, source=str(run_dir),
    )  # fmt: skip


def record_of(run: CorridorRun) -> CorridorRecord:
    """The record of a run in memory (:func:`hcomc.metrics.corridor.simulate_corridor`)."""
    samples = run.trajectories
    return CorridorRecord(
        corridor=run.corridor, seed=run.seed, controller=run.controller,
        trips=run.trips.set_index("id"), merges=run.merges, collisions=run.collisions,
        trajectories=None if samples is None else trajectories_of(samples, "trajectories"),
        manifest={},
    )  # fmt: skip


def _table(path: Path, columns: tuple[str, ...] | None) -> pd.DataFrame:
    """``path`` as a table; an empty one with ``columns`` when it is absent (required when
    ``columns`` is None)."""
    if path.is_file():
        return pd.read_csv(path, dtype={"origin": str, "ramp": str})
    if columns is None:
        raise ValueError(f"corridor run '{path.parent}' has no {path.name}")
    return pd.DataFrame(columns=list(columns))


def trajectories_of(samples: pd.DataFrame, where: str) -> Trajectories:
    """The trajectories of a samples table (columns of ``trajectories.csv``); ValueError if
    a column is missing, there are no samples or samples at one time only, or a vehicle's
    samples are not one per interval (module docstring)."""
    missing = [c for c in TRAJECTORY_COLUMNS if c not in samples.columns]
    if missing:
        raise ValueError(f"{where}: no column(s) {', '.join(missing)}; allowed: the "
                         "trajectories.csv of 'hcomc simulate CORRIDOR --out'")  # fmt: skip
    if samples.empty:
        raise ValueError(f"{where}: no samples (no vehicle on the road when sampled)")
    samples = samples.sort_values(["id", "t"], kind="stable")
    t = samples["t"].to_numpy(dtype=np.float64)
    distinct = np.unique(t)
    if distinct.size < 2:
        raise ValueError(f"{where}: samples at one time only; a trajectory needs two")
    interval = float(np.min(np.diff(distinct)))
    vehicle = samples["id"].to_numpy(dtype=np.int64)
    step = np.rint(t / interval).astype(np.int64)
    ids, start = np.unique(vehicle, return_index=True)
    stop = np.append(start[1:], vehicle.size)
    same = vehicle[1:] == vehicle[:-1]
    gaps = np.flatnonzero(same & (np.diff(step) != 1))
    if gaps.size:
        raise ValueError(f"{where}: vehicle {int(vehicle[gaps[0]])}: its samples are not one "
                         f"per interval of {interval:g} s")  # fmt: skip

    def column(name: str, dtype: type) -> np.ndarray:
        return samples[name].to_numpy(dtype=dtype)

    return Trajectories(
        interval=interval, vehicle=vehicle, step=step, t=t, x=column("x", np.float64),
        lane=column("lane", np.int64), code=column("code", np.int64), v=column("v", np.float64),
        a=column("a", np.float64), ids=ids, start=start, stop=stop,
    )  # fmt: skip
