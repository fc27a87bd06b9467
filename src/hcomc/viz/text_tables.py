"""Tables as text: for a terminal (rich, in the booktabs style of a paper: rules under the
title and the header, no vertical lines), fitted to a width by splitting the columns into
blocks; and as Markdown (pandas with ``tabulate``) or LaTeX (pandas' ``to_latex``, booktabs
rules) for a paper or a notebook.

Every function takes a frame of text (the views of
:mod:`hcomc.experiments.comparison.view`), so a number reads the same in every format.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import pandas as pd
from rich import box
from rich.cells import cell_len
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text

__all__ = [
    "TextTable",
    "column_blocks",
    "console_table",
    "fit_width",
    "print_fitted",
    "print_table",
    "print_wide",
    "table_width",
    "to_latex",
    "to_markdown",
]

GAP = 2
"""Spaces between two columns of a console table."""

WIDTH = 120
"""The width console tables are fitted to (a narrower terminal's, if less)."""

FOLDED = 28
"""The narrowest a text column is folded to (its text wrapped onto more lines) to fit a
table to the console; a table that would need it narrower is split into blocks of columns."""

_LATEX = {
    "±": r"$\pm$",
    "↑": r"$\uparrow$",
    "↓": r"$\downarrow$",
    "²": r"\textsuperscript{2}",
    "−": "-",
    "—": "---",
    "–": "--",
    "·": r"$\cdot$",
    "⚑": r"$^\dagger$",
    "≤": r"$\leq$",
    "≥": r"$\geq$",
    "×": r"$\times$",
    "∞": r"$\infty$",
}
"""The non-ASCII characters of hcomc's tables and their LaTeX."""

_SPECIAL = {
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
    "\\": r"\textbackslash{}",
    "<": r"\textless{}",
    ">": r"\textgreater{}",
    "|": r"\textbar{}",
}
"""LaTeX's special characters and their escaped forms."""


@dataclass(frozen=True)
class TextTable:
    """A table of text: its ``frame`` (every cell a string), a ``title`` and a ``caption``
    (the legend under it); ``numeric`` names the right-aligned columns."""

    frame: pd.DataFrame
    title: str
    caption: str = ""
    numeric: tuple[str, ...] = ()


def _header(name: str, values: pd.Series) -> str:
    """A column's header, broken at its middle space into two lines when it is wider than
    the column's widest value (so that a short column keeps its width)."""
    widest = max((cell_len(str(v)) for v in values), default=0)
    if cell_len(name) <= widest or " " not in name:
        return name
    middle = len(name) / 2
    cut = min((i for i, c in enumerate(name) if c == " "), key=lambda i: abs(i - middle))
    return name[:cut] + "\n" + name[cut + 1 :]


def _width(name: str, values: pd.Series) -> int:
    """The width a column takes on the console: its widest value or header line."""
    lines = _header(name, values).split("\n")
    return max([cell_len(line) for line in lines] + [cell_len(str(v)) for v in values])


def console_table(table: TextTable) -> Table:
    """A rich table of ``table``'s frame in the booktabs style (its title and caption are
    printed as lines of their own, :func:`print_table`); only its widest text column may
    wrap (:func:`print_fitted`)."""
    shown = Table(box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False, collapse_padding=True)
    fold = _fold_column(table)
    for col in table.frame.columns:
        values = table.frame[col]
        shown.add_column(escape(_header(str(col), values)),
                         justify="right" if col in table.numeric else "left",
                         no_wrap=col != fold)  # fmt: skip
    for row in table.frame.itertuples(index=False):
        shown.add_row(*(escape(str(v)) for v in row))
    return shown


def print_table(console: Console, table: TextTable, width: int) -> None:
    """``table`` on ``console`` within ``width`` characters: its title in bold, the table,
    its caption wrapped at ``width``."""
    console.print(Text(table.title, style="bold"), width=width)
    console.print(console_table(table), width=width, crop=False)
    if table.caption:
        console.print(Text(table.caption), width=width)


def fit_width(console: Console) -> int:
    """The width tables are fitted to: :data:`WIDTH`, or a narrower terminal's."""
    return min(WIDTH, console.width) if console.is_terminal else WIDTH


def print_wide(console: Console, table: TextTable) -> None:
    """``table`` with every column on one line, whatever the terminal's width (a terminal
    wraps its lines)."""
    wide = Console(file=console.file, width=max(table_width(table.frame), WIDTH),
                   force_terminal=False, no_color=True, highlight=False)  # fmt: skip
    print_table(wide, table, max(table_width(table.frame), WIDTH))


def _fold_column(table: TextTable) -> str | None:
    """The column a too-wide table folds (its text wrapped): the widest text column."""
    texts = [c for c in table.frame.columns if c not in table.numeric]
    return max(texts, key=lambda c: _width(str(c), table.frame[c]), default=None)


def column_blocks(frame: pd.DataFrame, keys: int, width: int) -> list[pd.DataFrame]:
    """``frame`` split into blocks of columns that each fit ``width`` characters on the
    console, each block led by the first ``keys`` columns (the row's names), the way pandas
    prints a wide frame; one block when it fits (or has no column beyond the keys)."""
    widths = [_width(str(c), frame[c]) for c in frame.columns]
    lead = sum(widths[:keys]) + GAP * keys
    blocks: list[list[int]] = [[]]
    used = lead
    for i in range(keys, len(widths)):
        if blocks[-1] and used + widths[i] > width:
            blocks.append([])
            used = lead
        blocks[-1].append(i)
        used += widths[i] + GAP
    lead_cols = list(range(keys))
    return [frame.iloc[:, lead_cols + block] for block in blocks if block or len(blocks) == 1]


def print_fitted(console: Console, table: TextTable, keys: int, width: int | None = None) -> None:
    """Print ``table`` on ``console`` within ``width`` characters (default:
    :func:`fit_width`): whole, its widest text column folded onto more lines when that column
    can give up the excess and keep :data:`FOLDED` characters, else in blocks of columns
    (:func:`column_blocks`), each block's title numbered and the caption under the last."""
    width = width or fit_width(console)
    excess = table_width(table.frame) - width
    texts = [_width(str(c), table.frame[c]) for c in table.frame.columns if c not in table.numeric]
    if excess <= 0 or (texts and max(texts) - excess >= FOLDED):
        print_table(console, table, width)
        return
    blocks = column_blocks(table.frame, keys, width)
    for i, block in enumerate(blocks):
        title = table.title + (f" ({i + 1} of {len(blocks)})" if len(blocks) > 1 else "")
        caption = table.caption if i == len(blocks) - 1 else ""
        print_table(console, replace(table, frame=block, title=title, caption=caption), width)


def table_width(frame: pd.DataFrame) -> int:
    """The characters ``frame`` takes as a console table (without title and caption)."""
    widths = [_width(str(c), frame[c]) for c in frame.columns]
    return sum(widths) + GAP * max(len(widths) - 1, 0)


def to_markdown(tables: Sequence[TextTable]) -> str:
    """``tables`` as one Markdown document: per table a bold title, the table (GitHub
    flavour, by pandas and ``tabulate``; every cell as written, ``|`` escaped) and its
    caption."""
    parts = []
    for table in tables:
        align = tuple("right" if c in table.numeric else "left" for c in table.frame.columns)
        cells = table.frame.map(lambda v: str(v).replace("|", "\\|"))
        cells.columns = [str(c).replace("|", "\\|") for c in table.frame.columns]
        # the cells are text already rounded: tabulate must not read them as numbers again
        body = cells.to_markdown(index=False, colalign=align, disable_numparse=True)
        parts.append(f"**{table.title}**\n\n{body}\n" + (f"\n{table.caption}\n" if
                                                            table.caption else ""))  # fmt: skip
    return "\n".join(parts)


def _latex_text(text: str) -> str:
    """``text`` escaped for LaTeX, the symbols of hcomc's tables as LaTeX (:data:`_LATEX`);
    other non-ASCII characters (a controller's name) as they are, which LaTeX reads as UTF-8
    (the default since 2018). A cell that starts with ``[`` is led by ``{}``, so that it is
    not read as the optional argument of the ``\\`` or rule before it."""
    out = "".join(_SPECIAL.get(c, _LATEX.get(c, c)) for c in text)
    return "{}" + out if out.startswith("[") else out


def to_latex(tables: Sequence[TextTable]) -> str:
    """``tables`` as LaTeX: per table a ``table`` environment with its caption (title and
    legend) and a ``tabular`` with booktabs rules (``\\usepackage{booktabs}``), by pandas'
    ``to_latex``; every cell escaped (:func:`_latex_text`)."""
    parts = []
    for table in tables:
        frame = table.frame.map(lambda v: _latex_text(str(v)))
        frame.columns = [_latex_text(str(c)) for c in table.frame.columns]
        align = "".join("r" if c in table.numeric else "l" for c in table.frame.columns)
        caption = _latex_text(". ".join(p for p in (table.title, table.caption) if p))
        parts.append(frame.to_latex(index=False, escape=False, column_format=align,
                                    caption=caption, position="htbp"))  # fmt: skip
    return "\n".join(parts)
