"""Corridor roads: every validation rule's message (key path, value, what is allowed), the
sorting of ramps and the sections of the presets."""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Callable
from importlib.resources import files
from pathlib import Path
from typing import Any

import pytest
import tomli_w

from hcomc.config import ConfigError
from hcomc.corridor import Section, load_corridor, sections

PRESET: dict[str, Any] = tomllib.loads(
    files("hcomc").joinpath("configs/corridors/corridor.toml").read_text(encoding="utf-8")
)


def _load_changed(tmp_path: Path, change: Callable[[dict[str, Any]], None]) -> Any:
    data = copy.deepcopy(PRESET)
    change(data)
    path = tmp_path / "changed.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return load_corridor(path)


def _error(tmp_path: Path, change: Callable[[dict[str, Any]], None]) -> str:
    with pytest.raises(ConfigError) as info:
        _load_changed(tmp_path, change)
    message = str(info.value)
    assert "\n" not in message
    return message


def _on(k: int, key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return lambda d: d["road"]["on_ramps"][k].__setitem__(key, value)


def _off(k: int, key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return lambda d: d["road"]["off_ramps"][k].__setitem__(key, value)


def _road(key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return lambda d: d["road"].__setitem__(key, value)


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (_road("lanes", 0), "key 'road.lanes' = 0: allowed: 1 <= lanes <= 6"),
        (_road("lanes", 7), "key 'road.lanes' = 7: allowed: 1 <= lanes <= 6"),
        (_on(1, "lanes", 3), "key 'road.on_ramps[1].lanes' = 3: allowed: 1 <= lanes <= 2"),
        (_off(3, "lanes", 0), "key 'road.off_ramps[3].lanes' = 0: allowed: 1 <= lanes <= 2"),
        (
            _road("lane_drops", [{"x": 9500.0, "lanes": 0}]),
            "key 'road.lane_drops[0].lanes' = 0: allowed: 1 <= lanes <= 6",
        ),
    ],
    ids=["zero-lanes", "seven-lanes", "ramp-lanes", "off-ramp-lanes", "drop-lanes"],
)
def test_lane_counts_out_of_range(tmp_path: Path, change: Any, expected: str) -> None:
    assert expected in _error(tmp_path, change)


def test_on_ramp_past_the_end(tmp_path: Path) -> None:
    message = _error(tmp_path, _on(2, "x", 9900.0))
    # 10 km road, 250 m acceleration lane: it must start before 9750 m
    assert "key 'road.on_ramps[2].x' = 9900.0: allowed: 0 <= x < 9750" in message
    assert "road.length = 10000" in message


def test_ramp_before_zero(tmp_path: Path) -> None:
    message = _error(tmp_path, _on(2, "x", -5.0))
    assert "key 'road.on_ramps[2].x' = -5.0: allowed: 0 <= x" in message


def test_off_ramp_past_the_end(tmp_path: Path) -> None:
    message = _error(tmp_path, _off(0, "x", 10000.0))
    assert "key 'road.off_ramps[0].x' = 10000.0: allowed: 0 <= x < 9800" in message


def test_lane_drop_past_the_end_or_before_zero(tmp_path: Path) -> None:
    past = _error(tmp_path, _road("lane_drops", [{"x": 12000.0, "lanes": 2}]))
    assert "key 'road.lane_drops[0].x' = 12000.0: allowed: 0 < x < road.length = 10000" in past
    before = _error(tmp_path, _road("lane_drops", [{"x": 0.0, "lanes": 2}]))
    assert "key 'road.lane_drops[0].x' = 0.0: allowed: 0 < x" in before


def test_lane_drop_must_change_the_count(tmp_path: Path) -> None:
    message = _error(tmp_path, _road("lane_drops", [{"x": 9500.0, "lanes": 3}]))
    assert "key 'road.lane_drops[0].lanes' = 3: allowed: a lane count other than 3" in message


def test_deceleration_lane_overlapping_an_acceleration_lane(tmp_path: Path) -> None:
    message = _error(tmp_path, _off(0, "x", 900.0))  # on1's acceleration lane: 800-1050 m
    assert "key 'road.off_ramps[0].x' = 900.0: allowed: x >= 1050" in message
    assert "on_ramps[0] ('on1', 800 to 1050 m)" in message


def test_acceleration_lanes_overlapping(tmp_path: Path) -> None:
    message = _error(tmp_path, _on(1, "x", 1000.0))
    assert "key 'road.on_ramps[1].x' = 1000.0: allowed: x >= 1050" in message


def test_lane_drop_inside_a_ramp_area(tmp_path: Path) -> None:
    message = _error(tmp_path, _road("lane_drops", [{"x": 2000.0, "lanes": 2}]))
    assert "key 'road.lane_drops[0].x' = 2000.0" in message
    assert "outside off_ramps[0] ('off1', 1900 to 2100 m)" in message


def test_duplicate_and_reserved_ids(tmp_path: Path) -> None:
    duplicate = _error(tmp_path, _off(1, "id", "on2"))
    assert "key 'road.off_ramps[1].id' = 'on2': allowed: an id not used before" in duplicate
    assert "used by on_ramps[1]" in duplicate
    reserved = _error(tmp_path, _on(0, "id", "exit"))
    assert "key 'road.on_ramps[0].id' = 'exit'" in reserved


def test_control_zone_must_lie_on_the_ramp(tmp_path: Path) -> None:
    message = _error(tmp_path, _on(0, "control_zone_length", 500.0))
    assert "key 'road.on_ramps[0].control_zone_length' = 500.0: allowed: <= ramp_length = 450" in (
        message
    )


def test_overlapping_speed_zones(tmp_path: Path) -> None:
    zones = [{"x0": 100.0, "x1": 500.0, "speed": 20.0}, {"x0": 400.0, "x1": 900.0, "speed": 25.0}]
    message = _error(tmp_path, _road("speed_limits", zones))
    assert "key 'road.speed_limits[1].x0' = 400.0: allowed: x0 >= 500" in message


def test_unknown_key_suggests_the_spelling(tmp_path: Path) -> None:
    message = _error(tmp_path, _on(0, "accel_lenght", 300.0))
    assert "unknown key 'road.on_ramps[0].accel_lenght' (did you mean 'accel_length'?)" in message


def test_unsorted_ramps_are_sorted(tmp_path: Path) -> None:
    corridor = _load_changed(tmp_path, lambda d: d["road"]["on_ramps"].reverse())
    assert [r.id for r in corridor.road.on_ramps] == ["on1", "on2", "on3", "on4", "on5"]
    assert [r.x for r in corridor.road.on_ramps] == [800.0, 2800.0, 4800.0, 6800.0, 8800.0]
    assert sections(corridor.road) == sections(load_corridor("corridor").road)


def test_sections_of_the_corridor_preset() -> None:
    road = load_corridor("corridor").road
    found = sections(road)
    # 5 acceleration + 4 deceleration areas, 2 speed-zone cuts: 21 sections
    assert len(found) == 21
    assert found[0] == Section(0.0, 800.0, 3, 0, None, "main", 33.3)
    assert found[1] == Section(800.0, 1050.0, 3, 1, "on1", "accel", 33.3)
    assert found[3] == Section(1900.0, 2100.0, 3, 1, "off1", "decel", 33.3)
    assert found[-1] == Section(9050.0, 10000.0, 3, 0, None, "main", 33.3)
    assert [s.x0 for s in found[1:]] == [s.x1 for s in found[:-1]]  # contiguous
    assert sum(s.length for s in found) == pytest.approx(10_000.0)
    accel = [s for s in found if s.kind == "accel"]
    decel = [s for s in found if s.kind == "decel"]
    assert [s.ramp for s in accel] == ["on1", "on2", "on3", "on4", "on5"]
    assert [s.ramp for s in decel] == ["off1", "off2", "off3", "off4"]
    assert {s.length for s in accel} == {250.0}
    assert {s.length for s in decel} == {200.0}
    # the 100 km/h zone 4500-6500 m holds on3 and off3
    slow = [s for s in found if s.speed_limit == 27.8]
    assert (slow[0].x0, slow[-1].x1) == (4500.0, 6500.0)
    assert {s.ramp for s in slow} == {None, "on3", "off3"}
    assert all(s.lanes == 3 and s.total_lanes == 3 + s.ramp_lanes for s in found)


def test_sections_of_the_paper_preset_match_condition_c1() -> None:
    from hcomc.config import load_config

    c1 = load_config("C1").road
    paper = load_corridor("paper")
    ramp = paper.road.on_ramps[0]
    assert (ramp.x, ramp.end) == (c1.accel_lane_start, c1.accel_lane_end)  # 700, 950 m
    assert ramp.x - ramp.ramp_length == c1.ramp_start  # 250 m
    assert ramp.control_zone_length == c1.control_zone_length  # 300 m
    assert paper.road.length == c1.length
    assert sections(paper.road) == (
        Section(0.0, 700.0, 2, 0, None, "main", 38.3),
        Section(700.0, 950.0, 2, 1, "ramp", "accel", 38.3),
        Section(950.0, 1500.0, 2, 0, None, "main", 38.3),
    )


def test_lane_drop_and_speed_zone_cut_sections(tmp_path: Path) -> None:
    def change(d: dict[str, Any]) -> None:
        d["road"]["lane_drops"] = [{"x": 9500.0, "lanes": 2}]
        d["road"]["speed_limits"] = [{"x0": 900.0, "x1": 1000.0, "speed": 22.2}]

    found = sections(_load_changed(tmp_path, change).road)
    assert [(s.x0, s.x1, s.lanes) for s in found[-2:]] == [
        (9050.0, 9500.0, 3),
        (9500.0, 10000.0, 2),
    ]
    # the zone cuts on1's acceleration lane into two sections of the same ramp
    assert [(s.x0, s.x1, s.ramp, s.speed_limit) for s in found[1:4]] == [
        (800.0, 900.0, "on1", 33.3),
        (900.0, 1000.0, "on1", 22.2),
        (1000.0, 1050.0, "on1", 33.3),
    ]
