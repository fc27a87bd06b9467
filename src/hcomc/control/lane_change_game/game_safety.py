r"""The safety term :math:`J_s` of both games: the lane-change game (paper Section III-B) and
the merge game of the Game baseline (:mod:`hcomc.control.merge_game`).

One function, :func:`safety_term`, maps Eq. 15's critical acceleration
:math:`U_{safe} = a_{cr}` (:func:`hcomc.equations.safety.critical_acceleration`) to the cost

.. math:: J_s = U_{safe} / a_{merg},

linear and not capped, with :math:`a_{merg}` Eq. 15's emergency deceleration
(``control.safety_emergency_decel``): the share of an emergency stop the worst follower would
need. An infeasible joint action (an unavoidable crash, :math:`U_{safe} = \infty`, or whatever
else a game declares infeasible through ``infeasible``) costs :data:`INFEASIBLE_SAFETY_COST`.
The paper gives neither game's payoff formula (the lane-change game's reference [20] is known
only by its abstract; Eq. 15 defines the safety *index* and Eq. 19 compares it with 4 m/s^2
when selecting among Pareto solutions, not inside a payoff), so nothing in it asks for a cap;
a cap at the Eq. 19 threshold saturates at highway speed (docs/models.md, Game baseline).

The capped form :math:`\min(1, U_{safe}/a_{th})` is kept only as the opt-in variant
``form="capped"`` of the merge game's controller ``game-capped``.

Both games call this function through the module (``game_safety.safety_term``), so it has one
home and replacing it replaces it in both.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from hcomc._typing import FloatArray

__all__ = ["INFEASIBLE_SAFETY_COST", "SAFETY_TERMS", "safety_term"]

INFEASIBLE_SAFETY_COST: float = 10.0
"""J_s of an infeasible joint action (overlap, unavoidable crash, ...) [-]: ten emergency
stops' worth, which no feasible action's weighted cost reaches."""

SAFETY_TERMS: tuple[str, ...] = ("linear", "capped")
"""Forms of :func:`safety_term`: ``"linear"`` U_safe / a_merg (both games), ``"capped"``
min(1, U_safe / threshold) (only the merge-game variant ``game-capped``)."""


def safety_term(
    u_safe: ArrayLike,
    emergency_decel: float,
    *,
    infeasible: ArrayLike = False,
    form: str = "linear",
    threshold: float | None = None,
) -> FloatArray:
    r"""Safety term :math:`J_s` of a joint action from its Eq. 15 critical acceleration.

    Parameters
    ----------
    u_safe : array_like
        :math:`U_{safe} = a_{cr}` [m/s^2], the worst Eq. 15 value of the action's
        follower-leader pairs (``+inf``: no deceleration avoids the crash).
    emergency_decel : float
        :math:`a_{merg}` [m/s^2], positive.
    infeasible : array_like of bool, optional
        Where the game declares the action infeasible for reasons of its own (broadcast
        against ``u_safe``).
    form : {"linear", "capped"}
        ``"linear"`` :math:`U_{safe}/a_{merg}` (the term of both games), ``"capped"``
        :math:`\min(1, U_{safe}/a_{th})` (the variant ``game-capped``; needs ``threshold``).
    threshold : float, optional
        :math:`a_{th}` [m/s^2] of the capped form.

    Returns
    -------
    numpy.ndarray
        :math:`J_s` [-], float64, broadcast shape (0-d for scalars);
        :data:`INFEASIBLE_SAFETY_COST` where ``infeasible`` or ``u_safe`` is not finite.

    Examples
    --------
    >>> float(safety_term(3.75, 7.5))
    0.5
    >>> float(safety_term(float("inf"), 7.5))
    10.0
    """
    if form not in SAFETY_TERMS:
        raise ValueError(f"safety = {form!r}: allowed {', '.join(map(repr, SAFETY_TERMS))}")
    u = np.asarray(u_safe, dtype=np.float64)
    bad = np.asarray(infeasible, dtype=bool) | ~np.isfinite(u)
    u_ok = np.where(bad, 0.0, u)
    if form == "capped":
        if threshold is None or not threshold > 0.0:
            raise ValueError(f"the capped safety term needs a threshold > 0, got {threshold!r}")
        j_s = np.minimum(1.0, u_ok / threshold)
    else:
        j_s = u_ok / emergency_decel
    return np.asarray(np.where(bad, INFEASIBLE_SAFETY_COST, j_s), dtype=np.float64)
