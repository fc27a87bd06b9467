r"""Generic solvers for the two-player lane-change game (paper Section III-B).

The discretionary lane-change model of the HCOMC paper (Section III-B) lets the subject vehicle
SV (the Stackelberg *leader*) choose an action knowing that the follower FV in the target lane
best-responds to it. An HDV follower's driving style is private information; following Harsanyi,
the style is a *type* θ drawn from a common prior :math:`p_\theta`, and the types' pure best
responses induce the "mixed-strategy probability distribution of FV" of the paper. SV minimises
the expectation of its own cost under that distribution. A CAV follower cooperates instead
(docs/models.md): both vehicles minimise the sum of their costs.

The functions here are pure and work on cost arrays only (lower is better); the traffic-specific
cost construction lives in :mod:`hcomc.control.lane_change_game.decision`.

Array conventions: ``S`` SV actions, ``F`` FV actions, ``n_types`` FV types.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-B.
.. [2] docs/models.md, lane-change game.
.. [3] J. C. Harsanyi, "Games with incomplete information played by 'Bayesian' players, I-III",
   Management Science 14 (1967-68).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from hcomc._typing import FloatArray, IntArray

__all__ = ["GameSolution", "solve_cooperative", "solve_stackelberg_harsanyi"]

PRIOR_TOLERANCE: float = 1e-9
"""Allowed deviation of ``sum(prior)`` from 1 [-]."""


@dataclass(frozen=True)
class GameSolution:
    """Equilibrium of a lane-change game.

    Attributes
    ----------
    sv_action : int
        SV's equilibrium action (index into the SV action set).
    expected_cost : numpy.ndarray
        Shape ``(S,)``. Stackelberg-Harsanyi: SV's expected cost of each SV action under FV's
        induced mixed strategy. Cooperative: the minimal joint cost (SV + FV) of each SV action.
    fv_response : numpy.ndarray
        Shape ``(S, n_types)``, integer. FV's best response to each SV action, per type (a
        single column for the cooperative solution).
    fv_mixed : numpy.ndarray
        Shape ``(S, F)``. FV's (mixed) strategy σ(f | s); each row sums to 1.
    cooperative : bool
        True for :func:`solve_cooperative`, False for :func:`solve_stackelberg_harsanyi`.
    """

    sv_action: int
    expected_cost: FloatArray
    fv_response: IntArray
    fv_mixed: FloatArray
    cooperative: bool


def _as_cost(name: str, value: ArrayLike, ndims: tuple[int, ...]) -> FloatArray:
    """Float64 copy of a cost array with one of the allowed ranks and no NaN/empty axis."""
    arr = np.array(value, dtype=np.float64)
    if arr.ndim not in ndims:
        allowed = " or ".join(f"{d}-D" for d in ndims)
        raise ValueError(f"{name} must be {allowed}, got shape {arr.shape}")
    if 0 in arr.shape:
        raise ValueError(f"{name} must not have an empty axis, got shape {arr.shape}")
    if np.isnan(arr).any():
        raise ValueError(f"{name} contains NaN")
    return arr


def solve_stackelberg_harsanyi(
    sv_cost: ArrayLike, fv_cost: ArrayLike, prior: ArrayLike
) -> GameSolution:
    r"""Stackelberg equilibrium with a Harsanyi-typed follower (paper §III-B).

    1. Follower best response of each type θ to each leader action s (ties to the lowest f):
       :math:`BR_\theta(s) = \arg\min_f J_{FV}^\theta(s, f)`.
    2. Induced mixed strategy of FV:
       :math:`\sigma(f \mid s) = \sum_\theta p_\theta\,\mathbb 1[f = BR_\theta(s)]`.
    3. SV's expected cost
       :math:`E(s) = \sum_\theta p_\theta\,J_{SV}(s, BR_\theta(s), \theta)`, which equals
       :math:`\sum_f \sigma(f \mid s) J_{SV}(s, f)` when SV's cost does not depend on the type;
       SV plays :math:`s^* = \arg\min_s E(s)` (ties to the lowest s).

    Parameters
    ----------
    sv_cost : array_like, shape (S, F) or (S, F, n_types)
        SV cost of each joint action, optionally per FV type. ``+inf`` is allowed, NaN is not.
    fv_cost : array_like, shape (S, F, n_types)
        FV cost of each joint action for each type. ``+inf`` is allowed, NaN is not.
    prior : array_like, shape (n_types,)
        Prior probabilities of the types, non-negative and summing to 1 (tolerance 1e-9).
        The paper gives no prior; docs/models.md suggests (0.25, 0.5, 0.25).

    Returns
    -------
    GameSolution
        With ``cooperative = False``.

    Raises
    ------
    ValueError
        If the shapes are inconsistent, a cost is NaN, or the prior is not a distribution
        (the message names the offending shape or value).

    Notes
    -----
    Types with zero prior still have a best response in ``fv_response`` but contribute nothing
    to σ or E (their terms are dropped, so ``0 * inf`` cannot produce NaN).

    Examples
    --------
    >>> sol = solve_stackelberg_harsanyi(
    ...     [[1.0, 3.0], [2.0, 2.0]], [[[0.0], [1.0]], [[1.0], [0.0]]], [1.0]
    ... )
    >>> sol.sv_action, sol.expected_cost.tolist(), sol.fv_response.tolist()
    (0, [1.0, 2.0], [[0], [1]])
    """
    fv = _as_cost("fv_cost", fv_cost, (3,))
    sv = _as_cost("sv_cost", sv_cost, (2, 3))
    p = np.array(prior, dtype=np.float64)
    n_s, n_f, n_t = fv.shape
    if p.shape != (n_t,):
        raise ValueError(f"prior must have shape ({n_t},) to match fv_cost, got shape {p.shape}")
    if not np.isfinite(p).all() or (p < 0.0).any():
        raise ValueError(f"prior must be finite and non-negative, got {p.tolist()}")
    if abs(p.sum() - 1.0) > PRIOR_TOLERANCE:
        raise ValueError(f"prior must sum to 1, got sum {float(p.sum())!r} for {p.tolist()}")
    if sv.ndim == 2:
        sv = sv[:, :, None]
    if sv.shape[:2] != (n_s, n_f) or sv.shape[2] not in (1, n_t):
        raise ValueError(
            f"sv_cost shape {sv.shape} does not match fv_cost shape {fv.shape} "
            "(need (S, F) or (S, F, n_types))"
        )
    sv = np.broadcast_to(sv, fv.shape)

    response = np.argmin(fv, axis=1).astype(np.int64)  # (S, n_types); first minimum wins
    one_hot = response[:, None, :] == np.arange(n_f)[None, :, None]  # (S, F, n_types)
    mixed = np.asarray(one_hot @ p, dtype=np.float64)  # (S, F)
    sv_at_br = np.take_along_axis(sv, response[:, None, :], axis=1)[:, 0, :]  # (S, n_types)
    weighted = np.where(p > 0.0, sv_at_br * np.where(p > 0.0, p, 1.0), 0.0)
    expected = np.asarray(weighted.sum(axis=1), dtype=np.float64)
    return GameSolution(
        sv_action=int(np.argmin(expected)),
        expected_cost=expected,
        fv_response=response,
        fv_mixed=mixed,
        cooperative=False,
    )


def solve_cooperative(sv_cost: ArrayLike, fv_cost: ArrayLike) -> GameSolution:
    r"""Cooperative solution with a CAV follower (docs/models.md).

    Both vehicles minimise the joint cost :math:`J(s, f) = J_{SV}(s, f) + J_{FV}(s, f)`. For each
    SV action the follower plays the joint minimiser :math:`f^*(s) = \arg\min_f J(s, f)` (ties to
    the lowest f), and SV plays :math:`s^* = \arg\min_s J(s, f^*(s))` (ties to the lowest s), so
    :math:`(s^*, f^*(s^*))` is the joint argmin over (s, f).

    Parameters
    ----------
    sv_cost : array_like, shape (S, F)
        SV cost of each joint action.
    fv_cost : array_like, shape (S, F)
        Cost of the (CAV, known-type) follower for each joint action.

    Returns
    -------
    GameSolution
        ``fv_response`` has shape ``(S, 1)``, ``fv_mixed`` is the one-hot of :math:`f^*(s)`,
        ``expected_cost`` is the joint minimum per SV action and ``cooperative = True``.

    Raises
    ------
    ValueError
        If the arrays are not 2-D, differ in shape, or contain NaN.

    Examples
    --------
    >>> sol = solve_cooperative([[1.0, 3.0], [2.0, 2.0]], [[5.0, 0.5], [1.0, 1.0]])
    >>> sol.sv_action, sol.expected_cost.tolist(), sol.fv_response[:, 0].tolist()
    (1, [3.5, 3.0], [1, 0])
    """
    sv = _as_cost("sv_cost", sv_cost, (2,))
    fv = _as_cost("fv_cost", fv_cost, (2,))
    if sv.shape != fv.shape:
        raise ValueError(f"sv_cost shape {sv.shape} differs from fv_cost shape {fv.shape}")
    joint = sv + fv
    best_f = np.argmin(joint, axis=1).astype(np.int64)  # (S,)
    expected = np.asarray(np.take_along_axis(joint, best_f[:, None], axis=1)[:, 0])
    mixed = (best_f[:, None] == np.arange(joint.shape[1])[None, :]).astype(np.float64)
    return GameSolution(
        sv_action=int(np.argmin(expected)),
        expected_cost=expected,
        fv_response=best_f[:, None],
        fv_mixed=mixed,
        cooperative=True,
    )
