"""The runner measures every configuration on the same vehicles against one cached
undisturbed run, and records each VR's merge sequence and number of replans."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.experiments.runner import (
    ALL_CONFIGURATIONS,
    CONFIGURATIONS,
    RunSpec,
    batches_by_reference,
    grid,
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


def test_batches_keep_runs_of_one_undisturbed_run_together() -> None:
    """A worker process simulates each undisturbed run once: the runs that share one fill
    consecutive places of the chunks, every spec exactly once, in spec order within a key."""
    specs = [
        *grid(["C1", "C2"], ["FIFO", "Game", "HCOMC"], range(5), FAST),
        *grid(["C1"], ["FIFO", "HCOMC"], range(2), {"duration": 50.0}),
    ]
    chunks = batches_by_reference(specs, 4)
    order = [i for chunk in chunks for i in chunk]
    assert sorted(order) == list(range(len(specs)))
    assert [len(chunk) for chunk in chunks[:-1]] == [4] * (len(chunks) - 1)
    keys = [specs[i].reference_key() for i in order]
    runs_of = {key: [i for i in order if specs[i].reference_key() == key] for key in keys}
    assert len(runs_of) == 2 * 5 + 2
    for key, members in runs_of.items():
        first = keys.index(key)
        assert keys[first : first + len(members)] == [key] * len(members)  # consecutive
        assert members == sorted(members)
        assert {specs[i].configuration for i in members} == (
            {"FIFO", "HCOMC"} if '"duration": 50.0' in key[2] else {"FIFO", "Game", "HCOMC"}
        )


def test_baselines_plan_once_as_published_and_replan_in_their_r_variants() -> None:
    assert set(CONFIGURATIONS) == {"FIFO", "Game", "HCOMC", "HCOMC-PSO", "HCOMC-SA"}
    assert set(ALL_CONFIGURATIONS) - set(CONFIGURATIONS) == {"FIFO-R", "Game-R", "HCOMC-R",
                                                             "HCOMC+", "HCOMC-eq"}  # fmt: skip
    control = {
        label: RunSpec("C1", label, 0).config_overrides()["control"]
        for label in ("FIFO", "FIFO-R", "Game-R", "HCOMC", "HCOMC-R", "HCOMC+", "HCOMC-eq")
    }
    assert "no_cooperation" not in control["HCOMC"]  # the paper's HCOMC: the config's value
    assert "lateral_safety_rule" not in control["HCOMC"]
    assert control["HCOMC-eq"] == {"replan_period": 0.0, "lateral_safety_rule": False,
                                   "controller": "hcomc", "optimizer": "nsga2"}  # fmt: skip
    assert control["HCOMC+"]["no_cooperation"] is True
    assert control["HCOMC+"]["controller"] == "hcomc"
    assert control["FIFO-R"]["controller"] == "fifo"
    assert control["Game-R"]["controller"] == "game"
    assert control["FIFO"]["replan_period"] == 0.0
    assert control["FIFO-R"]["replan_period"] == pytest.approx(1.0)
    assert control["HCOMC"]["replan_period"] == 0.0  # HCOMC plans once, as published
    assert control["HCOMC-R"]["replan_period"] == pytest.approx(1.0)
    assert control["HCOMC-R"]["controller"] == "hcomc"
