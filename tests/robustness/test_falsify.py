"""``hcomc falsify``: the search finds a collision where the box holds one, each worst case
reproduces from the config it writes, the score is the least TTC of a commanded vehicle, and
bad input is refused by key."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ConfigError, load_config
from hcomc.metrics.bodies import body_pairs
from hcomc.robustness.falsify import (
    FalsifySpec,
    commanded_ttc,
    evaluate,
    falsify,
    load_spec,
    worst,
)
from hcomc.robustness.impairments import Impairments
from hcomc.sim.engine import Simulation

runner = CliRunner()

WINDOW = {"duration_min": 6.0, "duration_max": 6.0}
CONSTRUCTED = FalsifySpec(
    condition="C1", controller="fifo",
    faults=({"kind": "emergency_brake", "role": "vmf", "decel": 9.0, **WINDOW},
            {"kind": "sensor_dropout", "role": "vmc", **WINDOW}),
    space={"seed": (0, 99), "faults.0.delay": (0.0, 6.0), "faults.1.delay": (0.0, 6.0)},
)  # fmt: skip
"""A box that holds collisions: VMF brakes at 9 m/s² for 6 s while the cooperating CAV
behind it (VMC, commanded by FIFO's plan) loses its sensors for 6 s and holds its
acceleration; where the windows overlap early enough, VMC runs into VMF."""

SPACE_TOML = """condition = "C1"
controller = "fifo"

[[faults]]
kind = "emergency_brake"
role = "vmf"
decel = 9.0
duration_min = 6.0
duration_max = 6.0

[[faults]]
kind = "sensor_dropout"
role = "vmc"
duration_min = 6.0
duration_max = 6.0

[space]
seed = [0, 99]
"faults.0.delay" = [0.0, 6.0]
"faults.1.delay" = [0.0, 6.0]
"""


def test_the_search_finds_a_collision_and_each_case_reproduces() -> None:
    found = falsify(CONSTRUCTED, 48, search_seed=0)
    assert len(found) == 48
    hits = [c for c in found if c.collisions > 0]
    assert hits
    (first,) = worst(found, 1)
    assert first.collisions > 0
    assert first.least_ttc == 0.0
    again = evaluate(CONSTRUCTED, first.values)
    assert (again.collisions, again.least_ttc) == (first.collisions, first.least_ttc)
    # the config alone (its seed inside) is the run
    config = first.config.model_copy(update={"seed": first.seed})
    impaired = Impairments(config.v2x, config.faults, config.shield)
    log = Simulation(config, listeners=[impaired]).run()
    assert impaired.collisions_commanded(log) > 0


def test_the_search_is_deterministic() -> None:
    a = [c.row() for c in falsify(CONSTRUCTED, 12, search_seed=3)]
    b = [c.row() for c in falsify(CONSTRUCTED, 12, search_seed=3)]
    assert a == b


def test_the_score_is_the_least_ttc_of_the_commanded_vehicles() -> None:
    """Against an independent computation: every row's pairs with the vehicles commanded in
    that step, one row at a time."""
    config = CONSTRUCTED.config({"faults.0.delay": 5.0, "faults.1.delay": 5.5})
    impaired = Impairments(config.v2x, config.faults, config.shield)
    sim = Simulation(config, 4, listeners=[impaired])
    log = sim.run()
    expected = math.inf
    for step, ids in impaired.commanded_at.items():
        row = step - sim.n_warmup
        if 0 <= row < log.n_steps:
            gap, closing = body_pairs(log, slice(row, row + 1), sorted(ids))
            sel = closing > 0.1
            if sel.any():
                expected = min(expected, float((gap[sel].clip(min=0) / closing[sel]).min()))
    assert commanded_ttc(log, impaired, sim.n_warmup, 1) == pytest.approx(expected, rel=1e-12)
    assert math.isfinite(expected)


def test_the_command_writes_the_worst_cases(tmp_path: Path) -> None:
    """One search per controller and shield setting; each worst case is a config that
    'hcomc simulate' runs again to the same outcome, and a replay; the summary and the docs
    section say what the evaluations hold."""
    space = tmp_path / "space.toml"
    space.write_text(SPACE_TOML, encoding="utf-8")
    out = tmp_path / "fz"
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "robustness.md").write_text(
        "# page\n<!-- falsification: begin -->\nold\n<!-- falsification: end -->\ntail\n",
        encoding="utf-8",
    )
    result = runner.invoke(app, ["falsify", "--space", str(space), "--budget", "32",
                                 "--shield", "both", "--top", "2", "--out", str(out),
                                 "--docs", str(docs)])  # fmt: skip
    assert result.exit_code == 0, result.output
    record = json.loads((out / "falsify.json").read_text())
    summary = pd.read_csv(out / "summary.csv")
    assert summary.shield.tolist() == [False, True]
    assert [s["folder"] for s in record["settings"]] == ["fifo-shield-off", "fifo-shield-on"]
    for setting, row in zip(record["settings"], summary.to_dict("records"), strict=True):
        evaluations = pd.read_csv(out / setting["folder"] / "evaluations.csv")
        assert len(evaluations) == row["runs"] == 32
        assert row["runs_with_collision"] == int((evaluations.collisions_commanded > 0).sum())
        least = sorted(evaluations.least_ttc)[:2]
        assert [w["least_ttc"] for w in setting["worst"]] == least
        first = setting["worst"][0]
        config = load_config(out / setting["folder"] / first["config"])
        assert config.seed == first["seed"]
        assert config.shield.enabled == row["shield"]
        replay = (out / setting["folder"] / first["replay"]).read_text(encoding="utf-8")
        assert "<html" in replay.lower()
        again = runner.invoke(app, ["simulate", str(out / setting["folder"] / first["config"]),
                                    "--json"])  # fmt: skip
        summary_again = json.loads(again.output.strip().splitlines()[-1])
        assert (summary_again["collisions"] > 0) == (first["collisions_commanded"] > 0)
    assert summary.runs_with_collision.iloc[0] > 0  # without the shield the box holds some
    page = (docs / "robustness.md").read_text(encoding="utf-8")
    assert page.startswith("# page\n<!-- falsification: begin -->")
    assert page.endswith("<!-- falsification: end -->\ntail\n")
    assert "| fifo | off | 32 | " in page
    assert (docs / "data" / "falsify" / "fifo-shield-on" / "worst-1.toml").exists()
    kept = runner.invoke(app, ["falsify", "--budget", "2", "--top", "1", "--out", str(out)])
    assert kept.exit_code == 2  # an earlier search is not overwritten


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ('conditon = "C1"\n', "conditon"),
        ('[space]\n"faults.3.delay" = [0.0, 1.0]\n', "faults.3.delay"),
        ('[space]\n"v2x.loss" = [0.5, 0.1]\n', "v2x.loss"),
        ('[space]\n"v2x.los" = [0.0, 0.1]\n', "v2x.los"),
        ("[space]\nseed = 3\n", "space"),
    ],
)
def test_bad_search_files_are_refused_by_key(tmp_path: Path, text: str, named: str) -> None:
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match=named.replace(".", r"\.")):
        load_spec(path)
    result = runner.invoke(app, ["falsify", "--space", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert named in result.output


def test_the_published_search_is_generated_from_its_data() -> None:
    """docs/robustness.md's falsification table is the one its data gives, for FIFO, Game and
    HCOMC with and without the shield, each worst case a config that loads with its seed."""
    from hcomc.viz.falsify_report import MARKERS, generated_part

    docs = Path(__file__).resolve().parents[2] / "docs"
    data = docs / "data" / "falsify"
    summary = pd.read_csv(data / "summary.csv")
    record = json.loads((data / "falsify.json").read_text(encoding="utf-8"))
    text = (docs / "robustness.md").read_text(encoding="utf-8")
    part = text[text.index(MARKERS[0]) : text.index(MARKERS[1]) + len(MARKERS[1])]
    assert part == generated_part(summary, record)
    assert sorted(zip(summary.controller, summary.shield, strict=True)) == [
        (c, s) for c in ("fifo", "game", "hcomc") for s in (False, True)
    ]
    assert (summary.runs == record["budget"]).all()
    for row in summary.to_dict("records"):
        config = load_config(data / row["config"])
        assert config.seed == row["seed"]
        assert config.shield.enabled == row["shield"]


def test_the_generated_sentences_follow_the_data() -> None:
    from hcomc.viz.falsify_report import generated_part

    summary = pd.DataFrame({
        "controller": ["a", "a", "b", "b"], "shield": [False, True, False, True],
        "runs": [10] * 4, "runs_with_collision": [2, 0, 0, 0],
        "least_ttc": [0.0, 1.5, 2.0, 1.0], "seed": [1, 2, 3, 4],
        "config": ["a-off/worst-1.toml", "a-on/worst-1.toml", "b-off/worst-1.toml",
                   "b-on/worst-1.toml"],
    })  # fmt: skip
    text = generated_part(summary, {"version": "v", "revision": "r", "command": "c"})
    assert "found a collision of a commanded vehicle for a (shield off)." in text
    assert "With the shield the least TTC found is larger for a, not for b." in text
    assert "| a | off | 10 | 2 | collision | 1 |" in text


def test_the_box_and_the_overrides_merge_key_by_key() -> None:
    spec = FalsifySpec(condition="C2", controller="fifo", faults=("brake-vmf",),
                       overrides={"hdv": {"time_headway": 1.2}, "duration": 40.0},
                       space={"hdv.reaction_time_gap": (0.3, 1.0),
                              "faults.0.delay": (0.0, 6.0)})  # fmt: skip
    config = spec.config({"hdv.reaction_time_gap": 0.9, "faults.0.delay": 2.5})
    assert (config.hdv.time_headway, config.hdv.reaction_time_gap) == (1.2, 0.9)
    assert config.duration == 40.0
    assert (config.faults[0].delay_min, config.faults[0].delay_max) == (2.5, 2.5)
    assert config.faults[0].kind == "emergency_brake"
    assert config.control.controller == "fifo"


def test_a_docs_directory_without_the_section_is_refused_before_the_search(
    tmp_path: Path,
) -> None:
    result = runner.invoke(app, ["falsify", "--budget", "2", "--top", "1", "--out",
                                 str(tmp_path / "o"), "--docs", str(tmp_path)])  # fmt: skip
    assert result.exit_code == 2
    assert "falsification: begin" in result.output
    assert not (tmp_path / "o").exists()
