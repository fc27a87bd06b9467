"""Commitment of a replanning HCOMC: keep the live plan's cooperation while it stays
feasible and safe.

The paper plans a merge once; a receding horizon (remaking the plan every second until VR
starts its lane change) lets the plan follow the traffic, but a plain re-optimisation also
lets it flip: the vehicle told to open a gap can change from one plan to the next, and with
it the sequence, so that one vehicle brakes for a while and then another. The rule here (an
assumption of ours, the paper being silent on replanning) keeps what the live plan commits
the traffic to — which vehicle VR merges in front of, and that vehicle's cooperation mode —
unless

* no candidate with that commitment is feasible any more,
* every feasible one fails Eq. 19's safety gate (U_safe above the threshold while another
  candidate is below it), or
* the best new candidate's Eq. 19 cost is lower than the best committed one's by more than
  ``control.commitment_margin``. Its default, 2, is the whole range of the cost, so that a
  replan never switches for cost alone: replanning corrects the committed plan for what the
  traffic did differently from its prediction (the merge position, duration and horizon are
  optimised again), and re-chooses the cooperation only when that plan can no longer be
  carried out or is no longer safe, as the one plan of the paper is carried out.

The candidates are the optimiser's Pareto set plus the live plan continued (its merge
position, duration and remaining horizon, re-predicted from now) and the same cooperation on
a small grid of merge positions and horizons, and Eq. 19's cost is taken over that pool
(:func:`hcomc.equations.selection.eq19_costs`: min-max normalised, so the margin is a share of
the pool's range, the [0, 2] range of the two normalised costs).

No drift toward the lane end (HCOMC-R, a problem made with ``replanning``): a replan may not
move the merge position of the committed cooperation further downstream than the live
plan's (:func:`merge_bound`; VR already past it: than the first position it can still start
at). Candidates keeping the cooperation beyond it are not feasible in the pool, and the grid
of :func:`continuations` spans the positions up to it. Without the bound each replan could
postpone the merge a little, until the plan lies past the point of no return. And once VR has
reached the live plan's merge position, where the engine executes the plan (and replans at
once, before its first attempt), a replan keeps the live cooperation whenever a feasible
candidate keeps it (:func:`at_merge_position`): it does not switch at the moment of execution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import AHEAD, MODE_NONE, OBJECTIVES
from hcomc.equations.selection import eq19_costs
from hcomc.interface import MergeGroup, MergePlan, Mode, TrafficView

Commitment = tuple[int, Mode]
"""What a plan commits the traffic to: the vehicle VR merges in front of (-1: none) and that
vehicle's cooperation mode."""


def executed(
    view: TrafficView, groups: tuple[MergeGroup, MergeGroup], problem: MergeProblem, x: FloatArray
) -> tuple[int, MergeGroup, Mode]:
    """The sequence, executed key group and cooperation mode of the candidate row ``x``."""
    (seq,), (mode,) = _executed_rows(view, groups, problem, np.atleast_2d(x))
    return seq, groups[seq], mode


def _executed_rows(
    view: TrafficView, groups: tuple[MergeGroup, MergeGroup], problem: MergeProblem, X: FloatArray
) -> tuple[list[int], list[Mode]]:
    """Sequences and cooperation modes of the rows ``X``: the cooperating vehicle
    (``group.vmc`` of the sequence's group) cooperates only if it is a CAV and the row's mode
    is not "none"."""
    seqs = problem.sequences(X).tolist()
    modes = [
        Mode.NONE
        if name == "none" or not view.is_cav(groups[seq].vmc)
        else Mode.LATERAL
        if name == "lateral"
        else Mode.LONGITUDINAL
        for seq, name in zip(seqs, problem.modes(X), strict=True)
    ]
    return seqs, modes


def commitment_of(plan: MergePlan) -> Commitment:
    """What the live ``plan`` commits the traffic to."""
    return plan.group.vmc, plan.mode


GRID_POSITIONS = 5
"""Merge positions of the committed grid of :func:`continuations`."""
GRID_HORIZONS = 3
"""Horizons of the committed grid of :func:`continuations`, besides the continued one."""


def merge_bound(live: MergePlan, problem: MergeProblem) -> float:
    """The most downstream merge position a replan may give the live plan's cooperation [m]:
    the live plan's, or the lower bound of the problem's merge position (VR's next position)
    when VR is already past it (its change was refused there); ``inf`` when the problem is
    not a replanning HCOMC's (``problem.replan_period`` 0) or the live plan has no merge
    position."""
    if problem.replan_period <= 0.0 or not np.isfinite(live.merge_x):
        return np.inf
    return max(float(live.merge_x), float(problem.xl[0]))


def at_merge_position(view: TrafficView, live: MergePlan, problem: MergeProblem) -> bool:
    """Whether a replan of HCOMC-R (``problem.replan_period`` > 0) comes when VR has reached
    the live plan's merge position: the engine executes the live plan from there on, and it
    replans at the first step there, before its first attempt, as it does after a refusal.
    Such a replan only continues the live cooperation (from VR's next position) unless no
    feasible candidate keeps it: switching then would race the change the engine is about
    to start."""
    if problem.replan_period <= 0.0 or not np.isfinite(live.merge_x):
        return False
    return bool(view.x[live.group.vr] >= live.merge_x)


def continuations(
    live: MergePlan, groups: tuple[MergeGroup, MergeGroup], problem: MergeProblem, t: float
) -> FloatArray | None:
    """Candidate rows of ``problem`` that keep the live plan's commitment: the live plan
    continued (its merge position and duration, the rest of its horizon), then the same
    cooperation on a small grid of merge positions (:data:`GRID_POSITIONS` evenly over the
    bounds) and horizons (the continued one and :data:`GRID_HORIZONS` evenly over the
    bounds), all with its mode and the sequence whose group has the same cooperating vehicle,
    clipped to the bounds. None when that vehicle is no longer next to VR's slot or the plan
    has no merge position (a fallback). The grid lets a cooperation that is still possible in
    another form be kept even when the optimiser did not search near it. For HCOMC-R the grid
    of positions ends at :func:`merge_bound` (no drift downstream)."""
    seqs = [s for s, g in enumerate(groups) if g.vmc == live.group.vmc]
    if live.mode == Mode.LATERAL:
        seqs = [s for s in seqs if s == AHEAD]  # a lateral row is rolled out "ahead"
    if not seqs or not np.isfinite(live.merge_x):
        return None
    mode = {Mode.LONGITUDINAL: 0.25, Mode.LATERAL: 0.75, Mode.NONE: 0.25}[live.mode]
    if live.mode == Mode.NONE and problem.no_cooperation and live.group.vmc >= 0:
        mode = MODE_NONE + 0.25
    xl, xu = problem.xl, problem.xu
    horizon = live.horizon - (t - live.t0)
    last = min(float(xu[0]), merge_bound(live, problem))
    positions = [live.merge_x, *np.linspace(xl[0], max(last, xl[0]), GRID_POSITIONS)]
    horizons = [horizon, *np.linspace(xl[2], xu[2], GRID_HORIZONS)]
    rows = [[live.merge_x, live.vr_duration, horizon, mode, seqs[0]]]
    rows += [[x, live.vr_duration, h, mode, seqs[0]] for x in positions[1:] for h in horizons]
    out: FloatArray = np.clip(np.array(rows), xl, xu)
    return out


@dataclass(frozen=True, slots=True)
class Choice:
    """The commitment rule's pick among a candidate pool.

    Attributes
    ----------
    row : index of the chosen row in the pool (-1: none is left, HCOMC-R's bound of
        :func:`merge_bound` having ruled out every feasible one).
    kept : the chosen row keeps the live plan's commitment.
    margin : Eq. 19 cost of the best committed row minus that of the best row (inf: no
        committed row is feasible, or none passes Eq. 19's safety gate while another does).
    why : what the rule did, in words: "kept", or "switched: " and the reason.
    """

    row: int
    kept: bool
    margin: float
    why: str


def choose(
    view: TrafficView,
    groups: tuple[MergeGroup, MergeGroup],
    problem: MergeProblem,
    pool: tuple[FloatArray, FloatArray, np.ndarray],
    live: MergePlan,
    margin: float,
) -> Choice:
    """Apply the commitment rule to the feasible candidates ``pool`` = (X, F, feasible).

    For HCOMC-R a candidate keeping the live cooperation with its merge position beyond
    :func:`merge_bound` counts as not feasible (no drift downstream), and once VR has reached
    the live plan's merge position (:func:`at_merge_position`) the live cooperation is kept
    whenever a feasible candidate keeps it and passes Eq. 19's gate as well as the best,
    whatever the margin."""
    X, F, feasible = pool
    promise = commitment_of(live)
    seqs, modes = _executed_rows(view, groups, problem, X)
    same = np.array(
        [(groups[seq].vmc, mode) == promise for seq, mode in zip(seqs, modes, strict=True)],
        dtype=bool,
    )
    drifts = same & (X[:, 0] > merge_bound(live, problem))
    if drifts.any():
        feasible = np.asarray(feasible, dtype=bool) & ~drifts
        if not feasible.any():
            return Choice(-1, False, np.inf, "switched: no feasible candidate")
    costs = eq19_costs(F, OBJECTIVES, feasible=feasible, safety_threshold=problem.safety.threshold)
    best = int(np.argmin(costs))
    committed = np.asarray(feasible, dtype=bool) & same
    if not committed.any():
        return Choice(best, False, np.inf, "switched: no feasible candidate keeps the cooperation")
    keep = int(np.flatnonzero(committed)[np.argmin(costs[committed])])
    excess = float(costs[keep] - costs[best])
    if excess <= margin:
        return Choice(keep, True, excess, "kept")
    if at_merge_position(view, live, problem) and np.isfinite(excess):
        return Choice(keep, True, excess, "kept")  # VR at its merge position
    if np.isinf(excess):
        gate = f"U_safe > {problem.safety.threshold:g} m/s² (Eq. 19's gate)"
        return Choice(best, False, excess, f"switched: every candidate keeping it has {gate}")
    return Choice(best, False, excess, f"switched: Eq. 19 cost lower by {excess:.3g}")
