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
sequence (:func:`hcomc.control.base.behind_group` for "behind": the vehicle behind VR's slot
plays VMC and follows VV1). The plan's mode is :attr:`Mode.LONGITUDINAL` when the yielding
vehicle exists and is a CAV, :attr:`Mode.NONE` otherwise (an HDV is never commanded). A CAV VR
follows its virtual leader VV0 towards its slot, as under every controller, and the engine
replans every ``control.replan_period`` seconds when that is set (the "as published"
configuration plans once).

Shared with :mod:`hcomc.control.merge_game`: the fixed merge position and duration
(:func:`merge_position`), the virtual-vehicle horizon (:func:`reach_horizon`) and the
single-candidate prediction (:func:`predict_longitudinal`).

Assumptions (documented; the paper gives no implementation details of its benchmarks):

* **No optimisation of the merge.** VR's lane-change duration is the CAV default
  ``config.cav.lane_change_duration``; the merge position is ``accel_lane_start + 10 m``,
  moved upstream if needed so that the predicted change, ending at
  ``x_f = merge_x + max(v_VR T, 3 L)`` with VR's *current* speed (the engine's rule of
  :meth:`hcomc.sim.engine.Simulation._start_lane_changes`), ends before ``accel_lane_end``, and
  never upstream of ``accel_lane_start`` (if even that overruns, the engine completes the change
  past the lane end, as it does for any change begun on the acceleration lane).
* **Virtual-vehicle horizon H.** VR's arrival time at ``merge_x``, first at constant speed,
  then refined once from the prediction of :class:`~hcomc.control.hcomc.problem.MergeProblem`
  (VR accelerating freely on the ramp), clipped to ``[4 s, horizon_max]``. VV1 therefore ends
  at VR's predicted state when its lane change starts.
* **VV1 end state and minimum headway.** VV1 ends exactly at VR's predicted position and speed;
  Ntousakis et al.'s minimum time headway h = 1.5 s between consecutive arrivals is supplied by
  the yielding vehicle's own car-following model behind VV1 (it keeps its time gap), not by
  shifting VV1. The h-respecting FIFO schedule ``t_k = max(t_k, t_{k-1} + h)`` is reported in
  :class:`FIFODetails` for information only.
* **Prediction.** VR, VMF and the yielding vehicle are predicted with
  :meth:`MergeProblem.predict <hcomc.control.hcomc.problem.MergeProblem.predict>` on the single
  candidate ``[merge_x, vr_duration, H, 0, sequence]`` (longitudinal); its ``vv0[0]`` and
  ``vv1[0]`` are exactly the coefficients the engine executes.
* **Nearest feasible VV1.** Ntousakis et al. give every vehicle an arrival time and the
  yielding vehicle an analytic trajectory to meet it, so the yielding vehicle yields whatever
  the traffic. When a virtual vehicle of the rule's candidate is infeasible (speed < 0 or
  deceleration beyond ``control.virtual_max_decel``), the candidate moves to the nearest
  feasible one (:func:`nearest_feasible`): on a deterministic grid, the merge position kept if
  possible and H lengthened in steps of :data:`HORIZON_STEP` up to ``control.horizon_max``;
  otherwise the merge position moved downstream in steps of :data:`POSITION_STEP` (up to the
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

import copy
import time
from dataclasses import dataclass, replace

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config import ScenarioConfig
from hcomc.control.base import (
    MergeGroup,
    MergePlan,
    Mode,
    PlanDetails,
    TrafficView,
    elapsed_ms,
)
from hcomc.control.hcomc.controller import merge_problem, sequence_groups
from hcomc.control.hcomc.problem import (
    AHEAD,
    BEHIND,
    CONSTRAINTS,
    OBJECTIVES,
    SEQUENCES,
    KeyState,
    MergeProblem,
    Prediction,
    load_prediction_kernels,
)
from hcomc.road import VMC, VR

__all__ = [
    "FIFO_HEADWAY",
    "HORIZON_STEP",
    "MERGE_OFFSET",
    "MIN_HORIZON",
    "POSITION_STEP",
    "FIFOController",
    "FIFODetails",
    "arrival_times",
    "feasible_candidate",
    "last_merge_position",
    "merge_position",
    "nearest_feasible",
    "predict_longitudinal",
    "reach_horizon",
    "virtual_vehicle_feasible",
    "with_cooperation",
]

MERGE_OFFSET = 10.0
"""VR starts its change this far downstream of the acceleration-lane start [m]."""
MIN_HORIZON = 4.0
"""Lower bound of the virtual-vehicle horizon H [s] (roughly 4-10 s)."""
FIFO_HEADWAY = 1.5
"""Ntousakis et al.'s minimum time headway between consecutive arrivals [s] (reported only)."""
HORIZON_STEP = 0.5
"""Step of the nearest-feasible search over the virtual-vehicle horizon H [s] (two prediction
steps at the default ``control.prediction_dt``)."""
POSITION_STEP = MERGE_OFFSET
"""Step of the nearest-feasible search over the merge position [m]."""
_MIN_SPEED = 0.1  # [m/s] floor in the arrival-time prediction
_G_VIRTUAL = CONSTRAINTS.index("virtual_vehicle")


def merge_position(view: TrafficView, vr: int) -> tuple[float, float]:
    """Fixed merge position and lane-change duration of VR (no optimisation).

    Parameters
    ----------
    view : traffic snapshot.
    vr : VR's vehicle index.

    Returns
    -------
    merge_x : ``accel_lane_start + 10 m``, clipped to ``accel_lane_end - max(v T, 3 L)`` so the
        change predicted at VR's current speed ends on the acceleration lane, and to at least
        ``accel_lane_start`` [m].
    vr_duration : ``config.cav.lane_change_duration`` [s].
    """
    road = view.config.road
    merge_x = min(road.accel_lane_start + MERGE_OFFSET, last_merge_position(view, vr))
    return max(merge_x, road.accel_lane_start), float(view.config.cav.lane_change_duration)


def last_merge_position(view: TrafficView, vr: int) -> float:
    """The last merge position whose change, predicted at VR's current speed with the CAV
    default duration, ends on the acceleration lane: ``accel_lane_end - max(v T, 3 L)`` [m]
    (the engine's rule, :meth:`hcomc.sim.engine.Simulation._start_lane_changes`)."""
    cfg = view.config
    duration = float(cfg.cav.lane_change_duration)
    span = max(float(view.v[vr]) * duration, 3.0 * float(view.fleet.length[vr]))
    return float(cfg.road.accel_lane_end - span)


def arrival_times(view: TrafficView, group: MergeGroup, merge_x: float) -> dict[str, float]:
    """Predicted arrival time at ``merge_x`` of VR, VMC and VMF, constant speed [s, absolute].

    ``t_i = t0 + (x_m - x_i) / max(v_i, 0.1)`` (Ntousakis et al. 2016, FIFO rule). Missing
    vehicles are left out; a vehicle already past ``merge_x`` gets a time <= t0.
    """
    out: dict[str, float] = {}
    for role, i in (("VR", group.vr), ("VMC", group.vmc), ("VMF", group.vmf)):
        if i >= 0:
            out[role] = view.t + (merge_x - float(view.x[i])) / max(float(view.v[i]), _MIN_SPEED)
    return out


def reach_horizon(view: TrafficView, vr: int, merge_x: float) -> float:
    """VR's constant-speed time to reach ``merge_x``, clipped to ``[4 s, horizon_max]`` [s]."""
    h_max = float(view.config.control.horizon_max)
    t_reach = (merge_x - float(view.x[vr])) / max(float(view.v[vr]), _MIN_SPEED)
    return float(np.clip(t_reach, min(MIN_HORIZON, h_max), h_max))


def with_cooperation(problem: MergeProblem, cooperates: bool) -> MergeProblem:
    """Copy of ``problem`` in which the ``vmc`` role (the vehicle behind VR's slot) does or does
    not cooperate (follow VV1), in both sequences.

    The rollout (:func:`hcomc.control.hcomc.rollout.rollout`) makes the VMC role follow VV1 iff
    its ``KeyState.coop`` flag is set, so the flag is overridden on copies of the key states
    (the original problem and the simulation are untouched); the Eq. 15 delays still follow the
    vehicles' true kinds. This idealises an HDV's "yield" as tracking VV1, and models "not
    yield" of a CAV as plain car following.
    """

    def flagged(state: KeyState) -> KeyState:
        coop = state.coop.copy()
        coop[VMC] = cooperates
        return replace(state, coop=coop)

    ahead, behind = problem.states
    out = copy.copy(problem)
    out.state = flagged(ahead)
    out.states = (out.state, None if behind is None else flagged(behind))
    return out


def predict_longitudinal(
    problem: MergeProblem,
    merge_x: float,
    vr_duration: float,
    horizon: float,
    h_max: float,
    sequence: int = AHEAD,
) -> tuple[Prediction, float]:
    """Predict the candidate ``[merge_x, vr_duration, H, 0, sequence]``, refining H once.

    The first prediction uses ``horizon`` (constant-speed estimate); H is then replaced by the
    predicted time at which VR reaches ``merge_x`` (clipped to ``[4 s, h_max]``) and the
    candidate is predicted again if that differs by more than one prediction step.

    Returns
    -------
    prediction : :class:`~hcomc.control.hcomc.problem.Prediction` of the single row.
    horizon : the H used [s].
    """
    row = np.array([[merge_x, vr_duration, horizon, 0.0, float(sequence)]])
    pred = problem.predict(row)
    reached = np.flatnonzero(pred.X[0, :, VR] >= merge_x)
    if reached.size:
        h_new = float(np.clip(pred.t[reached[0]], min(MIN_HORIZON, h_max), h_max))
        if abs(h_new - horizon) > problem.dt:
            horizon = h_new
            row[0, 2] = horizon
            pred = problem.predict(row)
    return pred, float(horizon)


def virtual_vehicle_feasible(pred: Prediction, row: int = 0) -> bool:
    """Whether the virtual vehicles (VV0 of a CAV VR, VV1 of a cooperating vehicle) of the
    prediction's ``row`` are feasible (v >= 0, a >= -b_max)."""
    return bool(pred.G[row, _G_VIRTUAL] <= 0.0)


def _steps(first: float, last: float, step: float) -> FloatArray:
    """``first, first + step, ...`` up to ``last``, and ``last`` itself (one value if
    ``last <= first``)."""
    n = int(np.floor(max(last - first, 0.0) / step + 1e-9))
    values = first + step * np.arange(n + 1, dtype=np.float64)
    if values[-1] < last:
        values = np.append(values, last)
    out: FloatArray = values
    return out


def nearest_feasible(
    problem: MergeProblem,
    merge_x: float,
    vr_duration: float,
    horizon: float,
    h_max: float,
    x_last: float,
    sequence: int = AHEAD,
) -> tuple[float, float] | None:
    """The candidate nearest to ``(merge_x, horizon)`` whose virtual vehicles are feasible.

    The grid, in the order searched: the merge position ``merge_x`` with H = ``horizon`` +
    k :data:`HORIZON_STEP` (k = 1, 2, ...) and ``h_max``; then each merge position ``merge_x`` +
    i :data:`POSITION_STEP` (i = 1, 2, ...) up to ``x_last`` (and ``x_last`` itself), each with
    H = ``horizon`` + k :data:`HORIZON_STEP` (k = 0, 1, ...) and ``h_max``. The candidates are
    scored in one call of :meth:`MergeProblem.evaluate
    <hcomc.control.hcomc.problem.MergeProblem.evaluate>` (longitudinal, ``sequence``); only
    the virtual-vehicle constraint is asked of them, the criterion of the rule's own candidate.

    Returns
    -------
    (merge_x, H) of the first feasible candidate [m, s], or None when none is feasible.
    """
    positions = _steps(merge_x, max(x_last, merge_x), POSITION_STEP)
    horizons = _steps(horizon, max(h_max, horizon), HORIZON_STEP)
    grid = np.array([(x, h) for x in positions for h in horizons])[1:]  # the rule's one tried
    if grid.size == 0:
        return None
    rows = np.column_stack(
        [grid[:, 0], np.full(len(grid), vr_duration), grid[:, 1],
         np.zeros(len(grid)), np.full(len(grid), float(sequence))]
    )  # fmt: skip
    _, G = problem.evaluate(rows)
    ok = np.flatnonzero(G[:, _G_VIRTUAL] <= 0.0)
    if ok.size == 0:
        return None
    return float(grid[ok[0], 0]), float(grid[ok[0], 1])


def feasible_candidate(
    view: TrafficView,
    vr: int,
    problem: MergeProblem,
    merge_x: float,
    vr_duration: float,
    sequence: int = AHEAD,
) -> tuple[Prediction, float, float, tuple[float, float]]:
    """The rule's candidate (:func:`predict_longitudinal` at the fixed merge position), moved
    to the :func:`nearest_feasible` one when its virtual vehicles are infeasible.

    Returns
    -------
    prediction : of the candidate executed (the rule's own if no candidate is feasible).
    merge_x, horizon : of that candidate [m, s].
    nominal : the rule's own (merge_x, H) [m, s].
    """
    h_max = float(view.config.control.horizon_max)
    pred, horizon = predict_longitudinal(
        problem, merge_x, vr_duration, reach_horizon(view, vr, merge_x), h_max, sequence
    )
    nominal = (merge_x, horizon)
    if virtual_vehicle_feasible(pred):
        return pred, merge_x, horizon, nominal
    found = nearest_feasible(
        problem, merge_x, vr_duration, horizon, h_max, last_merge_position(view, vr), sequence
    )
    if found is None:
        return pred, merge_x, horizon, nominal
    x, h = found
    row = np.array([[x, vr_duration, h, 0.0, float(sequence)]])
    return problem.predict(row), x, h, nominal


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


class PredictingBaseline:
    """Shared part of the baselines: HCOMC's merge problem (both sequences, longitudinal only)
    used as a predictor of the one candidate the baseline's rule picks."""

    def __init__(self, config: ScenarioConfig) -> None:
        load_prediction_kernels()
        self.config = config

    def problem(self, view: TrafficView, group: MergeGroup) -> MergeProblem:
        """The longitudinal-only merge problem of ``group`` and of its "behind" group."""
        return merge_problem(view, group)


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
