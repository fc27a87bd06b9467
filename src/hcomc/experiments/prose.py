"""Formatting and counting shared by the generated prose (:mod:`hcomc.experiments.narrative`)
and the checks (:mod:`hcomc.experiments.checks`): numbers as the documents print them, and
counts read from a digest's decisions table."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from hcomc.experiments.digest import Digest
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.experiments.tables import to_markdown

METRIC_NAMES = {m: m.replace("_", " ") for m in PAPER_METRICS}


def g(x: float) -> str:
    """Four significant digits, "—" for NaN."""
    return "—" if not np.isfinite(x) else f"{x:.4g}"


def sci(x: float, digits: int = 1) -> str:
    """Scientific notation without a padded exponent: 3.7e-4."""
    mantissa, exponent = f"{x:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def p_text(x: float) -> str:
    """A p-value: three decimals, or two significant digits below 0.001."""
    if not np.isfinite(x):
        return "—"
    return sci(x) if x < 1e-3 else f"{x:.3f}"


def pct(k: float, n: float) -> str:
    return "—" if not n or not np.isfinite(k) else f"{round(100 * k / n)} %"


def num(x: float) -> str:
    """A count or a value: an integer without decimals, else four significant digits."""
    if not np.isfinite(x):
        return "—"
    return str(int(x)) if float(x).is_integer() else f"{x:.4g}"


def join(items: Iterable[str]) -> str:
    """The items as prose: "a", "a and b", "a, b and c"."""
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def weighted(values: pd.Series, weights: pd.Series) -> float:
    """Mean of per-cell means weighted by their runs (NaN without weight or values)."""
    ok = values.notna() & (weights > 0)
    if not ok.any():
        return float("nan")
    return float(np.average(values[ok], weights=weights[ok]))


def md(frame: pd.DataFrame) -> str:
    return to_markdown(frame).rstrip("\n")


def total(d: Digest, column: str, configuration: str | None = None) -> tuple[float, int]:
    """Sum of a decisions column and of its runs (over one configuration, or all)."""
    dec = d.decisions
    part = dec if configuration is None else dec[dec["configuration"] == configuration]
    return float(part[column].sum(min_count=1)), int(part["runs"].sum())


def cell(d: Digest, condition: str, configuration: str, column: str) -> tuple[float, int]:
    dec = d.decisions
    row = dec[(dec["condition"] == condition) & (dec["configuration"] == configuration)]
    if row.empty:
        return float("nan"), 0
    return float(row[column].iloc[0]), int(row["runs"].iloc[0])


def total_collisions(d: Digest) -> float:
    """Collisions over every run: the seeded runs and the paper scenario's."""
    collisions = float(d.decisions["collisions"].sum(min_count=1))
    if "collisions" in d.scenario:
        collisions += float(d.scenario["collisions"].sum())
    return collisions
