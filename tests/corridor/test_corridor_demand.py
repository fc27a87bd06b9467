"""Corridor demand and loading: profile integrals and intervals, destination and class rules,
presets, ``base`` files, overrides and the TOML round trip."""

from __future__ import annotations

from pathlib import Path

import pytest

from hcomc.config import ConfigError
from hcomc.corridor import (
    OriginDemand,
    corridor_preset_names,
    corridor_to_toml,
    detector_positions,
    is_corridor_source,
    load_corridor,
)


def test_presets_are_listed_and_shipped() -> None:
    names = ["corridor", "paper", *(f"paper-C{k}" for k in range(1, 6))]
    assert corridor_preset_names() == names
    c = load_corridor("corridor")
    assert (c.road.length, c.road.lanes, c.corridor.duration) == (10_000.0, 3, 3600.0)
    assert (len(c.road.on_ramps), len(c.road.off_ramps)) == (5, 4)


def test_linear_profile_integral_and_intervals() -> None:
    main = load_corridor("corridor").demand["main"]  # 2400 -> 3200 (20 min) -> 3200 -> 2400
    assert main.rate(600.0) == pytest.approx(2800.0)
    assert main.rate(1800.0) == pytest.approx(3200.0)
    assert main.rate(3000.0) == pytest.approx(2800.0)
    # (2400 + 3000) / 2 veh/h over 900 s; and the whole hour: 933.3 + 1066.7 + 933.3
    assert main.vehicles(0.0, 900.0) == pytest.approx(675.0)
    assert main.vehicles(0.0, 3600.0) == pytest.approx(8800.0 / 3)
    intervals = main.intervals(3600.0, 60.0)
    assert len(intervals) == 20 + 1 + 20  # 60 s steps on the ramps, one on the plateau
    assert intervals[0] == pytest.approx((0.0, 60.0, 2420.0))  # mean of 2400 and 2440
    assert sum((b - a) * q / 3600.0 for a, b, q in intervals) == pytest.approx(8800.0 / 3)
    assert all(b - a <= 60.0 + 1e-9 for a, b, q in intervals if q != 3200.0)


def test_constant_profile_and_scalar_flow() -> None:
    on5 = load_corridor("corridor").demand["on5"]  # 300 veh/h, 450 veh/h from 1800 s
    assert on5.intervals(3600.0) == [(0.0, 1800.0, 300.0), (1800.0, 3600.0, 450.0)]
    assert on5.vehicles(1700.0, 1900.0) == pytest.approx(100 * 300 / 3600 + 100 * 450 / 3600)
    scalar = OriginDemand.model_validate({"flow": 720})
    assert scalar.flow == [(0.0, 720.0)]
    assert scalar.vehicles(0.0, 600.0) == pytest.approx(120.0)
    assert scalar.intervals(600.0) == [(0.0, 600.0, 720.0)]


def test_profile_rules() -> None:
    with pytest.raises(ValueError, match=r"key 'flow\[0\]' = \[5.0, 100.0\]: allowed: a first"):
        OriginDemand.model_validate({"flow": [[5, 100]]})
    with pytest.raises(ValueError, match=r"key 'flow\[1\]' = \[0.0, 200.0\]: allowed: t > 0"):
        OriginDemand.model_validate({"flow": [[0, 100], [0, 200]]})
    with pytest.raises(ValueError, match=r"allowed: shares summing to 1 \(they sum to 0.9\)"):
        OriginDemand.model_validate({"flow": 100, "classes": {"car": 0.9}})


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "c.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_destination_upstream_of_the_origin_is_refused(tmp_path: Path) -> None:
    path = _write(
        tmp_path,
        'base = "corridor"\n[demand.on3]\nflow = 400.0\n'
        "destinations = { exit = 0.9, off1 = 0.1 }\n",
    )
    with pytest.raises(ConfigError) as info:
        load_corridor(path)
    message = str(info.value)
    assert "key 'demand.on3.destinations.off1'" in message
    assert "off-ramp 'off1' (at 1900 m) is not downstream" in message
    assert "allowed: exit, off3, off4" in message


def test_unknown_origin_class_and_destination(tmp_path: Path) -> None:
    cases = {
        "[demand.on9]\nflow = 100.0\n": "key 'demand.on9': no such origin",
        "[demand.on1]\nflow = 100.0\nclasses = { bus = 1.0 }\n": (
            "key 'demand.on1.classes.bus': no such class; allowed: car, truck"
        ),
        "[demand.on1]\nflow = 100.0\ndestinations = { off9 = 1.0 }\n": (
            "key 'demand.on1.destinations.off9': no such destination"
        ),
        "[demand.main]\nflow = [[0.0, -100.0]]\n": (
            "key 'demand.main.flow[0]' = [0.0, -100.0]: allowed: a flow 0 <= q <= 20000 veh/h"
        ),
        "[demand.main]\ncav_share = 1.5\n": "key 'demand.main.cav_share' = 1.5: allowed: 0 <=",
    }
    for body, expected in cases.items():
        with pytest.raises(ConfigError) as info:
            load_corridor(_write(tmp_path, 'base = "corridor"\n' + body))
        assert expected in str(info.value), body


def test_base_file_overrides_and_class_defaults(tmp_path: Path) -> None:
    path = _write(
        tmp_path,
        'base = "paper"\n[corridor]\nname = "mine"\nduration = 120.0\n'
        "[vehicles.truck]\nlength = 12.0\n",
    )
    assert is_corridor_source(path)
    c = load_corridor(path, {"corridor.seed": 7, "corridor.duration": None})
    assert (c.name, c.corridor.duration, c.corridor.seed) == ("mine", 120.0, 7)
    assert c.road.on_ramps[0].x == 700.0  # from the base
    truck = c.vehicles["truck"]
    assert (truck.length, truck.max_speed, truck.time_headway) == (12.0, 25.0, 1.8)
    assert c.vehicles["car"].idm(cav=True)["time_headway"] == 1.0
    assert c.vehicles["car"].idm(cav=False)["time_headway"] == 1.5


def test_toml_round_trip(tmp_path: Path) -> None:
    c = load_corridor("corridor")
    text = corridor_to_toml(c)
    again = load_corridor(_write(tmp_path, text))
    assert again == c


def test_what_counts_as_a_corridor_source(tmp_path: Path) -> None:
    assert is_corridor_source("corridor")
    assert is_corridor_source("Paper")
    assert not is_corridor_source("C1")
    scenario = tmp_path / "s.toml"
    scenario.write_text('base = "C1"\n[demand]\ncav_penetration = 0.5\n', encoding="utf-8")
    assert not is_corridor_source(scenario)
    derived = tmp_path / "derived.toml"  # no [corridor] table, but based on a corridor
    derived.write_text('base = "paper"\n[demand.main]\nflow = 1000.0\n', encoding="utf-8")
    assert is_corridor_source(derived)
    assert load_corridor(derived).demand["main"].flow == [(0.0, 1000.0)]


def test_detector_positions_of_the_preset() -> None:
    xs = detector_positions(load_corridor("corridor"))
    # every km (9 inside the road) and 50 m before/after each of the 9 ramp areas (18)
    assert len(xs) == 27
    assert xs[:4] == [750.0, 1000.0, 1100.0, 1850.0]
    assert xs[-1] == 9100.0
