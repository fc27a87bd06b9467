"""Controllers see a ramp, not a scenario: every built-in controller reads the road only
through the view's :class:`~hcomc.interface.Ramp`, so it plans the same at any ramp whose
local traffic is the same, whatever the scenario's ``[road]`` table says and whatever codes
the lanes carry."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hcomc import Simulation, load_config
from hcomc.control.key_group import behind_group, find_key_vehicles
from hcomc.control.registry import make_controller, registered
from hcomc.interface import MergeGroup, MergePlan, Ramp, TrafficView

SEED = 11


def _decision(condition: str) -> tuple[TrafficView, MergeGroup]:
    """The view and key group of the first decision of a run of ``condition`` (every
    controller is then asked the same question)."""
    sim = Simulation(load_config(condition, control={"controller": "fifo"}), 2)
    assert sim.run_until_plan() is not None
    view, group = sim.requests[0]
    assert group.vmc >= 0, "a decision with a vehicle to cooperate"
    return view, group


def _plan(name: str, view: TrafficView, group: MergeGroup) -> MergePlan:
    config = view.config.model_copy(
        update={"control": view.config.control.model_copy(update={"controller": name})}
    )
    controller = make_controller(config)
    assert controller is not None
    return controller.plan(dataclasses.replace(view, config=config), group,
                           np.random.default_rng(SEED))  # fmt: skip


def _data(plan: MergePlan) -> dict[str, object]:
    """Everything a plan decided (not the wall-clock time it took nor its free-form
    details), arrays as lists."""
    skip = {"decision_ms", "details"}
    out = {}
    for f in dataclasses.fields(plan):
        if f.name in skip:
            continue
        value = getattr(plan, f.name)
        out[f.name] = value.tolist() if isinstance(value, np.ndarray) else value
    return out


def _same(a: MergePlan, b: MergePlan) -> None:
    da, db = _data(a), _data(b)
    assert da.keys() == db.keys()
    for key in da:
        assert repr(da[key]) == repr(db[key]), key  # NaN-safe, exact


@pytest.mark.parametrize("condition", ["C2", "C4"])
@pytest.mark.parametrize("name", sorted(registered()))
def test_a_controller_reads_the_road_from_the_ramp_alone(name, condition):
    view, group = _decision(condition)
    # another road in the scenario: a 40 m acceleration lane 200 m upstream, wider lanes
    # (read from there, every merge position and lane change would differ)
    old = view.config.road
    start = old.accel_lane_start - 200.0
    road = old.model_copy(update={
        "ramp_start": min(old.ramp_start, start - 50.0), "accel_lane_start": start,
        "accel_lane_end": start + 40.0, "lane_width": 4.5,
    })  # fmt: skip
    moved = dataclasses.replace(view, config=view.config.model_copy(update={"road": road}))
    assert moved.ramp == view.ramp == Ramp.of(view.config.road)
    _same(_plan(name, moved, group), _plan(name, view, group))


@pytest.mark.parametrize("name", sorted(registered()))
def test_a_controller_plans_the_same_whatever_codes_the_lanes_carry(name):
    view, group = _decision("C2")
    codes = {int(view.ramp.lane): 7, int(view.ramp.target): 4, int(view.ramp.beyond): 9}
    lane = np.array([codes.get(int(c), -1) for c in view.lane], dtype=np.int64)
    lane.flags.writeable = False
    ramp = dataclasses.replace(view.ramp, lane=7, target=4, beyond=9)
    relabelled = dataclasses.replace(view, lane=lane, ramp=ramp)
    assert find_key_vehicles(relabelled, group.vr) == group
    assert behind_group(relabelled, group) == behind_group(view, group)
    _same(_plan(name, relabelled, group), _plan(name, view, group))


def test_a_ramp_without_a_lane_beyond_has_no_vnf_nor_vnr():
    view, group = _decision("C2")
    single = dataclasses.replace(view, ramp=dataclasses.replace(view.ramp, beyond=-1))
    alone = find_key_vehicles(single, group.vr)
    assert (alone.vr, alone.vmc, alone.vmf, alone.vmr) == (group.vr, group.vmc, group.vmf,
                                                           group.vmr)  # fmt: skip
    assert (alone.vnf, alone.vnr) == (-1, -1)


def test_the_paper_road_as_a_ramp():
    road = load_config("C1").road
    ramp = Ramp.of(road)
    assert (ramp.accel_lane_start, ramp.accel_lane_end) == (road.accel_lane_start,
                                                             road.accel_lane_end)  # fmt: skip
    assert ramp.control_zone_start == road.control_zone_start
    assert (ramp.lane, ramp.target, ramp.beyond) == (0, 1, 2)
