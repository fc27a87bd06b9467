"""A lean PSO on arrays that makes pymoo's decisions, without pymoo's per-individual objects.

:class:`CompiledPSOOptimizer` runs the algorithm of :class:`~hcomc.optim.pymoo_backend.
PSOOptimizer` (pymoo 0.6's adaptive ``PSO`` on the scalarised problem) on plain arrays. A pymoo
run spends most of a decision outside the problem: ``Population.get``/``set`` on every step,
the improvement replacement and its duplicate check on ``Individual`` objects, the optimum
filter, and the velocity equation called again, a dozen numpy calls each time, for every
out-of-box retry (on the merge problem, whose good rows lie on bounds, about a dozen retries per
generation). Here the move with its retries, the duplicate check and the Latin hypercube
criterion are numba kernels, the rest whole-array numpy. The run draws the same random numbers,
in the same order and shapes, from a generator seeded like pymoo's
(``numpy.random.default_rng(seed)``; numba's ``Generator.random`` reads the same bit generator
and gives the same numbers), and computes every floating-point value with the same operations
in the same order (numpy itself where the last bit depends on numpy's implementation: ``np.exp``,
``np.power``; the sums of the swarm's spread follow numpy's pairwise summation, checked against
numpy once per process), so for the same problem, budget and ``rng`` it evaluates the same rows
and returns the same set as the pymoo optimiser (tests hold it to that).

One generation, as pymoo's ``PSO._infill`` and ``_advance`` do it:

1. new velocities and positions (:func:`move`, velocity clamped to +-20 % of the box);
   rows still out of the box are recomputed with fresh random numbers, at most 20 times, then
   out-of-box variables are re-drawn between the bound and the old position;
2. the particle with the best personal-best cost (first of equals, NaN last) is replaced by a
   polynomial mutation of that personal best (``eta`` uniform in [5, 30), row probability 0.9);
3. evaluation; a personal best is replaced where the new cost is strictly lower and the new
   position is not an exact duplicate (of an earlier new position, or of any personal best);
4. fuzzy adaptation of ``w``, ``c1``, ``c2`` from the swarm's spread (:func:`adapt`).

The social best is the personal best of lowest cost, ``np.argmin`` (so a NaN cost, which never
improves, would be chosen: pymoo's rule, kept). Budget, seeding and warm start are those of
the pymoo optimiser: ``n_gen = max(1, budget // pop_size)`` generations of ``pop_size`` rows,
the first a Latin hypercube sample (or the warm-start rows); one integer seed
(:func:`hcomc.rng.draw_seed`) drawn from the caller's generator after the warm-start rows.

What is returned, and why: PSO searches on the scalarised cost, but returns what every
optimiser here returns, the feasible, mutually non-dominated subset of every row it evaluated
(:func:`hcomc.optim.base.archive_front`: one per distinct objective vector, in evaluation order,
with its true ``F`` and ``G``), taken from an :class:`~hcomc.optim.base.Archive` allocated once
for the budget; only when no evaluated row is feasible, its best-scalarised row (NaN as inf,
the first seen wins ties). The controller's selection rule (Eq. 19, paper Section III-C-2) then
picks from PSO's set as it does from NSGA-II's, so that the comparison of NSGA-II, PSO and SA
(paper Section IV, Table II) compares the optimisers' searches under one selection rule rather
than Eq. 19's min-max normalisation against PSO's fixed-scale scalarisation.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from hcomc._jit import borrow, kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.optim import variation
from hcomc.optim.base import (
    Archive,
    ParetoResult,
    Problem,
    check_budget,
    check_pop_size,
    initial_rows,
)
from hcomc.optim.numpy_sum import numpy_sums_are_pairwise, pairwise_sum
from hcomc.optim.variation import polynomial_mutation
from hcomc.rng import draw_seed

MAX_VELOCITY_RATE = 0.2  # |velocity| <= this share of the box, per variable (pymoo default)
_RETRIES = 20  # recomputations of rows still outside the box (pymoo's fixed count)
_LHS_ITERATIONS = 20  # Latin hypercube samples drawn; the one of largest minimum distance wins
_PERTURB_ROW_PROB = 0.9  # probability that the best particle's mutation happens at all


@kernel
def min_distances(samples: FloatArray) -> FloatArray:
    """The smallest pairwise euclidean distance between the rows of each sample (k, n, n_var),
    pymoo's maxmin criterion: as scipy's ``cdist`` computes a distance (squared absolute
    differences summed in variable order from 0, then the square root), so the values are the
    same bit for bit; ``sqrt`` of the smallest sum is the smallest ``sqrt``, as ``sqrt`` is
    monotonic and correctly rounded."""
    k, n, n_var = samples.shape
    out = np.empty(k)
    for s in range(k):
        smallest = np.inf
        for i in range(n):
            for j in range(i + 1, n):
                total = 0.0
                for v in range(n_var):
                    d = abs(samples[s, i, v] - samples[s, j, v])
                    total += d * d
                smallest = min(smallest, total)
        out[s] = np.sqrt(smallest)
    return out


def latin_hypercube(n: int, xl: FloatArray, xu: FloatArray, rng: np.random.Generator) -> FloatArray:
    """``n`` rows by pymoo's ``LHS()``: the best of 20 smoothed Latin hypercube samples by the
    maxmin criterion (:func:`min_distances`, largest wins, the first of equals)."""
    # pymoo draws (n, n_var) uniforms for the ranks, then as many for the jitter, per sample:
    # one draw of all of them is the same stream
    draws = rng.random((_LHS_ITERATIONS, 2, n, xl.size))
    units = (draws[:, 0].argsort(axis=1) + 1 - draws[:, 1]) / n
    out: FloatArray = xl + units[int(np.argmax(min_distances(units)))] * (xu - xl)
    return out


@kernel
def _equation(
    X: FloatArray,
    P_X: FloatArray,
    s_x: FloatArray,
    V: FloatArray,
    v_max: FloatArray,
    params: tuple[float, float, float],
    rows: IntArray,
    rng: np.random.Generator,
    Xp: FloatArray,
    Vp: FloatArray,
) -> None:
    """Rows ``rows`` of the new positions and velocities, in place: ``X + V'`` with
    ``V' = w V + c1 r1 (P - X) + c2 r2 (s - X)`` clamped to +-v_max (pymoo's ``pso_equation``
    then ``set_to_bounds_if_outside``: the same operations in the same order per element, and
    ``r1`` then ``r2`` drawn as (rows, n_var) arrays from the same generator)."""
    w, c1, c2 = params
    r1 = rng.random((rows.size, X.shape[1]))
    r2 = rng.random((rows.size, X.shape[1]))
    for a in range(rows.size):
        i = rows[a]
        for j in range(X.shape[1]):
            v = (
                w * V[i, j]
                + c1 * r1[a, j] * (P_X[i, j] - X[i, j])
                + c2 * r2[a, j] * (s_x[j] - X[i, j])
            )
            v = -v_max[j] if v < -v_max[j] else v
            v = v_max[j] if v > v_max[j] else v
            Vp[i, j] = v
            Xp[i, j] = X[i, j] + v


@kernel
def _outside(Xp: FloatArray, xl: FloatArray, xu: FloatArray) -> IntArray:
    """Rows with a variable outside the box, ascending (NaN is not outside)."""
    out = np.zeros(Xp.shape[0], dtype=np.bool_)
    for i in range(Xp.shape[0]):
        for j in range(Xp.shape[1]):
            if Xp[i, j] < xl[j] or Xp[i, j] > xu[j]:
                out[i] = True
    return np.flatnonzero(out)


@kernel
def move(
    X: FloatArray,
    P_X: FloatArray,
    s_x: FloatArray,
    V: FloatArray,
    params: tuple[float, float, float],
    xl: FloatArray,
    xu: FloatArray,
    rng: np.random.Generator,
) -> tuple[FloatArray, FloatArray, int]:
    """Positions and velocities of the next generation, inside the box (pymoo's ``_infill``
    before the perturbation of the best), and how many recomputation rounds it took.

    Rows outside the box are recomputed from the old position with new random numbers, at most
    20 times; a variable still outside is then drawn uniformly between its bound and its old
    position (``repair_random_init``), the velocity is kept. One compiled kernel: on the merge
    problem, whose best rows lie on bounds, a move takes about a dozen rounds, each a dozen
    small numpy calls in pymoo's form. numba's ``Generator.random`` reads the same bit
    generator as numpy's, so the draws are the same numbers.
    """
    n, n_var = X.shape
    v_max = MAX_VELOCITY_RATE * (xu - xl)
    Xp, Vp = np.empty((n, n_var)), np.empty((n, n_var))
    _equation(X, P_X, s_x, V, v_max, params, np.arange(n), rng, Xp, Vp)
    retries = 0
    while retries < _RETRIES:
        rows = _outside(Xp, xl, xu)
        if rows.size == 0:
            break
        _equation(X, P_X, s_x, V, v_max, params, rows, rng, Xp, Vp)
        retries += 1
    for side in range(2):  # below the box first, then above, each in row-major order
        count = 0
        for i in range(n):
            for j in range(n_var):
                count += Xp[i, j] < xl[j] if side == 0 else Xp[i, j] > xu[j]
        if count == 0:
            continue
        r = rng.random(count)
        k = 0
        for i in range(n):
            for j in range(n_var):
                if side == 0 and Xp[i, j] < xl[j]:
                    Xp[i, j] = xl[j] + r[k] * (X[i, j] - xl[j])
                    k += 1
                elif side == 1 and Xp[i, j] > xu[j]:
                    Xp[i, j] = xu[j] - r[k] * (xu[j] - X[i, j])
                    k += 1
    return Xp, Vp, retries


@kernel
def _same(a: FloatArray, b: FloatArray) -> bool:
    """Euclidean distance 0: every squared difference is 0 (a sum of non-negative numbers
    cannot round to 0 otherwise); NaN never is."""
    for k in range(a.size):
        d = a[k] - b[k]
        if d * d != 0.0:
            return False
    return True


@kernel
def improvement(X: FloatArray, F: FloatArray, P_X: FloatArray, P_F: FloatArray) -> BoolArray:
    """Particles whose new position replaces their personal best (pymoo's
    ``ImprovementReplacement`` without constraints): a strictly lower cost (never against or
    with a NaN), and the new position is no duplicate, i.e. at euclidean distance > 0 from
    every earlier new position and from every personal best (``DefaultDuplicateElimination
    (epsilon=0)``, which pymoo applies to the new positions against themselves, then against
    the personal bests)."""
    n = X.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if not F[i] < P_F[i]:
            continue
        dup = False
        for j in range(i):
            dup = dup or _same(X[i], X[j])
        for j in range(P_X.shape[0]):
            dup = dup or _same(X[i], P_X[j])
        out[i] = not dup
    return out


def _norm_dist(A: FloatArray, B: FloatArray, xl: FloatArray, xu: FloatArray) -> FloatArray:
    """Euclidean distances between rows of ``A`` and ``B`` in box-normalised coordinates, with
    pymoo's ``vectorized_cdist`` layout and operations (so ``sum`` rounds the same way)."""
    u = np.repeat(A, B.shape[0], axis=0)
    v = np.tile(B, (A.shape[0], 1))
    D = np.sqrt((((u - v) / (xu - xl)) ** 2).sum(axis=1))
    out: FloatArray = np.reshape(D, (A.shape[0], B.shape[0]))
    return out


def _spread_numpy(
    P_X: FloatArray, s_x: FloatArray, xl: FloatArray, xu: FloatArray
) -> tuple[FloatArray, float]:
    """:func:`swarm_spread` as pymoo computes it, whole-array numpy."""
    n = P_X.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        mD = _norm_dist(P_X, P_X, xl, xu).sum(axis=1) / (n - 1)
        # pymoo averages the (n, n) distances of n copies of s_x to the bests: n equal rows;
        # the same n^2 values in the same layout give the same rounding
        g_D = np.tile(_norm_dist(s_x[None, :], P_X, xl, xu)[0], n).mean()
    return mD, float(g_D)


@kernel(inline="always")  # called n^2 times per spread: no call with array arguments
def _distance(p: FloatArray, q: FloatArray, width: FloatArray, terms: FloatArray) -> float:
    """Box-normalised euclidean distance of two rows, as :func:`_norm_dist` rounds it."""
    for k in range(p.size):
        d = (p[k] - q[k]) / width[k]
        terms[k] = d * d
    return float(np.sqrt(pairwise_sum(terms, 0, terms.size)))


@kernel
def _spread_kernel(
    P_X: FloatArray, s_x: FloatArray, xl: FloatArray, xu: FloatArray, scratch: FloatArray
) -> tuple[FloatArray, float]:
    """:func:`swarm_spread` compiled; ``scratch`` (n_var,) holds a distance's terms."""
    n = P_X.shape[0]
    width = xu - xl
    D, mD = np.empty((n, n)), np.empty(n)
    terms = borrow(scratch)  # n^2 sums without reference counting (the caller keeps it)
    for i in range(n):
        D[i, i] = _distance(P_X[i], P_X[i], width, terms)
        for j in range(i + 1, n):
            # a - b is exactly -(b - a): the distance matrix is symmetric bit for bit
            d = _distance(P_X[i], P_X[j], width, terms)
            D[i, j], D[j, i] = d, d
    for i in range(n):
        mD[i] = pairwise_sum(D[i], 0, n) / (n - 1)
    copies = np.empty(n * n)
    for j in range(n):
        copies[j] = _distance(s_x, P_X[j], width, terms)
    for k in range(1, n):
        copies[k * n : (k + 1) * n] = copies[:n]
    return mD, pairwise_sum(copies, 0, n * n) / (n * n)


def swarm_spread(
    P_X: FloatArray, s_x: FloatArray, xl: FloatArray, xu: FloatArray
) -> tuple[FloatArray, float]:
    """pymoo's two spreads of ``PSO._adapt`` (box-normalised euclidean distances): each
    personal best's mean distance to all personal bests (itself included, divided by n - 1)
    and the mean distance of the social best ``s_x`` to them, with pymoo's rounding.

    One compiled pass where numpy's sums are the pairwise summation of :func:`pairwise_sum`
    (:func:`numpy_sums_are_pairwise`), else numpy's arrays in pymoo's layout.
    """
    if numpy_sums_are_pairwise():
        mD, g_D = _spread_kernel(P_X, s_x, xl, xu, np.empty(P_X.shape[1]))
        return mD, float(g_D)
    return _spread_numpy(P_X, s_x, xl, xu)


def _memberships(f: float) -> list[float]:
    """Fuzzy memberships of the evolutionary factor ``f`` in the four states (exploration,
    exploitation, convergence, jumping out), pymoo's piecewise-linear functions."""
    s1 = 0 if f <= 0.4 else 5 * f - 2 if f <= 0.6 else 1 if f <= 0.7 else -10 * f + 8
    s1 = 0 if f > 0.8 else s1
    s2 = 0 if f <= 0.2 else 10 * f - 2 if f <= 0.3 else 1 if f <= 0.4 else -5 * f + 3
    s2 = 0 if f > 0.6 else s2
    s3 = 1 if f <= 0.1 else -5 * f + 1.5 if f <= 0.3 else 0
    s4 = 0 if f <= 0.7 else 5 * f - 3.5 if f <= 0.9 else 1
    return [s1, s2, s3, s4]


def adapt(
    P_X: FloatArray,
    s_x: FloatArray,
    c1: float,
    c2: float,
    xl: FloatArray,
    xu: FloatArray,
    rng: np.random.Generator,
) -> tuple[float, float, float]:
    """New ``(w, c1, c2)`` from the personal bests' spread (pymoo's ``PSO._adapt``).

    The evolutionary factor ``f`` places the mean distance of the social best ``s_x`` (the one
    this generation moved towards) to the personal bests among the particles' mean distances;
    its dominant fuzzy state shifts ``c1``/``c2`` by a random ``delta`` in [0.05, 0.1), clamped
    to [1.5, 2.5] and rescaled to a sum of at most 4 (``c2`` rescaled with the new ``c1``, as
    pymoo does), and ``w = 1 / (1 + 1.5 exp(-2.6 f))``.
    """
    mD, g_D = swarm_spread(P_X, s_x, xl, xu)
    lo, hi = mD.min(), mD.max()
    f = (g_D - lo) / (hi - lo + 1e-32)
    if np.isnan(f):  # pymoo fails here too (its memberships of NaN are None)
        raise ValueError(
            "adaptive PSO needs xl < xu in every variable (distances are box-normalised)"
        )
    strategy = int(np.array(_memberships(f)).argmax()) + 1
    delta = 0.05 + (rng.random() * 0.05)
    step = {1: (delta, -delta), 2: (0.5 * delta, -0.5 * delta),
            3: (0.5 * delta, 0.5 * delta), 4: (-delta, delta)}[strategy]  # fmt: skip
    c1, c2 = c1 + step[0], c2 + step[1]
    c1 = max(1.5, min(2.5, c1))
    c2 = max(1.5, min(2.5, c2))
    if c1 + c2 > 4.0:
        c1 = 4.0 * (c1 / (c1 + c2))
        c2 = 4.0 * (c2 / (c1 + c2))
    with np.errstate(over="ignore"):  # f = +-1e32 scale when all mean distances are equal
        w = 1 / (1 + 1.5 * np.exp(-2.6 * f))
    return w, c1, c2


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels of this module now."""
    rng = np.random.default_rng(0)
    xl, xu = np.zeros(2), np.ones(2)
    X = rng.random((3, 2))
    Xp, _, _ = move(X, X, X[0], X, (0.9, 2.0, 2.0), xl, xu, rng)
    improvement(Xp, np.zeros(3), X, np.ones(3))
    latin_hypercube(3, xl, xu, rng)
    swarm_spread(X, X[0], xl, xu)


@dataclass(frozen=True, slots=True)
class CompiledPSOOptimizer:
    """Adaptive PSO on arrays; the same decisions as the pymoo optimiser, without its objects.

    Parameters
    ----------
    pop_size : swarm size (rows per generation).
    w, c1, c2 : inertia and cognitive / social weights (initial values when ``adaptive``).
    adaptive : pymoo's fuzzy adaptation of ``w``, ``c1``, ``c2``.

    Notes
    -----
    Searches on ``problem.scalarise(F, G)`` as one unconstrained objective (the constraint
    penalty is inside ``scalarise``) and returns the feasible non-dominated subset of every
    evaluated row, or the best-scalarised row when none is feasible (see the module docstring).
    """

    pop_size: int = 24
    w: float = 0.9
    c1: float = 2.0
    c2: float = 2.0
    adaptive: bool = True
    name: str = field(default="pso", init=False)

    def __post_init__(self) -> None:
        check_pop_size(self.pop_size)
        variation.warm_up()  # load the compiled kernels now, not inside a timed decision
        warm_up()

    def minimize(
        self,
        problem: Problem,
        *,
        budget: int,
        rng: np.random.Generator,
        initial: FloatArray | None = None,
    ) -> ParetoResult:
        """Run ``max(1, budget // pop_size)`` generations; return the feasible non-dominated
        set of every row evaluated."""
        check_budget(budget)
        n_gen = max(1, budget // self.pop_size)
        xl = np.array(problem.xl, dtype=np.float64, copy=True)
        xu = np.array(problem.xu, dtype=np.float64, copy=True)
        n_var, n_obj, n_constr = int(problem.n_var), int(problem.n_obj), int(problem.n_constr)
        first = initial_rows(problem, initial, self.pop_size, rng)
        gen = np.random.default_rng(draw_seed(rng))
        if first is None:
            first = latin_hypercube(self.pop_size, xl, xu, gen)
        archive = Archive(first.shape[0] + (n_gen - 1) * self.pop_size, n_var, n_obj, n_constr)

        def evaluate(X: FloatArray) -> FloatArray:
            """Costs of rows ``X``; the rows kept in the archive."""
            F, G = problem.evaluate(X)
            n = X.shape[0]
            F = np.asarray(F, dtype=np.float64).reshape(n, n_obj)
            G = np.asarray(G, dtype=np.float64).reshape(n, n_constr)
            cost = np.asarray(problem.scalarise(F, G), dtype=np.float64).reshape(-1)
            archive.add(X, F, G, cost)
            return cost

        X = first
        P_X, P_F = X.copy(), evaluate(X)
        V = gen.random((self.pop_size, n_var)) * (MAX_VELOCITY_RATE * (xu - xl))[None, :]
        params = (float(self.w), float(self.c1), float(self.c2))  # one compiled signature
        for _ in range(n_gen - 1):
            s_x = P_X[int(np.argmin(P_F))].copy()  # social best: first minimum, NaN first
            X, V, _ = move(X, P_X, s_x, V, params, xl, xu, gen)
            k = int(np.argsort(P_F, kind="stable")[0])  # best personal best, NaN last
            eta = gen.uniform(5, 30)
            X[k] = polynomial_mutation(P_X[k : k + 1], xl, xu, eta, _PERTURB_ROW_PROB, gen)[0]
            F = evaluate(X)
            improved = improvement(X, F, P_X, P_F)
            P_X[improved], P_F[improved] = X[improved], F[improved]
            if self.adaptive:
                params = adapt(P_X, s_x, params[1], params[2], xl, xu, gen)
        return archive.result(archive.size, self.name)
