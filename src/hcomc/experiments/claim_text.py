"""The claims of a run in words and tables, family by family, every sentence gated by the data
it states (:mod:`hcomc.experiments.claims` makes the claims; this module only reports them).

The families (:data:`hcomc.experiments.claims.FAMILIES`) are reported apart and never summed:
the paper's own claims, the merge outcomes, the replanning variants (HCOMC-R against FIFO-R
and Game-R) and the extension HCOMC+. A sentence that says something of the results ("most
claims are undecided", "the decided claims are mostly about ...") is written only when the
counts it is computed from say so; otherwise the sentence is left out or says the opposite.
"""

from __future__ import annotations

import pandas as pd

from hcomc.experiments.claims import GROUPS, MIN_PAIRS, VERDICTS, verdict_counts
from hcomc.experiments.prose import METRIC_NAMES, g, md, p_text

FAMILY_NAMES = {
    "paper": "the paper's claims",
    "outcome": "merge outcomes (HCOMC vs FIFO/Game)",
    "replanning": "replanning variants (HCOMC-R vs FIFO-R/Game-R; extension)",
    "extension": "HCOMC+ (extension) vs FIFO/Game",
}
"""Family key -> its name in the docs, in display order."""


def family_share(claims: pd.DataFrame, family: str) -> pd.DataFrame:
    """The rows of a claims table in one Holm family."""
    return claims[claims["family"] == family]


def paper_share(claims: pd.DataFrame) -> pd.DataFrame:
    """The paper's own claims (Section IV, Tables II-III)."""
    return family_share(claims, "paper")


def extension_share(claims: pd.DataFrame) -> pd.DataFrame:
    """The claims of the labelled extension HCOMC+."""
    return family_share(claims, "extension")


def verdict_summary(claims: pd.DataFrame, column: str) -> str:
    """The counts of one verdict column of ``claims`` as prose: "a hold, b are reversed and
    c undecided" (for a count of one "holds" and "is reversed")."""
    if claims.empty:
        return "none evaluated"
    counts = verdict_counts(claims, column).loc["all"]
    holds, reversed_ = int(counts["holds"]), int(counts["reversed"])
    return (
        f"{holds} {'holds' if holds == 1 else 'hold'}, "
        f"{reversed_} {'is' if reversed_ == 1 else 'are'} reversed and "
        f"{counts['undecided']} undecided"
    )


def families_line(claims: pd.DataFrame) -> str:
    """Every family's count and verdicts (CI rule; Holm within the family), one clause each."""
    items = []
    for family, name in FAMILY_NAMES.items():
        part = family_share(claims, family)
        if len(part):
            items.append(
                f"{name}: {len(part)} claims, {verdict_summary(part, 'verdict')} (95 % CI); "
                f"{verdict_summary(part, 'verdict_holm')} (sign test, Holm)"
            )
    return " · ".join(items)


def verdict_table(claims: pd.DataFrame) -> str:
    """Claims per group and verdict, by the CI rule and by the Holm-corrected test, each
    family with its own total row."""
    rows = []
    for family, name in FAMILY_NAMES.items():
        part = family_share(claims, family)
        if part.empty:
            continue
        ci, holm = verdict_counts(part, "verdict"), verdict_counts(part, "verdict_holm")
        groups = list(ci.index) if len(ci.index) > 2 else ["all"]
        for group in groups:
            label = f"all: {name}" if group == "all" else str(group)
            rec = {"group": label, "claims": str(int(ci.loc[group].sum()))}
            for v in VERDICTS:
                rec[f"{v} (CI)"] = str(int(ci.loc[group, v]))
            for v in VERDICTS:
                rec[f"{v} (Holm)"] = str(int(holm.loc[group, v]))
            rows.append(rec)
    return md(pd.DataFrame(rows))


def table3_matrix(claims: pd.DataFrame, group: str = "table3") -> str:
    """Table III's claims (of HCOMC, HCOMC-R for ``"replanning"``, HCOMC+ for
    ``"extension"``) by metric (rows) and condition (columns): the CI verdict against FIFO /
    against Game, with the Holm verdict where it differs."""
    part = claims[claims["group"] == GROUPS[group]]
    if part.empty:
        return "(no runs for these claims)"
    suffix = "-R" if group == "replanning" else ""
    conditions = list(dict.fromkeys(part["condition"]))
    rows = []
    for metric in dict.fromkeys(part["metric"]):
        rec = {"metric": METRIC_NAMES.get(metric, metric.replace("_", " "))}
        for cond in conditions:
            cells = []
            for base in ("FIFO", "Game"):
                hit = part[
                    (part["metric"] == metric)
                    & (part["condition"] == cond)
                    & part["claim"].str.endswith(f"than {base}{suffix}")
                ]
                if hit.empty:
                    cells.append("—")
                    continue
                ci, holm = hit["verdict"].iloc[0], hit["verdict_holm"].iloc[0]
                cells.append(ci if ci == holm else f"{ci} (Holm: {holm})")
            rec[cond] = " / ".join(cells)
        rows.append(rec)
    return md(pd.DataFrame(rows))


def claims_table(claims: pd.DataFrame, group: str) -> str:
    """The claims of one group (a key of :data:`GROUPS`) as a Markdown table; "failed" gives
    the seeds on which A's / B's VR did not merge (each the worst outcome in the sign test)."""
    part = claims[claims["group"] == GROUPS[group]]
    if part.empty:
        return "(no runs for these claims)"
    rows = []
    for _, r in part.iterrows():
        rec = {"claim": r["claim"], "condition": r["condition"]}
        if r["metric"] in ("mode", "merged"):
            rec["ours"] = r["ours"]
        else:
            effect = f"{g(r['median_diff'])} [{g(r['ci_low'])}, {g(r['ci_high'])}]"
            rec["median A − B [CI]"] = effect
        rec["verdict"] = r["verdict"]
        rec["p (Holm)"] = p_text(r["p_holm"])
        rec["verdict (Holm)"] = r["verdict_holm"]
        rec["k of n"] = f"{int(r['holds'])} of {int(r['n'])}"
        if r["metric"] != "mode" and "failed_a" in part:
            rec["failed A / B"] = f"{int(r['failed_a'])} / {int(r['failed_b'])}"
        if "uniform" in part:
            rec["uniform"] = r["uniform"] or "—"
        rows.append(rec)
    return md(pd.DataFrame(rows))


def verdict_lists(claims: pd.DataFrame, column: str = "verdict") -> dict[str, str]:
    """The paper's claims that hold and those reversed, claim by claim with their
    conditions: "HCOMC fuel lower than FIFO (C1, C3)"."""
    part = paper_share(claims)
    out = {}
    for verdict in ("holds", "reversed"):
        hits = part[part[column] == verdict]
        items = [
            f"{claim} ({', '.join(group['condition'])})"
            for claim, group in hits.groupby("claim", sort=False)
        ]
        out[verdict] = "; ".join(items) if items else "none"
    return out


def mode_sentence(claims: pd.DataFrame) -> str:
    """HCOMC's cooperation modes in the conditions of the mode claims."""
    part = claims[claims["group"] == GROUPS["mode"]]
    items = [f"{r['condition']}: {r['ours']} (of {int(r['n'])} runs)" for _, r in part.iterrows()]
    return "HCOMC's cooperation mode — " + "; ".join(items) + "." if items else ""


def seeds_sentence(seeds: int) -> str:
    """Whether the run has seeds enough to decide a claim at all: a claim needs at least
    :data:`~hcomc.experiments.claims.MIN_PAIRS` seeds on which the two runs differ."""
    if seeds < MIN_PAIRS:
        return (
            f"With {seeds} seeds no claim can be decided: a claim needs at least {MIN_PAIRS} "
            "seeds on which the two runs differ, and Holm's correction over a family of many "
            "claims about 25 of 30 in one direction; this is a quick look, not evidence "
            "(the published run uses 30)."
        )
    return ""


def reading(claims: pd.DataFrame) -> str:
    """What the paper's family says as a whole, in sentences each computed from its counts:
    the share undecided, and the metric most of the decided claims are about (only when it is
    more than half of them)."""
    part = paper_share(claims)
    if part.empty:
        return ""
    undecided = int((part["verdict"] == "undecided").sum())
    share = undecided / len(part)
    quantity = "Most" if share > 0.5 else "A minority" if share < 0.5 else "Half"
    text = (
        f"{quantity} of the paper's claims are undecided by their confidence interval "
        f"({undecided} of {len(part)})."
    )
    decided = part[part["verdict"] != "undecided"]
    if len(decided):
        counts = decided["metric"].value_counts()
        top, n_top = str(counts.index[0]), int(counts.iloc[0])
        if 2 * n_top > len(decided):
            name = METRIC_NAMES.get(top, top.replace("_", " "))
            text += f" Of the {len(decided)} decided, {n_top} are about the {name}."
    return text
