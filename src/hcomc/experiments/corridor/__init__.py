"""Experiments on a corridor: runs of merge controllers at every ramp
(:mod:`~hcomc.experiments.corridor.runs`), their metrics
(:mod:`~hcomc.experiments.corridor.metrics`), paired comparisons
(:mod:`~hcomc.experiments.corridor.compare`) and sweeps (:mod:`~hcomc.experiments.corridor.sweep`).
"""
