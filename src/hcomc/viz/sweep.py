"""Heat maps of a sweep over the density x penetration grid."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hcomc.experiments.sweep_spec import GRID_KEYS
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


def heatmap_figure(table: pd.DataFrame, metric: str) -> Figure:  # noqa: PLR0915 (panel after panel)
    """Mean ``metric`` per grid cell for each configuration, and HCOMC's improvement.

    Columns of cells are the (lane 1, lane 2) mean-headway pairs (density), rows the CAV
    penetration. All configuration panels share one colour scale, so equal colours mean equal
    values across controllers; the improvement panels show ``HCOMC - baseline`` signed so that
    positive means HCOMC is better (larger for "larger is better" metrics, smaller otherwise)
    on one symmetric scale. A cell whose mean rests on fewer seeds than the sweep ran is
    labelled with its n, and the title says how many seeds a cell holds.
    """
    unit, better = _unit_better(metric)
    if metric not in table:
        raise ValueError(f"metric '{metric}' is not in this sweep's table")
    cells = table.groupby([*GRID_KEYS, "configuration"])[metric]
    means = cells.mean().unstack("configuration")
    counts = cells.count().unstack("configuration").fillna(0).astype(int)
    runs = table.groupby([*GRID_KEYS, "configuration"]).size().unstack("configuration")
    pairs = sorted({(a, b) for a, b, _ in means.index})
    pens = sorted({p for _, _, p in means.index})
    confs = list(means.columns)
    baselines = [b for b in ("FIFO", "Game") if b in confs and "HCOMC" in confs]
    sign = 1.0 if better == "larger" else -1.0
    panels = [(c, means[c], counts[c], False) for c in confs]
    panels += [(f"HCOMC vs {b} (+ = HCOMC better)", sign * (means["HCOMC"] - means[b]),
                np.minimum(counts["HCOMC"], counts[b]), True) for b in baselines]  # fmt: skip
    grids = [_grid(series, pairs, pens) for _, series, _, _ in panels]
    plain = np.concatenate([g.ravel() for g, (*_, diff) in zip(grids, panels, strict=True)
                            if not diff])  # fmt: skip
    plain = plain[np.isfinite(plain)]
    vmin, vmax = (float(plain.min()), float(plain.max())) if plain.size else (0.0, 1.0)
    diffs = [np.abs(g[np.isfinite(g)]) for g, (*_, diff) in zip(grids, panels, strict=True)
             if diff]  # fmt: skip
    lim = max([float(d.max()) for d in diffs if d.size] or [1.0]) or 1.0

    n_cols = min(len(panels), 3)
    n_rows = -(-len(panels) // n_cols)
    cell_w, cell_h = 0.9, 0.6  # [in] per grid cell, so labels fit
    panel_w = max(3.2, cell_w * len(pairs) + 1.6)
    panel_h = max(2.6, cell_h * len(pens) + 1.4)
    fig = new_figure(min(18.0, panel_w * n_cols), panel_h * n_rows + 0.7)
    axes = fig.subplots(n_rows, n_cols, squeeze=False).ravel()
    for ax in axes[len(panels) :]:
        ax.set_axis_off()
    n_max = int(runs.max().max()) if runs.size else 0
    label_size = 9 if len(pairs) <= 6 else 7
    for ax, grid, (title, _, count, diff) in zip(axes, grids, panels, strict=False):
        cmap = "RdBu" if diff else "viridis"
        lo, hi = (-lim, lim) if diff else (vmin, vmax)
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap=cmap, vmin=lo, vmax=hi)
        n_grid = _grid(count, pairs, pens)
        for (r, c), value in np.ndenumerate(grid):
            if not np.isfinite(value):
                ax.text(c, r, "no value", ha="center", va="center", fontsize=label_size - 1,
                        color="0.3")  # fmt: skip
                continue
            text = f"{value:.3g}"
            if n_grid[r, c] < n_max:
                text += f"\nn = {int(n_grid[r, c])}"
            ax.text(c, r, text, ha="center", va="center", fontsize=label_size,
                    color=_contrast(image, value))  # fmt: skip
        ax.set_xticks(range(len(pairs)), [f"{a:g}/{b:g}" for a, b in pairs])
        ax.set_yticks(range(len(pens)), [f"{p:.0%}" for p in pens])
        ax.set_xlabel("mean headway lane 1 / lane 2 [s]")
        ax.set_ylabel("CAV penetration")
        ax.set_title(title, fontsize=10)
    plain_axes = [ax for ax, (*_, diff) in zip(axes, panels, strict=False) if not diff]
    diff_axes = [ax for ax, (*_, diff) in zip(axes, panels, strict=False) if diff]
    name = f"{metric.replace('_', ' ')} [{unit}]"
    fig.colorbar(plain_axes[0].images[0], ax=plain_axes, label=name, shrink=0.9)
    if diff_axes:
        fig.colorbar(diff_axes[0].images[0], ax=diff_axes, label=f"difference [{unit}]",
                     shrink=0.9)  # fmt: skip
    n_min = int(runs.min().min()) if runs.size else 0
    seeds = f"{n_max}" if n_min == n_max else f"{n_min}–{n_max}"
    note = "; 'n = k': only k seeds give a value" if (counts < n_max).to_numpy().any() else ""
    fig.suptitle(f"{metric.replace('_', ' ')} over the density × penetration grid "
                 f"(mean over {seeds} seeds per cell{note})")  # fmt: skip
    return fig


def _grid(series: pd.Series, pairs: list, pens: list) -> np.ndarray:
    """Penetration x headway-pair array of a series indexed by the grid keys (NaN if absent)."""
    grid = np.full((len(pens), len(pairs)), np.nan)
    for (a, b, p), value in series.items():
        grid[pens.index(p), pairs.index((a, b))] = value
    return grid


def _contrast(image: Any, value: float) -> str:
    """Black or white text, whichever reads better on the cell's colour."""
    r, g, b, _ = image.cmap(image.norm(value))
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.5 else "white"
