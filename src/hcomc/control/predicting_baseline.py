"""What the rule-based baselines (FIFO, Game) share around their one predicted candidate: the
predictor and the plan that executes the candidate.

:class:`PredictingBaseline` poses HCOMC's merge problem (both sequences, longitudinal only) as
a predictor of the candidate a baseline's rule picks (:mod:`hcomc.control.longitudinal_candidate`);
:func:`longitudinal_plan` turns the prediction into the plan: a CAV VR follows VV0, the yielding
vehicle VV1 when the rule commands it, and an infeasible virtual vehicle falls back to gap
acceptance.
"""

from __future__ import annotations

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.control.hierarchical.controller import merge_problem
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_setup import load_prediction_kernels
from hcomc.control.hierarchical.problem_terms import OBJECTIVES, SEQUENCES, Prediction
from hcomc.control.longitudinal_candidate import virtual_vehicle_feasible
from hcomc.interface import MergeGroup, MergePlan, Mode, PlanDetails, TrafficView, elapsed_ms

__all__ = ["PredictingBaseline", "longitudinal_plan", "predicted_objectives"]


class PredictingBaseline:
    """Shared part of the baselines: HCOMC's merge problem (both sequences, longitudinal only)
    used as a predictor of the one candidate the baseline's rule picks."""

    def __init__(self, config: ScenarioConfig) -> None:
        load_prediction_kernels()
        self.config = config

    def problem(self, view: TrafficView, group: MergeGroup) -> MergeProblem:
        """The longitudinal-only merge problem of ``group`` and of its "behind" group."""
        return merge_problem(view, group)


def predicted_objectives(pred: Prediction) -> dict[str, float]:
    """Predicted HCOMC objectives of the executed candidate (for reporting)."""
    return dict(zip(OBJECTIVES, map(float, pred.F[0]), strict=True))


def longitudinal_plan(
    view: TrafficView,
    group: MergeGroup,
    pred: Prediction,
    *,
    merge_x: float,
    vr_duration: float,
    horizon: float,
    reason: str,
    start: float,
    details: PlanDetails,
    sequence: int,
    commands: bool,
) -> MergePlan:
    """The plan of a baseline's single predicted candidate.

    A CAV VR follows VV0 towards its slot; the yielding vehicle (``group.vmc``) follows VV1
    when ``commands`` (it is a CAV and the rule asks it to yield). If a commanded virtual
    vehicle is infeasible, the safe fallback applies (VR merges by gap acceptance, nobody
    commanded).
    """
    if not virtual_vehicle_feasible(pred):
        return MergePlan(
            group,
            Mode.NONE,
            view.t,
            horizon=horizon,
            fallback=True,
            reason=f"{reason}; virtual vehicle infeasible, VR merges by gap acceptance",
            decision_ms=elapsed_ms(start),
            details=details,
            sequence=SEQUENCES[sequence],
        )
    return MergePlan(
        group,
        Mode.LONGITUDINAL if commands else Mode.NONE,
        view.t,
        merge_x=merge_x,
        vr_duration=vr_duration,
        horizon=horizon,
        vv0=np.array(pred.vv0[0], dtype=np.float64) if view.is_cav(group.vr) else None,
        vv1=np.array(pred.vv1[0], dtype=np.float64) if commands else None,
        reason=reason if commands else f"{reason}; no vehicle commanded",
        objectives=predicted_objectives(pred),
        decision_ms=elapsed_ms(start),
        details=details,
        sequence=SEQUENCES[sequence],
    )
