"""Merge success of a controller comparison: k of n runs merged per cell and configuration,
and A against B paired by seed.

A run whose ramp vehicle (VR) never merged has no metrics of the merge
(:mod:`hcomc.experiments.comparison.effects`), but it is an outcome: :func:`merge_success`
counts it (k of n runs merged), and :func:`success_pairs` compares merge success itself,
paired by seed: the exact McNemar test (the sign test of the seeds where exactly one of the two
merged), Holm-adjusted over its own family.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields

import numpy as np
import pandas as pd

from hcomc.experiments.claims import holm, p_verdict, sign_test
from hcomc.experiments.comparison.effects import _by_seed, _merged, check_runs, configurations_of

__all__ = [
    "SUCCESS_COLUMNS",
    "SUCCESS_PAIR_COLUMNS",
    "Success",
    "SuccessPair",
    "merge_success",
    "success_pairs",
]


@dataclass(frozen=True)
class Success:
    """Merge success of one configuration in one cell: k of n runs in which VR merged."""

    condition: str
    configuration: str
    merged: int
    runs: int
    rate: float


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
    for condition in pd.unique(runs["condition"]):
        for conf in configurations or configurations_of(runs):
            part = _by_seed(runs, condition, conf)
            if part.empty:
                continue
            k, n = int(_merged(part).sum()), len(part)
            records.append(Success(str(condition), conf, k, n, k / n))
    return pd.DataFrame([asdict(r) for r in records], columns=list(SUCCESS_COLUMNS))


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
