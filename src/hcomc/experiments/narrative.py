"""The generated parts of the published documentation: every table and every sentence with a
number, made from a :class:`~hcomc.experiments.digest.Digest` alone.

:func:`values` returns them as the named values the templates of
:mod:`hcomc.viz.publish` put in place of their ``{{ name }}`` placeholders. Text
without numbers is the templates'; nothing with a number is written by hand.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from hcomc.experiments.claims import ALPHA, GROUPS, MIN_PAIRS, VERDICTS, verdict_counts
from hcomc.experiments.digest import Digest
from hcomc.experiments.paper import PAPER_METRICS, TABLE_III
from hcomc.experiments.tables import (
    BETTER,
    BOOTSTRAP_RESAMPLES,
    LABELS,
    TABLE_CAPTION,
    TIE_TOLERANCE,
    format_table,
    to_markdown,
)

CHECKS = {"behind": 0.20, "lateral_c2": 0.30, "not_worse": 4, "cd_larger": 3}
"""Thresholds of the checks of a faithful HCOMC: VR behind VMC in at least this share of
HCOMC's runs; lateral cooperation in at least this share of its C2 runs; average
acceleration and LSRV not worse than each baseline in at least this many conditions;
critical distance larger than FIFO's (paired median) in at least this many conditions."""

_METRIC_NAMES = {m: m.replace("_", " ") for m in PAPER_METRICS}


def _g(x: float) -> str:
    """Four significant digits, "—" for NaN."""
    return "—" if not np.isfinite(x) else f"{x:.4g}"


def _sci(x: float, digits: int = 1) -> str:
    """Scientific notation without a padded exponent: 3.7e-4."""
    mantissa, exponent = f"{x:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _p(x: float) -> str:
    """A p-value: three decimals, or two significant digits below 0.001."""
    if not np.isfinite(x):
        return "—"
    return _sci(x) if x < 1e-3 else f"{x:.3f}"


def _pct(k: float, n: float) -> str:
    return "—" if not n or not np.isfinite(k) else f"{round(100 * k / n)} %"


def _num(x: float) -> str:
    """A count or a value: an integer without decimals, else four significant digits."""
    if not np.isfinite(x):
        return "—"
    return str(int(x)) if float(x).is_integer() else f"{x:.4g}"


def _join(items: Iterable[str]) -> str:
    """The items as prose: "a", "a and b", "a, b and c"."""
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _weighted(values: pd.Series, weights: pd.Series) -> float:
    """Mean of per-cell means weighted by their runs (NaN without weight or values)."""
    ok = values.notna() & (weights > 0)
    if not ok.any():
        return float("nan")
    return float(np.average(values[ok], weights=weights[ok]))


def _md(frame: pd.DataFrame) -> str:
    return to_markdown(frame).rstrip("\n")


# --------------------------------------------------------------------------- run and decisions
def _total(d: Digest, column: str, configuration: str | None = None) -> tuple[float, int]:
    """Sum of a decisions column and of its runs (over one configuration, or all)."""
    dec = d.decisions
    part = dec if configuration is None else dec[dec["configuration"] == configuration]
    return float(part[column].sum(min_count=1)), int(part["runs"].sum())


def _cell(d: Digest, condition: str, configuration: str, column: str) -> tuple[float, int]:
    dec = d.decisions
    row = dec[(dec["condition"] == condition) & (dec["configuration"] == configuration)]
    if row.empty:
        return float("nan"), 0
    return float(row[column].iloc[0]), int(row["runs"].iloc[0])


def run_facts(d: Digest) -> dict[str, str]:
    """Scope and provenance of the run, and the quoted config values."""
    prov, settings = d.provenance, d.provenance.settings
    collisions = float(d.decisions["collisions"].sum(min_count=1))
    if "collisions" in d.scenario:
        collisions += float(d.scenario["collisions"].sum())
    n_runs = prov.seeded_runs + prov.scenario_runs
    lsrv = [v[3] for v in TABLE_III.values()]
    fuel = [v[4] for v in TABLE_III.values()]
    return {
        "command": prov.command,
        "version": prov.version,
        "revision": prov.revision,
        "short_revision": prov.revision[:12],
        "n_runs": str(n_runs),
        "n_seeded": str(prov.seeded_runs),
        "n_scenario": str(prov.scenario_runs),
        "seeds": str(prov.seeds),
        "seed_range": f"0–{prov.seeds - 1}" if prov.seeds > 1 else "0",
        "n_conditions": str(len(prov.conditions)),
        "n_configurations": str(len(prov.configurations)),
        "configurations": ", ".join(prov.configurations),
        "collisions": _num(collisions),
        "a_merg": _num(settings["a_merg"]),
        "virtual_max_decel": _num(settings["virtual_max_decel"]),
        "safety_threshold": _num(settings["safety_threshold"]),
        "cav_time_headway": _num(settings["cav_time_headway"]),
        "duration": _num(settings["duration"]),
        "road_length": _num(settings["road_length"] / 1000.0),
        "resamples": str(BOOTSTRAP_RESAMPLES),
        "confidence": _num(100 * (1 - ALPHA)),
        "alpha": _num(ALPHA),
        "min_pairs": str(MIN_PAIRS),
        "tie_tolerance": _sci(TIE_TOLERANCE, 0),
        "paper_lsrv_range": f"{min(lsrv):.0f}–{max(lsrv):.0f}",
        "paper_fuel": f"{np.mean(fuel):.0f}",
    }


def hcomc_facts(d: Digest) -> str:
    """One sentence: what HCOMC decided over the run."""
    behind, runs = _total(d, "behind", "HCOMC")
    lateral, all_runs = _total(d, "lateral", "HCOMC")
    lat_c2, runs_c2 = _cell(d, "C2", "HCOMC", "lateral")
    own = d.decisions[d.decisions["configuration"] == "HCOMC"]
    mean_plans = _weighted(own["plans_per_merge"], own["runs"] - own["no_plan"])
    merged, _ = _total(d, "merged", "HCOMC")
    merge = f"VR merged in {_num(merged)} of {runs} runs, " if np.isfinite(merged) else ""
    return (
        f"{merge}behind VMC in {_num(behind)} ({_pct(behind, runs)}); lateral cooperation in "
        f"{_num(lat_c2)} of {runs_c2} C2 runs ({_pct(lat_c2, runs_c2)}) and {_num(lateral)} of "
        f"{all_runs} runs overall; {_g(mean_plans)} plans per merge on average"
    )


def decisions_table(d: Digest) -> str:
    """Per configuration over all conditions: sequence, modes, plans, Eq. 19's branches,
    decision time and fallbacks (and merges, plan switches, the cause of lateral plans when
    the runs have them)."""
    tau = run_facts(d)["safety_threshold"]
    rows = []
    for conf, part in d.decisions.groupby("configuration", sort=False):
        runs = int(part["runs"].sum())

        def total(col: str, part: pd.DataFrame = part) -> float:
            return float(part[col].sum(min_count=1))

        planned = part["runs"] - part["no_plan"]
        rec: dict[str, str] = {"configuration": str(conf), "runs": str(runs)}
        if np.isfinite(total("merged")):
            rec["merged"] = _num(total("merged"))
        rec["VR behind VMC"] = f"{_num(total('behind'))} ({_pct(total('behind'), runs)})"
        rec["lateral / longitudinal / none"] = " / ".join(
            _num(total(m)) for m in ("lateral", "longitudinal", "none")
        )
        rec["plans per merge (mean)"] = _g(_weighted(part["plans_per_merge"], planned))
        if part["plan_switches"].notna().any():
            rec["plan switches (mean)"] = _g(_weighted(part["plan_switches"], planned))
        gate, low = total("gate"), total("min_safety")
        branch = "—" if gate + low == 0 else f"{_num(gate)} / {_num(low)}"
        rec[f'Eq. 19: "U_safe ≤ {tau}" / "all > {tau}"'] = branch
        if d.decisions["lateral_equilibrium"].notna().any():
            rec["lateral by equilibrium / safety rule"] = (
                f"{_num(total('lateral_equilibrium'))} / {_num(total('lateral_safety_rule'))}"
                if total("lateral") > 0
                else "—"
            )
        rec["decision time median [ms]"] = _g(float(part["decision_ms"].median()))
        rec["fallbacks"] = _num(total("fallback"))
        rows.append(rec)
    return _md(pd.DataFrame(rows))


def decisions_by_condition(d: Digest) -> str:
    """HCOMC's decisions condition by condition, one sentence each."""
    conditions = list(d.provenance.conditions)

    def series(col: str) -> str:
        return _join([_num(_cell(d, c, "HCOMC", col)[0]) for c in conditions])

    runs = _join([str(_cell(d, c, "HCOMC", "runs")[1]) for c in conditions])
    where = f"{conditions[0]}–{conditions[-1]}" if len(conditions) > 1 else conditions[0]
    hdv, n5 = _cell(d, conditions[-1], "HCOMC", "vmc_hdv")
    none, _ = _cell(d, conditions[-1], "HCOMC", "none")
    cav = d.provenance.settings["cav_penetration"].get(conditions[-1], float("nan"))
    return (
        f"HCOMC by condition ({where}, of {runs} runs): VR behind VMC in {series('behind')}; "
        f"lateral cooperation in {series('lateral')}; longitudinal in {series('longitudinal')}; "
        f'Eq. 19\'s "all U_safe > {run_facts(d)["safety_threshold"]}" branch in '
        f"{series('min_safety')}. In {conditions[-1]} ({_num(100 * cav)} % CAVs) VMC is an HDV "
        f'in {_num(hdv)} of {n5} runs and HCOMC plans only VR\'s own merge (mode "none") in '
        f"{_num(none)}."
    )


# --------------------------------------------------------------------------- tables II and III
def paper_tables(d: Digest) -> dict[str, str]:
    """Tables II and III in Markdown, their caption, and the range of our critical
    distances."""
    out = {"table_caption": TABLE_CAPTION}
    for which, key in (("II", "table2"), ("III", "table3")):
        part = d.tables[d.tables["table"] == which].reset_index(drop=True)
        out[key] = _md(format_table(part)) if len(part) else "(no runs)"
    cd = d.tables["critical_distance"].dropna()
    out["cd_range"] = f"{cd.min():.0f}–{cd.max():.0f}" if len(cd) else "—"
    return out


# --------------------------------------------------------------------------- claims
def verdict_table(d: Digest) -> str:
    """Claims per group and verdict, by the CI rule and by the Holm-corrected test."""
    ci = verdict_counts(d.claims, "verdict")
    holm = verdict_counts(d.claims, "verdict_holm")
    rows = []
    for group in ci.index:
        rec = {"group": str(group), "claims": str(int(ci.loc[group].sum()))}
        for v in VERDICTS:
            rec[f"{v} (CI)"] = str(int(ci.loc[group, v]))
        for v in VERDICTS:
            rec[f"{v} (Holm)"] = str(int(holm.loc[group, v]))
        rows.append(rec)
    return _md(pd.DataFrame(rows))


def verdict_summary(d: Digest, column: str) -> str:
    """The counts of one verdict column as prose: "a hold, b are reversed and c
    undecided"."""
    counts = verdict_counts(d.claims, column).loc["all"]
    return (
        f"{counts['holds']} hold, {counts['reversed']} are reversed and "
        f"{counts['undecided']} undecided"
    )


def table3_matrix(d: Digest) -> str:
    """Table III's claims by metric (rows) and condition (columns): the CI verdict against
    FIFO / against Game, with the Holm verdict where it differs."""
    part = d.claims[d.claims["group"] == GROUPS["table3"]]
    conditions = list(dict.fromkeys(part["condition"]))
    rows = []
    for metric in dict.fromkeys(part["metric"]):
        rec = {"metric": _METRIC_NAMES.get(metric, metric)}
        for cond in conditions:
            cells = []
            for base in ("FIFO", "Game"):
                hit = part[
                    (part["metric"] == metric)
                    & (part["condition"] == cond)
                    & part["claim"].str.endswith(f"than {base}")
                ]
                if hit.empty:
                    cells.append("—")
                    continue
                ci, holm = hit["verdict"].iloc[0], hit["verdict_holm"].iloc[0]
                cells.append(ci if ci == holm else f"{ci} (Holm: {holm})")
            rec[cond] = " / ".join(cells)
        rows.append(rec)
    return _md(pd.DataFrame(rows))


def claims_table(d: Digest, group: str) -> str:
    """The claims of one group (a key of :data:`GROUPS`) as a Markdown table."""
    part = d.claims[d.claims["group"] == GROUPS[group]]
    if part.empty:
        return "(no runs for these claims)"
    rows = []
    for _, r in part.iterrows():
        rec = {"claim": r["claim"], "condition": r["condition"]}
        if r["metric"] == "mode":
            rec["ours"] = r["ours"]
        else:
            effect = f"{_g(r['median_diff'])} [{_g(r['ci_low'])}, {_g(r['ci_high'])}]"
            rec["median A − B [CI]"] = effect
        rec["verdict"] = r["verdict"]
        rec["p (Holm)"] = _p(r["p_holm"])
        rec["verdict (Holm)"] = r["verdict_holm"]
        rec["k of n"] = f"{int(r['holds'])} of {int(r['n'])}"
        if "uniform" in part:
            rec["uniform"] = r["uniform"] or "—"
        rows.append(rec)
    return _md(pd.DataFrame(rows))


def verdict_lists(d: Digest, column: str = "verdict") -> dict[str, str]:
    """The claims that hold and those reversed (replanning comparisons left out), claim by
    claim with their conditions: "HCOMC fuel lower than FIFO (C1, C3)"."""
    part = d.claims[d.claims["group"] != GROUPS["replanning"]]
    out = {}
    for verdict in ("holds", "reversed"):
        hits = part[part[column] == verdict]
        items = [
            f"{claim} ({', '.join(group['condition'])})"
            for claim, group in hits.groupby("claim", sort=False)
        ]
        out[verdict] = "; ".join(items) if items else "none"
    return out


def mode_sentence(d: Digest) -> str:
    """HCOMC's cooperation modes in the conditions of the mode claims."""
    part = d.claims[d.claims["group"] == GROUPS["mode"]]
    items = [f"{r['condition']}: {r['ours']} (of {int(r['n'])} runs)" for _, r in part.iterrows()]
    return "HCOMC's last plan's cooperation mode — " + "; ".join(items) + "."


# --------------------------------------------------------------------------- checks
def _worse(row: pd.Series) -> bool:
    """Whether HCOMC is worse than the baseline on the claim's metric (CI clear of 0)."""
    if BETTER[row["metric"]] == "larger":
        return bool(row["ci_high"] < 0)
    return bool(row["ci_low"] > 0)


def _against(d: Digest, metric: str, base: str) -> pd.DataFrame:
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
    """The checks of a faithful HCOMC (:data:`CHECKS`), each with its value and "met" or
    "**not met**"."""
    behind, runs = _total(d, "behind", "HCOMC")
    lat, runs_c2 = _cell(d, "C2", "HCOMC", "lateral")
    n_runs = d.provenance.seeded_runs + d.provenance.scenario_runs
    collisions = run_facts(d)["collisions"]
    rows = [
        (
            f"HCOMC merges VR behind VMC in ≥ {_num(100 * CHECKS['behind'])} % of runs",
            f"{_pct(behind, runs)} ({_num(behind)} of {runs})",
            runs > 0 and behind / runs >= CHECKS["behind"],
        ),
        (
            f"lateral cooperation in ≥ {_num(100 * CHECKS['lateral_c2'])} % of C2 runs",
            f"{_pct(lat, runs_c2)} ({_num(lat)} of {runs_c2})",
            runs_c2 > 0 and lat / runs_c2 >= CHECKS["lateral_c2"],
        ),
    ]
    n_cond = len(d.provenance.conditions)
    for metric, unit in (("average_acceleration", "m/s²"), ("lsrv", "m²")):
        for base in ("FIFO", "Game"):
            text, ok = _not_worse(d, metric, base, unit)
            rows.append(
                (
                    f"{_METRIC_NAMES[metric]} not worse than {base} (CI of the paired median "
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
    rows.append(("no collision", f"{collisions} in {n_runs} runs", collisions == "0"))
    frame = pd.DataFrame(
        [{"check": c, "result": r, "": "met" if ok else "**not met**"} for c, r, ok in rows]
    )
    return _md(frame)


# --------------------------------------------------------------------------- paper scenario
def scenario_table(d: Digest) -> str:
    """The deterministic paper scenario's runs of FIFO, Game, HCOMC and any configuration
    the paper does not name (not the replanning baselines or the other optimisers)."""
    variants = ("FIFO-R", "Game-R", "HCOMC-PSO", "HCOMC-SA")  # Table III's controllers only
    part = d.scenario[~d.scenario["configuration"].isin(variants)].copy()
    for m in PAPER_METRICS:
        if m in part:
            part[m] = [_g(v) for v in part[m]]
    part = part.drop(columns=[c for c in ("collisions", "merged") if c in part])
    return _md(part.rename(columns=LABELS))


def values(d: Digest) -> dict[str, str]:
    """Every placeholder value of the templates, from the digest alone."""
    lists = verdict_lists(d)
    out = {
        **run_facts(d),
        **paper_tables(d),
        "hcomc_facts": hcomc_facts(d),
        "decisions_table": decisions_table(d),
        "decisions_by_condition": decisions_by_condition(d),
        "n_claims": str(len(d.claims)),
        "verdicts_ci": verdict_summary(d, "verdict"),
        "verdicts_holm": verdict_summary(d, "verdict_holm"),
        "verdict_table": verdict_table(d),
        "table3_matrix": table3_matrix(d),
        "holds_list": lists["holds"],
        "reversed_list": lists["reversed"],
        "mode_sentence": mode_sentence(d),
        "checks_table": checks_table(d),
        "scenario_table": scenario_table(d),
        "holm_first_step": _p(ALPHA / max(len(d.claims), 1)),
    }
    for group in GROUPS:
        out[f"claims_{group}"] = claims_table(d, group)
    return out
