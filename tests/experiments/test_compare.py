"""``hcomc compare``: paired statistics with known answers, and the command end to end."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments.claims import MIN_PAIRS, holm
from hcomc.experiments.comparison.effects import PREFERS, effects, pairs
from hcomc.experiments.comparison.means import means
from hcomc.experiments.comparison.success import merge_success, success_pairs
from hcomc.experiments.comparison.view import (
    PAIR_VIEW_COLUMNS,
    controller_labels,
    effects_view,
    means_view,
    safety_view,
    success_view,
)
from hcomc.experiments.paper import PAPER_METRICS

SEEDS = 10


def _runs(values: dict[str, np.ndarray], condition: str = "C1", merged=None) -> pd.DataFrame:
    """A runs table: every paper metric of configuration X equal to ``values[X]`` by seed."""
    rows = []
    for conf, series in values.items():
        for seed, value in enumerate(series):
            ok = True if merged is None else bool(merged[conf][seed])
            rows.append({
                "condition": condition, "configuration": conf, "seed": seed, "merged": ok,
                **dict.fromkeys(PAPER_METRICS, value if ok else np.nan),
            })  # fmt: skip
    return pd.DataFrame(rows)


BASE = np.linspace(10.0, 20.0, SEEDS) ** 1.3  # arbitrary, every seed different


def test_a_constant_shift_in_every_seed_is_decided_lower():
    runs = _runs({"B": BASE, "A": BASE - 1.0})
    frame = effects(runs, ["B", "A"])
    assert len(frame) == len(PAPER_METRICS)
    assert set(frame["a"]) == {"A"}
    assert set(frame["b"]) == {"B"}
    for _, row in frame.iterrows():
        assert row["median_diff"] == pytest.approx(-1.0)
        assert row["ci_high"] < 0.0
        assert row["verdict"] == "lower"
        assert (row["a_lower"], row["a_higher"], row["n"], row["excluded"]) == (SEEDS, 0, SEEDS, 0)
        assert row["p_value"] == pytest.approx(2 * 0.5**SEEDS)
        favours = "A" if PREFERS[row["metric"]] == "smaller" else "B"
        assert row["favours"] == favours
    critical = frame.set_index("metric").loc["critical_distance"]
    assert critical["favours"] == "B"  # lower critical distance is worse: B is favoured


def test_ties_are_undecided():
    runs = _runs({"A": BASE, "B": BASE + 1e-12})  # round-off is a tie
    frame = effects(runs)
    assert (frame["verdict"] == "undecided").all()
    assert (frame["median_diff"] == 0.0).all()
    assert (frame["ties"] == SEEDS).all()
    assert (frame["p_value"] == 1.0).all()
    assert (frame["favours"] == "").all()


def test_fewer_differing_seeds_than_min_pairs_is_undecided():
    runs = _runs({"B": BASE[: MIN_PAIRS - 1], "A": BASE[: MIN_PAIRS - 1] + 5.0})
    frame = effects(runs)
    assert (frame["ci_low"] > 0).all()  # the interval alone would say "higher"
    assert (frame["verdict"] == "undecided").all()


def test_an_unmerged_run_is_the_worse_value_of_its_pair():
    """A (2 above B where both merge) fails to merge on two seeds: each is A's worse outcome
    (higher for a metric that prefers smaller values, lower for the critical distance), never
    a missing pair."""
    merged = {"B": [True] * SEEDS, "A": [True] * SEEDS}
    merged["A"][0] = merged["A"][3] = False
    runs = _runs({"B": BASE, "A": BASE + 2.0}, merged=merged)
    frame = effects(runs, ["B", "A"]).set_index("metric")
    assert (frame["n"] == SEEDS).all()
    assert (frame["excluded"] == 0).all()
    assert (frame["failed_a"] == 2).all()
    assert (frame["failed_b"] == 0).all()
    fuel = frame.loc["fuel"]  # smaller is better: A's failures count as A > B
    assert (fuel["a_higher"], fuel["a_lower"]) == (SEEDS, 0)
    assert fuel["median_diff"] == pytest.approx(2.0)  # the eight seeds both merged on
    assert fuel["p_value"] == pytest.approx(2 * 0.5**SEEDS)
    cd = frame.loc["critical_distance"]  # larger is better: A's failures count as A < B
    assert (cd["a_higher"], cd["a_lower"]) == (SEEDS - 2, 2)
    assert cd["p_value"] == pytest.approx(2 * sum(math.comb(SEEDS, k) for k in range(3)) / 2**SEEDS)
    success = merge_success(runs).set_index("configuration")
    assert (success.loc["A", "merged"], success.loc["A", "runs"]) == (SEEDS - 2, SEEDS)
    assert success.loc["A", "rate"] == pytest.approx(0.8)
    assert success.loc["B", "merged"] == SEEDS
    view = success_view(merge_success(runs))
    assert view.loc[0, "A"] == "8/10 (80 %)"
    shown = effects_view(effects(runs, ["B", "A"]))
    row = shown[shown["metric"].str.startswith("Fuel")].iloc[0]
    assert row["A>B"] == "10"
    assert row["A<B"] == "0 of 10"
    assert row["failed A/B"] == "2/0"
    assert row["excluded"] == "0"


def test_a_merged_flag_false_is_a_failure_even_with_values():
    runs = _runs({"A": BASE, "B": BASE - 1.0})
    runs.loc[(runs["configuration"] == "A") & (runs["seed"] == 1), "merged"] = False
    frame = effects(runs)  # B against A (listed first)
    assert (frame["n"] == SEEDS).all()
    assert (frame["failed_b"] == 1).all()
    assert (frame["excluded"] == 0).all()


def test_merge_success_is_compared_paired_by_seed():
    never = {"A": [False] * SEEDS, "B": [True] * SEEDS}
    runs = _runs({"A": BASE, "B": BASE}, merged=never)
    frame = success_pairs(runs, [("A", "B")])
    row = frame.iloc[0]
    assert (row["both"], row["only_a"], row["only_b"], row["neither"]) == (0, 0, SEEDS, 0)
    assert row["p_value"] == pytest.approx(2 * 0.5**SEEDS)
    assert row["verdict"] == row["verdict_holm"] == "lower"
    effect_rows = effects(runs, comparisons=[("A", "B")])
    # every seed is A's failure: the worse value in the sign test of every metric, while the
    # median (of no pair) is undefined and the CI rule undecided
    assert (effect_rows["n"] == SEEDS).all()
    assert (effect_rows["excluded"] == 0).all()
    assert (effect_rows["verdict"] == "undecided").all()
    np.testing.assert_allclose(effect_rows["p_value"], 2 * 0.5**SEEDS)
    worse = effect_rows["favours"].eq("")  # no CI verdict; the Holm verdict names the side
    assert worse.all()
    assert set(effect_rows["verdict_holm"]) == {"lower", "higher"}


def test_holm_is_applied_over_the_whole_family():
    runs = pd.concat(
        [
            _runs({"X": BASE, "Y": BASE - 1.0, "Z": BASE + np.r_[1.0, -1.0].repeat(5)}, "C1"),
            _runs({"X": BASE, "Y": BASE + 1.0, "Z": BASE}, "C2"),
        ],
        ignore_index=True,
    )
    frame = effects(runs)
    assert len(frame) == 2 * 3 * len(PAPER_METRICS)  # cells x pairs x metrics
    np.testing.assert_allclose(frame["p_holm"], holm(frame["p_value"]))
    decided = frame[frame["p_value"] < 0.05]
    assert (frame.loc[decided.index, "p_holm"] >= decided["p_value"]).all()
    c2 = frame[(frame["condition"] == "C2") & (frame["a"] == "Y") & (frame["b"] == "X")]
    assert (c2["verdict"] == "higher").all()
    assert (c2["verdict_holm"] == "undecided").all()  # 2 * 0.5**10 * 30 > 0.05


def test_pairs_every_one_against_those_before_or_against_a_baseline():
    assert pairs(["fifo", "game", "mine"]) == [("game", "fifo"), ("mine", "fifo"), ("mine", "game")]
    assert pairs(["fifo", "game", "mine"], "game") == [("fifo", "game"), ("mine", "game")]
    with pytest.raises(ValueError, match="baseline"):
        pairs(["fifo"], "game")


def test_means_are_over_the_runs_with_a_value_with_the_t_interval():
    """A: the values 1, 2, 3 and a run without a merge; B: one value. Mean 2, half-width
    t(0.975, 2) s / sqrt(3) = 4.303 * 1 / 1.732 = 2.484; n 3 of 4 runs; B's interval NaN."""
    runs = pd.concat([
        _runs({"A": np.array([1.0, 2.0, 3.0, 9.0])}, merged={"A": [1, 1, 1, 0]}),
        _runs({"B": np.array([5.0])}),
    ])  # fmt: skip
    frame = means(runs, ["A", "B"], PAPER_METRICS).set_index(["configuration", "metric"])
    a, b = frame.loc[("A", "lsrv")], frame.loc[("B", "lsrv")]
    assert (a["mean"], a["n"], a["runs"]) == (2.0, 3, 4)
    assert a["ci"] == pytest.approx(4.302653 / math.sqrt(3.0), rel=1e-6)
    assert (b["mean"], b["n"], b["runs"]) == (5.0, 1, 1)
    assert math.isnan(b["ci"])
    view = means_view(means(runs, ["A", "B"], ["lsrv"]))
    assert view.loc[0, "A"] == "2.0 ± 2.5 (3)"  # rounded to the half-width; 3 of 4 runs
    assert view.loc[0, "B"] == "5.00"  # no interval: three significant digits


def test_a_comparison_missing_from_a_cell_is_left_out():
    runs = pd.concat([_runs({"A": BASE, "B": BASE}, "C1"), _runs({"A": BASE}, "C2")])
    frame = effects(runs)
    assert set(frame["condition"]) == {"C1"}
    assert set(merge_success(runs)["condition"]) == {"C1", "C2"}


# ------------------------------------------------------------------------- the command

GAP_ACCEPTANCE = '''
import numpy as np
from hcomc.interface import MergeGroup, MergePlan, Mode, TrafficView


class GapAcceptance:
    """Never cooperates: VR merges by gap acceptance, VMC drives on."""

    name = "gap-acceptance"

    def __init__(self, config):
        self.config = config

    def plan(self, view: TrafficView, group: MergeGroup, rng: np.random.Generator) -> MergePlan:
        return MergePlan(group, Mode.NONE, view.t)
'''


@pytest.fixture
def controller_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ga.py").write_text(GAP_ACCEPTANCE)
    return "./ga.py:GapAcceptance"


def test_tables_name_a_controller_of_a_file_by_its_name(controller_file, tmp_path):
    """A file's controller is shown by its ``name`` (else its class name); a name that two
    configurations would share, or a spec that does not load, keeps the spec."""
    (tmp_path / "twin.py").write_text(GAP_ACCEPTANCE)
    (tmp_path / "plain.py").write_text(GAP_ACCEPTANCE.replace('    name = "gap-acceptance"\n', ""))
    labels = controller_labels([
        "FIFO", "hcomc", controller_file, "./plain.py:GapAcceptance", "HCOMC [one]",
    ])  # fmt: skip
    assert labels == {
        controller_file: "gap-acceptance",
        "./plain.py:GapAcceptance": "GapAcceptance",
    }
    assert controller_labels([controller_file, "./twin.py:GapAcceptance"]) == {}
    assert controller_labels(["FIFO", "./plain.py:GapAcceptance", "gapacceptance"]) == {}


def _invoke(*args: str):
    return CliRunner().invoke(app, ["compare", *args])


def _check_written(folder: Path, text: str, controller: str) -> None:
    """The files of a first comparison of Game, HCOMC and ``controller`` on C1, C2, 2 seeds."""
    for name in ("runs.parquet", "runs.csv", "effects.csv", "success.csv",
                 "success_pairs.csv", "means.csv", "report.html", "compare.json"):  # fmt: skip
        assert (folder / name).is_file(), name
    runs = pd.read_parquet(folder / "runs.parquet")
    assert len(runs) == 12
    assert set(runs["condition"]) == {"C1", "C2"}
    assert set(runs["suite"]) == {"merge-v1"}
    assert list(pd.unique(runs["configuration"])) == ["Game", "HCOMC", controller]
    success = pd.read_csv(folder / "success.csv")
    assert len(success) == 6
    assert (success["runs"] == 2).all()
    for _, row in success.iterrows():  # printed as k/n (rate) for every cell and config
        assert f"{row['merged']}/2 ({100 * row['rate']:.0f} %)" in text
    found = pd.read_csv(folder / "effects.csv", keep_default_na=False)
    assert len(found) == 2 * 3 * 5  # cells x pairs x metrics
    assert set(found["verdict"]) == {"undecided"}  # two seeds never decide
    assert (found["n"] + found["excluded"] == 2).all()  # every seed is a pair or excluded
    record = json.loads((folder / "compare.json").read_text())
    assert (record["suite"], record["suite_version"]) == ("merge-v1", 1)
    assert record["git_revision"]
    assert record["hcomc_version"]
    assert record["controllers"][controller]["sha256"]
    assert "--set duration=40" in record["command"]
    html = (folder / "report.html").read_text()
    assert "merge-v1" in html
    assert "data:image/png;base64," in html


def _stamps(folder: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in (folder / "parts").glob("*.parquet")}


@pytest.mark.slow
def test_compare_runs_resumes_and_compares_folders(controller_file, tmp_path):
    args = ["--controllers", f"game,hcomc,{controller_file}", "--conditions", "C1,C2",
            "--seeds", "2", "--set", "duration=40", "--workers", "2"]  # fmt: skip
    first = _invoke(*args, "--out", "one")
    assert first.exit_code == 0, first.output
    for fragment in ("Merge success", "Paired effects", "undecided", "GapAcceptance",
                     "12 runs (12 new, 0 already done)"):  # fmt: skip
        assert fragment in first.stdout
    _check_written(tmp_path / "one", first.stdout, controller_file)

    again = _invoke(*args, "--out", "one")
    assert again.exit_code == 0, again.output
    assert "12 runs (0 new, 12 already done)" in again.stdout
    stamps = _stamps(tmp_path / "one")
    with open("ga.py", "a") as source:  # the controller changes: its runs are recomputed
        source.write("# tuned\n")
    edited = _invoke(*args, "--out", "one")
    assert edited.exit_code == 0, edited.output
    assert "12 runs (0 new, 8 already done, 4 recomputed" in edited.stdout
    kept = _stamps(tmp_path / "one")
    assert all(kept[name] == stamp for name, stamp in stamps.items())  # nothing overwritten
    assert len(kept) == 16

    second = _invoke("--controllers", "game,hcomc", "--conditions", "C1", "--seeds", "2",
                     "--set", "duration=40", "--workers", "1", "--out", "two")  # fmt: skip
    assert second.exit_code == 0, second.output
    both = _invoke("one", "two", "--out", "both")
    assert both.exit_code == 0, both.output
    assert "Game [two] vs Game [one]" in both.stdout
    pairs_found = pd.read_csv(tmp_path / "both" / "effects.csv")
    assert set(pairs_found["condition"]) == {"C1"}  # the cells both folders ran
    assert set(pairs_found["a"]) == {"Game [two]", "HCOMC [two]"}
    assert (pairs_found["a_lower"] + pairs_found["a_higher"] == 0).all()  # the same runs


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--controllers", "fifo,lifo"], "option '--controllers'"),
        (["--controllers", "fifo"], "two or more"),
        (["--controllers", "fifo,FIFO"], "given twice"),
        (["--controllers", "fifo,game", "--conditions", "C9"], "'C9' is not a cell"),
        (["--controllers", "fifo,game", "--seeds", "0"], "'--seeds' = 0"),
        (["--controllers", "fifo,game", "--suite", "merge-v0"], "no such suite"),
        (["--controllers", "fifo,game", "--baseline", "hcomc"], "not among the controllers"),
        (["--controllers", "fifo,game", "--workers", "0"], "'--workers' = 0"),
        (["--controllers", "fifo,game", "--set", "demand.ramp=none"], "no ramp demand"),
        (["--controllers", "fifo,game", "--set", "colour=1"], "colour"),
        (["--controllers", "fifo,game", "--out", "afile"], "is not a directory"),
        (["--controllers", "fifo,game", "--out", "reproduced"], "not a comparison"),
        (["--controllers", "fifo,game", "--out", "oldsuite"], "suite 'merge-v0'"),
        (["empty", "reproduced"], "holds no runs.parquet"),
        (["reproduced", "missing"], "does not exist"),
        (["reproduced"], "allowed: two"),
        (["reproduced", "reproduced"], "given twice"),
        (["reproduced", "other", "--seeds", "3"], "'--seeds' does not apply"),
        (["reproduced", "other"], "share no configuration"),
    ],
)
def test_bad_input_is_one_line_and_exit_2_before_anything_runs(
    tmp_path, monkeypatch, args, fragment
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("")
    (tmp_path / "empty").mkdir()
    for name, conf in (("reproduced", "FIFO"), ("other", "Mine")):
        (tmp_path / name).mkdir()
        _runs({conf: BASE[:2]}).to_parquet(tmp_path / name / "runs.parquet")
    (tmp_path / "oldsuite").mkdir()
    (tmp_path / "oldsuite" / "compare.json").write_text(
        json.dumps({"suite_id": "merge", "suite_version": 0})
    )
    before = sorted(p.name for p in tmp_path.rglob("*"))
    result = _invoke(*args)
    assert result.exit_code == 2, result.output
    assert fragment in result.stderr
    assert "Traceback" not in result.output
    assert len(result.stderr.strip().splitlines()) <= 2  # one message (wrapped at most once)
    assert sorted(p.name for p in tmp_path.rglob("*")) == before  # nothing written


def test_the_report_holds_the_tables_and_a_figure_per_cell(tmp_path):
    from hcomc.viz.compare_report import write_compare_report

    merged = {"B": [True] * SEEDS, "A": [True] * (SEEDS - 1) + [False]}
    runs = pd.concat(
        [_runs({"B": BASE, "A": BASE - 1.0}, cell, merged=merged) for cell in ("C1", "H1")]
    )
    comparisons = [("A", "B")]
    found = effects(runs, comparisons=comparisons)
    record = {"suite": "merge-v1", "git_revision": "abc123", "command": "hcomc compare <x>"}
    path = write_compare_report(
        tmp_path, runs, found, merge_success(runs), success_pairs(runs, comparisons), record,
        notes=["engine differs"],
    )  # fmt: skip
    html = path.read_text(encoding="utf-8")
    assert html.count("data:image/png;base64,") == 3  # success + one forest plot per cell
    assert "<h2>C1</h2>" in html
    assert "<h2>H1</h2>" in html
    assert "9/10 (90 %)" in html
    assert "hcomc compare &lt;x&gt;" in html
    assert "abc123" in html
    assert "engine differs" in html
    assert "http" not in html.replace("http-equiv", "")  # loads nothing


def _documented_rows(text: str) -> list[list[str]]:
    """The paired-effects rows of the example output in docs/benchmark.md, each led by its
    comparison's A and B (from the table's title)."""
    block = text.split("--seeds 3`, run a second time", 1)[1].split("```text", 1)[1]
    block = block.split("```", 1)[0]
    rows, pair = [], None
    for line in block.splitlines():
        title = re.match(r"Paired effects: .* \(A = (.+), B = (.+)\)", line)
        if title:
            pair = [title[1], title[2]]
        elif pair and re.match(r"C\d ", line):
            rows.append(pair + re.split(r"\s{2,}", line.strip()))
    return rows


@pytest.mark.slow
def test_the_documented_example_is_what_the_command_computes(tmp_path):
    docs = Path(__file__).resolve().parents[2] / "docs" / "benchmark.md"
    rows = _documented_rows(docs.read_text(encoding="utf-8"))
    assert len(rows) >= 10
    out = tmp_path / "example"
    result = _invoke("--controllers", "fifo,game,hcomc", "--conditions", "C1,C2",
                     "--seeds", "3", "--out", str(out))  # fmt: skip
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(out / "effects.csv", keep_default_na=False)
    computed = effects_view(frame).rename(columns={"favours": "favours (CI)"})
    computed_rows = computed[["A", "B", *PAIR_VIEW_COLUMNS]].astype(str).values.tolist()
    for row in rows:
        assert row in computed_rows, row


def test_safety_extremes_take_the_worst_run_and_its_seed():
    from hcomc.experiments.comparison.safety import safety_extremes

    runs = _runs({"A": BASE})
    runs["min_ttc"] = [5.0, 2.0, np.inf, np.nan, 3.0, 9.0, 4.0, 8.0, 7.0, 6.0]
    runs["max_drac"] = [0.1, 0.5, 0.2, 0.9, np.nan, 0.3, 0.1, 0.1, 0.1, 0.1]
    runs["collisions"] = [0, 1, 0, 0, 0, 0, 2, 0, 0, 0]
    runs["key_collisions"] = [0, 1, 0, 0, 0, 0, 0, 0, 0, 0]
    overlap = runs.assign(max_drac=runs["max_drac"].where(runs["seed"] != 6, np.inf))
    row = safety_extremes(runs, ["A"]).iloc[0]
    assert (row["least_ttc"], row["least_ttc_seed"]) == (2.0, 1)
    assert (row["max_drac"], row["max_drac_seed"]) == (0.9, 3)
    assert (row["collisions"], row["key_collisions"], row["runs"]) == (3, 1, SEEDS)
    worst = safety_extremes(overlap, ["A"]).iloc[0]  # a pair that overlapped is the worst
    assert (worst["max_drac"], worst["max_drac_seed"]) == (np.inf, 6)
    assert "∞ (seed 6)" in safety_view(safety_extremes(overlap, ["A"])).to_string()
    none = safety_extremes(runs.assign(min_ttc=np.inf), ["A"]).iloc[0]
    assert math.isnan(none["least_ttc"])
    assert none["least_ttc_seed"] == -1
    assert safety_extremes(runs.drop(columns="min_ttc"), ["A"]).empty  # corridor runs
