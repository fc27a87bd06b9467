"""What ``hcomc compare`` prints and writes once its runs are in: merge success, its paired
comparison and the paired effects as terminal tables, the tables as files and the HTML
report (:mod:`hcomc.viz.compare_report`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from hcomc.cli._app import out
from hcomc.viz.text_tables import (
    TextTable,
    fit_width,
    print_fitted,
    print_wide,
    to_latex,
    to_markdown,
)

NUMERIC = ("median A-B [95 % CI]", "A<B", "A>B", "failed A/B", "excluded", "p (Holm)",
           "both merged", "only A", "only B", "neither")  # fmt: skip
"""Columns right-aligned (the others, names and words, left-aligned)."""

if TYPE_CHECKING:
    from hcomc.experiments.comparison.analysis import ComparisonTables

OUTPUTS = ("runs.parquet", "runs.csv", "effects.csv", "success.csv", "success_pairs.csv",
           "means.csv", "safety.csv", "report.html")  # fmt: skip
"""What a comparison writes into its folder (besides its record and run store)."""


FORMATS = ("console", "markdown", "latex")
"""How a comparison prints its tables (``--format``)."""


@dataclass(frozen=True)
class Presentation:
    """How a comparison shows its tables: ``format`` "console" (rich tables fitted to
    :data:`hcomc.viz.text_tables.WIDTH` columns, or each on one line when ``wide``), "markdown" or
    "latex" (the tables as one document, written to ``tables.md`` / ``tables.tex`` in the
    folder and printed to ``document``, the command's stdout, while its other lines go to
    stderr)."""

    format: str = "console"
    wide: bool = False
    document: TextIO | None = None


def _say(text: str) -> None:
    """Print a line of plain text (names such as "HCOMC [results]" are not markup), wrapped
    at the tables' width."""
    from rich.markup import escape

    out.print(escape(text), highlight=False, width=fit_width(out))


def _print(table: TextTable, keys: int, wide: bool) -> None:
    """``table`` on the console: on one line when ``wide``, else in blocks of columns (each
    led by the ``keys`` columns) that fit :data:`hcomc.viz.text_tables.WIDTH` or a narrower
    terminal."""
    if wide:
        print_wide(out, table)
    else:
        print_fitted(out, table, keys)


def _write_tables(target: Path, runs: Any, found: ComparisonTables) -> None:
    from hcomc.sim.manifest import atomic_paths

    with atomic_paths(*(target / n for n in OUTPUTS[:7])) as tmp:
        runs.to_parquet(tmp[0], index=False)
        runs.to_csv(tmp[1], index=False)
        found.effects.to_csv(tmp[2], index=False)
        found.success.to_csv(tmp[3], index=False)
        found.success_pairs.to_csv(tmp[4], index=False)
        found.means.to_csv(tmp[5], index=False)
        found.safety.to_csv(tmp[6], index=False)


SUCCESS_TITLE = "Merge success — runs in which VR merged"
"""Title of the merge-success table (for runs of the scenario engine)."""

MEANS_TITLE = "Means per controller and cell"
"""Title of the means table."""

MEANS_CAPTION = (
    "mean over each controller's runs with a value ± the half-width of its 95 % t interval, "
    "rounded to two digits of the half-width; (n): the runs with a value, when fewer than "
    "the cell's runs"
)
"""What the means table shows."""

SAFETY_TITLE = "Safety extremes per controller and cell"
"""Title of the safety-extremes table."""

SAFETY_CAPTION = (
    "the least time to collision and the largest deceleration to avoid a crash over each "
    "controller's runs (every follower-leader pair of a lane with a key vehicle in it), with "
    "the seed each came from, and the collisions of those runs"
)
"""What the safety-extremes table shows."""

EFFECTS_TITLE = "Paired effects"
"""Title of the effects tables (followed by the comparison on the console)."""

PAIRS_NOTE = "A<B: k of n seeds (a failed merge the worse value)"
"""How the effects caption explains n (for the paper's metrics)."""


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
    presentation: Presentation = Presentation(),
) -> None:
    """Compute, print and write the comparison of ``runs`` on ``metrics`` (default: the
    paper's five)."""
    from hcomc.experiments.comparison.analysis import comparison_tables
    from hcomc.experiments.comparison.success import flagged_note
    from hcomc.experiments.paper import PAPER_METRICS
    from hcomc.viz.compare_report import write_compare_report

    # the tables by name; runs.parquet and compare.json keep the specs
    found = comparison_tables(runs, configurations, comparisons, metrics or PAPER_METRICS)
    if found.names:
        names = ", ".join(f"{name} = {spec}" for spec, name in found.names.items())
        notes = (*notes, f"controllers by name: {names}")
    flagged = flagged_note(found.success)
    notes = (*notes, flagged) if flagged else notes
    _write_tables(target, runs, found)
    report = write_compare_report(
        target,
        found.runs,
        found.effects,
        found.success,
        found.success_pairs,
        record,
        notes=notes,
        means=found.means,
        safety=found.safety,
    )
    for note in notes:
        _say(f"note: {note}")
    tables = _tables(found, success_title, pairs_note)
    if presentation.format == "console":
        _print_console(tables, presentation.wide)
    else:
        _write_document(target, tables, presentation)
    _say(f"report: {report}")


def _tables(
    found: ComparisonTables, success_title: str, pairs_note: str
) -> list[tuple[TextTable, int]]:
    """The comparison's tables with the number of columns that name a row: merge success,
    its paired comparison (where some seed merged on one side only), the means, the safety
    extremes and the effects (all comparisons in one table)."""
    from hcomc.experiments.comparison.view import (
        EFFECTS_LEGEND,
        effects_view,
        means_view,
        safety_view,
        success_pairs_view,
        success_view,
    )

    rates = success_view(found.success)
    tables = [(TextTable(rates, success_title, numeric=tuple(rates.columns[1:])), 1)]
    pairs = found.success_pairs
    discordant = pairs[(pairs["only_a"] + pairs["only_b"]) > 0] if len(pairs) else pairs
    if len(discordant):
        title = ("Merge success paired by seed — comparisons in which only one of the two "
                 "merged in some seed")  # fmt: skip
        caption = "p: exact McNemar test, Holm-adjusted over the comparisons"
        tables.append((TextTable(success_pairs_view(discordant), title, caption, NUMERIC), 3))
    if not found.means.empty:
        shown = means_view(found.means)
        tables.append((TextTable(shown, MEANS_TITLE, MEANS_CAPTION, tuple(shown.columns[2:])), 2))
    if not found.safety.empty:
        shown = safety_view(found.safety)
        tables.append((TextTable(shown, SAFETY_TITLE, SAFETY_CAPTION, tuple(shown.columns[2:])), 2))
    if len(found.effects):
        legend = f"median A-B over the pairs [95 % bootstrap CI]; {pairs_note}; {EFFECTS_LEGEND}"
        shown = effects_view(found.effects)
        tables.append((TextTable(shown, EFFECTS_TITLE, legend, NUMERIC), 4))
    return tables


def _print_console(tables: list[tuple[TextTable, int]], wide: bool) -> None:
    """The tables on the console; the effects one table per comparison unless ``wide``."""
    paired = any(t.title.startswith("Merge success paired") for t, _ in tables)
    for i, (table, keys) in enumerate(tables):
        if table.title == EFFECTS_TITLE and not wide:
            _print_by_comparison(table)
            continue
        _print(table, keys, wide)
        if i == 0 and not paired:
            _say("merge success paired by seed: in no seed did only one of two compared "
                 "configurations merge")  # fmt: skip


def _print_by_comparison(effects: TextTable) -> None:
    """The effects table as one table per comparison (A, B), without the A and B columns,
    its verdicts by the configuration each favours; the legend under the last."""
    from hcomc.experiments.comparison.view import PAIR_VIEW_COLUMNS

    frame = effects.frame.rename(columns={"favours": "favours (CI)"})
    groups = list(dict.fromkeys(zip(frame["A"], frame["B"], strict=True)))
    for i, (a, b) in enumerate(groups):
        rows = frame[(frame["A"] == a) & (frame["B"] == b)][list(PAIR_VIEW_COLUMNS)]
        caption = effects.caption if i == len(groups) - 1 else ""
        title = f"{EFFECTS_TITLE}: {a} - {b} (A = {a}, B = {b})"
        _print(TextTable(rows, title, caption, NUMERIC), 2, wide=False)


def _write_document(target: Path, tables: list[tuple[TextTable, int]], how: Presentation) -> None:
    """The tables as one Markdown or LaTeX document: into the folder and onto stdout."""
    from hcomc.sim.manifest import atomic_paths

    text = (to_markdown if how.format == "markdown" else to_latex)([t for t, _ in tables])
    name = "tables.md" if how.format == "markdown" else "tables.tex"
    with atomic_paths(target / name) as (tmp,):
        tmp.write_text(text, encoding="utf-8")
    if how.document is not None:
        how.document.write(text)
        how.document.flush()
    _say(f"tables: {target / name}")
