"""The paper's five metrics: mean and 95 % CI per condition and configuration."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from hcomc.viz.common import (
    CONFIGURATION_COLORS,
    new_figure,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure


METRIC_TITLES = {
    "critical_distance": "Critical distance",
    "average_acceleration": "Average acceleration",
    "stabilisation_time": "Stabilisation time",
    "lsrv": "Low-speed region volume",
    "fuel": "Fuel consumption",
}
"""Paper metric -> panel title of :func:`metrics_figure`."""


def metrics_figure(runs: pd.DataFrame, *, metrics: Sequence[str] | None = None) -> Figure:
    """The paper's metrics per condition and configuration: mean with 95 % CI.

    One panel per metric; condition groups along the horizontal axis and one bar per
    configuration (mean over seeds) with the half-width of the 95 % t confidence interval
    of :func:`hcomc.experiments.tables.mean_ci` as error bar (none when fewer than two
    finite values).

    Parameters
    ----------
    runs : pandas.DataFrame
        Results table of :func:`hcomc.experiments.runner.run_grid` (columns
        ``condition``, ``configuration`` and the metrics).
    metrics : sequence of str or None
        Metric columns to show; default the five paper metrics
        (:data:`hcomc.experiments.tables.LABELS`).

    Returns
    -------
    matplotlib.figure.Figure
        One axes per metric (2 rows x 3 columns grid, the legend in the free slot).

    Raises
    ------
    ValueError
        If *runs* is empty or lacks a needed column.
    """
    from hcomc.experiments.tables import BETTER, LABELS, mean_ci

    metrics = list(LABELS) if metrics is None else list(metrics)
    missing = [c for c in ("condition", "configuration", *metrics) if c not in runs.columns]
    if missing:
        raise ValueError(f"runs table lacks column(s) {missing}; has {list(runs.columns)}")
    if runs.empty:
        raise ValueError("runs table is empty: nothing to plot")
    conditions = list(pd.unique(runs["condition"]))
    present = list(pd.unique(runs["configuration"]))
    configs = [c for c in CONFIGURATION_COLORS if c in present]
    configs += [c for c in present if c not in configs]
    fallback = ("#66c2a5", "#fc8d62", "#8da0cb", "#e78ac3", "#a6d854", "#ffd92f")
    colors = {
        c: CONFIGURATION_COLORS.get(c, fallback[j % len(fallback)]) for j, c in enumerate(configs)
    }
    n_cols = 3 if len(metrics) > 2 else len(metrics)
    n_rows = math.ceil((len(metrics) + 1) / n_cols) if len(metrics) > 2 else 1
    fig = new_figure(4.0 * n_cols, 3.3 * n_rows + 0.4)
    grid = fig.add_gridspec(n_rows, n_cols)
    width = 0.8 / len(configs)
    centres = np.arange(len(conditions), dtype=np.float64)
    grouped = runs.groupby(["condition", "configuration"], sort=False)
    axes = []
    short: dict[str, int] = {}  # metric -> runs without a value
    for m_index, metric in enumerate(metrics):
        ax = fig.add_subplot(grid[m_index // n_cols, m_index % n_cols])
        axes.append(ax)
        for j, conf in enumerate(configs):
            stats = []
            for cond in conditions:
                part = (
                    grouped.get_group((cond, conf))[metric]
                    if (cond, conf) in grouped.groups
                    else pd.Series(dtype=float)
                )
                mean_c, half_c, n_c = mean_ci(part)
                stats.append((mean_c, half_c, n_c, len(part)))
            mean = np.array([s[0] for s in stats])
            half = np.array([s[1] for s in stats])
            x = centres + (j - (len(configs) - 1) / 2) * width
            ax.bar(
                x,
                np.nan_to_num(mean),
                width=width * 0.92,
                color=colors[conf],
                edgecolor="black",
                linewidth=0.4,
                label=conf,
                zorder=2,
            )
            ok = np.isfinite(mean) & np.isfinite(half)
            if ok.any():
                ax.errorbar(
                    x[ok],
                    mean[ok],
                    yerr=half[ok],
                    fmt="none",
                    ecolor="black",
                    elinewidth=0.8,
                    capsize=2.0,
                    zorder=3,
                )
            for xi, (m_c, h_c, n_c, rows) in zip(x, stats, strict=True):
                if rows > 0 and n_c < rows:  # a mean over fewer seeds than were run
                    short[metric] = short.get(metric, 0) + rows - n_c
                    top = np.nan_to_num(m_c) + (h_c if np.isfinite(h_c) else 0.0)
                    ax.annotate(f"n={n_c}", (xi, top), xytext=(0, 2), textcoords="offset points",
                                ha="center", va="bottom", fontsize=7)  # fmt: skip
        ax.set_xticks(centres, [str(c) for c in conditions])
        ax.set_ylabel(LABELS.get(metric, metric))
        better = BETTER.get(metric, "")
        note = {"larger": " (higher is better)", "smaller": " (lower is better)"}.get(better, "")
        ax.set_title(METRIC_TITLES.get(metric, metric) + note, fontsize=10)
        ax.grid(True, axis="y", color="0.88", linewidth=0.5, zorder=0)
        ax.set_axisbelow(True)
        if m_index // n_cols == n_rows - 1 or m_index + n_cols >= len(metrics):
            ax.set_xlabel("condition")
    handles, labels = axes[0].get_legend_handles_labels()
    n_seeds = runs.groupby(["condition", "configuration"]).size()
    seeds = (
        f"{n_seeds.min()}" if n_seeds.min() == n_seeds.max() else f"{n_seeds.min()}–{n_seeds.max()}"
    )
    note = f"bars: mean over {seeds} seeds; whiskers: 95 % CI"
    if short:
        note += "; 'n=k': only k seeds give a value"
    if "critical_distance" in short:
        note += (
            "; Crit. Dist. has no value in a run where VR did not merge or no two key "
            "vehicles share a lane after the merge"
        )
    free = len(metrics) % n_cols
    if n_rows > 1 and free:
        slot = fig.add_subplot(grid[n_rows - 1, free:])
        slot.set_axis_off()
        slot.legend(
            handles,
            labels,
            loc="center",
            title="configuration",
            frameon=False,
            ncols=1 if n_cols - free < 2 else 2,
        )
        slot.text(
            0.5,
            0.02,
            textwrap.fill(note, 70),
            transform=slot.transAxes,
            ha="center",
            va="bottom",
            fontsize=8,
        )
    else:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncols=len(labels),
            frameon=False,
            title=textwrap.fill(note, 110),
        )
    fig.suptitle("Merge metrics by condition and configuration")
    return fig
