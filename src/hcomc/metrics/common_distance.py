"""Each vehicle's fuel over its common distance, from a log's stored cells (compiled): the
passes behind :func:`hcomc.metrics.fuel_distance.fuel`, whose module docstring defines the
distance and the fuel.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations.fuel import FuelCoefficients, fuel_rate_scalar

__all__ = ["Cells", "fuel_to_distance", "reference_distances"]


class Cells(NamedTuple):
    """The stored cells of a log (:attr:`~hcomc.sim.log.SimulationLog.cells`, each (T, S))
    that fuel needs, and which vehicle a column holds when."""

    x: np.ndarray  # front-bumper position [m]
    v: np.ndarray  # speed [m/s]
    a: np.ndarray  # acceleration [m/s^2]
    active: np.ndarray  # bool: the vehicle is on the road
    slot: np.ndarray  # (N,) each vehicle's column (-1: none)
    span: np.ndarray  # (N, 2) the rows [first, end) its column holds it


@kernel
def reference_distances(cells: Cells, r0: int, r1: int) -> tuple[FloatArray, FloatArray]:
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
def fuel_to_distance(
    cells: Cells, r0: int, r1: int, distance: np.ndarray, v_first: np.ndarray,
    road_end: float, dt: float, v_min: float, coefficients: FuelCoefficients,
) -> FloatArray:  # fmt: skip
    """(N,) each vehicle's fuel over its common distance [mL] from the stored ``cells`` of
    rows ``[r0, r1)``: ``distance`` (N,) from :func:`reference_distances`, NaN for a vehicle
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
