"""Simulated annealing on arrays: SciPy's generalized simulated annealing, without SciPy's
per-call objects.

:class:`CompiledAnnealingOptimizer` runs the generalized simulated annealing of
:class:`~hcomc.optim.annealing.AnnealingOptimizer` (SciPy's ``dual_annealing`` with
``no_local_search=True``, ``maxiter = maxfun = budget``) on plain arrays. SciPy spends about as
much per call as the merge problem's compiled row evaluation: the strategy chain, the visiting
distribution's dozen numpy calls on tiny arrays, its numpy-scalar arithmetic and the energy
state's copies. Here one call is the generator's draws, one numba kernel for the move, the
row's evaluation and plain float arithmetic for the acceptance. The run draws the same random
numbers, in the same order and shapes, from the same generator (a fresh
``numpy.random.default_rng(draw_seed(rng))``; ``random`` where SciPy asks ``uniform`` on
[0, 1), the same numbers without the argument handling), and follows SciPy's formulas in
SciPy's order of operations.

Every ``exp``, ``log`` and ``sin`` is the C library's: in the kernels through numba, elsewhere
through Python's ``math`` (:mod:`hcomc.optim.ieee`, which adds the special values where
``math`` raises); the step scale's constant ``lgamma`` is SciPy's ``gammaln``. None is numpy's,
whose float64 functions are chosen by the CPU at run time (SIMD versions on AVX-512 differ
in the last bit), so a run is the same on every processor. SciPy takes numpy's: where those
differ from the C library's, a step or an acceptance can differ from SciPy's in the last bit
and the run goes its own way. The tests hold the compiled SA to SciPy's solution quality on the
recorded merge problems (hypervolume and best Eq. 19 cost, ``tests/unit/test_sa_compiled.py``),
not to SciPy's rows.

The run, as SciPy makes it:

1. the start is ``initial``'s first row (clipped) or uniform in the box, and is evaluated;
2. chain ``i`` (from 0) runs at ``T = initial_temp (2^(qv-1) - 1) / ((2+i)^(qv-1) - 1)``:
   ``n_var`` moves of every variable, then one move per variable, each by a distorted
   Cauchy-Lorentz step of scale set by ``T``, wrapped into the box; a lower cost is taken, a
   higher one with the generalized Metropolis probability at temperature ``T / (i + 1)``;
3. once ``T`` falls below ``restart_temp_ratio * initial_temp`` the current point is
   re-drawn uniformly in the box and evaluated (re-annealing), and ``i`` starts again at 0;
4. the run ends after ``budget`` evaluations.

Without local search SciPy's best energy, ``not_improved_idx`` and chain minimum never feed
back into a move, so they are not kept. The objective wrapper is the SciPy optimiser's own
(:class:`~hcomc.optim.annealing._Objective`), so rows are counted, capped at the budget, scored
(through the single-row path when the problem offers one) and kept exactly as there: in an
:class:`~hcomc.optim.base.Archive` of ``budget`` rows allocated once, the single-row path
scoring straight into the archive's row, the best-scalarised row tracked by index on the true
cost (non-finite costs are annealed as ``1e300``).

What is returned, and why: SA anneals the scalarised cost, but returns what every optimiser
here returns, the feasible, mutually non-dominated subset of every row it evaluated
(:func:`hcomc.optim.base.archive_front`: one per distinct objective vector, in evaluation order,
with its true ``F`` and ``G``); only when no evaluated row is feasible, its best-scalarised row
(NaN as inf, the first seen wins ties). The controller's selection rule (Eq. 19, paper Section
III-C-2) then picks from SA's set as it does from NSGA-II's, so that the comparison of NSGA-II,
PSO and SA (paper Section IV, Table II) compares the optimisers' searches under one selection
rule. A warm start anneals from ``initial``'s first row (for a replan seeded with the previous
set, its first member in evaluation order).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import gammaln

from hcomc._typing import FloatArray
from hcomc.optim.annealing import _Objective
from hcomc.optim.base import ParetoResult, Problem, check_budget
from hcomc.optim.ieee import divide, exp, log, sin
from hcomc.optim.visiting import TAIL_LIMIT, move_all, move_one
from hcomc.rng import draw_seed


class _Visiting:
    """SciPy's ``VisitingDistribution`` for one run: its constants and the per-temperature
    scale of the steps; a move allocates nothing but the generator's draws."""

    def __init__(self, visit: float, box: FloatArray, gen: np.random.Generator) -> None:
        self.visit, self.box, self.gen = float(visit), box, gen
        v = self.visit  # SciPy's constants, in SciPy's order of operations
        factor2 = exp((4.0 - v) * log(v - 1.0))
        factor3 = exp(divide((2.0 - v) * log(2.0), v - 1.0))
        self.factor4_p = divide(math.sqrt(math.pi) * factor2, factor3 * (3.0 - v))
        factor5 = divide(1.0, v - 1.0) - 0.5
        d1 = 2.0 - factor5
        ratio = divide(math.pi * (1.0 - factor5), sin(math.pi * (1.0 - factor5)))
        self.factor6 = divide(ratio, exp(float(gammaln(d1))))
        self.sigma = 1.0

    def set_temperature(self, temperature: float) -> None:
        """The steps' scale at ``temperature`` (SciPy recomputes it on every call)."""
        v = self.visit
        factor1 = exp(divide(log(temperature), v - 1.0))
        factor4 = self.factor4_p * factor1
        self.sigma = exp(divide(-(v - 1.0) * log(divide(self.factor6, factor4)), 3.0 - v))

    def _den_one(self, xy: FloatArray) -> float:
        """``exp((qv - 1) log|y| / (3 - qv))`` of one pair of normals ``xy`` (of ``y``, the
        second), with the C library's ``exp`` and ``log`` (0 where ``y`` is 0)."""
        v, y = self.visit, abs(float(xy[0, 1]))
        return exp(divide((v - 1.0) * log(y), 3.0 - v))

    def all(self, x: FloatArray, out: FloatArray) -> None:
        """A move of every variable of ``x`` into ``out``: normals (n_var, 2), then two
        uniforms for the tails."""
        xy = self.gen.normal(size=(x.size, 2))
        samples = self.gen.random(2)  # uniform(size=2): 0 + 1 u is u
        move_all(x, xy, samples, self.sigma, self.visit, self.box, out)

    def one(self, x: FloatArray, k: int, out: FloatArray) -> None:
        """A move of variable ``k`` alone: normals (1, 2), a uniform only for a tail step."""
        xy = self.gen.normal(size=(1, 2))
        step = divide(float(xy[0, 0]) * self.sigma, self._den_one(xy))  # inf where den is 0
        if step > TAIL_LIMIT:
            step = TAIL_LIMIT * self.gen.random()
        elif step < -TAIL_LIMIT:
            step = -TAIL_LIMIT * self.gen.random()
        move_one(x, k, step, self.box, out)


def accepts(r: float, e: float, current: float, temperature_step: float, accept: float) -> bool:
    """SciPy's acceptance of a cost ``e`` not below ``current`` for the uniform draw ``r``:
    ``r <= (1 - (1 - qa) (e - current) / T_step)^(1 / (1 - qa))``, 0 where the base is not
    positive.

    The power is taken with the C library's ``exp`` and ``log`` (:mod:`hcomc.optim.ieee`,
    IEEE 754's inf and NaN where a temperature step of 0, an overflow or ``accept`` = 1 make
    Python raise). A NaN base gives a NaN probability, which rejects, as in SciPy.
    """
    base = 1.0 - divide((1.0 - accept) * (e - current), temperature_step)
    if base <= 0.0:
        return r <= 0.0
    return r <= exp(divide(log(base), 1.0 - accept))


class _Annealing:
    """One run's state: SciPy's current point and energy, its generator and evaluations."""

    def __init__(
        self,
        opt: CompiledAnnealingOptimizer,
        cost: _Objective,
        lower: FloatArray,
        upper: FloatArray,
        gen: np.random.Generator,
    ) -> None:
        self.cost, self.lower, self.upper, self.gen = cost, lower, upper, gen
        self.accept = float(opt.accept)
        self.visiting = _Visiting(opt.visit, np.stack([lower, upper - lower]), gen)
        self.x = np.empty(lower.size)
        self.e = 0.0
        self._trial = np.empty(lower.size)

    def start(self, x0: FloatArray | None = None) -> None:
        """SciPy's ``EnergyState.reset``: ``x0`` or a uniform point, evaluated. The cost SciPy
        sees is always finite, so it never re-draws the point."""
        if x0 is None:
            self.x = self.gen.uniform(self.lower, self.upper, size=self.lower.size)
        else:
            self.x = np.array(x0, dtype=np.float64, copy=True)
        self.e = self.cost(self.x)

    def chain(self, step: int, temperature: float) -> bool:
        """SciPy's ``StrategyChain.run`` without local search; True once the budget is spent."""
        temperature_step = temperature / float(step + 1)
        self.visiting.set_temperature(temperature)
        n, cost = self.x.size, self.cost
        if cost.n_calls >= cost.budget:
            return True  # the hard cap (after a re-annealing start): SciPy would go one over
        for j in range(2 * n):
            trial = self._trial
            if j < n:
                self.visiting.all(self.x, trial)
            else:
                self.visiting.one(self.x, j - n, trial)
            e = cost(trial)
            if e < self.e or accepts(self.gen.random(), e, self.e, temperature_step, self.accept):
                self.x, self._trial, self.e = trial, self.x, e
            if cost.n_calls >= cost.budget:
                return True
        return False


def _check(lower: FloatArray, upper: FloatArray, restart_temp_ratio: float) -> None:
    """SciPy's checks of the box and the restart ratio, with its messages."""
    if restart_temp_ratio <= 0.0 or restart_temp_ratio >= 1.0:
        raise ValueError("Restart temperature ratio has to be in range (0, 1)")
    if not (np.isfinite(lower).all() and np.isfinite(upper).all()):
        raise ValueError("Some bounds values are inf values or nan values")
    if not np.all(lower < upper):
        raise ValueError("Bounds are not consistent min < max")


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels of this module now."""
    box, x, out = np.array([[0.0, 0.0], [1.0, 1.0]]), np.full(2, 0.5), np.empty(2)
    move_all(x, np.ones((2, 2)), np.full(2, 0.5), 0.1, 2.62, box, out)
    move_one(x, 1, 0.1, box, out)


@dataclass(frozen=True, slots=True)
class CompiledAnnealingOptimizer:
    """Generalized simulated annealing on arrays, SciPy's algorithm with the C library's math
    (see the module).

    Parameters
    ----------
    initial_temp, restart_temp_ratio, visit, accept : SciPy's annealing parameters (SciPy
        defaults). SA has no population: ``pop_size`` is not an option (it is rejected).
    row_path : score rows through the problem's single-row fast path when it offers one
        (:class:`~hcomc.optim.base.RowProblem`); False scores them with ``evaluate`` and
        ``scalarise`` on one-row populations (the same run, slower).

    Notes
    -----
    Returns the feasible non-dominated subset of every evaluated row, or the best-scalarised
    row when none is feasible (see the module docstring). ``n_eval == budget``.
    """

    initial_temp: float = 5230.0
    restart_temp_ratio: float = 2e-5
    visit: float = 2.62
    accept: float = -5.0
    row_path: bool = True
    name: str = field(default="sa", init=False)

    def __post_init__(self) -> None:
        warm_up()  # load the compiled kernels now, not inside a timed decision

    def minimize(
        self,
        problem: Problem,
        *,
        budget: int,
        rng: np.random.Generator,
        initial: FloatArray | None = None,
    ) -> ParetoResult:
        """Anneal with ``budget`` single-row evaluations; return the feasible non-dominated set
        of every row evaluated.

        With ``initial``, the annealing starts from its first row (clipped to the bounds).
        """
        check_budget(budget)
        lower = np.array(problem.xl, dtype=np.float64, copy=True)
        upper = np.array(problem.xu, dtype=np.float64, copy=True)
        x0 = None if initial is None or len(initial) == 0 else np.clip(initial[0], lower, upper)
        if x0 is not None and len(x0) != len(lower):
            raise ValueError("Bounds size does not match x0")
        _check(lower, upper, self.restart_temp_ratio)
        cost = _Objective(problem, budget, self.row_path)
        run = _Annealing(self, cost, lower, upper, np.random.default_rng(draw_seed(rng)))
        run.start(x0)
        t1 = exp((self.visit - 1.0) * log(2.0)) - 1.0  # the C library's, as every step
        restart = self.initial_temp * self.restart_temp_ratio
        step = iteration = 0
        while iteration < budget:  # SciPy's maxiter: never reached before maxfun
            t2 = exp((self.visit - 1.0) * log(float(step) + 2.0)) - 1.0
            temperature = divide(self.initial_temp * t1, t2)
            if temperature < restart:  # re-annealing from a new random point
                if cost.n_calls >= budget:
                    break  # the hard cap
                run.start()
                step = 0
                continue
            if run.chain(step, temperature):
                break
            step, iteration = step + 1, iteration + 1
        return cost.result(self.name)
