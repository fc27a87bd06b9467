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

Its fuel is Eq. 16 (:func:`hcomc.models.fuel.fuel_rate_scalar`) integrated over its factual
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
from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.metrics.window import MetricWindow, check_reference, road_of, window_rows
from hcomc.models.fuel import FUEL_DEFAULT, FuelCoefficients, FuelParams, fuel_rate_scalar
from hcomc.sim.log import SimulationLog

__all__ = ["CRUISE_MIN_SPEED", "fuel", "fuel_per_vehicle"]

CRUISE_MIN_SPEED = 1.0
"""Lowest speed a missing distance is completed at [m/s] (a vehicle that ends standing still
would otherwise need infinite time); the floor of the controller's completion."""


class Cells(NamedTuple):
    """The stored cells of a log (:attr:`~hcomc.sim.log.SimulationLog.cells`, each (T, S))
    that fuel needs, and which vehicle a column holds when."""

    x: np.ndarray  # front-bumper position [m]
    v: np.ndarray  # speed [m/s]
    a: np.ndarray  # acceleration [m/s^2]
    active: np.ndarray  # bool: the vehicle is on the road
    slot: np.ndarray  # (N,) each vehicle's column (-1: none)
    span: np.ndarray  # (N, 2) the rows [first, end) its column holds it

    @classmethod
    def of(cls, log: SimulationLog) -> Cells:
        """The cells of ``log``."""
        cells = log.cells
        return cls(cells["x"], cells["v"], cells["a"], cells["active"], log.slot, log.span)


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
    distance, v_first = _reference_distances(Cells.of(reference), rows.start, rows.stop)
    return _fuel_to_distance(
        Cells.of(log), rows.start, rows.stop, distance, v_first, road_of(log).length, log.dt,
        CRUISE_MIN_SPEED, FuelCoefficients.of(params),
    )  # fmt: skip


@kernel
def _reference_distances(cells: Cells, r0: int, r1: int) -> tuple[FloatArray, FloatArray]:
    """(N,) each vehicle's displacement between its first and last active rows in
    ``[r0, r1)`` of the stored ``cells`` [m], and its speed in the first [m/s]; NaN for a
    vehicle not on the road in those rows."""
    x, v, _, active, slot, span = cells
    n = slot.size
    distance, v_first = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):
        s = slot[i]
        if s < 0:
            continue
        first, last = -1, -1
        for k in range(max(r0, span[i, 0]), min(r1, span[i, 1])):
            if active[k, s]:
                if first < 0:
                    first = k
                last = k
        if first >= 0:
            distance[i] = np.float64(x[last, s]) - np.float64(x[first, s])
            v_first[i] = np.float64(v[first, s])
    return distance, v_first


@kernel
def _cruise_to(rest: float, v_end: float, v_min: float, coefficients: FuelCoefficients) -> float:
    """Fuel [mL] to drive ``rest`` [m] at the cruise rate of ``max(v_end, v_min)``."""
    if not rest > 0.0:
        return 0.0
    speed = max(v_end, v_min)
    b0, b1, b2, b3, c0, c1, c2, positive_only = coefficients
    rate = fuel_rate_scalar(speed, 0.0, b0, b1, b2, b3, c0, c1, c2, positive_only)
    return rate * rest / speed


@kernel
def _fuel_to_distance(
    cells: Cells, r0: int, r1: int, distance: np.ndarray, v_first: np.ndarray,
    road_end: float, dt: float, v_min: float, coefficients: FuelCoefficients,
) -> FloatArray:  # fmt: skip
    """(N,) each vehicle's fuel over its common distance [mL] from the stored ``cells`` of
    rows ``[r0, r1)``: ``distance`` (N,) from :func:`_reference_distances`, NaN for a vehicle
    without an undisturbed trajectory (then to ``road_end`` [m]); ``v_first`` its undisturbed
    first speed, the cruise speed of a vehicle never on the road here; ``dt`` the rows'
    interval [s], ``v_min`` the lowest cruise speed [m/s]."""
    x, v, a, active, slot, span = cells
    b0, b1, b2, b3, c0, c1, c2, positive_only = coefficients
    n = slot.size
    out = np.zeros(n)
    for i in range(n):
        s = slot[i]
        lo, hi = (max(r0, span[i, 0]), min(r1, span[i, 1])) if s >= 0 else (0, 0)
        first = -1
        for k in range(lo, hi):
            if active[k, s]:
                first = k
                break
        if first < 0:  # not on the road in the window: its undisturbed distance at cruise
            if math.isfinite(distance[i]):
                out[i] = _cruise_to(distance[i], v_first[i], v_min, coefficients)
            continue
        x0 = np.float64(x[first, s])
        target = distance[i] if math.isfinite(distance[i]) else road_end - x0
        total, k = 0.0, first
        while True:
            covered = np.float64(x[k, s]) - x0
            if covered >= target:
                break
            if k + 1 >= hi or not active[k + 1, s]:  # last row: complete at cruise
                total += _cruise_to(target - covered, np.float64(v[k, s]), v_min, coefficients)
                break
            rate = fuel_rate_scalar(np.float64(v[k, s]), np.float64(a[k, s]), b0, b1, b2, b3,
                                    c0, c1, c2, positive_only)  # fmt: skip
            step = np.float64(x[k + 1, s]) - np.float64(x[k, s])
            if covered + step >= target:  # the distance ends within this interval
                total += rate * dt * (target - covered) / step
                break
            total += rate * dt
            k += 1
        out[i] = total
    return out
