"""What a CommonRoad export is made of: :class:`ExportRun`, read from a run's directory.

Two kinds of runs are read (:func:`load_run`):

* hcomc's **scenario engine** (``hcomc simulate C1..C5|TOML|paper... --out DIR``, or its log
  file): the log (:class:`~hcomc.sim.log.SimulationLog`) with every logged row, on the paper's
  road of the config stored in the log; VR is the first vehicle logged on the ramp lane (the
  paper's single merging vehicle; in a run with a ramp flow, the first of them);
* a **corridor run** (``hcomc simulate CORRIDOR --trajectory-interval S --out DIR``):
  its sampled trajectories (:mod:`hcomc.commonroad.corridor_run`) on the corridor's road; VR
  is the first vehicle released from the most upstream on-ramp that is sampled twice or
  more, its merge target the rightmost mainline lane beside that ramp's acceleration lane.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import hcomc
from hcomc.commonroad.corridor_run import CorridorTracks, corridor_tracks
from hcomc.commonroad.lanes import Strip, StripKind, corridor_strips, paper_road_strips
from hcomc.commonroad.tracks import Track, first_ramp_vehicle, log_tracks
from hcomc.config import ConfigError, ScenarioConfig, validate_config
from hcomc.metrics.corridor.record import is_corridor_run
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog, log_file_of
from hcomc.sim.manifest import git_revision

__all__ = ["ExportRun", "load_run", "run_of_corridor", "run_of_log"]
"""What a scenario-engine run directory holds its log in (the first found)."""


@dataclass(frozen=True, slots=True)
class ExportRun:
    """A run ready for export: its road as strips, its tracks, its merging vehicle VR.

    ``dt`` is the time between two CommonRoad time steps [s]; ``vr`` the hcomc id of VR
    (None, with the reason in ``no_vr``, where the run has none), ``vr_ramp`` the id of its
    on-ramp on a corridor (None on the paper's road); ``provenance`` names the hcomc version
    and git revision that made the run."""

    name: str
    seed: int
    dt: float
    strips: tuple[Strip, ...]
    tracks: tuple[Track, ...]
    vr: int | None
    vr_ramp: str | None
    no_vr: str
    provenance: str
    corridor: bool

    def track_of(self, vehicle: int) -> Track | None:
        """The track of hcomc vehicle ``vehicle``, None if it has none."""
        return next((t for t in self.tracks if t.vehicle == vehicle), None)

    def goal_lanelets(self) -> tuple[int, ...]:
        """Strips VR merges into: the lane left of its acceleration lane (lane 1 of the
        paper's road; the rightmost mainline lane of a corridor), along that lane."""
        inner = (int(Lane.RAMP), -1)  # the ramp lane next to the mainline
        return tuple(
            s.left_neighbour
            for s in self.strips
            if s.kind == StripKind.ACCEL and s.ramp == self.vr_ramp and s.lane in inner
            and s.left_neighbour
        )  # fmt: skip


def load_run(source: Path) -> ExportRun:
    """The run of a ``hcomc simulate --out`` directory or log file (module docstring);
    ``ValueError`` with a one-line reason when it is neither."""
    if is_corridor_run(source):
        return run_of_corridor(corridor_tracks(source))
    log = SimulationLog.load(log_file_of(source))
    try:
        config = validate_config(log.meta["config"], f"{source} (config in the log)")
    except KeyError:
        raise ValueError(f"{source}: the log has no config in its metadata") from None
    except ConfigError as exc:
        raise ValueError(str(exc)) from None
    return run_of_log(log, config)


def run_of_log(log: SimulationLog, config: ScenarioConfig) -> ExportRun:
    """A scenario-engine log on the paper's road of ``config``."""
    tracks = log_tracks(log)
    vr = first_ramp_vehicle(log)
    no_vr = ""
    if vr is None:
        no_vr = "no vehicle is logged on the ramp lane (a run without its merging vehicle)"
    elif not any(t.vehicle == vr for t in tracks):
        no_vr, vr = f"the ramp vehicle {vr} is logged at one row only (no trajectory)", None
    return ExportRun(
        name=config.name, seed=int(log.meta.get("seed", config.seed)), dt=float(log.dt),
        strips=paper_road_strips(config), tracks=tracks, vr=vr, vr_ramp=None, no_vr=no_vr,
        provenance=_provenance(log.meta), corridor=False,
    )  # fmt: skip


def run_of_corridor(run: CorridorTracks) -> ExportRun:
    """A corridor run on its corridor's road."""
    trips = run.trips
    sampled = {t.vehicle for t in run.tracks}
    ramps = run.corridor.road.on_ramps
    vr, ramp_id, no_vr = None, None, "the corridor has no on-ramp"
    if ramps:
        ramp_id = ramps[0].id
        entered = trips[(trips["origin"] == ramp_id) & trips.index.isin(sampled)]
        entered = entered.sort_values(["insert"], kind="stable")
        if entered.empty:
            no_vr = f"no vehicle from on-ramp '{ramp_id}' is sampled twice or more"
        else:
            vr, no_vr = int(entered.index[0]), ""
    return ExportRun(
        name=run.corridor.name, seed=int(run.manifest.get("seed", run.corridor.corridor.seed)),
        dt=run.dt, strips=corridor_strips(run.corridor), tracks=run.tracks, vr=vr,
        vr_ramp=ramp_id, no_vr=no_vr, provenance=_provenance(run.manifest), corridor=True,
    )  # fmt: skip


def _provenance(meta: dict[str, Any]) -> str:
    """``hcomc <version> <git revision>`` of the run (of this hcomc where it is not stored)."""
    version = meta.get("hcomc_version") or hcomc.__version__
    revision = meta.get("git_revision") or git_revision()
    return f"hcomc {version} {revision}"
