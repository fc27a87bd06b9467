"""Self-contained HTML report of a reproduction run.

:func:`write_report` writes one HTML page holding everything: the paper's Tables II and III
side by side with ours, the per-seed claims table, and the figures as base64 ``data:`` URIs.
The page loads nothing from anywhere (no CDN, no external CSS, JavaScript or fonts, no
links), so it can be mailed, archived or opened offline. :func:`figure_png` turns a
matplotlib figure into the PNG bytes the report embeds.
"""

from __future__ import annotations

import base64
import html
import io
import math
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from hcomc.experiments.claims import claims
from hcomc.experiments.narrative import extension_share, paper_share, verdict_summary
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.experiments.tables import TABLE_CAPTION, merge_success, paper_table
from hcomc.sim.manifest import atomic_paths, build_manifest

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["REQUIRED_COLUMNS", "figure_png", "html_page", "write_report"]

#: Columns a results frame needs for the report's tables.
REQUIRED_COLUMNS = ("condition", "configuration", "seed", "mode", *PAPER_METRICS)

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
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


def figure_png(fig: Figure) -> bytes:
    """PNG bytes of a matplotlib figure, for :func:`write_report`.

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


def _claims_table(frame: pd.DataFrame) -> str:
    if frame.empty:
        return '<p class="empty" id="claims">No claim can be evaluated from these runs.</p>'
    rows = []
    for rec in frame.to_dict("records"):
        css = _e(rec["verdict"])
        median, low, high = (float(rec[c]) for c in ("median_diff", "ci_low", "ci_high"))
        effect = f"{median:.4g} [{low:.4g}, {high:.4g}]" if math.isfinite(median) else "—"
        p_holm = float(rec["p_holm"])
        rows.append(
            f'<tr class="{css}"><td>{_e(rec["claim"])}</td><td>{_e(rec["condition"])}</td>'
            f"<td>{_e(rec['verdict'])}</td><td>{_e(rec['verdict_holm'])}</td>"
            f'<td class="num">{p_holm:.2g}</td>'
            f'<td class="num">{int(rec["holds"])} of {int(rec["n"])}</td>'
            f'<td class="num">{_e(effect)}</td>'
            f"<td>{_e(rec['ours'])}</td><td>{_e(rec['paper'])}</td></tr>"
        )
    return (
        f"<p>{_e(_verdict_counts(frame))} "
        '(<span class="legend-holds">green</span>: holds by its 95 % CI; '
        '<span class="legend-reversed">red</span>: reversed; white: undecided).</p>\n'
        '<table id="claims">\n<caption>Comparative claims of the paper\'s Section IV, '
        "evaluated on paired runs (same seed): median paired difference A - B with its 95 % "
        "bootstrap CI; verdict by that CI; verdict (Holm) by the sign test, Holm-corrected over "
        "all claims; k of n: seeds in the paper's direction.</caption>\n"
        "<thead><tr><th>Claim</th><th>Condition</th><th>Verdict (95 % CI)</th>"
        "<th>Verdict (Holm)</th><th>p (Holm)</th><th>k of n seeds</th>"
        "<th>Median A - B [95 % CI]</th><th>Ours (mean A vs B)</th><th>Paper</th></tr>"
        "</thead>\n<tbody>\n" + "\n".join(rows) + "\n</tbody>\n</table>"
    )


def _verdict_counts(frame: pd.DataFrame) -> str:
    """The verdict counts of the paper's claims, and of the labelled extension's apart."""
    paper, extension = paper_share(frame), extension_share(frame)
    text = (
        f"Of {len(paper)} claims of the paper, {verdict_summary(paper, 'verdict')} by their "
        f"95 % CI; by the sign test with Holm's correction, "
        f"{verdict_summary(paper, 'verdict_holm')}"
    )
    if len(extension):
        text += (
            f". Of the {len(extension)} claims of HCOMC+ (a labelled extension, a Holm family "
            f"of its own), {verdict_summary(extension, 'verdict')} by their 95 % CI"
        )
    return text


def _merge_section(runs: pd.DataFrame) -> str:
    wide = merge_success(runs)
    if wide.empty:
        return '<p class="empty" id="merge-success">The runs do not record merge success.</p>'
    return _html_table(
        wide,
        "Runs in which VR merged, k of n, per condition and configuration.",
        table_id="merge-success",
    )


def _replay_section(replays: Mapping[str, str]) -> str:
    """Links to interactive replays (pages beside the report; relative paths only, so the
    report stays self-contained and loads nothing)."""
    for caption, target in replays.items():
        if re.match(r"^\s*([a-z][a-z0-9+.-]*:|/)", target, re.I):
            raise ValueError(
                f"replay {caption!r} links to {target!r}; allowed: a relative path beside "
                "the report (e.g. replay/C2-seed0.html)"
            )
    items = "\n".join(
        f'<li><a href="{_e(target)}">{_e(caption)}</a></li>' for caption, target in replays.items()
    )
    return f'<section id="replays">\n<h2>Replays</h2>\n<ul>\n{items}\n</ul>\n</section>\n'


def _figure_block(index: int, name: str, png: bytes) -> str:
    data = base64.b64encode(png).decode("ascii")
    # a caption that is already numbered ("Fig. 2 — …") is not numbered twice
    numbered = re.match(r"(Fig\.|Figure)\s*\d", name) is not None
    caption = name if numbered else f"Figure {index}. {name}"
    return (
        f'<figure id="figure-{index}">\n<img src="data:image/png;base64,{data}" '
        f'alt="{_e(name)}">\n<figcaption>{_e(caption)}</figcaption>\n</figure>'
    )


def _run_summary(runs: pd.DataFrame) -> str:
    def listing(column: str) -> str:
        values = sorted({str(v) for v in runs[column].dropna()})
        return ", ".join(values) if values else "none"

    return (
        f"{len(runs)} runs · conditions: {listing('condition')} · configurations: "
        f"{listing('configuration')} · {runs['seed'].nunique()} seeds"
    )


def write_report(
    out_dir: str | os.PathLike[str],
    runs: pd.DataFrame,
    *,
    figures: Mapping[str, bytes] | None = None,
    title: str = "hcomc reproduction",
    claim_frame: pd.DataFrame | None = None,
    replays: Mapping[str, str] | None = None,
) -> Path:
    """Write ``out_dir/report.html``, a self-contained report of a results table.

    The page has a header (title, package version, git revision, date), a short "how to
    read this" note, Table II (optimisers) and Table III (controllers) as built by
    :func:`hcomc.experiments.tables.paper_table` ("ours ± 95 % CI (paper)" over the seeds
    common to a condition's rows, with merge success), merge success per condition and
    configuration (when the runs record ``merged``), the claims of
    :func:`hcomc.experiments.claims.claims` with both verdict columns and "k of n seeds"
    (rows green when the CI verdict is "holds", red when "reversed"), every figure of
    *figures* with a caption, the links of *replays*, and a footer. It references no
    external resource: styles are inline, there is no script, images are embedded as
    ``data:image/png;base64`` URIs and the only links are relative ones to replay pages.
    All text coming from the data is HTML-escaped.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output directory; created if missing.
    runs : pandas.DataFrame
        One row per run, as written by the experiment runner (``runs.parquet``); needs the
        columns of :data:`REQUIRED_COLUMNS`.
    figures : mapping of str to bytes or None
        Figure caption → PNG file content (e.g. from :func:`figure_png`), shown in order.
    title : str
        Page title and heading.
    claim_frame : pandas.DataFrame or None
        ``claims(runs)`` when the caller has computed it already (its bootstrap is the
        slowest part of the page); computed here if None.
    replays : mapping of str to str or None
        Caption -> relative path (from ``out_dir``) of an interactive replay page written
        beside the report; listed in a "Replays" section. This is where the replay viewer
        links in.

    Returns
    -------
    pathlib.Path
        Path of the written ``report.html`` (written atomically).

    Raises
    ------
    ValueError
        If *runs* lacks a required column, a figure is not PNG data or a replay link is not
        a relative path.
    """
    missing = [col for col in REQUIRED_COLUMNS if col not in runs.columns]
    if missing:
        raise ValueError(
            f"runs lacks the column(s) {missing} needed for the report; "
            f"expected at least {list(REQUIRED_COLUMNS)}"
        )
    figures = dict(figures or {})
    for name, png in figures.items():
        if not isinstance(png, bytes | bytearray) or not bytes(png).startswith(_PNG_SIGNATURE):
            raise ValueError(f"figure {name!r} is not PNG data (use figure_png(fig))")

    replay_html = _replay_section(replays) if replays else ""
    manifest = build_manifest(seed=0, config={})
    version = manifest["hcomc_version"]
    revision = manifest["git_revision"]
    created = manifest["created_utc"]

    table_ii = paper_table(runs, "II")
    table_iii = paper_table(runs, "III")
    if claim_frame is None:
        claim_frame = claims(runs)

    figure_html = "\n".join(
        _figure_block(i, name, bytes(png)) for i, (name, png) in enumerate(figures.items(), 1)
    )
    if not figure_html:
        figure_html = '<p class="empty">No figures were included.</p>'

    body = html_page(
        title,
        f"""<header>
<h1>{_e(title)}</h1>
<p class="meta">hcomc <code>{_e(version)}</code> · git revision <code>{_e(revision)}</code>
· generated {_e(created)} (UTC) · Python {_e(manifest["python"])}
· {_e(manifest["platform"])}</p>
<p class="meta">{_e(_run_summary(runs))}</p>
</header>

<section id="how-to-read">
<h2>How to read this</h2>
<div class="note">
<p>Each table cell reads <em>ours ± half-width of the 95&nbsp;% confidence interval (paper
value)</em>, over the seeds on which every row of the condition has a value (<em>n</em>, per
metric when they differ), so the rows of a condition are comparable; <em>merged</em> counts
the runs in which VR merged. Our metric definitions differ from the paper's, which does not
give its own (see <code>docs/reproduction.md</code> in the source tree): the absolute numbers
are not comparable, and the reproduction is judged on the paper's comparative claims
(orderings and directions), each evaluated on paired runs. A claim <em>holds</em> when the
95&nbsp;% CI of its median paired difference excludes 0 in the paper's direction, is
<em>reversed</em> when it excludes 0 in the other direction and <em>undecided</em> otherwise;
the Holm verdict asks the same of the sign test, corrected for testing all claims at once.
"k of n seeds" describes the seeds; it is not a verdict.</p>
<p>Better is larger for the critical distance and smaller for the average acceleration, the
stabilisation time, the low-speed region volume (LSRV) and the fuel consumption.</p>
</div>
</section>

<section id="table-ii-section">
<h2>Table II — optimisers</h2>
{
            _html_table(
                table_ii,
                f"HCOMC with PSO, SA and NSGA-II, Conditions C1–C3 — {TABLE_CAPTION}.",
                table_id="table-ii",
            )
        }
</section>

<section id="table-iii-section">
<h2>Table III — controllers</h2>
{
            _html_table(
                table_iii,
                f"FIFO, Game and HCOMC, Conditions C1–C5 — {TABLE_CAPTION}.",
                table_id="table-iii",
            )
        }
</section>

<section id="merge-section">
<h2>Merge success</h2>
{_merge_section(runs)}
</section>

<section id="claims-section">
<h2>Claims of Section IV, paired by seed</h2>
{_claims_table(claim_frame)}
</section>

<section id="figures">
<h2>Figures</h2>
{figure_html}
</section>
{replay_html}
<footer>
<p>Generated by hcomc {_e(version)} (git revision {_e(revision)}) on {_e(created)} UTC.
Every number on this page is computed from the runs table; nothing is written by hand.
This page is self-contained: it loads no external resources.</p>
</footer>
""",
        generator=f"hcomc {version}",
    )
    target_dir = Path(out_dir)
    target_dir.mkdir(parents=True, exist_ok=True)
    target = target_dir / "report.html"
    with atomic_paths(target) as (tmp,):
        tmp.write_text(body, encoding="utf-8")
    return target
