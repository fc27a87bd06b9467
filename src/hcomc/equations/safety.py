r"""The safety index, paper Eq. (15) (critical acceleration), and the stopping distance.

The paper's safety index of a merge is "the critical acceleration, which is used as the
safety evaluation criterion at the end of on-ramp merging" and "represents the minimum
acceleration required for the rear vehicle to avoid rear-end collision when the front vehicle
suddenly decelerates in an emergency" (Section III-C-1):

.. math::
   U_\mathrm{safe} = a_\mathrm{cr} = \frac{v_r^2}{2\left(d_\mathrm{cri} - D - v_r T
       + \frac{v_f^2}{2 a_\mathrm{merg}}\right)}

where :math:`v_r` and :math:`v_f` are the speeds of the subject (rear) vehicle and its leading
vehicle, :math:`T` the delay time, :math:`a_\mathrm{merg}` the acceleration in emergency,
:math:`D` the minimum distance and :math:`d_\mathrm{cri}` the critical distance (the gap). The
public function is :func:`critical_acceleration`; its compiled kernel ``critical_accel`` is what
the HCOMC prediction and the environments call. Eq. (19) compares :math:`U_\mathrm{safe}` with a
threshold of 4 m/s^2 (:mod:`hcomc.equations.selection`).

:func:`stopping_distance` is the distance a vehicle needs to stop at a given deceleration
plus its jam gap, with which the engines decide whether a ramp vehicle can still stop before
the end of the acceleration lane.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section III-C-1, Eq. (15).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.equations._broadcast import broadcast_apply

__all__ = ["critical_acceleration", "stopping_distance"]


def critical_acceleration(
    d: ArrayLike,
    v_r: ArrayLike,
    v_f: ArrayLike,
    *,
    delay: ArrayLike,
    min_distance: float,
    emergency_decel: float,
) -> FloatArray:
    r"""Critical acceleration :math:`U_\mathrm{safe} = a_\mathrm{cr}`, paper Eq. (15) [m/s^2].

    .. math::
       :label: eq-15-critical-acceleration

       U_{safe} = a_{cr} = \frac{v_r^2}{2\left(d_{cri} - D - v_r T
                  + \frac{v_f^2}{2 a_{merg}}\right)}

    The deceleration the rear vehicle needs if its leader brakes in an emergency: the leader
    brakes from :math:`v_f` at :math:`a_\mathrm{merg}` to a stop after
    :math:`v_f^2/(2a_\mathrm{merg})`; the follower reacts after :math:`T`, travelling
    :math:`v_r T`, and then brakes at the constant :math:`a_\mathrm{cr}`, stopping :math:`D`
    behind it. Larger is less safe.

    Parameters
    ----------
    d : array_like
        Critical distance :math:`d_\mathrm{cri}`: the bumper-to-bumper gap [m].
    v_r : array_like
        Speed :math:`v_r` of the rear (subject) vehicle [m/s].
    v_f : array_like
        Speed :math:`v_f` of its leading vehicle [m/s].
    delay : array_like
        Delay time :math:`T` [s]: reaction plus brake build-up of the rear vehicle (0.5 s for
        a CAV, 1.0 s for an HDV follower by default).
    min_distance : float
        Minimum distance :math:`D` [m] left between the stopped vehicles.
    emergency_decel : float
        Emergency deceleration :math:`a_\mathrm{merg}` of the leader [m/s^2], positive.

    Returns
    -------
    numpy.ndarray
        :math:`a_\mathrm{cr}` [m/s^2], positive, ``float64``, broadcast shape of the inputs;
        ``+inf`` where no deceleration avoids the crash.

    Notes
    -----
    The paper does not say what the index is when the denominator is not positive (the
    follower would hit the stopped leader even braking at once with any deceleration): it is
    ``+inf`` here, infeasible, which every threshold rejects.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Eq. (15).

    Examples
    --------
    >>> round(float(critical_acceleration(50.0, 25.0, 25.0, delay=1.0, min_distance=2.0,
    ...                                   emergency_decel=7.5)), 2)
    4.83
    """
    return broadcast_apply(
        _critical_array, d, v_r, v_f, delay, float(min_distance), float(emergency_decel)
    )


@kernel
def critical_accel(
    d: float, v_r: float, v_f: float, delay: float, min_distance: float, emergency_decel: float
) -> float:
    """Eq. 15 for one follower-leader pair [m/s^2] (``inf`` when no deceleration avoids the
    crash): the compiled kernel of :func:`critical_acceleration` (same arguments,
    positional)."""
    denom = 2.0 * (d - min_distance - v_r * delay + v_f * v_f / (2.0 * emergency_decel))
    return v_r * v_r / denom if denom > 0.0 else np.inf


@kernel
def _critical_array(
    d: np.ndarray, v_r: np.ndarray, v_f: np.ndarray, delay: np.ndarray,
    min_distance: np.ndarray, emergency_decel: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(d.size)
    for i in range(d.size):
        out[i] = critical_accel(d[i], v_r[i], v_f[i], delay[i], min_distance[i], emergency_decel[i])
    return out


@kernel(inline="always")
def stopping_distance(v: float, decel: float, s0: float) -> float:
    r"""Distance a vehicle needs to stop at a constant deceleration, plus its jam gap [m].

    .. math::
       :label: stopping-distance

       s_\mathrm{stop} = \frac{v^2}{2 b} + s_0

    Not an equation of the paper, which leaves open when a ramp vehicle gives up waiting for
    a gap: a vehicle still on the acceleration lane that could no longer stop before its end
    (at MOBIL's safe deceleration :math:`b`, keeping the jam gap :math:`s_0`) is released
    from its plan.

    Parameters
    ----------
    v : float
        Speed [m/s].
    decel : float
        Deceleration :math:`b` [m/s^2], positive.
    s0 : float
        Jam gap :math:`s_0` [m] kept to the obstacle.

    Returns
    -------
    float
        Stopping distance [m].

    Notes
    -----
    The one stopping distance of hcomc: the engine's release of a ramp vehicle from its plan
    (``hcomc.sim.step.plans``), the robustness shield's and the planners' cap on the merge
    position all take it from here.
    """
    return v * v / (2.0 * decel) + s0
