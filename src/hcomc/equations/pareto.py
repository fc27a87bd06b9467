"""Eq. 18: the multi-objective merge problem and its Pareto optimal set.

The paper states the merge planning as "min F(x) = (f_1(x), ..., f_m(x)), s.t. x in Omega"
(Section III-C-2, Eq. 18): Omega is the decision space (the merge's timing, speeds and
sequence), F maps it to the objectives U_safe, U_eff and U_fuel (Eqs. 15-17), and "if there is
a solution x* in Omega, and meanwhile, there is no other solution to make F(x) dominate F(x*),
then x* can be called the Pareto optimal solution". The objectives of a candidate come from
its predicted merge (:meth:`hcomc.control.hierarchical.problem.MergeProblem.evaluate`); this
module is the solution concept: which of the evaluated candidates are Pareto optimal, the set
Eq. 19 then chooses one plan from.

Reference: Wang, Wang, Pan, Jiao and Claudel, "HCOMC: A Hierarchical Cooperative On-Ramp
Merging Control Framework in Mixed Traffic Environment on Two-Lane Highways",
arXiv:2507.11621, Section III-C-2, Eq. (18); Deb et al., "A fast and elitist multiobjective
genetic algorithm: NSGA-II", IEEE TEVC 6(2) (2002) for the dominance relation.
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray

__all__ = ["pareto_optimal"]


@kernel
def dominates(a: FloatArray, b: FloatArray) -> bool:
    """Whether objective vector ``a`` dominates ``b`` (all minimised): no worse in every
    objective and better in at least one; False when either holds a NaN where compared."""
    better = False
    for i in range(a.shape[0]):
        if not a[i] <= b[i]:
            return False
        if a[i] < b[i]:
            better = True
    return better


@kernel
def pareto_mask(F: FloatArray) -> BoolArray:
    """True for the rows of ``F`` that no other row dominates (pairwise, compiled)."""
    n = F.shape[0]
    keep = np.ones(n, dtype=np.bool_)
    for i in range(n):
        for j in range(n):
            if i != j and keep[j] and dominates(F[i], F[j]):
                keep[j] = False
    return keep


def pareto_optimal(F: FloatArray) -> BoolArray:
    """Which candidates are Pareto optimal solutions of the paper's Eq. 18.

    .. math::

        x^* \text{ is Pareto optimal} \\iff \nexists\\, x \\in \\Omega:\\;
        f_k(x) \\le f_k(x^*)\\ \forall k \\;\\wedge\\; f_k(x) < f_k(x^*)\\ \text{for some } k

    over the evaluated candidates, every objective minimised.

    Parameters
    ----------
    F : (n, m) array of float
        The objective vectors F(x) of n candidates (for the merge: U_safe [m/s^2], U_eff
        [m/s^2], U_fuel [mL]).

    Returns
    -------
    (n,) array of bool
        True for the rows that no other row dominates.

    Notes
    -----
    Identical rows do not dominate each other, so duplicates of a Pareto optimal point are all
    kept. Comparisons with NaN are false: a row containing NaN neither dominates nor is
    dominated through that column. Pairwise, O(n^2 m) time; feasibility (x in Omega) is the
    caller's: pass the feasible rows.
    """
    F = np.ascontiguousarray(F, dtype=np.float64)
    if F.ndim != 2:
        raise ValueError(f"F must be 2-D (n, m), got shape {F.shape}")
    mask: BoolArray = pareto_mask(F)
    return mask
