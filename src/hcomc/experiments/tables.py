"""Summaries of a results table: mean and 95 % CI, the paper's Tables II-III, and its claims.

Claims are the comparative statements of the paper's Section IV (text and Tables II-III),
each evaluated on paired runs (the same seed; the same condition unless the claim compares
conditions). For a claim "A lower (higher) than B" on a metric the per-seed difference is
``d = value_A - value_B``; the claim reports the **median paired difference**, its **95 %
bootstrap confidence interval** (percentile method, 2000 resamples of the seeds from a fixed
generator, so deterministic), **k of n** seeds where it holds (n counts the seeds where both
values are defined; ties, differences within 1e-9 relative, do not hold) and the paper's
values. Nothing here is written by
hand: every number comes from the runs, the paper's values from
:mod:`hcomc.experiments.paper`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from scipy import stats

from hcomc.experiments.paper import PAPER_METRICS, TABLE_II, TABLE_III

LABELS = {
    "critical_distance": "Crit. Dist. [m]",
    "average_acceleration": "Aver. Acc. [m/s²]",
    "stabilisation_time": "Stab. Time [s]",
    "lsrv": "LSRV [m²]",
    "fuel": "Fuel Cons. [L]",
}
BETTER = {
    "critical_distance": "larger",
    "average_acceleration": "smaller",
    "stabilisation_time": "smaller",
    "lsrv": "smaller",
    "fuel": "smaller",
}
TABLE_II_ROWS = {"PSO": "HCOMC-PSO", "SA": "HCOMC-SA", "NSGA-II": "HCOMC"}
TABLE_III_ROWS = {"FIFO": "FIFO", "Game": "Game", "HCOMC": "HCOMC"}
DIGITS = {
    "critical_distance": 2,
    "average_acceleration": 4,
    "stabilisation_time": 1,
    "lsrv": 1,
    "fuel": 3,
}


def mean_ci(values: pd.Series | np.ndarray) -> tuple[float, float, int]:
    """Mean, half-width of the 95 % t confidence interval, and n of the finite values."""
    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    n = x.size
    if n == 0:
        return float("nan"), float("nan"), 0
    if n == 1:
        return float(x[0]), float("nan"), 1
    half = stats.t.ppf(0.975, n - 1) * x.std(ddof=1) / np.sqrt(n)
    return float(x.mean()), float(half), n


def summary(runs: pd.DataFrame, metrics: tuple[str, ...] = PAPER_METRICS) -> pd.DataFrame:
    """Per (condition, configuration): mean, CI half-width and n of every metric."""
    records = []
    for (cond, conf), part in runs.groupby(["condition", "configuration"], sort=False):
        rec: dict[str, object] = {"condition": cond, "configuration": conf}
        for m in metrics:
            rec[m], rec[f"{m}_ci"], rec[f"{m}_n"] = mean_ci(part[m])
        records.append(rec)
    return pd.DataFrame(records)


def _fmt(value: float, half: float, digits: int) -> str:
    if not np.isfinite(value):
        return "—"
    ci = "" if not np.isfinite(half) else f" ± {half:.{digits}f}"
    return f"{value:.{digits}f}{ci}"


REPLANNING = {"FIFO": "FIFO-R", "Game": "Game-R"}
"""The baselines as published (one plan) -> their replanning variants (not in the paper)."""


def paper_table(runs: pd.DataFrame, which: str) -> pd.DataFrame:
    """Table II ("II": optimisers, C1-C3) or III ("III": controllers, C1-C5) in the paper's
    layout: one row per condition and model, each metric as "ours (paper)". Table III also
    lists the replanning baselines (FIFO-R, Game-R) under the paper's FIFO and Game values."""
    reference, rows = (TABLE_II, TABLE_II_ROWS) if which == "II" else (TABLE_III, TABLE_III_ROWS)
    summ = summary(runs).set_index(["condition", "configuration"])
    out = []
    for (cond, model), paper_values in reference.items():
        confs = [(model, rows[model])]
        if which == "III" and model in REPLANNING:
            confs.append((REPLANNING[model], REPLANNING[model]))
        for label, conf in confs:
            if (cond, conf) not in summ.index:
                continue
            s = summ.loc[(cond, conf)]
            rec = {"Condition": cond, "Model": label, "n": int(s[f"{PAPER_METRICS[0]}_n"])}
            for m, p in zip(PAPER_METRICS, paper_values, strict=True):
                rec[LABELS[m]] = f"{_fmt(s[m], s[f'{m}_ci'], DIGITS[m])} ({p:g})"
            out.append(rec)
    return pd.DataFrame(out)


BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 20250715  # fixed: the same runs always give the same interval
TIE_TOLERANCE = 1e-9  # paired values closer than this (relative, at least 1) are equal


@dataclass(frozen=True)
class Claim:
    """A comparative statement of the paper: metric of cell A lower/higher than of cell B.

    A cell is (condition, configuration); ``paper_a`` and ``paper_b`` are the paper's values.
    """

    text: str
    metric: str
    a: tuple[str, str]
    b: tuple[str, str]
    expect: str  # "lower" or "higher"
    paper_a: float
    paper_b: float


@dataclass(frozen=True)
class ModeClaim:
    """HCOMC's chosen cooperation mode in a condition."""

    condition: str
    mode: str


def median_ci(diff: np.ndarray) -> tuple[float, float, float]:
    """Median of the finite paired differences and its 95 % bootstrap percentile interval."""
    d = np.asarray(diff, dtype=np.float64)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return float("nan"), float("nan"), float("nan")
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    samples = rng.choice(d, size=(BOOTSTRAP_RESAMPLES, d.size), replace=True)
    low, high = np.percentile(np.median(samples, axis=1), [2.5, 97.5])
    return float(np.median(d)), float(low), float(high)


_T2_MODEL = {"HCOMC": "NSGA-II", "HCOMC-PSO": "PSO", "HCOMC-SA": "SA"}


def _paper_value(cell: tuple[str, str], metric: str) -> float:
    cond, conf = cell
    i = PAPER_METRICS.index(metric)
    if (cond, conf) in TABLE_III:
        return TABLE_III[(cond, conf)][i]
    return TABLE_II[(cond, _T2_MODEL[conf])][i]


def _pairwise(
    metric: str, a: tuple[str, str], b: tuple[str, str], names: dict[str, str] | None = None
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
    return Claim(text, metric, a, b, expect, pa, pb)


def paper_claims() -> list[Claim | ModeClaim]:
    """The comparative claims of Section IV, in the direction the paper's tables give.

    * The same HCOMC claims against FIFO-R and Game-R, the baselines replanning every second
      as HCOMC does (not in the paper: it separates HCOMC's method from replanning alone).
    * Sections IV-A to IV-D with Table III: HCOMC versus FIFO and versus Game on critical
      distance, average acceleration, stabilisation time, LSRV and fuel in every condition
      (the text: HCOMC improves safety in all conditions, stability and rapidity "almost
      under all", traffic efficiency, and fuel except in C2, where it uses more). Where the
      table has HCOMC worse (average acceleration vs FIFO in C2, fuel in C2) the claim says
      so.
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
                out.append(_pairwise(metric, (cond, "HCOMC"), (cond, base)))
    # the same claims against the baselines replanning as HCOMC does (paper's values kept)
    out += [
        replace(c, text=f"{c.text}-R", b=(c.b[0], REPLANNING[c.b[1]]))
        for c in list(out)
        if isinstance(c, Claim) and c.b[1] in REPLANNING
    ]
    out += [ModeClaim("C1", "longitudinal"), ModeClaim("C2", "lateral"),
            ModeClaim("C3", "longitudinal")]  # fmt: skip
    for conf in ("FIFO", "Game", "HCOMC"):
        for more, fewer in (("C1", "C4"), ("C4", "C5")):
            out.append(_pairwise("lsrv", (fewer, conf), (more, conf)))
    c2 = ("critical_distance", "lsrv", "fuel")  # the three the text discusses for C2
    for cond, metrics in (("C1", PAPER_METRICS), ("C3", PAPER_METRICS), ("C2", c2)):
        for metric in metrics:
            for rival in ("HCOMC-PSO", "HCOMC-SA"):
                out.append(_pairwise(metric, (cond, "HCOMC"), (cond, rival), _T2_MODEL))
    return [c for c in out if c is not None]


def _values(runs: pd.DataFrame, cell: tuple[str, str], metric: str) -> pd.Series:
    part = runs[(runs["condition"] == cell[0]) & (runs["configuration"] == cell[1])]
    return part.groupby("seed")[metric].first()


def _evaluate(runs: pd.DataFrame, claim: Claim) -> dict[str, float] | None:
    """Paired differences A - B by seed: median, bootstrap CI, k of n, means."""
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
    holds = diff < 0 if claim.expect == "lower" else diff > 0
    median, low, high = median_ci(diff)
    nan = float("nan")
    return {
        "median_diff": median,
        "ci_low": low,
        "ci_high": high,
        "holds": int(holds.sum()),
        "n": int(diff.size),
        "mean_a": float(a[both].mean()) if both.any() else nan,
        "mean_b": float(b[both].mean()) if both.any() else nan,
    }


def _evaluate_mode(runs: pd.DataFrame, claim: ModeClaim) -> dict[str, float | str] | None:
    part = runs[(runs["condition"] == claim.condition) & (runs["configuration"] == "HCOMC")]
    if part.empty or "mode" not in part:
        return None
    counts = part["mode"].value_counts().to_dict()
    return {
        "holds": int((part["mode"] == claim.mode).sum()),
        "n": len(part),
        "ours": ", ".join(f"{k}: {v}" for k, v in counts.items()),
    }


def _row(runs: pd.DataFrame, claim: Claim | ModeClaim) -> dict[str, object] | None:
    nan = float("nan")
    if isinstance(claim, ModeClaim):
        res = _evaluate_mode(runs, claim)
        if res is None:
            return None
        return {
            "claim": f"HCOMC chooses {claim.mode} cooperation",
            "condition": claim.condition,
            "metric": "mode",
            "paper": claim.mode,
            "paper_diff": nan,
            "median_diff": nan,
            "ci_low": nan,
            "ci_high": nan,
            "holds": res["holds"],
            "n": res["n"],
            "ours": res["ours"],
        }
    result = _evaluate(runs, claim)
    if result is None:
        return None
    same = claim.a[0] == claim.b[0]
    return {
        "claim": claim.text,
        "condition": claim.a[0] if same else f"{claim.a[0]}/{claim.b[0]}",
        "metric": claim.metric,
        "paper": f"{claim.paper_a:g} vs {claim.paper_b:g}",
        "paper_diff": claim.paper_a - claim.paper_b,
        **{k: result[k] for k in ("median_diff", "ci_low", "ci_high", "holds", "n")},
        "ours": f"{result['mean_a']:.4g} vs {result['mean_b']:.4g}",
    }


def claims(runs: pd.DataFrame, uniform: pd.DataFrame | None = None) -> pd.DataFrame:
    """Every claim of :func:`paper_claims` the runs can evaluate, one row each.

    Columns: ``claim``, ``condition``, ``metric``, ``paper`` (the paper's "A vs B", or the
    mode), ``paper_diff`` (A - B in the paper), ``median_diff`` (median over seeds of the
    paired A - B), ``ci_low`` and ``ci_high`` (its 95 % bootstrap CI), ``holds`` (k),
    ``n``, ``ours`` (our means "A vs B", or the mode counts), ``share`` (k / n) and, when
    ``uniform`` (runs of the deterministic paper scenario) is given, ``uniform``: "yes" or
    "no" for the claim on those runs, "" if undefined there.
    """
    records: list[dict[str, object]] = []
    for claim in paper_claims():
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
    return pd.DataFrame(records)


def to_markdown(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured markdown table (no optional dependency)."""
    cols = list(frame.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    for _, row in frame.iterrows():
        cells = [f"{v:.2f}" if isinstance(v, float) else str(v) for v in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
