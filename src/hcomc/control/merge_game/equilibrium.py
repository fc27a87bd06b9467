r"""Solution of the 2x2 merge game (Kita 1999): pure Nash equilibria, Kita's mixed
equilibrium, and the cooperative cell.

The game of :mod:`hcomc.control.merge_game` is played on cost matrices, rows the ramp
vehicle's actions (merge :data:`AHEAD` of / :data:`BEHIND` VMC), columns the lag vehicle's
(:data:`YIELD` / :data:`NOT_YIELD`). :func:`solve_merge_game` plays it: the joint-optimal cell
when VMC is a CAV (:func:`hcomc.control.lane_change_game.solvers.solve_cooperative`), else a
pure Nash equilibrium (:func:`pure_nash`; among several the largest payoff sum, ties to the
first in row-major order), else a draw from Kita's closed-form mixed equilibrium
(:func:`kita_mixed`).

References
----------
.. [1] H. Kita, "A merging-giveway interaction model of cars in a merging section: a game
   theoretic analysis", Transportation Research Part A 33 (1999) 305-312.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from hcomc._typing import FloatArray
from hcomc.control.lane_change_game.solvers import solve_cooperative

__all__ = [
    "AHEAD",
    "BEHIND",
    "NOT_YIELD",
    "YIELD",
    "GameOutcome",
    "kita_mixed",
    "pure_nash",
    "solve_merge_game",
]

AHEAD, BEHIND = 0, 1
"""VR's actions (rows): merge ahead of / behind VMC."""

YIELD, NOT_YIELD = 0, 1
"""The lag vehicle's actions (columns)."""


@dataclass(frozen=True)
class GameOutcome:
    """Solution of the 2x2 merge game.

    Attributes
    ----------
    row, col : the played actions (VR: AHEAD/BEHIND; lag vehicle: YIELD/NOT_YIELD).
    kind : "cooperative", "pure" or "mixed".
    pure : all pure Nash equilibria (row, col) (empty for the cooperative solution).
    p, q : Kita's mixed equilibrium, P(row AHEAD) and P(col YIELD) (NaN unless "mixed").
    """

    row: int
    col: int
    kind: str
    pure: tuple[tuple[int, int], ...] = ()
    p: float = float("nan")
    q: float = float("nan")


def _matrix(name: str, value: ArrayLike) -> FloatArray:
    arr = np.array(value, dtype=np.float64)
    if arr.shape != (2, 2) or np.isnan(arr).any():
        raise ValueError(f"{name} must be a 2x2 array without NaN, got {arr!r}")
    return arr


def pure_nash(A: ArrayLike, B: ArrayLike) -> list[tuple[int, int]]:
    """Pure Nash equilibria of the bimatrix game (A row payoffs, B column payoffs; maximised).

    A cell (i, j) is an equilibrium when neither player gains by deviating alone:
    ``A[i, j] >= A[1 - i, j]`` and ``B[i, j] >= B[i, 1 - j]`` (weak inequalities). Returned in
    row-major order.

    Examples
    --------
    >>> pure_nash([[3, 0], [5, 1]], [[3, 5], [0, 1]])  # prisoner's dilemma
    [(1, 1)]
    """
    a, b = _matrix("A", A), _matrix("B", B)
    return [
        (i, j)
        for i in range(2)
        for j in range(2)
        if a[i, j] >= a[1 - i, j] and b[i, j] >= b[i, 1 - j]
    ]


def kita_mixed(A: ArrayLike, B: ArrayLike) -> tuple[float, float]:
    r"""Kita's closed-form mixed equilibrium of a 2x2 game.

    .. math::
       q^* = \frac{a_{22} - a_{12}}{a_{11} - a_{12} - a_{21} + a_{22}},\qquad
       p^* = \frac{b_{22} - b_{21}}{b_{11} - b_{12} - b_{21} + b_{22}}

    :math:`q^*` is the column player's probability of its first action that makes the row
    player indifferent, :math:`p^*` the row player's probability of its first action that makes
    the column player indifferent (indices 1-based as in Kita 1999). The values are clipped to
    [0, 1]; a zero denominator (a player indifferent whatever the other does) gives 0.5.

    Returns
    -------
    p, q : P(row 0), P(column 0).

    Examples
    --------
    >>> kita_mixed([[1, -1], [-1, 1]], [[-1, 1], [1, -1]])  # matching pennies
    (0.5, 0.5)
    """
    a, b = _matrix("A", A), _matrix("B", B)
    den_q = a[0, 0] - a[0, 1] - a[1, 0] + a[1, 1]
    den_p = b[0, 0] - b[0, 1] - b[1, 0] + b[1, 1]
    q = (a[1, 1] - a[0, 1]) / den_q if den_q != 0.0 else 0.5
    p = (b[1, 1] - b[1, 0]) / den_p if den_p != 0.0 else 0.5
    return float(np.clip(p, 0.0, 1.0)), float(np.clip(q, 0.0, 1.0))


def solve_merge_game(
    J_row: ArrayLike, J_col: ArrayLike, *, cooperative: bool, rng: np.random.Generator
) -> GameOutcome:
    """Play the 2x2 merge game on costs (payoffs are their negatives).

    Parameters
    ----------
    J_row, J_col : (2, 2) costs of VR and of the lag vehicle, rows = VR's action.
    cooperative : True for a CAV VMC — the joint-optimal cell
        (:func:`hcomc.control.lane_change_game.solvers.solve_cooperative`); False — a pure Nash
        equilibrium (largest payoff sum, ties to row-major order) or, if none exists, a draw
        from Kita's mixed equilibrium (row action first, then column action, two
        ``rng.random()`` calls).
    rng : used only for the mixed equilibrium.
    """
    jr, jc = _matrix("J_row", J_row), _matrix("J_col", J_col)
    if cooperative:
        sol = solve_cooperative(jr, jc)
        return GameOutcome(sol.sv_action, int(sol.fv_response[sol.sv_action, 0]), "cooperative")
    A, B = -jr, -jc
    pure = pure_nash(A, B)
    if pure:
        welfare = [A[i, j] + B[i, j] for i, j in pure]
        row, col = pure[int(np.argmax(welfare))]
        return GameOutcome(row, col, "pure", tuple(pure))
    p, q = kita_mixed(A, B)
    row = AHEAD if rng.random() < p else BEHIND
    col = YIELD if rng.random() < q else NOT_YIELD
    return GameOutcome(row, col, "mixed", (), p, q)
