"""The robustness campaign: conditions x faults x channels x configurations x shield x seeds.

Every run is :func:`run_faulted`: a pure function of its :class:`FaultRun` that returns one
row. Seeds are shared across every other axis (the same traffic and the same fault timing),
so each cell is paired with the nominal run of the same seeds (fault ``none``, ideal channel,
no shield). A campaign directory holds ``campaign.json`` (the spec, package version and git
revision: a rerun with another spec or version is refused, so results never mix), one
``parts/<cell>.csv`` per finished cell (written atomically; a killed campaign rerun with the
same spec and code skips them) and, when all cells are done, ``runs.csv`` and ``summary.csv``
(:func:`hcomc.robustness.tables.summarise`).
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Callable, Sequence
from concurrent.futures import as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

import hcomc
from hcomc.config import ConfigError, load_config
from hcomc.config.impairment_tables import (
    CHANNELS,
    FAULTS,
    ChannelParams,
    FaultParams,
    ShieldParams,
)
from hcomc.experiments.pool import local_pool
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.manifest import atomic_paths, git_revision, write_json_atomic

__all__ = ["LARGE_CAMPAIGN", "CampaignSpec", "FaultRun", "run_campaign", "run_faulted"]

if TYPE_CHECKING:
    from hcomc.robustness.impairments import Impairments
    from hcomc.sumo.cosim import SumoSimulation


@dataclass(frozen=True)
class FaultRun:
    """One run: condition, configuration (a label of :mod:`hcomc.experiments.runner`), the
    fault and channel (names and settings), shield on or off, the seed, and the engine that
    moves the vehicles (``hcomc``, or ``sumo`` for the co-simulation)."""

    condition: str
    configuration: str
    fault: str
    channel: str
    shield: bool
    seed: int
    fault_params: FaultParams = FAULTS["none"]
    channel_params: ChannelParams = CHANNELS["ideal"]
    shield_params: ShieldParams = field(default_factory=ShieldParams)
    engine: str = "hcomc"

    def tables(self) -> dict[str, Any]:
        """The run's fault, channel and shield as a config's ``[[faults]]``, ``[v2x]`` and
        ``[shield]`` tables (:mod:`hcomc.config.impairment_tables`): a config loaded with
        them runs this run."""
        faults = [] if self.fault_params.nominal else [self.fault_params.model_dump()]
        shield = {**self.shield_params.model_dump(), "enabled": self.shield}
        return {"faults": faults, "v2x": self.channel_params.model_dump(), "shield": shield}


def run_faulted(run: FaultRun) -> dict[str, Any]:
    """Simulate one run and measure it: merge outcome, collisions (all, and those with a
    vehicle a live plan commanded in that step), the key vehicles' min TTC and max DRAC,
    shield overrides, plans (lost, fallbacks) and the fault's timing.

    On a corridor (a corridor preset or file as the condition) the controller acts at every
    on-ramp, the fault is timed from the first ramp vehicle's control-zone entry anywhere,
    and the merge figures are over every merge event of the run (merged: none failed,
    :func:`_corridor_run`)."""
    from hcomc.corridor import is_corridor_source

    start = time.perf_counter()
    measured = (_corridor_run if is_corridor_source(run.condition) else _scenario_run)(run)
    impaired = measured.impaired
    overrides = impaired.shield.counts()
    log, groups, entry = measured.log, measured.groups, measured.entry
    collisions = log.events_of(EventKind.COLLISION)
    return {
        "condition": run.condition, "configuration": run.configuration, "fault": run.fault,
        "channel": run.channel, "shield": run.shield, "seed": run.seed,
        **measured.merge, "collisions": int(collisions.size),
        "collisions_commanded": impaired.collisions_commanded(log),
        "shield_brakes": overrides["brake"], "shield_holds": overrides["hold_change"],
        "shield_releases": overrides["release"],
        "plans": measured.plans, "plans_lost": impaired.plans_lost,
        "fallbacks": measured.fallbacks,
        "fault_vehicle": impaired.fault.vehicle,
        "fault_start": impaired.fault.start - entry if math.isfinite(entry) else math.nan,
        "degraded_steps": impaired.degraded_steps,
        "collision_pair": _pair_roles(collisions, groups),
        "fault_involved": bool(set(impaired.fault.vehicles)
                               & (set(collisions["vehicle"]) | set(collisions["other"]))),
        "wall_s": time.perf_counter() - start,
    }  # fmt: skip


@dataclass(frozen=True)
class _Measured:
    """What a faulted run measured besides the listener's own counts: its log, the merge
    figures (merged, merge_time, min_ttc, max_drac), plans and fallbacks, the key groups
    (latest first) and when the first ramp vehicle entered a control zone [s]."""

    log: SimulationLog
    merge: dict[str, Any]
    plans: int
    fallbacks: int
    groups: list[dict[str, int]]
    entry: float
    impaired: Impairments  # the listener of the run's fault, channel and shield


def _scenario_run(run: FaultRun) -> _Measured:
    """One of the paper's conditions on either engine, measured on its key window."""
    from hcomc.experiments.runner import configuration_overrides
    from hcomc.metrics import key_window
    from hcomc.metrics.outcome import merge_outcome
    from hcomc.metrics.surrogate import closing_metrics, max_drac, min_ttc
    from hcomc.robustness.impairments import Impairments
    from hcomc.sim.engine import Simulation

    config = load_config(run.condition, **configuration_overrides(run.configuration, {}),
                         **run.tables())  # fmt: skip
    impaired = Impairments(config.v2x, config.faults, config.shield)
    engine: type[Simulation] | type[SumoSimulation] = Simulation
    if run.engine == "sumo":
        from hcomc.sumo.cosim import SumoSimulation

        engine = SumoSimulation
    sim = engine(config, run.seed, listeners=[impaired])
    log = sim.run()
    window = key_window(log)
    closing = closing_metrics(log, window)
    outcome = merge_outcome(log, window)
    merge = {"merged": bool(outcome.merged), "merge_time": outcome.merge_time,
             "min_ttc": closing[min_ttc], "max_drac": closing[max_drac]}  # fmt: skip
    return _Measured(log, merge, len(sim.decisions), sum(bool(p.fallback) for p in sim.decisions),
                     [window.group], window.t_start, impaired)  # fmt: skip


def _corridor_run(run: FaultRun) -> _Measured:
    """A corridor with the configuration's controller at every on-ramp, measured over all
    of its merge events (:mod:`hcomc.metrics.corridor.events`). Merged: no event failed,
    where a ramp vehicle that has not merged fails if it waited at its lane's end or left
    the road; one still driving on its ramp when the run ends is in progress."""
    from hcomc.corridor import load_corridor
    from hcomc.experiments.corridor.runs import with_configuration
    from hcomc.metrics.corridor import simulate_corridor
    from hcomc.robustness.impairments import Impairments

    corridor = with_configuration(load_corridor(run.condition, run.tables()), run.configuration)
    impaired = Impairments(corridor.v2x, corridor.faults, corridor.shield)
    measured = simulate_corridor(corridor, seed=run.seed, listeners=[impaired])
    events = measured.merges
    merged = events.merged.astype(bool).to_numpy()
    done = events[merged]
    waited = measured.log.events_of(EventKind.RAMP_WAIT)["vehicle"]
    on_road = measured.trips.set_index("id").outcome.reindex(events.vr) == "on_road"
    in_progress = on_road.to_numpy() & ~np.isin(events.vr, waited)
    merge = {
        "merged": bool((merged | in_progress).all()),
        "merge_time": float(done.time_to_merge.mean()) if len(done) else math.nan,
        "min_ttc": float(events.min_ttc.min()) if len(events) else math.nan,
        "max_drac": float(events.max_drac.max()) if len(events) else math.nan,
    }
    groups = [
        {k: int(v) for k, v in g.items() if k != "t"}
        for g in measured.log.meta.get("key_groups", [])
    ]
    entry = float(measured.log.meta["key_groups"][0]["t"]) if groups else math.nan
    fallbacks = int(events.fallback.astype(bool).sum()) if len(events) else 0
    return _Measured(
        measured.log, merge, measured.decisions, fallbacks, groups[::-1], entry, impaired
    )


def _pair_roles(collisions: Any, groups: list[dict[str, int]]) -> str:
    """The key-vehicle roles of the first collision's pair ("VR-VMF"; "other" for a vehicle
    that is not a key vehicle) in the latest of ``groups`` that holds either vehicle;
    "" without a collision."""
    if not len(collisions):
        return ""
    first = collisions[0]
    pair = (int(first["vehicle"]), int(first["other"]))
    group = next((g for g in groups if set(pair) & set(g.values())), {})
    roles = {int(i): role for role, i in group.items() if i >= 0}
    return "-".join(roles.get(i, "other") for i in pair)


LARGE_CAMPAIGN = 1000
"""Seeds from which a campaign is published in a section of its own."""


@dataclass(frozen=True)
class CampaignSpec:
    """The grid: every combination of the axes, each over ``seeds``."""

    conditions: tuple[str, ...] = ("C1", "C2", "C3", "C4", "C5")
    configurations: tuple[str, ...] = ("FIFO", "Game", "HCOMC")
    faults: tuple[str, ...] = tuple(FAULTS)
    channels: tuple[str, ...] = tuple(CHANNELS)
    shields: tuple[bool, ...] = (False, True)
    seeds: tuple[int, ...] = tuple(range(10))
    engine: str = "hcomc"

    def __post_init__(self) -> None:
        from hcomc.experiments.runner import ENGINES

        if self.engine not in ENGINES:
            raise ConfigError(f"engine '{self.engine}'; allowed: {', '.join(ENGINES)}")
        for key, names, known in (("fault", self.faults, FAULTS),
                                  ("channel", self.channels, CHANNELS)):  # fmt: skip
            for name in names:
                if name not in known:
                    raise ConfigError(f"{key} '{name}'; allowed: {', '.join(known)}")
        if not self.seeds:
            raise ConfigError("seeds: at least one seed is needed")
        corridors = self.corridors()
        if corridors and self.engine != "hcomc":
            raise ConfigError(
                f"condition '{corridors[0]}' with engine '{self.engine}'; allowed: "
                "the paper's conditions (the co-simulation runs the paper's road)"
            )

    def corridors(self) -> tuple[str, ...]:
        """The conditions that are corridors (presets or files)."""
        from hcomc.corridor import is_corridor_source

        return tuple(c for c in self.conditions if is_corridor_source(c))

    def cells(self) -> list[tuple[str, str, str, str, bool]]:
        """(condition, configuration, fault, channel, shield) of every cell, in order, then
        the nominal cell (no fault, ideal channel, no shield) of each condition and
        configuration that the grid leaves out: the runs every cell is paired with."""
        grid = [(c, k, f, ch, s) for c in self.conditions for k in self.configurations
                for f in self.faults for ch in self.channels for s in self.shields]  # fmt: skip
        nominal = [(c, k, "none", "ideal", False) for c in self.conditions
                   for k in self.configurations]  # fmt: skip
        return grid + [cell for cell in nominal if cell not in grid]

    @property
    def section(self) -> str:
        """Where the campaign is published (:func:`hcomc.robustness.publish.data_dir`): the
        engine's name, with the number of seeds for a campaign of at least
        :data:`LARGE_CAMPAIGN` seeds (kept beside the smaller one)."""
        many = len(self.seeds) >= LARGE_CAMPAIGN
        return f"{self.engine}-{len(self.seeds)}-seeds" if many else self.engine

    def runs(self, cell: tuple[str, str, str, str, bool]) -> list[FaultRun]:
        """The runs of one cell, one per seed."""
        cond, conf, fault, channel, shield = cell
        return [FaultRun(cond, conf, fault, channel, shield, seed, FAULTS[fault],
                         CHANNELS[channel], engine=self.engine)
                for seed in self.seeds]  # fmt: skip

    def identity(self) -> dict[str, Any]:
        """What a campaign directory's results depend on: the spec, the settings it names,
        hcomc's version, the hash of its result-bearing code (and SUMO's version)."""
        from hcomc.experiments.provenance import code_stamp

        sumo = {}
        if self.engine == "sumo":  # the co-simulation's SUMO, as its run logs record it
            from hcomc.sumo.cosim import SumoSimulation

            sumo = {"sumo_version": SumoSimulation._sumo_version()}
        from hcomc.control.registry import controller_source
        from hcomc.corridor import load_corridor
        from hcomc.experiments.runner import configuration_controller

        corridors = {c: load_corridor(c).model_dump(mode="json") for c in self.corridors()}
        controllers = {k: controller_source(configuration_controller(k)[0])
                       for k in self.configurations}  # fmt: skip
        return {"spec": asdict(self), "version": hcomc.__version__, "code": code_stamp(),
                "controllers": controllers, **({"corridors": corridors} if corridors else {}),
                "faults": {f: FAULTS[f].model_dump() for f in self.faults},
                "channels": {c: CHANNELS[c].model_dump(mode="json") for c in self.channels},
                "shield": ShieldParams().model_dump(), **sumo}  # fmt: skip

    def command(self) -> str:
        """The ``hcomc faults`` command line that runs this spec and publishes it."""
        default = CampaignSpec()
        words = ["hcomc faults"]
        if self.engine != default.engine:
            words.append(f"--engine {self.engine}")
        words.append(f"--seeds {len(self.seeds)}")
        for axis, option in (("conditions", "--conditions"),
                             ("configurations", "--configurations"),
                             ("faults", "--faults"), ("channels", "--channels")):  # fmt: skip
            if getattr(self, axis) != getattr(default, axis):
                words.append(f"{option} {','.join(getattr(self, axis))}")
        suffix = self.section.removeprefix("hcomc").lstrip("-")
        out = f"results/faults-{suffix}" if suffix else "results/faults"
        return " ".join([*words, f"--out {out} --docs docs"])


def _cell_name(cell: tuple[str, str, str, str, bool]) -> str:
    text = json.dumps(cell)
    readable = "_".join(str(p) for p in cell).replace("/", "-")
    return f"{readable}-{hashlib.sha256(text.encode()).hexdigest()[:8]}"


def _run_cell(runs: Sequence[FaultRun]) -> list[dict[str, Any]]:
    return [run_faulted(r) for r in runs]


def _run_on_dask(
    scheduler: str,
    spec: CampaignSpec,
    todo: list[tuple[str, str, str, str, bool]],
    store: Callable[[tuple[str, str, str, str, bool], list[dict[str, Any]]], None],
) -> None:
    """The cells ``todo`` as Dask tasks (a lost worker's cell is retried twice)."""
    from distributed import as_completed as dask_completed

    from hcomc.experiments.workers import connect

    client = connect(scheduler)
    try:
        futures = {client.submit(_run_cell, spec.runs(c), pure=False, retries=2): c for c in todo}
        for future in dask_completed(list(futures)):
            store(futures[future], future.result())
    finally:
        client.close()


def run_campaign(
    spec: CampaignSpec, out: Path, *, workers: int = 1, scheduler: str | None = None,
    force: bool = False, progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:  # fmt: skip
    """Run every unfinished cell of ``spec`` into ``out`` (on ``workers`` local processes, or
    on the Dask cluster at ``scheduler``) and return all runs' rows."""
    from hcomc.robustness.tables import summarise

    parts = out / "parts"
    parts.mkdir(parents=True, exist_ok=True)
    identity = spec.identity()
    stamp = out / "campaign.json"
    if stamp.exists() and not force:
        recorded = json.loads(stamp.read_text())
        if {k: recorded.get(k) for k in identity} != json.loads(json.dumps(identity)):
            raise ConfigError(
                f"{out} holds a campaign of another spec, hcomc version or code; allowed: "
                "the same spec and code, another --out, or --force"
            )
    else:  # a new campaign (the revision it started at stays with its runs)
        for old in parts.glob("*.csv"):
            old.unlink()
        write_json_atomic(stamp, {**identity, "revision": git_revision()})

    def part(cell: tuple[str, str, str, str, bool]) -> Path:
        return parts / f"{_cell_name(cell)}.csv"

    cells = spec.cells()
    todo = [c for c in cells if not part(c).exists()]
    done = len(cells) - len(todo)
    if progress:
        progress(done, len(cells))

    def store(cell: tuple[str, str, str, str, bool], rows: list[dict[str, Any]]) -> None:
        nonlocal done
        with atomic_paths(part(cell)) as (tmp,):
            pd.DataFrame(rows).to_csv(tmp, index=False)
        done += 1
        if progress:
            progress(done, len(cells))

    if scheduler is not None:
        _run_on_dask(scheduler, spec, todo, store)
    elif workers <= 1:
        for cell in todo:
            store(cell, _run_cell(spec.runs(cell)))
    else:
        with local_pool(workers) as pool:
            futures = {pool.submit(_run_cell, spec.runs(c)): c for c in todo}
            for future in as_completed(futures):
                store(futures[future], future.result())
    table = pd.concat([pd.read_csv(part(c)) for c in cells], ignore_index=True)
    with atomic_paths(out / "runs.csv", out / "summary.csv") as (runs_tmp, summary_tmp):
        table.to_csv(runs_tmp, index=False)
        summarise(table).to_csv(summary_tmp, index=False)
    return table
