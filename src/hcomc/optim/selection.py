r"""Picking one plan from a Pareto set: the paper's Eq. 19 rule, and a non-dominated filter.

Eq. 19 (paper Section III-C-2):

1. If every candidate has ``U_safe`` above the threshold (4 m/s^2), pick the one with the
   smallest ``U_safe``.
2. Otherwise, among the candidates with ``U_safe <= threshold``, min-max normalise the fuel cost
   ``U_fuel`` and the efficiency cost ``-U_eff`` over that subset and pick the smallest sum

   .. math:: U = \frac{c_{eff} - \min c_{eff}}{\max c_{eff} - \min c_{eff}}
                 + \frac{U_{fuel} - \min U_{fuel}}{\max U_{fuel} - \min U_{fuel}}.

The paper normalises ``U_eff`` itself as if it were a cost; the problem minimises ``-U_eff``,
so the ``efficiency`` column is already a cost and the rule is applied to it unchanged (the
consistent reading).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hcomc._typing import BoolArray, FloatArray
from hcomc.optim.dominance import non_dominated_mask

SAFETY = "safety"
FUEL = "fuel"
EFFICIENCY = "efficiency"


def non_dominated(F: FloatArray) -> BoolArray:
    """Mask of the non-dominated rows of ``F`` (all objectives minimised).

    Row ``i`` dominates row ``j`` if it is no worse in every objective and strictly better in
    at least one. Identical rows do not dominate each other, so duplicates of a non-dominated
    point are all kept. Comparisons with NaN are false: a row containing NaN neither dominates
    nor is dominated through that column.

    Parameters
    ----------
    F : (n, m) objective values.

    Returns
    -------
    (n,) boolean mask, True for rows that no other row dominates.

    Notes
    -----
    Pairwise, O(n^2 m) time, compiled (:func:`hcomc.optim.dominance.non_dominated_mask`).
    """
    F = np.ascontiguousarray(F, dtype=np.float64)
    if F.ndim != 2:
        raise ValueError(f"F must be 2-D (n, m), got shape {F.shape}")
    mask: BoolArray = non_dominated_mask(F)
    return mask


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
    """Index of the row of ``F`` chosen by the paper's Eq. 19 rule.

    Parameters
    ----------
    F : (n, m) objectives of the candidate set, all minimised; the columns named ``"safety"``
        (U_safe, critical acceleration [m/s^2]), ``"fuel"`` (U_fuel) and ``"efficiency"``
        (-U_eff, a cost) are used, other columns are ignored.
    names : the m column names of ``F``.
    feasible : (n,) optional feasibility mask. If any row is feasible only feasible rows are
        considered; otherwise (or if None) all rows are.
    safety_threshold : the U_safe gate [m/s^2] (paper: 4, MOBIL's b_safe;
        ``config.control.safety_threshold``).

    Returns
    -------
    Index into the rows of ``F``.

    Notes
    -----
    * All considered rows above the threshold: minimum ``safety``; ties go to the lower
      ``fuel``, then to the lower index.
    * Otherwise, over the rows with ``safety <= safety_threshold``: min-max normalise ``fuel``
      and ``efficiency`` over that subset (a constant column normalises to 0) and take the
      minimum sum; ties go to the lower index.
    * A NaN ``safety`` never passes the gate and sorts last in the first branch; a candidate
      whose normalised sum is NaN (non-finite cost) ranks after every finite one.
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
    """Eq. 19's cost of every row of ``F`` (the quantity :func:`select_eq19` minimises), so
    that two candidates of one set can be compared by how much one is worse.

    Rows are considered as in :func:`select_eq19`. If some considered row has ``safety <=
    safety_threshold``, a row of that gate subset costs the sum of its min-max normalised
    ``fuel`` and ``efficiency`` over the subset (range [0, 2]; NaN becomes +inf); otherwise a
    considered row costs its ``safety`` min-max normalised over the considered rows (range
    [0, 1]). Rows not considered cost +inf.
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
    """Which branch of Eq. 19 :func:`select_eq19` takes on this set.

    ``"gate"``: some considered row has U_safe <= threshold (normalised fuel + efficiency);
    ``"min_safety"``: every considered row is above the threshold (smallest U_safe).
    """
    F = np.asarray(F, dtype=np.float64)
    rows = np.ones(F.shape[0], dtype=bool)
    if feasible is not None and np.any(feasible):
        rows = np.asarray(feasible, dtype=bool)
    safety = F[rows, _column(names, SAFETY)]
    return "gate" if bool(np.any(safety <= safety_threshold)) else "min_safety"
