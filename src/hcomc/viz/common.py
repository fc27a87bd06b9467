"""Shared pieces of the static figures: saving, zone shading and colours.

Colours are fixed here so that every figure (and the animation and HTML report) shows a
vehicle type, a key role or a road zone in the same colour.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import matplotlib as mpl
import numpy as np
from matplotlib.figure import Figure

from hcomc.config import RoadParams
from hcomc.metrics import KEY_ROLES, MetricWindow, merge_window
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.manifest import atomic_paths

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.colors import Colormap

__all__ = [
    "ALLOWED_FORMATS",
    "CONFIGURATION_COLORS",
    "DPI",
    "KIND_COLORS",
    "KIND_NAMES",
    "LANE_NAMES",
    "MODE_COLORS",
    "NO_DATA_COLOR",
    "ROLE_COLORS",
    "SPEED_CMAP",
    "ZONE_COLORS",
    "configuration_label",
    "first_plan",
    "key_group",
    "key_time",
    "log_window",
    "merge_time",
    "new_figure",
    "run_title",
    "save_figure",
    "shade_zones",
    "speed_cmap",
]

ALLOWED_FORMATS: tuple[str, ...] = (".png", ".svg", ".pdf")
"""File extensions :func:`save_figure` writes."""

DPI = 150
"""Resolution of PNG files and of rasterised artists inside SVG/PDF files [dots per inch]."""

KIND_NAMES: dict[int, str] = {0: "HDV", 1: "CAV"}
"""Vehicle type code of :attr:`SimulationLog.kind` -> name."""

KIND_COLORS: dict[int, str] = {0: "#d95f02", 1: "#1b9e77"}
"""Vehicle type code -> colour (HDV orange, CAV teal; ColorBrewer Dark2)."""

ROLE_COLORS: dict[str, str] = {
    "VR": "#d62728",  # red: the merging ramp vehicle
    "VMC": "#1f77b4",  # blue: the cooperating lane-1 vehicle
    "VMF": "#2ca02c",  # green: VMC's leader
    "VMR": "#9467bd",  # purple: VMC's follower
    "VNF": "#8c564b",  # brown: lane-2 leader
    "VNR": "#e377c2",  # pink: lane-2 follower
}
"""Key role (paper Fig. 1) -> colour, in :data:`hcomc.metrics.KEY_ROLES` order."""

LANE_NAMES: dict[int, str] = {2: "lane 2", 1: "lane 1", 0: "ramp"}
"""Lane index -> label, top (outer lane 2) to bottom (ramp)."""

ZONE_COLORS: dict[str, str] = {"control zone": "#fde9a9", "acceleration lane": "#bcd9ee"}
"""Road zone -> light fill colour."""

MODE_COLORS: dict[str, str] = {
    "longitudinal": "#1f77b4",
    "lateral": "#ff7f0e",
    "none": "#7f7f7f",
}
"""VMC cooperation mode -> colour."""

CONFIGURATION_COLORS: dict[str, str] = {
    "FIFO": "#8c8c8c",
    "Game": "#d8b365",
    "HCOMC": "#08519c",
    "HCOMC-PSO": "#4292c6",
    "HCOMC-SA": "#9ecae1",
}
"""Configuration label (:data:`hcomc.experiments.runner.CONFIGURATIONS`) -> bar colour."""

NO_DATA_COLOR = "#ececec"
"""Fill of cells without data in speed maps."""

SPEED_CMAP = "turbo_r"
"""Colour map of speed [m/s]: red = slow, blue = fast."""


def speed_cmap() -> Colormap:
    """The speed colour map, with light grey for masked (no data) cells."""
    return mpl.colormaps[SPEED_CMAP].with_extremes(bad=NO_DATA_COLOR)


# --------------------------------------------------------------------------- figures
def new_figure(width: float, height: float) -> Figure:
    """A fresh figure with constrained layout, detached from any pyplot state.

    Parameters
    ----------
    width, height : float
        Figure size [inch].

    Returns
    -------
    matplotlib.figure.Figure
        Empty figure; :func:`save_figure` writes it.
    """
    return Figure(figsize=(width, height), layout="constrained")


def save_figure(fig: Figure, path: str | os.PathLike[str]) -> Path:
    """Write *fig* as PNG, SVG or PDF, chosen by the file extension, atomically.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Figure to write.
    path : str or os.PathLike
        Target file; the extension (case-insensitive) must be one of
        :data:`ALLOWED_FORMATS`. Missing parent directories are created.

    Returns
    -------
    pathlib.Path
        The target path.

    Raises
    ------
    ValueError
        On any other extension (the message names it and the allowed ones).

    Notes
    -----
    The figure is rendered into a temporary file in the target directory and moved into
    place with :func:`os.replace` (:func:`hcomc.sim.manifest.atomic_paths`), so a reader
    never sees a half-written file and an interrupted save leaves no temporary file behind.
    PNG files are written at :data:`DPI`; SVG and PDF files are vector graphics (dense
    artists such as speed meshes are rasterised at :data:`DPI`) without a creation date,
    so the same figure gives the same bytes.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in ALLOWED_FORMATS:
        shown = ext or "(none)"
        raise ValueError(
            f"unsupported figure file extension '{shown}'; allowed: {', '.join(ALLOWED_FORMATS)}"
        )
    fmt = ext[1:]
    metadata: dict[str, Any] = {
        "png": {"Software": None},
        "svg": {"Date": None},
        "pdf": {"CreationDate": None, "ModDate": None},
    }[fmt]
    path.parent.mkdir(parents=True, exist_ok=True)
    with (
        atomic_paths(path) as (tmp,),
        tmp.open("wb") as fh,
        mpl.rc_context({"svg.hashsalt": "hcomc"}),
    ):
        fig.savefig(fh, format=fmt, dpi=DPI, metadata=metadata)
    return path


# --------------------------------------------------------------------------- run facts
def first_plan(log: SimulationLog) -> dict[str, Any] | None:
    """The first merge plan of the run (``log.meta["plans"][0]``), None if there is none."""
    plans = log.meta.get("plans") or []
    return plans[0] if plans else None


def key_group(log: SimulationLog) -> dict[str, int]:
    """Role -> vehicle slot of the first merge's key vehicles (-1 = missing).

    The key vehicles the engine records when the first ramp vehicle enters the control zone,
    before any control acts (``log.meta["key_groups"]``, the vehicles the metrics measure);
    for a log without them, the first plan's group; {} if no ramp vehicle got that far.
    """
    plan = first_plan(log)
    groups = log.meta.get("key_groups") or []
    group = groups[0] if groups else plan.get("group", {}) if plan is not None else None
    if group is None:
        return {}
    return {role: int(group.get(role, -1)) for role in KEY_ROLES}


def key_time(log: SimulationLog) -> float:
    """Time [s] the first merge's key vehicles were found (planning time t0); NaN if never."""
    plan = first_plan(log)
    groups = log.meta.get("key_groups") or []
    if plan is not None:
        return float(plan["t0"])
    return float(groups[0]["t"]) if groups else math.nan


def log_window(log: SimulationLog) -> MetricWindow:
    """Evaluation window of the first merge (see :func:`key_group`), or the whole run if none.

    Parameters
    ----------
    log : SimulationLog
        The run's log.

    Returns
    -------
    hcomc.metrics.MetricWindow
        :func:`hcomc.metrics.merge_window` of the first plan's VR, or a window spanning all
        logged rows (no group, no merge) when the run has no plan.
    """
    group = key_group(log)
    if group.get("VR", -1) >= 0:
        return merge_window(log, group["VR"], group)
    t = np.asarray(log.t[: log.n_recorded], dtype=np.float64)
    t0, t1 = (float(t[0]), float(t[-1])) if t.size else (math.nan, math.nan)
    return MetricWindow(group={}, t_start=t0, t_merge=math.nan, t_end=t1)


def merge_time(log: SimulationLog, vehicle: int) -> tuple[float, float]:
    """Time [s] and position [m] of *vehicle*'s first MERGE event; (NaN, NaN) if none."""
    ev = log.events_of(EventKind.MERGE)
    ev = ev[ev["vehicle"] == vehicle]
    if ev.size == 0:
        return math.nan, math.nan
    return float(ev["t"][0]), float(ev["x"][0])


def configuration_label(log: SimulationLog) -> str:
    """Short configuration name of a run: ``FIFO``, ``Game``, ``HCOMC`` or ``HCOMC-PSO`` ...

    Read from ``log.meta["config"]["control"]``; ``"run"`` if the log has no config.
    """
    config = log.meta.get("config")
    control = config.get("control", {}) if isinstance(config, Mapping) else {}
    controller = str(control.get("controller", "")).lower()
    if not controller:
        return "run"
    name = {"fifo": "FIFO", "game": "Game", "hcomc": "HCOMC"}.get(controller, controller)
    optimizer = str(control.get("optimizer", "nsga2")).lower()
    if controller == "hcomc" and optimizer not in ("", "nsga2"):
        name += f"-{optimizer.upper()}"
    return name


def run_title(log: SimulationLog) -> str:
    """``"<condition> · seed <seed>"`` from the log's metadata (parts that are missing are left
    out)."""
    config = log.meta.get("config")
    name = config.get("name") if isinstance(config, Mapping) else None
    seed = log.meta.get("seed")
    parts = [str(name)] if name else []
    if seed is not None:
        parts.append(f"seed {seed}")
    return " · ".join(parts)


# --------------------------------------------------------------------------- zones
def shade_zones(
    ax: Axes,
    road: RoadParams,
    *,
    orientation: Literal["x", "y"] = "x",
    band: float | None = None,
    label: bool = True,
) -> None:
    """Mark the control zone and the acceleration lane along a position axis.

    The control zone is ``[accel_lane_start - control_zone_length, accel_lane_start]``
    (clipped at 0), the acceleration lane ``[accel_lane_start, accel_lane_end]`` [m].

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes whose horizontal (``orientation="x"``) or vertical (``"y"``) data axis is the
        road position x [m].
    road : hcomc.config.RoadParams
        Road geometry (:func:`hcomc.metrics.road_of`).
    orientation : {"x", "y"}
        Which axis carries the road position.
    band : float or None
        None: shade the zones over the whole axes, behind everything. A fraction in
        (0, 1]: draw them as an opaque band of that width along the top (``"x"``) or
        right (``"y"``) edge of the axes, above the data, with dashed boundary lines over
        the data (for panels whose data would hide a background shade).
    label : bool
        Give the patches legend labels ("control zone", "acceleration lane").
    """
    zones = {
        "control zone": (road.control_zone_start, road.accel_lane_start),
        "acceleration lane": (road.accel_lane_start, road.accel_lane_end),
    }
    span = ax.axvspan if orientation == "x" else ax.axhspan
    line = ax.axvline if orientation == "x" else ax.axhline
    for name, (lo, hi) in zones.items():
        if hi <= lo:
            continue
        kwargs: dict[str, Any] = {
            "facecolor": ZONE_COLORS[name],
            "edgecolor": "none",
            "label": name if label else None,
        }
        if band is None:
            span(lo, hi, zorder=0, alpha=0.7, **kwargs)
        else:
            lo_frac = 1.0 - band
            if orientation == "x":
                # span is axvspan here; mypy checks the call against both spans
                span(lo, hi, ymin=lo_frac, ymax=1.0, zorder=4, **kwargs)  # type: ignore[misc]
            else:
                span(lo, hi, xmin=lo_frac, xmax=1.0, zorder=4, **kwargs)  # type: ignore[misc]
    if band is not None:
        edges = sorted({road.control_zone_start, road.accel_lane_start, road.accel_lane_end})
        for edge in edges:
            line(edge, color="0.25", linewidth=0.6, linestyle=(0, (4, 3)), zorder=3)
