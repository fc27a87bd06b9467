"""The typed plan record: the JSON kept in SimulationLog.meta["plans"] and its reader."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.control.hierarchical.controller import HCOMCDetails
from hcomc.interface import MergeGroup, MergePlan, Mode, PlanDetails
from hcomc.optim.base import ParetoResult
from hcomc.road import KEY_ROLES
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog
from hcomc.sim.log.plans import PlanRecord, plan_records
from hcomc.sim.plan_execution import plan_record

finite = st.floats(-1e4, 1e4, allow_nan=False)
cubics = st.none() | st.lists(finite, min_size=4, max_size=4).map(np.array)


def _details(branch: str) -> PlanDetails:
    """HCOMC's details with Eq. 19 ``branch``; a plain plan's (no Eq. 19) when empty."""
    if not branch:
        return PlanDetails()
    empty = np.zeros((0, 3))
    pareto = ParetoResult(empty, empty, empty, np.zeros(0, dtype=bool), 0, "nsga2")
    return HCOMCDetails(pareto=pareto, games=(None, None), eq19_branch=branch)


@given(
    group=st.lists(st.integers(-1, 50), min_size=6, max_size=6),
    mode=st.sampled_from(list(Mode)),
    t0=finite,
    merge_x=finite,
    vv=st.tuples(cubics, cubics, cubics),
    sequence=st.sampled_from(["ahead", "behind"]),
    branch=st.sampled_from(["", "a", "b"]),
    objectives=st.dictionaries(st.sampled_from(["safety", "fuel", "efficiency"]), finite),
)
def test_record_survives_json(group, mode, t0, merge_x, vv, sequence, branch, objectives):
    plan = MergePlan(
        group=MergeGroup(*group),
        mode=mode,
        t0=t0,
        merge_x=merge_x,
        vv0=vv[0],
        vv1=vv[1],
        vv2=vv[2],
        sequence=sequence,
        objectives=objectives,
        details=_details(branch),
    )
    text = json.dumps(plan_record(plan))  # NaN != NaN: compare records through their JSON
    record = PlanRecord.from_json(json.loads(text))
    assert json.dumps(record.to_json()) == text
    assert json.dumps(PlanRecord.from_plan(plan).to_json()) == text
    assert record.vehicle("VR") == group[0]
    assert [record.vehicle(r) for r in KEY_ROLES] == group
    assert record.mode == mode.name.lower()
    assert record.eq19_branch == plan.details.eq19_branch == branch
    for got, want in zip((record.vv0, record.vv1, record.vv2), vv, strict=True):
        assert got == (None if want is None else tuple(want.tolist()))


def test_older_entries_take_defaults_and_bad_entries_are_named() -> None:
    old = PlanRecord.from_json({"group": {"VR": 3}, "mode": "none", "t0": 1.5})
    assert old.vehicle("VR") == 3
    assert old.vehicle("VMC") == -1
    assert math.isnan(old.merge_x)
    assert (old.sequence, old.eq19_branch, old.decision_ms) == ("ahead", "", 0.0)
    with pytest.raises(ValueError, match="key 'colour' unknown"):
        PlanRecord.from_json({"group": {"VR": 3}, "mode": "none", "t0": 0.0, "colour": 1})
    with pytest.raises(ValueError, match="key 't0' is missing"):
        PlanRecord.from_json({"group": {"VR": 3}, "mode": "none"})
    with pytest.raises(ValueError, match="key 'mode' = 'sideways'"):
        PlanRecord.from_json({"group": {"VR": 3}, "mode": "sideways", "t0": 0.0})
    with pytest.raises(ValueError, match="key 'vv1'"):
        PlanRecord.from_json({"group": {"VR": 3}, "mode": "none", "t0": 0.0, "vv1": [1.0]})
    with pytest.raises(ValueError, match="key 'group'"):
        PlanRecord.from_json({"group": {"VMC": 3}, "mode": "none", "t0": 0.0})


def test_a_run_reads_back_its_plans(tmp_path) -> None:
    config = load_config("C2", control={"controller": "fifo"}, duration=40.0)
    sim = Simulation(config, 1)
    log = sim.run()
    records = plan_records(log)
    assert len(records) == len(log.meta["plans"]) > 0
    text = json.dumps(log.meta["plans"])
    assert json.dumps([r.to_json() for r in records]) == text
    saved = SimulationLog.load(log.save(tmp_path / "run.npz"))
    assert json.dumps([r.to_json() for r in plan_records(saved)]) == text
    assert all(log.kind[r.vehicle("VR")] in (0, 1) for r in records)
