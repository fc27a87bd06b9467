"""The road of the top-down scene (:mod:`hcomc.viz.scene.frame`): its geometry and its static
drawing (lanes, ramp, acceleration lane, control zone, markings and their labels)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from matplotlib.patches import Rectangle

from hcomc.metrics import road_of
from hcomc.sim.log import SimulationLog

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["ROAD_COLOURS", "Y_MARGIN", "SceneRoad", "draw_road"]

Y_MARGIN = 0.85  # [lane widths] beyond the outer road edges

ROAD_COLOURS = {
    "asphalt": "#d9d9d9",
    "ramp": "#cfcfcf",
    "zone": "#fff3b0",
    "marking": "white",
    "edge": "#4d4d4d",
}


@dataclass(frozen=True)
class SceneRoad:
    """Road geometry needed for drawing [m]."""

    length: float
    lane_width: float
    accel_lane_start: float
    accel_lane_end: float
    ramp_start: float
    control_zone_start: float
    vehicle_length: float
    vehicle_width: float

    @classmethod
    def of(cls, log: SimulationLog) -> SceneRoad:
        """Geometry of the run (:func:`hcomc.metrics.road_of`; raises without one)."""
        road = road_of(log)
        return cls(
            length=road.length,
            lane_width=road.lane_width,
            accel_lane_start=road.accel_lane_start,
            accel_lane_end=road.accel_lane_end,
            ramp_start=road.ramp_start,
            control_zone_start=road.control_zone_start,
            vehicle_length=road.vehicle_length,
            vehicle_width=road.vehicle_width,
        )


def draw_road(ax: Axes, road: SceneRoad, window: tuple[float, float], lateral_scale: float) -> None:
    """Draw the road on ``ax``, showing x in ``window`` [m], with a note of how much the
    y axis is stretched relative to x on screen (``lateral_scale``)."""
    r, W = road, road.lane_width
    x_min, x_max = window
    half = 0.5 * W
    ax.set_facecolor("#eef3e8")  # verge
    ax.add_patch(
        Rectangle((0.0, -half), r.length, 2 * W, fc=ROAD_COLOURS["asphalt"], ec="none", zorder=0)
    )
    ax.add_patch(
        Rectangle(
            (r.ramp_start, -1.5 * W),
            r.accel_lane_end - r.ramp_start,
            W,
            fc=ROAD_COLOURS["ramp"],
            ec="none",
            zorder=0,
        )
    )
    zone = Rectangle(
        (r.control_zone_start, -1.5 * W),
        r.accel_lane_start - r.control_zone_start,
        3 * W,
        fc=ROAD_COLOURS["zone"],
        ec="none",
        alpha=0.55,
        zorder=1,
    )
    ax.add_patch(zone)
    solid: dict[str, Any] = {
        "color": ROAD_COLOURS["marking"],
        "lw": 1.6,
        "zorder": 2,
        "solid_capstyle": "butt",
    }
    dashed: dict[str, Any] = {**solid, "lw": 1.2, "dashes": (6, 6)}
    ax.plot([0.0, r.length], [1.5 * W, 1.5 * W], **solid)  # outer edge of lane 2
    ax.plot([0.0, r.length], [half, half], **dashed)  # lane 2 | lane 1
    ax.plot([0.0, r.ramp_start], [-half, -half], **solid)  # lane 1 edge upstream
    ax.plot([r.ramp_start, r.accel_lane_start], [-half, -half], **{**solid, "lw": 2.4})
    ax.plot([r.accel_lane_start, r.accel_lane_end], [-half, -half], **dashed)
    ax.plot([r.accel_lane_end, r.length], [-half, -half], **solid)
    ax.plot([r.ramp_start, r.accel_lane_end], [-1.5 * W, -1.5 * W], **solid)
    ax.plot([r.accel_lane_end, r.accel_lane_end], [-1.5 * W, -half], **solid)
    y_text = -1.5 * W - 0.15 * W
    text: dict[str, Any] = {
        "fontsize": 7,
        "va": "top",
        "color": "#555555",
        "zorder": 3,
        "clip_on": True,
    }
    cz_mid = 0.5 * (max(r.control_zone_start, x_min) + min(r.accel_lane_start, x_max))
    ax.text(cz_mid, 1.5 * W + 0.55 * W, "control zone", ha="center", **{**text, "va": "bottom"})
    ramp_mid = 0.5 * (max(r.ramp_start, x_min) + min(r.accel_lane_start, x_max))
    ax.text(ramp_mid, y_text, "ramp", ha="center", **text)
    acc_mid = 0.5 * (max(r.accel_lane_start, x_min) + min(r.accel_lane_end, x_max))
    ax.text(acc_mid, y_text, "acceleration lane", ha="center", **text)
    ax.set_xlim(x_min, x_max)
    ax.set_ylim(-(1.5 + Y_MARGIN) * W, (1.5 + Y_MARGIN) * W)
    ax.set_yticks([-W, 0.0, W], ["ramp", "lane 1", "lane 2"], fontsize=7)
    ax.tick_params(axis="x", labelsize=7)
    ax.set_xlabel("x [m]", fontsize=8, labelpad=1)
    for spine in ax.spines.values():
        spine.set_visible(False)
    ax.text(
        1.0,
        -0.22,
        f"lateral scale × {lateral_scale:.0f}",
        transform=ax.transAxes,
        ha="right",
        va="top",
        fontsize=7,
        color="#555555",
    )
