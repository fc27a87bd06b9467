"""Compiled Pareto dominance kernels: relation, non-dominated ranks, crowding distance.

All objectives are minimised. Row ``i`` dominates row ``j`` when it is no worse in every
objective and strictly better in at least one; identical rows do not dominate each other, and a
comparison with NaN is false (a NaN column neither helps nor hurts). These are the building
blocks of the compiled NSGA-II (:mod:`hcomc.optim.nsga2`) and of the non-dominated filter of
:mod:`hcomc.optim.selection`; each follows the definition of Deb et al. (2002) in the form
pymoo computes it, so that the compiled optimiser reproduces pymoo's decisions exactly.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from hcomc._typing import BoolArray, FloatArray, IntArray


@njit(cache=True)
def relation(a: FloatArray, b: FloatArray) -> int:
    """1 if ``a`` dominates ``b``, -1 if ``b`` dominates ``a``, 0 otherwise (pymoo's order of
    comparison: the first strict difference in each direction decides)."""
    val = 0
    for i in range(a.shape[0]):
        if a[i] < b[i]:
            if val == -1:
                return 0
            val = 1
        elif b[i] < a[i]:
            if val == 1:
                return 0
            val = -1
    return val


@njit(cache=True)
def _domination_matrix(F: FloatArray) -> np.ndarray:
    n = F.shape[0]
    dom = np.zeros((n, n), dtype=np.bool_)  # dom[i, j]: i dominates j
    for i in range(n):
        for j in range(i + 1, n):
            r = relation(F[i], F[j])
            if r == 1:
                dom[i, j] = True
            elif r == -1:
                dom[j, i] = True
    return dom


@njit(cache=True)
def pareto_ranks(F: FloatArray) -> IntArray:
    """Non-dominated rank of every row (0 = not dominated by any row; rank k = dominated only by
    rows of ranks < k), by peeling fronts (Deb's fast non-dominated sort), O(n^2 m)."""
    n = F.shape[0]
    dom = _domination_matrix(F)
    count = np.zeros(n, dtype=np.int64)  # how many rows dominate each row
    for i in range(n):
        for j in range(n):
            if dom[i, j]:
                count[j] += 1
    rank = np.full(n, -1, dtype=np.int64)
    front = np.flatnonzero(count == 0)
    k = 0
    while front.size > 0:
        nxt = np.zeros(n, dtype=np.bool_)
        for q in range(front.size):
            i = front[q]
            rank[i] = k
            for j in range(n):
                if dom[i, j]:
                    count[j] -= 1
                    if count[j] == 0:
                        nxt[j] = True
        front = np.flatnonzero(nxt)
        k += 1
    # rows left unranked sit on a dominance cycle, possible only through NaN (comparisons with
    # NaN are skipped): they share the next rank, so that every row has one
    rank[rank < 0] = k
    return rank


@njit(cache=True)
def _dominates(a: FloatArray, b: FloatArray) -> bool:
    """``a`` no worse than ``b`` everywhere and better somewhere (False if a NaN is involved)."""
    better = False
    for i in range(a.shape[0]):
        if not a[i] <= b[i]:
            return False
        if a[i] < b[i]:
            better = True
    return better


@njit(cache=True)
def non_dominated_mask(F: FloatArray) -> BoolArray:
    """True for the rows that no other row dominates; a NaN in either row of a pair means
    neither dominates the other."""
    n = F.shape[0]
    keep = np.ones(n, dtype=np.bool_)
    for i in range(n):
        for j in range(n):
            if i != j and keep[j] and _dominates(F[i], F[j]):
                keep[j] = False
    return keep


@njit(cache=True)
def crowding_distance(F: FloatArray) -> FloatArray:
    """NSGA-II crowding distance of the rows of one front, as pymoo's ``"cd"``.

    Per objective, the rows are sorted (stable); each row's distance to its neighbours is divided
    by the objective's range and the two sides are summed; the extreme rows get infinity, and an
    objective whose range is 0 contributes 0. The result is the sum over objectives divided by
    their number. Fronts of at most two rows are all infinite.
    """
    n, m = F.shape
    if n <= 2:
        return np.full(n, np.inf)
    total = np.zeros(n)
    for j in range(m):
        col = F[:, j].copy()
        order = np.argsort(col, kind="mergesort")
        fs = col[order]
        norm = fs.max() - fs.min()
        if norm == 0.0:
            norm = np.nan  # 0 / 0 and inf / 0 both become 0 below
        for r in range(n):
            last = fs[r] - (-np.inf if r == 0 else fs[r - 1])
            nxt = (np.inf if r == n - 1 else fs[r + 1]) - fs[r]
            d_last, d_next = last / norm, nxt / norm
            if np.isnan(d_last):
                d_last = 0.0
            if np.isnan(d_next):
                d_next = 0.0
            total[order[r]] += d_last + d_next
    return total / m


@njit(cache=True)
def ranked_fronts(F: FloatArray, n_needed: int) -> tuple[IntArray, FloatArray, int]:
    """Ranks of all rows, and the crowding distance within its front of every row of the
    first fronts that together hold at least ``n_needed`` rows (NaN beyond); the rank of the
    last of those fronts."""
    rank = pareto_ranks(F)
    crowd = np.full(F.shape[0], np.nan)
    taken, k = 0, 0
    while taken < n_needed:
        front = np.flatnonzero(rank == k)
        crowd[front] = crowding_distance(F[front])
        taken += front.size
        k += 1
    return rank, crowd, k - 1


@njit(cache=True)
def tournament(P: IntArray, F: FloatArray, cv: FloatArray, crowding: FloatArray) -> IntArray:
    """Winners of NSGA-II binary tournaments between rows ``P[i, 0]`` and ``P[i, 1]``.

    If either is infeasible (``cv > 0``) the smaller violation wins; if both are feasible, the
    dominating one, else the larger crowding distance. ``-1`` marks a tie, to be drawn at random
    by the caller (in order, so that the random stream matches pymoo's).
    """
    S = np.full(P.shape[0], -1, dtype=np.int64)
    for i in range(P.shape[0]):
        a, b = P[i, 0], P[i, 1]
        if cv[a] > 0.0 or cv[b] > 0.0:
            if cv[a] < cv[b]:
                S[i] = a
            elif cv[a] > cv[b]:
                S[i] = b
            continue
        r = relation(F[a], F[b])
        if r == 1:
            S[i] = a
        elif r == -1:
            S[i] = b
        elif crowding[a] > crowding[b]:
            S[i] = a
        elif crowding[a] < crowding[b]:
            S[i] = b
    return S


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) every kernel of this module now."""
    F = np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]])
    pareto_ranks(F)
    non_dominated_mask(F)
    crowding_distance(F)
    ranked_fronts(F, 2)
    tournament(np.array([[0, 1], [1, 2]], dtype=np.int64), F, np.zeros(3), np.ones(3))
