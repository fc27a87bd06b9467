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

A plan ends when VR's merge completes or a key vehicle leaves the road, and is replaced by a
new plan when the engine replans (every ``control.replan_period`` seconds until VR starts its
lane change or a lateral cooperation has begun). While it is active, commanded vehicles and
the connected (CAV) key vehicles make no discretionary (MOBIL) lane changes of their own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.control.base import MergePlan, Mode, virtual_states
from hcomc.road import Kind, Lane
from hcomc.sim.plans import PlanRecord

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig
    from hcomc.sim.fleet import Fleet
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
        """Receding horizon: replan every ``period`` s until a commanded lane change began.

        Within one period before its merge position VR keeps the plan it is about to execute
        (a replan cannot move the merge away at the last moment); if the change cannot start
        there (the MOBIL safety criterion fails), the plan has failed and replanning resumes
        until VR is released to gap acceptance.
        """
        merge_x = self.plan.merge_x
        committed = self.vr_commanded and merge_x - v_vr * period <= x_vr < merge_x
        return (
            period > 0.0
            and not committed
            and not self.vr_started
            and not self.vmc_started
            and not self.released
            and t - self.plan.t0 >= period - 1e-9
        )


def commanded(plans: list[ActivePlan], n: int) -> BoolArray:
    """Vehicles a live plan commands (excluded from MOBIL decisions)."""
    mask = np.zeros(n, dtype=bool)
    for p in plans:
        g = p.plan.group
        if p.vr_commanded and not p.vr_started and not p.released:
            mask[g.vr] = True
        if p.vmc_commanded:
            mask[g.vmc] = True
        if p.vnr_commanded:
            mask[g.vnr] = True
    return mask


def holding_lane(plans: list[ActivePlan], is_cav: BoolArray) -> BoolArray:
    """Vehicles that make no discretionary (MOBIL) lane change now: those a live plan
    commands, and every connected (CAV) key vehicle of a live plan, which keeps its lane so
    that it does not cut into the gap the plan opens (an HDV key vehicle cannot be told)."""
    mask = commanded(plans, is_cav.size)
    for p in plans:
        keys = p.plan.group.as_array()
        keys = keys[keys >= 0]
        mask[keys[is_cav[keys]]] = True
    return mask


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
    the horizon); their states are those of :func:`hcomc.control.base.virtual_states`.
    """
    rows: list[tuple[int, float, float, float, float]] = []
    for p in plans:
        plan, g = p.plan, p.plan.group
        states = virtual_states(plan, t, x, v, a)
        if p.vr_following and "vv0" in states and g.vmf >= 0:
            rows.append((g.vr, *states["vv0"], float(length[g.vmf])))
        if p.vmc_commanded and plan.mode == Mode.LONGITUDINAL and "vv1" in states:
            rows.append((g.vmc, *states["vv1"], float(length[g.vr])))
        if p.vnr_commanded and "vv2" in states:
            rows.append((g.vnr, *states["vv2"], float(length[g.vmc])))
    if not rows:
        empty = np.empty(0)
        return np.empty(0, dtype=np.int64), empty, empty, empty, empty
    table = np.array([r[1:] for r in rows], dtype=np.float64)
    followers = np.array([r[0] for r in rows], dtype=np.int64)
    return followers, table[:, 0], table[:, 1], table[:, 2], table[:, 3]


def game_confirms(
    x: FloatArray, v: FloatArray, lane: IntArray, fleet: Fleet, config: ScenarioConfig,
    chosen: IntArray, target: IntArray, ids: IntArray, lead: IntArray, index: LaneIndex,
) -> BoolArray:  # fmt: skip
    """Section III-B: a CAV's discretionary change must be its game equilibrium action
    (SV = the CAV, FV = its new follower); ramp merges and HDV changes are unaffected.
    Returns which of the ``chosen`` changes (to lanes ``target``) go ahead."""
    from hcomc.control.lane_change_game import game_params, game_vehicle, lane_change_game

    def vehicle(i: int):
        return game_vehicle(x, v, fleet, i)

    keep = np.ones(chosen.size, dtype=bool)
    new_lead, new_fol = index.lookup(target, x[chosen])
    old_lead = lead[np.searchsorted(ids, chosen)]
    for k, i in enumerate(chosen.tolist()):
        if fleet.kind[i] != Kind.CAV or lane[i] == Lane.RAMP:
            continue
        fol = int(new_fol[k])
        fv_idm = config.cav if fol >= 0 and fleet.kind[fol] == Kind.CAV else config.hdv
        decision = lane_change_game(
            vehicle(i), vehicle(fol), vehicle(int(old_lead[k])), vehicle(int(new_lead[k])),
            params=game_params(config), sv_idm=config.cav, fv_idm=fv_idm,
        )  # fmt: skip
        keep[k] = decision.change
    return keep


def plan_record(plan: MergePlan) -> dict[str, Any]:
    """JSON-ready summary of a plan, stored in ``SimulationLog.meta["plans"]`` for plots
    (:class:`hcomc.sim.plans.PlanRecord` is its typed form)."""
    return PlanRecord.from_plan(plan).to_json()
