"""Executing merge plans: which vehicles are commanded, and their virtual leaders.

The engine owns all state; this module only reads it and tells the engine what to do:

* a CAV VR on the ramp follows its virtual leader VV0 (the plan's speed profile towards its
  target gap: a cubic to its future leader's state at t0 + H, then that leader's projection)
  and does not brake for the lane end; it starts its lane change at the plan's merge position
  with the plan's duration if the MOBIL safety criterion holds then; otherwise it keeps trying
  while it can still stop before the lane end at the MOBIL safe deceleration, and then falls
  back to gap acceptance with the lane end as a standing obstacle (logged);
* longitudinal mode: a CAV VMC follows the nearer of its real leader and VV1 (Eq. 8-10),
  which is the cubic for t - t0 <= H and VR's projection onto lane 1 after that;
* lateral mode: a CAV VMC changes to lane 2 at the planning time if that is safe (else the
  plan falls back to VR's gap acceptance, logged); a CAV VNR follows the nearer of its real
  leader and VV2 (Eq. 11-13) for t - t0 <= H.

A plan fails when VR falls back (above) or waits at its lane's end, commanded or not: VR
merges by gap acceptance and VMC and VNR leave their virtual leaders (logged). A plan ends
when VR's merge completes or a key vehicle leaves the road, and is replaced by a
new plan when the engine replans (every ``control.replan_period`` seconds until VR starts its
lane change or a lateral cooperation has begun). While it is active, commanded vehicles and
the connected (CAV) key vehicles make no discretionary (MOBIL) lane changes of their own.

The engine executes these rules in its compiled step, from the plan table of its state
(:mod:`hcomc.sim.step.plans`, their one implementation); the functions here apply the same
kernels to a list of :class:`ActivePlan` (the SUMO co-simulation keeps its plans that way).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.interface import MergeGroup, MergePlan, TrafficView
from hcomc.road import Kind, Lane
from hcomc.sim.log.events import EventKind
from hcomc.sim.log.plans import PlanRecord
from hcomc.sim.step import plans as table
from hcomc.sim.step.plans import commanded_mask, encode_plan, holding_mask, replan_due

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig
    from hcomc.control.lane_change_game.players import GameVehicle
    from hcomc.interface import Fleet
    from hcomc.sim.log import SimulationLog
    from hcomc.sim.neighbours import LaneIndex


@dataclass
class ActivePlan:
    """A plan being executed and its progress."""

    plan: MergePlan
    vr_commanded: bool
    vmc_commanded: bool
    vnr_commanded: bool
    vr_started: bool = False
    vmc_started: bool = False
    released: bool = False  # VR back on gap acceptance
    done: bool = False

    @property
    def vr(self) -> int:
        """VR's vehicle index."""
        return self.plan.group.vr

    @property
    def vr_following(self) -> bool:
        """Whether VR is on the ramp following the plan (VV0, no lane-end braking)."""
        return self.vr_commanded and not self.vr_started and not self.released

    def may_replan(self, t: float, period: float, x_vr: float, v_vr: float) -> bool:
        """Receding horizon: replan every ``period`` s until a commanded lane change began
        (:func:`hcomc.sim.step.plans.replan_due`).

        Within one period before its merge position VR keeps the plan it is about to execute
        (a replan cannot move the merge away at the last moment); if the change cannot start
        there (the MOBIL safety criterion fails), the plan has failed and replanning resumes
        until VR is released to gap acceptance.
        """
        return bool(
            replan_due(self.vr_commanded, self.vr_started, self.vmc_started, self.released,
                       float(self.plan.t0), float(self.plan.merge_x), float(t), float(period),
                       float(x_vr), float(v_vr))
        )  # fmt: skip


def plan_table(plans: list[ActivePlan]) -> tuple[np.ndarray, np.ndarray]:
    """The plan table (:mod:`hcomc.sim.step.plans`) of ``plans``, row k being ``plans[k]``."""
    n = max(1, len(plans))
    pi, pf = np.zeros((n, table.N_INT), dtype=np.int64), np.zeros((n, table.N_FLOAT))
    for k, p in enumerate(plans):
        ints, floats = encode_plan(p.plan, p.vr_commanded, p.vmc_commanded, p.vnr_commanded, k)
        ints[[table.P_VR_STARTED, table.P_VMC_STARTED, table.P_RELEASED]] = (
            p.vr_started, p.vmc_started, p.released
        )  # fmt: skip
        pi[k], pf[k] = ints, floats
    return pi, pf


def plan_views(plan_int: np.ndarray, n: int, decisions: list[MergePlan]) -> list[ActivePlan]:
    """The first ``n`` rows of a plan table as :class:`ActivePlan` (copies), each with its
    plan from ``decisions``."""
    return [_view_of(row, decisions) for row in plan_int[:n]]


def _view_of(row: np.ndarray, decisions: list[MergePlan]) -> ActivePlan:
    return ActivePlan(
        decisions[int(row[table.P_ID])], vr_commanded=bool(row[table.P_VR_CMD]),
        vmc_commanded=bool(row[table.P_VMC_CMD]), vnr_commanded=bool(row[table.P_VNR_CMD]),
        vr_started=bool(row[table.P_VR_STARTED]), vmc_started=bool(row[table.P_VMC_STARTED]),
        released=bool(row[table.P_RELEASED]),
    )  # fmt: skip


def commanded(plans: list[ActivePlan], n: int) -> BoolArray:
    """Vehicles a live plan commands (excluded from MOBIL decisions)."""
    pi, _ = plan_table(plans)
    return commanded_mask(pi, len(plans), n)


def holding_lane(plans: list[ActivePlan], is_cav: BoolArray) -> BoolArray:
    """Vehicles that make no discretionary (MOBIL) lane change now: those a live plan
    commands, and every connected (CAV) key vehicle of a live plan other than VR, which keeps
    its lane so that it does not cut into the gap the plan opens (an HDV key vehicle cannot be
    told). A VR the plan does not command merges by gap acceptance."""
    pi, _ = plan_table(plans)
    return holding_mask(pi, len(plans), np.ascontiguousarray(is_cav, dtype=np.bool_))


def virtual_leaders(
    plans: list[ActivePlan],
    t: float,
    x: FloatArray,
    v: FloatArray,
    a: FloatArray,
    length: FloatArray,
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(followers, x_vv, v_vv, a_vv, length_vv)`` of every virtual vehicle in force at t.

    VV0 leads a CAV VR that follows its plan on the ramp, VV1 a cooperating VMC in
    longitudinal mode (until VR's merge is complete), VV2 a CAV VNR in lateral mode (within
    the horizon); their states are those of
    :func:`hcomc.control.hierarchical.controller.virtual_states`
    (:func:`hcomc.sim.step.plans.virtual_rows`).
    """
    pi, pf = plan_table(plans)
    f8 = np.float64
    return table.virtual_rows(
        pi, pf, len(plans), float(t), np.ascontiguousarray(x, dtype=f8),
        np.ascontiguousarray(v, dtype=f8), np.ascontiguousarray(a, dtype=f8),
        np.ascontiguousarray(length, dtype=f8),
    )  # fmt: skip


def game_confirms(
    x: FloatArray, v: FloatArray, lane: IntArray, fleet: Fleet, config: ScenarioConfig,
    chosen: IntArray, target: IntArray, ids: IntArray, lead: IntArray, index: LaneIndex,
) -> BoolArray:  # fmt: skip
    """Section III-B: a CAV's discretionary change must be its game equilibrium action
    (SV = the CAV, FV = its new follower); ramp merges and HDV changes are unaffected.
    Returns which of the ``chosen`` changes (to lanes ``target``) go ahead."""
    from hcomc.control.lane_change_game.decision import game_params, game_vehicle, lane_change_game

    def vehicle(i: int) -> GameVehicle | None:
        return game_vehicle(x, v, fleet, i)

    keep = np.ones(chosen.size, dtype=bool)
    new_lead, new_fol = index.lookup(target, x[chosen])
    old_lead = lead[np.searchsorted(ids, chosen)]
    for k, i in enumerate(chosen.tolist()):
        if fleet.kind[i] != Kind.CAV or lane[i] == Lane.RAMP:
            continue
        fol = int(new_fol[k])
        fv_idm = config.cav if fol >= 0 and fleet.kind[fol] == Kind.CAV else config.hdv
        sv = vehicle(i)
        assert sv is not None  # a chosen vehicle is on the road
        decision = lane_change_game(
            sv, vehicle(fol), vehicle(int(old_lead[k])), vehicle(int(new_lead[k])),
            params=game_params(config, config.road.lane_width), sv_idm=config.cav,
            fv_idm=fv_idm,
        )  # fmt: skip
        keep[k] = decision.change
    return keep


def plan_record(plan: MergePlan) -> dict[str, Any]:
    """JSON-ready summary of a plan, stored in ``SimulationLog.meta["plans"]`` for plots
    (:class:`hcomc.sim.log.plans.PlanRecord` is its typed form)."""
    return PlanRecord.from_plan(plan).to_json()


class DecisionRecorder(Protocol):
    """What :func:`record_decision` writes to: an :class:`~hcomc.interface.Engine`'s decision
    lists and log (an engine, or a mix-in that records for one)."""

    @property
    def x(self) -> FloatArray: ...
    @property
    def requests(self) -> list[tuple[TrafficView, MergeGroup]]: ...
    @property
    def decisions(self) -> list[MergePlan]: ...
    @property
    def log(self) -> SimulationLog: ...


def record_decision(
    engine: DecisionRecorder, view: TrafficView, group: MergeGroup, plan: MergePlan, t: float
) -> None:
    """Record a decision as every engine does: what was asked (``engine.requests``), the plan
    (``engine.decisions``, its :func:`plan_record` in the log's meta) and the PLAN event, with a
    FALLBACK event when the controller found no feasible plan."""
    vr, x = group.vr, engine.x[group.vr]
    engine.requests.append((view, group))
    engine.decisions.append(plan)
    engine.log.meta.setdefault("plans", []).append(plan_record(plan))
    engine.log.add_event(t, EventKind.PLAN, vr, other=group.vmc, x=x, value=int(plan.mode))
    if plan.fallback:
        engine.log.add_event(t, EventKind.FALLBACK, vr, other=group.vmc, x=x)
