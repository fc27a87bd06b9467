"""CommonRoad's collision checker (commonroad_dc) and hcomc's Eq. 7 test agree on an exported
run: on the C2 run as the engine logged it (no collision), and on the same log with one
vehicle shifted onto another for some rows (collisions: the same pairs at the same steps)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("commonroad")
pytest.importorskip("commonroad_dc")

from commonroad.common.file_reader import CommonRoadFileReader

from hcomc.commonroad.contacts import Contact, commonroad_contacts, log_contacts, onsets
from hcomc.commonroad.export import export_commonroad
from hcomc.commonroad.run import run_of_log
from hcomc.commonroad.scenario import build_scenario, write_scenario
from hcomc.config import validate_config
from hcomc.sim.log import EventKind, SimulationLog

REAR_END = range(40, 50)  # rows in which B overlaps A's rear by 0.8 m
SIDESWIPE = range(55, 60)  # rows in which B, turned by 0.05 rad, grazes A's left side
NEAR_MISS = range(62, 67)  # rows in which B drives beside A, 0.1 m apart


def _read_back(log: SimulationLog, path: Path) -> object:
    """The log exported to ``path`` and read with commonroad-io: its scenario."""
    config = validate_config(log.meta["config"], "log")
    built = build_scenario(run_of_log(log, config))
    write_scenario(built, path, source="test")
    scenario, _ = CommonRoadFileReader(str(path)).open()
    return scenario


def test_no_contact_in_the_run_by_either_checker(c2_run: Path, tmp_path: Path) -> None:
    log = SimulationLog.load(c2_run / "log.npz")
    out = tmp_path / "run.xml"
    export_commonroad(c2_run, out)
    scenario, _ = CommonRoadFileReader(str(out)).open()
    assert commonroad_contacts(scenario) == log_contacts(log) == ()
    assert log.events_of(EventKind.COLLISION).size == 0  # the engine's count


def _two_vehicles(log: SimulationLog) -> tuple[int, int]:
    """Two vehicles on the road, heading straight, at every row the shifts touch."""
    rows = np.arange(REAR_END.start, NEAR_MISS.stop)
    active = np.asarray(log.active[rows])
    straight = np.asarray(log.heading[rows]) == 0
    both = np.flatnonzero(active.all(axis=0) & straight.all(axis=0))
    assert both.size >= 2
    return int(both[0]), int(both[1])


def _shifted(log: SimulationLog) -> tuple[SimulationLog, int, int]:
    """``log`` with vehicle B moved onto vehicle A (module constants); also A and B."""
    n = log.n_recorded
    cells = {name: np.array(getattr(log, name)[:n]) for name in
             ("x", "y", "v", "a", "heading", "lane", "active")}  # fmt: skip
    a, b = _two_vehicles(log)
    x, y, h = cells["x"], cells["y"], cells["heading"]
    length, width = float(log.length[a]), float(log.width[a])
    for row in REAR_END:
        x[row, b], y[row, b], h[row, b] = x[row, a] - length + 0.8, y[row, a], 0.0
    for row in SIDESWIPE:  # B's rear corner reaches 0.049 m into A: only where the body
        # is L/2 behind the bumper and turned by the heading (a front-centred or unturned
        # rectangle would miss A), so this contact tests the export's conversion
        x[row, b], y[row, b], h[row, b] = x[row, a], y[row, a] + width + 0.2, 0.05
    for row in NEAR_MISS:
        x[row, b], y[row, b], h[row, b] = x[row, a], y[row, a] + width + 0.1, 0.0
    shifted = SimulationLog(
        dt=log.dt, t=log.t[:n], kind=log.kind, length=log.length, width=log.width,
        meta=log.meta, n_recorded=n, **cells,
    )  # fmt: skip
    return shifted, a, b


def test_both_checkers_find_the_same_collisions(c2_run: Path, tmp_path: Path) -> None:
    shifted, a, b = _shifted(SimulationLog.load(c2_run / "log.npz"))
    hcomc = log_contacts(shifted)
    pair = (min(a, b), max(a, b))
    touching = [c.step for c in hcomc if (c.a, c.b) == pair]
    assert touching == [*REAR_END, *SIDESWIPE]  # the near miss is no contact
    begun = [c for c in onsets(hcomc) if (c.a, c.b) == pair]
    assert begun == [Contact(REAR_END.start, *pair), Contact(SIDESWIPE.start, *pair)]
    commonroad = commonroad_contacts(_read_back(shifted, tmp_path / "shifted.xml"))
    assert commonroad == hcomc
    assert len(onsets(commonroad)) == len(onsets(hcomc)) >= 2
