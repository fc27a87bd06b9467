"""Commitment of a replanning HCOMC: keep the live plan's cooperation unless a new plan is
clearly better.

The paper plans a merge once; a receding horizon (remaking the plan every second until VR
starts its lane change) lets the plan follow the traffic, but a plain re-optimisation also
lets it flip: the vehicle told to open a gap can change from one plan to the next, and with
it the sequence, so that one vehicle brakes for a while and then another. The rule here (an
assumption of ours, the paper being silent on replanning) keeps what the live plan commits
the traffic to — which vehicle VR merges in front of, and that vehicle's cooperation mode —
unless

* no candidate with that commitment is feasible any more, or
* the best new candidate's Eq. 19 cost is lower than the best committed one's by more than
  ``control.commitment_margin``.

The candidates are the optimiser's Pareto set plus the live plan continued (its merge
position, duration and remaining horizon, re-predicted from now) and the same cooperation on
a small grid of merge positions and horizons, and Eq. 19's cost is taken over that pool
(:func:`hcomc.equations.selection.eq19_costs`: min-max normalised, so the margin is a share of
the pool's range: 0.2 of the [0, 2] range of the two normalised costs).
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
    another form be kept even when the optimiser did not search near it."""
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
    positions = [live.merge_x, *np.linspace(xl[0], xu[0], GRID_POSITIONS)]
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
    row : index of the chosen row in the pool.
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
    """Apply the commitment rule to the feasible candidates ``pool`` = (X, F, feasible)."""
    X, F, feasible = pool
    costs = eq19_costs(F, OBJECTIVES, feasible=feasible, safety_threshold=problem.safety.threshold)
    best = int(np.argmin(costs))
    promise = commitment_of(live)
    seqs, modes = _executed_rows(view, groups, problem, X)
    committed = np.array(
        [bool(ok) and (groups[seq].vmc, mode) == promise
         for ok, seq, mode in zip(feasible, seqs, modes, strict=True)]
    )  # fmt: skip
    if not committed.any():
        return Choice(best, False, np.inf, "switched: no feasible candidate keeps the cooperation")
    keep = int(np.flatnonzero(committed)[np.argmin(costs[committed])])
    excess = float(costs[keep] - costs[best])
    if excess <= margin:
        return Choice(keep, True, excess, "kept")
    if np.isinf(excess):
        gate = f"U_safe > {problem.safety.threshold:g} m/s² (Eq. 19's gate)"
        return Choice(best, False, excess, f"switched: every candidate keeping it has {gate}")
    return Choice(best, False, excess, f"switched: Eq. 19 cost lower by {excess:.3g}")
