"""Simulated annealing: SciPy's ``dual_annealing`` behind our Optimizer interface.

pymoo has no simulated annealing, so the SA baseline wraps SciPy's maintained generalized
simulated annealing and minimises ``problem.scalarise(F, G)``. Registered as ``sa-scipy``, the
reference of ``sa`` (:mod:`hcomc.optim.sa`), which runs the same annealing on arrays, without
SciPy's per-call Python machinery and with the C library's math instead of numpy's.

What is returned, and why: the annealing searches on the scalarised cost, but the optimiser
returns what every optimiser here returns, the feasible, mutually non-dominated subset of every
row it evaluated (:func:`hcomc.optim.base.archive_front`: one per distinct objective vector, in
evaluation order, with its true ``F`` and ``G``), kept in an
:class:`~hcomc.optim.base.Archive` of ``budget`` rows allocated once; only when no evaluated
row is feasible, the best-scalarised row. The controller's selection rule (Eq. 19, paper
Section III-C-2) then picks from SA's set as it does from NSGA-II's, so that the comparison of
NSGA-II, PSO and SA (paper Section IV, Table II) compares the optimisers' searches under one
selection rule.

* ``no_local_search=True``: traditional generalized SA, no L-BFGS-B polishing (the
  finite-difference local search would spend evaluations on a non-smooth, simulated
  objective).
* Budget: ``maxfun=budget`` with ``maxiter=budget``, so the evaluation count, not the
  iteration count, ends the run (one iteration costs ``2 n_var`` calls). ``maxfun`` is a soft
  limit in SciPy: a re-annealing restart spends one call before the limit is checked again.
  The objective wrapper therefore also enforces a hard cap: a call beyond the budget raises a
  private exception that :meth:`AnnealingOptimizer.minimize` catches, and the set of the rows
  evaluated so far is returned. ``n_eval <= budget`` always.
* Non-finite costs (an infinite penalty, NaN) are passed to SciPy as a large finite value
  (``1e300``): SciPy would otherwise re-sample its starting point up to 1000 times and then
  raise. The best-scalarised row is tracked on the true cost.
* Seeding: ``dual_annealing`` takes ``rng=`` since SciPy 1.15 (``seed=`` before, still
  accepted as a legacy alias). A fresh ``numpy.random.Generator`` seeded with
  :func:`hcomc.rng.draw_seed` from the caller's generator is passed through whichever
  keyword the installed SciPy has.
* SciPy calls the objective one point at a time, so each call is ``problem.evaluate`` on one
  row: inherent to SA and slower per row than the population-based optimisers. A problem that
  offers the single-row fast path (:class:`~hcomc.optim.base.RowProblem`, e.g. the HCOMC
  merge problem) is scored through it instead, straight into the archive's row: the same
  ``F``, ``G`` and cost bit for bit, hence the same annealing, without the population
  machinery.
"""

from __future__ import annotations

import contextlib
import inspect
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import dual_annealing

from hcomc._typing import FloatArray
from hcomc.optim.base import Archive, ParetoResult, Problem, RowProblem, check_budget
from hcomc.rng import draw_seed

_NONFINITE_COST = 1e300
_RNG_KEYWORD = "rng" if "rng" in inspect.signature(dual_annealing).parameters else "seed"


class _BudgetExhaustedError(Exception):
    """Raised by the objective wrapper when SciPy asks for more calls than the budget."""


class _Objective:
    """Scalar objective for SciPy: one row per call, counted and kept in an archive.

    Every row goes into :attr:`archive` (an :class:`~hcomc.optim.base.Archive` of ``budget``
    rows, allocated once): through the problem's single-row fast path when it has one
    (:class:`~hcomc.optim.base.RowProblem`, scored straight into the archive's row, ``x``
    copied after it), else through ``evaluate`` + ``scalarise`` on a one-row population,
    copied in. The archive tracks the best-scalarised row by index on the true cost.
    """

    def __init__(self, problem: Problem, budget: int, row_path: bool = True) -> None:
        self.problem = problem
        self.budget = budget
        self.n_calls = 0
        n_var, n_obj, n_constr = int(problem.n_var), int(problem.n_obj), int(problem.n_constr)
        self.archive = Archive(budget, n_var, n_obj, n_constr)
        self._row = problem if row_path and isinstance(problem, RowProblem) else None

    def __call__(self, x: FloatArray) -> float:
        """Cost of one point for SciPy (non-finite mapped to ``1e300``), counted and kept."""
        k = self.n_calls
        if k >= self.budget:
            raise _BudgetExhaustedError
        archive = self.archive
        if self._row is not None:  # the archive has room for the budget: row k is free
            cost = float(self._row.evaluate_row(x, archive.F[k], archive.G[k]))
            archive.X[k] = x
            archive.keep(k, cost)
        else:
            X = np.array(x, dtype=np.float64, copy=True).reshape(1, -1)
            F, G = self.problem.evaluate(X)
            F = np.asarray(F, dtype=np.float64).reshape(1, int(self.problem.n_obj))
            G = np.asarray(G, dtype=np.float64).reshape(1, int(self.problem.n_constr))
            costs = np.asarray(self.problem.scalarise(F, G), dtype=np.float64).reshape(-1)
            archive.add(X, F, G, costs)
            cost = float(costs[0])
        self.n_calls = k + 1
        return cost if math.isfinite(cost) else _NONFINITE_COST

    def result(self, algorithm: str) -> ParetoResult:
        """The returned set of the rows evaluated so far
        (:meth:`~hcomc.optim.base.Archive.result`)."""
        return self.archive.result(self.n_calls, algorithm)


@dataclass(frozen=True, slots=True)
class AnnealingOptimizer:
    """Generalized simulated annealing (SciPy ``dual_annealing``) on the scalarised problem.

    Parameters
    ----------
    initial_temp, restart_temp_ratio, visit, accept : SciPy's annealing parameters (SciPy
        defaults). SA has no population: ``pop_size`` is not an option (it is rejected).
    row_path : score rows through the problem's single-row fast path when it offers one
        (:class:`~hcomc.optim.base.RowProblem`). False scores them with ``evaluate`` and
        ``scalarise`` on one-row populations: the same decisions bit for bit, only slower;
        the switch exists to verify and to measure exactly that.

    Notes
    -----
    Returns the feasible non-dominated subset of every evaluated row, or the best-scalarised
    row when none is feasible; see the module docstring for this and for the budget and
    seeding rules. Registered as ``sa-scipy``: ``sa``
    (:class:`~hcomc.optim.sa.CompiledAnnealingOptimizer`) runs the same algorithm without
    SciPy's per-call Python machinery.
    """

    initial_temp: float = 5230.0
    restart_temp_ratio: float = 2e-5
    visit: float = 2.62
    accept: float = -5.0
    row_path: bool = True
    name: str = field(default="sa-scipy", init=False)

    def minimize(
        self,
        problem: Problem,
        *,
        budget: int,
        rng: np.random.Generator,
        initial: FloatArray | None = None,
    ) -> ParetoResult:
        """Anneal with at most ``budget`` single-row evaluations; return the feasible
        non-dominated set of every row evaluated.

        With ``initial``, the annealing starts from its first row (clipped to the bounds).
        """
        check_budget(budget)
        objective = _Objective(problem, budget, self.row_path)
        lower = np.array(problem.xl, dtype=np.float64, copy=True)
        upper = np.array(problem.xu, dtype=np.float64, copy=True)
        generator = np.random.default_rng(draw_seed(rng))
        # past the hard cap the wrapper raises; the rows evaluated so far give the answer
        with contextlib.suppress(_BudgetExhaustedError):
            dual_annealing(
                objective,
                bounds=list(zip(lower, upper, strict=True)),
                maxiter=budget,
                maxfun=budget,
                initial_temp=self.initial_temp,
                restart_temp_ratio=self.restart_temp_ratio,
                visit=self.visit,
                accept=self.accept,
                no_local_search=True,
                x0=None
                if initial is None or len(initial) == 0
                else np.clip(initial[0], lower, upper),
                **{_RNG_KEYWORD: generator},
            )
        return objective.result(self.name)
