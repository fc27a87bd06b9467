"""The paper's comparative claims, evaluated on paired runs, with verdicts.

A claim is a comparative statement of the paper's Section IV (text and Tables II-III),
evaluated on paired runs (the same seed; the same condition unless the claim compares
conditions). For "A lower (higher) than B" on a metric the per-seed difference is
``d = value_A - value_B`` (differences within 1e-9 relative are ties, d = 0). Every claim
reports, and nothing here is written by hand:

* **descriptive**: the median paired difference with its 95 % bootstrap CI
  (:func:`hcomc.experiments.tables.median_ci`), and "k of n seeds": ``holds`` = k seeds
  where d has the paper's sign, ``against`` seeds where it has the other sign, ``n`` seeds
  where both values are defined (ties are the rest);
* ``verdict`` (the CI rule): "holds" when the CI excludes 0 in the paper's direction,
  "reversed" when it excludes 0 in the other direction, "undecided" otherwise, and
  "undecided" when fewer than :data:`MIN_PAIRS` seeds differ at all;
* ``p_value``: the two-sided exact **sign test** of the non-zero differences (binomial
  test of ``holds`` against ``holds + against`` at 1/2); ``p_holm``: Holm's step-down
  adjustment over the family of every claim of the paper evaluated together (the claims of
  the labelled extension HCOMC+, :func:`extension_claims`, are a family of their own, so
  adding them changes no verdict of the paper's claims); ``verdict_holm``:
  "holds" or "reversed" by the direction of the majority of the non-zero differences
  when ``p_holm < ALPHA``, "undecided" otherwise.

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

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from scipy import stats

from hcomc.experiments.paper import PAPER_METRICS, TABLE_II, TABLE_III
from hcomc.experiments.tables import REPLANNING, TIE_TOLERANCE, median_ci

ALPHA = 0.05
"""Significance level of the tests (and 1 - the CI's coverage)."""

MIN_PAIRS = next(m for m in range(1, 64) if 2 * 0.5**m < ALPHA)
"""Fewest seeds with a non-zero paired difference for which a claim can be decided (6 at
ALPHA = 0.05): below it not even a unanimous sign reaches significance, and a bootstrap
interval of so few values (one value: the value itself) says nothing, so the CI verdict is
"undecided"."""

VERDICTS = ("holds", "reversed", "undecided")
"""The three verdicts, in display order."""

GROUPS = {
    "table3": "Table III (HCOMC vs FIFO/Game)",
    "replanning": "HCOMC vs FIFO-R/Game-R",
    "table2": "Table II (NSGA-II vs PSO/SA)",
    "penetration": "CAV penetration (LSRV)",
    "mode": "cooperation mode",
    "extension": "HCOMC+ (extension) vs FIFO/Game",
}
"""Claim group key -> its name (the ``group`` column), in display order."""


@dataclass(frozen=True)
class Claim:
    """A comparative statement of the paper: metric of cell A lower/higher than of cell B.

    A cell is (condition, configuration); ``paper_a`` and ``paper_b`` are the paper's values;
    ``group`` a key of :data:`GROUPS`.
    """

    text: str
    metric: str
    a: tuple[str, str]
    b: tuple[str, str]
    expect: str  # "lower" or "higher"
    paper_a: float
    paper_b: float
    group: str = "table3"


@dataclass(frozen=True)
class ModeClaim:
    """HCOMC's chosen cooperation mode in a condition."""

    condition: str
    mode: str
    group: str = "mode"


_T2_MODEL = {"HCOMC": "NSGA-II", "HCOMC-PSO": "PSO", "HCOMC-SA": "SA"}


def _paper_value(cell: tuple[str, str], metric: str) -> float:
    cond, conf = cell
    i = PAPER_METRICS.index(metric)
    if (cond, conf) in TABLE_III:
        return TABLE_III[(cond, conf)][i]
    return TABLE_II[(cond, _T2_MODEL[conf])][i]


def _pairwise(
    metric: str,
    a: tuple[str, str],
    b: tuple[str, str],
    group: str,
    names: dict[str, str] | None = None,
) -> Claim | None:
    """The claim the paper's tables make about cells A and B on ``metric`` (None if tied);
    ``names`` maps configurations to the paper's model names in the text."""
    pa, pb = _paper_value(a, metric), _paper_value(b, metric)
    if pa == pb:
        return None
    expect = "lower" if pa < pb else "higher"
    name = metric.replace("_", " ")
    label_a, label_b = ((names or {}).get(c, c) for c in (a[1], b[1]))
    if a[0] == b[0]:
        text = f"{label_a} {name} {expect} than {label_b}"
    else:
        text = f"{label_a} {name} {expect} in {a[0]} than in {b[0]}"
    return Claim(text, metric, a, b, expect, pa, pb, group)


def paper_claims() -> list[Claim | ModeClaim]:
    """The comparative claims of Section IV, in the direction the paper's tables give.

    * Sections IV-A to IV-D with Table III: HCOMC versus FIFO and versus Game on critical
      distance, average acceleration, stabilisation time, LSRV and fuel in every condition
      (the text: HCOMC improves safety in all conditions, stability and rapidity "almost
      under all", traffic efficiency, and fuel except in C2, where it uses more). Where the
      table has HCOMC worse (average acceleration vs FIFO in C2, fuel in C2) the claim says
      so.
    * The same HCOMC claims against FIFO-R and Game-R, the baselines replanning every second
      as HCOMC does (not in the paper: it separates HCOMC's method from replanning alone).
    * Section IV-A: HCOMC's VMC cooperates laterally in C2, longitudinally in C1 and C3.
    * Section IV-C: fewer CAVs, larger LSRV: C1 (90 %) < C4 (60 %) < C5 (30 %) for each
      controller (two paired claims per controller).
    * Table II: NSGA-II versus PSO and SA on all five metrics in C1 and C3 (longitudinal
      cooperation, where the text says NSGA-II is best) and, in C2 (lateral cooperation), on
      the three metrics the text discusses: LSRV ("NSGA-II also performs the best"), critical
      distance and fuel (NSGA-II "performs inferior ... only about 1 %").
    """
    out: list[Claim | ModeClaim | None] = []
    for cond in ("C1", "C2", "C3", "C4", "C5"):
        for metric in PAPER_METRICS:
            for base in ("FIFO", "Game"):
                out.append(_pairwise(metric, (cond, "HCOMC"), (cond, base), "table3"))
    # the same claims against the baselines replanning as HCOMC does (paper's values kept)
    out += [
        replace(c, text=f"{c.text}-R", b=(c.b[0], REPLANNING[c.b[1]]), group="replanning")
        for c in list(out)
        if isinstance(c, Claim) and c.b[1] in REPLANNING
    ]
    out += [ModeClaim("C1", "longitudinal"), ModeClaim("C2", "lateral"),
            ModeClaim("C3", "longitudinal")]  # fmt: skip
    for conf in ("FIFO", "Game", "HCOMC"):
        for more, fewer in (("C1", "C4"), ("C4", "C5")):
            out.append(_pairwise("lsrv", (fewer, conf), (more, conf), "penetration"))
    c2 = ("critical_distance", "lsrv", "fuel")  # the three the text discusses for C2
    for cond, metrics in (("C1", PAPER_METRICS), ("C3", PAPER_METRICS), ("C2", c2)):
        for metric in metrics:
            for rival in ("HCOMC-PSO", "HCOMC-SA"):
                out.append(_pairwise(metric, (cond, "HCOMC"), (cond, rival), "table2", _T2_MODEL))
    return [c for c in out if c is not None]


def extension_claims() -> list[Claim]:
    """The Table III claims of HCOMC made of HCOMC+, the labelled extension that may also
    leave the mainline alone (mode "none" among its candidates; not in the paper): does it
    keep HCOMC's published advantages over FIFO and Game? The paper's values are HCOMC's, for
    reference; these claims form a Holm family of their own."""
    out = []
    for c in paper_claims():
        if isinstance(c, Claim) and c.group == "table3":
            text = "HCOMC+" + c.text.removeprefix("HCOMC")
            out.append(replace(c, text=text, a=(c.a[0], "HCOMC+"), group="extension"))
    return out


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


def _values(runs: pd.DataFrame, cell: tuple[str, str], metric: str) -> pd.Series:
    part = runs[(runs["condition"] == cell[0]) & (runs["configuration"] == cell[1])]
    return part.groupby("seed")[metric].first()


def _evaluate(runs: pd.DataFrame, claim: Claim) -> dict[str, object] | None:
    """Paired differences A - B by seed: median, bootstrap CI, counts, sign test, means."""
    if claim.metric not in runs:
        return None
    a, b = _values(runs, claim.a, claim.metric), _values(runs, claim.b, claim.metric)
    if a.empty or b.empty:
        return None
    a, b = a.align(b, join="inner")
    both = (a.notna() & b.notna()).to_numpy()
    va, vb = a.to_numpy(dtype=np.float64)[both], b.to_numpy(dtype=np.float64)[both]
    diff = va - vb
    # float round-off (e.g. two stabilisation times from differently summed row times) is a tie
    scale = np.maximum(1.0, np.maximum(np.abs(va), np.abs(vb)))
    diff[np.abs(diff) <= TIE_TOLERANCE * scale] = 0.0
    sign = -1.0 if claim.expect == "lower" else 1.0
    holds, against = int((sign * diff > 0).sum()), int((sign * diff < 0).sum())
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
        "n": int(diff.size),
        "mean_a": float(a[both].mean()) if both.any() else nan,
        "mean_b": float(b[both].mean()) if both.any() else nan,
    }


def _mode_row(runs: pd.DataFrame, claim: ModeClaim) -> dict[str, object] | None:
    part = runs[(runs["condition"] == claim.condition) & (runs["configuration"] == "HCOMC")]
    if part.empty or "mode" not in part:
        return None
    n, k = len(part), int((part["mode"] == claim.mode).sum())
    p = float(stats.binomtest(k, n, 0.5).pvalue)
    direction = int(np.sign(2 * k - n))
    nan = float("nan")
    counts = part["mode"].replace("", "no plan").value_counts().to_dict()
    return {
        "claim": f"HCOMC chooses {claim.mode} cooperation",
        "condition": claim.condition,
        "metric": "mode",
        "paper": claim.mode,
        "paper_diff": nan,
        "median_diff": nan,
        "ci_low": nan,
        "ci_high": nan,
        "verdict": p_verdict(p, direction),
        "p_value": p,
        "direction": direction,
        "holds": k,
        "against": n - k,
        "n": n,
        "ours": ", ".join(f"{mode}: {v}" for mode, v in counts.items()),
    }


def _row(runs: pd.DataFrame, claim: Claim | ModeClaim) -> dict[str, object] | None:
    if isinstance(claim, ModeClaim):
        rec = _mode_row(runs, claim)
    else:
        result = _evaluate(runs, claim)
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
    return None if rec is None else {"group": GROUPS[claim.group], **rec}


COLUMNS = (
    "group", "claim", "condition", "metric", "paper", "paper_diff", "median_diff", "ci_low",
    "ci_high", "verdict", "p_value", "p_holm", "verdict_holm", "holds", "against", "n",
    "share", "ours",
)  # fmt: skip
"""The columns of :func:`claims`, in order (``uniform`` last when given)."""


def claims(runs: pd.DataFrame, uniform: pd.DataFrame | None = None) -> pd.DataFrame:
    """Every claim of :func:`paper_claims` and :func:`extension_claims` the runs can
    evaluate, one row each.

    Columns (:data:`COLUMNS`): ``group`` (:data:`GROUPS`), ``claim``, ``condition``,
    ``metric``, ``paper`` (the paper's "A vs B", or the mode), ``paper_diff`` (A - B in the
    paper), ``median_diff`` (median over seeds of the paired A - B), ``ci_low`` and
    ``ci_high`` (its 95 % bootstrap CI), ``verdict`` (the CI rule; the binomial test for a
    mode), ``p_value`` (sign test; binomial test for a mode), ``p_holm`` (Holm over the
    paper's claims, and over the extension's apart), ``verdict_holm``, ``holds`` (k),
    ``against``, ``n``, ``share`` (k / n), ``ours`` (our means "A vs B", or the mode
    counts) and, when ``uniform`` (runs of the deterministic paper scenario) is given,
    ``uniform``: "yes" or "no" for the claim on those runs, "" if undefined there. See the
    module docstring for the rules.
    """
    records: list[dict[str, object]] = []
    for claim in [*paper_claims(), *extension_claims()]:
        rec = _row(runs, claim)
        if rec is None:
            continue
        k, n = int(rec["holds"]), int(rec["n"])  # type: ignore[call-overload]
        rec["share"] = k / n if n else float("nan")
        if uniform is not None:
            check = _row(uniform, claim)
            defined = check is not None and int(check["n"]) > 0  # type: ignore[call-overload]
            rec["uniform"] = ("yes" if check["holds"] else "no") if defined else ""  # type: ignore[index]
        records.append(rec)
    extra = ["uniform"] if uniform is not None else []
    if not records:
        return pd.DataFrame(columns=[*COLUMNS, *extra])
    frame = pd.DataFrame(records)
    family = frame["group"] == GROUPS["extension"]
    frame["p_holm"] = np.nan
    for members in (~family, family):
        if members.any():
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
