"""Static figures (hcomc.viz): built from real short runs, written as PNG/SVG/PDF, inspected."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import LineCollection, QuadMesh
from matplotlib.contour import ContourSet
from matplotlib.figure import Figure
from matplotlib.image import imread

from hcomc.config import load_config
from hcomc.control.report import plan_report
from hcomc.experiments.tables import LABELS
from hcomc.metrics import KEY_ROLES, road_of
from hcomc.sim.engine import Simulation, simulate
from hcomc.sim.log import SimulationLog
from hcomc.viz.animation import animate
from hcomc.viz.common import (
    ALLOWED_FORMATS,
    configuration_label,
    key_group,
    save_figure,
    shade_zones,
)
from hcomc.viz.figures import (
    contour_figure,
    metrics_figure,
    pareto_figure,
    timespace_figure,
    trajectories_figure,
)
from hcomc.viz.inputs import FIGURE_KINDS, load_reports, load_runs, make_figure
from hcomc.viz.scene.frame import RoadScene
from hcomc.viz.smoothing import adaptive_smoothing

CONTROLLERS = {"FIFO": "fifo", "Game": "game", "HCOMC": "hcomc"}
DURATION = 40.0  # [s] measured after the warm-up; the C2 seed-0 merges end near t = 25 s
SEED = 0  # every controller's VR merges within DURATION


# --------------------------------------------------------------------------- data
@pytest.fixture(scope="module")
def logs() -> dict[str, SimulationLog]:
    """Short C2 runs of :data:`SEED` with each controller (same traffic: common random
    numbers)."""
    return {
        label: simulate(
            load_config("C2", duration=DURATION, control={"controller": controller}), seed=SEED
        )
        for label, controller in CONTROLLERS.items()
    }


@pytest.fixture(scope="module")
def reports() -> dict[str, dict[str, Any]]:
    """Plan reports of the first C2 decision of :data:`SEED` by each optimiser."""
    out = {}
    for opt in ("nsga2", "pso", "sa"):
        config = load_config("C2", control={"controller": "hcomc", "optimizer": opt})
        sim = Simulation(config, seed=SEED)
        plan = sim.run_until_plan()
        assert plan is not None
        out[opt] = plan_report(sim, plan)
    return out


@pytest.fixture(scope="module")
def runs() -> pd.DataFrame:
    """A small synthetic runs table: 2 conditions x 3 configurations x 4 seeds."""
    rng = np.random.default_rng(0)
    rows = []
    for cond in ("C1", "C2"):
        for conf in ("FIFO", "Game", "HCOMC"):
            for seed in range(4):
                rows.append(
                    {
                        "condition": cond,
                        "configuration": conf,
                        "seed": seed,
                        "critical_distance": rng.uniform(30, 90),
                        "average_acceleration": rng.uniform(0.05, 0.2),
                        "stabilisation_time": rng.uniform(20, 30),
                        "lsrv": rng.uniform(2000, 8000),
                        "fuel": rng.uniform(2.5, 4.5),
                    }
                )
    return pd.DataFrame(rows)


def check_files(fig: Figure, tmp_path: Path, name: str, min_std: float = 0.05) -> None:
    """Write PNG, SVG and PDF and check they are plausible, non-blank images."""
    paths = {ext: save_figure(fig, tmp_path / "figs" / f"{name}{ext}") for ext in ALLOWED_FORMATS}
    assert paths[".png"].stat().st_size > 10_000
    assert paths[".svg"].stat().st_size > 10_000
    assert paths[".pdf"].stat().st_size > 5_000
    assert paths[".svg"].read_text(encoding="utf-8").lstrip().startswith("<?xml")
    assert paths[".pdf"].read_bytes().startswith(b"%PDF")
    img = imread(paths[".png"])
    assert img.ndim == 3
    assert img.shape[0] > 400
    assert img.shape[1] > 600
    assert float(img[..., :3].std()) > min_std  # not a blank canvas
    assert not list((tmp_path / "figs").glob(".*.tmp"))  # no temporary file left behind


# --------------------------------------------------------------------------- figures
def test_contour_figure(logs: dict[str, SimulationLog], tmp_path: Path) -> None:
    fig = contour_figure(logs)
    n = len(logs)
    assert len(fig.axes) == 2 * n + 1  # panels + shared colour bar
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 2 * n
    meshes = [c for ax in panels for c in ax.collections if isinstance(c, QuadMesh)]
    assert len(meshes) == 2 * n
    assert len({m.norm.vmin for m in meshes}) == 1
    assert len({m.norm.vmax for m in meshes}) == 1
    contours = [c for ax in panels for c in ax.collections if isinstance(c, ContourSet)]
    assert contours
    titles = [ax.get_title() for ax in panels]
    assert titles[:2] == ["FIFO · lane 2", "Game · lane 2"]
    assert "HCOMC · lane 1" in titles
    assert all(ax.get_xlabel() == "position x [m]" for ax in panels[n:])
    assert fig.get_suptitle().endswith(f"C2 · seed {SEED}")
    check_files(fig, tmp_path, "contour")


def test_contour_figure_raw_bins(logs: dict[str, SimulationLog]) -> None:
    """smooth=False draws the binned field itself: most bins of sparse traffic are empty."""
    fig = contour_figure({"HCOMC": logs["HCOMC"]}, smooth=False)
    mesh = next(c for c in fig.axes[0].collections if isinstance(c, QuadMesh))
    data = np.ma.getmaskarray(mesh.get_array())
    assert data.mean() > 0.5


def test_timespace_figure(logs: dict[str, SimulationLog], tmp_path: Path) -> None:
    log = logs["HCOMC"]
    fig = timespace_figure(log)
    assert len(fig.axes) == 4  # lane 2, lane 1, ramp + colour bar
    lanes = fig.axes[:3]
    assert [ax.get_ylabel().split("\n")[0] for ax in lanes] == ["lane 2", "lane 1", "ramp"]
    for ax in lanes:
        assert any(isinstance(c, LineCollection) for c in ax.collections)
    texts = {t.get_text() for ax in lanes for t in ax.texts}
    present = {role for role, i in key_group(log).items() if i >= 0}
    assert len(present) >= 4
    assert present <= texts
    merge = [ln for ln in lanes[1].lines if ln.get_marker() == "*"]
    assert len(merge) == 1
    check_files(fig, tmp_path, "timespace")


def test_trajectories_figure(logs: dict[str, SimulationLog], tmp_path: Path) -> None:
    fig = trajectories_figure(logs["HCOMC"])
    assert len(fig.axes) == 3
    ax_path, ax_v, ax_a = fig.axes
    assert ax_v.get_ylabel() == "speed v [m/s]"
    assert ax_a.get_ylabel() == "acceleration a [m/s²]"
    roles = [ln.get_label() for ln in ax_v.lines if ln.get_label() in KEY_ROLES]
    present = [role for role, i in key_group(logs["HCOMC"]).items() if i >= 0]
    assert sorted(roles) == sorted(present)
    assert {ln.get_label() for ln in ax_path.lines} >= {"VR", "VMC"}
    assert any(ln.get_label() == "planning $t_0$" for ln in ax_v.lines)
    check_files(fig, tmp_path, "trajectories")


def test_trajectories_figure_needs_a_plan() -> None:
    log = simulate(load_config("C2", duration=2.0), seed=1)
    with pytest.raises(ValueError, match="merge plan"):
        trajectories_figure(log)
    assert len(timespace_figure(log).axes) == 3  # no plan: still drawable; no ramp vehicle yet


def test_pareto_figure(reports: dict[str, dict[str, Any]], tmp_path: Path) -> None:
    fig = pareto_figure(reports)
    assert len(fig.axes) == 3
    for ax in fig.axes:
        stars = [ln for ln in ax.lines if ln.get_marker() == "*"]
        assert len(stars) == 1
        assert "Eq. 19" in stars[0].get_label()
        chosen = reports["nsga2"]["chosen"]
        x, y = stars[0].get_xdata()[0], stars[0].get_ydata()[0]
        assert (x, y) in {(chosen[a], chosen[b]) for a in chosen for b in chosen if a != b}
        labels = {ln.get_label() for ln in ax.lines}
        assert {"PSO chosen", "SA chosen"} <= labels
        assert ax.collections  # the Pareto scatter
    assert any("safety gate" in ln.get_label() for ln in fig.axes[0].lines)
    check_files(fig, tmp_path, "pareto")


def test_pareto_figure_draws_the_configured_safety_gate(reports: dict[str, dict[str, Any]]):
    """The gate comes from the report's config (one home: control.safety_threshold)."""
    assert reports["nsga2"]["safety_threshold"] == 4.0
    moved = {k: {**r, "safety_threshold": 2.5} for k, r in reports.items()}
    gate = [ln for ln in pareto_figure(moved).axes[0].lines if "safety gate" in ln.get_label()]
    assert "2.5" in gate[0].get_label()
    old = {
        k: {key: v for key, v in r.items() if key != "safety_threshold"} for k, r in reports.items()
    }
    with pytest.raises(ValueError, match="safety_threshold"):
        pareto_figure(old)


def test_metrics_figure(runs: pd.DataFrame, tmp_path: Path) -> None:
    fig = metrics_figure(runs)
    axes = [ax for ax in fig.axes if ax.axison]
    assert len(axes) == len(LABELS) == 5
    assert [ax.get_ylabel() for ax in axes] == list(LABELS.values())
    for ax in axes:
        assert len(ax.patches) == 2 * 3  # conditions x configurations
        assert [t.get_text() for t in ax.get_xticklabels()] == ["C1", "C2"]
    check_files(fig, tmp_path, "metrics")


def test_metrics_figure_rejects_missing_columns(runs: pd.DataFrame) -> None:
    with pytest.raises(ValueError, match="lsrv"):
        metrics_figure(runs.drop(columns="lsrv"))


# --------------------------------------------------------------------------- common
def test_save_figure_rejects_other_extensions(tmp_path: Path) -> None:
    fig = Figure()
    fig.add_subplot().plot([0, 1], [0, 1])
    with pytest.raises(ValueError, match=r"'\.jpg'; allowed: \.png, \.svg, \.pdf"):
        save_figure(fig, tmp_path / "a.jpg")
    assert not list(tmp_path.iterdir())
    path = save_figure(fig, tmp_path / "deep" / "dir" / "A.PNG")  # case-insensitive; mkdir -p
    assert path.is_file()


def test_save_figure_is_deterministic(tmp_path: Path) -> None:
    fig = Figure()
    fig.add_subplot().plot([0, 1], [1, 0])
    for ext in ALLOWED_FORMATS:
        a = save_figure(fig, tmp_path / f"a{ext}").read_bytes()
        b = save_figure(fig, tmp_path / f"b{ext}").read_bytes()
        assert a == b, ext


def test_road_geometry_and_zones(logs: dict[str, SimulationLog]) -> None:
    road = road_of(logs["FIFO"])
    assert (road.accel_lane_start, road.accel_lane_end, road.control_zone_start) == (
        700.0,
        950.0,
        400.0,
    )
    ax = Figure().add_subplot()
    shade_zones(ax, road)
    assert {p.get_label() for p in ax.patches} == {"control zone", "acceleration lane"}
    assert configuration_label(logs["Game"]) == "Game"


def test_a_log_without_road_geometry_is_refused_everywhere(
    logs: dict[str, SimulationLog], tmp_path: Path
) -> None:
    """One reader of the geometry: no figure or animation draws a run on a default road."""
    log = copy.copy(logs["HCOMC"])
    log.meta = {k: v for k, v in log.meta.items() if k != "config"}
    builders = [
        lambda: contour_figure({"HCOMC": log}),
        lambda: timespace_figure(log),
        lambda: trajectories_figure(log),
        lambda: RoadScene(log, (0.0, 1000.0)),
        lambda: animate(log, tmp_path / "a.gif"),
    ]
    for build in builders:
        with pytest.raises(ValueError, match="road geometry is missing"):
            build()
    assert not (tmp_path / "a.gif").exists()


# --------------------------------------------------------------------------- smoothing
def test_adaptive_smoothing_constant_and_empty() -> None:
    x_edges, t_edges = np.arange(0.0, 501.0, 10.0), np.arange(0.0, 30.5, 0.5)
    V = np.full((t_edges.size - 1, x_edges.size - 1), np.nan)
    assert np.isnan(adaptive_smoothing(x_edges, t_edges, V)).all()
    V[::10, :] = 25.0  # sparse streaks of a constant speed
    out = adaptive_smoothing(x_edges, t_edges, V)
    finite = np.isfinite(out)
    assert finite.mean() > 0.8
    np.testing.assert_allclose(out[finite], 25.0, rtol=1e-9)
    with pytest.raises(ValueError, match="shape"):
        adaptive_smoothing(x_edges[:-1], t_edges, V)


# --------------------------------------------------------------------------- inputs
def test_make_figure_from_files(
    logs: dict[str, SimulationLog],
    reports: dict[str, dict[str, Any]],
    runs: pd.DataFrame,
    tmp_path: Path,
) -> None:
    assert set(FIGURE_KINDS) == {"contour", "timespace", "trajectories", "pareto", "metrics"}
    for label, log in logs.items():
        (tmp_path / label).mkdir()
        log.save(tmp_path / label / "log.npz")
    fig = make_figure("contour", [tmp_path / label for label in logs])
    assert [ax.get_title() for ax in fig.axes[:3]] == [f"{k} · lane 2" for k in logs]
    assert len(make_figure("timespace", [tmp_path / "HCOMC" / "log.npz"]).axes) == 4
    for opt, rep in reports.items():
        (tmp_path / f"{opt}.json").write_text(json.dumps(rep), encoding="utf-8")
    loaded = load_reports([tmp_path / f"{opt}.json" for opt in reports])
    assert list(loaded) == ["nsga2", "pso", "sa"]
    runs.to_parquet(tmp_path / "runs.parquet")
    assert len(load_runs(tmp_path)) == len(runs)
    assert len([ax for ax in make_figure("metrics", [tmp_path]).axes if ax.axison]) == 5


def test_make_figure_errors(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown figure kind 'heat'; allowed: contour"):
        make_figure("heat", [tmp_path])
    with pytest.raises(ValueError, match=r"holds no log\.npz"):
        make_figure("timespace", [tmp_path])
    with pytest.raises(ValueError, match="exactly one input"):
        make_figure("trajectories", [tmp_path, tmp_path])
    with pytest.raises(ValueError, match="needs a runs table"):
        make_figure("metrics", ["C2"])
    (tmp_path / "x.json").write_text("[1, 2]", encoding="utf-8")
    with pytest.raises(ValueError, match="holds no plan report"):
        load_reports([tmp_path / "x.json"])


# --------------------------------------------------------------------------- isolation
def test_core_modules_do_not_import_matplotlib() -> None:
    code = (
        "import sys, hcomc.cli, hcomc.sim.engine, hcomc.control.hierarchical.controller; "
        "import hcomc.viz; "
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_controller_logs_are_the_runs_of_those_configurations() -> None:
    """Fig. 2's runs are the runner's: FIFO and Game plan once (FIFO-R, Game-R replan) and the
    caller's overrides (``hcomc reproduce --set``) apply to every run."""
    from hcomc.experiments.runner import RunSpec, make_simulation
    from hcomc.viz.inputs import controller_logs

    overrides = {"duration": 40.0, "demand": {"cav_penetration": 0.8}}
    logs = controller_logs("C2", seed=3, configurations=("FIFO", "Game"), overrides=overrides)
    for label, log in logs.items():
        spec = RunSpec("C2", label, 3, overrides)
        config = load_config("C2", **spec.config_overrides())
        assert config.control.replan_period == 0.0  # as published
        assert config.demand.cav_penetration == 0.8
        ours = make_simulation(config, 3, "hcomc")
        ours.run()
        np.testing.assert_array_equal(log.x, ours.log.x)
        np.testing.assert_array_equal(log.t, ours.log.t)
        assert log.t[-1] <= 40.0 + 1e-9 < 60.0
