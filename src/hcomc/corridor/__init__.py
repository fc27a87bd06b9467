"""Corridors: a general road (mainline, on- and off-ramps, lane drops, speed-limit zones) and
its time-varying demand, validated from TOML presets and files.

hcomc's own engine simulates the paper's road (and corridors of its layout,
:mod:`hcomc.corridor.engine`); any corridor runs in SUMO
(:mod:`hcomc.sumo.corridor`, ``hcomc export sumo corridor --out DIR``). The sections of
:func:`~hcomc.corridor.road.sections` are the layout both read. This package depends only
on :mod:`hcomc.config` (its error type), so any layer may use it.
"""

from hcomc.corridor.demand import CAVOverrides, OriginDemand, VehicleClass
from hcomc.corridor.loading import (
    corridor_preset_names,
    corridor_to_toml,
    describe_corridor_error,
    is_corridor_source,
    load_corridor,
)
from hcomc.corridor.model import Corridor, DetectorSettings, RunSettings, detector_positions
from hcomc.corridor.road import LaneDrop, OffRamp, OnRamp, Road, Section, SpeedLimit, sections

__all__ = [
    "CAVOverrides",
    "Corridor",
    "DetectorSettings",
    "LaneDrop",
    "OffRamp",
    "OnRamp",
    "OriginDemand",
    "Road",
    "RunSettings",
    "Section",
    "SpeedLimit",
    "VehicleClass",
    "corridor_preset_names",
    "corridor_to_toml",
    "describe_corridor_error",
    "detector_positions",
    "is_corridor_source",
    "load_corridor",
    "sections",
]
