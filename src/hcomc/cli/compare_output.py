"""What ``hcomc compare`` prints and writes once its runs are in: merge success, its paired
comparison and the paired effects as terminal tables, the tables as files and the HTML
report (:mod:`hcomc.viz.compare_report`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hcomc.cli._app import out

NUMERIC = ("median A-B [95 % CI]", "A<B", "A>B", "failed A/B", "excluded", "p (Holm)",
           "both merged", "only A", "only B", "neither")  # fmt: skip
"""Columns right-aligned on the terminal (the others, names and words, left-aligned)."""

OUTPUTS = ("runs.parquet", "runs.csv", "effects.csv", "success.csv", "success_pairs.csv",
           "means.csv", "report.html")  # fmt: skip
"""What a comparison writes into its folder (besides its record and run store)."""


def _say(text: str) -> None:
    """Print a line of plain text (names such as "HCOMC [results]" are not markup)."""
    from rich.markup import escape

    out.print(escape(text), highlight=False)


def _table(frame: Any, title: str, numeric: tuple[str, ...] = NUMERIC) -> Any:
    """A rich table of a text frame: the ``numeric`` columns right-aligned, names and
    verdicts left-aligned."""
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(title))
    for col in frame.columns:
        table.add_column(escape(str(col)), justify="right" if col in numeric else "left")
    for row in frame.itertuples(index=False):
        table.add_row(*(escape(str(v)) for v in row))
    return table


def _write_tables(
    target: Path, runs: Any, effects: Any, success: Any, pairs: Any, means: Any
) -> None:
    from hcomc.sim.manifest import atomic_paths

    with atomic_paths(*(target / n for n in OUTPUTS[:6])) as tmp:
        runs.to_parquet(tmp[0], index=False)
        runs.to_csv(tmp[1], index=False)
        effects.to_csv(tmp[2], index=False)
        success.to_csv(tmp[3], index=False)
        pairs.to_csv(tmp[4], index=False)
        means.to_csv(tmp[5], index=False)


SUCCESS_TITLE = "Merge success — runs in which VR merged"
"""Title of the merge-success table (for runs of the scenario engine)."""

MEANS_TITLE = "Means — over each controller's runs with a value, ± 95 % t interval (n runs)"
"""Title of the means table."""

PAIRS_NOTE = "A<B: k of n seeds (a failed merge the worse value)"
"""How the effects title explains n (for the paper's metrics)."""


def _analyse(
    target: Path,
    runs: Any,
    comparisons: list[tuple[str, str]],
    configurations: list[str],
    record: dict[str, Any],
    notes: tuple[str, ...] = (),
    *,
    metrics: tuple[str, ...] | None = None,
    success_title: str = SUCCESS_TITLE,
    pairs_note: str = PAIRS_NOTE,
) -> None:
    """Compute, print and write the comparison of ``runs`` on ``metrics`` (default: the
    paper's five)."""
    from hcomc.experiments.comparison.effects import effects
    from hcomc.experiments.comparison.means import means
    from hcomc.experiments.comparison.success import flagged_note, merge_success, success_pairs
    from hcomc.experiments.comparison.view import (
        controller_labels,
        effects_view,
        means_view,
        success_pairs_view,
        success_view,
    )
    from hcomc.experiments.paper import PAPER_METRICS
    from hcomc.viz.compare_report import write_compare_report

    labels = controller_labels(configurations)
    shown = runs  # the tables by name; runs.parquet and compare.json keep the specs
    if labels:
        shown = runs.replace({"configuration": labels})
        configurations = [labels.get(c, c) for c in configurations]
        comparisons = [(labels.get(a, a), labels.get(b, b)) for a, b in comparisons]
        names = ", ".join(f"{name} = {spec}" for spec, name in labels.items())
        notes = (*notes, f"controllers by name: {names}")
    metrics = metrics or PAPER_METRICS
    effect_rows = effects(shown, configurations, comparisons=comparisons, metrics=metrics)
    mean_rows = means(shown, configurations, metrics)
    success = merge_success(shown, configurations)
    pairs = success_pairs(shown, comparisons)
    flagged = flagged_note(success)
    notes = (*notes, flagged) if flagged else notes
    _write_tables(target, runs, effect_rows, success, pairs, mean_rows)
    report = write_compare_report(
        target, shown, effect_rows, success, pairs, record, notes=notes, means=mean_rows
    )
    for note in notes:
        _say(f"note: {note}")
    rates = success_view(success)
    out.print(_table(rates, success_title, tuple(rates.columns[1:])))
    discordant = pairs[(pairs["only_a"] + pairs["only_b"]) > 0] if len(pairs) else pairs
    if len(discordant):
        title = (
            "Merge success paired by seed (exact McNemar test, Holm-adjusted) — comparisons "
            "in which only one of the two merged in some seed"
        )
        out.print(_table(success_pairs_view(discordant), title))
    else:
        out.print("merge success paired by seed: in no seed did only one of two compared "
                  "configurations merge", highlight=False)  # fmt: skip
    if not mean_rows.empty:
        table = means_view(mean_rows)
        out.print(_table(table, MEANS_TITLE, tuple(table.columns[2:])))
    out.print(
        _table(
            effects_view(effect_rows),
            "Paired effects — median A-B over seeds [95 % bootstrap CI]; verdict by the CI; "
            f"favours by the metric's better direction (↑ larger, ↓ smaller); {pairs_note}; "
            "failed A/B: seeds without a merge, each the worse value in A<B / A>B; excluded: "
            "seeds without a pair; p: sign test, Holm-adjusted over the table",
        )
    )
    _say(f"report: {report}")
