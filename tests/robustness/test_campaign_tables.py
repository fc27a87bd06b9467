"""The campaign's tables: the exact collision bound, and the paired effects of a fault against
the nominal runs of the same seeds, on constructed runs whose answer is known."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from hcomc.robustness.tables import OVERVIEW, collision_bound, page, summarise, verdicts


@pytest.mark.parametrize("runs", [1, 10, 50, 1000])
def test_no_collision_in_n_runs_bounds_the_share_near_three_over_n(runs: int) -> None:
    assert collision_bound(0, runs) == pytest.approx(1 - 0.05 ** (1 / runs), rel=1e-9)
    if runs >= 50:
        assert 2.9 / runs < collision_bound(0, runs) < 3.0 / runs


@pytest.mark.parametrize(("hit", "runs"), [(1, 10), (5, 100), (99, 100), (3, 1000)])
def test_the_bound_is_the_clopper_pearson_beta_quantile(hit: int, runs: int) -> None:
    """Independent oracle: the one-sided exact bound is the 95 % quantile of
    Beta(k + 1, n - k)."""
    assert collision_bound(hit, runs) == pytest.approx(
        stats.beta.ppf(0.95, hit + 1, runs - hit), rel=1e-9
    )
    assert collision_bound(runs, runs) == 1.0


def _runs(seeds: int = 12) -> pd.DataFrame:
    """Nominal runs and two faults over the same seeds: 'brake-vmf' lowers every seed's
    least TTC by exactly 1.5 s and raises its DRAC by 0.25; 'aggressive-hdv' changes nothing
    but fails to merge on seeds 0-1 (a failure is the worse outcome)."""
    rng = np.random.default_rng(0)
    rows = []
    for seed in range(seeds):
        ttc, drac = 10 + 5 * rng.random(), 0.5 * rng.random()
        for fault, d_ttc, d_drac, merged in (("none", 0, 0, True), ("brake-vmf", -1.5, 0.25, True),
                                             ("aggressive-hdv", 0, 0, seed > 1)):  # fmt: skip
            rows.append({
                "condition": "C1", "configuration": "FIFO", "fault": fault,
                "channel": "ideal", "shield": False, "seed": seed, "merged": merged,
                "min_ttc": ttc + d_ttc, "max_drac": drac + d_drac,
                "collisions": int(fault == "brake-vmf" and seed == 3), "collisions_commanded": 0,
                "shield_brakes": 0, "shield_holds": 0, "shield_releases": 0, "plans": 1,
                "plans_lost": 0, "fallbacks": 0, "collision_pair": "", "fault_involved": False,
                "min_ttc_unused": math.nan, "wall_s": 0.1,
            })  # fmt: skip
    return pd.DataFrame(rows)


def test_the_paired_effects_against_the_nominal_runs() -> None:
    table = summarise(_runs()).set_index("fault")
    brake, aggressive = table.loc["brake-vmf"], table.loc["aggressive-hdv"]
    assert brake.min_ttc_diff == pytest.approx(-1.5)
    assert brake.min_ttc_ci_low == pytest.approx(-1.5)
    assert brake.min_ttc_ci_high == pytest.approx(-1.5)
    assert brake.min_ttc_verdict == "lower"
    assert brake.max_drac_diff == pytest.approx(0.25)
    assert brake.max_drac_verdict == "higher"
    # 12 of 12 seeds lower: p = 2 / 2**12, Holm over the table's four effects
    assert brake.min_ttc_p_holm == pytest.approx(min(1.0, 4 * 2 / 2**12), rel=1e-9)
    assert brake.runs_with_collision == 1
    assert brake.collision_share_bound == pytest.approx(stats.beta.ppf(0.95, 2, 11))
    # unchanged values, two failed merges: no pair differs, both failures count as worse
    assert aggressive.min_ttc_diff == 0
    assert aggressive.min_ttc_p_holm == pytest.approx(1.0)
    assert math.isnan(table.loc["none"].min_ttc_diff)


def test_the_page_says_what_its_effects_say() -> None:
    runs = _runs()
    overview = summarise(runs, OVERVIEW)
    assert verdicts(overview).startswith(
        "Against the nominal runs of the same condition, controller and seeds, 1 of the 2 "
        "other settings lower the key vehicles' least TTC and 1 raise their largest DRAC"
    )
    text = page(runs, "stamp", "hcomc faults")
    assert "| brake-vmf | ideal | FIFO | off | 12/12 | 1 (< 34 %) |" in text
    assert "-1.50 [-1.50, -1.50] ↓" in text
    assert "0.250 [0.250, 0.250] ↑" in text
    assert "nominal" in text
