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


# --------------------------------------------------------------------------- overrides, base
def test_flat_dotted_and_nested_overrides_agree():
    flat = load_config("C2", cav_penetration=0.5)
    dotted = load_config("C2", **{"demand.cav_penetration": 0.5})
    nested = load_config("C2", demand={"cav_penetration": 0.5})
    assert flat == dotted == nested
    assert flat.demand.cav_penetration == 0.5
    assert flat.demand.mean_headway_main_2 == 7.0  # the rest of C2 is kept


def test_ambiguous_flat_override_names_its_homes():
    with pytest.raises(ConfigError) as info:
        load_config("C1", time_headway=1.2)
    assert "ambiguous" in str(info.value)
    assert "'hdv.time_headway'" in str(info.value)
    assert "'cav.time_headway'" in str(info.value)


@pytest.mark.parametrize(
    ("overrides", "suggestion"),
    [
        ({"cav_penetraton": 0.5}, "'demand.cav_penetration'"),
        ({"demand.cav_penetraton": 0.5}, "'demand.cav_penetration'"),
        ({"demand.politeness": 0.3}, "'lane_change.politeness'"),
        ({"durration": 60.0}, "'duration'"),
        ({"demnd.cav_penetration": 0.5}, "'demand.cav_penetration'"),
        ({"controler": "fifo"}, "'control.controller'"),
        ({"cav.coolnes": 0.5}, "'cav.coolness'"),
    ],
)
def test_unknown_key_suggests_the_closest_valid_one(overrides, suggestion):
    with pytest.raises(ConfigError, match="did you mean") as info:
        load_config("C1", **overrides)
    assert suggestion in str(info.value)
    assert "\n" not in str(info.value)


def test_unknown_key_in_a_file_suggests_too(tmp_path):
    path = tmp_path / "typo.toml"
    path.write_text("[lane_change]\npolitenes = 0.3\n")
    with pytest.raises(ConfigError, match=r"did you mean 'lane_change.politeness'\?"):
        load_config(path)
    path.write_text("[demnd]\nramp = 'flow'\n")
    with pytest.raises(ConfigError, match=r"unknown key 'demnd'.*did you mean 'demand'\?"):
        load_config(path)


def test_nothing_close_means_no_suggestion():
    with pytest.raises(ConfigError, match="not a config key") as info:
        load_config("C1", zzz=1)
    assert "did you mean" not in str(info.value)


def test_partial_file_inherits_the_preset_defaults(tmp_path):
    path = tmp_path / "partial.toml"
    path.write_text("[demand]\ncav_penetration = 0.5\n")
    config = load_config(path)
    assert config.duration == load_config("C1").duration == 90.0
    assert config.warmup == load_config("C1").warmup


def test_base_in_a_scenario_file(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('base = "C2"\n[demand]\ncav_penetration = 0.5\n')
    config = load_config(path)
    c2 = load_config("C2")
    assert config.demand.mean_headway_main_2 == 7.0  # from C2, not the 5.0 default
    assert config.demand.cav_penetration == 0.5
    assert config.name == "mine"  # not labelled as C2
    assert "demand.cav_penetration 0.9 -> 0.5" in config.description
    assert config.model_copy(update={"name": "C2", "description": c2.description}) == c2.model_copy(
        update={"demand": c2.demand.model_copy(update={"cav_penetration": 0.5})}
    )
    child = tmp_path / "child.toml"
    child.write_text('base = "mine.toml"\nduration = 40.0\n')  # relative to the file
    assert load_config(child).demand.cav_penetration == 0.5
    assert load_config(child).duration == 40.0


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("base = 3\n", "key 'base' = 3"),
        ('base = "C9"\n', "unknown preset 'C9'"),
        ('base = "loop.toml"\n', "circular"),
        ('base = "../sub/loop.toml"\n', "circular"),
    ],
)
def test_bad_base_is_one_line(tmp_path, text, fragment):
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "loop.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


def test_description_follows_overrides():
    assert load_config("C5").description.endswith("0.3")  # untouched preset: as written
    changed = load_config("C5", cav_penetration=0.8, duration=60.0)
    assert "demand.cav_penetration 0.3 -> 0.8" in changed.description
    assert "duration 90.0 -> 60.0" in changed.description


def test_annotated_toml_round_trips_and_documents_every_key(tmp_path):
    from hcomc.config import leaf_paths

    config = load_config("C3", cav_penetration=0.4)
    text = config_to_toml(config, annotate=True)
    path = tmp_path / "shown.toml"
    path.write_text(text)
    assert load_config(path) == config
    assert "cav_penetration = 0.4  # share of CAVs [-]" in text
    assert "[demand]  # Traffic demand" in text
    commented = [line for line in text.splitlines() if " = " in line and "  # " in line]
    assert len(commented) == len(leaf_paths())
