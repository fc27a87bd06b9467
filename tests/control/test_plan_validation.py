"""Every merge plan is checked before it acts (hcomc.control.validation)."""

from __future__ import annotations

import itertools
import math
import pickle
from dataclasses import replace
from functools import cache
from typing import Any

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.control.fifo import FIFOController
from hcomc.control.key_group import behind_group
from hcomc.control.validation import InvalidPlan, check_plan, checked
from hcomc.interface import MergeGroup, MergePlan, Mode, TrafficView
from hcomc.road import Kind
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog

NAME = "X"


@cache
def _request() -> tuple[MergePlan, TrafficView, MergeGroup]:
    """The first FIFO plan of C2 (seed 0), in the "ahead" sequence, and what it was asked,
    every vehicle made a CAV."""
    config = load_config("C2")
    sim = Simulation(config, 0, controller=FIFOController(config))
    sim.run_to(10**9, until_key_vehicles=True)
    (view, group), plan = sim.requests[0], sim.decisions[0]
    check_plan(plan, view, group, NAME)
    assert group.vmc >= 0, "the request has a VMC"
    assert group.vnr >= 0, "the request has a VNR"
    assert plan.mode == Mode.LONGITUDINAL
    # the tests vary a plan of the "ahead" sequence (the key group as identified)
    return replace(plan, group=group, sequence="ahead"), _with_kinds(view, {}), group


def _with_kinds(view: TrafficView, kinds: dict[int, Kind]) -> TrafficView:
    """``view`` with every vehicle a CAV except those ``kinds`` names."""
    kind = np.full_like(view.fleet.kind, Kind.CAV)
    for i, k in kinds.items():
        kind[i] = k
    return replace(view, fleet=replace(view.fleet, kind=kind))


@pytest.fixture
def request_() -> tuple[MergePlan, TrafficView, MergeGroup]:
    return _request()


def _error(plan: Any, view: TrafficView, group: MergeGroup) -> InvalidPlan:
    with pytest.raises(InvalidPlan) as info:
        check_plan(plan, view, group, NAME)
    return info.value


def _lateral(plan: MergePlan) -> MergePlan:
    """A valid lateral plan: VMC changes to lane 2, VNR follows VV2."""
    return replace(plan, mode=Mode.LATERAL, vv1=None, vv2=plan.vv1)


def _fallback(plan: MergePlan, **fields: Any) -> MergePlan:
    """A fallback plan as FIFO makes one (it keeps the horizon it tried)."""
    return MergePlan(plan.group, Mode.NONE, plan.t0, horizon=plan.horizon, fallback=True, **fields)


# ------------------------------------------------------------------ unit: check_plan
def test_the_built_in_plan_and_its_variants_pass(request_):
    plan, view, group = request_
    check_plan(plan, view, group, NAME)
    check_plan(_lateral(plan), view, group, NAME)
    check_plan(replace(_lateral(plan), vv2=None), view, group, NAME)  # VV2 is optional
    check_plan(replace(plan, mode=Mode.NONE, vv1=None), view, group, NAME)
    check_plan(MergePlan(group, Mode.NONE, view.t), view, group, NAME)  # the docs' example
    check_plan(_fallback(plan), view, group, NAME)
    check_plan(replace(plan, t0=view.t + 0.4 * view.config.dt), view, group, NAME)
    check_plan(replace(plan, vv1=list(plan.vv1)), view, group, NAME)  # any (4,) array-like


def test_merge_x_beyond_the_road_names_field_value_and_allowed(request_):
    plan, view, group = request_
    error = _error(replace(plan, merge_x=5000.0), view, group)
    assert (error.field, error.value) == ("merge_x", 5000.0)
    assert error.allowed == (
        "NaN (gap acceptance) or a position within the acceleration lane [700, 950] m"
    )
    assert str(error) == (
        f"controller 'X' returned an invalid plan for VR {group.vr} at t = {view.t:.10g} s: "
        "merge_x = 5000.0; allowed: NaN (gap acceptance) or a position within the "
        "acceleration lane [700, 950] m"
    )
    assert (error.controller, error.vr, error.t) == (NAME, group.vr, view.t)
    assert isinstance(error, ValueError)


def test_longitudinal_without_vv1(request_):
    plan, view, group = request_
    error = _error(replace(plan, vv1=None), view, group)
    assert (error.field, error.value) == ("vv1", None)
    assert "longitudinal mode" in error.allowed
    assert "vv1 = None; allowed: VV1's 4 cubic coefficients" in str(error)


def test_negative_vr_duration(request_):
    plan, view, group = request_
    error = _error(replace(plan, vr_duration=-1.0), view, group)
    assert (error.field, error.value) == ("vr_duration", -1.0)
    assert "a lane-change duration in (0.5, 15] s" in error.allowed  # the schema's bounds


def _cubic(bad: float) -> np.ndarray:
    return np.array([0.0, 20.0, bad, 0.0])


@pytest.mark.parametrize(
    ("field", "value", "allowed"),
    [
        ("t0", math.nan, "the planning time view.t"),
        ("t0", math.inf, "the planning time view.t"),
        ("t0", -1.0, "the planning time view.t"),
        ("merge_x", math.inf, "NaN (gap acceptance) or a position"),
        ("merge_x", 650.0, "[700, 950] m"),
        ("merge_x", "710", "NaN (gap acceptance) or a position"),
        ("vr_duration", math.inf, "(0.5, 15] s"),
        ("vr_duration", math.nan, "(0.5, 15] s (VR is a CAV with a finite merge_x)"),
        ("vr_duration", 0.3, "(0.5, 15] s"),
        ("horizon", math.inf, "a horizon in (0, 20] s"),
        ("horizon", math.nan, "a horizon in (0, 20] s (the plan has vv0, vv1)"),
        ("horizon", 0.0, "(0, 20] s"),
        ("horizon", 25.0, "(0, 20] s"),
        ("vv1", _cubic(math.nan), "None or 4 finite cubic coefficients"),
        ("vv0", _cubic(math.inf), "None or 4 finite cubic coefficients"),
        ("vv1", np.zeros(3), "shape (4,)"),
        ("vv1", np.zeros((2, 4)), "shape (4,)"),
    ],
)  # fmt: skip
def test_every_number_is_finite_and_bounded(request_, field, value, allowed):
    plan, view, group = request_
    error = _error(replace(plan, **{field: value}), view, group)
    assert error.field == field
    assert error.value is value
    assert allowed in error.allowed
    assert "\n" not in str(error)


def test_cooperating_vehicle_an_hdv(request_):
    plan, view, group = request_
    hdv = _with_kinds(view, {group.vmc: Kind.HDV})
    error = _error(plan, hdv, group)
    assert (error.field, error.value) == ("group.vmc", group.vmc)
    assert error.allowed == "a CAV in mode LONGITUDINAL (VMC is an HDV), or Mode.NONE"
    check_plan(replace(plan, mode=Mode.NONE, vv1=None), hdv, group, NAME)  # not commanded


def test_longitudinal_without_a_vmc(request_):
    plan, view, group = request_
    alone = MergeGroup(vr=group.vr)
    error = _error(replace(plan, group=alone), view, alone)
    assert (error.field, error.value) == ("group.vmc", -1)
    assert "(VMC is missing)" in error.allowed


def test_wrong_vr_and_wrong_roles(request_):
    plan, view, group = request_
    error = _error(replace(plan, group=replace(group, vr=group.vr + 1)), view, group)
    assert (error.field, error.value) == ("group.vr", group.vr + 1)
    assert error.allowed == f"{group.vr}, the ramp vehicle planned for"
    error = _error(replace(plan, group=replace(group, vnr=-1)), view, group)
    assert (error.field, error.value) == ("group.vnr", -1)
    assert error.allowed == f"{group.vnr}, VNR of the key group"
    # "behind" executes behind_group(view, group), not the group as identified
    behind = behind_group(view, group)
    error = _error(replace(plan, sequence="behind"), view, group)
    assert (error.field, error.value) == ("group.vmc", group.vmc)
    assert error.allowed == f"{behind.vmc}, VMC of behind_group(view, group)"
    error = _error(replace(plan, sequence="sideways"), view, group)
    assert (error.field, error.value) == ("sequence", "sideways")
    assert error.allowed == "'ahead' or 'behind' ('behind' only with a VMC)"


def test_not_a_plan_and_not_a_mode(request_):
    plan, view, group = request_
    error = _error({"mode": 1}, view, group)
    assert (error.field, error.value) == ("plan", "dict")
    error = _error(replace(plan, mode=1), view, group)
    assert (error.field, error.value) == ("mode", 1)


def test_virtual_vehicles_belong_to_their_mode(request_):
    plan, view, group = request_
    error = _error(replace(plan, mode=Mode.NONE), view, group)  # NONE commands no VMC
    assert error.field == "vv1"
    assert "longitudinal mode only; mode is NONE" in error.allowed
    error = _error(replace(plan, vv2=plan.vv1), view, group)
    assert error.field == "vv2"
    assert error.allowed == "None (VV2 belongs to lateral mode; mode is LONGITUDINAL)"
    error = _error(replace(_lateral(plan), vv1=plan.vv1), view, group)
    assert error.field == "vv1"


def test_vv2_commands_a_cav_vnr(request_):
    plan, view, group = request_
    error = _error(_lateral(plan), _with_kinds(view, {group.vnr: Kind.HDV}), group)
    assert error.field == "vv2"
    assert error.allowed == "None: VV2 commands VNR, which is an HDV"


def test_an_hdv_vr_may_carry_a_merge_position_but_no_vv0(request_):
    plan, view, group = request_
    hdv_vr = _with_kinds(view, {group.vr: Kind.HDV})
    check_plan(replace(plan, vv0=None), hdv_vr, group, NAME)  # FIFO's plan for an HDV VR
    check_plan(replace(plan, vv0=None, vr_duration=math.nan), hdv_vr, group, NAME)
    error = _error(plan, hdv_vr, group)
    assert error.field == "vv0"
    error = _error(replace(plan, merge_x=math.nan), view, group)  # VV0 leads VR to merge_x
    assert error.field == "vv0"


def test_a_fallback_plan_commands_nobody(request_):
    plan, view, group = request_
    check_plan(_fallback(plan, vr_duration=-1.0), view, group, NAME)  # not executed: not checked
    assert _error(replace(plan, fallback=True), view, group).field == "mode"
    assert _error(_fallback(plan, merge_x=710.0), view, group).field == "merge_x"
    assert _error(_fallback(plan, vv0=plan.vv0), view, group).field == "vv0"
    assert _error(replace(_fallback(plan), t0=math.nan), view, group).field == "t0"


def test_invalid_plan_pickles_and_reads_on_one_line(request_):
    plan, view, group = request_
    error = _error(replace(plan, vv1=np.full(4, np.nan)), view, group)
    assert "vv1 = array([nan, nan, nan, nan]); allowed:" in str(error)
    again = pickle.loads(pickle.dumps(error))
    assert (type(again), str(again), again.field) == (InvalidPlan, str(error), "vv1")


def _policy(view: TrafficView, policy: str) -> TrafficView:
    control = view.config.control.model_copy(update={"on_invalid_plan": policy})
    return replace(view, config=view.config.model_copy(update={"control": control}))


def test_checked_raises_or_falls_back_as_configured(request_):
    plan, view, group = request_
    assert checked(plan, view, group, NAME) is plan
    broken = replace(plan, merge_x=5000.0)
    with pytest.raises(InvalidPlan, match=r"merge_x = 5000\.0; allowed"):
        checked(broken, view, group, NAME)
    safe = checked(broken, _policy(view, "fallback"), group, NAME)
    assert (safe.mode, safe.fallback, safe.group, safe.t0) == (Mode.NONE, True, group, view.t)
    assert math.isnan(safe.merge_x)
    assert (safe.vv0, safe.vv1, safe.vv2) == (None, None, None)
    assert safe.reason.startswith("invalid plan from 'X': merge_x = 5000.0; allowed: NaN")
    assert safe.decision_ms == plan.decision_ms
    check_plan(safe, view, group, NAME)


# ---------------------------------------------------------- a broken controller, run
class CorruptFIFO:
    """FIFO with one field of every plan it makes corrupted (a researcher's bug)."""

    name = "corrupt-fifo"

    def __init__(self, config: ScenarioConfig, **corrupt: Any) -> None:
        self.inner = FIFOController(config)
        self.corrupt = corrupt

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        return replace(self.inner.plan(view, group, rng), **self.corrupt)


def test_a_broken_controller_stops_the_run_by_default():
    config = load_config("C2", duration=30.0)
    sim = Simulation(config, 0, controller=CorruptFIFO(config, merge_x=5000.0))
    with pytest.raises(InvalidPlan) as info:
        sim.run()
    error = info.value
    assert (error.controller, error.field, error.value) == ("corrupt-fifo", "merge_x", 5000.0)
    assert error.vr == next(iter(sim.key_groups))
    assert not sim.decisions  # nothing invalid was executed


def _fallback_run(seed: int) -> tuple[Simulation, SimulationLog, int]:
    """C2 with ``on_invalid_plan = "fallback"`` and a controller whose durations are -1."""
    config = load_config("C2", duration=60.0, **{"control.on_invalid_plan": "fallback"})
    sim = Simulation(config, seed, controller=CorruptFIFO(config, vr_duration=-1.0))
    log = sim.run()
    return sim, log, next(iter(sim.key_groups))


def test_a_broken_controller_falls_back_when_configured():
    sim, log, vr = _fallback_run(2)  # a seed whose VR is an HDV
    assert sim.fleet.kind[vr] == Kind.HDV
    assert sim.decisions
    for plan in sim.decisions:
        assert (plan.fallback, plan.mode, plan.vv0, plan.vv1) == (True, Mode.NONE, None, None)
        assert math.isnan(plan.merge_x)
        assert plan.reason.startswith("invalid plan from 'corrupt-fifo': vr_duration = -1.0; ")
        assert "allowed: NaN (not commanded) or a lane-change duration in (0.5, 15] s" in (
            plan.reason
        )
    records = log.meta["plans"]
    assert [(r["fallback"], r["reason"]) for r in records] == [
        (True, p.reason) for p in sim.decisions
    ]
    fallbacks = log.events_of(EventKind.FALLBACK)["vehicle"].tolist()
    assert fallbacks.count(vr) == len(sim.decisions)
    assert vr in log.events_of(EventKind.MERGE)["vehicle"].tolist()  # by gap acceptance


def test_a_cav_vr_on_fallback_plans_merges_by_gap_acceptance():
    sim, log, vr = _fallback_run(0)
    assert sim.fleet.kind[vr] == Kind.CAV
    invalid = [p for p in sim.decisions if p.reason.startswith("invalid plan from")]
    assert invalid
    assert invalid[0] is sim.decisions[0]
    # FIFO's own fallbacks (an infeasible VV1) pass unchanged: a fallback's duration is not used
    assert all(p.fallback and math.isnan(p.merge_x) and p.vv0 is None for p in sim.decisions)
    # no plan commands VR, and no live plan holds it on the ramp: it merges as an HDV would
    assert vr in log.events_of(EventKind.MERGE)["vehicle"].tolist()


# ------------------------------------------------------- the built-in controllers pass
@pytest.mark.parametrize("controller", ["fifo", "game", "game-capped", "hcomc"])
def test_built_in_plans_pass(controller):
    for condition, seed in itertools.product(("C1", "C2", "C3", "C4", "C5"), (0, 1)):
        sim = Simulation(load_config(condition, duration=30.0, controller=controller), seed)
        sim.run()  # the engine checks every plan: an invalid one would raise here
        assert sim.decisions
        for plan, (view, group) in zip(sim.decisions, sim.requests, strict=True):
            check_plan(plan, view, group, controller)


class _Raises:
    """A controller whose plan raises ``error``."""

    def __init__(self, error: Exception) -> None:
        self.error = error

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        raise self.error


def test_a_raising_controller_becomes_one_pickled_line(request_):
    """The exception's type and message on one line (the type alone without a message),
    the controller, VR, time and run; the traceback kept as text across a pickle."""
    from hcomc.control.validation import ControllerFailed, planned

    _, view, group = request_
    rng = np.random.default_rng(0)
    for error, shown in ((ValueError("bad\n  gap:"), "ValueError: bad gap:"),
                         (KeyError(), "KeyError")):  # fmt: skip
        with pytest.raises(ControllerFailed) as info:
            planned(_Raises(error), view, group, rng, "C1, seed 0")
        failed = info.value
        assert failed.error == shown
        assert str(failed) == (f"controller '_Raises' raised {shown} while planning for VR "
                               f"{group.vr} at t = {view.t:.10g} s (C1, seed 0)")  # fmt: skip
        again = pickle.loads(pickle.dumps(failed))
        assert (str(again), again.trace) == (str(failed), failed.trace)
        assert "raise self.error" in again.trace
