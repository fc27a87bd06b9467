"""``hcomc plot`` and ``hcomc animate`` from the command line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments.sweep import load_sweep, run_sweep

runner = CliRunner()


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("run")
    result = runner.invoke(
        app,
        [
            "simulate",
            "C2",
            "--controller",
            "hcomc",
            "--seed",
            "1",
            "--duration",
            "40",
            "--out",
            str(out),
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    return out


@pytest.mark.parametrize("kind", ["timespace", "trajectories", "contour"])
def test_plot_kinds_from_a_saved_run(run_dir, tmp_path, kind):
    target = tmp_path / f"{kind}.png"
    result = runner.invoke(app, ["plot", str(run_dir), "--kind", kind, "--out", str(target)])
    assert result.exit_code == 0, result.output
    pixels = imread(target)
    assert target.stat().st_size > 10_000
    assert pixels.std() > 0.05


@pytest.mark.slow
def test_heatmap_of_a_sweep(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text(
        'base = "C1"\nconfigurations = ["FIFO", "HCOMC"]\nseeds = 1\n'
        "duration = 30.0\n[grid]\ncav_penetration = [0.3, 0.9]\n"
    )
    run_sweep(load_sweep(spec), tmp_path / "sweep", workers=1)
    target = tmp_path / "heat.svg"
    result = runner.invoke(
        app,
        [
            "plot",
            str(tmp_path / "sweep"),
            "--kind",
            "heatmap",
            "--metric",
            "critical_distance",
            "--out",
            str(target),
        ],
    )
    assert result.exit_code == 0, result.output
    text = target.read_text()
    assert "HCOMC vs FIFO" in text
    bad = runner.invoke(
        app, ["plot", str(tmp_path / "sweep"), "--kind", "heatmap", "--metric", "beauty"]
    )
    assert bad.exit_code == 2
    assert "unknown metric 'beauty'" in bad.stderr


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["plot", "missing.npz", "--kind", "timespace"], "does not exist"),
        (["plot", "C2", "--kind", "sunset"], "'--kind' = 'sunset'"),
        (["plot", "C2", "--kind", "metrics"], "metrics"),
        (["animate", "missing.npz"], "does not exist"),
    ],
)
def test_bad_plot_input_is_a_clear_error(args, fragment, tmp_path):
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert fragment in result.stderr
    assert "Traceback" not in result.output


def test_animate_gif_and_bad_extension(run_dir, tmp_path):
    gif = tmp_path / "run.gif"
    result = runner.invoke(
        app, ["animate", str(run_dir / "log.npz"), "--out", str(gif), "--speedup", "10"]
    )
    assert result.exit_code == 0, result.output
    from PIL import Image

    with Image.open(gif) as image:
        assert image.n_frames > 10
        first = np.asarray(image.convert("RGB"))
        image.seek(image.n_frames - 1)
        assert not np.array_equal(first, np.asarray(image.convert("RGB")))
    bad = runner.invoke(
        app, ["animate", str(run_dir / "log.npz"), "--out", str(tmp_path / "run.avi")]
    )
    assert bad.exit_code == 2
    assert ".avi" in bad.stderr
    assert not (tmp_path / "run.avi").exists()


@pytest.mark.parametrize("command", ["plot", "animate"])
def test_an_existing_figure_is_kept_unless_forced(run_dir, tmp_path, command):
    target = tmp_path / ("fig.png" if command == "plot" else "run.gif")
    target.write_bytes(b"mine")
    argv = [command, str(run_dir if command == "plot" else run_dir / "log.npz")]
    argv += ["--kind", "timespace"] if command == "plot" else ["--speedup", "20"]
    refused = runner.invoke(app, [*argv, "--out", str(target)])
    assert refused.exit_code == 2
    assert f"option '--out' = '{target}': already exists" in refused.stderr
    assert target.read_bytes() == b"mine"
    forced = runner.invoke(app, [*argv, "--out", str(target), "--force"])
    assert forced.exit_code == 0, forced.output
    assert target.read_bytes() != b"mine"
