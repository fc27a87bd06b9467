"""The metric registry and :func:`compute_metrics`, the one call that evaluates a run.

* ``critical_distance`` [m, larger is better]: :func:`hcomc.metrics.paper.critical_distance`
* ``average_acceleration`` [m/s², smaller]: :func:`hcomc.metrics.paper.average_acceleration`
* ``stabilisation_time`` [s, smaller]: :func:`hcomc.metrics.paper.stabilisation_time`
* ``lsrv`` [m², smaller]: :func:`hcomc.metrics.speed_field.low_speed_region_volume`
* ``fuel`` [L, smaller]: :func:`hcomc.metrics.paper.fuel`
* ``min_ttc`` [s, larger]: :func:`hcomc.metrics.surrogate.min_ttc`
* ``max_drac`` [m/s², smaller]: :func:`hcomc.metrics.surrogate.max_drac`
* ``pet`` [s, larger]: :func:`hcomc.metrics.surrogate.pet_at_merge`
* ``collisions`` [count, smaller]: :func:`hcomc.metrics.surrogate.collisions`
* ``key_collisions`` [count, smaller]: :func:`hcomc.metrics.surrogate.key_collisions`

Average acceleration, stabilisation time and LSRV measure the merge's disturbance against
the undisturbed run (same scenario and seed, no ramp vehicle released); they are NaN when
no ``reference`` log is given. Each function's docstring gives the exact definition, units
and edge cases.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from hcomc.metrics.paper import (
    average_acceleration,
    critical_distance,
    disturbance_metrics,
    fuel,
    stabilisation_time,
)
from hcomc.metrics.speed_field import low_speed_region_volume
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

__all__ = ["METRICS", "MetricSpec", "compute_metrics"]


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
        "min bumper gap of consecutive same-lane key vehicles, merge to window end",
    ),
    MetricSpec(
        "average_acceleration", "m/s²", "smaller", average_acceleration,
        "mean abs(a - a_undisturbed) over the key vehicles (VR from its merge on) and window",
    ),
    MetricSpec(
        "stabilisation_time", "s", "smaller", stabilisation_time,
        "merge until all key vehicles hold abs(a - a_u) < 0.05 m/s² and abs(v - v_u) < 0.5 "
        "m/s for 2 s (censored at the window end)",
    ),
    MetricSpec(
        "lsrv", "m²", "smaller", low_speed_region_volume,
        "Σ lanes 1, 2 ∫∫ max(0, v_undisturbed - v) dx dt on 10 m x 0.5 s bins, control zone "
        "and downstream",
    ),
    MetricSpec("fuel", "L", "smaller", fuel, "Eq. 16 fuel of all vehicles over the window"),
    MetricSpec(
        "min_ttc", "s", "larger", min_ttc,
        "min gap / closing speed of consecutive same-lane key vehicles",
    ),
    MetricSpec(
        "max_drac", "m/s²", "smaller", max_drac,
        "max closing speed² / (2 gap) of consecutive same-lane key vehicles",
    ),
    MetricSpec(
        "pet", "s", "larger", pet_at_merge,
        "post-encroachment time of VR's new lane-1 follower at VR's merge point",
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
) -> dict[str, float]:
    """Evaluate every metric of :data:`METRICS` on one run.

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
        ``Simulation(config, seed, counterfactual=True)``. Without it the disturbance
        metrics (average acceleration, stabilisation time, LSRV) are NaN.

    Returns
    -------
    dict of str to float
        Registry key -> value, in registry order.
    """
    if window is None:
        window = key_window(log)
    # Metrics reading the same table (the deviation cells, the key-vehicle pairs) come from
    # one: the values their functions return.
    shared = {**disturbance_metrics(log, window, reference), **closing_metrics(log, window)}
    out: dict[str, float] = {}
    for name, spec in METRICS.items():
        if spec.func in shared:
            out[name] = float(shared[spec.func])
            continue
        kwargs = {"reference": reference} if spec.needs_reference else {}
        out[name] = float(spec.func(log, window, **kwargs))
    return out
