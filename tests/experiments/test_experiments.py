"""Experiment grid, summaries, claims and the reproduce command."""

from __future__ import annotations

import json
import math
from functools import partial

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments.claims import claims
from hcomc.experiments.runner import ALL_CONFIGURATIONS, RunSpec, grid, run_grid
from hcomc.experiments.tables import mean_ci, paper_table, summary

SHORT = {"duration": 60.0}


def test_grid_is_the_ordered_cartesian_product():
    specs = grid(["C1", "C2"], ["FIFO", "HCOMC"], [3, 5])
    assert [(s.condition, s.configuration, s.seed) for s in specs] == [
        ("C1", "FIFO", 3), ("C1", "FIFO", 5), ("C1", "HCOMC", 3), ("C1", "HCOMC", 5),
        ("C2", "FIFO", 3), ("C2", "FIFO", 5), ("C2", "HCOMC", 3), ("C2", "HCOMC", 5),
    ]  # fmt: skip
    spec = RunSpec("C1", "HCOMC-SA", 0, {"control": {"budget": 100}})
    control = {"budget": 100, "controller": "hcomc", "optimizer": "sa", "replan_period": 0.0}
    assert spec.config_overrides()["control"] == control  # plans once, as published
    replanning = RunSpec("C1", "HCOMC-R", 0).config_overrides()["control"]
    assert replanning == {"controller": "hcomc", "optimizer": "nsga2", "replan_period": 1.0}


def test_mean_ci_matches_the_t_interval():
    x = np.array([1.0, 2.0, 4.0, 7.0])
    mean, half, n = mean_ci(np.append(x, np.nan))
    assert (mean, n) == (3.5, 4)
    assert half == pytest.approx(stats.t.ppf(0.975, 3) * x.std(ddof=1) / 2.0)
    assert np.isnan(mean_ci([np.nan])[0])


def _synthetic_runs() -> pd.DataFrame:
    """Three seeds of C1 where HCOMC's critical distance beats FIFO in two."""
    rows = []
    for seed, (h, f) in enumerate([(120.0, 100.0), (90.0, 110.0), (130.0, 100.0)]):
        for conf, cd in (("HCOMC", h), ("FIFO", f)):
            rows.append({"condition": "C1", "configuration": conf, "seed": seed,
                         "critical_distance": cd, "average_acceleration": 0.02,
                         "stabilisation_time": 10.0, "lsrv": 5.0, "fuel": 8.0,
                         "mode": "longitudinal" if seed else "lateral"})  # fmt: skip
    return pd.DataFrame(rows)


def test_claims_count_paired_seeds():
    table = claims(_synthetic_runs()).set_index("claim")
    row = table.loc["HCOMC critical distance higher than FIFO"]
    assert (row["holds"], row["n"]) == (2, 3)
    assert row["median_diff"] == 20.0  # paired differences 20, -20, 30
    tie = table.loc["HCOMC fuel lower than FIFO"]
    assert (tie["holds"], tie["n"]) == (0, 3)  # equal values do not count as better
    mode = table.loc["HCOMC chooses longitudinal cooperation"]
    assert (mode["holds"], mode["n"]) == (2, 3)


def test_summary_and_paper_table_layout():
    runs = _synthetic_runs()
    s = summary(runs).set_index(["condition", "configuration"])
    assert s.loc[("C1", "HCOMC"), "critical_distance"] == pytest.approx(340.0 / 3)
    t3 = paper_table(runs, "III")
    assert list(t3["Model"]) == ["FIFO", "HCOMC"]
    assert t3.iloc[1]["Crit. Dist. [m]"].endswith("(114.21)")


def test_results_identical_with_one_and_two_workers():
    specs = grid(["C1"], ["FIFO", "HCOMC"], [0, 1], SHORT)
    # tasks queued behind the runs; one fails: its exception is handed over, the rows returned
    after = [partial(math.hypot, 3.0, 4.0), partial(pow, 2, 10), partial(math.sqrt, -1.0)]
    done: dict[int, dict[int, object]] = {1: {}, 2: {}}
    frames = {
        n: run_grid(specs, workers=n, after=after, on_after=done[n].__setitem__).drop(
            columns=["wall_s", "decision_ms"]
        )
        for n in (1, 2)
    }
    one, two = frames[1], frames[2]
    pd.testing.assert_frame_equal(one, two)
    for n in (1, 2):
        failed = done[n].pop(2)
        assert isinstance(failed, ValueError)
        assert "math domain error" in str(failed)
    assert done[1] == done[2] == {0: 5.0, 1: 1024}
    assert set(one["configuration"]) == {"FIFO", "HCOMC"}
    assert one.groupby("seed")["key_vehicles"].nunique().eq(1).all()  # same vehicles
    # (HCOMC, seed 1) leaves VR waiting at the acceleration-lane end within these 60 s
    assert one.loc[one["configuration"] == "FIFO", "critical_distance"].notna().all()


def test_run_command_json():
    result = CliRunner().invoke(app, ["run", "C2", "--controller", "game", "--seeds", "2",
                                      "--workers", "1", "--json"])  # fmt: skip
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert [r["seed"] for r in rows] == [0, 1]
    assert all(r["configuration"] == "Game" for r in rows)
    for key in ("critical_distance", "average_acceleration", "stabilisation_time", "lsrv",
                "fuel", "min_ttc", "max_drac", "pet", "collisions", "mode", "decision_ms",
                "wall_s"):  # fmt: skip
        assert key in rows[0]


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["run", "C1", "--controller", "magic"], "'--controller' = 'magic'"),
        (["run", "C1", "--controller", "hcomc", "--optimizer", "ga"], "'--optimizer' = 'ga'"),
        (["run", "C1", "--controller", "fifo", "--seeds", "0"], "'--seeds' = 0"),
        (["run", "C9", "--controller", "fifo"], "unknown preset 'C9'"),
        (["reproduce", "--seeds", "0"], "'--seeds' = 0"),
        (["reproduce", "--workers", "0"], "'--workers' = 0"),
    ],
)
def test_bad_experiment_input(args, fragment, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # default output paths must not meet a run left in the cwd
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2
    assert fragment in result.stderr
    assert "Traceback" not in result.output


@pytest.mark.slow
def test_reproduce_writes_every_output(tmp_path):
    result = CliRunner().invoke(app, ["reproduce", "--seeds", "1", "--workers", "2",
                                      "--out", str(tmp_path)])  # fmt: skip
    assert result.exit_code == 0, result.output
    for name in ("runs.csv", "runs.parquet", "table2.md", "table3.md", "claims.csv",
                 "paper_scenario.csv", "report.html"):  # fmt: skip
        assert (tmp_path / name).stat().st_size > 100, name
    report = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert report.count("data:image/png;base64,") == 2  # Fig. 2 (drawn by a worker), metrics
    assert "Fig. 2: Condition 2, seed 0" in report
    runs = pd.read_parquet(tmp_path / "runs.parquet")
    assert len(runs) == 5 * len(ALL_CONFIGURATIONS)
    assert (pd.read_csv(tmp_path / "runs.csv")["seed"] == 0).all()
    scenario = pd.read_csv(tmp_path / "paper_scenario.csv")
    assert len(scenario) == 5 * len(ALL_CONFIGURATIONS)  # one per condition x configuration
    assert len(list((tmp_path / "manifests").glob("*.json"))) == len(runs) + len(scenario)
    counted = f"{len(runs)} seeded runs"  # the same count on the console and in the report
    done = len(runs) + len(scenario)
    assert f"runs: {done}/{done} (100 %)" in result.stderr  # progress, off a terminal
    assert f"{counted} and {len(scenario)} of the paper scenario" in " ".join(result.stdout.split())
    assert f"{counted} · conditions" in report
    claims_csv = pd.read_csv(tmp_path / "claims.csv")
    assert (claims_csv["n"] <= 1).all()
    for col in ("median_diff", "ci_low", "ci_high", "paper", "uniform"):
        assert col in claims_csv
    for title in ("Table II", "Table III", "Paper scenario", "Claims"):
        assert title in result.stdout
    for col in ("sequence", "replans", "eq19_branch"):
        assert col in runs
    assert set(runs["sequence"]) <= {"ahead", "behind", ""}
    assert (runs.loc[runs["configuration"].isin(["FIFO", "Game"]), "replans"] == 0).all()
    # a second run into the same directory is refused before anything runs
    before = (tmp_path / "runs.csv").read_bytes()
    again = CliRunner().invoke(app, ["reproduce", "--seeds", "1", "--out", str(tmp_path)])
    assert again.exit_code == 2
    assert "--force" in again.stderr
    assert (tmp_path / "runs.csv").read_bytes() == before


def test_reproduce_set_is_validated_before_anything_runs(tmp_path):
    bad = CliRunner().invoke(
        app, ["reproduce", "--out", str(tmp_path), "--set", "control.safety_emergency_decel=99"]
    )
    assert bad.exit_code == 2
    assert "control.safety_emergency_decel" in bad.stderr
    assert not (tmp_path / "runs.csv").exists()
