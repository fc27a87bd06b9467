"""The tables of ``hcomc compare`` as a researcher publishes them: fitted to 120 columns with
units and names, rounded to their uncertainty, the same counts on the console, in the CSV
files and in the HTML report, and written as Markdown and LaTeX."""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import pandas as pd
import pytest
from rich.console import Console
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments.comparison.view import (
    EFFECTS_VIEW_COLUMNS,
    PAIR_VIEW_COLUMNS,
    effects_view,
    interval_text,
    means_view,
    rounded,
)
from hcomc.viz.text_tables import (
    TextTable,
    column_blocks,
    print_fitted,
    table_width,
    to_latex,
    to_markdown,
)

CONTROLLERS = ("FIFO", "Game", "HCOMC", "none")
UNITS = ("Crit. Dist. [m] ↑", "Aver. Acc. [m/s²] ↓", "Stab. Time from entry [s] ↓",
         "LSRV [m²] ↓", "Fuel Cons. [L] ↓")  # fmt: skip


@pytest.mark.parametrize(
    ("value", "uncertainty", "text"),
    [
        (54.19, 31.04, "54"),  # two digits of the uncertainty: 31
        (0.05675, 0.1288, "0.06"),  # 0.13
        (3.584, 0.0152, "3.584"),  # 0.015
        (2.0, 2.484, "2.0"),
        (25315.7, 62501.1, "25000"),  # two digits of 63000: to the thousand
        (-0.004, 0.5, "0.00"),  # no "-0.00"
        (math.inf, math.nan, "∞"),
        (5.0, math.nan, "5.00"),  # no uncertainty: three significant digits
        (38.95, 0.0, "39.0"),
        (math.nan, 1.0, "—"),
    ],
)
def test_a_number_is_rounded_to_two_digits_of_its_uncertainty(value, uncertainty, text):
    assert rounded(value, uncertainty) == text


def _frame(columns: int, width: int) -> pd.DataFrame:
    return pd.DataFrame({"cell": ["C1"], **{f"c{i}": ["x" * width] for i in range(columns)}})


def test_a_bound_that_rounds_to_zero_keeps_its_sign():
    assert interval_text(1.0, -0.04, 1.96) == "1.0 [-0.040, 2.0]"  # undecided: the CI holds 0
    assert interval_text(1.0, 0.04, 2.04) == "1.0 [0.040, 2.0]"
    assert interval_text(12925.0, 2671.0, 23179.0) == "13000 [3000, 23000]"
    assert interval_text(0.0, 0.0, 0.0) == "0 [0, 0]"
    assert interval_text(math.nan, math.nan, math.nan) == "—"


def test_a_wide_table_is_split_into_blocks_that_fit_each_led_by_its_names():
    frame = _frame(9, 20)
    blocks = column_blocks(frame, 1, 120)
    assert [b.columns[0] for b in blocks] == ["cell"] * len(blocks)
    assert sum(len(b.columns) - 1 for b in blocks) == 9  # every column once
    assert all(table_width(b) <= 120 for b in blocks)
    assert len(blocks) == 2  # 4 + 2 + 5 * 22 = 116 fits, a sixth column does not
    assert len(column_blocks(_frame(3, 20), 1, 120)) == 1


def test_a_table_a_little_too_wide_folds_its_widest_text_column():
    frame = pd.DataFrame({"claim": ["a claim of many words " * 3] * 2, "n": ["12345678"] * 2,
                          "p": ["0.5"] * 2})  # fmt: skip
    table = TextTable(frame, "claims", numeric=("n", "p"))
    console = Console(file=io.StringIO(), width=200)
    print_fitted(console, table, 1, 60)  # 66 + 2 + 8 + 2 + 3 = 81: the claim wraps
    lines = console.file.getvalue().splitlines()
    assert max(len(line.rstrip()) for line in lines) <= 60
    assert sum("12345678" in line for line in lines) == 2  # one table, numbers unwrapped
    assert len(lines) > 2 + 2 + 1  # title, header, rule and rows on more than one line each
    wide = TextTable(_frame(9, 20), "wide")
    console = Console(file=io.StringIO(), width=200)
    print_fitted(console, wide, 1, 120)  # no text column to fold: two blocks
    assert "wide (1 of 2)" in console.file.getvalue()


def test_latex_is_escaped_and_markdown_keeps_the_cells_as_written():
    frame = pd.DataFrame({
        "metric": ["LSRV [m²] ↓", "[C1] a|b"], "A<B": ["3 of 4", "0.0700"],
        "x_y": ["5 ± 1 (2 %)", "12345678"],
    })  # fmt: skip
    table = TextTable(frame, "Title & more", "legend — here", numeric=("A<B",))
    latex = to_latex([table])
    assert latex.isascii()
    assert r"LSRV [m\textsuperscript{2}] $\downarrow$" in latex
    assert r"A\textless{}B & x\_y \\" in latex
    assert r"5 $\pm$ 1 (2 \%)" in latex
    assert r"{}[C1] a\textbar{}b & 0.0700 & 12345678 \\" in latex  # no optional argument
    assert r"\caption{Title \& more. legend --- here}" in latex
    assert r"\begin{tabular}{lrl}" in latex
    assert "Zürich" in to_latex([TextTable(pd.DataFrame({"a": ["Zürich"]}), "t")])  # UTF-8
    lines = to_markdown([table]).splitlines()
    assert lines[0] == "**Title & more**"
    rows = [[c.strip() for c in re.split(r"(?<!\\)\|", line.strip("|"))] for line in lines[4:6]]
    assert rows[0] == ["LSRV [m²] ↓", "3 of 4", "5 ± 1 (2 %)"]
    assert rows[1] == [r"[C1] a\|b", "0.0700", "12345678"]  # not re-read as numbers


def _invoke(*args: str):
    return CliRunner().invoke(app, ["compare", *args], catch_exceptions=False)


def _args(target: Path) -> tuple[str, ...]:
    """A comparison of four controllers over two cells, two seeds, 40 s runs."""
    return ("--controllers", "fifo,game,hcomc,none", "--conditions", "C1,C2", "--seeds", "2",
            "--set", "duration=40", "--out", str(target), "--workers", "1")  # fmt: skip


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> tuple[Path, str]:
    """The folder of :func:`_args`' comparison and what it printed on stdout; its progress,
    on stderr off a terminal, counts the runs with the time left."""
    target = tmp_path_factory.mktemp("compare") / "four"
    result = _invoke(*_args(target))
    assert result.exit_code == 0, result.output
    assert re.search(r"runs: \d+/16 \(\d+ %\), \d+ s elapsed, about \d+ s left", result.stderr)
    assert "runs: 16/16 (100 %)" in result.stderr
    return target, result.stdout


def _effect_rows(text: str) -> dict[tuple[str, str], list[list[str]]]:
    """The rows of the console's per-comparison effects tables, by (A, B)."""
    rows: dict[tuple[str, str], list[list[str]]] = {}
    pair = None
    for line in text.splitlines():
        title = re.match(r"Paired effects: .* \(A = (.+), B = (.+)\)", line.strip())
        if title:
            pair = (title[1], title[2])
            rows[pair] = []
        elif pair and re.match(r"C\d ", line):
            rows[pair].append(re.split(r"\s{2,}", line.strip()))
    return rows


def test_the_console_fits_120_columns_with_units_names_and_the_files_numbers(folder):
    target, text = folder
    assert max(len(line.rstrip()) for line in text.splitlines()) <= 120
    assert "Means per controller and cell" in text
    for label in UNITS:
        assert label in text
    means = pd.read_csv(target / "means.csv")
    shown = means_view(means)
    for row in shown.itertuples(index=False):  # each mean as the console prints it
        line = next(t for t in text.splitlines() if t.startswith(f"{row.cell}    {row.metric}"))
        assert re.split(r"\s{2,}", line.strip())[2:] == [getattr(row, c) for c in CONTROLLERS]
    found = pd.read_csv(target / "effects.csv", keep_default_na=False)
    printed = _effect_rows(text)
    assert list(printed) == [("Game", "FIFO"), ("HCOMC", "FIFO"), ("none", "FIFO"),
                             ("HCOMC", "Game"), ("none", "Game"), ("none", "HCOMC")]  # fmt: skip
    full = effects_view(found).rename(columns={"favours": "favours (CI)"})
    for (a, b), rows in printed.items():
        expected = full[(full["A"] == a) & (full["B"] == b)][list(PAIR_VIEW_COLUMNS)]
        assert rows == expected.astype(str).values.tolist()


def test_safety_extremes_are_the_runs_worst_values_with_their_seeds(folder):
    target, text = folder
    runs = pd.read_csv(target / "runs.csv")
    safety = pd.read_csv(target / "safety.csv").set_index(["condition", "configuration"])
    html = (target / "report.html").read_text(encoding="utf-8")
    for (cell, conf), part in runs.groupby(["condition", "configuration"]):
        row = safety.loc[(cell, conf)]
        worst = part.loc[part["min_ttc"].idxmin()]
        assert row["least_ttc"] == pytest.approx(worst["min_ttc"], rel=1e-12)
        assert row["least_ttc_seed"] == worst["seed"]
        assert row["max_drac"] == pytest.approx(part["max_drac"].max(), rel=1e-12)
        assert row["max_drac_seed"] == part.loc[part["max_drac"].idxmax(), "seed"]
        assert row["collisions"] == part["collisions"].sum()
        shown = f"{rounded(row['least_ttc'])} (seed {int(row['least_ttc_seed'])})"
        assert shown in text
        assert shown in html
    assert "Safety extremes per controller and cell" in text


def test_counts_agree_between_console_csv_and_report(folder):
    target, text = folder
    success = pd.read_csv(target / "success.csv")
    runs = pd.read_csv(target / "runs.csv")
    html = (target / "report.html").read_text(encoding="utf-8")
    assert len(runs) == int(success["runs"].sum()) == 16
    for row in success.itertuples(index=False):
        shown = f"{row.merged}/{row.runs} ({100 * row.rate:.0f} %)"
        assert shown in text
        assert shown in html
    means = pd.read_csv(target / "means.csv")
    assert (means["runs"] == 2).all()
    for value in means_view(means).iloc[:, 2:].to_numpy().ravel():
        assert value in text
        assert value in html


def test_latex_and_markdown_hold_the_means_and_the_effects(folder):
    target, _ = folder
    done = _invoke(*_args(target), "--format", "latex")
    assert done.exit_code == 0, done.output
    latex = (target / "tables.tex").read_text(encoding="utf-8")
    assert done.stdout == latex  # stdout is the document alone; the other lines on stderr
    assert "16 runs (0 new" in done.stderr
    assert latex.isascii()
    assert latex.count(r"\begin{tabular}") == 4  # success, means, safety, effects
    assert r"\caption{Means per controller and cell." in latex
    assert r"\caption{Paired effects." in latex
    effects = pd.read_csv(target / "effects.csv", keep_default_na=False)
    body = latex.split(r"\caption{Paired effects.")[1]
    rows = [r for r in body.splitlines() if r.startswith("C")]
    assert len(rows) == len(effects) == 2 * 6 * 5
    assert all(r.count(" & ") == len(EFFECTS_VIEW_COLUMNS) - 1 for r in rows)
    medians = effects_view(effects)["median A-B [95 % CI]"]
    assert [r.split(" & ")[4] for r in rows] == list(medians)
    done = _invoke(*_args(target), "--format", "markdown")
    assert done.exit_code == 0, done.output
    markdown = (target / "tables.md").read_text(encoding="utf-8")
    assert "**Means per controller and cell**" in markdown
    assert "| Crit. Dist. [m] ↑" in markdown


def test_wide_prints_every_column_and_bad_format_is_refused(folder):
    target, _ = folder
    args = _args(target)
    done = _invoke(*args, "--wide")
    assert done.exit_code == 0, done.output
    header = [t for t in done.stdout.splitlines() if t.startswith("cell  metric")][-1]
    assert header.split()[:4] == ["cell", "metric", "A", "B"]
    rows = [re.split(r"\s{2,}", t.strip()) for t in done.stdout.splitlines() if t[:3] == "C1 "]
    effects = [r for r in rows if len(r) == len(EFFECTS_VIEW_COLUMNS)]
    assert len(effects) == 6 * 5  # one table: every comparison, every metric
    refused = _invoke(*args, "--format", "html")
    assert refused.exit_code == 2
    assert "option '--format' = 'html': allowed: console, markdown, latex" in refused.stderr
    refused = _invoke(*args, "--format", "latex", "--wide")
    assert refused.exit_code == 2
