"""The runner measures every configuration on the same vehicles against one cached
undisturbed run, and records each VR's merge sequence and number of replans."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.experiments.runner import (
    ALL_CONFIGURATIONS,
    CONFIGURATIONS,
    RunSpec,
    run_one,
    undisturbed_log,
)

FAST = {"duration": 60.0, "control": {"budget": 40, "pop_size": 8}}


def test_every_configuration_is_measured_on_the_same_vehicles() -> None:
    rows = {conf: run_one(RunSpec("C1", conf, 2, FAST))[0] for conf in ("FIFO", "Game", "HCOMC")}
    keys = {row["key_vehicles"] for row in rows.values()}
    vrs = {row["vr"] for row in rows.values()}
    assert len(keys) == 1
    assert len(vrs) == 1
    assert len(next(iter(keys)).split()) >= 4  # VR, VMC and neighbours found
    for row in rows.values():
        assert row["sequence"] in ("ahead", "behind")
        assert row["replans"] >= 0
        assert np.isfinite(row["lsrv"])
        assert np.isfinite(row["average_acceleration"])
        assert row["stabilisation_time"] > 0.0


def test_undisturbed_run_is_shared_and_keyed_by_non_control_overrides() -> None:
    fifo = RunSpec("C1", "FIFO", 4, FAST)
    hcomc = RunSpec("C1", "HCOMC-SA", 4, {**FAST, "control": {"budget": 99}})
    assert undisturbed_log(fifo) is undisturbed_log(hcomc)  # control does not matter
    other = RunSpec("C1", "FIFO", 4, {"duration": 50.0})
    assert undisturbed_log(other) is not undisturbed_log(fifo)
    assert undisturbed_log(other).n_recorded == 501
    assert not undisturbed_log(fifo).meta.get("key_groups")  # nothing merges in it


def test_baselines_plan_once_as_published_and_replan_in_their_r_variants() -> None:
    assert set(CONFIGURATIONS) == {"FIFO", "Game", "HCOMC", "HCOMC-PSO", "HCOMC-SA"}
    assert set(ALL_CONFIGURATIONS) - set(CONFIGURATIONS) == {"FIFO-R", "Game-R"}
    control = {
        label: RunSpec("C1", label, 0).config_overrides()["control"]
        for label in ("FIFO", "FIFO-R", "Game-R", "HCOMC")
    }
    assert control["FIFO-R"]["controller"] == "fifo"
    assert control["Game-R"]["controller"] == "game"
    assert control["FIFO"]["replan_period"] == 0.0
    assert control["FIFO-R"]["replan_period"] == pytest.approx(1.0)
    assert "replan_period" not in control["HCOMC"]  # HCOMC uses the config default
