"""The engine's doors for agents: commanded accelerations, commanded lane changes, advancing
to a step or to the key vehicles, alone and in an ensemble; the key-vehicle kernel."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.control.key_vehicles import key_vehicle_indices
from hcomc.road import Lane
from hcomc.sim.engine import Simulation
from hcomc.sim.ensemble import advance_ensemble
from hcomc.sim.log import EventKind

END = 10**12


def at_entry(seed: int = 0) -> Simulation:
    sim = Simulation(load_config("C1", control={"controller": "none"}), seed)
    sim.run_to(END, until_key_vehicles=True)
    assert sim.key_group is not None
    return sim


def test_commanded_acceleration_is_followed_exactly() -> None:
    """Ballistic integration of a constant command: v1 = v0 + a t, x1 = x0 + v0 t + a t^2 / 2."""
    sim = at_entry()
    vr = sim.key_group.vr
    x0, v0 = float(sim.x[vr]), float(sim.v[vr])
    sim.command(vr, 0.8)
    steps = 20
    sim.run_to(sim.step_index + steps)
    t = steps * sim.dt
    assert sim.v[vr] == pytest.approx(v0 + 0.8 * t, abs=1e-9)
    assert sim.x[vr] == pytest.approx(x0 + v0 * t + 0.4 * t * t, abs=1e-9)
    assert np.all(sim.log.a[-1:, vr][np.isfinite(sim.log.a[-1:, vr])] == np.float32(0.8))


def test_command_is_limited_to_the_emergency_deceleration_and_released_with_nan() -> None:
    sim = at_entry()
    vr = sim.key_group.vr
    sim.command(vr, -50.0)
    sim.run_to(sim.step_index + 1)
    assert sim.a[vr] == pytest.approx(-sim.config.lane_change.emergency_decel)
    sim.command(vr, math.nan)
    assert not sim.arrays.held[vr]
    sim.run_to(sim.step_index + 1)
    assert sim.a[vr] > -sim.config.lane_change.emergency_decel


def test_held_ramp_vehicle_never_merges_on_its_own_and_passes_the_lane_end() -> None:
    """Driven from outside, VR makes no gap-acceptance merge and does not brake for the end."""
    sim = at_entry()
    vr = sim.key_group.vr
    sim.command(vr, 0.0)
    end = sim.config.road.accel_lane_end
    while sim.x[vr] < end + 5 and not sim.finished:
        sim.run_to(sim.step_index + 10)
    assert sim.lane[vr] == Lane.RAMP
    assert sim.x[vr] >= end
    assert not np.any(sim.log.events_of(EventKind.LANE_CHANGE_START)["vehicle"] == vr)


def test_commanded_lane_change_merges_and_checks_its_target() -> None:
    sim = at_entry()
    vr = sim.key_group.vr
    with pytest.raises(ValueError, match="not adjacent"):
        sim.start_lane_change(vr, int(Lane.MAIN_2))
    sim.command(vr, 0.0)
    while sim.x[vr] < sim.config.road.accel_lane_start + 20:
        sim.run_to(sim.step_index + 1)
    sim.start_lane_change(vr, int(Lane.MAIN_1), 3.0)
    with pytest.raises(ValueError, match="already changing"):
        sim.start_lane_change(vr, int(Lane.MAIN_1))
    sim.run_to(sim.step_index + 60)
    merges = sim.log.events_of(EventKind.MERGE)
    assert vr in merges["vehicle"]
    assert sim.lane[vr] == Lane.MAIN_1


def test_ensemble_advance_equals_runs_alone() -> None:
    config = load_config("C1", control={"controller": "none"})
    alone = [Simulation(config, s) for s in (0, 1)]
    for sim in alone:
        sim.run_to(END, until_key_vehicles=True)
        sim.run_to(sim.step_index + 37)
    batch = [Simulation(config, s) for s in (0, 1)]
    advance_ensemble(batch, [END, END], until_key_vehicles=[True, True], threads=2)
    advance_ensemble(batch, [s.step_index + 37 for s in batch], threads=2)
    for a, b in zip(alone, batch, strict=True):
        assert a.step_index == b.step_index
        for name in ("x", "v", "a", "lane", "active"):
            np.testing.assert_array_equal(getattr(a.arrays, name), getattr(b.arrays, name))


def _key_oracle(x: np.ndarray, lane: np.ndarray, active: np.ndarray, vr: int) -> list[int]:
    """The rules of Section II-A by sorting, independently of the kernel."""

    def nearest(in_lane: int, x0: float, exclude: int) -> tuple[int, int]:
        idx = [i for i in range(x.size) if active[i] and lane[i] == in_lane and i != exclude]
        ahead = sorted((x[i], i) for i in idx if x[i] > x0)
        behind = sorted((-x[i], i) for i in idx if x[i] <= x0)
        return (ahead[0][1] if ahead else -1), (behind[0][1] if behind else -1)

    vmf, vmc = nearest(1, x[vr], vr)
    if vmc < 0:
        return [vr, -1, vmf, -1, -1, -1]
    vmr = nearest(1, x[vmc] - 1e-9, vmc)[1]
    vnf, vnr = nearest(2, x[vmc], vmc)
    return [vr, vmc, vmf, vmr, vnf, vnr]


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 60), st.integers(0, 2), st.booleans()), min_size=1, max_size=25
    )
)
def test_key_vehicle_kernel_matches_the_rules(cars: list[tuple[int, int, bool]]) -> None:
    x = np.array([5.0 * c[0] for c in cars])  # coarse positions: ties happen
    lane = np.array([c[1] for c in cars])
    active = np.array([c[2] for c in cars])
    vr = 0
    active[vr], lane[vr] = True, 0
    got = key_vehicle_indices(x, lane, active, vr, 1, 2).tolist()  # lanes 1 and 2
    assert got == _key_oracle(x, lane, active, vr)
