"""Paired claims: the paper's list, median paired differences and bootstrap intervals."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hcomc.experiments.tables import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    Claim,
    ModeClaim,
    claims,
    median_ci,
    paper_claims,
)


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
