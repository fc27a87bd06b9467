"""Re-exports for one release: the non-dominated filter (``non_dominated``, now
:func:`hcomc.equations.pareto.pareto_optimal`, paper Eq. 18) and the Eq. 19 choice of one
plan (:mod:`hcomc.equations.selection`). Import them from there.
"""

from __future__ import annotations

from hcomc.equations.pareto import pareto_optimal as non_dominated
from hcomc.equations.selection import (
    EFFICIENCY,
    FUEL,
    SAFETY,
    eq19_branch,
    eq19_costs,
    select_eq19,
)

__all__ = [
    "EFFICIENCY",
    "FUEL",
    "SAFETY",
    "eq19_branch",
    "eq19_costs",
    "non_dominated",
    "select_eq19",
]
