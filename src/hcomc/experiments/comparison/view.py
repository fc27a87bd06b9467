"""The tables of a controller comparison as text, for a terminal or a page: the effects
(:mod:`hcomc.experiments.comparison.effects`) and merge success
(:mod:`hcomc.experiments.comparison.success`), each metric named with its unit and preferred
direction."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from typing import Any

import pandas as pd

from hcomc.experiments.comparison.effects import PREFERS
from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS
from hcomc.experiments.tables import LABELS

__all__ = [
    "EFFECTS_VIEW_COLUMNS",
    "controller_labels",
    "effects_view",
    "means_view",
    "metric_label",
    "success_pairs_view",
    "success_view",
]

EFFECTS_VIEW_COLUMNS = (
    "cell", "metric", "A", "B", "median A-B [95 % CI]", "verdict", "favours", "A<B", "A>B",
    "failed A/B", "excluded", "p (Holm)", "verdict (Holm)",
)  # fmt: skip
"""The columns of :func:`effects_view`."""


def controller_labels(configurations: Sequence[str]) -> dict[str, str]:
    """The names under which a comparison's tables show the controllers named by module or
    file (``package.module:Class``, ``path/to/file.py:Class``): the ``name`` the class itself
    defines (not one inherited: a subclass of FIFO is not "fifo"), else the class name. A
    configuration keeps its spec when that name is taken, in any case (by another
    configuration or label), or its class cannot be loaded; configurations of
    other kinds (FIFO, HCOMC-R, a registered name, "HCOMC [one]") are not in the result. The
    spec stays the run's provenance (``runs.parquet``, ``compare.json``)."""
    from hcomc.config import ConfigError
    from hcomc.control.registry import controller_class

    names = {}
    for conf in configurations:
        if ":" not in conf:
            continue
        try:
            cls = controller_class(conf)
        except ConfigError:
            continue
        attr = vars(cls).get("name")
        names[conf] = attr if isinstance(attr, str) and attr else cls.__name__
    others = (c for c in configurations if c not in names)
    taken = Counter(n.lower() for n in names.values()) + Counter(c.lower() for c in others)
    return {conf: name for conf, name in names.items() if taken[name.lower()] == 1}


def metric_label(metric: str) -> str:
    """A metric's name with its unit and preferred direction (↑ larger is better, ↓ smaller)."""
    arrow = {"larger": " ↑", "smaller": " ↓"}.get(PREFERS.get(metric, ""), "")
    corridor = CORRIDOR_METRICS.get(metric)
    return LABELS.get(metric, corridor.label if corridor else metric) + arrow


def effects_view(frame: pd.DataFrame) -> pd.DataFrame:
    """The effects as text for a terminal or a page: cell, metric, A, B, median A - B with
    its 95 % CI, verdict, the favoured configuration, "k of n" seeds with A < B, seeds with
    A > B (a failed merge counted as the worse value), the seeds A / B did not merge on,
    excluded seeds, the Holm-adjusted p and its verdict."""

    def interval(m: float, lo: float, hi: float) -> str:
        return "—" if not math.isfinite(m) else f"{m:.4g} [{lo:.4g}, {hi:.4g}]"

    rows = frame.to_dict("records")
    return pd.DataFrame(
        {
            "cell": [r["condition"] for r in rows],
            "metric": [metric_label(r["metric"]) for r in rows],
            "A": [r["a"] for r in rows],
            "B": [r["b"] for r in rows],
            "median A-B [95 % CI]": [
                interval(r["median_diff"], r["ci_low"], r["ci_high"]) for r in rows
            ],
            "verdict": [r["verdict"] for r in rows],
            "favours": [r["favours"] or "—" for r in rows],
            "A<B": [f"{r['a_lower']} of {r['n']}" for r in rows],
            "A>B": [str(r["a_higher"]) for r in rows],
            "failed A/B": [f"{r['failed_a']}/{r['failed_b']}" for r in rows],
            "excluded": [str(r["excluded"]) for r in rows],
            "p (Holm)": [_p(r["p_holm"]) for r in rows],
            "verdict (Holm)": [r["verdict_holm"] for r in rows],
        },
        columns=EFFECTS_VIEW_COLUMNS,
    )


def means_view(frame: pd.DataFrame) -> pd.DataFrame:
    """The means (:func:`~hcomc.experiments.comparison.means.means`) as text: one row per cell
    and metric (with its unit and preferred direction), one column per configuration,
    "mean ± half-width (n)"; "—" without a value."""
    if frame.empty:
        return pd.DataFrame()

    def text(r: dict[str, Any]) -> str:
        if r["n"] == 0:
            return "—"
        half = f" ± {r['ci']:.2g}" if math.isfinite(r["ci"]) else ""
        return f"{r['mean']:.4g}{half} ({r['n']})"

    rows = frame.to_dict("records")
    labels = [metric_label(r["metric"]) for r in rows]
    shown = frame.assign(text=[text(r) for r in rows], label=labels)
    wide = shown.pivot(index=["condition", "label"], columns="configuration", values="text")
    order = pd.MultiIndex.from_frame(shown[["condition", "label"]].drop_duplicates())
    wide = wide.reindex(index=order, columns=pd.unique(frame["configuration"]))
    return wide.fillna("—").rename_axis(index=["cell", "metric"], columns=None).reset_index()


def _p(p: float) -> str:
    return "—" if not math.isfinite(p) else f"{p:.2g}"


def success_view(frame: pd.DataFrame) -> pd.DataFrame:
    """Merge success as text: one row per cell, one column per configuration, "k/n (rate)",
    then, if some plans fell back, "f/p fell back" (plans), marked "⚑" when the configuration
    is flagged (:data:`~hcomc.experiments.comparison.success.FALLBACK_FLAG`)."""
    if frame.empty:
        return pd.DataFrame()
    text = [
        f"{r['merged']}/{r['runs']} ({100 * r['rate']:.0f} %)" + _fell_back(r)
        for r in frame.to_dict("records")
    ]
    wide = frame.assign(text=text).pivot(index="condition", columns="configuration", values="text")
    wide = wide.reindex(index=pd.unique(frame["condition"]),
                        columns=pd.unique(frame["configuration"]))  # fmt: skip
    return wide.fillna("—").rename_axis(index="cell", columns=None).reset_index()


def _fell_back(row: dict[str, Any]) -> str:
    """What follows "k/n (rate)" when plans fell back: ", f/p plans fell back", with "⚑"
    when the configuration is flagged; nothing when none did."""
    fallbacks = int(row.get("fallbacks", 0) or 0)
    if not fallbacks:
        return ""
    flag = " ⚑" if row.get("flagged") else ""
    return f", {fallbacks}/{row['plans']} plans fell back{flag}"


def success_pairs_view(frame: pd.DataFrame) -> pd.DataFrame:
    """Paired merge success as text: cell, A, B, seeds where both / only A / only B /
    neither merged, the Holm-adjusted p of the exact McNemar test and its verdict."""
    rows = frame.to_dict("records")
    return pd.DataFrame(
        {
            "cell": [r["condition"] for r in rows],
            "A": [r["a"] for r in rows],
            "B": [r["b"] for r in rows],
            "both merged": [str(r["both"]) for r in rows],
            "only A": [str(r["only_a"]) for r in rows],
            "only B": [str(r["only_b"]) for r in rows],
            "neither": [str(r["neither"]) for r in rows],
            "p (Holm)": [_p(r["p_holm"]) for r in rows],
            "verdict (Holm)": [r["verdict_holm"] for r in rows],
        }
    )
