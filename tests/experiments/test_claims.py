"""Paired claims: the paper's list, median paired differences, bootstrap intervals, sign
tests, Holm's adjustment and the verdicts."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hcomc.experiments.claims import (
    COLUMNS,
    FAMILIES,
    GROUPS,
    MIN_PAIRS,
    Claim,
    ModeClaim,
    all_claims,
    ci_verdict,
    claims,
    holm,
    mcnemar_exact,
    paper_claims,
    sign_test,
    verdict_counts,
)
from hcomc.experiments.tables import BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, median_ci


def _runs() -> pd.DataFrame:
    """C1 and C2, FIFO and HCOMC, four seeds with hand-chosen critical distances."""
    rows = []
    hcomc = [120.0, 90.0, 130.0, 111.0]
    fifo = [100.0, 110.0, 100.0, 101.0]
    for cond in ("C1", "C2"):
        for seed in range(4):
            for conf, cd in (("HCOMC", hcomc[seed]), ("FIFO", fifo[seed])):
                rows.append({"condition": cond, "configuration": conf, "seed": seed,
                             "critical_distance": cd, "average_acceleration": 0.02,
                             "stabilisation_time": 10.0, "lsrv": 5.0, "fuel": 8.0,
                             "mode": "lateral" if seed else "longitudinal"})  # fmt: skip
    return pd.DataFrame(rows)


def test_claim_list_follows_the_paper_tables() -> None:
    listed = paper_claims()
    texts = {(c.a[0], c.text) for c in listed if isinstance(c, Claim)}
    # Table III has HCOMC's average acceleration ABOVE FIFO's in C2 (0.0477 vs 0.0442)
    assert ("C2", "HCOMC average acceleration higher than FIFO") in texts
    assert ("C2", "HCOMC average acceleration lower than FIFO") not in texts
    assert ("C2", "HCOMC fuel higher than Game") in texts  # IV-D: more fuel in C2
    assert ("C1", "HCOMC fuel lower than Game") in texts
    assert ("C5", "HCOMC lsrv higher in C5 than in C4") in texts  # fewer CAVs, more LSRV
    assert ("C1", "NSGA-II critical distance higher than PSO") in texts
    assert ("C2", "NSGA-II lsrv lower than SA") in texts
    assert ("C2", "NSGA-II critical distance lower than PSO") in texts  # IV-A: ~1 % worse
    assert ("C2", "NSGA-II fuel higher than SA") in texts  # IV-D: ~1 % worse
    assert not any("stabilisation" in t for c, t in texts if c == "C2" and "NSGA" in t)
    modes = {(c.condition, c.mode) for c in listed if isinstance(c, ModeClaim)}
    assert modes == {("C1", "longitudinal"), ("C2", "lateral"), ("C3", "longitudinal")}
    # every pairwise claim agrees with the paper's own numbers
    for c in listed:
        if isinstance(c, Claim):
            assert (c.paper_a < c.paper_b) == (c.expect == "lower")


def test_median_ci_is_the_seeded_percentile_bootstrap() -> None:
    d = np.array([20.0, -20.0, 30.0, 10.0, np.nan])
    median, low, high = median_ci(d)
    assert median == 15.0
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    boot = np.median(rng.choice(d[:4], size=(BOOTSTRAP_RESAMPLES, 4)), axis=1)
    assert (low, high) == tuple(np.percentile(boot, [2.5, 97.5]))
    assert -20.0 <= low <= median <= high <= 30.0
    assert median_ci(d) == (median, low, high)  # deterministic
    assert all(np.isnan(median_ci(np.array([np.nan]))))
    assert median_ci(np.array([2.0, 2.0, 2.0])) == (2.0, 2.0, 2.0)


def test_claims_report_paired_effects() -> None:
    table = claims(_runs())
    c1 = table[table["condition"] == "C1"].set_index("claim")
    row = c1.loc["HCOMC critical distance higher than FIFO"]
    # paired differences 20, -20, 30, 10: holds in 3 of 4, median 15
    assert (row["holds"], row["n"], row["share"]) == (3, 4, 0.75)
    assert row["median_diff"] == 15.0
    assert row["ci_low"] <= 15.0 <= row["ci_high"]
    assert row["paper"] == "114.21 vs 104.67"
    assert row["paper_diff"] == pytest.approx(9.54)
    assert row["ours"] == "112.8 vs 102.8"
    tie = c1.loc["HCOMC fuel lower than FIFO"]
    assert (tie["holds"], tie["n"], tie["median_diff"]) == (0, 4, 0.0)
    runs = _runs()
    hcomc = runs["configuration"] == "HCOMC"
    runs.loc[hcomc, "stabilisation_time"] = 10.0 - 2e-15  # round-off, not an improvement
    noise = claims(runs).set_index(["condition", "claim"])
    row = noise.loc[("C1", "HCOMC stabilisation time lower than FIFO")]
    assert (row["holds"], row["median_diff"]) == (0, 0.0)
    mode = table[(table["claim"] == "HCOMC chooses lateral cooperation")].iloc[0]
    assert (mode["condition"], mode["holds"], mode["n"]) == ("C2", 3, 4)
    assert "uniform" not in table
    # only claims whose cells exist are listed (no Game, no C3..C5, no PSO/SA)
    assert not table["claim"].str.contains("Game|PSO").any()
    assert set(table["condition"]) == {"C1", "C2"}


def test_claims_on_the_uniform_scenario() -> None:
    runs = _runs()
    uniform = runs[runs["seed"] == 1]  # HCOMC 90 < FIFO 110: the claim fails there
    table = claims(runs, uniform).set_index(["condition", "claim"])
    assert table.loc[("C1", "HCOMC critical distance higher than FIFO"), "uniform"] == "no"
    assert table.loc[("C2", "HCOMC chooses lateral cooperation"), "uniform"] == "yes"


def test_sign_test_is_the_exact_binomial_test() -> None:
    # 3 of 4 non-zero differences in one direction: P(X >= 3) + P(X <= 1) = 10/16
    assert sign_test(3, 1) == pytest.approx(10 / 16)
    assert sign_test(1, 3) == sign_test(3, 1)
    assert sign_test(5, 0) == pytest.approx(2 / 32)
    assert sign_test(0, 0) == 1.0  # nothing but ties: no evidence either way
    # 25 of 30: two-sided tail 2 * sum_{k>=25} C(30, k) / 2^30
    tail = sum(math.comb(30, k) for k in range(25, 31)) / 2**30
    assert sign_test(25, 5) == pytest.approx(2 * tail)


@given(st.lists(st.floats(0.0, 1.0), min_size=1, max_size=40))
def test_holm_matches_its_definition(p: list[float]) -> None:
    values = np.array(p)
    adjusted = holm(values)
    m = len(p)
    order = np.argsort(values, kind="stable")
    expected = np.empty(m)
    running = 0.0
    for i, j in enumerate(order):  # step down: (m - i) p_(i), monotone, capped at 1
        running = max(running, min(1.0, (m - i) * values[j]))
        expected[j] = running
    np.testing.assert_allclose(adjusted, expected, rtol=0, atol=1e-15)
    assert (adjusted >= values - 1e-15).all()
    # rejections at alpha are a step-down: all p below the first failure, in order
    rejected = adjusted < 0.05
    if rejected.any() and not rejected.all():
        assert values[rejected].max() <= values[~rejected].min()


def test_holm_leaves_nan_out_of_the_family() -> None:
    adjusted = holm(np.array([0.01, np.nan, 0.02]))
    assert np.isnan(adjusted[1])
    np.testing.assert_allclose(adjusted[[0, 2]], [0.02, 0.02])  # m = 2, not 3


@pytest.mark.parametrize(
    ("low", "high", "expect", "verdict"),
    [
        (1.0, 3.0, "higher", "holds"),
        (1.0, 3.0, "lower", "reversed"),
        (-3.0, -1.0, "lower", "holds"),
        (-3.0, -1.0, "higher", "reversed"),
        (0.0, 3.0, "higher", "undecided"),  # a CI touching 0 does not exclude it
        (-1.0, 3.0, "lower", "undecided"),
        (float("nan"), float("nan"), "lower", "undecided"),
    ],
)
def test_ci_verdict(low: float, high: float, expect: str, verdict: str) -> None:
    assert ci_verdict(low, high, expect) == verdict


def _strong_runs(n: int = 30) -> pd.DataFrame:
    """C1, FIFO and HCOMC over n seeds: HCOMC's critical distance larger in every seed,
    its average acceleration larger (the paper: smaller) in every seed, its fuel equal; HCOMC
    chooses longitudinal cooperation in every run but two."""
    rows = []
    for seed in range(n):
        for conf, cd, acc in (("HCOMC", 120.0 + seed, 0.05), ("FIFO", 100.0, 0.02 + 1e-4 * seed)):
            mode = "longitudinal" if seed >= 2 else "lateral"
            rows.append({"condition": "C1", "configuration": conf, "seed": seed,
                         "critical_distance": cd, "average_acceleration": acc,
                         "stabilisation_time": 10.0, "lsrv": 5.0, "fuel": 8.0,
                         "mode": mode})  # fmt: skip
    return pd.DataFrame(rows)


def test_verdicts_follow_the_ci_and_the_holm_corrected_sign_test() -> None:
    table = claims(_strong_runs())
    assert list(table.columns) == list(COLUMNS)
    rows = table.set_index("claim")
    cd = rows.loc["HCOMC critical distance higher than FIFO"]
    assert (cd["holds"], cd["against"], cd["n"]) == (30, 0, 30)
    assert cd["verdict"] == "holds"
    assert cd["p_value"] == pytest.approx(2 * 0.5**30)
    assert cd["group"] == GROUPS["table3"]
    acc = rows.loc["HCOMC average acceleration lower than FIFO"]
    assert (acc["holds"], acc["against"]) == (0, 30)
    assert (acc["verdict"], acc["verdict_holm"]) == ("reversed", "reversed")
    fuel = rows.loc["HCOMC fuel lower than FIFO"]  # all ties
    assert (fuel["p_value"], fuel["verdict"], fuel["verdict_holm"]) == (1.0, "undecided",
                                                                        "undecided")  # fmt: skip
    # Holm over the whole family: m finite p-values, smallest times m
    m = int(table["p_value"].notna().sum())
    assert m == len(table)
    np.testing.assert_allclose(table["p_holm"], holm(table["p_value"]))
    assert cd["p_holm"] == pytest.approx(min(1.0, m * cd["p_value"]))
    assert cd["verdict_holm"] == "holds"
    # the mode claim: 28 of 30 runs longitudinal, exact binomial test against 1/2
    mode = rows.loc["HCOMC chooses longitudinal cooperation"]
    assert (mode["holds"], mode["n"]) == (28, 30)
    binom = 2 * sum(math.comb(30, k) for k in range(28, 31)) / 2**30
    assert mode["p_value"] == pytest.approx(binom)
    assert (mode["verdict"], mode["verdict_holm"]) == ("holds", "holds")
    assert mode["ours"] == "longitudinal: 28, lateral: 2"


def test_a_weak_effect_holds_by_its_ci_but_not_after_holm() -> None:
    """22 of 30 seeds in the paper's direction: the CI of the median clears 0 and the sign
    test alone is significant, but not after Holm's correction over the claims of the runs:
    the two verdict columns answer different questions."""
    runs = _strong_runs()
    hcomc = runs["configuration"] == "HCOMC"
    runs.loc[hcomc, "critical_distance"] = [101.0 + s if s < 22 else 99.5 for s in range(30)]
    table = claims(runs)
    row = table.set_index("claim").loc["HCOMC critical distance higher than FIFO"]
    assert (row["holds"], row["against"]) == (22, 8)
    assert row["ci_low"] > 0
    assert row["verdict"] == "holds"
    assert row["p_value"] == pytest.approx(sign_test(22, 8))
    assert row["p_value"] < 0.05 < row["p_holm"]
    assert row["verdict_holm"] == "undecided"


def test_a_mode_chosen_in_few_runs_is_reversed() -> None:
    runs = _strong_runs()
    runs["mode"] = "lateral"  # never longitudinal: significantly below one half
    row = claims(runs).set_index("claim").loc["HCOMC chooses longitudinal cooperation"]
    assert (row["holds"], row["verdict"], row["verdict_holm"]) == (0, "reversed", "reversed")


def test_verdict_counts() -> None:
    table = claims(_strong_runs())
    counts = verdict_counts(table)
    assert list(counts.columns) == ["holds", "reversed", "undecided"]
    assert counts.loc["all"].sum() == len(table)
    assert counts.loc[GROUPS["mode"], "holds"] == 1
    holm_counts = verdict_counts(table, "verdict_holm")
    assert holm_counts.loc["all"].sum() == len(table)


def test_too_few_differing_seeds_are_undecided() -> None:
    """Five unanimous seeds give a bootstrap CI clear of 0, but no paired test could call
    them significant at 5 % (2 / 2^5 > 0.05): the CI verdict stays undecided."""
    assert MIN_PAIRS == 6
    assert sign_test(MIN_PAIRS, 0) < 0.05 < sign_test(MIN_PAIRS - 1, 0)
    for seeds, verdict in ((MIN_PAIRS - 1, "undecided"), (MIN_PAIRS, "holds")):
        row = claims(_strong_runs(seeds)).set_index("claim")
        cd = row.loc["HCOMC critical distance higher than FIFO"]
        assert cd["ci_low"] > 0
        assert (cd["holds"], cd["verdict"]) == (seeds, verdict)


def test_the_extension_is_a_holm_family_of_its_own() -> None:
    """HCOMC+'s runs add its Table III claims in their own group; the paper's claims keep
    every p_holm and verdict they had without them, and the extension's p_holm is Holm over
    its own claims only."""
    runs = _strong_runs()
    plus = runs[runs["configuration"] == "HCOMC"].assign(configuration="HCOMC+")
    plus["critical_distance"] = [99.0 + (s % 2) * 3.0 for s in range(30)]  # 15 of 30 above
    alone, both = claims(runs), claims(pd.concat([runs, plus], ignore_index=True))
    ext = both[both["group"] == GROUPS["extension"]]
    paper = both[both["family"] != "extension"].reset_index(drop=True)
    pd.testing.assert_frame_equal(paper, alone)
    assert len(ext) == len(alone[alone["group"] == GROUPS["table3"]])
    row = ext.set_index("claim").loc["HCOMC+ critical distance higher than FIFO"]
    assert (row["holds"], row["against"], row["verdict"]) == (15, 15, "undecided")
    assert (row["condition"], row["paper"]) == ("C1", "114.21 vs 104.67")
    np.testing.assert_allclose(ext["p_holm"], holm(ext["p_value"]))


def test_the_paper_family_has_its_85_claims_and_none_against_a_replanning_variant() -> None:
    """Section IV and Tables II-III make 85 comparative claims (50 of Table III, 26 of Table
    II, 6 on CAV penetration, 3 on the cooperation mode); the replanning variants', the
    extension's and the merge outcomes' are families of their own."""
    listed = all_claims()
    family = [FAMILIES[c.group] for c in listed]
    assert family.count("paper") == 85
    assert family.count("replanning") == 50
    assert family.count("extension") == 50
    assert family.count("outcome") == 20
    for c in paper_claims():
        cells = (c.a, c.b) if isinstance(c, Claim) else ()
        assert not any(conf.endswith("-R") for _, conf in cells)
    replanning = [c for c in listed if c.group == "replanning"]
    assert all(isinstance(c, Claim) and c.a[1] == "HCOMC-R" for c in replanning)
    assert {c.b[1] for c in replanning if isinstance(c, Claim)} == {"FIFO-R", "Game-R"}


def _with_failures() -> pd.DataFrame:
    """C1, FIFO and HCOMC over 12 seeds: where both merge HCOMC's critical distance is larger
    (seeds 0-5); on seeds 6-11 HCOMC's VR does not merge (its merge metrics NaN)."""
    rows = []
    for seed in range(12):
        failed = seed >= 6
        for conf, cd, merged in (("HCOMC", np.nan if failed else 120.0 + seed, not failed),
                                 ("FIFO", 100.0, True)):  # fmt: skip
            rows.append({"condition": "C1", "configuration": conf, "seed": seed,
                         "critical_distance": cd, "merged": merged, "merge_time": 20.0,
                         "mode": "longitudinal"})  # fmt: skip
    return pd.DataFrame(rows)


def test_a_run_without_a_merge_is_the_worst_outcome_in_the_sign_test() -> None:
    """Six seeds where HCOMC's critical distance is larger and six where its VR never merged:
    the median and CI describe the six merged pairs, but the sign test counts the failures
    against HCOMC (6 for, 6 against: p = 1), instead of dropping them (6 of 6: p = 0.03)."""
    rows = claims(_with_failures()).set_index("claim")
    cd = rows.loc["HCOMC critical distance higher than FIFO"]
    assert (cd["holds"], cd["against"], cd["n"]) == (6, 6, 12)
    assert (cd["failed_a"], cd["failed_b"]) == (6, 0)
    assert cd["median_diff"] == pytest.approx(22.5)  # the merged pairs: 20 … 25
    assert cd["p_value"] == pytest.approx(1.0)
    assert cd["verdict_holm"] == "undecided"
    assert cd["family"] == "paper"


def test_merge_success_is_a_claim_with_the_exact_mcnemar_test() -> None:
    rows = claims(_with_failures()).set_index("claim")
    success = rows.loc["HCOMC merges at least as often as FIFO"]
    assert success["family"] == "outcome"
    assert (success["holds"], success["against"], success["n"]) == (0, 6, 12)
    assert (success["failed_a"], success["failed_b"]) == (6, 0)
    assert success["p_value"] == pytest.approx(2 * 0.5**6)  # all six discordant seeds: FIFO
    assert success["p_value"] == mcnemar_exact(0, 6)
    assert success["verdict"] == "reversed"
    assert success["ours"] == "6/12 vs 12/12 merged"


def test_each_family_is_adjusted_alone() -> None:
    frame = claims(_with_failures())
    for _, part in frame.groupby("family"):
        np.testing.assert_allclose(part["p_holm"], holm(part["p_value"]))
