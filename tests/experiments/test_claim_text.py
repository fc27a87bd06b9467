"""The claims in words: every sentence that states a result is computed from the counts it
states, so that it says the opposite (or nothing) when the data do; a quick look with too few
seeds says so; and the templates' own text states no result."""

from __future__ import annotations

import re

import pandas as pd
import pytest

from hcomc.experiments.claim_text import (
    FAMILY_NAMES,
    families_line,
    reading,
    seeds_sentence,
    verdict_summary,
    verdict_table,
)
from hcomc.experiments.claims import MIN_PAIRS
from hcomc.viz.publish import PLACEHOLDER, template


def _claims(verdicts: list[tuple[str, str]], family: str = "paper") -> pd.DataFrame:
    """A claims table of (metric, verdict) rows in one family, Holm verdicts the same."""
    return pd.DataFrame(
        [
            {
                "family": family,
                "group": "Table III (HCOMC vs FIFO/Game)",
                "claim": f"c{i}",
                "condition": "C1",
                "metric": metric,
                "verdict": verdict,
                "verdict_holm": verdict,
            }
            for i, (metric, verdict) in enumerate(verdicts)
        ]
    )


def test_the_reading_follows_the_share_of_undecided_claims() -> None:
    most = _claims([("fuel", "undecided")] * 8 + [("lsrv", "holds")] * 2)
    few = _claims([("fuel", "undecided")] * 2 + [("lsrv", "holds")] * 8)
    assert reading(most).startswith("Most of the paper's claims are undecided")
    assert "(8 of 10)" in reading(most)
    assert reading(few).startswith("A minority of the paper's claims are undecided")
    assert "(2 of 10)" in reading(few)


def test_the_reading_names_a_metric_only_where_it_is_most_of_the_decided() -> None:
    about_lsrv = _claims([("lsrv", "holds")] * 3 + [("fuel", "reversed")] + [("fuel", "undecided")])
    assert "Of the 4 decided, 3 are about the lsrv." in reading(about_lsrv)
    split = _claims([("lsrv", "holds")] * 2 + [("fuel", "reversed")] * 2)
    assert "decided," not in reading(split)
    assert reading(_claims([("fuel", "undecided")], family="extension")) == ""


def test_a_quick_look_says_that_it_cannot_decide_a_claim() -> None:
    few = seeds_sentence(MIN_PAIRS - 1)
    assert f"With {MIN_PAIRS - 1} seeds no claim can be decided" in few
    assert f"at least {MIN_PAIRS}" in few
    assert seeds_sentence(MIN_PAIRS) == ""
    assert seeds_sentence(30) == ""


def test_a_count_of_one_takes_the_singular() -> None:
    one = _claims([("fuel", "holds"), ("lsrv", "reversed"), ("fuel", "undecided")])
    assert verdict_summary(one, "verdict") == "1 holds, 1 is reversed and 1 undecided"
    two = _claims([("fuel", "holds")] * 2 + [("lsrv", "reversed")] * 2)
    assert verdict_summary(two, "verdict") == "2 hold, 2 are reversed and 0 undecided"


def test_every_family_is_counted_apart() -> None:
    frame = pd.concat(
        [_claims([("fuel", "holds")] * 3), _claims([("fuel", "reversed")] * 2, "replanning")],
        ignore_index=True,
    )
    line = families_line(frame)
    assert f"{FAMILY_NAMES['paper']}: 3 claims, 3 hold, 0 are reversed" in line
    assert f"{FAMILY_NAMES['replanning']}: 2 claims, 0 hold, 2 are reversed" in line
    assert FAMILY_NAMES["extension"] not in line
    table = verdict_table(frame)
    assert f"all: {FAMILY_NAMES['paper']}" in table
    assert f"all: {FAMILY_NAMES['replanning']}" in table


EMPIRICAL = re.compile(
    r"\b((?<!more )(?<!as )often|rarely|seldom|usually|typically|mostly|"
    r"almost (?:never|always)|most claims|in most|a few by chance)\b",
    re.IGNORECASE,
)
"""Words that state how the results came out (a frequency, a majority); "more often" and "as
often" define a test or a claim."""


@pytest.mark.parametrize("name", ["reproduction.md", "readme.md"])
def test_no_template_sentence_states_a_result_of_its_own(name: str) -> None:
    """A sentence of a template that says how often or mostly something happened holds a
    placeholder, i.e. its statement is computed (and gated) by the narrative; the templates'
    own sentences describe the method only."""
    text = re.sub(r"<!--.*?-->", "", template(name), flags=re.S)
    text = re.sub(r"\s*\n\s*", " ", text)
    sentences = re.split(r"(?<=[.;])\s+(?=[A-Z*(])", text)
    ungated = [s for s in sentences if EMPIRICAL.search(s) and not PLACEHOLDER.search(s)]
    assert ungated == []
