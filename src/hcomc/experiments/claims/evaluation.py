"""How a claim (:mod:`hcomc.experiments.claims.statements`) is tested on paired runs.

A claim is a comparative statement of the paper's Section IV (text and Tables II-III),
evaluated on paired runs (the same seed; the same condition unless the claim compares
conditions). For "A lower (higher) than B" on a metric the per-seed difference is
``d = value_A - value_B`` (differences within 1e-9 relative are ties, d = 0). Every claim
reports, and nothing here is written by hand:

* **descriptive**: the median paired difference with its 95 % bootstrap CI
  (:func:`hcomc.experiments.tables.median_ci`), and "k of n seeds": ``holds`` = k seeds
  where d has the paper's sign, ``against`` seeds where it has the other sign, ``n`` seeds
  where both values are defined or a merge failed (ties are the rest);
* ``verdict`` (the CI rule): "holds" when the CI excludes 0 in the paper's direction,
  "reversed" when it excludes 0 in the other direction, "undecided" otherwise, and
  "undecided" when fewer than :data:`MIN_PAIRS` seeds differ at all;
* ``p_value``: the two-sided exact **sign test** of the non-zero differences (binomial
  test of ``holds`` against ``holds + against`` at 1/2); ``p_holm``: Holm's step-down
  adjustment within the claim's ``family`` (:data:`FAMILIES`): the paper's own claims are
  one family, the replanning variants', the extension HCOMC+'s and the merge outcomes' are
  families of their own, so adding one changes no verdict of another; ``verdict_holm``:
  "holds" or "reversed" by the direction of the majority of the non-zero differences
  when ``p_holm < ALPHA``, "undecided" otherwise.

**A run without a merge is an outcome, never a missing pair.** Its merge metrics are
undefined (NaN), so the median and CI describe the seeds on which both runs merged; in the
sign test, and so in ``p_value`` and ``verdict_holm``, a seed on which only one of the two
runs merged counts for the one that merged (the worst outcome for the other), and a seed on
which neither merged is a tie. ``failed_a`` and ``failed_b`` show how many seeds A and B
failed on. Merge success itself is a claim (:func:`outcome_claims`: the exact McNemar test of
the seeds on which exactly one of the two merged).

Why the sign test (not the Wilcoxon signed-rank test): the verdicts are about the
*median* paired difference, and the sign test's null hypothesis is exactly that the
difference is as often positive as negative. It assumes nothing about the shape of the
differences, whose distributions are skewed (LSRV, fuel) and hold many exact ties (where
two controllers act alike, e.g. when VMC is an HDV); the Wilcoxon test assumes them
symmetric and can reject a zero median for a merely skewed distribution. It is exact at
any n (binomial, no normal approximation), and it uses the same counts as the "k of n
seeds" column. The price is power: with 30 seeds Holm's first step (p < 0.05 / m for m
claims) needs about 25 of 30 seeds in one direction.

Mode claims ("HCOMC chooses lateral cooperation in C2") count the runs that end with that
cooperation mode: ``holds`` = k of n runs, ``p_value`` the two-sided exact binomial test of
k / n against 1/2; the verdict is "holds" when significantly above 1/2, "reversed" when
significantly below, "undecided" otherwise (``verdict`` at p < ALPHA, ``verdict_holm`` at
p_holm < ALPHA, in the same Holm family).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from hcomc.experiments.claims.statements import (
    FAMILIES,
    GROUPS,
    AnyClaim,
    Claim,
    ModeClaim,
    SuccessClaim,
    all_claims,
)
from hcomc.experiments.tables import TIE_TOLERANCE, median_ci

ALPHA = 0.05
"""Significance level of the tests (and 1 - the CI's coverage)."""

MIN_PAIRS = next(m for m in range(1, 64) if 2 * 0.5**m < ALPHA)
"""Fewest seeds with a non-zero paired difference for which a claim can be decided (6 at
ALPHA = 0.05): below it not even a unanimous sign reaches significance, and a bootstrap
interval of so few values (one value: the value itself) says nothing, so the CI verdict is
"undecided"."""

VERDICTS = ("holds", "reversed", "undecided")
"""The three verdicts, in display order."""


def sign_test(holds: int, against: int) -> float:
    """Two-sided exact sign test: p of ``holds`` successes in ``holds + against`` non-zero
    paired differences at probability 1/2 (1.0 without a non-zero difference)."""
    m = holds + against
    return 1.0 if m == 0 else float(stats.binomtest(holds, m, 0.5).pvalue)


def holm(p_values: np.ndarray | pd.Series) -> np.ndarray:
    """Holm's step-down adjustment of a family of p-values (NaN stays NaN, out of the family).

    With the m finite p-values sorted ascending, ``p_(i)`` becomes
    ``max_{j <= i} min(1, (m - j + 1) p_(j))`` (1-based); rejecting where the adjusted value
    is below alpha controls the family-wise error rate at alpha under any dependence.
    """
    p = np.asarray(p_values, dtype=np.float64)
    out = np.full(p.shape, np.nan)
    finite = np.flatnonzero(np.isfinite(p))
    order = finite[np.argsort(p[finite], kind="stable")]
    m = order.size
    scaled = np.minimum(1.0, (m - np.arange(m)) * p[order])
    out[order] = np.maximum.accumulate(scaled)
    return out


def ci_verdict(low: float, high: float, expect: str) -> str:
    """The CI rule: "holds" when [low, high] excludes 0 on the ``expect`` side ("lower":
    below 0, "higher": above 0), "reversed" on the other side, "undecided" otherwise."""
    if not (np.isfinite(low) and np.isfinite(high)):
        return "undecided"
    if low > 0.0 or high < 0.0:
        return "holds" if (high < 0.0) == (expect == "lower") else "reversed"
    return "undecided"


def p_verdict(p: float, direction: int) -> str:
    """The test's verdict: "holds" (direction > 0, the paper's) or "reversed" (direction
    < 0) when p < ALPHA, "undecided" otherwise."""
    if not np.isfinite(p) or p >= ALPHA or direction == 0:
        return "undecided"
    return "holds" if direction > 0 else "reversed"


class _Cells:
    """The runs split once by (condition, configuration) cell, and each cell by seed: there
    are hundreds of claims, each reading two cells, and selecting a cell from all the runs
    anew took most of :func:`claims`' time."""

    def __init__(self, runs: pd.DataFrame) -> None:
        self.runs = runs
        groups = runs.groupby(["condition", "configuration"], sort=False) if len(runs) else ()
        self._parts: dict[tuple[str, str], pd.DataFrame] = dict(iter(groups))
        self._by_seed: dict[tuple[str, str], pd.DataFrame] = {}

    def part(self, cell: tuple[str, str]) -> pd.DataFrame:
        """The runs of ``cell`` (none: no rows)."""
        return self._parts.get(cell, self.runs.iloc[:0])

    def values(self, cell: tuple[str, str], metric: str) -> pd.Series:
        """``metric`` of ``cell``'s runs by seed (a seed's first value)."""
        if cell not in self._by_seed:
            self._by_seed[cell] = self.part(cell).groupby("seed").first()
        return self._by_seed[cell][metric]


def _failed(cells: _Cells, cell: tuple[str, str], seeds: pd.Index) -> np.ndarray:
    """Whether the run of ``cell`` failed to merge, on each of ``seeds`` (all False when the
    runs have no ``merged`` column)."""
    if "merged" not in cells.runs:
        return np.zeros(len(seeds), dtype=bool)
    merged = cells.values(cell, "merged").reindex(seeds)
    return ~merged.fillna(False).astype(bool).to_numpy()


def _evaluate(cells: _Cells, claim: Claim) -> dict[str, object] | None:
    """Paired differences A - B by seed: median, bootstrap CI, counts, sign test (a failed
    merge the worst outcome), means."""
    if claim.metric not in cells.runs:
        return None
    a, b = cells.values(claim.a, claim.metric), cells.values(claim.b, claim.metric)
    if a.empty or b.empty:
        return None
    a, b = a.align(b, join="inner")
    fail_a, fail_b = _failed(cells, claim.a, a.index), _failed(cells, claim.b, b.index)
    both = (a.notna() & b.notna()).to_numpy() & ~fail_a & ~fail_b
    va, vb = a.to_numpy(dtype=np.float64)[both], b.to_numpy(dtype=np.float64)[both]
    diff = va - vb
    # float round-off (e.g. two stabilisation times from differently summed row times) is a tie
    scale = np.maximum(1.0, np.maximum(np.abs(va), np.abs(vb)))
    diff[np.abs(diff) <= TIE_TOLERANCE * scale] = 0.0
    sign = -1.0 if claim.expect == "lower" else 1.0
    only_a, only_b = int((fail_a & ~fail_b).sum()), int((fail_b & ~fail_a).sum())
    holds = int((sign * diff > 0).sum()) + only_b  # B alone failed: A's outcome is better
    against = int((sign * diff < 0).sum()) + only_a
    median, low, high = median_ci(diff)
    nan = float("nan")
    p = sign_test(holds, against) if diff.size else nan
    decidable = holds + against >= MIN_PAIRS
    verdict = ci_verdict(low, high, claim.expect) if decidable else "undecided"
    return {
        "median_diff": median,
        "ci_low": low,
        "ci_high": high,
        "verdict": verdict,
        "p_value": p,
        "direction": int(np.sign(holds - against)),
        "holds": holds,
        "against": against,
        "n": int(diff.size + (fail_a | fail_b).sum()),
        "failed_a": int(fail_a.sum()),
        "failed_b": int(fail_b.sum()),
        "mean_a": float(a[both].mean()) if both.any() else nan,
        "mean_b": float(b[both].mean()) if both.any() else nan,
    }


def _no_difference() -> dict[str, float]:
    """The paired-difference columns, undefined for a claim that counts runs (a mode, merge
    success)."""
    nan = float("nan")
    return {"paper_diff": nan, "median_diff": nan, "ci_low": nan, "ci_high": nan}


def mcnemar_exact(a_only: int, b_only: int) -> float:
    """Two-sided exact McNemar test: the seeds on which exactly one of the two merged, A's
    share of them against 1/2 (1 when there are none)."""
    return sign_test(a_only, b_only)


def _success_row(cells: _Cells, claim: SuccessClaim) -> dict[str, object] | None:
    """Merge success of A against B on their common seeds (exact McNemar)."""
    if "merged" not in cells.runs:
        return None
    a = cells.values((claim.condition, claim.a), "merged")
    b = cells.values((claim.condition, claim.b), "merged")
    a, b = a.align(b, join="inner")
    if a.empty:
        return None
    ma, mb = a.fillna(False).astype(bool).to_numpy(), b.fillna(False).astype(bool).to_numpy()
    a_only, b_only = int((ma & ~mb).sum()), int((mb & ~ma).sum())
    p = mcnemar_exact(a_only, b_only)
    direction = int(np.sign(a_only - b_only))
    return {
        "claim": f"{claim.a} merges at least as often as {claim.b}",
        "condition": claim.condition,
        "metric": "merged",
        "paper": "every VR merges",
        **_no_difference(),
        "verdict": p_verdict(p, direction),
        "p_value": p,
        "direction": direction,
        "holds": a_only,
        "against": b_only,
        "n": int(ma.size),
        "failed_a": int((~ma).sum()),
        "failed_b": int((~mb).sum()),
        "ours": f"{int(ma.sum())}/{ma.size} vs {int(mb.sum())}/{mb.size} merged",
    }


def _mode_row(cells: _Cells, claim: ModeClaim) -> dict[str, object] | None:
    part = cells.part((claim.condition, "HCOMC"))
    if part.empty or "mode" not in part:
        return None
    n, k = len(part), int((part["mode"] == claim.mode).sum())
    p = float(stats.binomtest(k, n, 0.5).pvalue)
    direction = int(np.sign(2 * k - n))
    counts = part["mode"].replace("", "no plan").value_counts().to_dict()
    return {
        "claim": f"HCOMC chooses {claim.mode} cooperation",
        "condition": claim.condition,
        "metric": "mode",
        "paper": claim.mode,
        **_no_difference(),
        "verdict": p_verdict(p, direction),
        "p_value": p,
        "direction": direction,
        "holds": k,
        "against": n - k,
        "n": n,
        "ours": ", ".join(f"{mode}: {v}" for mode, v in counts.items()),
    }


def _row(cells: _Cells, claim: AnyClaim) -> dict[str, object] | None:
    if isinstance(claim, ModeClaim):
        rec = _mode_row(cells, claim)
    elif isinstance(claim, SuccessClaim):
        rec = _success_row(cells, claim)
    else:
        result = _evaluate(cells, claim)
        if result is None:
            return None
        same = claim.a[0] == claim.b[0]
        rec = {
            "claim": claim.text,
            "condition": claim.a[0] if same else f"{claim.a[0]}/{claim.b[0]}",
            "metric": claim.metric,
            "paper": f"{claim.paper_a:g} vs {claim.paper_b:g}",
            "paper_diff": claim.paper_a - claim.paper_b,
            **{k: v for k, v in result.items() if k not in ("mean_a", "mean_b")},
            "ours": f"{result['mean_a']:.4g} vs {result['mean_b']:.4g}",
        }
    if rec is None:
        return None
    return {"family": FAMILIES[claim.group], "group": GROUPS[claim.group], **rec}


COLUMNS = (
    "family", "group", "claim", "condition", "metric", "paper", "paper_diff", "median_diff",
    "ci_low", "ci_high", "verdict", "p_value", "p_holm", "verdict_holm", "holds", "against", "n",
    "failed_a", "failed_b", "share", "ours",
)  # fmt: skip
"""The columns of :func:`claims`, in order (``uniform`` last when given)."""


def claims(runs: pd.DataFrame, uniform: pd.DataFrame | None = None) -> pd.DataFrame:
    """Every claim of :func:`all_claims` the runs can evaluate, one row each.

    Columns (:data:`COLUMNS`): ``family`` (:data:`FAMILIES`), ``group`` (:data:`GROUPS`),
    ``claim``, ``condition``, ``metric``, ``paper`` (the paper's "A vs B", or the mode),
    ``paper_diff`` (A - B in the paper), ``median_diff`` (median over seeds of the paired A -
    B), ``ci_low`` and ``ci_high`` (its 95 % bootstrap CI), ``verdict`` (the CI rule; the
    binomial test for a mode), ``p_value`` (sign test; binomial test for a mode, exact McNemar
    for merge success), ``p_holm`` (Holm within the family), ``verdict_holm``, ``holds`` (k),
    ``against``, ``n`` (seeds, failed merges included), ``failed_a`` and ``failed_b`` (seeds on
    which A's or B's VR did not merge), ``share`` (k / n), ``ours`` (our means "A vs B", or the
    mode counts) and, when ``uniform`` (runs of the deterministic paper scenario) is given,
    ``uniform``: "yes" or "no" for the claim on those runs, "" if undefined there. See the
    module docstring for the rules.
    """
    records: list[dict[str, object]] = []
    cells, uniform_cells = _Cells(runs), None if uniform is None else _Cells(uniform)
    for claim in all_claims():
        rec = _row(cells, claim)
        if rec is None:
            continue
        k, n = int(rec["holds"]), int(rec["n"])  # type: ignore[call-overload]
        rec["share"] = k / n if n else float("nan")
        if uniform_cells is not None:
            check = _row(uniform_cells, claim)
            defined = check is not None and int(check["n"]) > 0  # type: ignore[call-overload]
            rec["uniform"] = ("yes" if check["holds"] else "no") if defined else ""  # type: ignore[index]
        records.append(rec)
    extra = ["uniform"] if uniform is not None else []
    if not records:
        return pd.DataFrame(columns=[*COLUMNS, *extra])
    frame = pd.DataFrame(records)
    frame["p_holm"] = np.nan
    for family in pd.unique(frame["family"]):
        members = frame["family"] == family
        frame.loc[members, "p_holm"] = holm(frame.loc[members, "p_value"])
    frame["verdict_holm"] = [
        p_verdict(p, int(d)) for p, d in zip(frame["p_holm"], frame["direction"], strict=True)
    ]
    return frame[[*COLUMNS, *extra]]


def verdict_counts(frame: pd.DataFrame, column: str = "verdict", by: str = "group") -> pd.DataFrame:
    """Claims per ``by`` value (rows, in order of appearance) and verdict (columns, in
    :data:`VERDICTS` order) of ``column``, with a total row."""
    table = pd.crosstab(frame[by], frame[column]).reindex(columns=list(VERDICTS), fill_value=0)
    table = table.reindex(list(pd.unique(frame[by])))
    table.loc["all"] = table.sum()
    return table.astype(int)
