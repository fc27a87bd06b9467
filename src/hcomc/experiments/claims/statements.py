"""What the paper claims, as statements that runs can test (Section IV, Tables II-III).

A :class:`Claim` says that a metric of cell A (condition, configuration) is lower or higher
than of cell B, in the direction of the paper's tables; a :class:`ModeClaim` which cooperation
mode HCOMC chooses; a :class:`SuccessClaim` that A's VR merges at least as often as B's. The
claims fall into Holm families (:data:`FAMILIES`): the paper's own (:func:`paper_claims`, 85
when every condition is run), the merge outcomes the paper takes for granted
(:func:`outcome_claims`), and those of the labelled extensions, which the paper never makes:
the variants replanning every second (:func:`replanning_claims`) and HCOMC+
(:func:`extension_claims`). How they are tested: :mod:`hcomc.experiments.claims.evaluation`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from hcomc.experiments.paper import PAPER_METRICS, TABLE_II, TABLE_III
from hcomc.experiments.tables import REPLANNING

GROUPS = {
    "table3": "Table III (HCOMC vs FIFO/Game)",
    "table2": "Table II (NSGA-II vs PSO/SA)",
    "penetration": "CAV penetration (LSRV)",
    "mode": "cooperation mode",
    "outcome": "merge outcome (HCOMC vs FIFO/Game)",
    "replanning": "HCOMC-R vs FIFO-R/Game-R (replanning, extension)",
    "extension": "HCOMC+ (extension) vs FIFO/Game",
}
"""Claim group key -> its name (the ``group`` column), in display order."""

FAMILIES = {
    "table3": "paper",
    "table2": "paper",
    "penetration": "paper",
    "mode": "paper",
    "outcome": "outcome",
    "replanning": "replanning",
    "extension": "extension",
}
"""Claim group key -> its Holm family (the ``family`` column): the paper's own claims of
Section IV and Tables II-III; the merge outcomes the paper takes for granted (every VR
merges); the replanning variants (not in the paper); the extension HCOMC+ (not in the
paper)."""


@dataclass(frozen=True)
class Claim:
    """A comparative statement of the paper: metric of cell A lower/higher than of cell B.

    A cell is (condition, configuration); ``paper_a`` and ``paper_b`` are the paper's values;
    ``group`` a key of :data:`GROUPS`.
    """

    text: str
    metric: str
    a: tuple[str, str]
    b: tuple[str, str]
    expect: str  # "lower" or "higher"
    paper_a: float
    paper_b: float
    group: str = "table3"


@dataclass(frozen=True)
class SuccessClaim:
    """Configuration A's VR merges at least as often as B's, on the same seeds (the paper
    reports every merge as completed)."""

    condition: str
    a: str
    b: str
    group: str = "outcome"


@dataclass(frozen=True)
class ModeClaim:
    """HCOMC's chosen cooperation mode in a condition."""

    condition: str
    mode: str
    group: str = "mode"


AnyClaim = Claim | ModeClaim | SuccessClaim
"""A claim of any kind."""

_T2_MODEL = {"HCOMC": "NSGA-II", "HCOMC-PSO": "PSO", "HCOMC-SA": "SA"}


def _paper_value(cell: tuple[str, str], metric: str) -> float:
    cond, conf = cell
    i = PAPER_METRICS.index(metric)
    if (cond, conf) in TABLE_III:
        return TABLE_III[(cond, conf)][i]
    return TABLE_II[(cond, _T2_MODEL[conf])][i]


def _pairwise(
    metric: str,
    a: tuple[str, str],
    b: tuple[str, str],
    group: str,
    names: dict[str, str] | None = None,
) -> Claim | None:
    """The claim the paper's tables make about cells A and B on ``metric`` (None if tied);
    ``names`` maps configurations to the paper's model names in the text."""
    pa, pb = _paper_value(a, metric), _paper_value(b, metric)
    if pa == pb:
        return None
    expect = "lower" if pa < pb else "higher"
    name = metric.replace("_", " ")
    label_a, label_b = ((names or {}).get(c, c) for c in (a[1], b[1]))
    if a[0] == b[0]:
        text = f"{label_a} {name} {expect} than {label_b}"
    else:
        text = f"{label_a} {name} {expect} in {a[0]} than in {b[0]}"
    return Claim(text, metric, a, b, expect, pa, pb, group)


def paper_claims() -> list[AnyClaim]:
    """The comparative claims of Section IV, in the direction the paper's tables give.

    * Sections IV-A to IV-D with Table III: HCOMC versus FIFO and versus Game on critical
      distance, average acceleration, stabilisation time, LSRV and fuel in every condition
      (the text: HCOMC improves safety in all conditions, stability and rapidity "almost
      under all", traffic efficiency, and fuel except in C2, where it uses more). Where the
      table has HCOMC worse (average acceleration vs FIFO in C2, fuel in C2) the claim says
      so.
    * Section IV-A: HCOMC's VMC cooperates laterally in C2, longitudinally in C1 and C3.
    * Section IV-C: fewer CAVs, larger LSRV: C1 (90 %) < C4 (60 %) < C5 (30 %) for each
      controller (two paired claims per controller).
    * Table II: NSGA-II versus PSO and SA on all five metrics in C1 and C3 (longitudinal
      cooperation, where the text says NSGA-II is best) and, in C2 (lateral cooperation), on
      the three metrics the text discusses: LSRV ("NSGA-II also performs the best"), critical
      distance and fuel (NSGA-II "performs inferior ... only about 1 %").
    """
    out: list[Claim | ModeClaim | None] = list(_table3())
    out += [ModeClaim("C1", "longitudinal"), ModeClaim("C2", "lateral"),
            ModeClaim("C3", "longitudinal")]  # fmt: skip
    for conf in ("FIFO", "Game", "HCOMC"):
        for more, fewer in (("C1", "C4"), ("C4", "C5")):
            out.append(_pairwise("lsrv", (fewer, conf), (more, conf), "penetration"))
    c2 = ("critical_distance", "lsrv", "fuel")  # the three the text discusses for C2
    for cond, metrics in (("C1", PAPER_METRICS), ("C3", PAPER_METRICS), ("C2", c2)):
        for metric in metrics:
            for rival in ("HCOMC-PSO", "HCOMC-SA"):
                out.append(_pairwise(metric, (cond, "HCOMC"), (cond, rival), "table2", _T2_MODEL))
    return [c for c in out if c is not None]


def _table3() -> list[Claim]:
    """Table III's claims: HCOMC versus FIFO and Game, every metric and condition."""
    out = [
        _pairwise(metric, (cond, "HCOMC"), (cond, base), "table3")
        for cond in ("C1", "C2", "C3", "C4", "C5")
        for metric in PAPER_METRICS
        for base in ("FIFO", "Game")
    ]
    return [c for c in out if c is not None]


def outcome_claims() -> list[SuccessClaim | Claim]:
    """What the paper takes for granted of every configuration (each VR merges) and how soon:
    in every condition, HCOMC's VR merges at least as often as FIFO's and Game's, and merges
    sooner after its control-zone entry (``merge_time``; Section IV-C's "traffic efficiency",
    not a column of the paper's tables, so the paper's values are NaN)."""
    out: list[SuccessClaim | Claim] = []
    nan = float("nan")
    for cond in ("C1", "C2", "C3", "C4", "C5"):
        for base in ("FIFO", "Game"):
            out.append(SuccessClaim(cond, "HCOMC", base))
            text = f"HCOMC merge time lower than {base}"
            out.append(Claim(text, "merge_time", (cond, "HCOMC"), (cond, base), "lower", nan,
                             nan, "outcome"))  # fmt: skip
    return out


def replanning_claims() -> list[Claim]:
    """Table III's claims made of the variants replanning every second (HCOMC-R against
    FIFO-R and Game-R; not in the paper), with the paper's values for reference."""
    out = []
    for c in _table3():
        text = f"{REPLANNING['HCOMC']}{c.text.removeprefix('HCOMC')}-R"
        a, b = (c.a[0], REPLANNING["HCOMC"]), (c.b[0], REPLANNING[c.b[1]])
        out.append(replace(c, text=text, a=a, b=b, group="replanning"))
    return out


def extension_claims() -> list[Claim]:
    """The Table III claims of HCOMC made of HCOMC+, the labelled extension that may also
    leave the mainline alone (mode "none" among its candidates; not in the paper): does it
    keep HCOMC's published advantages over FIFO and Game? The paper's values are HCOMC's, for
    reference; these claims form a Holm family of their own."""
    out = []
    for c in _table3():
        text = "HCOMC+" + c.text.removeprefix("HCOMC")
        out.append(replace(c, text=text, a=(c.a[0], "HCOMC+"), group="extension"))
    return out


def all_claims() -> list[AnyClaim]:
    """Every claim, family by family: the paper's, the merge outcomes, the replanning
    variants', the extension's."""
    return [*paper_claims(), *outcome_claims(), *replanning_claims(), *extension_claims()]
