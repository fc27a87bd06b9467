"""Speed contour map v(x, t) per controller and main lane (paper Fig. 2)."""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from hcomc.metrics import reference_speed, road_of, speed_field
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog
from hcomc.viz.common import (
    LANE_NAMES,
    NO_DATA_COLOR,
    log_window,
    new_figure,
    run_title,
    shade_zones,
    speed_cmap,
)
from hcomc.viz.figures._shared import (
    _MAIN_LANES,
    _MERGE,
    _is_merge,
    _merge_of,
    _speed_limits,
    _times,
)
from hcomc.viz.smoothing import adaptive_smoothing

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from hcomc._typing import FloatArray

LOW_SPEED_MARGIN = 1.0
"""The contour map outlines the low-speed region v < v_ref - LOW_SPEED_MARGIN [m/s]."""


def contour_figure(
    logs: Mapping[str, SimulationLog],
    *,
    dx: float = 10.0,
    dt_bin: float = 0.5,
    smooth: bool = True,
) -> Figure:
    """Speed contour maps of both main lanes for several controllers (paper Fig. 2).

    For each log (one column per entry, in mapping order) and each main lane (lane 2 top,
    lane 1 bottom), the binned speed field of :func:`hcomc.metrics.speed_field` over the
    whole logged run is drawn as a mesh over road position x [m] and time t [s] (by
    default reconstructed from the bins with the adaptive smoothing method of
    :mod:`hcomc.viz.smoothing`; cells without data light grey), with the low-speed region
    ``v < v_ref - 1 m/s`` outlined (v_ref from
    :func:`hcomc.metrics.reference_speed` on the merge's evaluation window, as for the
    LSRV metric), the control zone and acceleration lane as a band along the top edge
    with dashed boundaries, and VR's merge as a star on lane 1.

    Parameters
    ----------
    logs : mapping of str to SimulationLog
        Column label (e.g. "FIFO", "Game", "HCOMC") -> log of that controller's run,
        normally the same condition and seed.
    dx : float
        Space bin [m], default 10 (the LSRV binning).
    dt_bin : float
        Time bin [s], default 0.5.
    smooth : bool
        Draw the adaptive-smoothing reconstruction (default; sparse traffic leaves most
        bins empty, see :mod:`hcomc.viz.smoothing`); False draws the raw bins, exactly as
        the LSRV metric integrates them.

    Returns
    -------
    matplotlib.figure.Figure
        2 x len(logs) panels sharing x and t, one colour bar (same speed limits for every
        panel).

    Raises
    ------
    ValueError
        If *logs* is empty.
    """
    if not logs:
        raise ValueError("contour_figure needs at least one log, got none")
    labels = list(logs)
    n = len(labels)
    fields: dict[tuple[str, int], tuple[FloatArray, FloatArray, FloatArray]] = {}
    v_refs: dict[str, float] = {}
    for label, log in logs.items():
        window = log_window(log)
        v_refs[label] = reference_speed(log, window)
        times = _times(log)
        full = dataclasses.replace(window, t_start=float(times[0]), t_end=float(times[-1]))
        for lane in _MAIN_LANES:
            x_edges, t_edges, V = speed_field(log, full, lane=lane, dx=dx, dt_bin=dt_bin)
            if smooth:
                V = adaptive_smoothing(x_edges, t_edges, V)
            fields[label, lane] = (x_edges, t_edges, V)
    vmin, vmax = _speed_limits([f[2] for f in fields.values()])
    norm = Normalize(vmin, vmax)
    cmap = speed_cmap()
    # a lane nobody drove on (lane 2 of a platoon run) gets no row of empty panels
    lanes = [
        lane for lane in _MAIN_LANES
        if any(np.isfinite(fields[label, lane][2]).any() for label in labels)
    ] or list(_MAIN_LANES)  # fmt: skip
    merge = all(_is_merge(log) for log in logs.values())

    fig = new_figure(max(3.3 * n + 1.2, 7.5), 1.4 + 2.5 * len(lanes))
    axes = fig.subplots(len(lanes), n, sharex=True, sharey=True, squeeze=False)
    mesh = None
    for col, label in enumerate(labels):
        log = logs[label]
        road = road_of(log)
        level = v_refs[label] - LOW_SPEED_MARGIN
        t_merge, x_merge = _merge_of(log)
        for row, lane in enumerate(lanes):
            ax: Axes = axes[row, col]
            x_edges, t_edges, V = fields[label, lane]
            mesh = ax.pcolormesh(
                x_edges,
                t_edges,
                np.ma.masked_invalid(V),
                cmap=cmap,
                norm=norm,
                shading="flat",
                rasterized=True,
            )
            if math.isfinite(level) and np.isfinite(V).any():
                xc = 0.5 * (x_edges[:-1] + x_edges[1:])
                tc = 0.5 * (t_edges[:-1] + t_edges[1:])
                with warnings.catch_warnings():
                    # matplotlib < 3.9 warns when no cell is slow enough to have an outline
                    warnings.filterwarnings(
                        "ignore", message="No contour levels were found", category=UserWarning
                    )
                    ax.contour(
                        xc,
                        tc,
                        np.ma.masked_invalid(V),
                        levels=[level],
                        colors="black",
                        linewidths=0.9,
                    )
            if merge:
                shade_zones(ax, road, orientation="x", band=0.035, label=row == col == 0)
            if lane == Lane.MAIN_1 and math.isfinite(t_merge):
                ax.plot([x_merge], [t_merge], linestyle="none", zorder=5, **_MERGE)
            ax.set_title(f"{label} · {LANE_NAMES[lane]}")
            ax.text(
                0.98,
                0.04,
                f"$v_{{ref}}$ = {v_refs[label]:.1f} m/s",
                transform=ax.transAxes,
                ha="right",
                va="bottom",
                fontsize=8,
                bbox={
                    "boxstyle": "round,pad=0.2",
                    "facecolor": "white",
                    "alpha": 0.8,
                    "edgecolor": "none",
                },
            )
            ax.set_xlim(0.0, road.length)
            ax.set_ylim(t_edges[0], t_edges[-1])
            if row == len(lanes) - 1:
                ax.set_xlabel("position x [m]")
            if col == 0:
                ax.set_ylabel("time t [s]")
    assert mesh is not None
    what = "adaptive smoothing of" if smooth else "mean of"
    bins = f"{what} {dx:g} m × {dt_bin:g} s bins"
    fig.colorbar(mesh, ax=axes, label=f"speed v [m/s]\n({bins})", shrink=0.9, pad=0.02)
    handles, _ = axes[0, 0].get_legend_handles_labels()
    handles += [
        Line2D([], [], color="black", linewidth=0.9, label=r"$v = v_{ref} - 1$ m/s"),
        Patch(facecolor=NO_DATA_COLOR, edgecolor="0.7", label="no data" if smooth else "empty bin"),
    ]
    if any(math.isfinite(_merge_of(log)[0]) for log in logs.values()):
        handles.append(Line2D([], [], linestyle="none", label="VR merge", **_MERGE))
    fig.legend(
        handles=handles,
        loc="outside lower center",
        ncols=len(handles) if n > 1 else 3,
        fontsize=8,
        frameon=False,
    )
    titles = sorted({run_title(log) for log in logs.values()} - {""})
    suffix = f" — {'; '.join(titles)}" if titles else ""
    where = "both main lanes" if len(lanes) == 2 else LANE_NAMES[lanes[0]]
    fig.suptitle(f"Speed contour maps v(x, t) of {where}{suffix}")
    return fig
