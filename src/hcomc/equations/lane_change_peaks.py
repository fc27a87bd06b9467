r"""Peak lateral speed, acceleration and jerk of a quintic lane change, and the shortest
duration within given limits.

The paper sets the HDV lane-changing time to 4 s and lets HCOMC choose the CAV's (Section
II-B-2); it gives no comfort limits. The time-parametrised rest-to-rest change
``y(t) = y_0 + W p(t / T_lc)`` of the quintic
:math:`p(\xi) = 10\xi^3 - 15\xi^4 + 6\xi^5` (:mod:`hcomc.equations.lane_change`, Eq. 4) reaches
its extrema at fixed points of ξ, so each peak is W over a power of the duration times a
constant of the polynomial: these closed forms choose a lane-change duration without
sampling the path.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section II-B-2,
   Eqs. (4)-(6).
"""

from __future__ import annotations

import math
from math import sqrt

import numpy as np

from hcomc._typing import FloatArray

__all__ = [
    "min_duration",
    "peak_lateral_accel",
    "peak_lateral_jerk",
    "peak_lateral_speed",
]

PEAK_SPEED_FACTOR: float = 15.0 / 8.0
"""max p'(ξ) = 15/8 = 1.875, attained at ξ = 1/2."""

PEAK_ACCEL_FACTOR: float = 10.0 / sqrt(3.0)
"""max |p''(ξ)| = 10/√3 ≈ 5.7735, attained at ξ = (3 ∓ √3)/6."""

PEAK_JERK_FACTOR: float = 60.0
"""max |p'''(ξ)| = 60, attained at ξ = 0 and ξ = 1."""


def peak_lateral_speed(width: FloatArray | float, duration: FloatArray | float) -> FloatArray:
    r"""Peak lateral speed of a time-parametrised rest-to-rest quintic lane change.

    .. math:: \max_t |\dot y| = \frac{15}{8}\,\frac{W}{T_{lc}} = 1.875\,\frac{W}{T_{lc}}

    attained at mid-manoeuvre.

    Parameters
    ----------
    width : float or array_like
        Lateral displacement W [m] (its magnitude is used).
    duration : float or array_like
        Lane-change duration T_lc [s].

    Returns
    -------
    numpy.ndarray
        Peak lateral speed [m/s].

    Examples
    --------
    >>> round(float(peak_lateral_speed(3.75, 4.0)), 4)
    1.7578
    """
    return np.asarray(PEAK_SPEED_FACTOR * np.abs(width) / duration, dtype=np.float64)


def peak_lateral_accel(width: FloatArray | float, duration: FloatArray | float) -> FloatArray:
    r"""Peak lateral acceleration of a time-parametrised rest-to-rest quintic lane change.

    .. math:: \max_t |\ddot y| = \frac{10}{\sqrt 3}\,\frac{W}{T_{lc}^2}
              \approx 5.7735\,\frac{W}{T_{lc}^2}

    attained at :math:`\xi = (3 \mp \sqrt 3)/6`.

    Parameters
    ----------
    width : float or array_like
        Lateral displacement W [m] (its magnitude is used).
    duration : float or array_like
        Lane-change duration T_lc [s].

    Returns
    -------
    numpy.ndarray
        Peak lateral acceleration [m/s^2].

    Examples
    --------
    >>> round(float(peak_lateral_accel(3.75, 4.0)), 4)
    1.3532
    """
    duration = np.asarray(duration, dtype=np.float64)
    return np.asarray(PEAK_ACCEL_FACTOR * np.abs(width) / (duration * duration), dtype=np.float64)


def peak_lateral_jerk(width: FloatArray | float, duration: FloatArray | float) -> FloatArray:
    r"""Peak lateral jerk of a time-parametrised rest-to-rest quintic lane change.

    .. math:: \max_t |\dddot y| = 60\,\frac{W}{T_{lc}^3}

    attained at the start and end of the manoeuvre.

    Parameters
    ----------
    width : float or array_like
        Lateral displacement W [m] (its magnitude is used).
    duration : float or array_like
        Lane-change duration T_lc [s].

    Returns
    -------
    numpy.ndarray
        Peak lateral jerk [m/s^3].

    Examples
    --------
    >>> round(float(peak_lateral_jerk(3.75, 4.0)), 4)
    3.5156
    """
    duration = np.asarray(duration, dtype=np.float64)
    peak = PEAK_JERK_FACTOR * np.abs(width) / (duration * duration * duration)
    return np.asarray(peak, dtype=np.float64)


def min_duration(
    width: FloatArray | float, a_max: FloatArray | float, j_max: FloatArray | float
) -> FloatArray:
    r"""Shortest lane-change duration meeting lateral acceleration and jerk limits.

    .. math::
       T_\mathrm{min} = \max\left(\sqrt{\frac{10}{\sqrt 3}\frac{W}{a_{y,\max}}},\;
                        \left(\frac{60\,W}{j_{y,\max}}\right)^{1/3}\right)

    the inverse of :func:`peak_lateral_accel` and :func:`peak_lateral_jerk`.

    Parameters
    ----------
    width : float or array_like
        Lateral displacement W [m] (its magnitude is used).
    a_max : float or array_like
        Admissible peak lateral acceleration [m/s^2].
    j_max : float or array_like
        Admissible peak lateral jerk [m/s^3].

    Returns
    -------
    numpy.ndarray
        Minimum duration [s].

    Examples
    --------
    With W = 3.75 m, 2 m/s^2 and 5 m/s^3 the jerk limit governs: (45)^(1/3) = 3.557 s
    (the acceleration limit alone gives 3.290 s).

    >>> round(float(min_duration(3.75, 2.0, 5.0)), 3)
    3.557
    """
    w = np.abs(np.asarray(width, dtype=np.float64))
    t_acc = np.sqrt(PEAK_ACCEL_FACTOR * w / a_max)
    # the C library's cube root (numpy's is chosen by the CPU and may differ in the last bit)
    t_jerk = np.vectorize(math.cbrt, otypes=[np.float64])(PEAK_JERK_FACTOR * w / j_max)
    return np.asarray(np.maximum(t_acc, t_jerk), dtype=np.float64)
