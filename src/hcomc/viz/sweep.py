"""Heat maps of a sweep over the density x penetration grid."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hcomc.experiments.sweep import GRID_KEYS
from hcomc.metrics import METRICS
from hcomc.viz.common import new_figure

_EXTRA_UNITS = {"throughput": ("veh/h", "larger"), "ramp_delay": ("s", "smaller")}


def _unit_better(metric: str) -> tuple[str, str]:
    if metric in METRICS:
        return METRICS[metric].unit, METRICS[metric].better
    if metric in _EXTRA_UNITS:
        return _EXTRA_UNITS[metric]
    allowed = ", ".join([*METRICS, *_EXTRA_UNITS])
    raise ValueError(f"unknown metric '{metric}'; allowed: {allowed}")


def heatmap_figure(table: pd.DataFrame, metric: str) -> Figure:
    """Mean ``metric`` per grid cell for each configuration, and HCOMC's improvement.

    Columns of cells are the (lane 1, lane 2) mean-headway pairs (density), rows the CAV
    penetration. The improvement panels show ``HCOMC - baseline`` signed so that positive means
    HCOMC is better (larger for "larger is better" metrics, smaller otherwise).
    """
    unit, better = _unit_better(metric)
    if metric not in table:
        raise ValueError(f"metric '{metric}' is not in this sweep's table")
    means = table.groupby([*GRID_KEYS, "configuration"])[metric].mean().unstack("configuration")
    pairs = sorted({(a, b) for a, b, _ in means.index})
    pens = sorted({p for _, _, p in means.index})
    confs = list(means.columns)
    baselines = [b for b in ("FIFO", "Game") if b in confs and "HCOMC" in confs]
    panels = [(c, means[c]) for c in confs]
    sign = 1.0 if better == "larger" else -1.0
    panels += [(f"HCOMC vs {b} (+ = better)", sign * (means["HCOMC"] - means[b]))
               for b in baselines]  # fmt: skip
    fig = new_figure(4.2 * len(panels), 3.8)
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (title, series) in zip(axes, panels, strict=True):
        grid = np.full((len(pens), len(pairs)), np.nan)
        for (a, b, p), value in series.items():
            grid[pens.index(p), pairs.index((a, b))] = value
        diverging = title.startswith("HCOMC vs")
        lim = np.nanmax(np.abs(grid)) if diverging and np.isfinite(grid).any() else None
        image = ax.imshow(grid, origin="lower", aspect="auto",
                          cmap="RdBu" if diverging else "viridis",
                          vmin=-lim if lim else None, vmax=lim)  # fmt: skip
        for (r, c), value in np.ndenumerate(grid):
            if np.isfinite(value):
                ax.text(c, r, f"{value:.3g}", ha="center", va="center", fontsize=8,
                        bbox={"facecolor": "white", "alpha": 0.7, "linewidth": 0})  # fmt: skip
        ax.set_xticks(range(len(pairs)), [f"{a:g}/{b:g}" for a, b in pairs])
        ax.set_yticks(range(len(pens)), [f"{p:.0%}" for p in pens])
        ax.set_xlabel("mean headway lane 1 / lane 2 [s]")
        ax.set_ylabel("CAV penetration")
        ax.set_title(title)
        fig.colorbar(image, ax=ax, label=f"{metric.replace('_', ' ')} [{unit}]")
    fig.suptitle(f"{metric.replace('_', ' ')} over the density × penetration grid (mean of seeds)")
    return fig
