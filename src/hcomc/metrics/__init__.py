"""Evaluation metrics of a simulation log (paper Tables II-III).

One call evaluates a run against its undisturbed counterpart::

    log = Simulation(config, seed).run()
    reference = Simulation(config, seed, counterfactual=True).run()
    values = compute_metrics(log, reference=reference)

Lower level: every metric is a function ``metric(log, window, ...) -> float`` of a
:class:`~hcomc.sim.log.SimulationLog` and the :class:`MetricWindow` of one merge (built by
:func:`key_window` or :func:`merge_window`). Modules: :mod:`~hcomc.metrics.window` (window,
key vehicles, tolerances), :mod:`~hcomc.metrics.paper` (critical distance, average
acceleration, stabilisation times, integrated disturbance),
:mod:`~hcomc.metrics.merge_safety` (Eq. 15's U_safe at the merge),
:mod:`~hcomc.metrics.leaders` (actual same-lane leaders), :mod:`~hcomc.metrics.lsrv` (LSRV),
:mod:`~hcomc.metrics.fuel_distance` (fuel over a common distance),
:mod:`~hcomc.metrics.outcome` (merged, merge time, ramp wait, sequence),
:mod:`~hcomc.metrics.speed_field` (speed fields for the figures),
:mod:`~hcomc.metrics.lane_profile` (the lane profile of a logged row, behind the lane speed
field and VR's undisturbed counterpart), :mod:`~hcomc.metrics.surrogate` (TTC, DRAC, PET,
collisions), :mod:`~hcomc.metrics.core` (registry).
"""

from __future__ import annotations

from hcomc.metrics.core import METRICS, MetricSpec, compute_metrics
from hcomc.metrics.fuel_distance import fuel
from hcomc.metrics.logged_profile import lane_profile_at
from hcomc.metrics.lsrv import low_speed_region_volume
from hcomc.metrics.merge_safety import u_safe_at_merge
from hcomc.metrics.outcome import OUTCOME_FIELDS, MergeOutcome, merge_outcome, realised_sequence
from hcomc.metrics.paper import (
    average_acceleration,
    critical_distance,
    deviations,
    integrated_disturbance,
    stabilisation_time,
    stabilisation_time_from_merge,
)
from hcomc.metrics.speed_field import (
    DT_BIN,
    DX_BIN,
    lane_speed_field,
    reference_speed,
    speed_field,
)
from hcomc.metrics.surrogate import (
    CLOSING_SPEED,
    collisions,
    key_collisions,
    max_drac,
    min_ttc,
    pet_at_merge,
)
from hcomc.metrics.window import (
    A_TOL,
    HOLD,
    KEY_ROLES,
    V_TOL,
    MetricWindow,
    key_window,
    merge_window,
    road_of,
)

__all__ = [
    "A_TOL",
    "CLOSING_SPEED",
    "DT_BIN",
    "DX_BIN",
    "HOLD",
    "KEY_ROLES",
    "METRICS",
    "OUTCOME_FIELDS",
    "V_TOL",
    "MergeOutcome",
    "MetricSpec",
    "MetricWindow",
    "average_acceleration",
    "collisions",
    "compute_metrics",
    "critical_distance",
    "deviations",
    "fuel",
    "integrated_disturbance",
    "key_collisions",
    "key_window",
    "lane_profile_at",
    "lane_speed_field",
    "low_speed_region_volume",
    "max_drac",
    "merge_outcome",
    "merge_window",
    "min_ttc",
    "pet_at_merge",
    "realised_sequence",
    "reference_speed",
    "road_of",
    "speed_field",
    "stabilisation_time",
    "stabilisation_time_from_merge",
    "u_safe_at_merge",
]
