"""The top-down road scene that :func:`hcomc.viz.animation.animate` renders frame by frame:
road and zones, vehicles by kind, the key vehicles of the first plan, the virtual vehicles of
every plan (ghosts) and a status line."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from hcomc.equations.collision import rectangle_corners
from hcomc.road import KEY_ROLES
from hcomc.sim.log import SimulationLog
from hcomc.viz.scene.ghosts import plan_ghosts
from hcomc.viz.scene.road import ROAD_COLOURS, Y_MARGIN, SceneRoad, draw_road

__all__ = ["DPI", "RoadScene", "hex_rgba"]

_FIG_SIZE = (12.0, 2.8)  # [in]; with DPI an even pixel size, as H.264 needs
DPI = 100
_AX_RECT = (0.035, 0.2, 0.955, 0.6)  # left, bottom, width, height (figure fraction)

_COLOURS = {
    "hdv": "#d95f02",
    "cav": "#1b9e77",
    "ghost": "#7570b3",
}


class RoadScene:
    """Figure with the static road and the per-frame artists of one log."""

    def __init__(self, log: SimulationLog, window: tuple[float, float]) -> None:
        self.log = log
        self.road = SceneRoad.of(log)
        self.x_min, self.x_max = window
        self.fig = Figure(figsize=_FIG_SIZE, dpi=DPI)
        self.ax = self.fig.add_axes(_AX_RECT)
        draw_road(self.ax, self.road, window, self.y_exaggeration())
        self.lengths = log.length.astype(np.float64)
        self.widths = log.width.astype(np.float64)
        colours = np.array(
            [
                hex_rgba(_COLOURS["hdv"]),
                hex_rgba(_COLOURS["cav"]),
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
        self.ghosts = plan_ghosts(log.meta, self.lengths, self.widths, self.road)

        self.vehicles = PolyCollection([], closed=True, zorder=5)
        self.ax.add_collection(self.vehicles)
        self.ghost_patches = PolyCollection(
            [],
            closed=True,
            facecolors=(*hex_rgba(_COLOURS["ghost"])[:3], 0.18),
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
    def y_exaggeration(self) -> float:
        """How much the y axis is stretched relative to x on screen [-]."""
        width_in = _FIG_SIZE[0] * _AX_RECT[2]
        height_in = _FIG_SIZE[1] * _AX_RECT[3]
        y_span = 2 * (1.5 + Y_MARGIN) * self.road.lane_width
        return ((self.x_max - self.x_min) / width_in) / (y_span / height_in)

    def _legend(self) -> None:
        handles = [
            Patch(fc=_COLOURS["hdv"], ec="#333333", lw=0.5, label="HDV"),
            Patch(fc=_COLOURS["cav"], ec="#333333", lw=0.5, label="CAV"),
            Patch(
                fc=(*hex_rgba(_COLOURS["ghost"])[:3], 0.18),
                ec=_COLOURS["ghost"],
                ls="--",
                label="virtual vehicle (VV1, VV2)",
            ),
            Patch(fc=ROAD_COLOURS["zone"], ec="none", label="control zone"),
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


def hex_rgba(colour: str) -> tuple[float, float, float, float]:
    from matplotlib.colors import to_rgba

    return to_rgba(colour)
