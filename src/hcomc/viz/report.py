"""Self-contained HTML report of a reproduction run.

:func:`write_report` writes one HTML page holding everything: the paper's Tables II and III
side by side with ours, the per-seed claims table, and the figures as base64 ``data:`` URIs
(made with :func:`hcomc.viz.page.figure_png`). The page loads nothing from anywhere (no CDN,
no external CSS, JavaScript or fonts, no links but relative ones to replay pages), so it can
be mailed, archived or opened offline.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from pathlib import Path

import pandas as pd

from hcomc.experiments.claim_text import families_line
from hcomc.experiments.claims import claims
from hcomc.experiments.paper import PAPER_METRICS
from hcomc.experiments.tables import TABLE_CAPTION, merge_success, paper_table
from hcomc.sim.manifest import atomic_paths, build_manifest
from hcomc.viz.page import _e, _figure_block, _html_table, html_page

__all__ = ["REQUIRED_COLUMNS", "write_report"]

#: Columns a results frame needs for the report's tables.
REQUIRED_COLUMNS = ("condition", "configuration", "seed", "mode", *PAPER_METRICS)

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


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
        "bootstrap CI; verdict by that CI; verdict (Holm) by the sign test (a run without a "
        "merge the worst outcome), Holm-corrected within its family; k of n: seeds in the "
        "paper's direction.</caption>\n"
        "<thead><tr><th>Claim</th><th>Condition</th><th>Verdict (95 % CI)</th>"
        "<th>Verdict (Holm)</th><th>p (Holm)</th><th>k of n seeds</th>"
        "<th>Median A - B [95 % CI]</th><th>Ours (mean A vs B)</th><th>Paper</th></tr>"
        "</thead>\n<tbody>\n" + "\n".join(rows) + "\n</tbody>\n</table>"
    )


def _verdict_counts(frame: pd.DataFrame) -> str:
    """The verdict counts of each Holm family apart: the paper's claims, the merge outcomes,
    the replanning variants', the extension's."""
    return families_line(frame)


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


def _run_summary(runs: pd.DataFrame) -> str:
    def listing(column: str) -> str:
        values = sorted({str(v) for v in runs[column].dropna()})
        return ", ".join(values) if values else "none"

    return (
        f"{len(runs)} seeded runs · conditions: {listing('condition')} · configurations: "
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
        Figure caption → PNG file content (e.g. from :func:`hcomc.viz.page.figure_png`),
        shown in order.
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
