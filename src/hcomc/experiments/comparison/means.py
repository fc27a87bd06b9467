"""The per-controller numbers beside a comparison's paired effects: per cell, configuration
and metric the mean over the runs with a value and the half-width of its 95 % t interval
(:func:`hcomc.experiments.tables.mean_ci`, as Tables II and III give them).

A run whose ramp vehicle never merged has no value of a merge metric and does not enter its
mean; merge success counts it (:mod:`hcomc.experiments.comparison.success`), and ``n``
against ``runs`` shows how many runs a mean rests on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields

import pandas as pd

from hcomc.experiments.comparison.effects import _cells, check_runs
from hcomc.experiments.tables import mean_ci

__all__ = ["MEANS_COLUMNS", "Mean", "means"]


@dataclass(frozen=True)
class Mean:
    """One metric of one configuration in one cell: mean over ``n`` of its ``runs`` (those
    with a finite value) and the half-width ``ci`` of its 95 % t interval (NaN for n < 2)."""

    condition: str
    configuration: str
    metric: str
    mean: float
    ci: float
    n: int
    runs: int


MEANS_COLUMNS = tuple(f.name for f in fields(Mean))


def means(
    runs: pd.DataFrame, configurations: Sequence[str] | None, metrics: Sequence[str]
) -> pd.DataFrame:
    """:class:`Mean` per cell, configuration (one run per seed) and metric of ``runs``."""
    check_runs(runs)
    records = []
    for condition, conf, part in _cells(runs, configurations):
        for metric in metrics:
            values = part[metric] if metric in part else pd.Series(dtype=float)
            mean, half, n = mean_ci(values)
            records.append(Mean(condition, conf, metric, mean, half, n, len(part)))
    return pd.DataFrame([asdict(r) for r in records], columns=list(MEANS_COLUMNS))
