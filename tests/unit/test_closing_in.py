"""Time to collision and DRAC of every logged cell against its leader
(hcomc.metrics.corridor.events.closing_in): closed forms, and a run's log against numpy's sort
of each row by lane and position as the oracle."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.metrics.cell_passes import LANE_APART
from hcomc.metrics.corridor.events import closing_in
from hcomc.metrics.detectors import vehicle_rows
from hcomc.safety.surrogate import CLOSING_SPEED
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog


def _log(x0: list[float], speeds: list[float], lanes: list[int], rows: int = 3) -> SimulationLog:
    t = np.arange(rows, dtype=np.float64) * 0.1
    x = np.asarray(x0)[None, :] + t[:, None] * np.asarray(speeds)[None, :]
    shape, n = x.shape, len(x0)
    return SimulationLog(
        dt=0.1, t=t, x=x, y=np.zeros(shape), v=np.broadcast_to(speeds, shape).copy(),
        a=np.zeros(shape), heading=np.zeros(shape), lane=np.broadcast_to(lanes, shape).copy(),
        active=np.ones(shape, dtype=bool), kind=np.zeros(n), length=np.full(n, 5.0),
        width=np.full(n, 1.8), n_recorded=rows,
    )  # fmt: skip


def test_a_follower_closing_in_gets_gap_over_closing_speed() -> None:
    # 0 closes in on 1 (45 m bumper gap, 5 m/s); 2 is faster than 1 but in another lane;
    # 3 leads lane 1 and 1 does not close in on it
    log = _log([100.0, 150.0, 120.0, 400.0], [20.0, 15.0, 30.0, 25.0], [1, 1, 2, 1], rows=1)
    ttc, drac = closing_in(log, vehicle_rows(log))
    assert ttc[0, 0] == np.float32(45.0 / 5.0)
    assert drac[0, 0] == np.float32(25.0 / 90.0)
    assert np.isinf(ttc[0, 1:]).all()
    assert (drac[0, 1:] == 0.0).all()


def _by_numpy_sort(log: SimulationLog) -> tuple[np.ndarray, np.ndarray]:
    """Each row's cells ordered by numpy's argsort of lane and position, each measured
    against the next (the oracle)."""
    rows = vehicle_rows(log)
    cells = log.cells
    length = np.zeros(cells["x"].shape, dtype=np.float32)
    length[rows.row, rows.column] = rows.length
    x = cells["x"].astype(np.float64)
    lane, active, v = cells["lane"], cells["active"], cells["v"]
    order = np.argsort(np.where(active, lane * LANE_APART + x, np.inf), axis=1)

    def by(a: np.ndarray) -> np.ndarray:
        return np.take_along_axis(a, order, axis=1)

    xs, vs, ls, on = by(x), by(v), by(lane), by(active)
    led = on[:, :-1] & on[:, 1:] & (ls[:, 1:] == ls[:, :-1])
    gap = np.maximum(xs[:, 1:] - by(length)[:, 1:] - xs[:, :-1], 1e-3)
    closing = vs[:, :-1] - vs[:, 1:]
    hit = led & (closing >= CLOSING_SPEED)
    ttc = np.full(x.shape, np.inf, dtype=np.float32)
    drac = np.zeros(x.shape, dtype=np.float32)
    here = np.arange(x.shape[0])[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        ttc[here, order[:, :-1]] = np.where(hit, gap / closing, np.inf)
        drac[here, order[:, :-1]] = np.where(hit, closing * closing / (2.0 * gap), 0.0)
    return ttc, drac


@pytest.mark.parametrize(("scenario", "seed"), [("C3", 0), ("C5", 4)])
def test_a_runs_cells_equal_those_of_a_sort_of_every_row(scenario: str, seed: int) -> None:
    log = Simulation(load_config(scenario), seed).run()
    assert log.n_slots < log.n_vehicles  # columns handed on from vehicle to vehicle
    ttc, drac = closing_in(log, vehicle_rows(log))
    expected_ttc, expected_drac = _by_numpy_sort(log)
    assert np.isfinite(ttc).sum() > 100  # followers closing in, in every run
    np.testing.assert_array_equal(ttc, expected_ttc)
    np.testing.assert_array_equal(drac, expected_drac)
