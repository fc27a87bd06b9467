"""U_fuel (paper Eq. 16) over a common distance, per predicted trajectory, compiled.

Each vehicle's fuel over the prediction window is completed to the distance it covers in the
no-merge counterfactual at its end speed's cruise rate; the rates are
:func:`hcomc.equations.fuel.fuel_rate_scalar`, their one home, summed in time order. Used for whole
populations (:meth:`hcomc.control.hierarchical.problem.MergeProblem.evaluate`) and for the
single rows of simulated annealing alike.
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc.equations.fuel import FuelCoefficients, fuel_rate_scalar


@kernel
def _fuel_to_distance_kernel(
    cf: np.ndarray, roles: np.ndarray, X: np.ndarray, V: np.ndarray, A: np.ndarray, dt: float,
    coefficients: FuelCoefficients,
) -> np.ndarray:  # fmt: skip
    """:meth:`MergeProblem._fuel_to_distance` (n, C): Eq. 16 rates of samples 1..K summed in
    time order, times ``dt``, plus the cruise rate at ``max(v_K, 1)`` over the distance still
    missing."""
    b0, b1, b2, b3, c0, c1, c2, positive = coefficients
    C, K1 = X.shape[0], X.shape[1]
    out = np.empty((roles.size, C))
    for i in range(roles.size):
        r = roles[i]
        distance = cf[0, K1 - 1, r] - cf[0, 0, r]
        for c in range(C):
            burnt = 0.0
            for k in range(1, K1):
                burnt += fuel_rate_scalar(
                    V[c, k, r], A[c, k, r], b0, b1, b2, b3, c0, c1, c2, positive
                )
            v_end = max(V[c, K1 - 1, r], 1.0)
            cruise = fuel_rate_scalar(v_end, 0.0, b0, b1, b2, b3, c0, c1, c2, positive)
            rest = distance - (X[c, K1 - 1, r] - X[c, 0, r])
            out[i, c] = burnt * dt + cruise * rest / v_end
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
    coefficients: FuelCoefficients,
) -> np.ndarray:
    """U_fuel [L] of each trajectory (C,), Eq. 16 over a common distance: VR's fuel
    (``roles`` ``[VR]``), or VR's plus the cooperating vehicle's minus its counterfactual fuel
    ``cf_fuel`` [mL] (``roles`` ``[VR, VMC]``). Arguments as :func:`_fuel_to_distance_kernel`.
    """
    fuel = _fuel_to_distance_kernel(cf, roles, X, V, A, dt, coefficients)
    out = np.empty(fuel.shape[1])
    for c in range(out.size):
        total = fuel[0, c]
        if roles.size > 1:
            total = total + fuel[1, c] - cf_fuel
        out[c] = total / 1000.0
    return out
