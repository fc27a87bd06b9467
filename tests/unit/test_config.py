"""Config loading, presets, round trip and error messages."""

from __future__ import annotations

import pytest

from hcomc.config import (
    ConfigError,
    ScenarioConfig,
    config_to_toml,
    load_config,
    preset_names,
    validate_config,
)

TABLE_I = {
    "C1": (5.0, 5.0, 0.9),
    "C2": (5.0, 7.0, 0.9),
    "C3": (5.0, 3.0, 0.9),
    "C4": (5.0, 5.0, 0.6),
    "C5": (5.0, 5.0, 0.3),
}


@pytest.mark.parametrize(("name", "values"), TABLE_I.items())
def test_presets_match_table_one(name, values):
    d = load_config(name).demand
    assert (d.mean_headway_main_1, d.mean_headway_main_2, d.cav_penetration) == values


def test_preset_names_case_insensitive():
    assert set(TABLE_I) | {"platoon"} == set(preset_names())
    assert load_config("c3") == load_config("C3")


@pytest.mark.parametrize("name", [*TABLE_I, "platoon"])
def test_resolved_toml_round_trips(name, tmp_path):
    config = load_config(name)
    path = tmp_path / "resolved.toml"
    path.write_text(config_to_toml(config))
    assert load_config(path) == config


def test_models_are_frozen():
    config = load_config("C1")
    with pytest.raises(ValueError, match="frozen"):
        config.duration = 3.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("data", "fragments"),
    [
        ({"demand": {"cav_penetraton": 0.5}}, ["unknown key 'demand.cav_penetraton'", "0.5"]),
        ({"demand": {"cav_penetration": 1.5}}, ["demand.cav_penetration", "1.5", "less than"]),
        ({"demand": {"mean_headway_main_1": -5}}, ["mean_headway_main_1", "-5", "greater than"]),
        ({"dt": "fast"}, ["'dt'", "'fast'", "number"]),
        ({"demand": {"mean_headway_main_2": 0.5}}, ["mean_headway_main_2", "min_headway"]),
        ({"road": {"accel_lane_end": 600.0}}, ["road", "accel_lane_start < accel_lane_end"]),
        ({"log_interval": 0.25}, ["log_interval", "multiple of dt"]),
    ],
)
def test_errors_name_key_value_and_rule(data, fragments):
    with pytest.raises(ConfigError) as info:
        validate_config(data, "test.toml")
    message = str(info.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message


def test_missing_file_and_unknown_preset(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        load_config(tmp_path / "nope.toml")
    with pytest.raises(ConfigError, match=r"unknown preset 'C9'; allowed: C1, C2"):
        load_config("C9")


def test_invalid_toml(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("duration = = 3")
    with pytest.raises(ConfigError, match="invalid TOML"):
        load_config(path)


def test_defaults_follow_models_md():
    c = ScenarioConfig()
    assert (c.hdv.time_headway, c.hdv.max_accel, c.hdv.reaction_time_gap) == (1.5, 1.0, 0.6)
    assert (c.cav.time_headway, c.cav.max_accel, c.cav.coolness) == (1.0, 1.4, 0.99)
    assert (c.road.lane_width, c.road.control_zone_start, c.dt) == (3.75, 400.0, 0.1)
