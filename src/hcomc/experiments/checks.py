"""The checks of a faithful reproduction: thresholds fixed before the run, each reported as
met, not met or not measured, from a :class:`~hcomc.experiments.digest.Digest` alone."""

from __future__ import annotations

import numpy as np
import pandas as pd

from hcomc.experiments.claims import GROUPS
from hcomc.experiments.digest import Digest
from hcomc.experiments.prose import METRIC_NAMES, cell, md, num, pct, total, total_collisions
from hcomc.experiments.tables import BETTER

CHECKS = {
    "behind": 0.20,
    "lateral_c2": 0.30,
    "not_worse": 4,
    "cd_larger": 3,
    "game_c2": 0.50,
    "final_switch": 0.05,
    "merged": 0.99,
    "fallback_r": 0.02,
    "paper_claims": 85,
}
"""Thresholds of the checks of a faithful reproduction: VR behind VMC in at least this share
of HCOMC's runs; lateral cooperation in at least this share of its C2 runs; average
acceleration and LSRV not worse than each baseline in at least this many conditions;
critical distance larger than FIFO's (paired median) in at least this many conditions;
Game's VMC cooperating longitudinally in at least this share of C2 runs (Section IV-A: "VMC
implements longitudinal cooperation both in FIFO and game theory"); the replanning HCOMC-R's
last plan switching the commanded vehicle in at most this share of runs; the faithful HCOMC
merging in at least this share of runs, without a fallback and with one plan per run; HCOMC-R
falling back in at most this share of runs; the paper's family holding this many claims."""


def _worse(row: pd.Series) -> bool:
    """Whether HCOMC is worse than the baseline on the claim's metric (CI clear of 0)."""
    if BETTER[row["metric"]] == "larger":
        return bool(row["ci_high"] < 0)
    return bool(row["ci_low"] > 0)


def _against(d: Digest, metric: str, base: str) -> pd.DataFrame:
    """HCOMC's Table III claims on ``metric`` against ``base``."""
    part = d.claims[(d.claims["group"] == GROUPS["table3"]) & (d.claims["metric"] == metric)]
    return part[part["claim"].str.endswith(f"than {base}")]


def _not_worse(d: Digest, metric: str, base: str, unit: str) -> tuple[str, bool]:
    rows = _against(d, metric, base)
    worse = rows[[_worse(r) for _, r in rows.iterrows()]]
    ok = len(rows) - len(worse)
    text = f"{ok} of {len(rows)}"
    if len(worse):
        effects = "; ".join(
            f"{r['condition']}: {r['median_diff']:+.3g} [{r['ci_low']:+.3g}, {r['ci_high']:+.3g}]"
            for _, r in worse.iterrows()
        )
        text += f" (worse in {effects} {unit})"
    return text, ok >= CHECKS["not_worse"]


def checks_table(d: Digest) -> str:
    """The checks of a faithful reproduction (:data:`CHECKS`), each with its value and "met",
    "**not met**" or "not measured" (the runs lack the column)."""
    behind, runs = total(d, "behind", "HCOMC")
    lat, runs_c2 = cell(d, "C2", "HCOMC", "lateral")
    n_runs = d.provenance.seeded_runs + d.provenance.scenario_runs
    collisions = num(total_collisions(d))
    rows: list[tuple[str, str, bool | None]] = [
        (
            f"HCOMC merges VR behind VMC in ≥ {num(100 * CHECKS['behind'])} % of runs",
            f"{pct(behind, runs)} ({num(behind)} of {runs})",
            runs > 0 and behind / runs >= CHECKS["behind"],
        ),
        (
            f"lateral cooperation in ≥ {num(100 * CHECKS['lateral_c2'])} % of C2 runs",
            f"{pct(lat, runs_c2)} ({num(lat)} of {runs_c2})",
            runs_c2 > 0 and lat / runs_c2 >= CHECKS["lateral_c2"],
        ),
    ]
    n_cond = len(d.provenance.conditions)
    for metric, unit in (("average_acceleration", "m/s²"), ("lsrv", "m²")):
        for base in ("FIFO", "Game"):
            text, ok = _not_worse(d, metric, base, unit)
            rows.append(
                (
                    f"{METRIC_NAMES[metric]} not worse than {base} (CI of the paired median "
                    f"reaching 0 or better) in ≥ {CHECKS['not_worse']} of {n_cond} conditions",
                    text,
                    ok,
                )
            )
    cd = _against(d, "critical_distance", "FIFO")
    larger = list(cd.loc[cd["median_diff"] > 0, "condition"])
    clear = list(cd.loc[cd["ci_low"] > 0, "condition"])
    rows.append(
        (
            f"critical distance larger than FIFO's (paired median) in ≥ {CHECKS['cd_larger']} "
            f"of {n_cond} conditions",
            f"{len(larger)} of {len(cd)}: {', '.join(larger) or 'none'} (CI above 0: "
            f"{', '.join(clear) or 'none'})",
            len(larger) >= CHECKS["cd_larger"],
        )
    )
    rows += _decision_checks(d)
    rows.append(("no collision", f"{collisions} in {n_runs} runs", collisions == "0"))
    status = {True: "met", False: "**not met**", None: "not measured"}
    frame = pd.DataFrame([{"check": c, "result": r, "": status[ok]} for c, r, ok in rows])
    return md(frame)


def _decision_checks(d: Digest) -> list[tuple[str, str, bool | None]]:
    """Game's longitudinal cooperation in C2 and HCOMC's switches in its last plan (None:
    the runs do not record it)."""
    game, runs_c2 = cell(d, "C2", "Game", "longitudinal")
    return [
        (
            f"Game's VMC cooperates longitudinally in ≥ {num(100 * CHECKS['game_c2'])} % of "
            "C2 runs (Section IV-A)",
            f"{pct(game, runs_c2)} ({num(game)} of {runs_c2})",
            runs_c2 > 0 and game / runs_c2 >= CHECKS["game_c2"],
        ),
        *_faithful_checks(d),
        _share_check(
            d, "HCOMC-R", "fallback", "falls back (no feasible candidate)", CHECKS["fallback_r"]
        ),
        _share_check(
            d,
            "HCOMC-R",
            "final_switch",
            "last plan switches the commanded vehicle",
            CHECKS["final_switch"],
        ),
    ]


def _share_check(
    d: Digest, configuration: str, column: str, what: str, most: float
) -> tuple[str, str, bool | None]:
    """``configuration``'s runs with ``column`` in at most the share ``most`` (None: the
    runs do not record it or have no such configuration)."""
    k, runs = total(d, column, configuration)
    ok = None if not np.isfinite(k) or runs == 0 else k / runs <= most
    return (
        f"{configuration} {what} in ≤ {num(100 * most)} % of runs",
        f"{pct(k, runs)} ({num(k)} of {runs})" if runs else "—",
        ok,
    )


def _faithful_checks(d: Digest) -> list[tuple[str, str, bool | None]]:
    """HCOMC as published plans once: it merges, never falls back, makes one plan per run;
    the paper's family has its claims, none against a replanning variant."""
    merged, runs = total(d, "merged", "HCOMC")
    own = d.decisions[d.decisions["configuration"] == "HCOMC"]
    planned = own["runs"] - own["no_plan"]
    plans = float((own["plans_per_merge"] * planned).sum()) if len(own) else float("nan")
    paper = d.claims[d.claims["family"] == "paper"]
    against_r = paper["claim"].str.endswith("-R").sum()
    success = d.claims[d.claims["metric"] == "merged"]
    return [
        (
            f"HCOMC (plans once, as published) merges in ≥ {num(100 * CHECKS['merged'])} % of runs",
            f"{pct(merged, runs)} ({num(merged)} of {runs})",
            None if not np.isfinite(merged) else runs > 0 and merged / runs >= CHECKS["merged"],
        ),
        _share_check(d, "HCOMC", "fallback", "falls back (no feasible candidate)", 0.0),
        (
            "HCOMC makes one plan per run that plans",
            f"{num(plans)} plans in {num(planned.sum())} runs",
            None if not np.isfinite(plans) else bool(np.isclose(plans, planned.sum())),
        ),
        (
            f"the paper's Holm family holds its {CHECKS['paper_claims']} claims, none against "
            "a replanning variant",
            f"{len(paper)} claims, {int(against_r)} against FIFO-R/Game-R",
            len(paper) == CHECKS["paper_claims"] and against_r == 0,
        ),
        (
            "merge success is a claim (exact McNemar) per condition and baseline",
            f"{len(success)} claims",
            len(success) > 0,
        ),
    ]
