"""Paths y(x) of VR and VMC and v(t), a(t) of the six key vehicles."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from hcomc.metrics import KEY_ROLES, road_of
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.viz.common import (
    LANE_NAMES,
    ROLE_COLORS,
    first_plan,
    key_group,
    key_time,
    new_figure,
    run_title,
    shade_zones,
)
from hcomc.viz.figures._shared import (
    _LC_END,
    _LC_START,
    _MERGE,
    _lane_events,
    _merge_of,
    _row_of,
    _times,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from hcomc.config import RoadParams


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
    road = road_of(log)
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
    agent = log.meta.get("agent")
    if plan is None and agent:
        coop = f"{agent['role']} driven by a learning agent"
    elif plan is None:
        coop = "no merge controller (gap acceptance)"
    else:
        mode = str(plan.get("mode", "none"))
        coop = "no cooperation by VMC" if mode == "none" else f"{mode} cooperation"
    fig.suptitle(
        f"Merge trajectories — {title} · {coop}" if title else f"Merge trajectories · {coop}"
    )
    return fig
