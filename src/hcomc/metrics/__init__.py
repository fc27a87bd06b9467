"""Evaluation metrics of a simulation log (DESIGN.md §5, MODELS.md §12, paper Tables II-III).

Every metric is a pure function ``metric(log, window) -> float`` of a
:class:`~hcomc.sim.log.SimulationLog` and the :class:`MetricWindow` of one merge, built by
:func:`merge_window`; :func:`compute_metrics` evaluates the whole :data:`METRICS` registry.
"""

from __future__ import annotations

from hcomc.metrics.core import (
    A_TOL,
    CLOSING_SPEED,
    HOLD,
    KEY_ROLES,
    METRICS,
    V_TOL,
    MetricSpec,
    MetricWindow,
    average_acceleration,
    collisions,
    compute_metrics,
    critical_distance,
    fuel,
    key_collisions,
    low_speed_region_volume,
    max_drac,
    merge_window,
    min_ttc,
    pet_at_merge,
    reference_speed,
    speed_field,
    stabilisation_time,
)

__all__ = [
    "A_TOL",
    "CLOSING_SPEED",
    "HOLD",
    "KEY_ROLES",
    "METRICS",
    "V_TOL",
    "MetricSpec",
    "MetricWindow",
    "average_acceleration",
    "collisions",
    "compute_metrics",
    "critical_distance",
    "fuel",
    "key_collisions",
    "low_speed_region_volume",
    "max_drac",
    "merge_window",
    "min_ttc",
    "pet_at_merge",
    "reference_speed",
    "speed_field",
    "stabilisation_time",
]
