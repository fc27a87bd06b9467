"""Benchmark suites: every cell loads, cells are picked by id and range, the docs match."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from hcomc.config import ConfigError, merge_tables
from hcomc.experiments.suite import LATEST, MERGE_V1, SUITES, Cell, suite_named

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("cell", MERGE_V1.cells, ids=lambda c: c.id)
def test_every_cell_loads_as_a_merge_scenario(cell: Cell):
    config = cell.config()
    assert config.scenario == "merge"
    assert config.demand.ramp in ("single", "flow")
    assert cell.description


def test_cells_are_unique_and_the_paper_conditions_are_unchanged():
    for suite in SUITES.values():
        ids = [c.id.lower() for c in suite.cells]
        assert len(ids) == len(set(ids))
        scenarios = [(c.condition, repr(sorted(c.overrides.items()))) for c in suite.cells]
        assert len(scenarios) == len(set(scenarios))  # two cells never share their runs
    assert [c.id for c in MERGE_V1.cells[:5]] == ["C1", "C2", "C3", "C4", "C5"]
    assert all(c.condition == c.id and not c.overrides for c in MERGE_V1.cells[:5])


def test_held_out_cells_are_what_their_names_say():
    dense, lowpen, flow = (MERGE_V1.cell(i).config() for i in ("H1-dense", "H2-lowpen", "H3-flow"))
    c2 = MERGE_V1.cell("C2").config()
    assert dense.demand.mean_headway_main_1 < c2.demand.mean_headway_main_1
    assert dense.demand.mean_headway_main_2 < c2.demand.mean_headway_main_2
    assert lowpen.demand.cav_penetration == 0.2
    assert (flow.demand.ramp, flow.demand.ramp_mean_headway) == ("flow", 12.0)
    assert flow.warmup == 0.0  # the first ramp vehicle's merge falls in the measured time


def test_suite_names_carry_their_version():
    assert LATEST == "merge-v1" == MERGE_V1.name
    assert suite_named("MERGE-v1") is MERGE_V1
    with pytest.raises(ConfigError, match="allowed: merge-v1"):
        suite_named("merge-v9")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (None, [c.id for c in MERGE_V1.cells]),
        ("C2", ["C2"]),
        ("c1, C3", ["C1", "C3"]),
        ("C1..C5", ["C1", "C2", "C3", "C4", "C5"]),
        ("C4..H2-lowpen", ["C4", "C5", "H1-dense", "H2-lowpen"]),
        ("C2,C1..C3", ["C2", "C1", "C3"]),  # each once, in the order first named
    ],
)
def test_cells_are_picked_by_id_and_range(text, expected):
    assert [c.id for c in MERGE_V1.select(text)] == expected


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("C9", "'C9' is not a cell of suite 'merge-v1'"),
        ("C3..C1", "C3 comes after C1"),
        ("C1,,C2", "an empty cell id"),
        ("C1..", "'' is not a cell"),
    ],
)
def test_bad_cell_selections_name_what_is_allowed(text, fragment):
    with pytest.raises(ConfigError, match=re.escape(fragment)):
        MERGE_V1.select(text)


def test_overrides_merge_table_by_table():
    base = {"demand": {"cav_penetration": 0.2, "ramp": "flow"}}
    merged = merge_tables(base, {"demand": {"cav_penetration": 0.5}, "duration": 40.0})
    assert merged == {"demand": {"cav_penetration": 0.5, "ramp": "flow"}, "duration": 40.0}
    assert base == {"demand": {"cav_penetration": 0.2, "ramp": "flow"}}  # unchanged
    cell = MERGE_V1.cell("H2-lowpen")
    assert cell.config(duration=40.0).demand.cav_penetration == 0.2


def test_the_documented_cells_table_is_the_code_s():
    text = (ROOT / "docs" / "benchmark.md").read_text(encoding="utf-8")
    assert MERGE_V1.markdown_table() in text, (
        "docs/benchmark.md's cells table differs from the code; paste in MERGE_V1.markdown_table()"
    )
