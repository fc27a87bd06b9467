"""Static figures: one function per figure kind, each returning a matplotlib ``Figure``.

==================== ========================================= ==============================
function             shows                                     input
==================== ========================================= ==============================
contour_figure       speed field v(x, t) per controller and    ``{label: SimulationLog}``
                     main lane (paper Fig. 2)
timespace_figure     x(t) of every vehicle per lane, coloured  ``SimulationLog``
                     by speed; key vehicles and events marked
trajectories_figure  y-x paths of VR and VMC; v(t), a(t) of    ``SimulationLog``
                     the six key vehicles
pareto_figure        NSGA-II Pareto set in objective space,    ``{optimiser: plan_report}``
                     chosen plans of every optimiser
metrics_figure       the paper's five metrics, mean and 95 %   runs ``DataFrame``
                     CI per condition and configuration
==================== ========================================= ==============================

Figures are built with the object-oriented API on fresh :class:`~matplotlib.figure.Figure`
objects (see :func:`hcomc.viz.common.new_figure`); write them with
:func:`hcomc.viz.common.save_figure`.
"""

from __future__ import annotations

import dataclasses
import math
import textwrap
import warnings
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import pandas as pd
from matplotlib import patheffects
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from hcomc.metrics import KEY_ROLES, reference_speed, speed_field
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.viz.common import (
    CONFIGURATION_COLORS,
    LANE_NAMES,
    MODE_COLORS,
    NO_DATA_COLOR,
    ROLE_COLORS,
    first_plan,
    key_group,
    key_time,
    log_window,
    merge_time,
    new_figure,
    road_geometry,
    run_title,
    shade_zones,
    speed_cmap,
)
from hcomc.viz.smoothing import adaptive_smoothing

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from hcomc._typing import FloatArray
    from hcomc.config import RoadParams

__all__ = [
    "LOW_SPEED_MARGIN",
    "METRIC_TITLES",
    "contour_figure",
    "metrics_figure",
    "pareto_figure",
    "timespace_figure",
    "trajectories_figure",
]

LOW_SPEED_MARGIN = 1.0
"""The contour map outlines the low-speed region v < v_ref - LOW_SPEED_MARGIN [m/s]."""

METRIC_TITLES = {
    "critical_distance": "Critical distance",
    "average_acceleration": "Average acceleration",
    "stabilisation_time": "Stabilisation time",
    "lsrv": "Low-speed region volume",
    "fuel": "Fuel consumption",
}
"""Paper metric -> panel title of :func:`metrics_figure`."""

_MAIN_LANES = (2, 1)  # top to bottom
_ALL_LANES = (2, 1, 0)
_OUTLINE = [patheffects.Stroke(linewidth=4.2, foreground="black"), patheffects.Normal()]
_LC_START: dict[str, Any] = {
    "marker": "o",
    "markersize": 5,
    "markerfacecolor": "white",
    "markeredgecolor": "k",
}
_LC_END: dict[str, Any] = {
    "marker": "o",
    "markersize": 4,
    "markerfacecolor": "black",
    "markeredgecolor": "k",
}
_MERGE: dict[str, Any] = {
    "marker": "*",
    "markersize": 13,
    "markerfacecolor": "gold",
    "markeredgecolor": "k",
}


# --------------------------------------------------------------------------- helpers
def _times(log: SimulationLog) -> FloatArray:
    return np.asarray(log.t[: log.n_recorded], dtype=np.float64)


def _row_of(log: SimulationLog, t: float) -> int:
    """Index of the logged row nearest to time *t* (clipped to the recorded rows)."""
    times = _times(log)
    return int(np.clip(np.rint((t - times[0]) / log.dt), 0, times.size - 1))


def _speed_limits(values: Sequence[FloatArray]) -> tuple[float, float]:
    """Colour limits [m/s] covering all finite values, widened to whole m/s."""
    finite = [v[np.isfinite(v)] for v in values]
    finite = [v for v in finite if v.size]
    if not finite:
        return 0.0, 1.0
    lo = math.floor(min(float(v.min()) for v in finite))
    hi = math.ceil(max(float(v.max()) for v in finite))
    return float(lo), float(max(hi, lo + 1))


def _lane_events(
    log: SimulationLog, kind: EventKind, vehicles: Sequence[int] | None = None
) -> list[tuple[float, float, int, int]]:
    """``(t, x, vehicle, lane)`` of the events of *kind* inside the logged time span.

    The lane is the vehicle's logged lane at the event (the origin lane for a lane-change
    start, the target lane for an end, lane 1 for a merge); x falls back to the logged
    position when the event has none.
    """
    times = _times(log)
    if times.size == 0:
        return []
    out = []
    for ev in log.events_of(kind):
        t, i = float(ev["t"]), int(ev["vehicle"])
        if not times[0] - 1e-9 <= t <= times[-1] + 1e-9:
            continue
        if vehicles is not None and i not in vehicles:
            continue
        k = _row_of(log, t)
        x = float(ev["x"]) if math.isfinite(ev["x"]) else float(log.x[k, i])
        if kind is EventKind.LANE_CHANGE_START:
            lane = int(log.lane[k, i])
        elif kind is EventKind.MERGE:
            lane = 1
        else:
            lane = int(ev["value"]) if math.isfinite(ev["value"]) else int(log.lane[k, i])
        if lane >= 0 and math.isfinite(x):
            out.append((t, x, i, lane))
    return out


def _merge_of(log: SimulationLog) -> tuple[float, float]:
    """Time [s] and position [m] of the first plan's VR merge; NaN if none."""
    vr = key_group(log).get("VR", -1)
    return merge_time(log, vr) if vr >= 0 else (math.nan, math.nan)


def _is_merge(log: SimulationLog) -> bool:
    """Whether the run is a merge scenario (road zones mean something); True if unknown."""
    config = log.meta.get("config")
    return not isinstance(config, Mapping) or config.get("scenario", "merge") == "merge"


# --------------------------------------------------------------------------- contour (Fig. 2)
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
        road = road_geometry(log)
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
                    warnings.simplefilter("ignore")  # "no contour levels" when never slow
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
            if lane == 1 and math.isfinite(t_merge):
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


# --------------------------------------------------------------------------- time-space
def _lane_segments(
    log: SimulationLog, lane: int, vehicles: np.ndarray | None = None
) -> tuple[np.ndarray, FloatArray]:
    """Line segments ``(M, 2, 2)`` of (t, x) between consecutive rows a vehicle spends in
    *lane*, and their mean speeds ``(M,)`` [m/s]."""
    n = log.n_recorded
    times = _times(log)
    lanes = log.lane[:n]
    x = log.x[:n].astype(np.float64)
    v = log.v[:n].astype(np.float64)
    inlane = (lanes == lane) & log.active[:n]
    if vehicles is not None:
        keep = np.zeros(log.n_vehicles, dtype=bool)
        keep[vehicles] = True
        inlane &= keep[None, :]
    both = inlane[:-1] & inlane[1:] & np.isfinite(x[:-1]) & np.isfinite(x[1:])
    k, i = np.nonzero(both)
    start = np.column_stack([times[k], x[k, i]])
    end = np.column_stack([times[k + 1], x[k + 1, i]])
    return np.stack([start, end], axis=1), 0.5 * (v[k, i] + v[k + 1, i])


def timespace_figure(log: SimulationLog) -> Figure:
    """Time-space diagram x(t) of every vehicle, one panel per lane, coloured by speed.

    Panels (top to bottom, sharing t and x): lane 2, lane 1, ramp (with the acceleration
    lane); a lane no vehicle used (the ramp and lane 2 of a platoon run) gets no panel, and
    the control zone and acceleration lane are shaded only in merge scenarios. A vehicle's
    line breaks where it is not in the panel's lane (a lane change
    switches lane at its lateral midpoint). The six key vehicles of the first plan are
    drawn thicker with a black outline and labelled with their role at the planning time;
    lane-change starts (open circles, in the origin lane), ends (filled circles, in the
    target lane) and VR's merge (star) are marked.

    Parameters
    ----------
    log : SimulationLog
        A finished run.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per used lane and a speed colour bar [m/s].
    """
    road = road_geometry(log)
    times = _times(log)
    group = key_group(log)
    plan = first_plan(log)
    keys = np.array([i for i in group.values() if i >= 0], dtype=np.int64)
    n = log.n_recorded
    vmin, vmax = _speed_limits([log.v[:n][log.active[:n]].astype(np.float64)])
    norm, cmap = Normalize(vmin, vmax), speed_cmap()
    used = log.active[:n] & np.isin(log.lane[:n], _ALL_LANES)
    lanes = [lane for lane in _ALL_LANES if (used & (log.lane[:n] == lane)).any()] or [1]
    merge = _is_merge(log)

    fig = new_figure(9.0, 1.0 + 2.5 * len(lanes))
    axes = list(fig.subplots(len(lanes), 1, sharex=True, sharey=True, squeeze=False)[:, 0])
    collection = None
    for ax, lane in zip(axes, lanes, strict=True):
        if merge:
            shade_zones(ax, road, orientation="y", label=ax is axes[0])
        segs, speed = _lane_segments(log, lane)
        collection = LineCollection(
            cast(Any, segs),  # an (n, 2, 2) array; the stubs only name sequences
            cmap=cmap,
            norm=norm,
            linewidths=0.9,
            rasterized=True,
            zorder=2,
            label=f"{LANE_NAMES[lane]} trajectories",
        )
        collection.set_array(speed)
        ax.add_collection(collection)
        if keys.size:
            ksegs, kspeed = _lane_segments(log, lane, keys)
            if len(ksegs):
                highlight = LineCollection(
                    cast(Any, ksegs),
                    cmap=cmap,
                    norm=norm,
                    linewidths=2.4,
                    zorder=3,
                    path_effects=_OUTLINE,
                    label="key vehicles",
                )
                highlight.set_array(kspeed)
                ax.add_collection(highlight)
        ax.set_ylabel(f"{LANE_NAMES[lane]}\nposition x [m]")
        ax.grid(True, color="0.85", linewidth=0.5, zorder=1)
    # Role labels at the planning time, stacked to avoid overlaps.
    if plan is not None and keys.size:
        t0 = float(plan["t0"])
        k0 = _row_of(log, t0)
        per_lane: dict[int, list[tuple[float, str]]] = {}
        for role, i in group.items():
            if i >= 0 and log.active[k0, i]:
                per_lane.setdefault(int(log.lane[k0, i]), []).append((float(log.x[k0, i]), role))
        for lane, items in per_lane.items():
            if lane not in lanes:
                continue
            ax = axes[lanes.index(lane)]
            items.sort(reverse=True)
            for j, (x, role) in enumerate(items):
                ax.annotate(
                    role,
                    xy=(times[k0], x),
                    xytext=(-34, 14 - 13 * j + 6 * (len(items) - 1)),
                    textcoords="offset points",
                    ha="right",
                    va="center",
                    fontsize=8,
                    fontweight="bold",
                    color="white",
                    zorder=6,
                    bbox={
                        "boxstyle": "round,pad=0.2",
                        "facecolor": ROLE_COLORS[role],
                        "edgecolor": "none",
                    },
                    arrowprops={"arrowstyle": "-", "color": ROLE_COLORS[role], "lw": 0.9},
                )
    drawn: set[str] = set()
    for kind, style in (
        (EventKind.LANE_CHANGE_START, _LC_START),
        (EventKind.LANE_CHANGE_END, _LC_END),
    ):
        for t, x, _, lane in _lane_events(log, kind):
            if lane in lanes:
                axes[lanes.index(lane)].plot([t], [x], linestyle="none", zorder=5, **style)
                drawn.add(kind.name)
    t_merge, x_merge = _merge_of(log)
    if math.isfinite(t_merge) and 1 in lanes:
        axes[lanes.index(1)].plot([t_merge], [x_merge], linestyle="none", zorder=7, **_MERGE)
        drawn.add("merge")
    if plan is not None:
        for ax in axes:
            ax.axvline(float(plan["t0"]), color="0.3", linewidth=0.8, linestyle=(0, (1, 2)))
    axes[-1].set_xlabel("time t [s]")
    axes[-1].set_xlim(times[0], times[-1])
    x_seen = log.x[:n][used]
    x_lo = 0.0 if merge or not x_seen.size else max(0.0, float(x_seen.min()) - 50.0)
    axes[-1].set_ylim(x_lo, road.length)
    assert collection is not None
    fig.colorbar(collection, ax=axes, label="speed v [m/s]", shrink=0.85, pad=0.02)
    handles, _ = axes[0].get_legend_handles_labels()
    handles = [h for h in handles if not isinstance(h, LineCollection)]
    # only what the figure shows: a platoon run has no key vehicles, merges or plans
    candidates = [
        (keys.size > 0, Line2D([], [], color="0.3", linewidth=2.4, path_effects=_OUTLINE,
                               label="key vehicle")),
        ("LANE_CHANGE_START" in drawn,
         Line2D([], [], linestyle="none", label="lane change start", **_LC_START)),
        ("LANE_CHANGE_END" in drawn,
         Line2D([], [], linestyle="none", label="lane change end", **_LC_END)),
        ("merge" in drawn, Line2D([], [], linestyle="none", label="VR merge", **_MERGE)),
        (plan is not None, Line2D([], [], color="0.3", linewidth=0.8, linestyle=(0, (1, 2)),
                                  label="planning time $t_0$")),
    ]  # fmt: skip
    handles += [handle for shown, handle in candidates if shown]
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=8, frameon=False)
    title = run_title(log)
    plan_note = f" · plan: {plan['mode']}" if plan is not None else ""
    fig.suptitle(f"Time-space diagram — {title}{plan_note}" if title else "Time-space diagram")
    return fig


# --------------------------------------------------------------------------- trajectories
def _draw_road(ax: Axes, road: RoadParams) -> None:
    """Lane markings of the two-lane road with the ramp / acceleration lane (y up = lane 2)."""
    W, L = road.lane_width, road.length
    solid: dict[str, Any] = {"color": "0.35", "linewidth": 1.0, "zorder": 1}
    dashed: dict[str, Any] = {
        "color": "0.5",
        "linewidth": 0.8,
        "linestyle": (0, (6, 4)),
        "zorder": 1,
    }
    ax.plot([0, L], [1.5 * W] * 2, **solid)
    ax.plot([0, L], [0.5 * W] * 2, **dashed)
    ax.plot([0, road.accel_lane_start], [-0.5 * W] * 2, **solid)
    ax.plot([road.accel_lane_start, road.accel_lane_end], [-0.5 * W] * 2, **dashed)
    ax.plot([road.accel_lane_end, L], [-0.5 * W] * 2, **solid)
    ax.plot([road.ramp_start, road.accel_lane_end], [-1.5 * W] * 2, **solid)
    ax.plot([road.accel_lane_end] * 2, [-1.5 * W, -0.5 * W], **solid)


def trajectories_figure(log: SimulationLog) -> Figure:
    """Merge trajectories of the first merge's key vehicles.

    Panels: (1) lateral position y [m] over x [m] of VR and VMC over the whole run, on the
    drawn road (lane lines at y = +-W/2; the quintic lane changes are visible), with the
    control zone, the acceleration lane and, for a controlled run, the planned merge position
    marked; (2) speed v(t) and (3) acceleration a(t) of the six key vehicles, with the
    planning time t0 (or, without a merge controller, the time VR entered the control zone)
    and VR's merge time marked.

    Parameters
    ----------
    log : SimulationLog
        A finished run whose first ramp vehicle reached the control zone (a plan in
        ``log.meta["plans"]`` or key vehicles in ``log.meta["key_groups"]``).

    Returns
    -------
    matplotlib.figure.Figure
        3 axes; the v(t) axis holds one line per present key vehicle, labelled by role.

    Raises
    ------
    ValueError
        If no ramp vehicle reached the control zone (no key vehicles).
    """
    plan = first_plan(log)
    group = key_group(log)
    if group.get("VR", -1) < 0:
        raise ValueError(
            "the trajectories figure needs a run in which a ramp vehicle reached the control "
            "zone (no merge plan and no key vehicles in this log); allowed: a merge scenario "
            "run long enough for the ramp vehicle to arrive"
        )
    road = road_geometry(log)
    times = _times(log)
    n = log.n_recorded
    t0 = key_time(log)
    t0_label = "planning $t_0$" if plan is not None else "VR enters control zone"
    t_merge, _ = _merge_of(log)

    fig = new_figure(9.5, 9.0)
    grid = fig.add_gridspec(3, 1, height_ratios=[1.0, 1.0, 1.0])
    ax_path = fig.add_subplot(grid[0])
    ax_v = fig.add_subplot(grid[1])
    ax_a = fig.add_subplot(grid[2], sharex=ax_v)

    # (1) paths
    shade_zones(ax_path, road, orientation="x")
    _draw_road(ax_path, road)
    W = road.lane_width
    x_lo = float(road.length)
    for role in ("VR", "VMC"):
        i = group.get(role, -1)
        if i < 0:
            continue
        act = log.active[:n, i]
        x, y = log.x[:n, i][act], log.y[:n, i][act]
        if x.size:
            x_lo = min(x_lo, float(x.min()))
        ax_path.plot(x, y, color=ROLE_COLORS[role], linewidth=2.0, label=role, zorder=3)
        for kind, style in (
            (EventKind.LANE_CHANGE_START, _LC_START),
            (EventKind.LANE_CHANGE_END, _LC_END),
        ):
            for t, _, _, _ in _lane_events(log, kind, [i]):
                k = _row_of(log, t)
                ax_path.plot([log.x[k, i]], [log.y[k, i]], linestyle="none", zorder=4, **style)
    if plan is not None:
        ax_path.axvline(
            float(plan["merge_x"]),
            color=ROLE_COLORS["VR"],
            linewidth=1.0,
            linestyle=(0, (2, 2)),
            label=f"planned merge x = {plan['merge_x']:.0f} m",
        )
    if math.isfinite(t_merge):
        vr = group["VR"]
        k = _row_of(log, t_merge)
        ax_path.plot(
            [log.x[k, vr]], [log.y[k, vr]], linestyle="none", zorder=5, label="VR merge", **_MERGE
        )
    ax_path.set_xlim(max(0.0, min(x_lo, road.control_zone_start) - 20.0), road.length)
    ax_path.set_ylim(-1.5 * W - 0.6, 1.5 * W + 0.6)
    ax_path.set_yticks([-W, 0.0, W])
    for y_lane, lane in ((W, 2), (0.0, 1), (-W, 0)):
        ax_path.annotate(
            LANE_NAMES[lane],
            xy=(1.0, y_lane),
            xycoords=("axes fraction", "data"),
            xytext=(4, 0),
            textcoords="offset points",
            va="center",
            fontsize=8,
        )
    ax_path.set_xlabel("position x [m]")
    ax_path.set_ylabel("lateral position y [m]")
    ax_path.set_title("Paths of VR and VMC")
    ax_path.legend(loc="center left", bbox_to_anchor=(1.06, 0.5), fontsize=8, frameon=False)

    # (2) v(t), (3) a(t)
    t_lo, t_hi = float(times[-1]), float(times[0])
    for role in KEY_ROLES:
        i = group.get(role, -1)
        if i < 0:
            continue
        act = log.active[:n, i]
        if not act.any():
            continue
        t_role = np.where(act, times, np.nan)
        t_lo, t_hi = min(t_lo, float(np.nanmin(t_role))), max(t_hi, float(np.nanmax(t_role)))
        line: dict[str, Any] = {
            "color": ROLE_COLORS[role],
            "linewidth": 2.2 if role in ("VR", "VMC") else 1.3,
        }
        ax_v.plot(t_role, np.where(act, log.v[:n, i], np.nan), label=role, **line)
        ax_a.plot(t_role, np.where(act, log.a[:n, i], np.nan), label=role, **line)
    lc = _lane_events(log, EventKind.LANE_CHANGE_START, [group["VR"]])
    lc_end = _lane_events(log, EventKind.LANE_CHANGE_END, [group["VR"]])
    for ax in (ax_v, ax_a):
        if lc and lc_end:
            ax.axvspan(
                lc[0][0],
                lc_end[0][0],
                color=ROLE_COLORS["VR"],
                alpha=0.08,
                linewidth=0,
                label="VR lane change",
            )
        ax.axvline(t0, color="0.2", linewidth=1.0, linestyle=(0, (4, 2)), label=t0_label)
        if math.isfinite(t_merge):
            ax.axvline(
                t_merge,
                color=ROLE_COLORS["VR"],
                linewidth=1.0,
                linestyle=(0, (1, 1.5)),
                label="VR merge",
            )
        ax.grid(True, color="0.88", linewidth=0.5)
    ax_a.axhline(0.0, color="0.5", linewidth=0.6)
    if t_hi > t_lo:
        ax_v.set_xlim(t_lo, t_hi)
    ax_v.set_ylabel("speed v [m/s]")
    ax_v.set_title("Key vehicles: speed and acceleration")
    ax_a.set_ylabel("acceleration a [m/s²]")
    ax_a.set_xlabel("time t [s]")
    ax_v.tick_params(labelbottom=False)
    ax_v.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, frameon=False)
    title = run_title(log)
    if plan is None:
        coop = "no merge controller (gap acceptance)"
    else:
        mode = str(plan.get("mode", "none"))
        coop = "no cooperation by VMC" if mode == "none" else f"{mode} cooperation"
    fig.suptitle(
        f"Merge trajectories — {title} · {coop}" if title else f"Merge trajectories · {coop}"
    )
    return fig


# --------------------------------------------------------------------------- Pareto
_PROJECTIONS = (("safety", "fuel"), ("safety", "efficiency"), ("fuel", "efficiency"))
_OBJECTIVE_LABELS = {
    "safety": "$U_{safe}$ [m/s²]",
    "fuel": "$U_{fuel}$ [L]",
    "efficiency": "$-U_{eff}$ [m/s²]",
}
_OPTIMIZER_NAMES = {"nsga2": "NSGA-II", "pso": "PSO", "sa": "SA"}
_OPTIMIZER_MARKERS = {"pso": ("D", "#17becf"), "sa": ("^", "#e377c2")}
_OTHER_MARKERS = (("s", "#8c564b"), ("P", "#7f7f7f"), ("X", "#bcbd22"), ("v", "#9467bd"))


def _pick_front(reports: Mapping[str, Mapping[str, Any]]) -> str:
    """Key of the report whose Pareto set is drawn: NSGA-II if present, else the largest."""
    for key, rep in reports.items():
        if str(key).lower() == "nsga2" or str(rep.get("optimizer", "")).lower() == "nsga2":
            return key
    return max(reports, key=lambda k: len(reports[k].get("pareto") or []))


def pareto_figure(
    reports: Mapping[str, Mapping[str, Any]], *, safety_threshold: float | None = None
) -> Figure:
    """Pairwise projections of the Pareto set of one merge decision.

    Three panels: U_safe-U_fuel, U_safe-(-U_eff) and U_fuel-(-U_eff) (all minimised). The
    feasible Pareto set of the NSGA-II report is scattered, coloured by VMC's cooperation
    mode; its Eq. 19 choice is a gold star; the chosen solutions of the other optimisers
    (PSO, SA ...) are distinct markers; the Eq. 19 safety gate is a dashed line.

    Parameters
    ----------
    reports : mapping of str to dict
        Optimiser name (``"nsga2"``, ``"pso"``, ``"sa"`` ...) -> plan report of
        :func:`hcomc.control.report.plan_report` for the same decision (same scenario and
        seed).
    safety_threshold : float or None
        U_safe gate of Eq. 19 [m/s^2]; default: the ``control.safety_threshold`` the
        decision ran with, recorded in its report.

    Returns
    -------
    matplotlib.figure.Figure
        3 axes.

    Raises
    ------
    ValueError
        If *reports* is empty, or no threshold is given and a report does not record one.
    """
    if not reports:
        raise ValueError("pareto_figure needs at least one plan report, got none")
    front_key = _pick_front(reports)
    front = reports[front_key]
    if safety_threshold is None:
        if "safety_threshold" not in front:
            raise ValueError(
                f"plan report '{front_key}' does not record its safety_threshold "
                "(written by an older hcomc): pass safety_threshold=..."
            )
        safety_threshold = float(front["safety_threshold"])
    pareto = list(front.get("pareto") or [])
    fig = new_figure(13.0, 4.6)
    axes = fig.subplots(1, 3)
    front_name = _OPTIMIZER_NAMES.get(str(front.get("optimizer", front_key)).lower(), front_key)
    for ax, (fx, fy) in zip(axes, _PROJECTIONS, strict=True):
        for mode in MODE_COLORS:
            pts = [p for p in pareto if p.get("mode") == mode]
            if pts:
                ax.scatter(
                    [p[fx] for p in pts],
                    [p[fy] for p in pts],
                    s=22,
                    color=MODE_COLORS[mode],
                    alpha=0.75,
                    edgecolors="white",
                    linewidths=0.4,
                    zorder=2,
                    label=f"{front_name} Pareto set, {mode}",
                )
        chosen = front.get("chosen")
        if chosen:
            ax.plot(
                [chosen[fx]],
                [chosen[fy]],
                linestyle="none",
                marker="*",
                markersize=17,
                markerfacecolor="gold",
                markeredgecolor="black",
                zorder=5,
                label=f"{front_name} chosen (Eq. 19)",
            )
        others = [k for k in reports if k != front_key]
        for j, key in enumerate(others):
            rep = reports[key]
            opt = str(rep.get("optimizer", key)).lower()
            marker, color = _OPTIMIZER_MARKERS.get(opt, _OTHER_MARKERS[j % len(_OTHER_MARKERS)])
            ch = rep.get("chosen")
            if ch:
                ax.plot(
                    [ch[fx]],
                    [ch[fy]],
                    linestyle="none",
                    marker=marker,
                    markersize=9,
                    markerfacecolor=color,
                    markeredgecolor="black",
                    zorder=4,
                    label=f"{_OPTIMIZER_NAMES.get(opt, key)} chosen",
                )
        if fx == "safety":
            lo, hi = ax.get_xlim()
            pad = 0.05 * (hi - lo)
            lo, hi = min(lo, safety_threshold - pad), max(hi, safety_threshold + pad)
            ax.axvspan(
                safety_threshold,
                hi,
                color="#b2182b",
                alpha=0.06,
                linewidth=0,
                label="penalised by Eq. 19 ($U_{safe}$ above the gate)",
            )
            ax.set_xlim(lo, hi)
            ax.axvline(
                safety_threshold,
                color="#b2182b",
                linewidth=1.1,
                linestyle=(0, (5, 3)),
                label=f"safety gate $U_{{safe}}$ = {safety_threshold:g} m/s²",
            )
        ax.set_xlabel(_OBJECTIVE_LABELS[fx])
        ax.set_ylabel(_OBJECTIVE_LABELS[fy])
        ax.set_title(f"{_OBJECTIVE_LABELS[fx].split()[0]} vs {_OBJECTIVE_LABELS[fy].split()[0]}")
        ax.grid(True, color="0.88", linewidth=0.5)
        ax.xaxis.set_major_locator(MaxNLocator(5))
    handles, labels = axes[0].get_legend_handles_labels()
    h2, l2 = axes[2].get_legend_handles_labels()
    for h, lab in zip(h2, l2, strict=True):
        if lab not in labels:
            handles.append(h)
            labels.append(lab)
    fig.legend(
        handles,
        labels,
        loc="outside lower center",
        ncols=min(len(labels), 4),
        fontsize=8,
        frameon=False,
    )
    scenario, seed, t = front.get("scenario"), front.get("seed"), front.get("t")
    facts = [str(scenario)] if scenario else []
    if seed is not None:
        facts.append(f"seed {seed}")
    if t is not None:
        facts.append(f"t = {float(t):.1f} s")
    facts.append(f"{len(pareto)} feasible Pareto solutions")
    fig.suptitle("Pareto set of the merge decision — " + " · ".join(facts))
    return fig


# --------------------------------------------------------------------------- metrics
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
