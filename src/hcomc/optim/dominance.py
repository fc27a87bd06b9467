"""Compiled Pareto dominance kernels: relation, non-dominated ranks, crowding distance, and the
NSGA-II steps built on them (rank-and-crowding survival, tournaments, an archive's front).

All objectives are minimised. Row ``i`` dominates row ``j`` when it is no worse in every
objective and strictly better in at least one; identical rows do not dominate each other, and a
comparison with NaN is false (a NaN column neither helps nor hurts). These are the building
blocks of the compiled NSGA-II (:mod:`hcomc.optim.nsga2`), on the dominance of Eq. 18
(:func:`hcomc.equations.pareto.dominates`); each follows the definition of Deb et al. (2002)
in the form pymoo computes it, so that the compiled optimiser ranks, crowds and selects by
pymoo's rules.
"""

from __future__ import annotations

import functools

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray, IntArray
from hcomc.equations.pareto import pareto_mask


@kernel
def relation(a: FloatArray, b: FloatArray) -> int:
    """1 if ``a`` dominates ``b``, -1 if ``b`` dominates ``a``, 0 otherwise: strictly better
    in some objective and strictly worse in none (a comparison with NaN is neither). Counted
    over every objective rather than decided at the first difference, which is the same
    answer without a branch per objective (the order of random rows mispredicts them)."""
    better, worse = 0, 0
    for i in range(a.shape[0]):
        better += a[i] < b[i]
        worse += b[i] < a[i]
    if worse == 0:
        return 1 if better > 0 else 0
    return -1 if better == 0 else 0


@kernel
def pareto_ranks(F: FloatArray) -> IntArray:
    """Non-dominated rank of every row (0 = not dominated by any row; rank k = dominated only by
    rows of ranks < k), by peeling fronts (Deb's fast non-dominated sort), O(n^2 m)."""
    n = F.shape[0]
    dom = np.zeros((n, n), dtype=np.bool_)  # dom[i, j]: i dominates j
    count = np.zeros(n, dtype=np.int64)  # how many rows dominate each row
    for i in range(n):
        for j in range(i + 1, n):
            r = relation(F[i], F[j])
            if r == 1:
                dom[i, j] = True
                count[j] += 1
            elif r == -1:
                dom[j, i] = True
                count[i] += 1
    rank = np.full(n, -1, dtype=np.int64)
    front, nxt = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    size = 0
    for i in range(n):
        if count[i] == 0:
            front[size] = i
            size += 1
    k = 0
    while size > 0:
        n_next = 0
        for q in range(size):
            i = front[q]
            rank[i] = k
            for j in range(n):
                if dom[i, j]:
                    count[j] -= 1
                    if count[j] == 0:
                        nxt[n_next] = j
                        n_next += 1
        front, nxt, size = nxt, front, n_next
        k += 1
    # rows left unranked sit on a dominance cycle, possible only through NaN (comparisons with
    # NaN are skipped): they share the next rank, so that every row has one
    rank[rank < 0] = k
    return rank


@kernel
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


@kernel
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


@kernel
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


@kernel
def survival_fronts(
    F: FloatArray, cv: FloatArray, rows: IntArray, n_survive: int
) -> tuple[IntArray, FloatArray, IntArray, FloatArray, IntArray]:
    """The first half of NSGA-II's rank-and-crowding survival (pymoo's ``RankAndCrowding``) of
    the population ``rows`` of ``F``, ``cv``: feasible rows (``cv <= 0``) front by front, then
    infeasible rows; what is left to random tie-breaks and numpy's sorts is done by the caller.

    Returns
    -------
    order : positions in ``rows``: the feasible rows of the fronts taken whole (front by front,
        each in position order), those of the last front taken (position order), then every
        infeasible row (position order).
    key : what the caller sorts: crowding distance for the last front's entries of ``order``,
        violation for the infeasible entries (NaN for the others).
    rank, crowding : per position; -1 and NaN where not computed (infeasible rows, fronts after
        the last one taken).
    counts : rows in whole fronts, in the last front, to remove from it, and infeasible rows
        taken, for :func:`survivors`.
    """
    n = rows.size
    n_survive = min(n_survive, n)
    feasible = np.empty(n, dtype=np.int64)
    infeasible = np.empty(n, dtype=np.int64)
    n_feas, n_infeas = 0, 0
    for p in range(n):
        if cv[rows[p]] <= 0.0:
            feasible[n_feas] = p
            n_feas += 1
        else:  # NaN too
            infeasible[n_infeas] = p
            n_infeas += 1
    n_feasible = min(n_feas, n_survive)
    rank = np.full(n, -1, dtype=np.int64)
    crowding = np.full(n, np.nan)
    order = np.empty(n, dtype=np.int64)
    key = np.full(n, np.nan)
    n_inner, k = 0, 0
    if n_feasible > 0:
        Ff = np.empty((n_feas, F.shape[1]))
        for q in range(n_feas):
            Ff[q] = F[rows[feasible[q]]]
        ranks, d, last = ranked_fronts(Ff, n_feasible)
        for q in range(n_feas):
            rank[feasible[q]], crowding[feasible[q]] = ranks[q], d[q]
        for r in range(last):  # whole fronts, front by front, in position order
            for q in range(n_feas):
                if ranks[q] == r:
                    order[k] = feasible[q]
                    k += 1
        n_inner = k
        for q in range(n_feas):
            if ranks[q] == last:
                order[k], key[k] = feasible[q], d[q]
                k += 1
    n_front = k - n_inner
    for q in range(n_infeas):
        order[k], key[k] = infeasible[q], cv[rows[infeasible[q]]]
        k += 1
    counts = np.array([n_inner, n_front, n_inner + n_front - n_feasible, n_survive - n_feasible])
    return order[:k], key[:k], rank, crowding, counts


@kernel
def survivors(
    order: IntArray, counts: IntArray, perm: IntArray, by_crowding: IntArray, by_violation: IntArray
) -> IntArray:
    """Positions of the survivors, best first, from :func:`survival_fronts`' ``order`` and
    ``counts``: the whole fronts, the last front cut to size, the least-violating infeasible rows.

    The last front (when cut) keeps its rows of largest crowding: ``perm`` is the random
    permutation of the front and ``by_crowding`` the stable sort of its crowding distances in
    that order, read from the end; ``by_violation`` is the stable sort of the infeasible rows
    by violation (stable: the order of ties is the same on every machine).
    """
    n_inner, n_front, n_remove, n_infeasible = counts
    n_kept = n_front - max(n_remove, 0)
    idx = np.empty(n_inner + n_kept + n_infeasible, dtype=np.int64)
    idx[:n_inner] = order[:n_inner]
    for q in range(n_kept):
        j = perm[by_crowding[n_front - 1 - q]] if n_remove > 0 else q
        idx[n_inner + q] = order[n_inner + j]
    for q in range(n_infeasible):
        idx[n_inner + n_kept + q] = order[n_inner + n_front + by_violation[q]]
    return idx


@kernel
def survive_and_select(
    F: FloatArray,
    cv: FloatArray,
    rows: IntArray,
    crowding: FloatArray,
    order: IntArray,
    counts: IntArray,
    perm: IntArray,
    by_crowding: IntArray,
    by_violation: IntArray,
    P: IntArray,
) -> tuple[IntArray, IntArray, IntArray]:
    """:func:`survivors`, then the binary tournaments ``P`` between them (:func:`tournament`):
    the survivors' positions in ``rows``, the winners (positions among the survivors, ``-1`` for
    a tie) and the ties' indices, to be drawn by the caller in order."""
    idx = survivors(order, counts, perm, by_crowding, by_violation)
    n = idx.size
    Fs = np.empty((n, F.shape[1]))
    cvs, cds = np.empty(n), np.empty(n)
    for q in range(n):
        Fs[q], cvs[q], cds[q] = F[rows[idx[q]]], cv[rows[idx[q]]], crowding[idx[q]]
    S = tournament(P, Fs, cvs, cds)
    return idx, S, np.flatnonzero(S < 0)


@kernel
def feasible_front(F: FloatArray, G: FloatArray) -> IntArray:
    """Rows of the feasible (every ``G <= 0``), mutually non-dominated subset of ``F``, one per
    distinct objective vector (the first), in row order.

    Rows are taken in order against the front so far: a row that some member is no worse than
    everywhere (dominates or equals) is dropped, else it joins and drops the members it is no
    worse than (which it then dominates). Domination is transitive and implies NaN-free rows,
    so a row dominated by any earlier row is dominated by a member of the front, and the result
    is the non-dominated set with the first of equal rows; a row with NaN neither dominates nor
    equals any other, so each one stays. O(n |front| m).
    """
    n, m = F.shape
    front = np.empty(n, dtype=np.int64)
    beaten = np.empty(n, dtype=np.bool_)  # front members the new row is no worse than
    size = 0
    for i in range(n):
        feasible = True
        for c in range(G.shape[1]):
            if not G[i, c] <= 0.0:
                feasible = False
                break
        if not feasible:
            continue
        dropped = False
        for q in range(size):
            j = front[q]
            member_le, row_le = True, True  # F[j] <= F[i] everywhere, F[i] <= F[j] everywhere
            for c in range(m):
                if not F[j, c] <= F[i, c]:
                    member_le = False
                if not F[i, c] <= F[j, c]:
                    row_le = False
            if member_le:
                dropped = True
                break
            beaten[q] = row_le
        if dropped:
            continue
        kept = 0
        for q in range(size):
            if not beaten[q]:
                front[kept] = front[q]
                kept += 1
        front[kept] = i
        size = kept + 1
    return front[:size].copy()


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) every kernel of this module now."""
    F = np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]])
    pareto_ranks(F)
    pareto_mask(F)
    crowding_distance(F)
    feasible_front(F, np.zeros((3, 1)))
    rows = np.arange(3)
    order, _, _, crowding, counts = survival_fronts(F, np.zeros(3), rows, 2)
    none = np.empty(0, dtype=np.int64)
    P = np.array([[0, 1]], dtype=np.int64)
    survive_and_select(F, np.zeros(3), rows, crowding, order, counts, none, none, none, P)
