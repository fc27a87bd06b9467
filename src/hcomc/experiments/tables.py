"""Summaries of a results table: mean and 95 % CI, median and bootstrap CI, the paper's
Tables II-III side by side with ours, and merge success.

Tables II and III show each row on its own runs: a metric's mean, CI and median in a row are
taken over the seeds on which that row has a finite value (n), so that no other row, and no
configuration added to the run, can change a row's numbers. Every row of a condition runs the
same seeds; a seed missing from a metric's n is a run without a merge (merge metrics are
undefined for it) or without a defined value, and the merged column (runs in which VR merged,
k of n) and VR's delay (from its control-zone entry to its merge) count every run. The
paired comparisons, with failed merges as outcomes, are :mod:`hcomc.experiments.claims`.
The claims built on the same runs are :mod:`hcomc.experiments.claims`. Nothing here is
written by hand: every number comes from the runs, the paper's values from
:mod:`hcomc.experiments.paper`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from hcomc.experiments.paper import PAPER_METRICS, TABLE_II, TABLE_III

LABELS = {
    "critical_distance": "Crit. Dist. [m]",
    "average_acceleration": "Aver. Acc. [m/s²]",
    "stabilisation_time": "Stab. Time from entry [s]",
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
    "merge_time": 1,
}
MEDIAN_SHOWN = ("critical_distance",)
"""Metrics whose median is shown beside the mean (a minimum over a run, heavy-tailed)."""


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


REPLANNING = {"FIFO": "FIFO-R", "Game": "Game-R", "HCOMC": "HCOMC-R"}
"""The configurations as published (one plan) -> their variants replanning every second (a
labelled extension, not in the paper)."""

TABLE_CAPTION = (
    "ours: mean ± 95 % CI (paper value in brackets) over the row's own seeds with a value; "
    "n = those seeds, per metric in column order when they differ; merged: runs in which VR "
    "merged, k/n; VR delay: from VR's control-zone entry to its merge, over its merged runs "
    "(not in the paper's tables); the critical distance's median beside its mean"
)
"""What a cell of :func:`paper_table` means (the caption wherever the tables are shown)."""


def table_rows(runs: pd.DataFrame, which: str) -> list[tuple[str, str, str, tuple | None]]:
    """``(condition, model, configuration, paper values or None)`` of every row of Table II
    ("II": optimisers, C1-C3) or III ("III": controllers, C1-C5) the runs have, in order.

    Table III lists the replanning variants (FIFO-R, Game-R, HCOMC-R) under the paper's FIFO,
    Game and HCOMC values, and after a condition's HCOMC every other configuration of the runs that
    neither table names (e.g. a variant of HCOMC), without a paper value.
    """
    reference, names = (TABLE_II, TABLE_II_ROWS) if which == "II" else (TABLE_III, TABLE_III_ROWS)
    present = set(zip(runs["condition"], runs["configuration"], strict=True))
    named = {*TABLE_II_ROWS.values(), *TABLE_III_ROWS.values(), *REPLANNING.values()}
    rows: list[tuple[str, str, str, tuple | None]] = []
    for (cond, model), values in reference.items():
        rows.append((cond, model, names[model], values))
        if which == "III" and model in REPLANNING:
            rows.append((cond, REPLANNING[model], REPLANNING[model], values))
        if which == "III" and model == "HCOMC":
            others = pd.unique(runs.loc[runs["condition"] == cond, "configuration"])
            rows += [(cond, str(c), str(c), None) for c in others if c not in named]
    return [row for row in rows if (row[0], row[2]) in present]


def _merged(part: pd.DataFrame) -> float:
    """Runs of ``part`` in which VR merged (NaN without a ``merged`` column)."""
    return float(part["merged"].eq(True).sum()) if "merged" in part else float("nan")


def table_summary(runs: pd.DataFrame, which: str) -> pd.DataFrame:
    """Table II or III as numbers: one row per :func:`table_rows` entry.

    Columns: ``table``, ``condition``, ``model``, ``configuration``, ``runs`` (rows of the
    cell), ``merged`` (runs with ``merged`` true; NaN when the runs have no such column) and
    per paper metric ``m`` and ``merge_time`` (VR's delay): ``m`` (mean over the row's
    seeds with a finite value), ``m_ci`` (half-width of its 95 % t interval), ``m_n`` (those
    seeds), ``m_median`` and ``m_paper`` (NaN for ``merge_time``).
    """
    records = []
    for cond, model, conf, paper in table_rows(runs, which):
        cell = runs[(runs["condition"] == cond) & (runs["configuration"] == conf)]
        rec: dict[str, object] = {
            "table": which, "condition": cond, "model": model, "configuration": conf,
            "runs": len(cell), "merged": _merged(cell),
        }  # fmt: skip
        for i, m in enumerate((*PAPER_METRICS, "merge_time")):
            values = _finite(cell, m)
            rec[m], rec[f"{m}_ci"], rec[f"{m}_n"] = mean_ci(values)
            rec[f"{m}_median"] = float(np.median(values)) if values.size else float("nan")
            shown = paper is not None and i < len(PAPER_METRICS)
            rec[f"{m}_paper"] = paper[i] if shown else float("nan")  # type: ignore[index]
        records.append(rec)
    return pd.DataFrame(records)


def _finite(cell: pd.DataFrame, metric: str) -> np.ndarray:
    """The finite values of ``metric`` in the runs ``cell`` (none without the column)."""
    if metric not in cell:
        return np.empty(0)
    values = cell[metric].to_numpy(dtype=np.float64)
    return values[np.isfinite(values)]


def _fmt(value: float, half: float, digits: int) -> str:
    if not np.isfinite(value):
        return "—"
    ci = "" if not np.isfinite(half) else f" ± {half:.{digits}f}"
    return f"{value:.{digits}f}{ci}"


def _seeds(row: pd.Series) -> str:
    """The n of a row: one number when every metric has the same, else one per metric."""
    ns = [str(int(row[f"{m}_n"])) for m in PAPER_METRICS]
    return ns[0] if len(set(ns)) == 1 else " · ".join(ns)


def format_table(table: pd.DataFrame) -> pd.DataFrame:
    """A :func:`table_summary` frame in the paper's layout: Condition, Model, merged (when
    known), n and each metric as "mean ± CI (paper)" (see :data:`TABLE_CAPTION`)."""
    out = []
    for _, row in table.iterrows():
        rec: dict[str, object] = {"Condition": row["condition"], "Model": row["model"]}
        if np.isfinite(row["merged"]):
            rec["merged"] = f"{int(row['merged'])}/{int(row['runs'])}"
        rec["n"] = _seeds(row)
        for m in PAPER_METRICS:
            paper = row[f"{m}_paper"]
            shown = f"{paper:g}" if np.isfinite(paper) else "—"
            rec[LABELS[m]] = f"{_fmt(row[m], row[f'{m}_ci'], DIGITS[m])} ({shown})"
            if m in MEDIAN_SHOWN:
                rec[f"{LABELS[m].split(' [')[0]} median"] = _fmt(row[f"{m}_median"], np.nan,
                                                                 DIGITS[m])  # fmt: skip
        rec["VR delay [s]"] = _fmt(row["merge_time"], row["merge_time_ci"], DIGITS["merge_time"])
        out.append(rec)
    return pd.DataFrame(out)


def paper_table(runs: pd.DataFrame, which: str) -> pd.DataFrame:
    """Table II ("II") or III ("III") in the paper's layout: :func:`format_table` of
    :func:`table_summary`."""
    return format_table(table_summary(runs, which))


def merge_success(runs: pd.DataFrame) -> pd.DataFrame:
    """Runs in which VR merged, "k/n", per condition (rows) and configuration (columns, in
    order of appearance); empty when the runs have no ``merged`` column."""
    if "merged" not in runs:
        return pd.DataFrame()
    grouped = runs.groupby(["condition", "configuration"], sort=False)["merged"]
    cells = grouped.agg(lambda s: f"{int(s.eq(True).sum())}/{len(s)}")
    wide = cells.unstack().reindex(columns=list(pd.unique(runs["configuration"])))
    return wide.fillna("—").rename_axis(index="condition", columns=None).reset_index()


BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 20250715  # fixed: the same runs always give the same interval
TIE_TOLERANCE = 1e-9  # paired values closer than this (relative, at least 1) are equal


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


def to_markdown(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured markdown table (no optional dependency)."""
    cols = list(frame.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    for _, row in frame.iterrows():
        cells = [f"{v:.2f}" if isinstance(v, float) else str(v) for v in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
