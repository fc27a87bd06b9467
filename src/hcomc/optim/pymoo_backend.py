"""NSGA-II and PSO from pymoo behind our :class:`~hcomc.optim.base.Optimizer` interface.

This is the only module that imports pymoo. A private adapter,
:class:`_PymooProblem`, wraps our vectorised :class:`~hcomc.optim.base.Problem` as a
``pymoo.core.problem.Problem``: one ``problem.evaluate(X)`` call per population, every row
kept in an :class:`~hcomc.optim.base.Archive` allocated once for the budget.

What is returned, and why: both optimisers return the same kind of set, the feasible, mutually
non-dominated subset of every row they evaluated (:func:`hcomc.optim.base.archive_front`: one
per distinct objective vector, in evaluation order), NSGA-II searching on the objectives and
PSO on the scalarised cost. When no evaluated row is feasible, NSGA-II returns pymoo's
least-violating row and PSO its best-scalarised row. The controller's selection rule (Eq. 19,
paper Section III-C-2) then picks from either set alike, so that the comparison of NSGA-II,
PSO and SA (paper Section IV, Table II) compares the optimisers' searches under one selection
rule.

Budget layout: ``budget`` counts evaluated rows. Both optimisers run
``n_gen = max(1, budget // pop_size)`` generations of ``pop_size`` rows (the first generation
is the initial sample), so they spend exactly ``pop_size * n_gen`` rows when ``budget`` is a
multiple of ``pop_size`` and at least one population when ``budget < pop_size``.
``ParetoResult.n_eval`` reports the rows actually evaluated (NSGA-II's duplicate elimination
can, rarely, make a generation smaller).

Seeding: one integer seed (:func:`hcomc.rng.draw_seed`) is drawn from the caller's
generator and passed to ``pymoo.optimize.minimize(seed=...)``; pymoo derives every random
number of the run from it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.algorithms.soo.nonconvex.pso import PSO
from pymoo.core.problem import Problem as _PymooBaseProblem
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.sampling.rnd import FloatRandomSampling
from pymoo.optimize import minimize as _pymoo_minimize
from pymoo.termination import get_termination

from hcomc._typing import FloatArray
from hcomc.optim.base import (
    Archive,
    ParetoResult,
    Problem,
    archive_front,
    check_budget,
    check_pop_size,
    generations,
    initial_rows,
)
from hcomc.rng import draw_seed


def _as_2d(a: Any, n_cols: int) -> FloatArray:
    """``a`` as a float (p, n_cols) array; pymoo gives 1-D arrays for single solutions."""
    return np.asarray(a, dtype=np.float64).reshape(-1, n_cols)


class _PymooProblem(_PymooBaseProblem):
    """pymoo view of one of our problems: vectorised, keeping every evaluated row.

    Parameters
    ----------
    problem : our problem; its bounds are copied, never modified.
    capacity : rows the run is planned to evaluate (the archive's first allocation).
    scalar : if True, expose one objective ``problem.scalarise(F, G)`` and no constraints
        (single-objective optimisers; the penalty is inside ``scalarise``), and track the
        best-scalarised row. Otherwise expose ``F`` and ``G`` as they are.

    Every evaluated row is kept, with its true ``F`` and ``G``, in :attr:`archive`
    (:class:`~hcomc.optim.base.Archive`), in evaluation order.
    """

    def __init__(self, problem: Problem, capacity: int, *, scalar: bool = False) -> None:
        self.problem = problem
        self.scalar = scalar
        n_var, n_obj, n_constr = int(problem.n_var), int(problem.n_obj), int(problem.n_constr)
        self.archive = Archive(capacity, n_var, n_obj, n_constr)
        super().__init__(
            n_var=n_var,
            n_obj=1 if scalar else n_obj,
            n_ieq_constr=0 if scalar else n_constr,
            xl=np.array(problem.xl, dtype=np.float64, copy=True),
            xu=np.array(problem.xu, dtype=np.float64, copy=True),
        )

    @property
    def n_rows(self) -> int:
        """Rows evaluated so far."""
        return self.archive.size

    def _evaluate(self, x: FloatArray, out: dict[str, Any], *args: Any, **kwargs: Any) -> None:
        X = np.asarray(x, dtype=np.float64)
        F, G = self.problem.evaluate(X)
        n = X.shape[0]
        F = np.asarray(F, dtype=np.float64).reshape(n, int(self.problem.n_obj))
        G = np.asarray(G, dtype=np.float64).reshape(n, int(self.problem.n_constr))
        if not self.scalar:
            self.archive.add(X, F, G)
            out["F"] = F
            if self.n_ieq_constr > 0:
                out["G"] = G
            return
        cost = np.asarray(self.problem.scalarise(F, G), dtype=np.float64).reshape(-1)
        self.archive.add(X, F, G, cost)
        out["F"] = cost[:, None]


@dataclass(frozen=True, slots=True)
class NSGA2Optimizer:
    """NSGA-II (Deb et al. 2002) from pymoo, returning the non-dominated set of all evaluations.

    Parameters
    ----------
    pop_size : population size (rows per generation).
    crossover_eta, crossover_prob : SBX distribution index and probability (pymoo defaults).
    mutation_eta : polynomial-mutation distribution index (pymoo default; per-variable
        probability min(0.5, 1/n_var)).
    eliminate_duplicates : pymoo's duplicate elimination. Off by default: with continuous
        variables exact duplicates are vanishingly rare, and the pairwise check would run in
        every generation of a decision.

    Notes
    -----
    Tournament by domination then crowding, rank-and-crowding survival, duplicate elimination
    (pymoo defaults otherwise). The returned set is the feasible, mutually
    non-dominated subset of *every* evaluated row (an archive: with a small population, the
    final population alone can hold fewer good trade-offs than were found on the way); if no
    row is feasible it is pymoo's single least-violating row, with ``feasible`` False.
    """

    pop_size: int = 24
    crossover_eta: float = 15.0
    crossover_prob: float = 0.9
    mutation_eta: float = 20.0
    eliminate_duplicates: bool = False
    name: str = field(default="nsga2-pymoo", init=False)

    def __post_init__(self) -> None:
        check_pop_size(self.pop_size)

    def minimize(
        self,
        problem: Problem,
        *,
        budget: int,
        rng: np.random.Generator,
        initial: FloatArray | None = None,
    ) -> ParetoResult:
        """Run ``max(1, budget // pop_size)`` generations and return the non-dominated set."""
        check_budget(budget)
        adapter = _PymooProblem(problem, self.pop_size * generations(budget, self.pop_size))
        first = initial_rows(problem, initial, self.pop_size, rng)
        algorithm = NSGA2(
            pop_size=self.pop_size,
            sampling=FloatRandomSampling() if first is None else first,
            crossover=SBX(eta=self.crossover_eta, prob=self.crossover_prob),
            mutation=PM(eta=self.mutation_eta),
            eliminate_duplicates=self.eliminate_duplicates,
        )
        res = _pymoo_minimize(
            adapter,
            algorithm,
            get_termination("n_gen", generations(budget, self.pop_size)),
            seed=draw_seed(rng),
            verbose=False,
            save_history=False,
        )
        archive = adapter.archive
        n = archive.size
        X, F, G = archive.X[:n], archive.F[:n], archive.G[:n]
        keep = archive_front(F, G)
        if keep.size == 0:
            # pymoo's least-infeasible individual (res.opt is None when nothing is feasible)
            opt = res.algorithm.opt
            return ParetoResult(
                X=_as_2d(opt.get("X"), problem.n_var)[:1],
                F=_as_2d(opt.get("F"), problem.n_obj)[:1],
                G=_as_2d(opt.get("G"), problem.n_constr)[:1]
                if problem.n_constr > 0
                else np.zeros((1, 0)),
                feasible=np.zeros(1, dtype=bool),
                n_eval=adapter.n_rows,
                algorithm=self.name,
            )
        return ParetoResult(
            X=X[keep],
            F=F[keep],
            G=G[keep],
            feasible=np.ones(keep.size, dtype=bool),
            n_eval=adapter.n_rows,
            algorithm=self.name,
        )


@dataclass(frozen=True, slots=True)
class PSOOptimizer:
    """Particle swarm optimisation from pymoo on the scalarised problem.

    Minimises ``problem.scalarise(F, G)`` as a single unconstrained objective (the constraint
    penalty is inside ``scalarise``), with pymoo's adaptive PSO (w = 0.9, c1 = c2 = 2.0 as the
    starting values, fuzzy adaptation, Latin hypercube initialisation).

    Parameters
    ----------
    pop_size : swarm size (rows per generation); pymoo's default is 25, 24 shares the budget
        layout with NSGA-II.
    w, c1, c2 : inertia and cognitive / social weights (initial values when ``adaptive``).
    adaptive : pymoo's fuzzy adaptation of ``w``, ``c1``, ``c2``.

    Notes
    -----
    Returns the feasible, mutually non-dominated subset of every evaluated row (kept by the
    adapter, so no extra evaluation is spent), with its true ``F`` and ``G``; when none is
    feasible, the best-scalarised row (the first row seen wins ties). Registered as
    ``pso-pymoo``: ``pso`` (:class:`~hcomc.optim.pso.optimizer.CompiledPSOOptimizer`) makes the same
    decisions without pymoo's per-individual objects.
    """

    pop_size: int = 24
    w: float = 0.9
    c1: float = 2.0
    c2: float = 2.0
    adaptive: bool = True
    name: str = field(default="pso-pymoo", init=False)

    def __post_init__(self) -> None:
        check_pop_size(self.pop_size)

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
        capacity = self.pop_size * generations(budget, self.pop_size)
        adapter = _PymooProblem(problem, capacity, scalar=True)
        first = initial_rows(problem, initial, self.pop_size, rng)
        algorithm = PSO(
            pop_size=self.pop_size,
            w=self.w,
            c1=self.c1,
            c2=self.c2,
            adaptive=self.adaptive,
            **({} if first is None else {"sampling": first}),
        )
        _pymoo_minimize(
            adapter,
            algorithm,
            get_termination("n_gen", generations(budget, self.pop_size)),
            seed=draw_seed(rng),
            verbose=False,
            save_history=False,
        )
        return adapter.archive.result(adapter.n_rows, self.name)
