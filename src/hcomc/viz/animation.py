"""Top-down animation of a simulation run.

:func:`animate` turns a :class:`~hcomc.sim.log.SimulationLog` into a GIF (matplotlib's
:class:`~matplotlib.animation.PillowWriter`) or an MP4 (:class:`~matplotlib.animation.FFMpegWriter`,
when ``ffmpeg`` is installed). The road (lanes, ramp, acceleration lane, control zone) is drawn
once; per frame only a few artists change: one :class:`~matplotlib.collections.PolyCollection`
for the vehicles, one for the virtual vehicles, the key-vehicle labels and the clock. The
output file is written atomically.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from matplotlib import animation as mpl_animation
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle

from hcomc.config import RoadParams
from hcomc.road import KEY_ROLES
from hcomc.safety.collision import rectangle_corners
from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import atomic_paths

__all__ = ["ALLOWED_SUFFIXES", "animate"]

#: Output formats :func:`animate` writes, by file extension.
ALLOWED_SUFFIXES = (".gif", ".mp4")

_FIG_SIZE = (12.0, 2.8)  # [in]; with _DPI an even pixel size, as H.264 needs
_DPI = 100
_AX_RECT = (0.035, 0.2, 0.955, 0.6)  # left, bottom, width, height (figure fraction)
_Y_MARGIN = 0.85  # [lane widths] beyond the outer road edges

# Coefficients (c0, c1, c2, c3) of a virtual vehicle's cubic x(τ) (Section III-A, Eqs. 8-9).
Cubic = tuple[float, float, float, float]

_COLOURS = {
    "hdv": "#d95f02",
    "cav": "#1b9e77",
    "ghost": "#7570b3",
    "asphalt": "#d9d9d9",
    "ramp": "#cfcfcf",
    "zone": "#fff3b0",
    "marking": "white",
    "edge": "#4d4d4d",
}


@dataclass(frozen=True)
class _Road:
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
    def from_meta(cls, meta: Mapping[str, Any]) -> _Road:
        """Geometry from ``meta["config"]["road"]``, defaults for missing keys."""
        raw = dict((meta.get("config") or {}).get("road") or {})
        fields = set(RoadParams.model_fields)
        road = RoadParams(**{k: v for k, v in raw.items() if k in fields})
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


@dataclass(frozen=True)
class _Ghost:
    """One virtual vehicle of a plan: cubic x(τ) in a fixed lane while the plan is in force
    (from its t0 until its horizon ends or a replan of the same VR replaces it)."""

    label: str
    coefficients: Cubic
    t0: float
    horizon: float
    until: float
    y: float
    length: float
    width: float

    def x_at(self, t: float) -> float | None:
        """Position [m] at time *t* [s], or None outside ``[t0, min(t0 + horizon, until))``."""
        tau = t - self.t0
        if not (0.0 <= tau <= self.horizon and t < self.until):
            return None
        b1, b2, b3, b4 = self.coefficients
        return b1 + tau * (b2 + tau * (b3 + tau * b4))


class _QuantizingPillowWriter(mpl_animation.PillowWriter):
    """:class:`~matplotlib.animation.PillowWriter` that keeps frames in palette mode.

    A GIF stores palette images anyway; quantising each frame as it is grabbed (fast octree,
    about 3 ms a frame instead of Pillow's 16 ms median cut at save time) keeps a third of the
    memory and halves the render time.
    """

    def grab_frame(self, **savefig_kwargs: Any) -> None:
        super().grab_frame(**savefig_kwargs)
        frames = getattr(self, "_frames", None)
        if frames and frames[-1].mode == "RGB":
            from PIL import Image

            frames[-1] = frames[-1].quantize(256, method=Image.Quantize.FASTOCTREE)


def _check_suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in ALLOWED_SUFFIXES:
        raise ValueError(
            f"cannot write an animation to {path.name!r}: extension {path.suffix or '(none)'!r} "
            f"is not supported; use one of {', '.join(ALLOWED_SUFFIXES)}"
        )
    if suffix == ".mp4" and not mpl_animation.writers.is_available("ffmpeg"):
        raise ValueError(
            f"cannot write {path.name!r}: mp4 needs ffmpeg, which is not installed; use .gif"
        )
    return suffix


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be finite and > 0, got {value}")
    return value


def _frame_rows(t: np.ndarray, step: float, t_range: tuple[float, float] | None) -> np.ndarray:
    """Log rows nearest to ``t_start, t_start + step, ...`` within the time range."""
    t_first, t_last = float(t[0]), float(t[-1])
    if t_range is None:
        start, stop = t_first, t_last
    else:
        start, stop = (float(v) for v in t_range)
        if not (math.isfinite(start) and math.isfinite(stop) and start < stop):
            raise ValueError(f"t_range must be (start, stop) with start < stop [s], got {t_range}")
        if stop < t_first or start > t_last:
            raise ValueError(
                f"t_range {t_range} [s] does not overlap the log's time span "
                f"[{t_first:g}, {t_last:g}] s"
            )
        start, stop = max(start, t_first), min(stop, t_last)
    targets = start + step * np.arange(math.floor((stop - start) / step + 1e-9) + 1)
    right = np.clip(np.searchsorted(t, targets), 1, t.size - 1) if t.size > 1 else None
    if right is None:
        return np.zeros(targets.size, dtype=np.intp)
    left = right - 1
    nearer_left = np.abs(t[left] - targets) <= np.abs(t[right] - targets)
    return np.where(nearer_left, left, right)


def _ghosts(
    meta: Mapping[str, Any], lengths: np.ndarray, widths: np.ndarray, road: _Road
) -> list[_Ghost]:
    """Virtual vehicles of every plan in ``meta["plans"]``, each until the next plan of its VR."""
    ghosts: list[_Ghost] = []
    plans = list(meta.get("plans") or [])
    for i, plan in enumerate(plans):
        group = plan.get("group") or {}
        later = [
            float(p["t0"])
            for p in plans[i + 1 :]
            if (p.get("group") or {}).get("VR") == group.get("VR") and p.get("t0") is not None
        ]
        until = min(later, default=math.inf)
        for label, key, lane_y, owner in (
            ("VV0", "vv0", -road.lane_width, "VMF"),
            ("VV1", "vv1", 0.0, "VR"),
            ("VV2", "vv2", road.lane_width, "VMC"),
        ):
            coefficients = plan.get(key)
            if coefficients is None or plan.get("horizon") is None or plan.get("t0") is None:
                continue
            owner_k = group.get(owner)
            k = -1 if owner_k is None else int(owner_k)
            valid = 0 <= k < lengths.size
            ghosts.append(
                _Ghost(
                    label=label,
                    coefficients=cast(Cubic, tuple(float(c) for c in coefficients)),
                    t0=float(plan["t0"]),
                    horizon=float(plan["horizon"]),
                    until=until,
                    y=lane_y,
                    length=float(lengths[k]) if valid else road.vehicle_length,
                    width=float(widths[k]) if valid else road.vehicle_width,
                )
            )
    return ghosts


class _RoadAnimator:
    """Figure with the static road and the per-frame artists of one log."""

    def __init__(self, log: SimulationLog, window: tuple[float, float]) -> None:
        self.log = log
        self.road = _Road.from_meta(log.meta)
        self.x_min, self.x_max = window
        self.fig = Figure(figsize=_FIG_SIZE, dpi=_DPI)
        self.ax = self.fig.add_axes(_AX_RECT)
        self._draw_road()
        self.lengths = log.length.astype(np.float64)
        self.widths = log.width.astype(np.float64)
        colours = np.array(
            [
                _hex_rgba(_COLOURS["hdv"]),
                _hex_rgba(_COLOURS["cav"]),
            ]
        )
        self.face = colours[np.clip(log.kind.astype(np.intp), 0, 1)]
        plans = log.meta.get("plans") or []
        self.plan = plans[0] if plans else None
        group = (self.plan or {}).get("group") or {}
        self.key = {
            role: int(group[role])
            for role in KEY_ROLES
            if group.get(role) is not None and 0 <= int(group[role]) < log.n_vehicles
        }
        self.is_key = np.zeros(log.n_vehicles, dtype=bool)
        self.is_key[list(self.key.values())] = True
        self.ghosts = _ghosts(log.meta, self.lengths, self.widths, self.road)

        self.vehicles = PolyCollection([], closed=True, zorder=5)
        self.ax.add_collection(self.vehicles)
        self.ghost_patches = PolyCollection(
            [],
            closed=True,
            facecolors=(*_hex_rgba(_COLOURS["ghost"])[:3], 0.18),
            edgecolors=_COLOURS["ghost"],
            linestyles="--",
            linewidths=1.2,
            zorder=6,
        )
        self.ax.add_collection(self.ghost_patches)
        label_style: dict[str, Any] = {
            "fontsize": 7,
            "ha": "center",
            "va": "bottom",
            "zorder": 8,
            "textcoords": "offset points",
            "xytext": (0, 5),
            "annotation_clip": False,
        }
        self.labels = {
            role: self.ax.annotate(
                role,
                (0.0, 0.0),
                fontweight="bold",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.75},
                visible=False,
                **label_style,
            )
            for role in self.key
        }
        self.ghost_labels = [
            self.ax.annotate(
                g.label, (0.0, 0.0), color=_COLOURS["ghost"], visible=False, **label_style
            )
            for g in self.ghosts
        ]
        self.clock = self.fig.text(0.035, 0.9, "", fontsize=11, fontweight="bold", va="center")
        self.status = self.fig.text(0.16, 0.9, "", fontsize=8, va="center", color="#333333")
        self._legend()
        self._freeze_background()

    # ------------------------------------------------------------------ static parts
    def _draw_road(self) -> None:
        r, ax, W = self.road, self.ax, self.road.lane_width
        half = 0.5 * W
        ax.set_facecolor("#eef3e8")  # verge
        ax.add_patch(
            Rectangle((0.0, -half), r.length, 2 * W, fc=_COLOURS["asphalt"], ec="none", zorder=0)
        )
        ax.add_patch(
            Rectangle(
                (r.ramp_start, -1.5 * W),
                r.accel_lane_end - r.ramp_start,
                W,
                fc=_COLOURS["ramp"],
                ec="none",
                zorder=0,
            )
        )
        zone = Rectangle(
            (r.control_zone_start, -1.5 * W),
            r.accel_lane_start - r.control_zone_start,
            3 * W,
            fc=_COLOURS["zone"],
            ec="none",
            alpha=0.55,
            zorder=1,
        )
        ax.add_patch(zone)
        solid: dict[str, Any] = {
            "color": _COLOURS["marking"],
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
        cz_mid = 0.5 * (max(r.control_zone_start, self.x_min) + min(r.accel_lane_start, self.x_max))
        ax.text(cz_mid, 1.5 * W + 0.55 * W, "control zone", ha="center", **{**text, "va": "bottom"})
        ramp_mid = 0.5 * (max(r.ramp_start, self.x_min) + min(r.accel_lane_start, self.x_max))
        ax.text(ramp_mid, y_text, "ramp", ha="center", **text)
        acc_mid = 0.5 * (max(r.accel_lane_start, self.x_min) + min(r.accel_lane_end, self.x_max))
        ax.text(acc_mid, y_text, "acceleration lane", ha="center", **text)
        ax.set_xlim(self.x_min, self.x_max)
        ax.set_ylim(-(1.5 + _Y_MARGIN) * W, (1.5 + _Y_MARGIN) * W)
        ax.set_yticks([-W, 0.0, W], ["ramp", "lane 1", "lane 2"], fontsize=7)
        ax.tick_params(axis="x", labelsize=7)
        ax.set_xlabel("x [m]", fontsize=8, labelpad=1)
        for spine in ax.spines.values():
            spine.set_visible(False)
        ax.text(
            1.0,
            -0.22,
            f"lateral scale × {self.y_exaggeration():.0f}",
            transform=ax.transAxes,
            ha="right",
            va="top",
            fontsize=7,
            color="#555555",
        )

    def y_exaggeration(self) -> float:
        """How much the y axis is stretched relative to x on screen [-]."""
        width_in = _FIG_SIZE[0] * _AX_RECT[2]
        height_in = _FIG_SIZE[1] * _AX_RECT[3]
        y_span = 2 * (1.5 + _Y_MARGIN) * self.road.lane_width
        return ((self.x_max - self.x_min) / width_in) / (y_span / height_in)

    def _legend(self) -> None:
        handles = [
            Patch(fc=_COLOURS["hdv"], ec="#333333", lw=0.5, label="HDV"),
            Patch(fc=_COLOURS["cav"], ec="#333333", lw=0.5, label="CAV"),
            Patch(
                fc=(*_hex_rgba(_COLOURS["ghost"])[:3], 0.18),
                ec=_COLOURS["ghost"],
                ls="--",
                label="virtual vehicle (VV1, VV2)",
            ),
            Patch(fc=_COLOURS["zone"], ec="none", label="control zone"),
            Line2D([], [], color="black", marker="v", ls="none", ms=5, label="planned merge x"),
        ]
        self.fig.legend(
            handles=handles,
            loc="center right",
            bbox_to_anchor=(0.99, 0.9),
            ncol=len(handles),
            fontsize=7,
            frameon=False,
            handlelength=1.6,
            columnspacing=1.2,
        )
        self.merge_marker = self.ax.plot(
            [], [], marker="v", color="black", ms=5, ls="none", zorder=7, clip_on=True
        )[0]

    def _freeze_background(self) -> None:
        """Render the static artists once and show them as one image from then on.

        Ticks, legend and road markings cost most of a frame's drawing time; as a pixel-exact
        figure image (frames are grabbed at the figure's dpi) they cost almost nothing.
        """
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        animated = [
            self.vehicles,
            self.ghost_patches,
            self.merge_marker,
            self.clock,
            self.status,
            *self.labels.values(),
            *self.ghost_labels,
        ]
        shown = [artist.get_visible() for artist in animated]
        for artist in animated:
            artist.set_visible(False)
        canvas = FigureCanvasAgg(self.fig)
        canvas.draw()
        background = np.asarray(canvas.buffer_rgba()).copy()
        keep = {id(artist) for artist in animated} | {id(self.ax)}
        for artist in (*self.fig.get_children(), *self.ax.get_children()):
            if id(artist) not in keep:
                artist.set_visible(False)
        self.ax.set_axis_off()
        self.fig.figimage(background, xo=0, yo=0, origin="upper", zorder=-10)
        for artist, visible in zip(animated, shown, strict=True):
            artist.set_visible(visible)

    # ------------------------------------------------------------------ per frame
    def update(self, row: int) -> None:
        """Show log row *row*."""
        log, t = self.log, float(self.log.t[row])
        x = log.x[row].astype(np.float64)
        active = log.active[row] & np.isfinite(x)
        slack = float(self.lengths.max(initial=0.0)) + 1.0
        shown = active & (x >= self.x_min - 1.0) & (x - slack <= self.x_max)
        ids = np.flatnonzero(shown)
        corners = rectangle_corners(
            x[ids],
            log.y[row, ids].astype(np.float64),
            np.nan_to_num(log.heading[row, ids].astype(np.float64)),
            self.lengths[ids],
            self.widths[ids],
        )
        # Arrays are accepted by matplotlib; its stubs only name sequences, hence the casts.
        self.vehicles.set_verts(cast(Any, corners))
        self.vehicles.set_facecolor(cast(Any, self.face[ids]))
        key = self.is_key[ids]
        edge = np.where(key[:, None], (0, 0, 0, 1), (0.2, 0.2, 0.2, 0.8))
        self.vehicles.set_edgecolor(cast(Any, edge))
        self.vehicles.set_linewidth(cast(Any, np.where(key, 1.4, 0.4)))

        for role, k in self.key.items():
            label = self.labels[role]
            if shown[k]:
                label.xy = (x[k] - 0.5 * self.lengths[k], float(log.y[row, k]))
                label.set_visible(True)
            else:
                label.set_visible(False)

        ghost_verts = []
        for ghost, label in zip(self.ghosts, self.ghost_labels, strict=True):
            gx = ghost.x_at(t)
            if gx is None or not (self.x_min - ghost.length <= gx <= self.x_max + ghost.length):
                label.set_visible(False)
                continue
            ghost_verts.append(rectangle_corners(gx, ghost.y, 0.0, ghost.length, ghost.width))
            label.xy = (gx - 0.5 * ghost.length, ghost.y)
            label.set_visible(True)
        self.ghost_patches.set_verts(
            cast(Any, np.asarray(ghost_verts) if ghost_verts else np.empty((0, 4, 2)))
        )

        self.clock.set_text(f"t = {t:.1f} s")
        self._update_status(t)

    def _update_status(self, t: float) -> None:
        plan = self.plan
        if plan is None or plan.get("t0") is None:
            self.status.set_text("")
            self.merge_marker.set_data([], [])
            return
        t0 = float(plan["t0"])
        end = t0 + float(plan.get("horizon") or 0.0)
        merge_x = plan.get("merge_x")
        mode = plan.get("mode") or "?"
        if t < t0:
            text = "no merge plan yet"
        else:
            state = "in force" if t <= end else "finished"
            where = f", merge at x = {float(merge_x):.0f} m" if merge_x is not None else ""
            text = f"plan issued at {t0:.1f} s ({state}): {mode} cooperation{where}"
        self.status.set_text(text)
        if merge_x is not None and t0 <= t <= end:
            self.merge_marker.set_data([float(merge_x)], [-0.5 * self.road.lane_width + 0.6])
        else:
            self.merge_marker.set_data([], [])


def _hex_rgba(colour: str) -> tuple[float, float, float, float]:
    from matplotlib.colors import to_rgba

    return to_rgba(colour)


def _default_window(road: _Road) -> tuple[float, float]:
    return road.control_zone_start - 50.0, road.accel_lane_end + 150.0


def _check_window(window: Sequence[float] | None, road: _Road) -> tuple[float, float]:
    if window is None:
        return _default_window(road)
    if len(window) != 2:
        raise ValueError(f"window must be (x_min, x_max) [m], got {window!r}")
    x_min, x_max = (float(v) for v in window)
    if not (math.isfinite(x_min) and math.isfinite(x_max) and x_min < x_max):
        raise ValueError(f"window must be (x_min, x_max) with x_min < x_max [m], got {window!r}")
    return x_min, x_max


def animate(
    log: SimulationLog,
    out_path: str | os.PathLike[str],
    *,
    fps: float = 10,
    speedup: float = 5.0,
    t_range: tuple[float, float] | None = None,
    window: tuple[float, float] | None = None,
) -> Path:
    """Write a top-down animation of a run to a GIF or MP4 file.

    The road is seen from above: lane 2 and lane 1, the ramp (from ``ramp_start``) and the
    acceleration lane ``[accel_lane_start, accel_lane_end]``, the cooperative control zone
    shaded. Vehicles are their true ``length`` × ``width`` rectangles at their heading, with
    the reference point at the front bumper, coloured by kind (HDV / CAV). The six key
    vehicles of the first merge plan (``log.meta["plans"][0]``) are outlined and labelled
    (VR, VMC, VMF, VMR, VNF, VNR); the virtual vehicles of every plan are drawn as dashed,
    transparent ghost rectangles while the plan is in force (from ``t0`` until ``t0 + horizon``
    or until a replan replaces it): VV0 on the ramp (y = -W), VV1 in lane 1 (y = 0), VV2 in
    lane 2 (y = W). A clock shows the simulation time and a
    status line the plan (mode, planned merge position, marked with a triangle).

    **The lateral (y) scale is exaggerated** so that the three lanes remain readable in a
    wide strip of road: at the default window (about 750 m of road in a 12 × 2.8 inch
    figure) one metre across is drawn about 6 times longer than one metre along the road,
    so vehicles look stubby and lane changes look steep. The factor is printed in the
    bottom right corner of every frame.

    Parameters
    ----------
    log : SimulationLog
        The run. Its ``meta["config"]["road"]`` gives the geometry (defaults of
        :class:`hcomc.config.RoadParams` for missing keys) and ``meta["plans"]`` the plans.
    out_path : str or os.PathLike
        Output file, ``.gif`` (always available) or ``.mp4`` (needs ``ffmpeg``). Its
        directory must exist. Written atomically: an existing file is replaced only once
        the new one is complete, and a failed render leaves nothing behind.
    fps : float
        Frames per second of the output [1/s], > 0.
    speedup : float
        Simulated seconds per second of video, > 0. One frame is drawn every
        ``speedup / fps`` simulated seconds, from the log row nearest to each frame time
        (rows repeat when this is shorter than the logging interval).
    t_range : (float, float) or None
        Simulated time span ``(start, stop)`` [s] to show; default the whole log. Clipped to
        the log; it must overlap it.
    window : (float, float) or None
        Visible stretch of road ``(x_min, x_max)`` [m]. Default: the merge area, from 50 m
        upstream of the control zone to 150 m past the end of the acceleration lane.

    Returns
    -------
    pathlib.Path
        *out_path*.

    Raises
    ------
    ValueError
        If the extension is neither ``.gif`` nor ``.mp4``, if ``.mp4`` is asked for without
        ``ffmpeg``, if the log has no recorded rows, or on a bad ``fps``, ``speedup``,
        ``t_range`` or ``window``. All checks run before anything is drawn.

    Notes
    -----
    GIF frames are held in memory (as 256-colour palette images, about 0.35 MB each at the
    default size) until the file is written, so very long animations are better cut with
    *t_range* or written as MP4, which streams to ``ffmpeg``. At the default settings a
    90 s run (181 frames) renders in a few seconds.
    """
    target = Path(out_path)
    suffix = _check_suffix(target)
    fps = _positive("fps", fps)
    speedup = _positive("speedup", speedup)
    n = log.n_recorded
    if n == 0:
        raise ValueError("the log has no recorded rows: nothing to animate")
    t = np.asarray(log.t[:n], dtype=np.float64)
    if not np.isfinite(t).all():
        raise ValueError("the log's time column contains NaN in its recorded rows")
    rows = _frame_rows(t, speedup / fps, t_range)
    road = _Road.from_meta(log.meta)
    window_xy = _check_window(window, road)
    if not target.parent.is_dir():
        raise ValueError(f"output directory {str(target.parent)!r} does not exist")

    animator = _RoadAnimator(log, window_xy)
    if suffix == ".gif":
        writer: mpl_animation.AbstractMovieWriter = _QuantizingPillowWriter(fps=fps)  # type: ignore[arg-type]  # a float rate works
    else:
        writer = mpl_animation.FFMpegWriter(fps=fps, codec="h264")  # type: ignore[arg-type]
    with atomic_paths(target) as (tmp,):
        # Writers pick the format from the extension, so render to "<tmp>.gif" / ".mp4".
        render_path = tmp.with_name(tmp.name + suffix)
        try:
            with writer.saving(animator.fig, render_path, _DPI):
                for row in rows:
                    animator.update(int(row))
                    writer.grab_frame()
            os.replace(render_path, tmp)
        finally:
            render_path.unlink(missing_ok=True)
    return target
