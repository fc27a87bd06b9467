"""A lean PSO on arrays: pymoo's adaptive PSO, without pymoo's per-individual objects.

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
and gives the same numbers), with pymoo's formulas. Its math is the C library's, never numpy's
CPU-dispatched functions (the mutation's powers, the adaptation's ``exp``), and its sums are
plain sums in index order (the swarm spread), so a run is the same on every processor; it can
part from pymoo's in the last bit and go its own way. The tests hold it to pymoo's solution
quality on the recorded merge problems (``tests/unit/test_pso_compiled.py``).

One generation, as pymoo's ``PSO._infill`` and ``_advance`` do it:

1. new velocities and positions (:func:`~hcomc.optim.pso.move.move`, velocity clamped to
   +-20 % of the box); rows still out of the box are recomputed with fresh random numbers, at
   most 20 times, then out-of-box variables are re-drawn between the bound and the old
   position;
2. the particle with the best personal-best cost (first of equals, NaN last) is replaced by a
   polynomial mutation of that personal best (``eta`` uniform in [5, 30), row probability 0.9);
3. evaluation; a personal best is replaced where the new cost is strictly lower and the new
   position is not an exact duplicate (of an earlier new position, or of any personal best);
4. fuzzy adaptation of ``w``, ``c1``, ``c2`` from the swarm's spread
   (:func:`~hcomc.optim.pso.adaptation.adapt`).

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

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.optim import variation
from hcomc.optim.base import (
    Archive,
    ParetoResult,
    Problem,
    check_budget,
    check_pop_size,
    generations,
    initial_rows,
)
from hcomc.optim.pso.adaptation import adapt, swarm_spread
from hcomc.optim.pso.move import MAX_VELOCITY_RATE, improvement, move
from hcomc.optim.variation import polynomial_mutation
from hcomc.rng import draw_seed

_LHS_ITERATIONS = 20  # Latin hypercube samples drawn; the one of largest minimum distance wins
_PERTURB_ROW_PROB = 0.9  # probability that the best particle's mutation happens at all


@kernel
def min_distances(samples: FloatArray) -> FloatArray:
    """The smallest pairwise euclidean distance between the rows of each sample (k, n, n_var),
    pymoo's maxmin criterion: squared differences summed in variable order, then the square
    root; ``sqrt`` of the smallest sum is the smallest ``sqrt``, as ``sqrt`` is monotonic and
    correctly rounded."""
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
    units = (draws[:, 0].argsort(axis=1, kind="stable") + 1 - draws[:, 1]) / n
    out: FloatArray = xl + units[int(np.argmax(min_distances(units)))] * (xu - xl)
    return out


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
    """Adaptive PSO on arrays, pymoo's algorithm without its objects (see the module).

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
        n_gen = generations(budget, self.pop_size)
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
