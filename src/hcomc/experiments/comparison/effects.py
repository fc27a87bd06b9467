"""Paired comparison of merge controllers: the effects of one configuration against another
per cell and metric, with their verdicts.

Runs of a comparison share their seeds across configurations (common random numbers: the
same traffic for every controller), so configurations A and B are compared **paired**: in a
cell (a scenario, the ``condition`` column) and a seed, ``d = value_A - value_B``. The rule
is the one the paper's claims are judged by (:mod:`hcomc.experiments.claims`), with words
that take no side, since a comparison of your own has no expected direction:

* **median** of the paired differences with its 95 % bootstrap CI
  (:func:`hcomc.experiments.tables.median_ci`); differences within 1e-9 (relative) are ties;
* ``verdict`` (the CI rule): "lower" when the CI lies below 0 (A lower than B), "higher"
  when above 0, "undecided" otherwise, and "undecided" when fewer than
  :data:`~hcomc.experiments.claims.MIN_PAIRS` seeds differ at all;
* ``favours``: the configuration the verdict favours by the metric's preferred direction
  (:data:`PREFERS`, the metric registry's: larger critical distance, smaller everything
  else), empty when undecided;
* ``p_value``: the two-sided exact sign test of the non-zero differences; ``p_holm``: Holm's
  adjustment over every effect of the comparison together (all cells, pairs and metrics),
  ``verdict_holm`` by ``p_holm < ALPHA``;
* "k of n": ``a_lower`` seeds where A < B, ``a_higher`` where A > B, ``n`` seeds in which
  both runs merged with a defined value or exactly one of them merged. **A run without a
  merge is the worst outcome**, never a missing pair: on a seed where only B merged, A's
  value counts as worse than B's in the metric's preferred direction (a_higher for a metric
  that prefers smaller values, a_lower for one that prefers larger), so it enters the sign
  test, ``p_holm`` and ``verdict_holm``; the median and its CI describe the seeds on which
  both merged; ``failed_a`` and ``failed_b`` show the seeds each did not merge on.

The corridor metrics (:data:`~hcomc.experiments.corridor.metrics.CORRIDOR_METRICS`, of runs
on a corridor) are run-level figures whose failures are inside them (an unmerged ramp
vehicle lowers ``merged_share``), so their pairs are the seeds in which both runs have a
defined value, whatever the runs' ``merged`` says (:data:`RUN_LEVEL`).

A run whose ramp vehicle (VR) never merged has no metrics of the merge: it is an outcome, not
a run without disturbance. It never vanishes: it is the worst outcome in the sign test (see
above), ``excluded`` counts the seeds both configurations ran that give neither a pair nor a
failure on one side, and :mod:`hcomc.experiments.comparison.success` counts and compares
merge success itself. :mod:`hcomc.experiments.comparison.view` turns the
tables into text.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, fields

import numpy as np
import pandas as pd

from hcomc.experiments.claims import ALPHA, MIN_PAIRS, ci_verdict, holm, p_verdict, sign_test
from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.experiments.tables import TIE_TOLERANCE, median_ci
from hcomc.metrics import METRICS

PREFERS: dict[str, str] = {
    **{m: spec.better for m, spec in METRICS.items()},
    **{m: spec.better for m, spec in CORRIDOR_METRICS.items()},
}
"""Metric -> the direction that is better ("larger" or "smaller"): the metric registry's (the
paper's metrics as the claims use them, the surrogate safety measures), and the corridor
metrics' registry's."""

RUN_LEVEL = frozenset(CORRIDOR_METRICS)
"""Metrics defined for every run, failed merges included: paired without regard to
``merged``."""

VERDICTS = ("lower", "higher", "undecided")
"""The verdicts of A against B, in display order."""

REQUIRED = ("condition", "configuration", "seed")
"""Columns every runs table needs (plus ``merged`` and the metrics when there are any)."""

_WORDS = {"holds": "lower", "reversed": "higher", "undecided": "undecided"}
"""The claims' verdict for the expectation "A lower" -> the neutral word."""


@dataclass(frozen=True)
class Effect:
    """The paired effect of configuration A against B on one metric in one cell."""

    condition: str
    metric: str
    a: str
    b: str
    prefers: str  # "larger" or "smaller": the better direction of the metric
    median_diff: float  # median of A - B over the pairs
    ci_low: float
    ci_high: float
    verdict: str  # by the CI rule: "lower", "higher" or "undecided"
    favours: str  # the configuration the verdict favours ("" if undecided)
    p_value: float  # two-sided exact sign test
    p_holm: float  # Holm-adjusted over the whole comparison
    verdict_holm: str
    a_lower: int  # seeds with A < B (a failed merge counted as the worse value)
    a_higher: int  # seeds with A > B (likewise)
    ties: int
    n: int  # seeds in which both merged with a defined value, or exactly one failed
    excluded: int  # seeds both ran that give no pair (both unmerged, or undefined)
    failed_a: int  # seeds both ran on which A's VR did not merge
    failed_b: int
    mean_a: float  # means over the n pairs
    mean_b: float


EFFECT_COLUMNS = tuple(f.name for f in fields(Effect))


def check_runs(runs: pd.DataFrame) -> None:
    """ValueError naming the columns a runs table lacks for a comparison."""
    missing = [c for c in REQUIRED if c not in runs.columns]
    if missing:
        raise ValueError(f"the runs lack the column(s) {', '.join(missing)}")


def configurations_of(runs: pd.DataFrame) -> list[str]:
    """The configurations of ``runs`` in order of appearance."""
    return [str(c) for c in pd.unique(runs["configuration"])]


def pairs(configurations: Sequence[str], baseline: str | None = None) -> list[tuple[str, str]]:
    """The (A, B) comparisons: every configuration against each one listed before it (A the
    later: ``fifo,game,mine`` gives Game vs FIFO, mine vs FIFO, mine vs Game), or, with a
    ``baseline``, every other configuration against it."""
    if baseline is not None:
        if baseline not in configurations:
            raise ValueError(f"baseline '{baseline}' is not among {', '.join(configurations)}")
        return [(c, baseline) for c in configurations if c != baseline]
    return [(a, b) for b, a in itertools.combinations(configurations, 2)]


def _by_seed(runs: pd.DataFrame, condition: str, configuration: str) -> pd.DataFrame:
    part = runs[(runs["condition"] == condition) & (runs["configuration"] == configuration)]
    return part.drop_duplicates("seed").set_index("seed")


def _cells(
    runs: pd.DataFrame, configurations: Sequence[str] | None
) -> Iterator[tuple[str, str, pd.DataFrame]]:
    """(cell, configuration, its runs by seed) of every cell of ``runs`` and configuration
    (default: those of ``runs``) that has runs, cell by cell."""
    for condition in pd.unique(runs["condition"]):
        for conf in configurations or configurations_of(runs):
            part = _by_seed(runs, condition, conf)
            if not part.empty:
                yield str(condition), conf, part


def _merged(part: pd.DataFrame) -> pd.Series:
    """Whether VR merged in each run (every run counts as merged without the column)."""
    if "merged" not in part:
        return pd.Series(True, index=part.index)
    return part["merged"].eq(True)


def _pair_values(
    side_a: pd.DataFrame, side_b: pd.DataFrame, metric: str
) -> tuple[np.ndarray, np.ndarray, int]:
    """A's and B's values of ``metric`` on the seeds where both merged with a defined value
    (for a :data:`RUN_LEVEL` metric: with a defined value), and the number of seeds both
    ran."""
    va, vb, seeds, _, _ = _pairs_and_failures(side_a, side_b, metric)
    return va, vb, seeds


def _pairs_and_failures(
    side_a: pd.DataFrame, side_b: pd.DataFrame, metric: str
) -> tuple[np.ndarray, np.ndarray, int, np.ndarray, np.ndarray]:
    """:func:`_pair_values` and, per seed both ran, whether A's and B's VR failed to merge
    (never for a :data:`RUN_LEVEL` metric, whose failures are inside its value)."""
    seeds = side_a.index.intersection(side_b.index)
    va = pd.to_numeric(side_a.loc[seeds, metric], errors="coerce").to_numpy(np.float64)
    vb = pd.to_numeric(side_b.loc[seeds, metric], errors="coerce").to_numpy(np.float64)
    both = np.isfinite(va) & np.isfinite(vb)
    fail_a = fail_b = np.zeros(len(seeds), dtype=bool)
    if metric not in RUN_LEVEL:
        fail_a = ~_merged(side_a.loc[seeds]).to_numpy()
        fail_b = ~_merged(side_b.loc[seeds]).to_numpy()
        both &= ~fail_a & ~fail_b
    return va[both], vb[both], len(seeds), fail_a, fail_b


def _differences(va: np.ndarray, vb: np.ndarray) -> np.ndarray:
    """A - B, with differences within the tie tolerance (float round-off) set to 0."""
    diff = va - vb
    scale = np.maximum(1.0, np.maximum(np.abs(va), np.abs(vb)))
    diff[np.abs(diff) <= TIE_TOLERANCE * scale] = 0.0
    return diff


def paired_differences(
    runs: pd.DataFrame, condition: str, metric: str, a: str, b: str
) -> np.ndarray:
    """The paired differences A - B of ``metric`` in one cell, by seed (the pairs of
    :class:`Effect`: both runs merged with a defined value, or for a :data:`RUN_LEVEL`
    metric both defined; ties set to 0)."""
    va, vb, _ = _pair_values(_by_seed(runs, condition, a), _by_seed(runs, condition, b), metric)
    return _differences(va, vb)


def _effect(
    condition: str, metric: str, a: str, b: str, side_a: pd.DataFrame, side_b: pd.DataFrame
) -> Effect:
    va, vb, seeds, fail_a, fail_b = _pairs_and_failures(side_a, side_b, metric)
    diff = _differences(va, vb)
    only_a, only_b = int((fail_a & ~fail_b).sum()), int((fail_b & ~fail_a).sum())
    prefers = PREFERS.get(metric, "")
    if prefers not in ("larger", "smaller"):  # no worse side: a failure gives no pair
        only_a = only_b = 0
    a_worse_is_higher = prefers == "smaller"
    lower = int((diff < 0).sum()) + (only_b if a_worse_is_higher else only_a)
    higher = int((diff > 0).sum()) + (only_a if a_worse_is_higher else only_b)
    n = int(diff.size) + only_a + only_b
    median, low, high = median_ci(diff)
    decidable = lower + higher >= MIN_PAIRS
    verdict = _WORDS[ci_verdict(low, high, "lower")] if decidable else "undecided"
    nan = float("nan")
    return Effect(
        condition=condition, metric=metric, a=a, b=b, prefers=PREFERS.get(metric, ""),
        median_diff=median, ci_low=low, ci_high=high, verdict=verdict,
        favours=favoured(verdict, PREFERS.get(metric, ""), a, b),
        p_value=sign_test(lower, higher) if n else nan, p_holm=nan,
        verdict_holm="undecided", a_lower=lower, a_higher=higher,
        ties=n - lower - higher, n=n, excluded=int(seeds - n),
        failed_a=int(fail_a.sum()), failed_b=int(fail_b.sum()),
        mean_a=float(va.mean()) if va.size else nan, mean_b=float(vb.mean()) if vb.size else nan,
    )  # fmt: skip


def favoured(verdict: str, prefers: str, a: str, b: str) -> str:
    """The configuration a verdict favours on a metric that prefers ``prefers`` values ("" if
    undecided or the metric has no preferred direction)."""
    if verdict == "undecided" or prefers not in ("larger", "smaller"):
        return ""
    return a if (verdict == "lower") == (prefers == "smaller") else b


def effects(
    runs: pd.DataFrame,
    configurations: Sequence[str] | None = None,
    *,
    baseline: str | None = None,
    metrics: Sequence[str] = PAPER_METRICS,
    comparisons: Sequence[tuple[str, str]] | None = None,
) -> pd.DataFrame:
    """Every paired effect (:class:`Effect`, one row each: cell, then comparison, then
    metric), Holm-adjusted together.

    ``configurations`` (default: those of the runs, in order) and ``baseline`` give the
    comparisons (:func:`pairs`), unless ``comparisons`` lists the (A, B) pairs itself. A
    comparison missing from a cell (one of its configurations has no run there) is left
    out of that cell.
    """
    check_runs(runs)
    configurations = list(configurations or configurations_of(runs))
    todo = list(comparisons) if comparisons is not None else pairs(configurations, baseline)
    records: list[Effect] = []
    for condition in pd.unique(runs["condition"]):
        for a, b in todo:
            side_a, side_b = _by_seed(runs, condition, a), _by_seed(runs, condition, b)
            if side_a.empty or side_b.empty:
                continue
            records += [
                _effect(str(condition), m, a, b, side_a, side_b) for m in metrics if m in runs
            ]
    frame = pd.DataFrame([asdict(r) for r in records], columns=list(EFFECT_COLUMNS))
    if len(frame):
        frame["p_holm"] = holm(frame["p_value"].to_numpy(np.float64))
        direction = np.sign(frame["a_lower"] - frame["a_higher"]).astype(int)  # > 0: A lower
        frame["verdict_holm"] = [
            _WORDS[p_verdict(p, d)] for p, d in zip(frame["p_holm"], direction, strict=True)
        ]
    return frame


__all__ = [
    "ALPHA",
    "EFFECT_COLUMNS",
    "PREFERS",
    "RUN_LEVEL",
    "VERDICTS",
    "Effect",
    "effects",
    "favoured",
    "paired_differences",
    "pairs",
]
