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
position, duration and remaining horizon, re-predicted from now), and Eq. 19's cost is taken
over that pool (:func:`hcomc.optim.selection.eq19_costs`: min-max normalised, so the margin
is a share of the pool's range: 0.2 of the [0, 2] range of the two normalised costs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray
from hcomc.control.base import MergeGroup, MergePlan, Mode, TrafficView
from hcomc.control.hcomc.problem import AHEAD, MODE_NONE, OBJECTIVES, MergeProblem
from hcomc.optim.selection import eq19_costs

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


def continuation(
    live: MergePlan, groups: tuple[MergeGroup, MergeGroup], problem: MergeProblem, t: float
) -> FloatArray | None:
    """The live plan as a candidate row of ``problem`` (its merge position and duration, the
    rest of its horizon, its mode and the sequence whose group has the same cooperating
    vehicle), clipped to the bounds; None when that vehicle is no longer next to VR's slot
    or the plan has no merge position (a fallback)."""
    seqs = [s for s, g in enumerate(groups) if g.vmc == live.group.vmc]
    if live.mode == Mode.LATERAL:
        seqs = [s for s in seqs if s == AHEAD]  # a lateral row is rolled out "ahead"
    if not seqs or not np.isfinite(live.merge_x):
        return None
    mode = {Mode.LONGITUDINAL: 0.25, Mode.LATERAL: 0.75, Mode.NONE: 0.25}[live.mode]
    if live.mode == Mode.NONE and problem.no_cooperation and live.group.vmc >= 0:
        mode = MODE_NONE + 0.25
    row = np.array([live.merge_x, live.vr_duration, live.horizon - (t - live.t0), mode, seqs[0]])
    out: FloatArray = np.clip(row, problem.xl, problem.xu)
    return out


@dataclass(frozen=True, slots=True)
class Choice:
    """The commitment rule's pick among a candidate pool.

    Attributes
    ----------
    row : index of the chosen row in the pool.
    kept : the chosen row keeps the live plan's commitment.
    margin : Eq. 19 cost of the best committed row minus that of the best row (inf: no
        committed row is feasible; nan: nothing was live).
    """

    row: int
    kept: bool
    margin: float


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
        return Choice(best, False, np.inf)
    keep = int(np.flatnonzero(committed)[np.argmin(costs[committed])])
    excess = float(costs[keep] - costs[best])
    if excess <= margin:
        return Choice(keep, True, excess)
    return Choice(best, False, excess)
