"""hcomc's engine for corridors: any road of :mod:`hcomc.corridor` (mainline lanes, on- and
off-ramps, lane drops, speed zones), its time-varying demand and vehicle classes, compiled
step by step; measured with induction loops, Edie's space-time cells and per-vehicle trips.
"""

from hcomc.sim.corridor.run import OUTCOMES, CorridorRun, simulate_corridor

__all__ = ["OUTCOMES", "CorridorRun", "simulate_corridor"]
