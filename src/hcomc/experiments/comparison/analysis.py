"""The tables of a controller comparison, computed from its runs in one call: merge success
(:func:`~hcomc.experiments.comparison.success.merge_success`), its paired comparison
(:func:`~hcomc.experiments.comparison.success.success_pairs`), the means
(:func:`~hcomc.experiments.comparison.means.means`), the paired effects
(:func:`~hcomc.experiments.comparison.effects.effects`) and the safety extremes
(:func:`~hcomc.experiments.comparison.safety.safety_extremes`).

A controller named by module or file (``package.module:Class``, ``path/to/file.py:Class``)
is shown by its name (:func:`~hcomc.experiments.comparison.view.controller_labels`) in the
runs the tables are computed from, so that every table names it alike; the spec stays the
provenance of whoever keeps the runs as they ran (``runs.parquet``, ``compare.json``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pandas as pd

from hcomc.experiments.comparison.effects import effects
from hcomc.experiments.comparison.means import means
from hcomc.experiments.comparison.safety import safety_extremes
from hcomc.experiments.comparison.success import merge_success, success_pairs
from hcomc.experiments.comparison.view import controller_labels
from hcomc.experiments.paper import PAPER_METRICS

__all__ = ["ComparisonTables", "comparison_tables"]


@dataclass(frozen=True, eq=False)
class ComparisonTables:
    """A comparison's tables, every configuration by the name the tables show.

    ``names`` maps the spec of each controller shown by another name to that name; ``runs``
    are the runs the tables were computed from, with those names."""

    names: dict[str, str]
    configurations: tuple[str, ...]
    comparisons: tuple[tuple[str, str], ...]  # (A, B), A the configuration compared with B
    runs: pd.DataFrame
    success: pd.DataFrame  # hcomc.experiments.comparison.success.Success, a row each
    success_pairs: pd.DataFrame  # ... .success.SuccessPair
    means: pd.DataFrame  # hcomc.experiments.comparison.means.Mean
    effects: pd.DataFrame  # hcomc.experiments.comparison.effects.Effect
    safety: pd.DataFrame  # hcomc.experiments.comparison.safety.SafetyExtremes


def comparison_tables(
    runs: pd.DataFrame,
    configurations: Sequence[str],
    comparisons: Sequence[tuple[str, str]],
    metrics: Sequence[str] = PAPER_METRICS,
) -> ComparisonTables:
    """The tables of ``runs`` (one per cell, configuration and seed) for ``comparisons`` of
    ``configurations`` on ``metrics`` (default: the paper's five)."""
    names = controller_labels(configurations)
    shown = runs.replace({"configuration": names}) if names else runs
    confs = [names.get(c, c) for c in configurations]
    pairs = [(names.get(a, a), names.get(b, b)) for a, b in comparisons]
    return ComparisonTables(
        names=names,
        configurations=tuple(confs),
        comparisons=tuple(pairs),
        runs=shown,
        success=merge_success(shown, confs),
        success_pairs=success_pairs(shown, pairs),
        means=means(shown, confs, metrics),
        effects=effects(shown, confs, comparisons=pairs, metrics=metrics),
        safety=safety_extremes(shown, confs),
    )
