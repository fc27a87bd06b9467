"""Tables II and III on the seeds common to a condition's rows, and merge success."""

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


def test_means_are_over_the_seeds_common_to_every_row_of_the_condition() -> None:
    table = table_summary(_runs(), "III").set_index("configuration")
    # critical distance: seeds 0 and 1 only (Game lacks seed 2, HCOMC+ seed 3)
    assert (table["critical_distance_n"] == 2).all()
    for i, conf in enumerate(("FIFO", "Game", "HCOMC", "HCOMC+")):
        assert table.loc[conf, "critical_distance"] == pytest.approx(5.0 + i)
        half = stats.t.ppf(0.975, 1) * np.std([0.0, 10.0], ddof=1) / np.sqrt(2)
        assert table.loc[conf, "critical_distance_ci"] == pytest.approx(half)
        assert table.loc[conf, "fuel"] == pytest.approx(15.0 + i)  # all four seeds
    assert (table["fuel_n"] == 4).all()
    assert table.loc["HCOMC", "merged"] == 3
    assert table.loc["FIFO", "merged"] == table.loc["FIFO", "runs"] == 4
    assert np.isnan(table.loc["HCOMC+", "fuel_paper"])
    assert table.loc["HCOMC", "fuel_paper"] == 8.0375
    # a table of fewer rows has more common seeds: Table II's only row here is HCOMC
    assert table_summary(_runs(), "II").iloc[0]["critical_distance_n"] == 4


def test_the_formatted_table_shows_n_per_metric_and_merge_success() -> None:
    shown = paper_table(_runs(), "III").set_index("Model")
    assert list(shown.columns) == ["Condition", "merged", "n", *LABELS.values()]
    assert shown.loc["HCOMC", "merged"] == "3/4"
    assert shown.loc["HCOMC", "n"] == "2 · 4 · 4 · 4 · 4"
    assert shown.loc["HCOMC", "Fuel Cons. [L]"].endswith("(8.0375)")
    assert shown.loc["HCOMC+", "Fuel Cons. [L]"] == "18.000 ± 20.543 (—)"
    # without a merged column the table has none, and equal n shows once
    plain = format_table(table_summary(_runs(merged=False).dropna(), "III"))
    assert "merged" not in plain
    assert set(plain["n"]) == {"2"}


def test_merge_success() -> None:
    wide = merge_success(_runs()).set_index("condition")
    assert wide.loc["C1", "HCOMC"] == "3/4"
    assert wide.loc["C1", "FIFO"] == "4/4"
    assert merge_success(_runs(merged=False)).empty
