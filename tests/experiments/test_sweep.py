"""Sweeps: the same table on any backend, resumable, values from base, clear errors."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments import run_store, workers
from hcomc.experiments import sweep as sweep_mod
from hcomc.experiments.run_store import run_key
from hcomc.experiments.sweep import expand, load_sweep, run_sweep

SPEC = """
name = "tiny"
base = "C1"
configurations = ["FIFO", "HCOMC"]
seeds = 2
duration = 30.0
[grid]
mean_headway_main_1 = [5.0]
mean_headway_main_2 = [3.0, 5.0]
cav_penetration = [0.9]
"""


@pytest.fixture
def spec_file(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(SPEC)
    return path


def test_expand_is_the_grid_product(spec_file):
    runs = expand(load_sweep(spec_file))
    assert len(runs) == 2 * 2 * 2
    assert [r.overrides["demand"]["mean_headway_main_2"] for r in runs[::4]] == [3.0, 5.0]
    assert len({run_key(r) for r in runs}) == len(runs)


@pytest.mark.slow
def test_local_pool_and_dask_cluster_give_identical_tables(spec_file, tmp_path):
    distributed = pytest.importorskip("distributed")
    spec = load_sweep(spec_file)
    local = run_sweep(spec, tmp_path / "local", workers=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:  # fmt: skip
        remote = run_sweep(spec, tmp_path / "dask", scheduler=cluster.scheduler_address)
    serial = run_sweep(spec, tmp_path / "serial", workers=1)
    pd.testing.assert_frame_equal(local, remote)
    pd.testing.assert_frame_equal(local, serial)
    assert len(local) == 8
    assert (tmp_path / "dask" / "summary.csv").stat().st_size > 0


_RUN_BATCH = workers.run_batch


def _dying_run_batch(runs, threads=None):
    """Kill the worker process the first time it is called (marker file), then behave."""
    marker = Path(os.environ["HCOMC_TEST_MARKER"])
    if not marker.exists():
        marker.write_text("died once")
        os._exit(13)
    return _RUN_BATCH(runs, threads=threads)


def test_a_dying_worker_has_its_runs_retried(spec_file, tmp_path, monkeypatch):
    monkeypatch.setenv("HCOMC_TEST_MARKER", str(tmp_path / "marker"))
    monkeypatch.setattr(workers, "run_batch", _dying_run_batch)
    table = run_sweep(load_sweep(spec_file), tmp_path / "out", workers=2)
    assert (tmp_path / "marker").exists()
    assert len(table) == 8
    assert len(list((tmp_path / "out" / "parts").glob("*.parquet"))) == 8


@pytest.mark.slow
def test_killed_sweep_resumes_without_losing_or_repeating_runs(spec_file, tmp_path):
    out = tmp_path / "store"
    cmd = [sys.executable, "-m", "hcomc", "sweep", str(spec_file), "--out", str(out),
           "--workers", "1"]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)  # fmt: skip
    parts = out / "parts"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(parts.glob("*.parquet"))) < 2:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in parts.glob("*.parquet")}
    assert 2 <= len(before) < 8
    for part in parts.glob("*.parquet"):  # every part is complete (written, then renamed)
        assert len(pd.read_parquet(part)) == 1
    result = CliRunner().invoke(app, ["sweep", str(spec_file), "--out", str(out),
                                      "--workers", "2"])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert f"{8 - len(before)} new, {len(before)} already done" in result.stdout
    assert "sweep: 8/8 (100 %)" in result.stderr
    after = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in parts.glob("*.parquet")}
    assert len(after) == 8
    assert not list(parts.glob("*.tmp*"))  # the killed run's temporary files are gone
    for name, stamp in before.items():
        assert after[name] == stamp  # not recomputed
    table = pd.read_parquet(out / "sweep.parquet")
    assert len(table) == 8
    assert not table.duplicated(["mean_headway_main_2", "configuration", "seed"]).any()


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        (SPEC + "colour = 'red'\n", "unknown key 'grid.colour'"),
        (SPEC.replace("cav_penetration = [0.9]", "cav_penetration = []"), "grid.cav_penetration"),
        (
            SPEC.replace("cav_penetration = [0.9]", "cav_penetration = [1.5]"),
            "demand.cav_penetration",
        ),
        (SPEC.replace('"FIFO", ', '"LIFO", '), "configurations"),
    ],
)
def test_bad_spec_is_rejected_before_any_run(tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = CliRunner().invoke(app, ["sweep", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert fragment in result.stderr
    assert "Traceback" not in result.output
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_unreachable_scheduler_is_a_clear_error(spec_file, tmp_path):
    args = ["sweep", str(spec_file), "--scheduler", "tcp://127.0.0.1:9"]
    result = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "no Dask scheduler reachable" in result.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_flow_sweep_reports_throughput_and_delay(tmp_path):
    path = tmp_path / "flow.toml"
    path.write_text(SPEC.replace('seeds = 2', 'seeds = 1\nramp = "flow"\nramp_mean_headway = 8.0')
                    .replace("duration = 30.0", "duration = 120.0")
                    .replace("[3.0, 5.0]", "[5.0]").replace('"FIFO", ', ""))  # fmt: skip
    table = run_sweep(load_sweep(path), tmp_path / "o", workers=1)
    row = table.iloc[0]
    assert row["plans"] >= 5  # every ramp vehicle entering the control zone is planned
    assert 500 < row["throughput"] < 5000
    assert row["ramp_delay"] > -5.0


# --------------------------------------------------------------------------- resolved values
def _spec(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("base", "expected"),
    [
        ("C5", {"mean_headway_main_2": 5.0, "cav_penetration": 0.3}),
        ("C2", {"mean_headway_main_2": 7.0, "cav_penetration": 0.9}),
    ],
)
def test_keys_left_out_of_the_grid_come_from_base(tmp_path, base, expected):
    text = f"""
base = "{base}"
configurations = ["FIFO"]
seeds = 1
duration = 15.0
[grid]
mean_headway_main_1 = [4.0]
"""
    spec = load_sweep(_spec(tmp_path, text))
    table = run_sweep(spec, tmp_path / "o", workers=1)
    row = table.iloc[0]
    assert row["base"] == base
    assert row["condition"] == base
    assert row["mean_headway_main_1"] == 4.0
    for key, value in expected.items():
        assert row[key] == value
    assert row["ramp"] == "single"  # the base's, not a sweep default
    assert row["duration"] == 15.0
    manifest = json.loads(next((tmp_path / "o" / "manifests").glob("*.json")).read_text())
    demand = manifest["config"]["demand"]
    assert demand["cav_penetration"] == expected["cav_penetration"]  # what really ran
    assert demand["mean_headway_main_2"] == expected["mean_headway_main_2"]


def test_ramp_and_duration_come_from_a_base_file(tmp_path):
    base = tmp_path / "flowbase.toml"
    base.write_text('base = "C1"\nduration = 25.0\n[demand]\nramp = "flow"\n'
                    "ramp_mean_headway = 9.0\ncav_penetration = 0.6\n")  # fmt: skip
    text = """
base = "flowbase.toml"
configurations = ["FIFO"]
seeds = 1
[grid]
mean_headway_main_2 = [6.0]
"""
    spec = load_sweep(_spec(tmp_path, text))
    runs = expand(spec)
    assert len(runs) == 1
    config = run_store.resolved_config(runs[0])
    assert (config.demand.ramp, config.demand.ramp_mean_headway) == ("flow", 9.0)
    assert (config.duration, config.demand.cav_penetration) == (25.0, 0.6)
    assert config.demand.mean_headway_main_2 == 6.0
    row = sweep_mod._row(runs[0], {"seed": 0, "wall_s": 1.0}).iloc[0]
    assert (row["ramp"], row["ramp_mean_headway"], row["duration"]) == ("flow", 9.0, 25.0)
    assert (row["cav_penetration"], row["mean_headway_main_1"]) == (0.6, 5.0)
    assert "wall_s" not in row


def test_resumed_sweep_recomputes_runs_whose_config_or_version_changed(tmp_path, monkeypatch):
    base = tmp_path / "mybase.toml"
    base.write_text('base = "C1"\n')
    text = """
base = "mybase.toml"
configurations = ["FIFO"]
seeds = 2
duration = 15.0
[grid]
cav_penetration = [0.5]
"""
    spec_path = _spec(tmp_path, text)
    out = tmp_path / "store"
    args = ["sweep", str(spec_path), "--out", str(out), "--workers", "1"]
    first = CliRunner().invoke(app, args)
    assert first.exit_code == 0, first.output
    assert "2 new, 0 already done" in first.stdout
    again = CliRunner().invoke(app, args)
    assert "0 new, 2 already done" in again.stdout

    base.write_text('base = "C1"\n[hdv]\nmax_accel = 1.3\n')  # the base changes
    changed = CliRunner().invoke(app, args)
    assert changed.exit_code == 0, changed.output
    assert "0 new, 0 already done, 2 recomputed because the config" in changed.stdout
    assert "2 stored parts of other configs ignored" in changed.stdout
    assert len(list((out / "parts").glob("*.parquet"))) == 4  # old results kept, not mixed
    assert len(pd.read_parquet(out / "sweep.parquet")) == 2
    keys = [run_key(r) for r in expand(load_sweep(spec_path))]
    for key in keys:
        manifest = json.loads((out / "manifests" / f"{key}.json").read_text())
        assert manifest["config"]["hdv"]["max_accel"] == 1.3

    ours = run_store.code_stamp
    monkeypatch.setattr(run_store, "code_stamp", lambda: "another revision")  # the code changes
    status = sweep_mod.sweep_status(load_sweep(spec_path), out)
    assert (status.done, status.new, status.changed) == (0, 0, 2)
    monkeypatch.setattr(run_store, "code_stamp", ours)
    monkeypatch.setattr(run_store.hcomc, "__version__", "99.0")  # another release
    status = sweep_mod.sweep_status(load_sweep(spec_path), out)
    assert (status.done, status.new, status.changed) == (0, 0, 2)


def test_workers_with_a_scheduler_is_an_error(spec_file, tmp_path):
    args = ["sweep", str(spec_file), "--scheduler", "tcp://127.0.0.1:9", "--workers", "2"]
    result = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "'--workers' = 2 does not apply with '--scheduler'" in result.stderr
    assert not (tmp_path / "o").exists()


def test_sweep_engine_is_part_of_each_run_and_of_its_key(tmp_path):
    spec_file = tmp_path / "engine.toml"
    spec_file.write_text('base = "C1"\nseeds = 1\nconfigurations = ["FIFO"]\nengine = "sumo"\n')
    spec = load_sweep(spec_file)
    runs = expand(spec)
    assert {r.engine for r in runs} == {"sumo"}
    ours = expand(spec.model_copy(update={"engine": "hcomc"}))
    assert [run_key(a) for a in runs] != [run_key(b) for b in ours]  # never mixed on resume
