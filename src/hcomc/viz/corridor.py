"""Figures and a standalone HTML page of a corridor run, drawn from the run's tables.

The inputs are pandas frames, so this module does not depend on the simulator that made them:
``grid``, Edie's generalized definitions over space-time cells of the mainline, all lanes
together (``x0, x1`` [m], ``t0, t1`` [s], ``distance`` [veh·m], ``time`` [veh·s]; Edie 1963,
"Discussion of traffic stream measurements and definitions"); ``detectors``, virtual loops
with the columns of :data:`hcomc.metrics.detectors.DETECTOR_COLUMNS` (lane 0 = rightmost
mainline lane, negative = ramp lanes); ``trips``, one row per vehicle.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from matplotlib.colors import Normalize

from hcomc.sim.manifest import atomic_paths, build_manifest
from hcomc.viz.common import new_figure, save_figure, speed_cmap
from hcomc.viz.page import _e, _figure_block, _html_table, figure_png, html_page

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.cm import ScalarMappable
    from matplotlib.figure import Figure

__all__ = [
    "CORRIDOR_KINDS",
    "FIGURE_FILES",
    "KIND_TABLES",
    "corridor_figure",
    "corridor_report_html",
    "detector_density",
    "edie_measures",
    "flow_density",
    "speed_heatmap",
    "travel_time_distribution",
    "trip_table",
    "write_corridor_figures",
]

CORRIDOR_KINDS: dict[str, str] = {
    "speed_heatmap": "space-mean speed of the mainline over position and time (grid.csv)",
    "flow_density": "fundamental diagram: flow against density per detector interval "
    "(detectors.csv)",
    "travel_times": "empirical CDF of the arrived trips' travel times per origin (trips.csv)",
}
"""Figure kind -> one-line description: the corridor choices of ``hcomc plot --kind``."""

KIND_TABLES = {"speed_heatmap": "grid", "flow_density": "detectors", "travel_times": "trips"}
"""Figure kind -> the run table it is drawn from (``<table>.csv`` of a corridor run)."""

FIGURE_FILES = tuple(f"{kind}.png" for kind in CORRIDOR_KINDS)
"""File names :func:`write_corridor_figures` writes, in order."""

_SIZES = {"speed_heatmap": (8.0, 4.8), "flow_density": (6.5, 4.5), "travel_times": (6.5, 4.5)}
_CAPTIONS = (
    "Space-mean speed of the mainline over position and time (Edie's definitions per cell).",
    "Fundamental diagram: mainline flow against density q/v per detector and interval.",
    "Empirical CDF of the travel times of the arrived trips, per origin.",
)
_HEADERS = {
    "n": "vehicles",
    "median_travel_time": "median travel time [s]",
    "mean_travel_time": "mean travel time [s]",
    "mean_delay": "mean delay [s]",
}  # trip_table columns -> the HTML table's headers
_MS_TO_KMH = 3.6


def _axes(ax: Axes | None, size: tuple[float, float]) -> Axes:
    """*ax*, or the single axes of a fresh figure (:func:`hcomc.viz.common.new_figure`)."""
    return ax if ax is not None else new_figure(*size).add_subplot()


def _colorbar(ax: Axes, mappable: ScalarMappable, label: str) -> None:
    fig = ax.get_figure()
    assert fig is not None  # an axes drawn on belongs to a figure
    fig.colorbar(mappable, ax=ax, label=label, pad=0.02)


def _note(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.4")


# --------------------------------------------------------------------------- Edie grid
def edie_measures(grid: pd.DataFrame) -> pd.DataFrame:
    """Edie's flow, density and space-mean speed of every space-time cell of *grid*.

    With the cell area A = (x1 − x0)(t1 − t0) [m·s]: flow q = distance / A, density
    k = time / A, speed v = q / k = distance / time (Edie 1963). Being averages over the whole
    cell, they hold for any mix of vehicles entering, leaving or standing in it.

    Returns a frame with ``x0, x1, t0, t1``, ``flow`` [veh/h], ``density`` [veh/km] and
    ``speed`` [m/s] (NaN where no vehicle spent time in the cell), one row per grid row.
    """
    area = (grid["x1"] - grid["x0"]) * (grid["t1"] - grid["t0"])
    time = grid["time"].astype(float)
    cells = grid[["x0", "x1", "t0", "t1"]].astype(float)
    return cells.assign(
        flow=3600.0 * grid["distance"] / area,
        density=1000.0 * time / area,
        speed=grid["distance"] / time.where(time > 0),
    )


def speed_heatmap(grid: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """Time-space diagram of the mainline's space-mean speed v(x, t) [km/h].

    Each cell of *grid* is drawn over its time span (horizontal, [min]) and road span
    (vertical, [km]) in the colour of its Edie speed (:func:`edie_measures`), slow red to
    fast blue (:func:`hcomc.viz.common.speed_cmap`), with a colour bar from 0 km/h. Cells
    without vehicles, and lattice cells missing from *grid*, stay in the no-data grey.
    Congestion shows as red bands whose slope is the speed of the queue's tail.

    Returns the axes drawn on (a new figure's when *ax* is None); it holds one ``QuadMesh``
    whose array is the cells' speed [km/h], rows along x and columns along t.

    Raises ValueError if the cells do not tile a lattice (one x step and one t step each).
    """
    ax = _axes(ax, _SIZES["speed_heatmap"])
    cells = edie_measures(grid)
    if cells.empty:
        _note(ax, "no grid cells")
        return ax
    x_edges = np.unique(np.concatenate([cells["x0"], cells["x1"]]))
    t_edges = np.unique(np.concatenate([cells["t0"], cells["t1"]]))
    i = np.searchsorted(x_edges, cells["x0"])
    j = np.searchsorted(t_edges, cells["t0"])
    if not (
        np.array_equal(x_edges[i + 1], cells["x1"]) and np.array_equal(t_edges[j + 1], cells["t1"])
    ):
        raise ValueError("grid cells must tile a lattice: each cell spans one step in x and t")
    speed = np.full((x_edges.size - 1, t_edges.size - 1), np.nan)
    speed[i, j] = _MS_TO_KMH * cells["speed"].to_numpy()
    finite = speed[np.isfinite(speed)]
    top = 10.0 * math.ceil(float(finite.max()) / 10.0) if finite.size else 10.0
    mesh = ax.pcolormesh(
        t_edges / 60.0,
        x_edges / 1000.0,
        np.ma.masked_invalid(speed),
        cmap=speed_cmap(),
        norm=Normalize(0.0, max(top, 10.0)),
        shading="flat",
        rasterized=True,
    )
    _colorbar(ax, mesh, "space-mean speed v [km/h]")
    ax.set_xlabel("time t [min]")
    ax.set_ylabel("position x [km]")
    dx, dt = float(np.median(np.diff(x_edges))), float(np.median(np.diff(t_edges)))
    ax.set_title(f"Mainline speed (Edie, {dx:g} m × {dt:g} s cells; grey: no vehicle)")
    return ax


# --------------------------------------------------------------------------- detectors
def detector_density(detectors: pd.DataFrame) -> pd.DataFrame:
    """Cross-section flow, space-mean speed and density of every mainline detector interval.

    Per position x and interval [begin, end), over the mainline lanes (lane ≥ 0): flow
    Q = Σ q_l [veh/h]; speed V = Σ q_l / Σ (q_l / v_l) [m/s], the flow-weighted harmonic
    mean of the lanes' harmonic speeds v_l (so the harmonic mean over all vehicles that
    crossed, the space-mean speed estimate); density K = Q / V [veh/km] (q = k·v; the
    arithmetic time-mean speed would bias K low). Intervals in which no mainline vehicle
    crossed are skipped; where a lane counted vehicles without a harmonic speed (one stood
    on the loop) V and K are NaN.

    Returns a frame with ``x`` [m], ``begin``, ``end`` [s], ``flow`` [veh/h], ``speed``
    [m/s] and ``density`` [veh/km], sorted by x and begin.
    """
    main = detectors[detectors["lane"] >= 0]
    used = main["count"] > 0
    inverse = main["flow"] / main["harmonic_speed"].where(main["harmonic_speed"] > 0)
    main = main.assign(_q=main["flow"].astype(float), _n=used, _inv=inverse.where(used, 0.0))
    sums = main.groupby(["x", "begin", "end"], sort=True).agg(
        flow=("_q", "sum"),
        n=("_n", "sum"),
        inv=("_inv", lambda s: s.sum(min_count=len(s))),  # NaN if any lane's is
    )
    sums = sums[sums["n"] > 0].reset_index().astype(float)
    speed = sums["flow"] / sums["inv"]
    return sums[["x", "begin", "end", "flow"]].assign(
        speed=speed, density=sums["flow"] / (_MS_TO_KMH * speed)
    )


def flow_density(detectors: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """Fundamental diagram: flow [veh/h] against density [veh/km] of every detector interval.

    One point per cross-section and interval (:func:`detector_density`, mainline lanes
    together), coloured by the detector position [km]: free flow lies on the rising branch,
    congestion on the falling one, and the colours show where along the corridor each is.

    Returns the axes drawn on; its first collection holds the points (density, flow).
    """
    ax = _axes(ax, _SIZES["flow_density"])
    points = detector_density(detectors).dropna(subset=["density"])
    if points.empty:
        _note(ax, "no detector interval with vehicles")
        return ax
    km = points["x"].to_numpy() / 1000.0
    dots = ax.scatter(points["density"], points["flow"], c=km, cmap="viridis", s=14, lw=0)
    if np.ptp(km) > 0:
        _colorbar(ax, dots, "detector position x [km]")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel("density k = q / v [veh/km]")
    ax.set_ylabel("flow q [veh/h], mainline lanes")
    ax.grid(True, color="0.85", linewidth=0.5)
    ax.set_title("Fundamental diagram (detectors, per interval)")
    return ax


# --------------------------------------------------------------------------- trips
def _origins(trips: pd.DataFrame) -> list[str]:
    """Origins of *trips*: the mainline ("main") first, then the on-ramps in name order."""
    return sorted({str(o) for o in trips["origin"]}, key=lambda o: (o != "main", o))


def _arrived(trips: pd.DataFrame) -> pd.DataFrame:
    return trips[(trips["outcome"] == "arrived") & np.isfinite(trips["travel_time"])]


def trip_table(trips: pd.DataFrame) -> pd.DataFrame:
    """Trips per origin: how many, how many arrived, and the arrived trips' times.

    Returns one row per origin (mainline first, then the ramps by name) with ``origin``,
    ``n`` (vehicles), ``arrived`` (outcome "arrived") and, over the arrived trips,
    ``median_travel_time``, ``mean_travel_time`` and ``mean_delay`` [s] (NaN if none).
    """
    arrived = _arrived(trips)
    done = arrived.groupby(arrived["origin"].astype(str))
    table = pd.DataFrame(
        {
            "n": trips.groupby(trips["origin"].astype(str)).size(),
            "arrived": done.size(),
            "median_travel_time": done["travel_time"].median(),
            "mean_travel_time": done["travel_time"].mean(),
            "mean_delay": done["delay"].mean(),
        },
        index=pd.Index(_origins(trips), name="origin", dtype=object),
    )
    table[["n", "arrived"]] = table[["n", "arrived"]].fillna(0).astype(np.int64)
    return table.reset_index()


_MERGE_HEADERS = {
    "events": "events", "merged_share": "merged share", "mean_time_to_merge":
    "zone to merge [s]", "min_ttc_p05": "least TTC, 5th pct. [s]", "ttc_below_1_5s_share":
    "share with TTC < 1.5 s", "max_drac": "max DRAC [m/s²]", "max_decel":
    "hardest braking [m/s²]", "plans": "plans", "fallbacks": "fallbacks",
}  # fmt: skip
"""Columns of :func:`merge_table` (keys of :func:`hcomc.metrics.corridor.events.merge_summary`)
and their headers in the report."""


def merge_table(merges: pd.DataFrame) -> pd.DataFrame:
    """Merge events per on-ramp (:func:`hcomc.metrics.corridor.events.merge_summary` of each
    ramp in ``merges``), one row per ramp, columns as :data:`_MERGE_HEADERS` says."""
    from hcomc.metrics.corridor.events import merge_summary

    rows = []
    for ramp in sorted(merges["ramp"].astype(str).unique()):
        summary = merge_summary(merges, ramp)
        rows.append({"ramp": ramp, **{k: summary[k] for k in _MERGE_HEADERS}})
    return pd.DataFrame(rows, columns=["ramp", *_MERGE_HEADERS])


def travel_time_distribution(trips: pd.DataFrame, ax: Axes | None = None) -> Axes:
    """Empirical CDF of the travel time [s] of the arrived trips, one step line per origin.

    Each line has one point per arrived trip, at (its travel time, share of its origin's
    arrived trips at most that long), so it ends at 1; the legend gives n and the median,
    the numbers to compare origins by (the ramps' trips include the merge).

    Returns the axes drawn on; one line per origin with arrived trips, mainline first.
    """
    ax = _axes(ax, _SIZES["travel_times"])
    arrived = _arrived(trips)
    for origin in _origins(arrived):
        values = np.sort(arrived.loc[arrived["origin"] == origin, "travel_time"].to_numpy(float))
        share = np.arange(1, values.size + 1) / values.size
        label = f"{origin} (n = {values.size}, median {np.median(values):.0f} s)"
        ax.step(values, share, where="post", label=label)
    if arrived.empty:
        _note(ax, "no arrived trips")
    else:
        ax.legend(title="origin", fontsize=8, loc="lower right")
    ax.set_ylim(0.0, 1.02)
    ax.set_xlabel("travel time [s]")
    ax.set_ylabel("share of arrived trips")
    ax.grid(True, color="0.85", linewidth=0.5)
    ax.set_title("Travel times of the arrived trips (empirical CDF)")
    return ax


# --------------------------------------------------------------------------- output
def corridor_figure(kind: str, table: pd.DataFrame) -> Figure:
    """The figure of *kind* (:data:`CORRIDOR_KINDS`) drawn from its run *table*
    (:data:`KIND_TABLES`) on a fresh figure of that kind's size: the one drawing that
    :func:`write_corridor_figures`, the HTML page and ``hcomc plot`` share.

    Raises ValueError on an unknown kind.
    """
    draws = (speed_heatmap, flow_density, travel_time_distribution)  # CORRIDOR_KINDS order
    draw = dict(zip(CORRIDOR_KINDS, draws, strict=True)).get(kind)
    if draw is None:
        raise ValueError(f"unknown corridor figure '{kind}'; allowed: {', '.join(CORRIDOR_KINDS)}")
    fig = new_figure(*_SIZES[kind])
    draw(table, fig.add_subplot())
    return fig


def _figures(grid: pd.DataFrame, detectors: pd.DataFrame, trips: pd.DataFrame) -> list[Figure]:
    """The three figures, each on a fresh figure, in :data:`FIGURE_FILES` order."""
    tables = {"grid": grid, "detectors": detectors, "trips": trips}
    return [corridor_figure(kind, tables[KIND_TABLES[kind]]) for kind in CORRIDOR_KINDS]


def write_corridor_figures(
    grid: pd.DataFrame,
    detectors: pd.DataFrame,
    trips: pd.DataFrame,
    out_dir: str | os.PathLike[str],
) -> list[Path]:
    """Write the speed heat map, fundamental diagram and travel-time CDFs as PNG files.

    The files (:data:`FIGURE_FILES`) go into *out_dir*, created if missing; existing files
    are replaced atomically (:func:`hcomc.viz.common.save_figure`). Returns their paths, in
    :data:`FIGURE_FILES` order.
    """
    figures = _figures(grid, detectors, trips)
    out = Path(out_dir)
    return [save_figure(fig, out / name) for fig, name in zip(figures, FIGURE_FILES, strict=True)]


def corridor_report_html(
    grid: pd.DataFrame,
    detectors: pd.DataFrame,
    trips: pd.DataFrame,
    out_dir: str | os.PathLike[str],
    *,
    title: str = "hcomc corridor run",
    merges: pd.DataFrame | None = None,
) -> Path:
    """Write ``out_dir/corridor.html``, the trips table, the merge events per on-ramp (with
    ``merges``, :func:`merge_table`) and the three figures, and return it.

    Like :func:`hcomc.viz.report.write_report` (both build on :mod:`hcomc.viz.page`) the
    page loads nothing (inline styles, no script, figures as base64 PNG), escapes all text,
    is stamped with the hcomc version and git revision, and is written atomically, replacing
    an existing page; *out_dir* is created if missing.
    """
    table = trip_table(trips).rename(columns=_HEADERS)
    table_html = (
        _html_table(table, "Trips per origin; times over the arrived trips.", table_id="trips")
        if not table.empty
        else '<p class="empty" id="trips">No trips.</p>'
    )
    merge_html = ""
    if merges is not None:
        per_ramp = merge_table(merges).rename(columns=_MERGE_HEADERS)
        caption = "Merge events per on-ramp, from VR's entry into the control zone."
        merge_html = (
            '<section id="merges-section">\n<h2>Merges</h2>\n'
            f"{_html_table(per_ramp, caption, table_id='merges')}\n</section>"
        )
    pairs = zip(_CAPTIONS, _figures(grid, detectors, trips), strict=True)
    figures = "\n".join(_figure_block(i, c, figure_png(f)) for i, (c, f) in enumerate(pairs, 1))
    run = build_manifest(seed=0, config={})
    body = html_page(
        title,
        f"""<header>
<h1>{_e(title)}</h1>
<p class="meta">hcomc <code>{_e(run["hcomc_version"])}</code> · git revision
<code>{_e(run["git_revision"])}</code> · generated {_e(run["created_utc"])} (UTC)</p>
</header>
<section id="trips-section">
<h2>Trips</h2>
{table_html}
</section>
{merge_html}
<section id="figures">
<h2>Figures</h2>
{figures}
</section>
""",
    )
    target = Path(out_dir) / "corridor.html"
    target.parent.mkdir(parents=True, exist_ok=True)
    with atomic_paths(target) as (tmp,):
        tmp.write_text(body, encoding="utf-8")
    return target
