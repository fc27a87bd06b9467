"""Tables II and III, each row on its own seeds, and merge success."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from hcomc.experiments.paper import PAPER_METRICS
from hcomc.experiments.tables import (
    LABELS,
    format_table,
    merge_success,
    paper_table,
    table_rows,
    table_summary,
)


def _runs(merged: bool = True) -> pd.DataFrame:
    """C1 with FIFO, Game, HCOMC and HCOMC+ over four seeds; values 10 * seed + row index;
    Game has no critical distance in seed 2, HCOMC+ none in seed 3; HCOMC fails to merge in
    seed 1."""
    rows = []
    for i, conf in enumerate(("FIFO", "Game", "HCOMC", "HCOMC+")):
        for seed in range(4):
            rec = {"condition": "C1", "configuration": conf, "seed": seed, "mode": "none"}
            rec.update(dict.fromkeys(PAPER_METRICS, 10.0 * seed + i))
            if (conf, seed) in {("Game", 2), ("HCOMC+", 3)}:
                rec["critical_distance"] = np.nan
            if merged:
                rec["merged"] = (conf, seed) != ("HCOMC", 1)
            rows.append(rec)
    return pd.DataFrame(rows)


def test_rows_of_table_iii_include_unnamed_configurations_after_hcomc() -> None:
    rows = table_rows(_runs(), "III")
    assert [(r[1], r[2]) for r in rows] == [
        ("FIFO", "FIFO"), ("Game", "Game"), ("HCOMC", "HCOMC"), ("HCOMC+", "HCOMC+"),
    ]  # fmt: skip
    assert rows[3][3] is None  # no paper value
    assert rows[0][3][0] == 104.67
    assert table_rows(_runs(), "II") == [("C1", "NSGA-II", "HCOMC", rows[2][3])]


def test_each_row_is_summarised_over_its_own_seeds() -> None:
    table = table_summary(_runs(), "III").set_index("configuration")
    # critical distance: Game lacks seed 2, HCOMC+ seed 3; the others have all four
    assert table["critical_distance_n"].to_dict() == {"FIFO": 4, "Game": 3, "HCOMC": 4,
                                                       "HCOMC+": 3}  # fmt: skip
    for i, conf in enumerate(("FIFO", "Game", "HCOMC", "HCOMC+")):
        seeds = [s for s in range(4) if (conf, s) not in {("Game", 2), ("HCOMC+", 3)}]
        values = [10.0 * s + i for s in seeds]
        assert table.loc[conf, "critical_distance"] == pytest.approx(np.mean(values))
        assert table.loc[conf, "critical_distance_median"] == pytest.approx(np.median(values))
        half = stats.t.ppf(0.975, len(values) - 1) * np.std(values, ddof=1) / np.sqrt(len(values))
        assert table.loc[conf, "critical_distance_ci"] == pytest.approx(half)
        assert table.loc[conf, "fuel"] == pytest.approx(15.0 + i)  # all four seeds
    assert (table["fuel_n"] == 4).all()
    assert table.loc["HCOMC", "merged"] == 3
    assert table.loc["FIFO", "merged"] == table.loc["FIFO", "runs"] == 4
    assert np.isnan(table.loc["HCOMC+", "fuel_paper"])
    assert table.loc["HCOMC", "fuel_paper"] == 8.0375


def test_no_other_configuration_changes_a_row() -> None:
    """HCOMC's Table II and III values are the same with and without the extension's runs
    (whose NaNs once removed seeds from every row of the condition)."""
    runs = _runs()
    without = runs[runs["configuration"] != "HCOMC+"]
    for which in ("II", "III"):
        full = table_summary(runs, which).set_index("configuration").loc["HCOMC"]
        alone = table_summary(without, which).set_index("configuration").loc["HCOMC"]
        pd.testing.assert_series_equal(full, alone)


def test_the_formatted_table_shows_n_per_metric_and_merge_success() -> None:
    shown = paper_table(_runs(), "III").set_index("Model")
    labels = list(LABELS.values())
    assert list(shown.columns) == ["Condition", "merged", "n", labels[0], "Crit. Dist. median",
                                   *labels[1:], "VR delay [s]"]  # fmt: skip
    assert shown.loc["HCOMC", "merged"] == "3/4"
    assert shown.loc["HCOMC", "n"] == "4"
    assert shown.loc["Game", "n"] == "3 · 4 · 4 · 4 · 4"
    assert shown.loc["HCOMC", "Fuel Cons. [L]"].endswith("(8.0375)")
    assert shown.loc["HCOMC+", "Fuel Cons. [L]"] == "18.000 ± 20.543 (—)"
    # without a merged column the table has none, and equal n shows once
    plain = format_table(table_summary(_runs(merged=False).dropna(), "III"))
    assert "merged" not in plain
    assert set(plain["n"]) == {"3", "4"}  # one number per row: its metrics share their seeds


def test_merge_success() -> None:
    wide = merge_success(_runs()).set_index("condition")
    assert wide.loc["C1", "HCOMC"] == "3/4"
    assert wide.loc["C1", "FIFO"] == "4/4"
    assert merge_success(_runs(merged=False)).empty
