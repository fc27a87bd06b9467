"""``hcomc plot`` of corridor runs: figures from a ``simulate CORRIDOR --out`` directory or a
simulated corridor, checked against the run's CSV tables computed independently."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PathCollection, QuadMesh
from matplotlib.image import imread
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.viz.corridor import FIGURE_FILES, corridor_figure
from hcomc.viz.corridor_inputs import make_corridor_figure

runner = CliRunner()
DURATION = 120.0  # [s] of the corridor run the tests draw


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The --out directory of a short run of the corridor preset."""
    out = tmp_path_factory.mktemp("corridor-run")
    args = ["simulate", "corridor", "--duration", f"{DURATION:g}", "--seed", "1", "--out",
            str(out), "--json"]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def scenario_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The --out directory of a short scenario run (log.npz and detectors.csv)."""
    out = tmp_path_factory.mktemp("scenario-run")
    result = runner.invoke(app, ["simulate", "C2", "--duration", "5", "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


def short_corridor(tmp_path: Path, base: str, duration: float) -> Path:
    """A corridor TOML file: preset *base* with a shorter duration [s]."""
    path = tmp_path / f"{base}-short.toml"
    path.write_text(f'base = "{base}"\n[corridor]\nduration = {duration}\n', encoding="utf-8")
    return path


# --------------------------------------------------------------------------- figures
def test_heatmap_image_is_the_speed_of_every_grid_cell(run_dir: Path) -> None:
    fig = make_corridor_figure("speed_heatmap", [run_dir])
    (mesh,) = [c for c in fig.axes[0].collections if isinstance(c, QuadMesh)]
    grid = pd.read_csv(run_dir / "grid.csv")
    grid["kmh"] = 3.6 * grid["distance"] / grid["time"].where(grid["time"] > 0)
    expected = grid.pivot(index="x0", columns="t0", values="kmh")  # rows x, columns t
    assert expected.shape == (100, 2)  # 10 km in 100 m cells, 120 s in 60 s cells
    assert expected.notna().sum().sum() > 20  # vehicles in many cells
    plotted = np.ma.asarray(mesh.get_array()).reshape(expected.shape)
    np.testing.assert_array_equal(np.ma.getmaskarray(plotted), expected.isna().to_numpy())
    np.testing.assert_allclose(plotted.filled(np.nan), expected.to_numpy(), rtol=1e-12)


def test_flow_density_points_are_flow_over_speed_of_each_detector_interval(
    run_dir: Path,
) -> None:
    fig = make_corridor_figure("flow_density", [run_dir])
    (dots,) = [c for c in fig.axes[0].collections if isinstance(c, PathCollection)]
    det = pd.read_csv(run_dir / "detectors.csv")
    expected = []
    for (x, begin), rows in det[det["lane"] >= 0].groupby(["x", "begin"]):
        counted = rows[rows["count"] > 0]
        if counted.empty:
            continue
        # the cross-section's density is the sum of its lanes' q / v [veh/km]
        density = float((counted["flow"] / (3.6 * counted["harmonic_speed"])).sum())
        expected.append((x, begin, density, float(rows["flow"].sum())))
    assert len(expected) > 10
    points = np.array([(k, q) for *_, k, q in expected if np.isfinite(k)])
    np.testing.assert_allclose(dots.get_offsets(), points, rtol=1e-12)


def test_travel_time_lines_are_the_sorted_arrived_trips_per_origin(run_dir: Path) -> None:
    fig = make_corridor_figure("travel_times", [run_dir])
    lines = {ln.get_label().split()[0]: ln for ln in fig.axes[0].get_lines()}
    trips = pd.read_csv(run_dir / "trips.csv")
    arrived = trips[trips["outcome"] == "arrived"]
    assert len(arrived) > 0
    assert set(lines) == set(arrived["origin"])
    for origin, line in lines.items():
        times = np.sort(arrived.loc[arrived["origin"] == origin, "travel_time"].to_numpy())
        np.testing.assert_allclose(line.get_xdata(), times)
        np.testing.assert_allclose(line.get_ydata(), np.arange(1, times.size + 1) / times.size)


# --------------------------------------------------------------------------- command line
@pytest.mark.parametrize("name", FIGURE_FILES)
def test_plot_of_a_run_directory_is_the_figure_simulate_wrote(
    run_dir: Path, tmp_path: Path, name: str
) -> None:
    target = tmp_path / name
    kind = name.removesuffix(".png")
    result = runner.invoke(app, ["plot", str(run_dir), "--kind", kind, "--out", str(target)])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output
    assert target.stat().st_size > 10_000
    # the same drawing of the same tables as `hcomc simulate --out` made: the same pixels
    np.testing.assert_array_equal(imread(target), imread(run_dir / name))


def test_plot_writes_svg_and_pdf(run_dir: Path, tmp_path: Path) -> None:
    for name in ("heat.svg", "heat.pdf"):
        target = tmp_path / name
        args = ["plot", str(run_dir), "--kind", "speed_heatmap", "--out", str(target)]
        assert runner.invoke(app, args).exit_code == 0
        assert target.stat().st_size > 1_000


def test_plot_of_a_corridor_simulates_it_with_the_seed(tmp_path: Path) -> None:
    from hcomc.corridor import load_corridor
    from hcomc.metrics.corridor import simulate_corridor
    from hcomc.viz.common import save_figure

    source = short_corridor(tmp_path, "corridor", 30.0)
    target = tmp_path / "cli.png"
    args = ["plot", str(source), "--kind", "speed_heatmap", "--seed", "3", "--out", str(target)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    run = simulate_corridor(load_corridor(source, {}), seed=3)
    assert run.duration == 30.0
    direct = save_figure(corridor_figure("speed_heatmap", run.grid), tmp_path / "direct.png")
    np.testing.assert_array_equal(imread(target), imread(direct))


def test_a_corridor_of_the_papers_layout_is_drawn_by_the_scenario_kinds(tmp_path: Path) -> None:
    from hcomc.corridor import load_corridor
    from hcomc.corridor.engine import scenario_config, scenario_of

    source = short_corridor(tmp_path, "paper", 10.0)
    config = scenario_config(source, duration=8.0)
    assert config == scenario_of(load_corridor(source, {}), duration=8.0)
    assert (config.duration, config.road.length, config.road.ramp_start) == (8.0, 1500.0, 250.0)
    target = tmp_path / "ts.png"
    args = ["plot", str(source), "--kind", "timespace", "--seed", "1", "--out", str(target)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert target.stat().st_size > 10_000


def test_bad_corridor_input_is_a_one_line_error(
    run_dir: Path, scenario_dir: Path, tmp_path: Path
) -> None:
    partial = tmp_path / "partial"
    partial.mkdir()
    for name in ("corridor.toml", "detectors.csv"):
        shutil.copy(run_dir / name, partial / name)
    (partial / "trips.csv").write_text("id,depart\n1,0.0\n", encoding="utf-8")
    empty = tmp_path / "empty"
    empty.mkdir()
    cases = [
        ([run_dir, "--kind", "contour"], "'--kind' = 'contour' does not apply to corridor run"),
        ([run_dir, "--kind", "heatmap"], "'--kind' = 'heatmap' does not apply to corridor run"),
        (["corridor", "--kind", "timespace"], "'corridor', which runs as a corridor"),
        (["paper", "--kind", "speed_heatmap"], "'paper': it has the paper's layout"),
        ([scenario_dir, "--kind", "speed_heatmap"], "is not a corridor run (it has no corr"),
        ([scenario_dir / "log.npz", "--kind", "flow_density"], "is a file, not a corridor run"),
        (["C2", "--kind", "travel_times"], "'C2' is a scenario preset, not a corridor"),
        ([empty, "--kind", "travel_times"], "is not a corridor run"),
        ([partial, "--kind", "speed_heatmap"], f"corridor run '{partial}' has no grid.csv"),
        ([partial, "--kind", "travel_times"], "lacks the column(s) origin, outcome, travel_time"),
        ([run_dir, "--kind", "speed_heatmap", "--seed", "3"], "'--seed' = 3 applies only"),
        ([run_dir, "--kind", "speed", "--raw"], "'--raw' applies to --kind contour only"),
        ([run_dir, "--kind", "speed"], "allowed: contour, timespace, trajectories, pareto, "
         "metrics, heatmap, speed_heatmap, flow_density, travel_times"),
    ]  # fmt: skip
    for args, fragment in cases:
        target = tmp_path / "f.png"
        result = runner.invoke(app, ["plot", *map(str, args), "--out", str(target)])
        assert result.exit_code == 2, (args, result.output)
        assert result.stderr.startswith("error: "), result.stderr
        assert fragment in result.stderr, (args, result.stderr)
        assert result.stderr.count("\n") == 1  # one line, no traceback
        assert not target.exists()
