"""U_fuel (paper Eq. 16) over a common distance, per predicted trajectory, compiled.

Each vehicle's fuel over the prediction window is completed to the distance it covers in the
no-merge counterfactual at its end speed's cruise rate; the rates are
:func:`hcomc.models.fuel.fuel_rate_scalar`, their one home, summed in numpy's pairwise order
so that the values equal the array forms they replaced bit for bit. Used for whole
populations (:meth:`hcomc.control.hcomc.problem.MergeProblem.evaluate`) and for the single
rows of simulated annealing alike.
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.models.fuel import fuel_rate_scalar


@kernel
def _block_sum(a: FloatArray, lo: int, n: int) -> float:
    """numpy's pairwise sum of ``a[lo:lo + n]`` for n <= 128: in order below 8 values, else
    eight partial sums combined as a tree, then the remainder in order."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i, m = 8, n - n % 8
    while i < m:
        j = lo + i
        r0, r1, r2, r3 = r0 + a[j], r1 + a[j + 1], r2 + a[j + 2], r3 + a[j + 3]
        r4, r5, r6, r7 = r4 + a[j + 4], r5 + a[j + 5], r6 + a[j + 6], r7 + a[j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@kernel
def _pairwise_sum(a: FloatArray, n: int) -> float:
    """Sum of ``a[:n]`` in numpy's pairwise order, so that it equals ``ndarray.sum`` bit for
    bit: blocks of up to 128 values (:func:`_block_sum`), longer runs split in two at half
    the length rounded down to a multiple of 8 and the halves added. The split is walked with
    an explicit stack (numba cannot cache a recursive function)."""
    if n <= 128:
        return _block_sum(a, 0, n)
    node_lo = np.empty(64, dtype=np.int64)  # pending nodes: start, length, stage
    node_n = np.empty(64, dtype=np.int64)
    stage = np.empty(64, dtype=np.int64)
    sums = np.empty(64)  # finished nodes' sums, in order
    node_lo[0], node_n[0], stage[0] = 0, n, 0
    top, done = 0, 0
    while top >= 0:
        lo, m = node_lo[top], node_n[top]
        if m <= 128:
            sums[done] = _block_sum(a, lo, m)
            done += 1
            top -= 1
            continue
        half = m // 2
        half -= half % 8
        if stage[top] == 2:  # both halves summed
            sums[done - 2] = sums[done - 2] + sums[done - 1]
            done -= 1
            top -= 1
            continue
        child_lo, child_n = (lo, half) if stage[top] == 0 else (lo + half, m - half)
        stage[top] += 1
        top += 1
        node_lo[top], node_n[top], stage[top] = child_lo, child_n, 0
    return float(sums[0])


@kernel
def _fuel_to_distance_kernel(cf, roles, X, V, A, dt, b0, b1, b2, b3, c0, c1, c2, positive):
    """:meth:`MergeProblem._fuel_to_distance` (n, C): Eq. 16 rates of samples 1..K summed
    times ``dt``, plus the cruise rate at ``max(v_K, 1)`` over the distance still missing."""
    C, K1 = X.shape[0], X.shape[1]
    out = np.empty((roles.size, C))
    rate = np.empty(K1 - 1)
    for i in range(roles.size):
        r = roles[i]
        distance = cf[0, K1 - 1, r] - cf[0, 0, r]
        for c in range(C):
            for k in range(1, K1):
                rate[k - 1] = fuel_rate_scalar(
                    V[c, k, r], A[c, k, r], b0, b1, b2, b3, c0, c1, c2, positive
                )
            v_end = max(V[c, K1 - 1, r], 1.0)
            cruise = fuel_rate_scalar(v_end, 0.0, b0, b1, b2, b3, c0, c1, c2, positive)
            rest = distance - (X[c, K1 - 1, r] - X[c, 0, r])
            out[i, c] = _pairwise_sum(rate, K1 - 1) * dt + cruise * rest / v_end
    return out


@kernel
def common_distance_fuel(
    cf: np.ndarray,
    roles: np.ndarray,
    X: np.ndarray,
    V: np.ndarray,
    A: np.ndarray,
    dt: float,
    cf_fuel: float,
    coefficients: np.ndarray,
) -> np.ndarray:
    """U_fuel [L] of each trajectory (C,), Eq. 16 over a common distance: VR's fuel
    (``roles`` ``[VR]``), or VR's plus the cooperating vehicle's minus its counterfactual fuel
    ``cf_fuel`` [mL] (``roles`` ``[VR, VMC]``). Arguments as :func:`_fuel_to_distance_kernel`,
    with :meth:`~hcomc.models.fuel.FuelParams.coefficients` as an array."""
    b0, b1, b2, b3 = coefficients[0], coefficients[1], coefficients[2], coefficients[3]
    c0, c1, c2, positive = coefficients[4], coefficients[5], coefficients[6], coefficients[7]
    fuel = _fuel_to_distance_kernel(cf, roles, X, V, A, dt, b0, b1, b2, b3, c0, c1, c2, positive)
    out = np.empty(fuel.shape[1])
    for c in range(out.size):
        total = fuel[0, c]
        if roles.size > 1:
            total = total + fuel[1, c] - cf_fuel
        out[c] = total / 1000.0
    return out
