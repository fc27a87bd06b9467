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
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import animation as mpl_animation

from hcomc.sim.log import SimulationLog
from hcomc.sim.manifest import atomic_paths
from hcomc.viz.scene.frame import DPI, RoadScene
from hcomc.viz.scene.road import SceneRoad

__all__ = ["ALLOWED_SUFFIXES", "animate"]

#: Output formats :func:`animate` writes, by file extension.
ALLOWED_SUFFIXES = (".gif", ".mp4")


class _QuantizingPillowWriter(mpl_animation.PillowWriter):
    """:class:`~matplotlib.animation.PillowWriter` that keeps frames in palette mode.

    A GIF stores palette images anyway; quantising each frame as it is grabbed (fast octree,
    instead of Pillow's median cut at save time) keeps palette frames in memory instead of
    full-colour ones and spares the slower quantiser.
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


def _default_window(road: SceneRoad) -> tuple[float, float]:
    return road.control_zone_start - 50.0, road.accel_lane_end + 150.0


def _check_window(window: Sequence[float] | None, road: SceneRoad) -> tuple[float, float]:
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
        The run. Its ``meta["config"]["road"]`` gives the geometry (a log without one is
        refused, :func:`hcomc.metrics.road_of`) and ``meta["plans"]`` the plans.
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
        ``ffmpeg``, if the log has no recorded rows or no road geometry, or on a bad
        ``fps``, ``speedup``, ``t_range`` or ``window``. All checks run before anything is
        drawn.

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
    road = SceneRoad.of(log)
    window_xy = _check_window(window, road)
    if not target.parent.is_dir():
        raise ValueError(f"output directory {str(target.parent)!r} does not exist")

    animator = RoadScene(log, window_xy)
    if suffix == ".gif":
        writer: mpl_animation.AbstractMovieWriter = _QuantizingPillowWriter(fps=fps)  # type: ignore[arg-type]  # a float rate works
    else:
        writer = mpl_animation.FFMpegWriter(fps=fps, codec="h264")  # type: ignore[arg-type]
    with atomic_paths(target) as (tmp,):
        # Writers pick the format from the extension, so render to "<tmp>.gif" / ".mp4".
        render_path = tmp.with_name(tmp.name + suffix)
        try:
            with writer.saving(animator.fig, render_path, DPI):
                for row in rows:
                    animator.update(int(row))
                    writer.grab_frame()
            os.replace(render_path, tmp)
        finally:
            render_path.unlink(missing_ok=True)
    return target
