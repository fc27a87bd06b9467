"""Self-contained HTML report of a controller comparison (``hcomc compare``).

:func:`write_compare_report` writes ``report.html``: provenance (suite and version, hcomc
version, git revision, command), how to read the tables, merge success per cell and
configuration with a bar chart, the paired comparison of merge success, and per cell the
paired effects with a forest plot of the paired differences. Like the reproduction's report
(:mod:`hcomc.viz.report`) it loads nothing: styles inline, no script, figures embedded as
base64 PNG. Every number comes from the runs.
"""

from __future__ import annotations

import base64
import html
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from hcomc.experiments.claims import MIN_PAIRS
from hcomc.experiments.comparison.effects import paired_differences
from hcomc.experiments.comparison.view import (
    effects_view,
    means_view,
    metric_label,
    safety_view,
    success_pairs_view,
    success_view,
)
from hcomc.sim.manifest import atomic_paths
from hcomc.viz.common import new_figure
from hcomc.viz.page import figure_png, html_page

__all__ = ["differences_figure", "success_figure", "write_compare_report"]

_CSS = """
body { font-family: system-ui, sans-serif; margin: 0; background: #f6f7f9; color: #1d2330;
       line-height: 1.45; }
main { max-width: 1240px; margin: 0 auto; padding: 1.5rem 2rem 2.5rem; background: #fff; }
h1 { color: #2a4d69; margin-bottom: 0.2rem; }
h2 { color: #2a4d69; border-bottom: 1px solid #d5dbe3; margin-top: 2rem; }
.meta { font-size: 0.85rem; color: #555; margin: 0.1rem 0; }
code { background: #eef1f5; padding: 0 0.25em; border-radius: 3px; }
.note { background: #f2f6fa; border-left: 4px solid #4b86b4; padding: 0.4rem 1rem;
        font-size: 0.92rem; }
table { border-collapse: collapse; margin: 0.6rem 0; font-size: 0.82rem; width: 100%; }
th, td { border: 1px solid #d5dbe3; padding: 0.2rem 0.45rem; text-align: left; }
th { background: #e8edf3; }
tr.decided td { background: #e8f0fb; }
figure { margin: 1rem 0; text-align: center; }
figure img { max-width: 100%; border: 1px solid #e1e5ea; }
figcaption { font-size: 0.88rem; color: #444; }
.empty { color: #888; font-style: italic; }
"""

_DOT, _MEDIAN, _DECIDED = "#9aa7b6", "#1d2330", "#08519c"


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _table(frame: pd.DataFrame, caption: str, decided: Sequence[bool] | None = None) -> str:
    """An HTML table of text cells; rows flagged in ``decided`` are shaded."""
    if frame.empty:
        return f'<p class="empty">{_e(caption)}: nothing to show.</p>'
    head = "".join(f"<th>{_e(c)}</th>" for c in frame.columns)
    rows = []
    for i, record in enumerate(frame.itertuples(index=False)):
        css = ' class="decided"' if decided is not None and decided[i] else ""
        rows.append(f"<tr{css}>" + "".join(f"<td>{_e(v)}</td>" for v in record) + "</tr>")
    return (
        f"<table>\n<caption>{_e(caption)}</caption>\n<thead><tr>{head}</tr></thead>\n<tbody>\n"
        + "\n".join(rows)
        + "\n</tbody>\n</table>"
    )


def _figure(png: bytes, caption: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (
        f'<figure><img src="data:image/png;base64,{data}" alt="{_e(caption)}">'
        f"<figcaption>{_e(caption)}</figcaption></figure>"
    )


def differences_figure(runs: pd.DataFrame, effects: pd.DataFrame, condition: str) -> Figure:
    """Forest plot of one cell: a panel per metric, a row per comparison A vs B; grey dots
    are the per-seed differences A - B, the black (blue when decided) mark and bar the median
    and its 95 % bootstrap CI, the dashed line 0."""
    cell = effects[effects["condition"] == condition]
    metrics = list(pd.unique(cell["metric"]))
    comparisons = list(dict.fromkeys(zip(cell["a"], cell["b"], strict=True)))
    fig = new_figure(3.2 * max(len(metrics), 1), 0.9 + 0.42 * max(len(comparisons), 1))
    axes = fig.subplots(1, max(len(metrics), 1), sharey=True, squeeze=False)[0]
    rng = np.random.default_rng(0)  # jitter only; fixed so the page is reproducible
    for ax, metric in zip(axes, metrics, strict=False):
        for y, (a, b) in enumerate(comparisons):
            diff = paired_differences(runs, condition, metric, a, b)
            ax.scatter(diff, y + rng.uniform(-0.15, 0.15, diff.size), s=9, color=_DOT, lw=0)
            row = cell[(cell["metric"] == metric) & (cell["a"] == a) & (cell["b"] == b)]
            if row.empty or not np.isfinite(row["median_diff"].iloc[0]):
                continue
            r = row.iloc[0]
            colour = _DECIDED if r["verdict"] != "undecided" else _MEDIAN
            ax.errorbar(
                [r["median_diff"]], [y],
                xerr=[[r["median_diff"] - r["ci_low"]], [r["ci_high"] - r["median_diff"]]],
                fmt="D", ms=5, color=colour, capsize=3, lw=1.4,
            )  # fmt: skip
        ax.axvline(0.0, color="#888", ls="--", lw=0.8)
        ax.set_title(metric_label(metric), fontsize=9)
        ax.tick_params(labelsize=8)
    axes[0].set_yticks(range(len(comparisons)))
    axes[0].set_yticklabels([f"{a} − {b}" for a, b in comparisons], fontsize=8)
    axes[0].set_ylim(len(comparisons) - 0.5, -0.5)
    fig.suptitle(f"{condition}: paired differences A − B by seed", fontsize=10)
    return fig


def success_figure(success: pd.DataFrame) -> Figure:
    """Merge success rate per cell (groups) and configuration (bars), k/n above each bar."""
    cells = list(pd.unique(success["condition"]))
    confs = list(pd.unique(success["configuration"]))
    fig = new_figure(max(5.0, 0.5 * len(cells) * len(confs) + 2.0), 3.2)
    ax = fig.add_subplot()
    width = 0.8 / max(len(confs), 1)
    for j, conf in enumerate(confs):
        part = success[success["configuration"] == conf].set_index("condition").reindex(cells)
        x = np.arange(len(cells)) + (j - (len(confs) - 1) / 2) * width
        ax.bar(x, part["rate"].fillna(0.0), width, label=conf)
        for xi, k, n in zip(x, part["merged"], part["runs"], strict=True):
            if np.isfinite(n):
                ax.text(xi, 1.01, f"{int(k)}/{int(n)}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(range(len(cells)), cells)
    ax.set_ylim(0.0, 1.12)
    ax.set_ylabel("runs in which VR merged")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return fig


def _provenance(record: Mapping[str, Any]) -> str:
    runs = record.get("runs") or {}
    what = ("corridors", ", ".join(record["corridors"])) if "corridors" in record else (
        "suite", record.get("suite", "—"))  # fmt: skip
    return (
        f'<p class="meta">{what[0]} <code>{_e(what[1])}</code> · hcomc '
        f"<code>{_e(record.get('hcomc_version', '—'))}</code> · git revision "
        f"<code>{_e(record.get('git_revision', '—'))}</code> · engine "
        f"<code>{_e(record.get('engine', '—'))}</code> · generated "
        f"{_e(record.get('created_utc', '—'))} (UTC)</p>\n"
        f'<p class="meta">command: <code>{_e(record.get("command", "—"))}</code></p>\n'
        f'<p class="meta">overrides of every cell: '
        f"<code>{_e(json.dumps(record.get('overrides') or {}))}</code> · runs: "
        f"{_e(', '.join(f'{k} {v}' for k, v in runs.items()) or '—')}</p>"
    )


_HOW_TO_READ = f"""<div class="note">
<p>Runs are paired by cell and seed: every configuration meets the same traffic. For each
metric, <em>median A−B</em> is the median over seeds of the paired difference with its 95 %
bootstrap CI. <em>verdict</em>: "lower" (A lower than B) when the CI lies below 0, "higher"
when above 0, "undecided" otherwise or when fewer than {MIN_PAIRS} seeds differ.
<em>favours</em> names the configuration the verdict favours by the metric's preferred
direction (↑ larger is better, ↓ smaller is better). <em>A&lt;B</em>: k of n seeds with A
lower, a run without a merge counting as its pair's worse value; <em>A&gt;B</em>: seeds with A
higher; <em>failed A/B</em>: the seeds on which A's / B's ramp vehicle did not merge;
<em>excluded</em>: seeds both ran that give no pair (neither merged, or a value is undefined).
<em>p (Holm)</em>: two-sided exact sign test, Holm-adjusted over every effect on this page;
<em>verdict (Holm)</em> at p &lt; 0.05 and <em>favours (Holm)</em> the configuration it
favours. Numbers are rounded to two significant digits of their interval's half-width. Merge
success counts every run; its paired comparison is the exact McNemar test of the seeds in
which only one of the two merged, Holm-adjusted
over its own table. Shaded rows are decided.</p></div>"""


def write_compare_report(
    out_dir: Path,
    runs: pd.DataFrame,
    effects: pd.DataFrame,
    success: pd.DataFrame,
    pairs: pd.DataFrame,
    record: Mapping[str, Any],
    *,
    notes: Sequence[str] = (),
    title: str = "hcomc compare",
    means: pd.DataFrame | None = None,
    safety: pd.DataFrame | None = None,
) -> Path:
    """Write ``out_dir/report.html`` (atomically) and return its path.

    ``runs`` is the runs table, ``effects``, ``success`` and ``pairs`` the frames of
    :func:`hcomc.experiments.comparison.effects.effects`,
    :func:`~hcomc.experiments.comparison.success.merge_success` and
    :func:`~hcomc.experiments.comparison.success.success_pairs`, ``record`` the folder's record
    (suite, versions, command) and ``notes`` lines shown under the header (e.g. settings in
    which two compared folders differ); ``means``, the frame of
    :func:`~hcomc.experiments.comparison.means.means`, adds the per-controller means, and
    ``safety``, the frame of :func:`~hcomc.experiments.comparison.safety.safety_extremes`,
    the safety extremes.
    """
    note_html = "".join(f'<p class="note">{_e(n)}</p>\n' for n in notes)
    sections = []
    for condition in pd.unique(effects["condition"]):
        cell = effects[effects["condition"] == condition]
        view = effects_view(cell).drop(columns="cell")
        fig = differences_figure(runs, effects, str(condition))
        sections.append(
            f"<h2>{_e(condition)}</h2>\n"
            + _table(view, f"Paired effects in {condition}", list(cell["verdict"] != "undecided"))
            + "\n"
            + _figure(figure_png(fig), f"{condition}: paired differences A − B by seed")
        )
    success_html = _table(success_view(success), "Runs in which VR merged, k/n (rate)")
    if not success.empty:
        success_html += _figure(figure_png(success_figure(success)), "Merge success rate")
    pairs_html = _table(
        success_pairs_view(pairs),
        "Merge success paired by seed (exact McNemar test)",
        list(pairs["verdict_holm"] != "undecided") if len(pairs) else None,
    )
    effects_html = "\n".join(sections) or '<p class="empty">No paired effects.</p>'
    means_html = (
        ""
        if means is None or means.empty
        else "<h2>Means</h2>\n"
        + _table(means_view(means), "Over each controller's runs with a value, ± 95 % t interval")
    )
    if safety is not None and not safety.empty:
        means_html += "\n<h2>Safety extremes</h2>\n" + _table(
            safety_view(safety),
            "Least TTC and largest DRAC over each controller's runs (with their seed), and "
            "the collisions of those runs",
        )
    body = html_page(
        title,
        f"""<h1>{_e(title)}</h1>
{_provenance(record)}
{note_html}
<h2>How to read this</h2>
{_HOW_TO_READ}
<h2>Merge success</h2>
{success_html}
<h2>Merge success, paired</h2>
{pairs_html}
{means_html}
{effects_html}
""",
        css=_CSS,
    )
    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / "report.html"
    with atomic_paths(target) as (tmp,):
        tmp.write_text(body, encoding="utf-8")
    return target
