"""Building blocks of the self-contained HTML pages (the reproduction's report
:mod:`hcomc.viz.report`, the comparison's :mod:`hcomc.viz.compare_report`, the corridor
page of :mod:`hcomc.viz.corridor`): the page frame with its inline style, escaped text and
tables, and figures embedded as base64 PNG ``data:`` URIs, so a page loads nothing from
anywhere (no CDN, no external CSS, JavaScript or fonts) and can be mailed, archived or
opened offline. :func:`figure_png` turns a matplotlib figure into the PNG bytes a page
embeds.
"""

from __future__ import annotations

import base64
import html
import io
import math
import re
from typing import TYPE_CHECKING, Any

import pandas as pd

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["figure_png", "html_page"]

_FIGURE_DPI = 120

_CSS = """
:root { color-scheme: light; }
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial,
       sans-serif; margin: 0; background: #f6f7f9; color: #1d2330; line-height: 1.45; }
main { max-width: 1180px; margin: 0 auto; padding: 1.5rem 2rem 2.5rem; background: #fff;
       box-shadow: 0 0 12px rgba(0, 0, 0, 0.06); }
header { border-bottom: 2px solid #2a4d69; margin-bottom: 1.2rem; padding-bottom: 0.6rem; }
h1 { margin: 0 0 0.3rem; font-size: 1.7rem; color: #2a4d69; }
h2 { margin-top: 2rem; font-size: 1.25rem; color: #2a4d69;
     border-bottom: 1px solid #d5dbe3; padding-bottom: 0.2rem; }
.meta { margin: 0; font-size: 0.85rem; color: #555; }
.meta code, p code { background: #eef1f5; padding: 0 0.25em; border-radius: 3px; }
.note { background: #f2f6fa; border-left: 4px solid #4b86b4; padding: 0.6rem 1rem;
        font-size: 0.92rem; }
table { border-collapse: collapse; margin: 0.6rem 0 0.4rem; font-size: 0.82rem; width: 100%; }
caption { caption-side: top; text-align: left; font-size: 0.85rem; color: #555;
          padding-bottom: 0.3rem; }
th, td { border: 1px solid #d5dbe3; padding: 0.25rem 0.5rem; text-align: left;
         vertical-align: top; }
th { background: #e8edf3; font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tbody tr:nth-child(even) td { background: #fafbfc; }
tr.holds td { background: #e3f4e1 !important; }
tr.reversed td { background: #f9e0e0 !important; }
.legend-holds { background: #e3f4e1; padding: 0 0.3em; }
.legend-reversed { background: #f9e0e0; padding: 0 0.3em; }
figure { margin: 1.2rem 0; text-align: center; }
figure img { max-width: 100%; height: auto; border: 1px solid #e1e5ea; }
figcaption { font-size: 0.88rem; color: #444; margin-top: 0.3rem; }
.empty { color: #888; font-style: italic; }
footer { margin-top: 2.5rem; border-top: 1px solid #d5dbe3; padding-top: 0.6rem;
         font-size: 0.8rem; color: #666; }
"""
"""The default style of :func:`html_page` (the reproduction's report, the corridor page)."""


def figure_png(fig: Figure) -> bytes:
    """PNG bytes of a matplotlib figure, to embed in a page (e.g. the figures of
    :func:`hcomc.viz.report.write_report`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure; it is saved as it is (no layout change), at 120 dpi.

    Returns
    -------
    bytes
        The PNG file content.
    """
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=_FIGURE_DPI)
    return buffer.getvalue()


def html_page(title: str, main: str, *, css: str = _CSS, generator: str = "") -> str:
    """A standalone HTML page: ``main`` (HTML) in the ``<main>`` element, with its title,
    inline style ``css`` and an optional generator tag; loads nothing."""
    meta = f'<meta name="generator" content="{_e(generator)}">\n' if generator else ""
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
{meta}<title>{_e(title)}</title>
<style>{css}</style>
</head>
<body>
<main>
{main}</main>
</body>
</html>
"""


def _e(value: Any) -> str:
    """HTML-escaped text of *value* (quotes too)."""
    return html.escape(str(value), quote=True)


def _cell(value: Any) -> str:
    if isinstance(value, bool):
        return f"<td>{_e(value)}</td>"
    if isinstance(value, int):
        return f'<td class="num">{value}</td>'
    if isinstance(value, float):
        text = "—" if not math.isfinite(value) else f"{value:.4g}"
        return f'<td class="num">{_e(text)}</td>'
    return f"<td>{_e(value)}</td>"


def _html_table(frame: pd.DataFrame, caption: str, *, table_id: str) -> str:
    """A plain HTML table of *frame* (every header and cell escaped)."""
    if frame.empty:
        return f'<p class="empty" id="{_e(table_id)}">No runs for this table.</p>'
    head = "".join(f"<th>{_e(col)}</th>" for col in frame.columns)
    rows = []
    for record in frame.itertuples(index=False):
        cells = "".join(_cell(_plain(v)) for v in record)
        rows.append(f"<tr>{cells}</tr>")
    return (
        f'<table id="{_e(table_id)}">\n<caption>{_e(caption)}</caption>\n'
        f"<thead><tr>{head}</tr></thead>\n<tbody>\n" + "\n".join(rows) + "\n</tbody>\n</table>"
    )


def _plain(value: Any) -> Any:
    """numpy scalars as Python scalars, so :func:`_cell` can tell ints from floats."""
    item = getattr(value, "item", None)
    return item() if callable(item) and not isinstance(value, str | bytes) else value


def _figure_block(index: int, name: str, png: bytes) -> str:
    data = base64.b64encode(png).decode("ascii")
    # a caption that is already numbered ("Fig. 2 — …") is not numbered twice
    numbered = re.match(r"(Fig\.|Figure)\s*\d", name) is not None
    caption = name if numbered else f"Figure {index}. {name}"
    return (
        f'<figure id="figure-{index}">\n<img src="data:image/png;base64,{data}" '
        f'alt="{_e(name)}">\n<figcaption>{_e(caption)}</figcaption>\n</figure>'
    )
