"""Tables of a robustness campaign: one row per cell, and the page docs/robustness.md.

A cell is (condition, configuration, fault, channel, shield) over the campaign's seeds. Its
row counts runs, merges and collisions (all, and with a vehicle a live plan commanded), bounds
the share of runs with a collision from above (exact, one-sided 95 %: 0 in n runs gives about
3/n), and gives the distributions of the key vehicles' min TTC (5th percentile, median) and
max DRAC (median, 95th percentile), the shield's overrides and the plans lost or fallen back.
Beside it stand the paired effects of the cell's fault, channel and shield against the
nominal runs (no fault, ideal channel, no shield) of the same condition, configuration and
seeds, as ``hcomc compare`` computes them (:func:`hcomc.experiments.comparison.effects`):
the median difference with its 95 % bootstrap CI, a run without a merge the worse outcome in
the sign test, Holm's correction over every effect of the table. The page is written from
the runs only, stamped with the version and revision of the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from hcomc.experiments.comparison.effects import effects
from hcomc.experiments.comparison.view import interval_text

__all__ = [
    "CELL",
    "EFFECT_COLUMNS",
    "EFFECT_METRICS",
    "collision_bound",
    "fault_effects",
    "overview_view",
    "page",
    "summarise",
    "verdicts",
]

CELL = ["condition", "configuration", "fault", "channel", "shield"]
"""The columns that name a cell."""

NOMINAL = ("none", "ideal", False)
"""(fault, channel, shield) of the nominal runs every cell is paired with."""

EFFECT_METRICS = ("min_ttc", "max_drac")
"""The metrics whose paired effects against the nominal runs the tables give."""

_EFFECT_STATS = {"median_diff": "diff", "ci_low": "ci_low", "ci_high": "ci_high",
                 "p_holm": "p_holm", "verdict_holm": "verdict"}  # fmt: skip
"""An effect's columns (:class:`hcomc.experiments.comparison.effects.Effect`) -> suffix."""

EFFECT_COLUMNS = tuple(f"{m}_{n}" for m in EFFECT_METRICS for n in _EFFECT_STATS.values())
"""The effect columns of a summary: ``min_ttc_diff`` ... ``max_drac_verdict``."""

CONFIDENCE = 0.95
"""Level of the collision bound."""


def _quantile(q: float) -> Any:
    def f(values: pd.Series) -> float:
        finite = values[np.isfinite(values)]
        return float(np.quantile(finite, q)) if finite.size else float("inf")

    return f


def collision_bound(hit: int, runs: int) -> float:
    """Exact one-sided upper confidence bound (:data:`CONFIDENCE`) on the share of runs with
    a collision, from ``hit`` of ``runs`` (Clopper-Pearson, SciPy's ``binomtest``): 0 of n
    gives ``1 - 0.05**(1/n)``, about 3/n."""
    if runs == 0:
        return float("nan")
    test = stats.binomtest(hit, runs, alternative="less")
    return float(test.proportion_ci(CONFIDENCE, method="exact").high)


def summarise(runs: pd.DataFrame, by: Sequence[str] = CELL) -> pd.DataFrame:
    """One row per group of ``by`` (default: per cell), in the order the groups appear, with
    the paired effects against the nominal runs (:func:`fault_effects`) when ``by`` holds
    the fault, channel and shield."""
    grouped = runs.groupby(list(by), sort=False)
    table = grouped.agg(
        runs=("seed", "size"),
        merged=("merged", "sum"),
        runs_with_collision=("collisions", lambda c: int((c > 0).sum())),
        collisions=("collisions", "sum"),
        collisions_commanded=("collisions_commanded", "sum"),
        min_ttc_p5=("min_ttc", _quantile(0.05)),
        min_ttc_median=("min_ttc", _quantile(0.5)),
        max_drac_median=("max_drac", _quantile(0.5)),
        max_drac_p95=("max_drac", _quantile(0.95)),
        shield_brakes=("shield_brakes", "sum"),
        shield_holds=("shield_holds", "sum"),
        shield_releases=("shield_releases", "sum"),
        plans=("plans", "sum"),
        plans_lost=("plans_lost", "sum"),
        fallbacks=("fallbacks", "sum"),
    ).reset_index()
    table.insert(
        list(table.columns).index("collisions"), "collision_share_bound",
        [collision_bound(h, n) for h, n in zip(table.runs_with_collision, table.runs, strict=True)],
    )  # fmt: skip
    if not {"fault", "channel", "shield"} <= set(by):
        return table
    paired = fault_effects(runs, [c for c in by if c in CELL])
    if paired.empty:  # no nominal runs to pair with
        return table.assign(**dict.fromkeys(EFFECT_COLUMNS, np.nan))
    return table.merge(paired, how="left", on=list(by))


def _label(fault: object, channel: object, shield: object) -> str:
    return f"{fault}|{channel}|{'on' if bool(shield) else 'off'}"


def fault_effects(runs: pd.DataFrame, by: Sequence[str] = CELL) -> pd.DataFrame:
    """Per group of ``by`` other than the nominal one, the paired effects on
    :data:`EFFECT_METRICS` of its fault, channel and shield against the nominal runs of the
    same condition, configuration and seed (pooled over the conditions ``by`` leaves out:
    the pairs are then per condition and seed); Holm over every effect returned. Columns:
    ``by``, then per metric ``<metric>_diff``, ``_ci_low``, ``_ci_high``, ``_p_holm`` and
    ``_verdict`` (the Holm verdict: "lower", "higher" or "undecided")."""
    setting = [_label(*x) for x in zip(runs.fault, runs.channel, runs.shield, strict=True)]
    group = [c for c in by if c not in ("fault", "channel", "shield")]
    pooled = "condition" not in group
    frame = runs.assign(
        condition=runs[group].astype(str).agg("|".join, axis=1) if group else "",
        configuration=setting,
        seed=runs.condition.astype(str) + ":" + runs.seed.astype(str) if pooled else runs.seed,
    )  # fmt: skip
    nominal = _label(*NOMINAL)
    todo = [(x, nominal) for x in pd.unique(frame.configuration) if x != nominal]
    table = effects(frame, comparisons=todo, metrics=EFFECT_METRICS)
    if table.empty:
        return pd.DataFrame(columns=[*by, *EFFECT_COLUMNS])
    keys = table.condition.str.split("|", expand=True) if group else pd.DataFrame(index=table.index)
    setting_of = table.a.str.split("|", expand=True)
    out = pd.DataFrame({**{c: keys[k] for k, c in enumerate(group)},
                        "fault": setting_of[0], "channel": setting_of[1],
                        "shield": setting_of[2] == "on", "metric": table.metric})  # fmt: skip
    for column in ("median_diff", "ci_low", "ci_high", "p_holm", "verdict_holm"):
        out[column] = table[column]
    wide = out.pivot_table(index=list(by), columns="metric", values=list(_EFFECT_STATS),
                           sort=False, aggfunc="first")  # fmt: skip
    wide.columns = [f"{metric}_{_EFFECT_STATS[stat]}" for stat, metric in wide.columns]
    return wide[list(EFFECT_COLUMNS)].reset_index()


def _fmt(value: Any) -> str:
    if isinstance(value, bool | np.bool_):
        return "on" if value else "off"
    if isinstance(value, float | np.floating):
        return "∞" if np.isinf(value) else f"{value:.2f}"
    return str(value)


def _markdown(table: pd.DataFrame) -> str:
    head = "| " + " | ".join(table.columns) + " |"
    rule = "|" + "|".join("---" for _ in table.columns) + "|"
    rows = ["| " + " | ".join(_fmt(v) for v in row) + " |" for row in table.itertuples(index=False)]
    return "\n".join([head, rule, *rows])


OVERVIEW = ["fault", "channel", "configuration", "shield"]
"""The columns of the page's main table (summed over conditions)."""


def _count(runs: pd.DataFrame, column: str) -> str:
    """``"5 conditions"``, ``"1 condition"``: the distinct values of ``column``."""
    n = runs[column].nunique()
    return f"{n} {column}{'' if n == 1 else 's'}"


def _grid(runs: pd.DataFrame) -> str:
    """The campaign's grid in words: its axes' sizes, and the nominal cells it adds to a
    grid that leaves them out."""
    faulted = runs[[(f, c, bool(s)) != NOMINAL for f, c, s in
                    zip(runs.fault, runs.channel, runs.shield, strict=True)]]  # fmt: skip
    full = runs[CELL].drop_duplicates().shape[0] == np.prod([runs[c].nunique() for c in CELL])
    part = runs if full else faulted
    text = (f"{_count(part, 'condition')} × {_count(part, 'configuration')} × "
            f"{_count(part, 'fault')} × {_count(part, 'channel')} × shield off/on × "
            f"{_count(runs, 'seed')}")  # fmt: skip
    return text if full else text + ", and the nominal cell of each condition and configuration"


def _effect_text(row: dict[str, Any], metric: str) -> str:
    """ "median [low, high]" of a paired effect, with ↓ / ↑ where Holm's correction finds
    the setting lower / higher than nominal; "nominal" for the nominal row."""
    if (row["fault"], row["channel"], bool(row["shield"])) == NOMINAL:
        return "nominal"
    text = interval_text(row[f"{metric}_diff"], row[f"{metric}_ci_low"], row[f"{metric}_ci_high"])
    return text + {"lower": " ↓", "higher": " ↑"}.get(str(row[f"{metric}_verdict"]), "")


def overview_view(table: pd.DataFrame) -> pd.DataFrame:
    """The page's main table from :func:`summarise` by :data:`OVERVIEW`: counts, the
    collision bound as a percentage, quantiles to two decimals, effects as intervals."""
    rows = []
    for row in table.to_dict("records"):
        rows.append({
            **{c: row[c] for c in ("fault", "channel", "configuration")},
            "shield": "on" if row["shield"] else "off",
            "merged": f"{row['merged']}/{row['runs']}",
            "runs with a collision (95 % bound)":
                f"{row['runs_with_collision']} (< {100 * row['collision_share_bound']:.2g} %)",
            "commanded": row["collisions_commanded"],
            "least TTC p5 [s]": _fmt(row["min_ttc_p5"]),
            "Δ least TTC [s]": _effect_text(row, "min_ttc"),
            "largest DRAC p95 [m/s²]": _fmt(row["max_drac_p95"]),
            "Δ largest DRAC [m/s²]": _effect_text(row, "max_drac"),
            "shield brakes/holds/releases":
                f"{row['shield_brakes']}/{row['shield_holds']}/{row['shield_releases']}",
            "plans lost": row["plans_lost"], "fallbacks": row["fallbacks"],
        })  # fmt: skip
    return pd.DataFrame(rows)


def verdicts(table: pd.DataFrame) -> str:
    """What the paired effects of :func:`summarise`'s ``table`` say, counted by Holm's
    verdict, each sentence only as its counts have it."""
    settings = zip(table.fault, table.channel, table.shield, strict=True)
    shown = table[[(f, c, bool(s)) != NOMINAL for f, c, s in settings]]
    n = len(shown)
    if n == 0:
        return "No setting other than the nominal one was run."
    if shown[list(EFFECT_COLUMNS)].isna().all().all():
        return "No nominal runs (no fault, ideal channel, no shield) to pair the settings with."
    lower_ttc = int((shown.min_ttc_verdict == "lower").sum())
    higher_drac = int((shown.max_drac_verdict == "higher").sum())
    better = int(((shown.min_ttc_verdict == "higher") | (shown.max_drac_verdict == "lower")).sum())
    text = (f"Against the nominal runs of the same condition, controller and seeds, {lower_ttc} "
            f"of the {n} other settings lower the key vehicles' least TTC and {higher_drac} "
            "raise their largest DRAC (sign test, Holm's correction over every effect of the "
            "table, α = 0.05)")  # fmt: skip
    if better:
        text += f"; {better} raise the least TTC or lower the largest DRAC"
    return text + "."


def page(runs: pd.DataFrame, stamp: str, command: str) -> str:
    """The generated part of docs/robustness.md: the overview table (per fault, channel,
    configuration and shield setting, over all conditions and seeds, with the paired effects
    against the nominal runs), what the effects say, and every run with a collision
    involving a commanded vehicle."""
    overview = summarise(runs, OVERVIEW)
    worst = runs[runs["collisions_commanded"] > 0].sort_values(["fault", "channel", "seed"])
    worst_cols = ["condition", "configuration", "fault", "channel", "shield", "seed",
                  "collision_pair", "fault_involved", "min_ttc", "max_drac"]  # fmt: skip
    lines = [
        f"<!-- generated by `{command}`; {stamp} -->",
        "",
        f"{len(runs)} runs: {_grid(runs)} "
        f"({stamp}); simulated and measured in {runs['wall_s'].sum() / 60:.1f} CPU-minutes "
        f"({runs['wall_s'].mean():.2f} s per run).",
        "",
        _markdown(overview_view(overview)),
        "",
        "Δ: median paired difference from the nominal runs (no fault, ideal channel, no shield) "
        "of the same condition, controller and seed [95 % bootstrap CI]; ↓ / ↑: lower / higher "
        "by the sign test with Holm's correction over every Δ of the table (a run without a "
        "merge counts as the worse outcome); the collision bound is exact (Clopper-Pearson, "
        "one-sided: 0 in n runs gives about 3/n).",
        "",
        verdicts(overview),
        "",
        f"Runs with a collision involving a commanded vehicle during a live plan: "
        f"{len(worst)} (shield off: {int((~worst['shield'].astype(bool)).sum())}, "
        f"shield on: {int(worst['shield'].astype(bool).sum())}).",
        "",
    ]
    if len(worst):
        lines += [_markdown(worst[worst_cols]), ""]
    return "\n".join(lines)
