r"""The choice of one plan from the Pareto set, paper Eq. (19).

"After getting the Pareto optimal solution set of NSGA-II, the unique optimal solution needs
to be picked out as the final output of the optimization model" (Section III-C-2):

1. If :math:`U_\mathrm{safe} > 4` (every candidate), select the merging plan with the
   smallest :math:`U_\mathrm{safe}` (Eq. 15, the critical acceleration [m/s^2]).
2. Otherwise, among the candidates with :math:`U_\mathrm{safe} \le 4`, min-max normalise the
   efficiency cost and the economy cost :math:`U_\mathrm{fuel}` (Eq. 16) and select the
   smallest sum

   .. math::
      U = \frac{U_\mathrm{eff} - \min U_\mathrm{eff}}
               {\max U_\mathrm{eff} - \min U_\mathrm{eff}}
        + \frac{U_\mathrm{fuel} - \min U_\mathrm{fuel}}
               {\max U_\mathrm{fuel} - \min U_\mathrm{fuel}}.

The paper normalises :math:`U_\mathrm{eff}` (Eq. 17, an incentive: larger is better) itself as
if it were a cost; the problem minimises :math:`-U_\mathrm{eff}`, so the ``efficiency`` column
is already a cost and the rule is applied to it unchanged (the consistent reading). The 4 m/s^2
gate is MOBIL's safe deceleration; it is a parameter here. The public function is
:func:`select_eq19`; :func:`eq19_costs` gives the quantity it minimises and
:func:`eq19_branch` the case it takes. The multi-objective problem of Eq. (18) whose Pareto set
this chooses from is :meth:`hcomc.control.hierarchical.problem.MergeProblem.evaluate`.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-C-2, Eq. (19).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hcomc._typing import BoolArray, FloatArray

__all__ = ["EFFICIENCY", "FUEL", "SAFETY", "eq19_branch", "eq19_costs", "select_eq19"]

SAFETY = "safety"
"""Name of the objective column U_safe (Eq. 15) [m/s^2]."""
FUEL = "fuel"
"""Name of the objective column U_fuel (Eq. 16)."""
EFFICIENCY = "efficiency"
"""Name of the objective column -U_eff (Eq. 17), a cost."""


def _column(names: Sequence[str], name: str) -> int:
    try:
        return list(names).index(name)
    except ValueError:
        raise ValueError(f"objective '{name}' not found in names {tuple(names)}") from None


def _minmax(values: FloatArray) -> FloatArray:
    """Min-max normalise to [0, 1]; a constant column normalises to 0."""
    lo, hi = values.min(), values.max()
    if hi == lo:
        return np.zeros_like(values)
    return (values - lo) / (hi - lo)


def select_eq19(
    F: FloatArray,
    names: Sequence[str],
    *,
    feasible: BoolArray | None = None,
    safety_threshold: float,
) -> int:
    r"""Index of the plan of a candidate set chosen by the rule of paper Eq. (19).

    .. math::
       :label: eq-19-selection

       i^* = \begin{cases}
         \arg\min_i U_{\mathrm{safe},i} & U_{\mathrm{safe},i} > \theta \ \forall i \\
         \arg\min_{i:\,U_{\mathrm{safe},i} \le \theta}
           \left(\hat c_{\mathrm{eff},i} + \hat U_{\mathrm{fuel},i}\right) & \text{otherwise}
       \end{cases}

    with :math:`\hat{\cdot}` the min-max normalisation over the gated subset and
    :math:`\theta` the safety threshold (4 m/s^2 in the paper).

    Parameters
    ----------
    F : numpy.ndarray
        Objectives of the candidate set, shape (n, m), all minimised; the columns named
        :data:`SAFETY` (:math:`U_\mathrm{safe}`, the critical acceleration of Eq. 15
        [m/s^2]), :data:`FUEL` (:math:`U_\mathrm{fuel}` of Eq. 16 [L]) and
        :data:`EFFICIENCY` (:math:`-U_\mathrm{eff}` of Eq. 17 [m/s^2], a cost) are used,
        other columns are ignored.
    names : sequence of str
        The m column names of ``F``.
    feasible : numpy.ndarray, optional
        Feasibility mask, shape (n,). If any row is feasible only feasible rows are
        considered; otherwise (or if None) all rows are.
    safety_threshold : float
        The :math:`U_\mathrm{safe}` gate :math:`\theta` [m/s^2] (paper: 4, MOBIL's
        :math:`b_\mathrm{safe}`; ``config.control.safety_threshold``).

    Returns
    -------
    int
        Index into the rows of ``F``.

    Raises
    ------
    ValueError
        If ``F`` is not (n, len(names)), is empty, lacks one of the three columns, or
        ``feasible`` has the wrong shape.

    Notes
    -----
    The paper leaves ties, constant columns, non-finite costs and infeasible candidates open:

    * All considered rows above the threshold: minimum ``safety``; ties go to the lower
      ``fuel``, then to the lower index.
    * Otherwise, over the rows with ``safety <= safety_threshold``: min-max normalise ``fuel``
      and ``efficiency`` over that subset (a constant column normalises to 0) and take the
      minimum sum; ties go to the lower index.
    * A NaN ``safety`` never passes the gate and sorts last in the first branch; a candidate
      whose normalised sum is NaN (non-finite cost) ranks after every finite one.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Section III-C-2, Eq. (19).

    Examples
    --------
    >>> F = np.array([[5.0, 1.0, 0.0], [3.0, 2.0, 0.0], [6.0, 0.5, -1.0]])
    >>> select_eq19(F, ["safety", "fuel", "efficiency"], safety_threshold=4.0)
    1
    """
    F = np.asarray(F, dtype=np.float64)
    if F.ndim != 2 or F.shape[1] != len(names):
        raise ValueError(f"F must have shape (n, {len(names)}), got {F.shape}")
    n = F.shape[0]
    if n == 0:
        raise ValueError("cannot select from an empty set")
    i_safe, i_fuel = _column(names, SAFETY), _column(names, FUEL)
    _column(names, EFFICIENCY)  # required, as the gate branch reads it

    candidates = np.arange(n)
    if feasible is not None:
        feasible = np.asarray(feasible, dtype=np.bool_)
        if feasible.shape != (n,):
            raise ValueError(f"feasible must have shape ({n},), got {feasible.shape}")
        if feasible.any():
            candidates = candidates[feasible]

    safety = F[candidates, i_safe]
    fuel = F[candidates, i_fuel]
    gate = safety <= safety_threshold
    if not gate.any():
        # lexsort: last key is primary; NaN sorts last
        order = np.lexsort((candidates, fuel, safety))
        return int(candidates[order[0]])
    subset = candidates[gate]
    costs = eq19_costs(F, names, feasible=feasible, safety_threshold=safety_threshold)
    return int(subset[np.argmin(costs[subset])])


def eq19_costs(
    F: FloatArray,
    names: Sequence[str],
    *,
    feasible: BoolArray | None = None,
    safety_threshold: float,
) -> FloatArray:
    """Eq. (19)'s cost of every row of ``F`` (the quantity :func:`select_eq19` minimises), so
    that two candidates of one set can be compared by how much one is worse.

    Rows are considered as in :func:`select_eq19`. If some considered row has ``safety <=
    safety_threshold``, a row of that gate subset costs the sum of its min-max normalised
    ``fuel`` and ``efficiency`` over the subset (range [0, 2]; NaN becomes +inf); otherwise a
    considered row costs its ``safety`` min-max normalised over the considered rows (range
    [0, 1]). Rows not considered cost +inf.

    Parameters
    ----------
    F : numpy.ndarray
        Objectives of the candidate set, shape (n, m), as for :func:`select_eq19`
        (``safety`` [m/s^2], ``fuel`` [L], ``efficiency`` [m/s^2]).
    names : sequence of str
        The m column names of ``F``.
    feasible : numpy.ndarray, optional
        Feasibility mask, shape (n,), as for :func:`select_eq19`.
    safety_threshold : float
        The :math:`U_\\mathrm{safe}` gate [m/s^2].

    Returns
    -------
    numpy.ndarray
        Cost of each row [-], shape (n,): normalised, so dimensionless; +inf for rows not
        considered.
    """
    F = np.asarray(F, dtype=np.float64)
    n = F.shape[0]
    i_safe, i_fuel, i_eff = (_column(names, c) for c in (SAFETY, FUEL, EFFICIENCY))
    considered = np.ones(n, dtype=bool)
    if feasible is not None and np.any(feasible):
        considered = np.asarray(feasible, dtype=np.bool_).copy()
    costs = np.full(n, np.inf)
    gate = considered & (F[:, i_safe] <= safety_threshold)
    if gate.any():
        total = _minmax(F[gate, i_fuel]) + _minmax(F[gate, i_eff])
        costs[gate] = np.where(np.isnan(total), np.inf, total)
    else:
        normalised = _minmax(F[considered, i_safe])
        costs[considered] = np.where(np.isnan(normalised), np.inf, normalised)
    return costs


def eq19_branch(
    F: FloatArray, names: Sequence[str], feasible: BoolArray | None, safety_threshold: float
) -> str:
    """Which branch of Eq. (19) :func:`select_eq19` takes on this set.

    Parameters
    ----------
    F : numpy.ndarray
        Objectives of the candidate set, shape (n, m), as for :func:`select_eq19`.
    names : sequence of str
        The m column names of ``F``.
    feasible : numpy.ndarray or None
        Feasibility mask, shape (n,), as for :func:`select_eq19`.
    safety_threshold : float
        The :math:`U_\\mathrm{safe}` gate [m/s^2].

    Returns
    -------
    str
        ``"gate"``: some considered row has :math:`U_\\mathrm{safe}` <= threshold (the
        normalised sum of fuel and efficiency decides); ``"min_safety"``: every considered
        row is above the threshold (the smallest :math:`U_\\mathrm{safe}` is chosen).
    """
    F = np.asarray(F, dtype=np.float64)
    rows = np.ones(F.shape[0], dtype=bool)
    if feasible is not None and np.any(feasible):
        rows = np.asarray(feasible, dtype=bool)
    safety = F[rows, _column(names, SAFETY)]
    return "gate" if bool(np.any(safety <= safety_threshold)) else "min_safety"
