"""The vehicles of a corridor run: who departs when and where, with which parameters.

Departure times, origins and destinations come from the corridor's departure schedule
(:func:`hcomc.corridor.schedule.departure_times`, the same vehicles SUMO gets); each
vehicle's class and automation are drawn from its origin's shares with the run's seed (as
SUMO draws a flow's vehicle type from its ``vTypeDistribution``: class share x CAV share or
1 - CAV share). A CAV drives the IDM with its class's CAV values.
:func:`hcomc.sim.corridor.setup.build_fleet` builds the fleet.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["IDM_COLUMNS", "CorridorFleet"]

IDM_COLUMNS = ("desired_speed", "time_headway", "min_gap", "max_accel", "comfort_decel",
               "exponent")  # fmt: skip
"""Columns of :attr:`CorridorFleet.idm`, in order."""


class CorridorFleet(NamedTuple):
    """Per-vehicle arrays, vehicles in departure order (ids 0 … N-1)."""

    depart: np.ndarray  # wanted departure time [s]
    origin: np.ndarray  # index into ``origins``
    destination: np.ndarray  # index into ``destinations`` (0 = the mainline exit)
    vclass: np.ndarray  # index into ``classes``
    cav: np.ndarray  # bool
    idm: np.ndarray  # (N, 6): IDM_COLUMNS
    length: np.ndarray  # [m]
    max_speed: np.ndarray  # [m/s]
    start_code: np.ndarray  # ramp code j = 0 of an on-ramp origin, -1 for the mainline
    exit_code: np.ndarray  # code j = 0 of the destination off-ramp, -1 for the mainline exit
    queue_start: np.ndarray  # (n_origins + 1,): origin o's vehicles are queue[start[o]:start[o+1]]
    queue: np.ndarray  # vehicle ids grouped by origin, each group in departure order
    origins: tuple[str, ...]
    destinations: tuple[str, ...]
    classes: tuple[str, ...]
