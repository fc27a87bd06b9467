"""Time-space diagram: x(t) of every vehicle per lane, coloured by speed."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D

from hcomc.metrics import road_of
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.viz.common import (
    LANE_NAMES,
    ROLE_COLORS,
    first_plan,
    key_group,
    new_figure,
    run_title,
    shade_zones,
    speed_cmap,
)
from hcomc.viz.figures._shared import (
    _ALL_LANES,
    _LC_END,
    _LC_START,
    _MERGE,
    _OUTLINE,
    _is_merge,
    _lane_events,
    _merge_of,
    _row_of,
    _speed_limits,
    _times,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from hcomc._typing import FloatArray


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
    road = road_of(log)
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
