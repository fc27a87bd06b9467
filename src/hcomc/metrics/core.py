"""The metric registry and :func:`compute_metrics`, the one call that evaluates a run.

* ``critical_distance`` [m, larger is better]: :func:`hcomc.metrics.paper.critical_distance`
* ``u_safe_at_merge`` [m/s², smaller]: :func:`hcomc.metrics.merge_safety.u_safe_at_merge`
* ``average_acceleration`` [m/s², smaller]: :func:`hcomc.metrics.paper.average_acceleration`
* ``stabilisation_time`` [s, smaller]: :func:`hcomc.metrics.paper.stabilisation_time` (from
  VR's control-zone entry)
* ``stabilisation_time_from_merge`` [s, smaller; favours late merges]:
  :func:`hcomc.metrics.paper.stabilisation_time_from_merge`
* ``integrated_disturbance`` [m, smaller]: :func:`hcomc.metrics.paper.integrated_disturbance`
* ``lsrv`` [m², smaller]: :func:`hcomc.metrics.lsrv.low_speed_region_volume`
* ``fuel`` [L, smaller]: :func:`hcomc.metrics.fuel_distance.fuel`
* ``min_ttc`` [s, larger]: :func:`hcomc.metrics.surrogate.min_ttc`
* ``max_drac`` [m/s², smaller]: :func:`hcomc.metrics.surrogate.max_drac`
* ``pet`` [s, larger]: :func:`hcomc.metrics.surrogate.pet_at_merge`
* ``collisions`` [count, smaller]: :func:`hcomc.metrics.surrogate.collisions`
* ``key_collisions`` [count, smaller]: :func:`hcomc.metrics.surrogate.key_collisions`

Average acceleration, the stabilisation times, the integrated disturbance, LSRV and fuel
compare with the undisturbed run (same scenario and seed, no ramp vehicle released); they are
NaN when no ``reference`` log is given. A run whose ramp vehicle never merged is an outcome,
not an undisturbed run: every metric that measures the merge (the six above, critical
distance, U_safe at the merge, PET) is NaN for it, and
:func:`compute_metrics` adds the merge's outcome (:mod:`hcomc.metrics.outcome`). Each
function's docstring gives the exact definition, units and edge cases.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from hcomc.metrics.fuel_distance import fuel
from hcomc.metrics.lsrv import low_speed_region_volume
from hcomc.metrics.merge_safety import u_safe_at_merge
from hcomc.metrics.outcome import OUTCOME_FIELDS, merge_outcome
from hcomc.metrics.paper import (
    average_acceleration,
    critical_distance,
    disturbance_metrics,
    integrated_disturbance,
    stabilisation_time,
    stabilisation_time_from_merge,
)
from hcomc.metrics.surrogate import (
    closing_metrics,
    collisions,
    key_collisions,
    max_drac,
    min_ttc,
    pet_at_merge,
)
from hcomc.metrics.window import MetricWindow, key_window
from hcomc.sim.log import SimulationLog

__all__ = ["METRICS", "OUTCOME_FIELDS", "MetricSpec", "compute_metrics"]


@dataclass(frozen=True)
class MetricSpec:
    """A registered metric.

    Parameters
    ----------
    name : str
        Registry key and results-table column.
    unit : str
        Unit of the value.
    better : {"larger", "smaller"}
        Which direction is better.
    func : callable
        ``func(log, window, **kwargs) -> float``; takes ``reference=`` if it compares with
        the undisturbed run.
    description : str
        One-line definition.
    """

    name: str
    unit: str
    better: Literal["larger", "smaller"]
    func: Callable[..., float]
    description: str

    @property
    def needs_reference(self) -> bool:
        """True if the metric compares with the undisturbed run."""
        return _takes_reference(self.func)


@functools.cache
def _takes_reference(func: Callable[..., float]) -> bool:
    return "reference" in inspect.signature(func).parameters


_SPECS = (
    MetricSpec(
        "critical_distance", "m", "larger", critical_distance,
        "min bumper gap of a key vehicle to its actual same-lane leader (any vehicle), merge "
        "to window end",
    ),
    MetricSpec(
        "u_safe_at_merge", "m/s²", "smaller", u_safe_at_merge,
        "Eq. 15 critical acceleration of VR's new lane-1 follower behind VR at the merge row",
    ),
    MetricSpec(
        "average_acceleration", "m/s²", "smaller", average_acceleration,
        "mean abs(a - a_undisturbed) over the key vehicles (VR from its merge on) and window",
    ),
    MetricSpec(
        "stabilisation_time", "s", "smaller", stabilisation_time,
        "VR's control-zone entry until all key vehicles stay within abs(a - a_u) < 0.05 m/s² "
        "and abs(v - v_u) < 0.5 m/s for the rest of the window (final settling; censored)",
    ),
    MetricSpec(
        "stabilisation_time_from_merge", "s", "smaller", stabilisation_time_from_merge,
        "variant: the same final settling from VR's merge, post-merge rows only; favours "
        "late merges",
    ),
    MetricSpec(
        "integrated_disturbance", "m", "smaller", integrated_disturbance,
        "Σ abs(v - v_undisturbed) dt over the key vehicles (VR from its merge on) and window",
    ),
    MetricSpec(
        "lsrv", "m²", "smaller", low_speed_region_volume,
        "Σ lanes 1, 2: each vehicle's max(0, v_u - v) dt against itself undisturbed, merge "
        "area, times the lane's mean undisturbed spacing",
    ),
    MetricSpec(
        "fuel", "L", "smaller", fuel,
        "Eq. 16 fuel of every vehicle over the distance it covers undisturbed in the window",
    ),
    MetricSpec(
        "min_ttc", "s", "larger", min_ttc,
        "min gap / closing speed of consecutive key vehicles in a lane, a lane-changing one "
        "in both lanes while its body overlaps both",
    ),
    MetricSpec(
        "max_drac", "m/s²", "smaller", max_drac,
        "max closing speed² / (2 gap) of consecutive key vehicles in a lane, a lane-changing "
        "one in both lanes while its body overlaps both",
    ),
    MetricSpec(
        "pet", "s", "larger", pet_at_merge,
        "post-encroachment time at VR's merge point: the first vehicle after VR to pass it in "
        "lane 1 (never one changing away from lane 1)",
    ),
    MetricSpec(
        "collisions", "count", "smaller", collisions,
        "COLLISION events in the window, all vehicles",
    ),
    MetricSpec(
        "key_collisions", "count", "smaller", key_collisions,
        "COLLISION events in the window involving a key vehicle",
    ),
)  # fmt: skip

METRICS: dict[str, MetricSpec] = {spec.name: spec for spec in _SPECS}
"""Registry of all metrics, keyed by results-table column name."""


def compute_metrics(
    log: SimulationLog,
    window: MetricWindow | None = None,
    *,
    reference: SimulationLog | None = None,
) -> dict[str, float | bool | str]:
    """Evaluate every metric of :data:`METRICS` on one run, and the merge's outcome.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow or None
        Evaluation window; default :func:`~hcomc.metrics.window.key_window`: the key
        vehicles the engine recorded when the first ramp vehicle entered the control zone
        (``log.meta["key_groups"]``), fixed before any control acts, so every controller
        is measured on the same vehicles.
    reference : SimulationLog or None
        The undisturbed run: the same scenario and seed simulated with
        ``Simulation(config, seed, counterfactual=True)``. Without it the metrics that
        compare with it (average acceleration, stabilisation times, integrated disturbance,
        LSRV, fuel) are NaN.

    Returns
    -------
    dict
        Registry key -> value (float), in registry order, then the
        :class:`~hcomc.metrics.outcome.MergeOutcome` fields :data:`OUTCOME_FIELDS`:
        ``merged`` (bool), ``merge_time`` [s], ``ramp_wait`` [s] (floats) and ``sequence``
        (str).
    """
    if window is None:
        window = key_window(log)
    # Metrics reading the same table (the deviation cells, the key-vehicle pairs) come from
    # one: the values their functions return.
    shared = {**disturbance_metrics(log, window, reference), **closing_metrics(log, window)}
    out: dict[str, float | bool | str] = {}
    for name, spec in METRICS.items():
        if spec.func in shared:
            out[name] = float(shared[spec.func])
            continue
        kwargs = {"reference": reference} if spec.needs_reference else {}
        out[name] = float(spec.func(log, window, **kwargs))
    out.update(merge_outcome(log, window).as_dict())
    return out
