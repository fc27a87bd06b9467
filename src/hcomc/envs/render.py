"""Frames of an environment's run: what ``render_mode="rgb_array"`` returns.

A top-down view of the road around one vehicle (the agent's, or VR), to scale: lanes, ramp,
acceleration lane and control zone (paper Section II-A), every vehicle on the road as the
rectangle of its size and heading (front-bumper reference, as the collision test draws it,
:func:`hcomc.equations.collision.rectangle_corners`), HDVs orange, CAVs green, the centred
vehicle blue. numpy only: no display and no plotting library. To watch a whole episode
instead, replay its log in the browser (``hcomc.viz.replay(env.episode_logs()[0])``).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.equations.collision import rectangle_corners
from hcomc.road import Kind
from hcomc.sim.engine import Simulation

__all__ = ["FRAME_SIZE", "RENDER_MODES", "SCALE", "check_render_mode", "render_frame"]

FRAME_SIZE = (160, 640)
"""(height, width) of a frame [px]."""
SCALE = 4.0
"""Pixels per metre (both axes: the frame is to scale; 160 m of road across)."""
BEHIND = 0.4
"""Share of the frame's width behind the centred vehicle."""

RENDER_MODES = ("rgb_array",)
"""The environments' render modes (``"human"`` is not one: the browser replay of an
episode's log is the way to watch it)."""

_RGB = {
    "verge": (238, 243, 232), "asphalt": (217, 217, 217), "ramp": (200, 200, 200),
    "zone": (255, 236, 150), "marking": (255, 255, 255), "hdv": (217, 95, 2),
    "cav": (27, 158, 119), "focus": (31, 95, 214),
}  # fmt: skip
_DASH, _GAP = 3.0, 6.0  # lane divider dash and gap [m]


class _Canvas:
    """An RGB frame with world coordinates: x across from ``left`` [m], y up from the middle."""

    def __init__(self, height: int, width: int, left: float, scale: float) -> None:
        self.img = np.empty((height, width, 3), dtype=np.uint8)
        self.img[:] = _RGB["verge"]
        self.left, self.scale = left, scale
        self.h, self.w = height, width
        self.col_x = left + (np.arange(width) + 0.5) / scale  # world x of each pixel column

    def px(self, x: float) -> float:
        return (x - self.left) * self.scale

    def py(self, y: float) -> float:
        return 0.5 * self.h - y * self.scale

    def rect(self, x0: float, x1: float, y0: float, y1: float, rgb: tuple[int, ...],
             alpha: float = 1.0) -> None:  # fmt: skip
        """Fill the world rectangle [x0, x1] x [y0, y1] (blended with ``alpha`` < 1)."""
        c0, c1 = (int(np.clip(round(self.px(v)), 0, self.w)) for v in (x0, x1))
        r0, r1 = (int(np.clip(round(self.py(v)), 0, self.h)) for v in (y1, y0))
        area = self.img[r0:r1, c0:c1]
        area[:] = ((1.0 - alpha) * area + alpha * np.asarray(rgb)).astype(np.uint8)

    def line(self, x0: float, x1: float, y: float, dashed: bool) -> None:
        row = math.floor(self.py(y))
        if not 0 <= row < self.h:
            return
        cols = (self.col_x >= x0) & (self.col_x <= x1)
        if dashed:
            cols &= np.mod(self.col_x, _DASH + _GAP) < _DASH
        self.img[row, cols] = _RGB["marking"]

    def polygon(self, corners: np.ndarray, rgb: tuple[int, ...]) -> None:
        """Fill a convex polygon given by its world corners (K, 2)."""
        cx = (corners[:, 0] - self.left) * self.scale
        cy = 0.5 * self.h - corners[:, 1] * self.scale
        c0, c1 = max(int(cx.min()), 0), min(math.ceil(cx.max()), self.w)
        r0, r1 = max(int(cy.min()), 0), min(math.ceil(cy.max()), self.h)
        if c0 >= c1 or r0 >= r1:
            return
        gx, gy = np.meshgrid(np.arange(c0, c1) + 0.5, np.arange(r0, r1) + 0.5)
        side = []
        for k in range(len(cx)):
            ax, ay = cx[k], cy[k]
            bx, by = cx[(k + 1) % len(cx)], cy[(k + 1) % len(cy)]
            side.append((bx - ax) * (gy - ay) - (by - ay) * (gx - ax))
        sides = np.stack(side)
        inside = (sides >= 0).all(axis=0) | (sides <= 0).all(axis=0)
        self.img[r0:r1, c0:c1][inside] = rgb


def render_frame(
    sim: Simulation,
    config: ScenarioConfig,
    focus: int,
    size: tuple[int, int] = FRAME_SIZE,
    scale: float = SCALE,
) -> np.ndarray:
    """The (height, width, 3) uint8 frame of ``sim`` now, centred on vehicle ``focus`` (on the
    control zone's start while it is not on the road)."""
    road = config.road
    w = road.lane_width
    height, width = size
    on_road = 0 <= focus < sim.x.size and bool(sim.active[focus])
    centre = float(sim.x[focus]) if on_road else road.control_zone_start
    canvas = _Canvas(height, width, centre - BEHIND * width / scale, scale)
    canvas.rect(0.0, road.length, -0.5 * w, 1.5 * w, _RGB["asphalt"])
    canvas.rect(road.ramp_start, road.accel_lane_end, -1.5 * w, -0.5 * w, _RGB["ramp"])
    canvas.rect(road.control_zone_start, road.accel_lane_start, -1.5 * w, 1.5 * w, _RGB["zone"],
                alpha=0.4)  # fmt: skip
    canvas.line(0.0, road.length, 1.5 * w, dashed=False)
    canvas.line(0.0, road.length, 0.5 * w, dashed=True)
    canvas.line(0.0, road.accel_lane_start, -0.5 * w, dashed=False)
    canvas.line(road.accel_lane_start, road.accel_lane_end, -0.5 * w, dashed=True)
    canvas.line(road.accel_lane_end, road.length, -0.5 * w, dashed=False)
    canvas.line(road.ramp_start, road.accel_lane_end, -1.5 * w, dashed=False)
    right = canvas.left + width / scale
    fleet = sim.fleet
    ids = np.flatnonzero(sim.active & (sim.x >= canvas.left) & (sim.x - fleet.length <= right))
    corners = rectangle_corners(sim.x[ids], sim.y[ids], sim.heading[ids], fleet.length[ids],
                                fleet.width[ids])  # fmt: skip
    for k, i in enumerate(ids.tolist()):
        rgb = _RGB["focus"] if i == focus else _RGB["cav" if fleet.kind[i] == Kind.CAV else "hdv"]
        canvas.polygon(corners[k], rgb)
    return canvas.img


def check_render_mode(mode: str | None) -> str | None:
    """``mode`` if it is None or one of :data:`RENDER_MODES`; else a one-line ValueError."""
    if mode is not None and mode not in RENDER_MODES:
        allowed = ", ".join(repr(m) for m in RENDER_MODES)
        raise ValueError(f"key 'render_mode' = {mode!r}: allowed: {allowed} or None")
    return mode
