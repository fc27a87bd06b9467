"""The results row of a finished run: who ran, the key vehicles, and what the plans did.

:func:`run_columns` gives the columns of a row that describe the run and its merge controller's
decisions (configuration, controller, seed, the key vehicles' kinds, the last plan's mode and
fallback, the lane-change games, replans and plan switches, the decision time, the realised
merge sequence); :mod:`hcomc.experiments.runner` adds the metrics against the undisturbed run
and the time taken. A run without a ramp vehicle in the control zone keeps the defaults
(empty strings, zeros, NaN), so every row has the same columns.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from hcomc.interface import Engine
from hcomc.metrics.outcome import realised_sequence
from hcomc.sim.log import SimulationLog

__all__ = ["lateral_cause", "plan_switches", "run_columns"]


def _plan_columns(sim: Engine[SimulationLog], vr: int) -> dict[str, Any]:
    """Columns of VR's plans: the last plan's mode, fallback, Eq. 19 branch and lateral
    admission (:func:`lateral_cause`); the Section III-B lane-change games played over the
    plans, how many chose "change lane" at equilibrium and how many only the added safety
    rule admitted (an extension); the number of replans (plans for
    VR minus one) and of fallbacks; the mean decision time; and the plan switches
    (:func:`plan_switches`: their number, and whether the last plan is one)."""
    plans = [p for p in sim.decisions if p.group.vr == vr]
    if not plans:
        return {}
    last = plans[-1]
    switches = plan_switches(plans)
    games = [g for g in (getattr(p.details, "game", None) for p in plans) if g is not None]
    return {
        "mode": last.mode.name.lower(),
        "fallback": bool(last.fallback),
        "fallbacks": sum(bool(p.fallback) for p in plans),
        "eq19_branch": last.details.eq19_branch,
        "lateral_cause": lateral_cause(last),
        "games": len(games),
        "games_change": sum(bool(g.change) for g in games),
        "games_safety_rule": sum(g.admitted_by == "safety_rule" for g in games),
        "replans": len(plans) - 1,
        "plan_switches": len(switches),
        "final_switch": bool(switches) and switches[-1] == len(plans) - 1,
        "decision_ms": float(np.mean([p.decision_ms for p in plans])),
    }


def plan_switches(plans: Sequence[Any]) -> list[int]:
    """Indices of the plans (of one VR, in decision order) whose cooperating vehicle
    (:attr:`~hcomc.interface.MergePlan.cooperating`, -1 for nobody) differs from the plan
    before: a receding-horizon controller that switches commands another vehicle, or stops
    or starts commanding one."""
    return [i for i in range(1, len(plans)) if plans[i].cooperating != plans[i - 1].cooperating]


def lateral_cause(plan: Any) -> str:
    """Why a lateral plan was admissible: "equilibrium" when the Section III-B lane-change
    game's equilibrium action of the cooperating vehicle is to change lane, "safety_rule"
    when only the added admission (its change keeps Eq. 15 below the threshold against every
    response of its follower) allowed it; "" for a plan that is not lateral."""
    game = getattr(plan.details, "game", None)
    if plan.mode.name != "LATERAL" or game is None:
        return ""
    return str(game.admitted_by)


def run_columns(
    sim: Engine[SimulationLog],
    *,
    condition: str,
    configuration: str,
    controller: str,
    optimizer: str,
    seed: int,
) -> dict[str, Any]:
    """The columns of ``sim``'s row before its metrics: the run as named by the arguments,
    then the key vehicles of the first ramp vehicle that entered the control zone (its index
    and kind, VMC's kind), the columns of its plans (:func:`_plan_columns`) and its realised
    merge sequence."""
    row: dict[str, Any] = {
        "condition": condition,
        "configuration": configuration,
        "controller": controller,
        "optimizer": optimizer,
        "seed": seed,
        "mode": "",
        "sequence": "",
        "eq19_branch": "",
        "lateral_cause": "",
        "games": 0,
        "games_change": 0,
        "games_safety_rule": 0,
        "replans": 0,
        "plan_switches": 0,
        "final_switch": False,
        "fallback": False,
        "fallbacks": 0,
        "decision_ms": np.nan,
        "vr": -1,
        "vr_kind": "",
        "vmc_kind": "",
    }
    group = sim.key_group
    if group is not None:
        kinds = sim.fleet.kind
        row.update(
            vr=group.vr,
            vr_kind="CAV" if kinds[group.vr] else "HDV",
            vmc_kind="" if group.vmc < 0 else "CAV" if kinds[group.vmc] else "HDV",
        )
        row.update(_plan_columns(sim, group.vr))
        row["sequence"] = realised_sequence(sim.log, group.vr, group.vmc)
    return row
