"""Corridors as conditions of ``hcomc run``, ``hcomc compare`` and ``hcomc sweep``.

The numbers are checked against independent computations: each run's corridor metrics
against pandas on the trips and merge events of ``simulate_corridor`` of the same corridor,
controller and seed (the configuration's meaning built by hand, not through the runner), the
paired effects against the pandas differences of the runs table, the sign test and Holm's
step-down method written out here, and a paper-layout corridor's rows against the runner on
the scenario the corridor becomes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ControlParams
from hcomc.corridor import load_corridor
from hcomc.experiments.comparison.effects import PREFERS, RUN_LEVEL, effects
from hcomc.experiments.comparison.success import merge_success
from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS, corridor_metrics
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.metrics.corridor import simulate_corridor

SHORT = """
[corridor]
name = "short"
duration = 600.0
seed = 0

[road]
lanes = 3
length = 2500.0
speed_limit = 33.3

[[road.on_ramps]]
id = "on1"
x = 500.0
accel_length = 250.0
control_zone_length = 300.0
ramp_length = 450.0

[[road.on_ramps]]
id = "on2"
x = 1500.0
accel_length = 250.0
control_zone_length = 300.0
ramp_length = 450.0

[demand.main]
flow = 3600.0
cav_share = 0.5

[demand.on1]
flow = 600.0
cav_share = 0.5

[demand.on2]
flow = 600.0
cav_share = 0.5
"""
"""A 2.5 km three-lane corridor with two on-ramps (not the paper's layout: it runs as a
corridor); in 120 s about 40 trips complete and about 40 ramp vehicles reach a zone."""

DURATION = 120.0
SEEDS = 3


def _invoke(*args: str) -> Any:
    return CliRunner().invoke(app, list(args))


@pytest.fixture(scope="module")
def corridor_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("corridor") / "short.toml"
    path.write_text(SHORT, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def compared(corridor_file: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """``hcomc compare --controllers none,fifo`` on the short corridor, 3 seeds, 120 s."""
    out = tmp_path_factory.mktemp("compare") / "cmp"
    result = _invoke("compare", "--controllers", "none,fifo", "--conditions", str(corridor_file),
                     "--seeds", str(SEEDS), "--set", f"corridor.duration={DURATION}",
                     "--workers", "1", "--out", str(out))  # fmt: skip
    assert result.exit_code == 0, result.output
    return out, result.stdout


def _simulated(path: Path, controller: str, seed: int, **control: Any) -> Any:
    """The run by hand: the corridor with ``controller`` (and ``control`` values) in its
    control table, simulated for seed ``seed``."""
    corridor = load_corridor(path, {"corridor.duration": DURATION})
    table = {**corridor.control.model_dump(), "controller": controller, **control}
    return simulate_corridor(
        corridor.model_copy(update={"control": ControlParams(**table)}), seed=seed
    )


def _expected(run: Any) -> dict[str, float]:
    """The corridor metrics of a run, written out in pandas."""
    trips, merges = run.trips, run.merges
    done = trips[trips.outcome.isin(["arrived", "missed_exit"]) & trips.travel_time.notna()]
    merged = merges[merges.merged]
    ttc = merges.min_ttc[np.isfinite(merges.min_ttc)]
    drac = merges.max_drac[np.isfinite(merges.max_drac)]
    return {
        "travel_time": done.travel_time.mean(),
        "travel_time_main": done[done.origin == "main"].travel_time.mean(),
        "delay": done.delay.mean(),
        "completed_trips": float(len(done)),
        "merged_share": merges.merged.mean(),
        "time_to_merge": merged.time_to_merge.mean(),
        "min_ttc_p05": np.percentile(ttc, 5),
        "ttc_below_1_5s_share": (merges.min_ttc < 1.5).mean(),
        "max_drac_p95": np.percentile(drac, 95),
        "collisions": float(run.collision_count),
        "fallbacks": float(merges.fallback.sum()),
    }


@pytest.fixture(scope="module")
def by_hand(corridor_file: Path) -> dict[tuple[str, int], Any]:
    """Every run of the comparison simulated by hand: "none" is no controller, "FIFO" is
    fifo planning once (replan_period 0, as the paper's FIFO)."""
    runs = {}
    for seed in range(SEEDS):
        runs["none", seed] = _simulated(corridor_file, "none", seed)
        runs["FIFO", seed] = _simulated(corridor_file, "fifo", seed, replan_period=0.0)
    return runs


def test_each_row_holds_the_metrics_of_its_own_simulation(compared, by_hand):
    out, _ = compared
    runs = pd.read_parquet(out / "runs.parquet")
    assert len(runs) == 2 * SEEDS  # one row per configuration and seed
    assert list(runs[["configuration", "seed"]].itertuples(index=False, name=None)) == [
        (conf, seed) for conf in ("none", "FIFO") for seed in range(SEEDS)
    ]
    assert set(runs["kind"]) == {"corridor"}
    assert set(runs["corridor"]) == {"short"}
    for row in runs.to_dict("records"):
        run = by_hand[row["configuration"], row["seed"]]
        for metric, value in _expected(run).items():
            assert row[metric] == pytest.approx(value, rel=1e-12, nan_ok=True), metric
        assert row["events"] == len(run.merges) > 20
        assert row["merged"] == bool(run.merges.merged.all())
        assert row["merged_events"] == int(run.merges.merged.sum())
    assert (runs["completed_trips"] > 10).all()  # travel times are of real trips
    assert runs.loc[runs["configuration"] == "FIFO", "plans"].gt(0).all()
    assert runs.loc[runs["configuration"] == "none", "plans"].eq(0).all()


def test_failed_merges_lower_the_share_and_never_drop_a_run(compared, by_hand):
    out, _ = compared
    runs = pd.read_parquet(out / "runs.parquet")
    assert not runs["merged"].any()  # at 120 s some ramp vehicle is always still merging
    assert (runs["merged_share"] < 1.0).all()
    found = pd.read_csv(out / "effects.csv", keep_default_na=False)
    assert (found["n"] == SEEDS).all()  # every seed is a pair although no run "merged"
    assert (found["excluded"] == 0).all()
    success = pd.read_csv(out / "success.csv")
    assert success["merged"].tolist() == [0, 0]
    assert success["runs"].tolist() == [SEEDS, SEEDS]


def _sign_p(lower: int, higher: int) -> float:
    n = lower + higher
    return 1.0 if n == 0 else min(1.0, 2 * stats.binom.cdf(min(lower, higher), n, 0.5))


def _holm(p: np.ndarray) -> np.ndarray:
    order = np.argsort(p)
    adjusted = np.empty_like(p)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (len(p) - rank) * p[i]))
        adjusted[i] = running
    return adjusted


def test_paired_effects_are_the_pandas_differences(compared):
    out, text = compared
    runs = pd.read_parquet(out / "runs.parquet")
    found = pd.read_csv(out / "effects.csv", keep_default_na=False)
    assert list(found["metric"]) == list(CORRIDOR_METRICS)  # every corridor metric, once
    assert set(zip(found["a"], found["b"], strict=True)) == {("FIFO", "none")}
    wide = runs.pivot(index="seed", columns="configuration")
    for row in found.to_dict("records"):
        metric = row["metric"]
        diff = np.array(wide[metric]["FIFO"] - wide[metric]["none"], dtype=np.float64)
        scale = np.maximum(1.0, np.maximum(wide[metric]["FIFO"].abs(), wide[metric]["none"].abs()))
        diff[np.abs(diff) <= 1e-9 * scale.to_numpy()] = 0.0
        assert row["median_diff"] == pytest.approx(np.median(diff), rel=1e-12, abs=1e-12)
        assert (row["a_lower"], row["a_higher"]) == ((diff < 0).sum(), (diff > 0).sum())
        assert row["mean_a"] == pytest.approx(wide[metric]["FIFO"].mean(), rel=1e-12)
        assert row["p_value"] == pytest.approx(_sign_p(row["a_lower"], row["a_higher"]))
        assert row["prefers"] == CORRIDOR_METRICS[metric].better == PREFERS[metric]
        assert row["verdict"] == "undecided"  # three seeds never decide
        assert row["favours"] == ""
    p = found["p_value"].to_numpy(np.float64)
    np.testing.assert_allclose(found["p_holm"].to_numpy(np.float64), _holm(p))
    assert "Travel time [s] ↓" in text
    assert "Merged share ↑" in text
    record = json.loads((out / "compare.json").read_text())
    assert record["kind"] == "corridor"
    assert record["corridors"][record["cells"][0]]["corridor"]["duration"] == DURATION
    assert record["git_revision"]
    assert record["hcomc_version"]
    assert (out / "report.html").is_file()
    assert (out / "success_pairs.csv").is_file()


def test_manifests_record_seed_corridor_version_and_revision(compared):
    out, _ = compared
    manifests = [json.loads(p.read_text()) for p in (out / "manifests").glob("*.json")]
    assert sorted((m["run"]["configuration"], m["seed"]) for m in manifests) == sorted(
        (conf, seed) for conf in ("none", "FIFO") for seed in range(SEEDS)
    )
    for manifest in manifests:
        corridor = manifest["corridor"]
        assert corridor["corridor"]["duration"] == DURATION
        assert corridor["control"]["controller"] == manifest["run"]["configuration"].lower()
        assert manifest["hcomc_version"]
        assert manifest["git_revision"]
        assert manifest["engine"] == "hcomc-corridor"
    fifo = next(m for m in manifests if m["run"]["configuration"] == "FIFO")
    assert fifo["corridor"]["control"]["replan_period"] == 0.0  # FIFO plans once
    assert fifo["controller"]["class"] == "hcomc.control.fifo:FIFOController"


def test_a_rerun_resumes_and_two_workers_give_the_same_table(compared, corridor_file, tmp_path):
    out, _ = compared
    args = ["compare", "--controllers", "none,fifo", "--conditions", str(corridor_file),
            "--seeds", str(SEEDS), "--set", f"corridor.duration={DURATION}"]  # fmt: skip
    again = _invoke(*args, "--workers", "1", "--out", str(out))
    assert again.exit_code == 0, again.output
    assert f"{2 * SEEDS} runs (0 new, {2 * SEEDS} already done)" in again.stdout
    two = _invoke(*args, "--workers", "2", "--out", str(tmp_path / "two"))
    assert two.exit_code == 0, two.output
    pd.testing.assert_frame_equal(
        pd.read_parquet(out / "runs.parquet"), pd.read_parquet(tmp_path / "two" / "runs.parquet")
    )
    pd.testing.assert_frame_equal(
        pd.read_csv(out / "effects.csv"), pd.read_csv(tmp_path / "two" / "effects.csv")
    )
    both = _invoke("compare", str(out), str(tmp_path / "two"), "--out", str(tmp_path / "both"))
    assert both.exit_code == 0, both.output
    found = pd.read_csv(tmp_path / "both" / "effects.csv")
    assert set(found["metric"]) == set(CORRIDOR_METRICS)  # folders of corridor runs
    assert (found["a_lower"] + found["a_higher"] == 0).all()  # the same runs twice


def test_hcomc_run_prints_the_same_rows(compared, corridor_file):
    out, _ = compared
    args = ["run", str(corridor_file), "--controller", "fifo", "--set",
            f"corridor.duration={DURATION}", "--workers", "1"]  # fmt: skip
    result = _invoke(*args, "--seeds", "2", "--json")
    assert result.exit_code == 0, result.output
    rows = pd.DataFrame(json.loads(result.stdout))
    assert list(rows["configuration"]) == ["FIFO", "FIFO"]
    stored = pd.read_parquet(out / "runs.parquet").query("configuration == 'FIFO'")
    for metric in CORRIDOR_METRICS:
        np.testing.assert_allclose(rows[metric], stored[metric].iloc[:2], rtol=1e-12)
    text = _invoke(*args, "--seeds", "1")
    assert text.exit_code == 0, text.output
    assert "Merged share: " in text.stdout
    assert "FIFO at every on-ramp" in text.stdout


def test_corridor_metrics_of_known_tables():
    trips = pd.DataFrame({
        "origin": ["main", "main", "on1", "on1", "main"],
        "outcome": ["arrived", "missed_exit", "arrived", "on_road", "not_inserted"],
        "travel_time": [100.0, 120.0, 80.0, np.nan, np.nan],
        "delay": [10.0, 30.0, 5.0, np.nan, np.nan],
    })  # fmt: skip
    merges = pd.DataFrame({
        "ramp": ["on1"] * 4, "merged": [True, True, True, False],
        "time_to_merge": [10.0, 12.0, 20.0, np.nan], "min_ttc": [2.0, 1.0, np.inf, 6.0],
        "max_drac": [0.5, 1.5, 0.0, 0.1], "max_decel": [1.0] * 4,
        "vmc_speed_drop": [0.0] * 4, "plans": [1, 2, 0, 1],
        "fallback": [False, True, False, False],
    })  # fmt: skip
    got = corridor_metrics(trips, merges, collisions=2)
    assert got["travel_time"] == pytest.approx(100.0)
    assert got["travel_time_main"] == pytest.approx(110.0)
    assert got["delay"] == pytest.approx(15.0)
    assert got["completed_trips"] == 3
    assert got["merged_share"] == 0.75  # the vehicle that never merged counts
    assert got["time_to_merge"] == pytest.approx(14.0)
    assert got["min_ttc_p05"] == pytest.approx(1.0 + 0.1 * (2.0 - 1.0))  # finite: 1, 2, 6
    assert got["ttc_below_1_5s_share"] == 0.25
    assert got["max_drac_p95"] == pytest.approx(np.percentile([0.5, 1.5, 0.0, 0.1], 95))
    assert (got["collisions"], got["fallbacks"], got["merged"]) == (2.0, 1.0, False)
    assert (got["events"], got["merged_events"], got["on_road"], got["not_inserted"]) == (
        4, 3, 1, 1)  # fmt: skip
    assert math.isnan(corridor_metrics(trips, merges.iloc[:0], 0)["merged_share"])
    assert corridor_metrics(trips, merges.iloc[:0], 0)["merged"] is False  # nothing merged


def test_corridor_metrics_pair_whatever_merged_says_paper_metrics_do_not():
    rows = [{"condition": "c", "configuration": conf, "seed": seed, "merged": seed != 0,
             "travel_time": 10.0 + seed + (conf == "A"), "lsrv": 1.0 + seed + (conf == "A")}
            for conf in ("B", "A") for seed in range(4)]  # fmt: skip
    found = effects(pd.DataFrame(rows), ["B", "A"], metrics=["travel_time", "lsrv"])
    by_metric = found.set_index("metric")
    assert "travel_time" in RUN_LEVEL
    assert "lsrv" not in RUN_LEVEL
    assert (by_metric.loc["travel_time", "n"], by_metric.loc["travel_time", "excluded"]) == (4, 0)
    assert (by_metric.loc["lsrv", "n"], by_metric.loc["lsrv", "excluded"]) == (3, 1)
    assert merge_success(pd.DataFrame(rows))["merged"].tolist() == [3, 3]


SWEEP = """
name = "short-sweep"
base = "short.toml"
configurations = ["none"]
seeds = 2
duration = 60.0

[corridor_grid.demand.main]
cav_share = [0.2, 0.8]
"""


def test_a_sweep_over_a_corridor_grid_is_keyed_by_the_corridor(corridor_file, tmp_path):
    from hcomc.experiments.sweep import load_sweep, sweep_status

    spec = corridor_file.parent / "sweep.toml"
    spec.write_text(SWEEP, encoding="utf-8")
    result = _invoke("sweep", str(spec), "--out", str(tmp_path / "sw"), "--workers", "1")
    assert result.exit_code == 0, result.output
    table = pd.read_parquet(tmp_path / "sw" / "sweep.parquet")
    assert list(table.columns[:3]) == ["base", "demand.main.cav_share", "duration"]
    assert list(zip(table["demand.main.cav_share"], table["seed"], strict=True)) == [
        (0.2, 0), (0.2, 1), (0.8, 0), (0.8, 1)]  # fmt: skip
    corridor = load_corridor(corridor_file, {"demand.main.cav_share": 0.8,
                                             "corridor.duration": 60.0})  # fmt: skip
    run = simulate_corridor(corridor, seed=1)
    row = table.iloc[3]
    for metric, value in _expected(run).items():
        assert row[metric] == pytest.approx(value, rel=1e-12, nan_ok=True), metric
    summary = pd.read_csv(tmp_path / "sw" / "summary.csv")
    assert summary["n"].tolist() == [2, 2]
    assert summary["merged_share"].iloc[1] == pytest.approx(table["merged_share"].iloc[2:].mean())
    manifests = [json.loads(p.read_text()) for p in (tmp_path / "sw" / "manifests").iterdir()]
    shares = sorted(m["corridor"]["demand"]["main"]["cav_share"] for m in manifests)
    assert shares == [0.2, 0.2, 0.8, 0.8]
    # a changed corridor file is never mixed with the stored runs: every key changes
    corridor_file.write_text(SHORT.replace("flow = 600.0", "flow = 500.0", 1), encoding="utf-8")
    try:
        status = sweep_status(load_sweep(spec), tmp_path / "sw")
    finally:
        corridor_file.write_text(SHORT, encoding="utf-8")
    assert (status.done, status.changed, status.stale) == (0, 4, 4)
    assert sweep_status(load_sweep(spec), tmp_path / "sw").done == 4


def test_a_paper_layout_corridor_runs_in_the_scenario_engine(tmp_path):
    from hcomc.config import config_to_toml
    from hcomc.corridor.engine import scenario_of
    from hcomc.experiments.runner import RunSpec, run_batch

    out = tmp_path / "paper"
    result = _invoke("compare", "--controllers", "fifo,game", "--conditions", "paper",
                     "--seeds", "2", "--set", "corridor.duration=60", "--workers", "1",
                     "--out", str(out))  # fmt: skip
    assert result.exit_code == 0, result.output
    runs = pd.read_parquet(out / "runs.parquet")
    assert set(runs["kind"]) == {"scenario"}
    assert set(pd.read_csv(out / "effects.csv")["metric"]) == set(PAPER_METRICS)
    corridor = load_corridor("paper", {"corridor.duration": 60})
    scenario = scenario_of(corridor, control=corridor.control.model_dump())
    path = tmp_path / "by_hand.toml"
    path.write_text(config_to_toml(scenario), encoding="utf-8")
    rows = [row for row, _ in run_batch([RunSpec(str(path), c, s)
                                         for c in ("FIFO", "Game") for s in (0, 1)])]  # fmt: skip
    for mine, theirs in zip(runs.to_dict("records"), rows, strict=True):
        assert mine["merged"] == theirs["merged"]
        for metric in (*PAPER_METRICS, "throughput", "ramp_delay"):
            assert mine[metric] == pytest.approx(theirs[metric], nan_ok=True), metric
    manifest = json.loads(next((out / "manifests").glob("*.json")).read_text())
    assert manifest["corridor"]["corridor"]["name"] == "paper"
    assert manifest["config"]["duration"] == 60.0


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["compare", "--controllers", "none,fifo", "--conditions", "SHORT", "--engine", "sumo"],
         "runs in the engine as a corridor"),
        (["compare", "--controllers", "none,fifo", "--conditions", "SHORT",
          "--set", "corridor.duratoin=60"], "unknown key 'corridor.duratoin'"),
        (["compare", "--controllers", "none,fifo", "--conditions", "C1,SHORT"],
         "names corridors"),
        (["compare", "--controllers", "none,fifo", "--conditions", "paper,SHORT"],
         "paper's layout (paper)"),
        (["compare", "--controllers", "none,fifo", "--conditions", "SHORT",
          "--suite", "merge-v1"], "'--suite'"),
        (["compare", "--controllers", "none,fifo", "--conditions", "missing.toml"],
         "'missing.toml' does not exist"),
        (["compare", "--controllers", "none,fifo", "--conditions", "SHORT", "--set",
          "control.options.gain=1"], "control.options.gain"),
        (["compare", "--controllers", "none,fifo", "--conditions", "SHORT", "--set",
          "corridor.warmup=10"], "key 'corridor.warmup' = 10.0 runs only in hcomc's scenario"),
        (["run", "SHORT", "--controller", "fifo", "--engine", "sumo"],
         "runs in the engine as a corridor"),
        (["run", "SHORT", "--controller", "fifo", "--set", "corridor.duration=-5"],
         "corridor.duration"),
        (["run", "SHORT"], "no merge controller"),
        (["sweep", "BADSWEEP"], "grid.cav_penetration"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_and_exit_2(corridor_file, tmp_path, args, fragment):
    bad = tmp_path / "bad.toml"
    bad.write_text(SWEEP.replace("[corridor_grid.demand.main]", "[grid]").replace(
        "cav_share", "cav_penetration").replace("short.toml", str(corridor_file)))  # fmt: skip
    swap = {"SHORT": str(corridor_file), "C1,SHORT": f"C1,{corridor_file}",
            "paper,SHORT": f"paper,{corridor_file}", "BADSWEEP": str(bad)}  # fmt: skip
    out = [] if args[0] == "run" else ["--out", str(tmp_path / "o")]  # run has no --out
    result = _invoke(*(swap.get(a, a) for a in args), *out)
    assert result.exit_code == 2, result.output
    assert fragment in result.stderr
    assert "Traceback" not in result.output
    assert len(result.stderr.strip().splitlines()) <= 3  # one message, wrapped at most twice
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("label", "expected"),
    [
        ("FIFO", {"controller": "fifo", "replan_period": 0.0}),
        ("Game", {"controller": "game", "replan_period": 0.0}),
        ("FIFO-R", {"controller": "fifo", "replan_period": 1.0}),
        ("Game-R", {"controller": "game", "replan_period": 1.0}),
        ("HCOMC-R", {"controller": "hcomc", "optimizer": "nsga2", "replan_period": 1.0}),
        ("HCOMC-PSO", {"controller": "hcomc", "optimizer": "pso", "replan_period": 0.0}),
        ("HCOMC-SA", {"controller": "hcomc", "optimizer": "sa", "replan_period": 0.0}),
        ("HCOMC+", {"controller": "hcomc", "no_cooperation": True, "replan_period": 0.0}),
        ("none", {"controller": "none", "replan_period": 2.0}),
    ],
)
def test_configuration_labels_set_the_corridors_control_table(label, expected):
    from hcomc.experiments.corridor.runs import with_configuration

    corridor = load_corridor("corridor", {"control.replan_period": 2.0})
    control = with_configuration(corridor, label).control.model_dump()
    assert {key: control[key] for key in expected} == expected


GAP_ACCEPTANCE = """
from hcomc.interface import MergePlan, Mode


class GapAcceptance:
    name = "gap-acceptance"

    def __init__(self, config):
        self.config = config

    def plan(self, view, group, rng):
        return MergePlan(group, Mode.NONE, view.t)
"""


def test_a_controller_of_ones_own_runs_at_every_on_ramp(corridor_file, tmp_path):
    import hashlib

    from hcomc.experiments.corridor.runs import CorridorSpec, run_corridor_batch

    source = tmp_path / "ga.py"
    source.write_text(GAP_ACCEPTANCE, encoding="utf-8")
    name = f"{source}:GapAcceptance"
    spec = CorridorSpec(str(corridor_file), name, 0, {"corridor.duration": 60.0})
    ((row, manifest),) = run_corridor_batch([spec])
    assert row["configuration"] == name
    assert row["plans"] > 0  # asked at every ramp vehicle's zone entry
    assert row["fallbacks"] == 0
    assert manifest["corridor"]["control"]["controller"] == name
    assert manifest["controller"]["sha256"] == hashlib.sha256(source.read_bytes()).hexdigest()


def test_the_example_corridor_sweep_spec_loads():
    from hcomc.experiments.sweep import expand, load_sweep

    root = Path(__file__).resolve().parents[2]
    runs = expand(load_sweep(root / "configs" / "sweeps" / "corridor.toml"))
    assert len(runs) == 3 * 3 * 3  # CAV shares x configurations x seeds
    assert {r.overrides["corridor.duration"] for r in runs} == {900.0}


def test_the_paper_conditions_as_corridors_run_as_the_conditions():
    rows = {}
    for source in ("paper-C2", "C2"):
        result = _invoke("run", source, "--controller", "fifo", "--seeds", "1", "--workers", "1",
                         "--json")  # fmt: skip
        assert result.exit_code == 0, result.output
        (rows[source],) = json.loads(result.stdout)
    assert rows["paper-C2"]["merged"] is True
    for metric in PAPER_METRICS:
        assert rows["paper-C2"][metric] == rows["C2"][metric], metric
