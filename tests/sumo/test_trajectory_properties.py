"""Property: any log on our road survives FCD and highD round trips (hypothesis)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.road import Lane, lane_centre
from hcomc.sim.log import SimulationLog
from hcomc.sumo.fcd import read_fcd, write_fcd
from hcomc.sumo.highd import read_highd, write_highd

CONFIG = load_config("C1")


@st.composite
def logs(draw: st.DrawFn) -> SimulationLog:
    """Random logs: vehicles on any lane of the road, moving forwards, in and out of view."""
    n_rows = draw(st.integers(2, 12))
    n = draw(st.integers(1, 6))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    road = CONFIG.road
    kind = rng.integers(0, 2, n)
    log = SimulationLog.allocate(n_rows, n, dt=0.1, kind=kind, length=np.full(n, 5.0),
                                 width=np.full(n, 1.8), meta={})  # fmt: skip
    lane = rng.integers(0, 3, n)
    lo = np.where(lane == Lane.RAMP, road.ramp_start + 5.0, 5.0)
    hi = np.where(lane == Lane.RAMP, road.accel_lane_end - 10.0, road.length - 10.0)
    x0 = rng.uniform(lo, hi)
    for k in range(n_rows):
        active = rng.random(n) < 0.8
        x = np.minimum(x0 + k * rng.uniform(0.0, 1.0, n), hi + 5.0)
        offset = rng.uniform(-0.45, 0.45, n) * road.lane_width  # anywhere inside the lane
        log.record(k, k * 0.1, x, lane_centre(lane, road.lane_width) + offset,
                   rng.uniform(0.5, 35.0, n), rng.uniform(-5.0, 2.0, n),
                   rng.uniform(-0.2, 0.2, n), lane, active)  # fmt: skip
    log.active[0, 0] = True  # a vehicle in the first row (files start at their first vehicle)
    log.x[0, 0], log.y[0, 0], log.v[0, 0], log.a[0, 0], log.heading[0, 0] = 100.0, 0.0, 1, 0, 0
    log.lane[0, 0] = Lane.MAIN_1
    return log


def _check(log: SimulationLog, back: SimulationLog) -> None:
    n, m = log.n_recorded, back.n_vehicles  # row 0 always holds a vehicle: rows align
    assert not log.active[:, m:].any()  # a file knows only the vehicles it shows
    act = log.active[:n, :m]
    assert back.n_recorded == n
    np.testing.assert_array_equal(back.active[:, :m], act)
    np.testing.assert_array_equal(back.lane[:, :m][act], log.lane[:n, :m][act])
    np.testing.assert_allclose(back.t, log.t[:n], atol=1e-9)
    for name in ("x", "y", "v", "a", "heading"):
        got = getattr(back, name)[:, :m][act]
        np.testing.assert_allclose(got, getattr(log, name)[:n, :m][act], atol=2e-4,
                                   err_msg=name)  # fmt: skip


@settings(max_examples=25, deadline=None)
@given(logs())
def test_fcd_round_trip(log: SimulationLog) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = write_fcd(log, Path(tmp) / "f.xml", CONFIG)
        back, _ = read_fcd(path, CONFIG)
    _check(log, back)


@settings(max_examples=25, deadline=None)
@given(logs())
def test_highd_round_trip(log: SimulationLog) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        back, _ = read_highd(write_highd(log, Path(tmp) / "h", CONFIG), CONFIG)
    _check(log, back)
