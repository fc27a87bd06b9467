"""The generated parts of the published documentation: every table and every sentence with a
number, made from a :class:`~hcomc.experiments.digest.Digest` alone.

:func:`values` returns them as the named values the templates of
:mod:`hcomc.viz.publish` put in place of their ``{{ name }}`` placeholders. Text
without numbers is the templates'; nothing with a number is written by hand.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from hcomc.experiments.checks import checks_table
from hcomc.experiments.claim_text import (
    claims_table,
    families_line,
    family_share,
    mode_sentence,
    paper_share,
    reading,
    seeds_sentence,
    table3_matrix,
    verdict_lists,
    verdict_summary,
    verdict_table,
)
from hcomc.experiments.claims import ALPHA, GROUPS, MIN_PAIRS
from hcomc.experiments.digest import Digest
from hcomc.experiments.paper import PAPER_METRICS, TABLE_III
from hcomc.experiments.prose import (
    cell,
    g,
    join,
    md,
    num,
    p_text,
    pct,
    sci,
    total,
    total_collisions,
    weighted,
)
from hcomc.experiments.tables import (
    BOOTSTRAP_RESAMPLES,
    LABELS,
    TABLE_CAPTION,
    TIE_TOLERANCE,
    format_table,
)


def run_facts(d: Digest) -> dict[str, str]:
    """Scope and provenance of the run, and the quoted config values."""
    prov, settings = d.provenance, d.provenance.settings
    collisions = total_collisions(d)
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
        "collisions": num(collisions),
        "a_merg": num(settings["a_merg"]),
        "virtual_max_decel": num(settings["virtual_max_decel"]),
        "safety_threshold": num(settings["safety_threshold"]),
        "cav_time_headway": num(settings["cav_time_headway"]),
        "duration": num(settings["duration"]),
        "road_length": num(settings["road_length"] / 1000.0),
        "resamples": str(BOOTSTRAP_RESAMPLES),
        "confidence": num(100 * (1 - ALPHA)),
        "alpha": num(ALPHA),
        "min_pairs": str(MIN_PAIRS),
        "tie_tolerance": sci(TIE_TOLERANCE, 0),
        "paper_lsrv_range": f"{min(lsrv):.0f}–{max(lsrv):.0f}",
        "paper_fuel": f"{np.mean(fuel):.0f}",
    }


def hcomc_facts(d: Digest) -> str:
    """One sentence: what HCOMC decided over the run."""
    behind, runs = total(d, "behind", "HCOMC")
    lateral, all_runs = total(d, "lateral", "HCOMC")
    lat_c2, runs_c2 = cell(d, "C2", "HCOMC", "lateral")
    own = d.decisions[d.decisions["configuration"] == "HCOMC"]
    mean_plans = weighted(own["plans_per_merge"], own["runs"] - own["no_plan"])
    merged, _ = total(d, "merged", "HCOMC")
    merge = f"VR merged in {num(merged)} of {runs} runs, " if np.isfinite(merged) else ""
    return (
        f"{merge}behind VMC in {num(behind)} ({pct(behind, runs)}); lateral cooperation in "
        f"{num(lat_c2)} of {runs_c2} C2 runs ({pct(lat_c2, runs_c2)}) and {num(lateral)} of "
        f"{all_runs} runs overall; {g(mean_plans)} "
        f"{'plan' if g(mean_plans) == '1' else 'plans'} per merge on average"
    )


def decisions_table(d: Digest) -> str:
    """Per configuration over all conditions: sequence, modes, plans, Eq. 19's branches,
    decision time and fallbacks (and merges, plan switches, the cause of lateral plans when
    the runs have them)."""
    tau = run_facts(d)["safety_threshold"]
    rows = []
    for conf, part in d.decisions.groupby("configuration", sort=False):
        runs = int(part["runs"].sum())

        def count(col: str, part: pd.DataFrame = part) -> float:
            return float(part[col].sum(min_count=1))

        planned = part["runs"] - part["no_plan"]
        rec: dict[str, str] = {"configuration": str(conf), "runs": str(runs)}
        if np.isfinite(count("merged")):
            rec["merged"] = num(count("merged"))
        rec["VR behind VMC"] = f"{num(count('behind'))} ({pct(count('behind'), runs)})"
        rec["lateral / longitudinal / none"] = " / ".join(
            num(count(m)) for m in ("lateral", "longitudinal", "none")
        )
        rec["plans per merge (mean)"] = g(weighted(part["plans_per_merge"], planned))
        if part["plan_switches"].notna().any():
            rec["plan switches (mean)"] = g(weighted(part["plan_switches"], planned))
        gate, low = count("gate"), count("min_safety")
        branch = "—" if gate + low == 0 else f"{num(gate)} / {num(low)}"
        rec[f'Eq. 19: "U_safe ≤ {tau}" / "all > {tau}"'] = branch
        if d.decisions["lateral_equilibrium"].notna().any():
            rec["lateral by equilibrium / safety rule"] = (
                f"{num(count('lateral_equilibrium'))} / {num(count('lateral_safety_rule'))}"
                if count("lateral") > 0
                else "—"
            )
        if np.isfinite(count("games_safety_rule")) and count("games") > 0:
            rec["lane-change games: equilibrium change / safety rule only"] = (
                f"{num(count('games_change'))} / {num(count('games_safety_rule'))} "
                f"of {num(count('games'))}"
            )
        rec["decision time median [ms]"] = g(float(part["decision_ms"].median()))
        rec["fallbacks"] = num(count("fallback"))
        rows.append(rec)
    return md(pd.DataFrame(rows))


def decisions_by_condition(d: Digest) -> str:
    """HCOMC's decisions condition by condition, one sentence each."""
    conditions = list(d.provenance.conditions)

    def series(col: str) -> str:
        return join([num(cell(d, c, "HCOMC", col)[0]) for c in conditions])

    runs = join([str(cell(d, c, "HCOMC", "runs")[1]) for c in conditions])
    where = f"{conditions[0]}–{conditions[-1]}" if len(conditions) > 1 else conditions[0]
    hdv, n5 = cell(d, conditions[-1], "HCOMC", "vmc_hdv")
    none, _ = cell(d, conditions[-1], "HCOMC", "none")
    cav = d.provenance.settings["cav_penetration"].get(conditions[-1], float("nan"))
    return (
        f"HCOMC by condition ({where}, of {runs} runs): VR behind VMC in {series('behind')}; "
        f"lateral cooperation in {series('lateral')}; longitudinal in {series('longitudinal')}; "
        f'Eq. 19\'s "all U_safe > {run_facts(d)["safety_threshold"]}" branch in '
        f"{series('min_safety')}. In {conditions[-1]} ({num(100 * cav)} % CAVs) VMC is an HDV "
        f'in {num(hdv)} of {n5} runs and HCOMC plans only VR\'s own merge (mode "none") in '
        f"{num(none)}."
    )


# --------------------------------------------------------------------------- tables II and III
def paper_tables(d: Digest) -> dict[str, str]:
    """Tables II and III in Markdown, their caption, and the range of our critical
    distances."""
    out = {"table_caption": TABLE_CAPTION}
    for which, key in (("II", "table2"), ("III", "table3")):
        part = d.tables[d.tables["table"] == which].reset_index(drop=True)
        out[key] = md(format_table(part)) if len(part) else "(no runs)"
    cd = d.tables["critical_distance"].dropna()
    out["cd_range"] = f"{cd.min():.0f}–{cd.max():.0f}" if len(cd) else "—"
    return out


def decision_facts(d: Digest) -> dict[str, str]:
    """Counts quoted in the prose: "k of n (p %)" per configuration (over all conditions)
    of the last plan switching (``final_switch_*``), of at least one switch
    (``switched_*``), of merges (``merged_*``), of fallbacks (``fallbacks_*``) and of lateral
    last plans (``lateral_*``), and
    Game's and FIFO's longitudinal cooperation in C2 (``longitudinal_c2_*``); a
    configuration the run lacks gives "—"; ``cd_by_mode_*``: the mean critical distance by the
    last plan's mode; ``unmerged_fallback_*``: "k of its m" runs without a merge whose last
    plan fell back."""
    out = {}
    for conf in ("FIFO", "Game", "HCOMC", "HCOMC+", "HCOMC-eq", "FIFO-R", "Game-R", "HCOMC-R"):
        key = conf.lower().replace("+", "_plus").replace("-", "_")
        for column, name in (
            ("final_switch", "final_switch"),
            ("switched", "switched"),
            ("merged", "merged"),
            ("fallback", "fallbacks"),
            ("lateral", "lateral"),
        ):
            k, n = total(d, column, conf) if column in d.decisions else (float("nan"), 0)
            out[f"{name}_{key}"] = f"{num(k)} of {n} ({pct(k, n)})" if n else "—"
        out[f"cd_by_mode_{key}"] = _cd_by_mode(d, conf)
        merged, runs = total(d, "merged", conf) if "merged" in d.decisions else (np.nan, 0)
        fell, _ = total(d, "unmerged_fallback", conf) if runs else (np.nan, 0)
        out[f"unmerged_fallback_{key}"] = (
            f"{num(fell)} of its {num(runs - merged)}"
            if "unmerged_fallback" in d.decisions
            else "—"
        )
        k, n = cell(d, "C2", conf, "longitudinal")
        out[f"longitudinal_c2_{key}"] = f"{num(k)} of {n} ({pct(k, n)})" if n else "—"
    return out


def _cd_by_mode(d: Digest, configuration: str) -> str:
    """Mean critical distance by the last plan's mode over all conditions: "longitudinal
    53.1 m (n = 73), ..." (modes without runs left out; "—" without any)."""
    part = d.decisions[d.decisions["configuration"] == configuration]
    items = []
    for mode in ("longitudinal", "lateral", "none"):
        if f"cd_{mode}" not in part:
            continue
        n = part[f"cd_n_{mode}"]
        if n.sum() > 0:
            items.append(f"{mode} {g(weighted(part[f'cd_{mode}'], n))} m (n = {num(n.sum())})")
    return ", ".join(items) if items else "—"


# --------------------------------------------------------------------------- paper scenario
def scenario_table(d: Digest) -> str:
    """The deterministic paper scenario's runs of FIFO, Game, HCOMC and any configuration
    the paper does not name (not the replanning baselines or the other optimisers)."""
    variants = ("FIFO-R", "Game-R", "HCOMC-R", "HCOMC-PSO", "HCOMC-SA")  # Table III's only
    part = d.scenario[~d.scenario["configuration"].isin(variants)].copy()
    for m in PAPER_METRICS:
        if m in part:
            part[m] = [g(v) for v in part[m]]
    part = part.drop(columns=[c for c in ("collisions", "merged") if c in part])
    return md(part.rename(columns=LABELS))


def values(d: Digest) -> dict[str, str]:
    """Every placeholder value of the templates, from the digest alone."""
    claims = d.claims
    lists = verdict_lists(claims)
    paper = paper_share(claims)
    out = {
        **run_facts(d),
        **paper_tables(d),
        "hcomc_facts": hcomc_facts(d),
        "decisions_table": decisions_table(d),
        "decisions_by_condition": decisions_by_condition(d),
        **decision_facts(d),
        "n_claims": str(len(paper)),
        "verdicts_ci": verdict_summary(paper, "verdict"),
        "verdicts_holm": verdict_summary(paper, "verdict_holm"),
        "families_line": families_line(claims),
        "verdict_table": verdict_table(claims),
        "table3_matrix": table3_matrix(claims),
        "table3_matrix_replanning": table3_matrix(claims, "replanning"),
        "table3_matrix_extension": table3_matrix(claims, "extension"),
        "holds_list": lists["holds"],
        "reversed_list": lists["reversed"],
        "mode_sentence": mode_sentence(claims),
        "reading": reading(claims),
        "seeds_sentence": seeds_sentence(d.provenance.seeds),
        "checks_table": checks_table(d),
        "scenario_table": scenario_table(d),
        "holm_first_step": p_text(ALPHA / max(len(paper), 1)),
    }
    for family in ("outcome", "replanning", "extension"):
        part = family_share(claims, family)
        out[f"n_claims_{family}"] = str(len(part))
        out[f"verdicts_{family}"] = verdict_summary(part, "verdict")
        out[f"verdicts_{family}_holm"] = verdict_summary(part, "verdict_holm")
    for group in GROUPS:
        out[f"claims_{group}"] = claims_table(claims, group)
    return out
