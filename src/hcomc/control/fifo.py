"""FIFO merge-sequence baseline (Ntousakis, Nikolos & Papageorgiou 2016).

The paper (Section I) describes the baseline it follows: "Ntousakis et al. [11] established two
merging sequence decision rules: first in first out (FIFO) and linear prediction of vehicle
speed, which can ensure safety"; Section IV compares HCOMC with "the FIFO model [11]" (Table
III). This FIFO baseline orders the ramp vehicle VR and the mainline vehicles
around its projection first-in-first-out by their predicted arrival time at the merge point,
and lets the mainline vehicle that must give way yield longitudinally through the virtual
vehicle VV1 of Eq. 8-10. It never uses lateral cooperation (paper Table III: FIFO and Game are
longitudinal-only) and never optimises anything.

Sequence. At the planning instant t0 (VR entering the control zone) the
arrival time of vehicle i at the merge point x_m is predicted at constant speed,
``t_i = t0 + (x_m - x_i) / v_i``, for VR, VMC and VMF. If VR arrives strictly before VMC, VR
merges between VMF and VMC and VMC yields; otherwise (also on a tie: the mainline keeps its
priority) VR merges behind VMC and VMR yields.

The plan records the sequence (``"ahead"``/``"behind"``) and executes the group of that
sequence (:func:`hcomc.control.key_group.behind_group` for "behind": the vehicle behind VR's slot
plays VMC and follows VV1). The plan's mode is :attr:`Mode.LONGITUDINAL` when the yielding
vehicle exists and is a CAV, :attr:`Mode.NONE` otherwise (an HDV is never commanded). A CAV VR
follows its virtual leader VV0 towards its slot, as under every controller, and the engine
replans every ``control.replan_period`` seconds when that is set (the "as published"
configuration plans once).

Shared with :mod:`hcomc.control.merge_game`: the single longitudinal candidate, its fixed
merge position and duration, virtual-vehicle horizon, prediction and nearest feasible
replacement (:mod:`hcomc.control.longitudinal_candidate`), and the predictor and plan around it
(:mod:`hcomc.control.predicting_baseline`).

Assumptions (documented; the paper gives no implementation details of its benchmarks):

* **No optimisation of the merge.** VR's lane-change duration is the CAV default
  ``config.cav.lane_change_duration``; the merge position is ``accel_lane_start + 10 m``,
  moved upstream if needed so that the predicted change, ending at
  ``x_f = merge_x + max(v_VR T, 3 L)`` with VR's *current* speed (the engine's rule of
  :func:`hcomc.sim.step.lane_change.start_lane_changes`), ends before ``accel_lane_end``, and
  never upstream of ``accel_lane_start`` (if even that overruns, the engine completes the change
  past the lane end, as it does for any change begun on the acceleration lane).
* **Virtual-vehicle horizon H.** VR's arrival time at ``merge_x``, first at constant speed,
  then refined once from the prediction of :class:`~hcomc.control.hierarchical.problem.MergeProblem`
  (VR accelerating freely on the ramp), clipped to ``[4 s, horizon_max]``. VV1 therefore ends
  at VR's predicted state when its lane change starts.
* **VV1 end state and minimum headway.** VV1 ends exactly at VR's predicted position and speed;
  Ntousakis et al.'s minimum time headway h = 1.5 s between consecutive arrivals is supplied by
  the yielding vehicle's own car-following model behind VV1 (it keeps its time gap), not by
  shifting VV1. The h-respecting FIFO schedule ``t_k = max(t_k, t_{k-1} + h)`` is reported in
  :class:`FIFODetails` for information only.
* **Prediction.** VR, VMF and the yielding vehicle are predicted with
  :meth:`MergeProblem.predict <hcomc.control.hierarchical.problem.MergeProblem.predict>` on
  the single candidate ``[merge_x, vr_duration, H, 0, sequence]`` (longitudinal); its ``vv0[0]`` and
  ``vv1[0]`` are exactly the coefficients the engine executes.
* **Nearest feasible VV1.** Ntousakis et al. give every vehicle an arrival time and the
  yielding vehicle an analytic trajectory to meet it, so the yielding vehicle yields whatever
  the traffic. When a virtual vehicle of the rule's candidate is infeasible (speed < 0 or
  deceleration beyond ``control.virtual_max_decel``), the candidate moves to the nearest
  feasible one (:func:`~hcomc.control.longitudinal_candidate.nearest_feasible`): on a
  deterministic grid, the merge position kept if possible and H lengthened in steps of
  :data:`~hcomc.control.longitudinal_candidate.HORIZON_STEP` up to ``control.horizon_max``;
  otherwise the merge position moved downstream in steps of
  :data:`~hcomc.control.longitudinal_candidate.POSITION_STEP` (up to the
  last position whose change still ends on the acceleration lane), each with the smallest such
  H. The first candidate in that order whose virtual vehicles are feasible is executed (the
  plan records the rule's own candidate in :attr:`FIFODetails.nominal`). Only when none is
  feasible does the plan fall back to gap acceptance (``fallback=True``, mode NONE,
  ``merge_x`` NaN), like HCOMC's.
* **Only VMF, VMC and VR are sequenced.** If VR is predicted to arrive even before VMF, it still
  takes the VMF-VMC slot (VMF's own leader is outside the key group);
  :attr:`FIFODetails.order` shows the predicted order and the engine's MOBIL safety check
  decides the actual gap.
* Speeds below 0.1 m/s are floored in the arrival-time prediction (no division by zero).

References
----------
.. [1] I. A. Ntousakis, I. K. Nikolos, M. Papageorgiou, "Optimal vehicle trajectory planning in
   the context of cooperative merging on highways", Transportation Research Part C 71 (2016)
   464-488 (FIFO and linear-speed-prediction sequencing rules).
.. [2] Wang et al., HCOMC, arXiv:2507.11621, Eq. 8-10 and Table III.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from hcomc.control.hierarchical.controller import sequence_groups
from hcomc.control.hierarchical.problem_terms import AHEAD, BEHIND, Prediction
from hcomc.control.longitudinal_candidate import MIN_SPEED, feasible_candidate, merge_position
from hcomc.control.predicting_baseline import PredictingBaseline, longitudinal_plan
from hcomc.interface import MergeGroup, MergePlan, Mode, PlanDetails, TrafficView, elapsed_ms

__all__ = [
    "FIFO_HEADWAY",
    "FIFOController",
    "FIFODetails",
    "arrival_times",
]

FIFO_HEADWAY = 1.5
"""Ntousakis et al.'s minimum time headway between consecutive arrivals [s] (reported only)."""


def arrival_times(view: TrafficView, group: MergeGroup, merge_x: float) -> dict[str, float]:
    """Predicted arrival time at ``merge_x`` of VR, VMC and VMF, constant speed [s, absolute].

    ``t_i = t0 + (x_m - x_i) / max(v_i, 0.1)`` (Ntousakis et al. 2016, FIFO rule). Missing
    vehicles are left out; a vehicle already past ``merge_x`` gets a time <= t0.
    """
    out: dict[str, float] = {}
    for role, i in (("VR", group.vr), ("VMC", group.vmc), ("VMF", group.vmf)):
        if i >= 0:
            out[role] = view.t + (merge_x - float(view.x[i])) / max(float(view.v[i]), MIN_SPEED)
    return out


def _schedule(arrivals: dict[str, float], headway: float) -> dict[str, float]:
    """FIFO arrival times respecting a minimum headway: ``t_k = max(t_k, t_{k-1} + h)``."""
    out: dict[str, float] = {}
    prev = -np.inf
    for role, t in sorted(arrivals.items(), key=lambda kv: kv[1]):
        prev = max(t, prev + headway)
        out[role] = prev
    return out


@dataclass(frozen=True, slots=True)
class FIFODetails(PlanDetails):
    """What a FIFO decision reports besides its plan.

    Attributes
    ----------
    arrival : predicted arrival time at the merge position per role ("VR", "VMC", "VMF";
        missing vehicles left out) [s, absolute].
    order : the roles in FIFO order (earliest arrival first).
    schedule : the h-respecting arrival times per role (information only) [s, absolute].
    yielding : vehicle index of the vehicle that yields (-1: none).
    prediction : the prediction of the executed candidate (None without a VMC).
    feasible : whether that prediction satisfies every constraint (False without one).
    nominal : the rule's own candidate (merge position [m], H [s]) before the nearest-feasible
        search (NaN without a VMC); the plan's ``merge_x`` and ``horizon`` differ from it when
        its virtual vehicles were infeasible and a feasible one was found.
    """

    arrival: dict[str, float]
    order: tuple[str, ...]
    schedule: dict[str, float]
    yielding: int = -1
    prediction: Prediction | None = None
    feasible: bool = False
    nominal: tuple[float, float] = (float("nan"), float("nan"))


class FIFOController(PredictingBaseline):
    """First-in-first-out merge sequencing with longitudinal cooperation (Ntousakis 2016).

    Parameters
    ----------
    config : scenario (the controller reads ``road``, ``cav`` and ``control``).

    Notes
    -----
    See the module docstring for the rule and every assumption; the plan's ``details`` are a
    :class:`FIFODetails`.
    """

    name = "fifo"

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        """Order VR, VMC, VMF by predicted arrival and let the follower of VR's slot yield.

        ``rng`` is not used (the rule is deterministic); it is accepted for the protocol.
        """
        start = time.perf_counter()
        vr = group.vr
        merge_x, vr_duration = merge_position(view, vr)
        arrivals = arrival_times(view, group, merge_x)
        order = tuple(r for r, _ in sorted(arrivals.items(), key=lambda kv: kv[1]))
        schedule = _schedule(arrivals, FIFO_HEADWAY)
        if group.vmc < 0:
            return MergePlan(
                group,
                Mode.NONE,
                view.t,
                merge_x=merge_x,
                vr_duration=vr_duration,
                reason="FIFO: no lane-1 vehicle behind VR, nobody to yield",
                decision_ms=elapsed_ms(start),
                details=FIFODetails(arrivals, order, schedule),
            )
        seq = AHEAD if arrivals["VR"] < arrivals["VMC"] else BEHIND
        exec_group = sequence_groups(view, group)[seq]
        problem = self.problem(view, group)
        pred, merge_x, horizon, nominal = feasible_candidate(
            view, vr, problem, merge_x, vr_duration, seq
        )
        details = FIFODetails(
            arrivals,
            order,
            schedule,
            yielding=exec_group.vmc,
            prediction=pred,
            feasible=bool((pred.G[0] <= 0.0).all()),
            nominal=nominal,
        )
        what = "VR before VMC: VMC yields" if seq == AHEAD else "VMC before VR: VR merges behind"
        if (merge_x, horizon) != nominal:
            what += f" (nearest feasible VV1: merge at {merge_x:.0f} m, H = {horizon:.2f} s)"
        return longitudinal_plan(
            view,
            exec_group,
            pred,
            merge_x=merge_x,
            vr_duration=vr_duration,
            horizon=horizon,
            reason=f"FIFO: {what}",
            start=start,
            details=details,
            sequence=seq,
            commands=view.is_cav(exec_group.vmc),
        )
