"""The reward terms of one action period, from the log rows the period wrote (compiled:
they run for every episode at every step). Each calls the one home of its equation."""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.equations.car_following import follow_accel
from hcomc.equations.fuel import fuel_rate_scalar


@kernel
def fuel_over_rows(v: np.ndarray, a: np.ndarray, dt: float, coefs: np.ndarray) -> float:
    """Eq. 16: a vehicle's fuel over log rows with speeds ``v`` and accelerations ``a``
    [mL] (rows where it is absent, NaN, count 0; ``coefs`` as
    :meth:`hcomc.config.fuel.FuelParams.coefficients`)."""
    total = 0.0
    for k in range(v.size):
        rate = fuel_rate_scalar(
            float(v[k]), float(a[k]), coefs[0], coefs[1], coefs[2], coefs[3],
            coefs[4], coefs[5], coefs[6], coefs[7],
        )  # fmt: skip
        if not math.isnan(rate):
            total += rate
    return total * dt


@kernel
def gain_over_rows(
    v: np.ndarray, a: np.ndarray, ref_a: np.ndarray, dt: float, free_road: bool,
    p: np.ndarray, iidm: bool,
) -> float:  # fmt: skip
    """Eq. 17's ``a_new - a_ori`` of a vehicle integrated over log rows with speeds ``v``
    and accelerations ``a`` [m/s].

    ``a_ori`` is the undisturbed run's (``ref_a``, the same rows), or with ``free_road`` (a
    ramp vehicle, absent from the undisturbed run) the vehicle's model on a free road at its
    speed (``p`` = its v0, T, s0, a, b, delta, c). Rows where it is absent count 0.
    """
    total = 0.0
    for k in range(v.size):
        ak, vk = float(a[k]), float(v[k])
        if math.isnan(ak) or math.isnan(vk):
            continue
        if free_road:
            ori = follow_accel(math.inf, vk, 0.0, 0.0, p[0], p[1], p[2], p[3], p[4], p[5],
                               p[6], iidm)  # fmt: skip
        else:
            ori = float(ref_a[k])
            if math.isnan(ori):
                continue
        total += ak - ori
    return total * dt
