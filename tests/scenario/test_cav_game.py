"""Opt-in Section III-B game for CAV discretionary lane changes (lane_change.cav_game)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import hcomc.control.lane_change_game.decision as game_module
from hcomc.config import load_config
from hcomc.road import Kind, Lane
from hcomc.sim.engine import simulate
from hcomc.sim.log import EventKind


def _config(cav_game: bool):
    demand = {**load_config("C3").demand.model_dump(), "ramp": "flow"}
    return load_config("C3", duration=150.0, demand=demand, lane_change={"cav_game": cav_game})


def _discretionary_starts(log) -> tuple[int, int]:
    """(CAV, HDV) lane-change starts from a main lane."""
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    cav = hdv = 0
    for e in starts:
        i, row = int(e["vehicle"]), round(float(e["t"] - log.t[0]) / log.dt)
        if 0 <= row < log.lane.shape[0] and log.lane[row, i] in (Lane.MAIN_1, Lane.MAIN_2):
            cav += log.kind[i] == Kind.CAV
            hdv += log.kind[i] == Kind.HDV
    return cav, hdv


def test_game_that_always_keeps_blocks_every_cav_discretionary_change(monkeypatch):
    calls = []

    def keep(sv, fv, sv_leader, target_leader, **kwargs):
        calls.append(sv)
        assert sv.is_cav
        return SimpleNamespace(change=False)

    monkeypatch.setattr(game_module, "lane_change_game", keep)
    log = simulate(_config(True), seed=2)
    cav, hdv = _discretionary_starts(log)
    assert calls  # the game was consulted
    assert cav == 0
    assert hdv > 0  # human drivers keep deciding by MOBIL alone
    assert log.events_of(EventKind.MERGE).size > 0  # ramp merges are not gated


@pytest.mark.slow
def test_real_game_gates_cav_changes_and_stays_collision_free():
    without, with_game = simulate(_config(False), seed=2), simulate(_config(True), seed=2)
    assert _discretionary_starts(with_game)[0] < _discretionary_starts(without)[0]
    assert with_game.events_of(EventKind.COLLISION).size == 0
    again = simulate(_config(True), seed=2)
    np.testing.assert_array_equal(with_game.x, again.x)
