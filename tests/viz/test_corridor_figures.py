"""Corridor figures (hcomc.viz.corridor) on synthetic tables whose numbers are known by hand."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PathCollection, QuadMesh
from matplotlib.image import imread

from hcomc.viz.common import new_figure
from hcomc.viz.corridor import (
    FIGURE_FILES,
    corridor_report_html,
    detector_density,
    edie_measures,
    flow_density,
    speed_heatmap,
    travel_time_distribution,
    trip_table,
    write_corridor_figures,
)

PNG = b"\x89PNG\r\n\x1a\n"
U = 25.0  # [m/s] speed of the single vehicle of the grid fixture
DX, DT = 200.0, 10.0  # [m], [s] grid cells
X_END, T_END = 1000.0, 60.0


# --------------------------------------------------------------------------- data
def one_vehicle_grid(speed: float = U, t_enter: float = 0.0) -> pd.DataFrame:
    """Edie grid of one vehicle at constant *speed* entering x = 0 at *t_enter*: the time it
    spends in a cell is the overlap of the cell's [t0, t1) with its passage through
    [x0, x1), and the distance is speed times that time."""
    rows = []
    for x0 in np.arange(0.0, X_END, DX):
        for t0 in np.arange(0.0, T_END, DT):
            inside = min(t0 + DT, t_enter + (x0 + DX) / speed) - max(t0, t_enter + x0 / speed)
            time = max(inside, 0.0)
            rows.append(
                {"x0": x0, "x1": x0 + DX, "t0": t0, "t1": t0 + DT,
                 "distance": speed * time, "time": time}
            )  # fmt: skip
    return pd.DataFrame(rows)


def detector_row(x: float, lane: int, begin: float, speeds: list[float]) -> dict[str, float]:
    """One E1 row for the crossing *speeds* [m/s] in a 60 s interval."""
    v = np.asarray(speeds, dtype=float)
    n = v.size
    return {
        "x": x, "lane": lane, "begin": begin, "end": begin + 60.0, "count": n,
        "flow": 60.0 * n, "speed": v.mean() if n else np.nan,
        "harmonic_speed": n / np.sum(1.0 / v) if n and (v > 0).all() else np.nan,
        "occupancy": 5.0 * n, "mean_length": 5.0 if n else np.nan,
    }  # fmt: skip


LANE0 = [20.0, 25.0, 30.0, 22.0]
LANE1 = [30.0, 35.0]
RAMP = [8.0, 9.0, 10.0]


@pytest.fixture
def detectors() -> pd.DataFrame:
    return pd.DataFrame(
        [
            # x = 500: both lanes and the ramp in the first interval
            detector_row(500.0, 0, 0.0, LANE0),
            detector_row(500.0, 1, 0.0, LANE1),
            detector_row(500.0, -1, 0.0, RAMP),
            # second interval: only lane 0 counted, lane 1 empty (NaN speeds), ramp busy
            detector_row(500.0, 0, 60.0, [15.0]),
            detector_row(500.0, 1, 60.0, []),
            detector_row(500.0, -1, 60.0, RAMP),
            # third interval: nobody on the mainline (skipped), the ramp does not count
            detector_row(500.0, 0, 120.0, []),
            detector_row(500.0, 1, 120.0, []),
            detector_row(500.0, -1, 120.0, RAMP),
            # x = 1500: a vehicle standing on the loop (speed 0: no harmonic speed)
            detector_row(1500.0, 0, 0.0, [0.0, 10.0]),
            detector_row(1500.0, 1, 0.0, [12.0]),
        ]
    )


@pytest.fixture
def trips() -> pd.DataFrame:
    rows = [
        # origin, outcome, travel time [s], delay [s]
        ("main", "arrived", 100.0, 10.0),
        ("main", "arrived", 200.0, 40.0),
        ("main", "on_road", np.nan, np.nan),
        ("main", "arrived", 120.0, 16.0),
        ("r1", "arrived", 170.0, 30.0),
        ("r1", "not_inserted", np.nan, np.nan),
        ("r1", "arrived", 150.0, 20.0),
        ("r0", "missed_exit", np.nan, np.nan),
    ]
    frame = pd.DataFrame(rows, columns=["origin", "outcome", "travel_time", "delay"])
    n = len(frame)
    return frame.assign(
        id=np.arange(n),
        destination="exit",
        vclass="passenger",
        cav=np.arange(n) % 2 == 0,
        depart=10.0 * np.arange(n),
        insert=10.0 * np.arange(n),
        arrive=10.0 * np.arange(n) + frame["travel_time"],
        route_length=3000.0,
    )


# --------------------------------------------------------------------------- Edie grid
def test_edie_measures_of_two_vehicles_in_one_cell() -> None:
    # 100 m x 10 s cell: A drives through at 10 m/s (10 s, 100 m), B at 25 m/s (4 s, 100 m)
    grid = pd.DataFrame(
        {"x0": [0.0], "x1": [100.0], "t0": [0.0], "t1": [10.0], "distance": [200.0],
         "time": [14.0]}
    )  # fmt: skip
    cell = edie_measures(grid).iloc[0]
    assert cell["flow"] == pytest.approx(3600.0 * 200.0 / 1000.0)  # 720 veh/h
    assert cell["density"] == pytest.approx(1000.0 * 14.0 / 1000.0)  # 14 veh/km
    assert cell["speed"] == pytest.approx(200.0 / 14.0)  # space mean, not (10 + 25) / 2
    assert cell["flow"] / 3.6 == pytest.approx(cell["density"] * cell["speed"])  # q = k v


def test_heatmap_of_one_vehicle_shows_its_speed_and_nothing_else() -> None:
    grid = one_vehicle_grid()
    ax = speed_heatmap(grid)
    meshes = [c for c in ax.collections if isinstance(c, QuadMesh)]
    assert len(meshes) == 1
    plotted = np.ma.asarray(meshes[0].get_array()).reshape(int(X_END / DX), int(T_END / DT))
    occupied = (grid["time"] > 0).to_numpy().reshape(plotted.shape)
    # 8 s per 200 m cell, 40 s for 1 km: 8 of the 30 cells, x up, t across
    assert occupied.sum() == 8
    np.testing.assert_array_equal(np.ma.getmaskarray(plotted), ~occupied)
    np.testing.assert_allclose(plotted.compressed(), 3.6 * U)  # 90 km/h in every cell
    coords = meshes[0].get_coordinates()
    np.testing.assert_allclose(coords[0, :, 0], np.arange(0.0, T_END + DT, DT) / 60.0)  # min
    np.testing.assert_allclose(coords[:, 0, 1], np.arange(0.0, X_END + DX, DX) / 1000.0)  # km
    assert "km/h" in ax.figure.axes[-1].get_ylabel()  # the colour bar


def test_heatmap_leaves_missing_lattice_cells_blank_and_rejects_overlaps() -> None:
    grid = one_vehicle_grid(speed=10.0)
    plotted = np.ma.asarray(speed_heatmap(grid.drop(index=[0])).collections[0].get_array())
    assert np.ma.getmaskarray(plotted).ravel()[0]
    np.testing.assert_allclose(plotted.compressed(), 36.0)
    bad = pd.concat([grid, grid.iloc[[0]].assign(x1=2 * DX)], ignore_index=True)
    with pytest.raises(ValueError, match="lattice"):
        speed_heatmap(bad)


# --------------------------------------------------------------------------- detectors
def harmonic(values: list[float]) -> float:
    return len(values) / sum(1.0 / v for v in values)


def test_detector_density_is_total_flow_over_flow_weighted_harmonic_speed(
    detectors: pd.DataFrame,
) -> None:
    out = detector_density(detectors)
    assert list(out.columns) == ["x", "begin", "end", "flow", "speed", "density"]
    assert list(zip(out["x"], out["begin"], strict=True)) == [(500.0, 0.0), (500.0, 60.0),
                                                              (1500.0, 0.0)]  # fmt: skip
    first = out.iloc[0]
    q0, q1 = 60.0 * len(LANE0), 60.0 * len(LANE1)  # 240 + 120 veh/h; the ramp is left out
    v = (q0 + q1) / (q0 / harmonic(LANE0) + q1 / harmonic(LANE1))
    assert first["flow"] == pytest.approx(360.0)
    assert first["speed"] == pytest.approx(v)
    # ... which is the harmonic mean of all six crossing speeds
    assert first["speed"] == pytest.approx(harmonic(LANE0 + LANE1))
    assert first["density"] == pytest.approx(360.0 / 3.6 / v)  # veh/h / (km/h) = veh/km
    second = out.iloc[1]  # the empty lane 1 adds nothing
    assert (second["flow"], second["speed"]) == (60.0, 15.0)
    assert second["density"] == pytest.approx(60.0 / (3.6 * 15.0))
    standing = out.iloc[2]  # a lane with vehicles but no harmonic speed: unknown, not skipped
    assert standing["flow"] == 180.0
    assert np.isnan(standing["speed"])
    assert np.isnan(standing["density"])


def test_flow_density_plots_the_known_points(detectors: pd.DataFrame) -> None:
    ax = flow_density(detectors)
    scatter = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert len(scatter) == 1
    expected = detector_density(detectors).dropna()
    np.testing.assert_allclose(scatter[0].get_offsets(), expected[["density", "flow"]])
    np.testing.assert_allclose(np.asarray(scatter[0].get_array()), [0.5, 0.5])  # x [km]


# --------------------------------------------------------------------------- trips
def test_trip_table_counts_and_times_by_hand(trips: pd.DataFrame) -> None:
    table = trip_table(trips)
    assert list(table["origin"]) == ["main", "r0", "r1"]
    assert list(table["n"]) == [4, 1, 3]
    assert list(table["arrived"]) == [3, 0, 2]
    main, r0, r1 = (table.iloc[i] for i in range(3))
    assert main["median_travel_time"] == 120.0
    assert main["mean_travel_time"] == pytest.approx(140.0)
    assert main["mean_delay"] == pytest.approx(22.0)
    assert (r1["median_travel_time"], r1["mean_travel_time"], r1["mean_delay"]) == (
        160.0, 160.0, 25.0
    )  # fmt: skip
    assert r0[["median_travel_time", "mean_travel_time", "mean_delay"]].isna().all()


def test_travel_time_cdf_steps_through_every_arrived_trip(trips: pd.DataFrame) -> None:
    ax = travel_time_distribution(trips)
    lines = ax.get_lines()
    assert len(lines) == 2  # r0 has no arrived trip
    expected = {"main": [100.0, 120.0, 200.0], "r1": [150.0, 170.0]}
    for line, (origin, times) in zip(lines, expected.items(), strict=True):
        x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
        np.testing.assert_allclose(x, times)
        np.testing.assert_allclose(y, np.arange(1, len(times) + 1) / len(times))
        assert y[-1] == 1.0
        label = f"{origin} (n = {len(times)}, median {np.median(times):.0f} s)"
        assert line.get_label() == label
    legend = ax.get_legend()
    assert legend is not None
    assert [t.get_text() for t in legend.get_texts()] == [ln.get_label() for ln in lines]


def test_figures_of_empty_tables_draw_notes(trips: pd.DataFrame) -> None:
    empty_grid = one_vehicle_grid().iloc[:0]
    assert not speed_heatmap(empty_grid).collections
    assert not flow_density(pd.DataFrame([detector_row(0.0, 0, 0.0, [])])).collections
    ax = new_figure(4, 3).add_subplot()
    assert travel_time_distribution(trips.iloc[[2, 5]], ax) is ax
    assert not ax.get_lines()
    assert [t.get_text() for t in ax.texts] == ["no arrived trips"]


# --------------------------------------------------------------------------- output
def test_write_corridor_figures_writes_pngs_and_replaces_them(
    tmp_path: Path, detectors: pd.DataFrame, trips: pd.DataFrame
) -> None:
    out = tmp_path / "new" / "figs"
    paths = write_corridor_figures(one_vehicle_grid(), detectors, trips, out)
    assert paths == [out / name for name in FIGURE_FILES]
    assert [p.name for p in paths] == ["speed_heatmap.png", "flow_density.png", "travel_times.png"]
    for path in paths:
        assert path.read_bytes().startswith(PNG)
        height, width, _ = imread(path).shape
        assert width > 600
        assert height > 400
    again = write_corridor_figures(one_vehicle_grid(), detectors, trips.iloc[:3], out)
    assert again == paths
    assert sorted(p.name for p in out.iterdir()) == sorted(FIGURE_FILES)  # no temporary files


def test_corridor_report_embeds_figures_and_the_trip_table(
    tmp_path: Path, detectors: pd.DataFrame, trips: pd.DataFrame
) -> None:
    trips = trips.assign(origin=trips["origin"].replace({"r1": "<r&1>"}))
    page = corridor_report_html(one_vehicle_grid(), detectors, trips, tmp_path)
    assert page == tmp_path / "corridor.html"
    text = page.read_text(encoding="utf-8")
    assert text.count('src="data:image/png;base64,') == 3
    assert "<r&1>" not in text
    assert "&lt;r&amp;1&gt;" in text
    table = re.search(r'<table id="trips">.*?</table>', text, flags=re.S)
    assert table is not None
    rows = re.findall(r"<tr>(.*?)</tr>", table.group(0), flags=re.S)
    cells = [re.findall(r"<td[^>]*>(.*?)</td>", row) for row in rows[1:]]
    # the mainline first, then the ramps in name order ("<" sorts before "r")
    assert cells[0] == ["main", "4", "3", "120", "140", "22"]
    assert cells[1] == ["&lt;r&amp;1&gt;", "3", "2", "160", "160", "25"]
    assert cells[2] == ["r0", "1", "0", "—", "—", "—"]
    assert "git revision" in text
    assert not re.search(r"(src|href)=\"(https?:)?//", text)  # loads nothing
