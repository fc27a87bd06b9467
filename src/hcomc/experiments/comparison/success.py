"""Merge success of a controller comparison: k of n runs merged per cell and configuration,
with the plans that fell back, and A against B paired by seed.

A run whose ramp vehicle (VR) never merged has no metrics of the merge
(:mod:`hcomc.experiments.comparison.effects`), but it is an outcome: :func:`merge_success`
counts it (k of n runs merged), and :func:`success_pairs` compares merge success itself,
paired by seed: the exact McNemar test (the sign test of the seeds where exactly one of the two
merged), Holm-adjusted over its own family.

A plan that fell back (no feasible plan, or an invalid one under ``control.on_invalid_plan =
"fallback"``) is the safe default: VR merges by gap acceptance and nobody is commanded. A
configuration whose plans fell back in more than :data:`FALLBACK_FLAG` of its decisions in a
cell is flagged: its scores there are those of gap acceptance, not of its plans.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields

import numpy as np
import pandas as pd

from hcomc.experiments.claims import holm, p_verdict, sign_test
from hcomc.experiments.comparison.effects import _by_seed, _cells, _merged, check_runs

__all__ = [
    "FALLBACK_FLAG",
    "SUCCESS_COLUMNS",
    "SUCCESS_PAIR_COLUMNS",
    "Success",
    "SuccessPair",
    "flagged_note",
    "merge_success",
    "success_pairs",
]


FALLBACK_FLAG = 0.5
"""Share of a configuration's plans in a cell above which it is flagged (module docstring)."""


@dataclass(frozen=True)
class Success:
    """Merge success of one configuration in one cell: k of n runs in which VR merged; the
    plans made for VR over those runs and how many fell back (0 and 0 when the runs do not
    record plans), and whether more than :data:`FALLBACK_FLAG` of them did."""

    condition: str
    configuration: str
    merged: int
    runs: int
    rate: float
    plans: int
    fallbacks: int
    flagged: bool


@dataclass(frozen=True)
class SuccessPair:
    """Merge success of A against B in one cell, paired by seed (exact McNemar test)."""

    condition: str
    a: str
    b: str
    both: int  # seeds in which both merged
    only_a: int
    only_b: int
    neither: int
    p_value: float  # exact sign test of only_a against only_a + only_b
    p_holm: float  # Holm-adjusted over every success pair of the comparison
    verdict: str  # "higher" (A merges more often), "lower" or "undecided", at p < ALPHA
    verdict_holm: str


SUCCESS_COLUMNS = tuple(f.name for f in fields(Success))
SUCCESS_PAIR_COLUMNS = tuple(f.name for f in fields(SuccessPair))


def merge_success(runs: pd.DataFrame, configurations: Sequence[str] | None = None) -> pd.DataFrame:
    """Merge success (:class:`Success`) per cell and configuration: every run counts."""
    check_runs(runs)
    records = []
    for condition, conf, part in _cells(runs, configurations):
        k, n = int(_merged(part).sum()), len(part)
        plans, fallbacks = _plans(part)
        flagged = plans > 0 and fallbacks > FALLBACK_FLAG * plans
        records.append(Success(condition, conf, k, n, k / n, plans, fallbacks, flagged))
    return pd.DataFrame([asdict(r) for r in records], columns=list(SUCCESS_COLUMNS))


def _plans(part: pd.DataFrame) -> tuple[int, int]:
    """Plans made for VR over the runs ``part`` and how many fell back, from the run rows'
    ``replans`` (plans minus one, in runs with a plan: a non-empty ``mode``) and
    ``fallbacks``; (0, 0) when the rows do not have them."""
    if not {"replans", "fallbacks", "mode"} <= set(part.columns):
        return 0, 0
    planned = part["mode"].fillna("").astype(str).ne("")
    plans = int((part.loc[planned, "replans"].fillna(0) + 1).sum())
    return plans, int(part["fallbacks"].fillna(0).sum())


def flagged_note(success: pd.DataFrame) -> str | None:
    """One line naming the configurations flagged in some cell, with their fallback counts,
    or None if none is."""
    rows = success[success["flagged"]] if "flagged" in success else success.iloc[0:0]
    if rows.empty:
        return None
    cells = "; ".join(
        f"{r.configuration} in {r.condition} ({r.fallbacks} of {r.plans} plans)"
        for r in rows.itertuples()
    )
    return (
        f"flagged (more than {100 * FALLBACK_FLAG:.0f} % of the plans fell back to the safe "
        f"default, VR merging by gap acceptance): {cells}; their results there are those of "
        "gap acceptance, not of their plans"
    )


def success_pairs(
    runs: pd.DataFrame,
    comparisons: Sequence[tuple[str, str]],
) -> pd.DataFrame:
    """Merge success of A against B per cell, paired by seed (:class:`SuccessPair`): the
    exact McNemar test on the seeds where exactly one merged, Holm-adjusted over all rows."""
    check_runs(runs)
    records = []
    for condition in pd.unique(runs["condition"]):
        for a, b in comparisons:
            side_a, side_b = _by_seed(runs, condition, a), _by_seed(runs, condition, b)
            seeds = side_a.index.intersection(side_b.index)
            if seeds.empty:
                continue
            ma = _merged(side_a.loc[seeds]).to_numpy()
            mb = _merged(side_b.loc[seeds]).to_numpy()
            only_a, only_b = int((ma & ~mb).sum()), int((~ma & mb).sum())
            p = sign_test(only_a, only_b)
            records.append(SuccessPair(
                condition=str(condition), a=a, b=b, both=int((ma & mb).sum()), only_a=only_a,
                only_b=only_b, neither=int((~ma & ~mb).sum()), p_value=p, p_holm=math.nan,
                verdict=_success_word(p, only_a - only_b), verdict_holm="undecided",
            ))  # fmt: skip
    frame = pd.DataFrame([asdict(r) for r in records], columns=list(SUCCESS_PAIR_COLUMNS))
    if len(frame):
        frame["p_holm"] = holm(frame["p_value"].to_numpy(np.float64))
        frame["verdict_holm"] = [
            _success_word(p, int(d))
            for p, d in zip(frame["p_holm"], frame["only_a"] - frame["only_b"], strict=True)
        ]
    return frame


def _success_word(p: float, direction: int) -> str:
    """The success verdict: "higher" when A merges significantly more often, "lower" when
    less, else "undecided"."""
    return {"holds": "higher", "reversed": "lower"}.get(p_verdict(p, direction), "undecided")
