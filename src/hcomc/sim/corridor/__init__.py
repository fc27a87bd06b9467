"""hcomc's engine for corridors: any road of :mod:`hcomc.corridor` (mainline lanes, on- and
off-ramps, lane drops, speed zones), its time-varying demand and vehicle classes, compiled
step by step, with a merge controller at every on-ramp; measured with induction loops,
Edie's space-time cells, per-vehicle trips and per-merge events.

The names below load :mod:`hcomc.sim.corridor.run` on first use: the compiled modules of this
package import only each other, so that editing the Python around them (running, deciding,
tabulating) does not recompile the kernels.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["OUTCOMES", "CorridorRun", "simulate_corridor"]


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module("hcomc.sim.corridor.run"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
