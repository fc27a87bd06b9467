"""The safety extremes of a controller comparison: per cell and configuration, the least time
to collision and the largest deceleration to avoid a crash over all its runs, each with the
seed it came from, and the collisions of those runs.

Means hide the worst case, which is what a safety argument is about; these are the worst
values the runs reached. Each run's ``min_ttc`` and ``max_drac`` are taken over every
follower–leader pair of a lane with a key vehicle in it (:mod:`hcomc.metrics.bodies`), and
``collisions`` counts every collision of the run (``key_collisions`` those involving a key
vehicle). A run without a least TTC (no pair ever closed in) does not enter its extreme; an
infinite DRAC (a pair that overlapped) is the largest; ``runs`` says how many runs the row
covers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields

import pandas as pd

from hcomc.experiments.comparison.effects import _cells, check_runs

__all__ = ["SAFETY_COLUMNS", "SafetyExtremes", "safety_extremes"]

NEEDS = ("min_ttc", "max_drac", "collisions")
"""The columns of a runs table the extremes are taken from (runs of the scenario engine)."""


@dataclass(frozen=True)
class SafetyExtremes:
    """The worst safety values of one configuration's runs in one cell."""

    condition: str
    configuration: str
    runs: int
    least_ttc: float  # [s], the least of the runs' finite least TTC (NaN: no run has one)
    least_ttc_seed: int  # the seed it came from (-1 without)
    max_drac: float  # [m/s^2], the largest of the runs' largest DRAC (inf: an overlap)
    max_drac_seed: int
    collisions: int  # of all runs
    key_collisions: int  # of those, involving a key vehicle


SAFETY_COLUMNS = tuple(f.name for f in fields(SafetyExtremes))


def safety_extremes(runs: pd.DataFrame, configurations: Sequence[str] | None) -> pd.DataFrame:
    """:class:`SafetyExtremes` per cell and configuration of ``runs``; an empty table when the
    runs do not record the safety measures (corridor runs: their metrics hold
    their own, :data:`~hcomc.experiments.corridor.metrics.CORRIDOR_METRICS`)."""
    check_runs(runs)
    if any(c not in runs for c in NEEDS):
        return pd.DataFrame(columns=list(SAFETY_COLUMNS))
    records = []
    for condition, conf, part in _cells(runs, configurations):
        ttc, ttc_seed = _extreme(part["min_ttc"], lowest=True)
        drac, drac_seed = _extreme(part["max_drac"], lowest=False)
        key = part["key_collisions"] if "key_collisions" in part else pd.Series(0, part.index)
        records.append(SafetyExtremes(
            condition, conf, len(part), ttc, ttc_seed, drac, drac_seed,
            int(part["collisions"].fillna(0).sum()), int(key.fillna(0).sum()),
        ))  # fmt: skip
    return pd.DataFrame([asdict(r) for r in records], columns=list(SAFETY_COLUMNS))


def _extreme(values: pd.Series, *, lowest: bool) -> tuple[float, int]:
    """The least (``lowest``) or largest value of ``values`` (indexed by seed) and its seed;
    (NaN, -1) without one. A run's least TTC of +inf (no pair ever closed in) is no value;
    a largest DRAC of +inf (a pair that overlapped) is the worst value there is."""
    found = pd.to_numeric(values, errors="coerce").dropna()
    if lowest:
        found = found[found.map(math.isfinite)]
    if found.empty:
        return math.nan, -1
    seed = found.idxmin() if lowest else found.idxmax()
    return float(found[seed]), int(seed)
