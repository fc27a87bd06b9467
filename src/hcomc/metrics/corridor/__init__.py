"""Corridor runs: any road of :mod:`hcomc.corridor` (mainline lanes, on- and off-ramps, lane
drops, speed zones) with its time-varying demand and vehicle classes, run on the engine of
every road (:class:`hcomc.sim.engine.Simulation` with the corridor's scene) with a merge
controller at every on-ramp, and measured from the run's log with induction loops, Edie's
space-time cells, per-vehicle trips and per-merge events.

The names below load :mod:`hcomc.metrics.corridor.run` on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["OUTCOMES", "CorridorRun", "simulate_corridor"]


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module("hcomc.metrics.corridor.run"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
