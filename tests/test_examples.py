"""The example notebook script runs as documented and its results are the library's."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

from hcomc.metrics import METRICS, OUTCOME_FIELDS

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "notebook_api.py"


@pytest.fixture(scope="module")
def cells() -> dict:
    return runpy.run_path(str(EXAMPLE), run_name="__main__")


def test_overrides_resolve_to_their_homes(cells):
    config = cells["config"]
    assert config.demand.cav_penetration == 0.5
    assert config.demand.mean_headway_main_2 == 7.0  # the rest of C2 is kept
    assert config.duration == 60.0
    assert "demand.cav_penetration 0.9 -> 0.5" in config.description


def test_metrics_cell_gives_every_paper_metric_for_the_logged_merge(cells):
    metrics, log, group = cells["metrics"], cells["log"], cells["group"]
    assert list(metrics) == [*METRICS, *OUTCOME_FIELDS]
    assert metrics["merged"] is True
    assert group["VR"] >= 0
    assert metrics["fuel"] > 0
    assert metrics["collisions"] == 0
    for name in ("average_acceleration", "stabilisation_time", "lsrv"):  # vs the reference
        assert np.isfinite(metrics[name]), name
        assert metrics[name] >= 0.0, name
    merges = cells["events"].query("kind == 'MERGE'")
    assert group["VR"] in set(merges["vehicle"])  # the window is the recorded VR's merge
    assert log.n_recorded == round(60.0 / 0.1) + 1


def test_frames_match_the_log(cells):
    log, frame = cells["log"], cells["frame"]
    assert len(frame) == int(log.active[: log.n_recorded].sum())


def test_custom_controller_is_called_once_per_ramp_vehicle(cells):
    custom, controller = cells["custom"], cells["controller"]
    # one ramp vehicle, planned once at control-zone entry (the default, as the paper)
    assert len(custom.key_groups) == 1
    assert custom.config.control.replan_period == 0.0
    assert len(controller.seen) == len(custom.decisions) == 1
    vr = next(iter(custom.key_groups))
    assert custom.decisions[0].group.vr == vr
    plans = cells["custom_log"].meta["plans"]
    assert plans[0]["mode"] == "none"
    assert plans[0]["reason"].startswith("lane-1 gap")


def test_example_is_deterministic(cells):
    again = runpy.run_path(str(EXAMPLE), run_name="__main__")
    assert again["metrics"] == cells["metrics"]
