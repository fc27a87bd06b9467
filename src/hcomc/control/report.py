"""Plain-data report of one merge decision (for ``hcomc plan`` and JSON output)."""

from __future__ import annotations

from typing import Any

import numpy as np

from hcomc.control.hierarchical.controller import HCOMCDetails
from hcomc.control.hierarchical.problem_terms import MODE_NONE
from hcomc.interface import Engine, MergePlan, Mode
from hcomc.road import Kind


def _solution(x: np.ndarray, f: np.ndarray) -> dict[str, Any]:
    return {
        "merge_x": float(x[0]),
        "vr_duration": float(x[1]),
        "horizon": float(x[2]),
        "mode": "none" if x[3] >= MODE_NONE else "lateral" if x[3] >= 0.5 else "longitudinal",
        "sequence": "ahead" if x[3] >= 0.5 or x[4] < 0.5 else "behind",
        "safety": float(f[0]),
        "fuel": float(f[1]),
        "efficiency": float(f[2]),
    }


def plan_report(sim: Engine[object], plan: MergePlan) -> dict[str, Any]:
    """Key vehicles, game outcome, Pareto set and chosen plan as JSON-ready data."""
    view, group = sim.requests[0]
    keys: dict[str, Any] = {}
    for role, i in group.as_dict().items():
        keys[role] = (
            None
            if i < 0
            else {
                "id": i,
                "kind": Kind(int(view.fleet.kind[i])).name,
                "lane": int(view.lane[i]),
                "x": float(view.x[i]),
                "v": float(view.v[i]),
            }
        )
    d = plan.details
    hcomc = d if isinstance(d, HCOMCDetails) else None
    game = None if hcomc is None else hcomc.game
    pareto: list[dict[str, Any]] = []
    chosen = None
    if hcomc is not None:
        res = hcomc.pareto
        pareto = [
            _solution(x, f) for x, f, ok in zip(res.X, res.F, res.feasible, strict=True) if ok
        ]
        if 0 <= hcomc.chosen < len(res.X):
            k = hcomc.chosen
            chosen = {"index": k, **_solution(res.X[k], res.F[k])}
    return {
        "scenario": sim.config.name,
        "seed": sim.seed,
        "t": float(plan.t0),
        "optimizer": sim.config.control.optimizer if hcomc is None else hcomc.pareto.algorithm,
        "safety_threshold": sim.config.control.safety_threshold,
        "n_eval": 0 if hcomc is None else int(hcomc.pareto.n_eval),
        "key_vehicles": keys,
        "game": None
        if game is None
        else {
            "change": bool(game.change),
            "change_is_safe": bool(game.change_is_safe),
            "lateral_allowed": game.admits(sim.config.control.lateral_safety_rule),
            "admitted_by": game.admitted_by,
            "reason": game.reason,
        },
        "pareto": pareto,
        "chosen": chosen,
        "controller": sim.config.control.controller,
        "merge_x": float(plan.merge_x),
        "vr_duration": float(plan.vr_duration),
        "horizon": float(plan.horizon),
        "mode": Mode(plan.mode).name.lower(),
        "sequence": plan.sequence,
        "eq19_branch": d.eq19_branch,
        "fallback": plan.fallback,
        "reason": plan.reason,
        "decision_ms": float(plan.decision_ms),
    }
