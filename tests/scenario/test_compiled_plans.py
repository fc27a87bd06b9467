"""Live merge plans run in the compiled loop: Python is entered only at decisions.

A run is stepped two ways: by :meth:`Simulation.run` (many steps per compiled call, plans
executed from the plan table of the compiled state) and entirely in Python, one
:meth:`Simulation.step` at a time. The two must give bit-identical runs (logs, events in
order, decisions, what the controllers were asked, the plans left), and the compiled run must
take a Python step exactly at the decision events: a ramp vehicle entering the control zone
(key vehicles, a first plan) or a replan.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.control.hierarchical.controller import virtual_states
from hcomc.interface import Mode
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind
from hcomc.sim.plan_execution import ActivePlan, virtual_leaders
from hcomc.sim.step import state as layout

CASES: dict[str, tuple[str, dict[str, Any], int]] = {
    "C1 FIFO-R": ("C1", {"controller": "fifo", "replan_period": 1.0}, 0),
    "C2 Game-R": ("C2", {"controller": "game", "replan_period": 1.0}, 1),
    "C3 FIFO": ("C3", {"controller": "fifo", "replan_period": 0.0}, 2),
    "C5 Game": ("C5", {"controller": "game", "replan_period": 0.0}, 0),
    "C3 HCOMC": ("C3", {"controller": "hcomc"}, 0),
}


def _in_python(sim: Simulation, check: Any = None) -> int:
    """Run ``sim`` to its end one Python step at a time; the steps with live plans."""
    live = 0
    while not sim.finished:
        if sim.step_index < sim.stop_step:
            if check is not None:
                check(sim)
            live += bool(sim.plans)
            sim.resume(layout.NEED_PYTHON)  # one step in Python (and its log row)
        else:
            sim.resume(layout.DONE)  # the end of a stage
    return live


def _same_run(a: Simulation, b: Simulation) -> None:
    la, lb = a.log, b.log
    np.testing.assert_array_equal(la.t, lb.t)
    for name, cells in la.cells.items():
        np.testing.assert_array_equal(cells, lb.cells[name], err_msg=name)
    assert la.events.dtype.names is not None
    for field in la.events.dtype.names:  # every event, in order
        np.testing.assert_array_equal(la.events[field], lb.events[field], err_msg=field)
    for name in ("x", "v", "a", "y", "lane"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert _without_timing(la) == _without_timing(lb)
    assert la.meta.get("key_groups") == lb.meta.get("key_groups")
    assert len(a.decisions) == len(b.decisions)
    for pa, pb in zip(a.decisions, b.decisions, strict=True):
        assert (pa.group, pa.mode, pa.t0, pa.fallback) == (pb.group, pb.mode, pb.t0, pb.fallback)
        np.testing.assert_array_equal([pa.merge_x, pa.horizon], [pb.merge_x, pb.horizon])
    for (va, ga), (vb, gb) in zip(a.requests, b.requests, strict=True):
        assert ga == gb
        assert va.t == vb.t
        np.testing.assert_array_equal(va.x, vb.x)
        assert [p.group for p in va.plans] == [p.group for p in vb.plans]
    assert [_progress(p) for p in a.plans] == [_progress(p) for p in b.plans]
    assert a.vehicle_steps == b.vehicle_steps


def _without_timing(log: Any) -> list[dict[str, Any]]:
    return [{k: v for k, v in p.items() if k != "decision_ms"} for p in log.meta["plans"]]


def _progress(p: ActivePlan) -> tuple[Any, ...]:
    return (p.vr, p.vr_commanded, p.vmc_commanded, p.vnr_commanded, p.vr_started,
            p.vmc_started, p.released)  # fmt: skip


def _expected_leaders(plans: list[ActivePlan], t: float, sim: Simulation) -> list[tuple]:
    """The virtual-leader rows as the engine formed them in Python, from virtual_states."""
    rows = []
    for p in plans:
        plan, g = p.plan, p.plan.group
        states = virtual_states(plan, t, sim.x, sim.v, sim.a)
        length = sim.fleet.length
        if p.vr_following and "vv0" in states and g.vmf >= 0:
            rows.append((g.vr, *states["vv0"], float(length[g.vmf])))
        if p.vmc_commanded and plan.mode == Mode.LONGITUDINAL and "vv1" in states:
            rows.append((g.vmc, *states["vv1"], float(length[g.vr])))
        if p.vnr_commanded and "vv2" in states:
            rows.append((g.vnr, *states["vv2"], float(length[g.vmc])))
    return rows


def _check_leaders(sim: Simulation) -> None:
    plans = sim.plans
    got = virtual_leaders(plans, sim.t, sim.x, sim.v, sim.a, sim.fleet.length)
    rows = list(zip(*(col.tolist() for col in got), strict=True))
    assert rows == _expected_leaders(plans, sim.t, sim)


@pytest.mark.parametrize("name", sorted(CASES))
def test_compiled_plans_equal_python_steps(name: str) -> None:
    preset, control, seed = CASES[name]
    config = load_config(preset, control=control)
    python = Simulation(config, seed)
    live = _in_python(python, _check_leaders)
    compiled = Simulation(config, seed)
    steps: list[int] = []
    decision_step = compiled._decision_step

    def counted() -> None:
        steps.append(compiled.step_index)
        decision_step()

    compiled._decision_step = counted  # type: ignore[method-assign]
    compiled.run()
    _same_run(python, compiled)
    assert python.decisions, "the case must make plans"
    # Python was entered only at decisions, and at every one
    dt, warmup = config.dt, config.warmup
    decided = {round((g["t"] + warmup) / dt) for g in compiled.log.meta.get("key_groups", [])}
    plans = compiled.log.events_of(EventKind.PLAN)
    decided |= {round((float(t) + warmup) / dt) for t in plans["t"]}
    assert sorted(steps) == sorted(decided)
    assert compiled.python_steps == len(steps) == len(set(steps))
    assert live > 2 * len(steps)  # most steps with live plans ran compiled


def test_a_replanned_run_reenters_python_only_to_replan() -> None:
    """FIFO-R replans every second: each Python step after the first plan makes a plan."""
    config = load_config("C1", control={"controller": "fifo", "replan_period": 1.0})
    sim = Simulation(config, 0)
    sim.run()
    plans = sim.log.events_of(EventKind.PLAN)
    assert plans.size > 3  # replans happened
    first_plan_steps = {round((float(t) + config.warmup) / config.dt) for t in plans["t"]}
    identified = {round((g["t"] + config.warmup) / config.dt) for g in sim.log.meta["key_groups"]}
    assert sim.python_steps == len(first_plan_steps | identified)
