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

from hcomc.experiments.comparison.effects import PREFERS, favoured
from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS
from hcomc.experiments.tables import LABELS

__all__ = [
    "EFFECTS_LEGEND",
    "EFFECTS_VIEW_COLUMNS",
    "PAIR_VIEW_COLUMNS",
    "SAFETY_LABELS",
    "controller_labels",
    "effects_view",
    "interval_text",
    "means_view",
    "metric_label",
    "rounded",
    "safety_view",
    "success_pairs_view",
    "success_view",
]

EFFECTS_VIEW_COLUMNS = (
    "cell", "metric", "A", "B", "median A-B [95 % CI]", "A<B", "A>B", "failed A/B",
    "excluded", "verdict", "favours", "p (Holm)", "verdict (Holm)", "favours (Holm)",
)  # fmt: skip
"""The columns of :func:`effects_view`."""

PAIR_VIEW_COLUMNS = (
    "cell", "metric", "median A-B [95 % CI]", "A<B", "A>B", "failed A/B", "excluded",
    "p (Holm)", "favours (CI)", "favours (Holm)",
)  # fmt: skip
"""The columns of one comparison's effects on a terminal of 120 columns: those of
:data:`EFFECTS_VIEW_COLUMNS` without A and B (the comparison is the table's title) and the
verdicts (the favoured configuration says them)."""

EFFECTS_LEGEND = (
    "A>B: seeds; failed A/B: seeds without a merge; excluded: seeds without a pair; p: "
    "two-sided sign test, Holm-adjusted over every effect shown; favours: the configuration "
    "that the CI rule (CI) or the Holm-adjusted sign test (Holm) finds better by the metric's "
    "direction (↑ larger, ↓ smaller), — if undecided"
)
"""What the effects tables' columns after A<B mean (the end of their caption)."""


def rounded(value: float, uncertainty: float = float("nan")) -> str:
    """``value`` to the precision its ``uncertainty`` (a CI half-width) supports: two
    significant digits of the uncertainty (54.2 ± 3.1, 0.0612 ± 0.0048, 25000 ± 63000), or
    three of the value itself without one (n < 2, or an interval of width 0); "—" for NaN,
    "∞" / "-∞" for an infinite value."""
    if math.isnan(value):
        return "—"
    if math.isinf(value):
        return "∞" if value > 0 else "-∞"
    scale = abs(uncertainty) if math.isfinite(uncertainty) and uncertainty != 0 else 0.0
    if scale:
        places = 1 - math.floor(math.log10(scale))
    elif value:
        places = 2 - math.floor(math.log10(abs(value)))
    else:
        places = 0
    places = min(places, 9)
    text = f"{round(value, places):.{max(places, 0)}f}"  # places < 0: to tens, hundreds, ...
    return text.lstrip("-") if float(text) == 0 else text  # no "-0.00"


def interval_text(median: float, low: float, high: float) -> str:
    """ "median [low, high]", rounded to the interval's half-width (:func:`rounded`); a bound
    that would round to 0 keeps its first significant digit, so that its sign shows (an
    interval from -0.04 to 1.96 reads [-0.040, 2.0], not [0.0, 2.0]); "—" without a
    median."""
    if math.isnan(median):
        return "—"
    half = (high - low) / 2 if math.isfinite(high - low) else math.nan
    if half <= 1e-9 * max(1.0, abs(median)):  # a point interval, up to round-off
        half = 0.0

    def bound(b: float) -> str:
        text = rounded(b, half)
        return rounded(b, abs(b)) if b and math.isfinite(b) and float(text) == 0 else text

    return f"{rounded(median, half)} [{bound(low)}, {bound(high)}]"


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
    """The effects as text for a page or a wide terminal, one row per cell, comparison and
    metric (:data:`EFFECTS_VIEW_COLUMNS`): the median A - B with its 95 % CI rounded to the
    CI's precision (:func:`rounded`), "k of n" seeds with A < B, seeds with A > B (a failed
    merge counted as the worse value), the seeds A / B did not merge on, excluded seeds, the
    CI rule's verdict and the configuration it favours, the Holm-adjusted p, its verdict and
    the configuration that favours."""
    rows = frame.to_dict("records")
    return pd.DataFrame(
        {
            "cell": [r["condition"] for r in rows],
            "metric": [metric_label(r["metric"]) for r in rows],
            "A": [r["a"] for r in rows],
            "B": [r["b"] for r in rows],
            "median A-B [95 % CI]": [_interval(r) for r in rows],
            "A<B": [f"{r['a_lower']} of {r['n']}" for r in rows],
            "A>B": [str(r["a_higher"]) for r in rows],
            "failed A/B": [f"{r['failed_a']}/{r['failed_b']}" for r in rows],
            "excluded": [str(r["excluded"]) for r in rows],
            "verdict": [r["verdict"] for r in rows],
            "favours": [r["favours"] or "—" for r in rows],
            "p (Holm)": [_p(r["p_holm"]) for r in rows],
            "verdict (Holm)": [r["verdict_holm"] for r in rows],
            "favours (Holm)": [_favoured_by_holm(r) or "—" for r in rows],
        },
        columns=EFFECTS_VIEW_COLUMNS,
    )


def _interval(row: dict[str, Any]) -> str:
    return interval_text(row["median_diff"], row["ci_low"], row["ci_high"])


def _favoured_by_holm(row: dict[str, Any]) -> str:
    return favoured(row["verdict_holm"], row["prefers"], row["a"], row["b"])


def means_view(frame: pd.DataFrame) -> pd.DataFrame:
    """The means (:func:`~hcomc.experiments.comparison.means.means`) as text: one row per cell
    and metric (with its unit and preferred direction), one column per configuration,
    "mean ± half-width", rounded to the half-width (:func:`rounded`), followed by "(n)" when
    only n of the cell's runs have a value; "—" without a value."""
    if frame.empty:
        return pd.DataFrame()

    def text(r: dict[str, Any]) -> str:
        if r["n"] == 0:
            return "—"
        half = f" ± {rounded(r['ci'], r['ci'])}" if math.isfinite(r["ci"]) else ""
        fewer = f" ({r['n']})" if r["n"] < r["runs"] else ""
        return f"{rounded(r['mean'], r['ci'])}{half}{fewer}"

    rows = frame.to_dict("records")
    labels = [metric_label(r["metric"]) for r in rows]
    shown = frame.assign(text=[text(r) for r in rows], label=labels)
    wide = shown.pivot(index=["condition", "label"], columns="configuration", values="text")
    order = pd.MultiIndex.from_frame(shown[["condition", "label"]].drop_duplicates())
    wide = wide.reindex(index=order, columns=pd.unique(frame["configuration"]))
    return wide.fillna("—").rename_axis(index=["cell", "metric"], columns=None).reset_index()


SAFETY_LABELS = {"min_ttc": "least TTC [s]", "max_drac": "max DRAC [m/s²]"}
"""The run columns of the safety measures and their labels."""

SAFETY_ROWS = (
    (SAFETY_LABELS["min_ttc"] + " ↑", "least_ttc", "least_ttc_seed"),
    (SAFETY_LABELS["max_drac"] + " ↓", "max_drac", "max_drac_seed"),
)
"""The rows of :func:`safety_view` with a value and its seed: label, value, seed column."""


def safety_view(frame: pd.DataFrame) -> pd.DataFrame:
    """The safety extremes (:func:`~hcomc.experiments.comparison.safety.safety_extremes`) as
    text: per cell the least TTC and the largest DRAC over each configuration's runs, "value
    (seed s)" to three significant digits, and its collisions ("k, j with a key vehicle");
    "—" without a value."""
    if frame.empty:
        return pd.DataFrame()
    rows = []
    for condition, cell in frame.groupby("condition", sort=False):
        by_conf = cell.set_index("configuration")
        for label, value, seed in SAFETY_ROWS:
            rows.append({"cell": condition, "measure": label, **{
                c: "—" if r[seed] < 0 else f"{rounded(r[value])} (seed {r[seed]})"
                for c, r in by_conf.iterrows()}})  # fmt: skip
        rows.append({"cell": condition, "measure": "collisions ↓", **{
            c: str(r["collisions"]) + (f", {r['key_collisions']} with a key vehicle"
                                       if r["key_collisions"] else "")
            for c, r in by_conf.iterrows()}})  # fmt: skip
    return pd.DataFrame(rows).fillna("—")


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
