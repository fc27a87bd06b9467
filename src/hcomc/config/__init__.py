"""Scenario configuration: TOML files validated into frozen pydantic v2 models.

Every parameter carries its SI unit in the field description and a documented default
(docs/models.md gives each one's source). Unknown keys are rejected (``extra="forbid"``),
so a typo in a config file is an error, never a silently ignored setting.

A config is named either by a path to a TOML file or by a built-in preset name
(``C1`` … ``C5`` for the paper's Table I conditions, ``platoon`` for the scripted-leader
platoon), see :func:`load_config`.
"""

from hcomc.config.control_table import ControlParams
from hcomc.config.loading import (
    config_to_toml,
    describe_error,
    leaf_paths,
    load_config,
    merge_tables,
    nest_overrides,
    preset_names,
    suggest,
    validate_config,
)
from hcomc.config.schema import MIN_STEP, ConfigError, ScenarioConfig
from hcomc.config.traffic_tables import DemandParams, PlatoonParams, RoadParams
from hcomc.config.vehicle_tables import CAVParams, HDVParams, IDMParams, LaneChangeParams

__all__ = [
    "MIN_STEP",
    "CAVParams",
    "ConfigError",
    "ControlParams",
    "DemandParams",
    "HDVParams",
    "IDMParams",
    "LaneChangeParams",
    "PlatoonParams",
    "RoadParams",
    "ScenarioConfig",
    "config_to_toml",
    "describe_error",
    "leaf_paths",
    "load_config",
    "merge_tables",
    "nest_overrides",
    "preset_names",
    "suggest",
    "validate_config",
]
