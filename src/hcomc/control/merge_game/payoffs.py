r"""Payoffs of the 2x2 merge game: each player's cost :math:`J = w_s J_s + w_e J_e + w_c J_c`
over a predicted joint action.

:func:`safety_term` is the safety term :math:`J_s` of a predicted joint action: the merge game's
infeasibility rules, then the term both games share,
:func:`hcomc.control.lane_change_game.game_safety.safety_term` (linear in Eq. 15's U_safe, or the
capped variant; :data:`INFEASIBLE_SAFETY` for an infeasible prediction), :func:`player_cost`
adds a player's efficiency and comfort terms with its weights (:data:`CAV_WEIGHTS`,
:data:`NORMAL_WEIGHTS`). The module docstring of :mod:`hcomc.control.merge_game` states the
terms, the weights and why the safety term is linear.
"""

from __future__ import annotations

import numpy as np

from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import CONSTRAINTS, Prediction
from hcomc.control.lane_change_game import game_safety
from hcomc.control.lane_change_game.game_safety import INFEASIBLE_SAFETY_COST, SAFETY_TERMS
from hcomc.control.longitudinal_candidate import virtual_vehicle_feasible

__all__ = [
    "CAV_WEIGHTS",
    "INFEASIBLE_SAFETY",
    "NORMAL_WEIGHTS",
    "SAFETY_TERMS",
    "player_cost",
    "safety_term",
]

CAV_WEIGHTS = (0.5, 0.3, 0.2)
"""(w_s, w_e, w_c) of a CAV ramp vehicle."""

NORMAL_WEIGHTS = (0.4, 0.4, 0.2)
"""(w_s, w_e, w_c) of the "normal" driving type (Hang et al. 2021)."""

INFEASIBLE_SAFETY = INFEASIBLE_SAFETY_COST
"""J_s of an infeasible prediction (collision, unavoidable crash, infeasible VV1) [-]; the
same cost the lane-change game gives an infeasible action."""

_G = {name: i for i, name in enumerate(CONSTRAINTS)}


def player_cost(
    pred: Prediction,
    problem: MergeProblem,
    role: int,
    weights: tuple[float, float, float],
    j_s: float,
    row: int = 0,
) -> tuple[float, dict[str, float]]:
    """Cost ``w_s J_s + w_e J_e + w_c J_c`` of the key vehicle in ``role``.

    ``J_e = mean |v - v0| / v0`` and ``J_c = mean a^2 / a_max^2`` over the prediction window,
    with the vehicle's desired speed and maximum-acceleration parameters; ``j_s`` is the shared
    safety term. An absent vehicle costs 0.

    Returns
    -------
    cost : J [-].
    terms : {"J_s", "J_e", "J_c"}.
    """
    s = problem.states[int(pred.sequence[row])] or problem.state
    if not s.present[role]:
        return 0.0, {"J_s": 0.0, "J_e": 0.0, "J_c": 0.0}
    v0, a_max = s.desired_speed(role), s.max_accel(role)
    j_e = float(np.mean(np.abs(pred.V[row, :, role] - v0)) / v0)
    j_c = float(np.mean(pred.A[row, :, role] ** 2) / a_max**2)
    w_s, w_e, w_c = weights
    return w_s * j_s + w_e * j_e + w_c * j_c, {"J_s": j_s, "J_e": j_e, "J_c": j_c}


def safety_term(
    pred: Prediction,
    problem: MergeProblem,
    u_safe: float,
    safety: str = "linear",
    row: int = 0,
) -> float:
    """Safety term ``J_s`` of one predicted joint action (module docstring).

    The term both games share,
    :func:`hcomc.control.lane_change_game.game_safety.safety_term`:
    ``u_safe / a_merg`` (``safety="linear"``; ``a_merg`` = ``control.safety_emergency_decel``)
    or ``min(1, u_safe / threshold)`` (``"capped"``; ``control.safety_threshold``), or
    :data:`INFEASIBLE_SAFETY` when the prediction has a collision, VR not merged, an
    unavoidable crash (``u_safe`` infinite), an infeasible virtual vehicle, or a present key
    vehicle braking harder than Eq. 15's emergency deceleration ``a_merg``.
    """
    if safety not in SAFETY_TERMS:
        raise ValueError(f"safety = {safety!r}: allowed {', '.join(map(repr, SAFETY_TERMS))}")
    g = pred.G[row]
    present = (problem.states[int(pred.sequence[row])] or problem.state).present
    a_min = float(pred.A[row][:, present].min())
    a_merg = problem.safety.emergency_decel
    infeasible = (
        g[_G["collision"]] > 0.0
        or g[_G["not_merged"]] > 0.0
        or not np.isfinite(u_safe)
        or not virtual_vehicle_feasible(pred, row)
        or a_min < -a_merg
    )
    j_s = game_safety.safety_term(
        u_safe, a_merg, infeasible=infeasible, form=safety, threshold=problem.safety.threshold
    )
    return float(j_s)
