r"""Fuel consumption over a common distance (paper "Fuel Cons."; smaller is better).

Summing Eq. 16 over a fixed time window would favour a controller that slows the traffic
down: slower vehicles cover less road in the window and burn less fuel in it. Every vehicle is
therefore measured over the **same distance in every run of a scenario and seed**, the distance
it covers in the undisturbed run (the ``reference`` log, see :mod:`hcomc.metrics.window`)
within the window:

* ``D_i = x^u_i(last) - x^u_i(first)``, its undisturbed displacement between its first and
  last rows on the road within ``[t_start, t_end]`` (from the window start or its insertion
  until the window end or its exit);
* a vehicle without an undisturbed trajectory in the window (VR, which the undisturbed run
  never releases; with a ramp flow every ramp vehicle) is measured over the distance from its
  first position in the window to the road end, ``road.length - x_i(first)``.

Its fuel is Eq. 16 (:func:`hcomc.equations.fuel.fuel_rate_scalar`) integrated over its factual
rows by the rectangle rule, row k standing for the interval to row k + 1 and its displacement
``x_{k+1} - x_k``, from its first row in the window until it has covered ``D_i`` (the last
interval counted by the fraction of its displacement still needed). A vehicle that has not
covered ``D_i`` by its last row (the window ends, or it left the road) completes the rest at
the cruise rate of its last speed ``v_e``, ``fdot(v_e, 0) (D_i - covered) / v_e`` with
``v_e`` at least :data:`CRUISE_MIN_SPEED` (as the controller completes a prediction's fuel to
a common distance, :mod:`hcomc.control.prediction.fuel`); one that is never on the road
in the factual window (its insertion blocked) drives all of ``D_i`` at the cruise rate of its
undisturbed first speed. At constant speed ``v`` every vehicle so uses ``fdot(v, 0) D / v``.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._typing import FloatArray
from hcomc.config.fuel import FUEL_DEFAULT, FuelParams
from hcomc.equations.fuel import FuelCoefficients
from hcomc.metrics.common_distance import Cells, fuel_to_distance, reference_distances
from hcomc.metrics.window import MetricWindow, check_reference, road_of, window_rows
from hcomc.sim.log import SimulationLog

__all__ = ["CRUISE_MIN_SPEED", "fuel", "fuel_per_vehicle"]

CRUISE_MIN_SPEED = 1.0
"""Lowest speed a missing distance is completed at [m/s] (a vehicle that ends standing still
would otherwise need infinite time); the floor of the controller's completion."""


def fuel(
    log: SimulationLog,
    window: MetricWindow,
    *,
    reference: SimulationLog | None = None,
    params: FuelParams = FUEL_DEFAULT,
) -> float:
    """Fuel of all vehicles, each over its common distance [L] (paper "Fuel Cons.").

    Definition: the sum over every vehicle of :func:`fuel_per_vehicle` (see the module
    docstring).

    Returns
    -------
    float
        Fuel [L]. NaN without a reference, or if the run has a ramp vehicle that never
        merged (an outcome, see :func:`hcomc.metrics.outcome.merge_outcome`).
    """
    if reference is None:
        return math.nan
    check_reference(log, reference)
    if window.group and not window.merged:
        return math.nan
    return float(np.sum(fuel_per_vehicle(log, window, reference, params)) / 1000.0)


def fuel_per_vehicle(
    log: SimulationLog,
    window: MetricWindow,
    reference: SimulationLog,
    params: FuelParams = FUEL_DEFAULT,
) -> FloatArray:
    """(N,) each vehicle's Eq. 16 fuel over its common distance [mL]; 0 for a vehicle on
    the road in neither run within the window."""
    check_reference(log, reference)
    rows = window_rows(log, window)
    distance, v_first = reference_distances(_cells(reference), rows.start, rows.stop)
    return fuel_to_distance(
        _cells(log), rows.start, rows.stop, distance, v_first, road_of(log).length, log.dt,
        CRUISE_MIN_SPEED, FuelCoefficients.of(params),
    )  # fmt: skip


def _cells(log: SimulationLog) -> Cells:
    """The cells of ``log`` that fuel needs."""
    cells = log.cells
    return Cells(cells["x"], cells["v"], cells["a"], cells["active"], log.slot, log.span)
