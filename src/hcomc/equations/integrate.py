r"""The ballistic integration step every simulator and prediction in hcomc takes.

The paper integrates the car-following acceleration twice to obtain the longitudinal position
(Eq. 5 for HDVs, Eq. 6 for CAVs) without stating a numerical scheme. hcomc uses the update of
SUMO's ballistic scheme (Treiber & Kanagaraj 2015): over a step of length :math:`\Delta t` with
a constant acceleration :math:`a` the vehicle travels :math:`v\,\Delta t + a\,\Delta t^2/2` and
ends at :math:`v + a\,\Delta t`. The engine's step, the controllers' prediction, the lane-change
game's forward simulation all call :func:`ballistic_step`, so that a
plan is predicted with the motion that then executes it.

References
----------
.. [1] M. Treiber and V. Kanagaraj, "Comparing numerical integration schemes for
   time-continuous car-following models", Physica A 419, 183-195 (2015).
.. [2] Wang, Wang, Pan, Jiao and Claudel, "HCOMC: A Hierarchical Cooperative On-Ramp Merging
   Control Framework in Mixed Traffic Environment on Two-Lane Highways", arXiv:2507.11621,
   Section II-B, Eqs. (5)-(6).
"""

from __future__ import annotations

from hcomc._jit import kernel

__all__ = ["ballistic_step"]


@kernel(inline="always")
def ballistic_step(v: float, a: float, dt: float) -> tuple[float, float, float]:
    r"""One ballistic step of one vehicle: distance, end speed and applied acceleration.

    .. math::
       :label: ballistic-step

       \Delta x = v\,\Delta t + \tfrac12 a\,\Delta t^2, \qquad v' = v + a\,\Delta t,
       \qquad\text{if } v + a\,\Delta t \ge 0;

       \Delta x = -\frac{v^2}{2a}, \qquad v' = 0, \qquad a_\mathrm{applied} = -\frac{v}{\Delta t}
       \qquad\text{otherwise.}

    Parameters
    ----------
    v : float
        Speed at the start of the step [m/s], ``v >= 0``.
    a : float
        Acceleration held over the step [m/s^2].
    dt : float
        Step length [s], > 0.

    Returns
    -------
    dx : float
        Distance travelled in the step [m], >= 0.
    v1 : float
        Speed at the end of the step [m/s], >= 0.
    a_applied : float
        Acceleration the vehicle actually had over the step [m/s^2]: ``a``, or ``-v / dt``
        when it stops within the step.

    Notes
    -----
    The paper's Eqs. (5)-(6) integrate the acceleration twice and leave the scheme open. A
    vehicle whose speed would turn negative within the step stops exactly at :math:`v = 0`
    after :math:`v^2/(2|a|)` and stays there (vehicles never reverse), as in SUMO's ballistic
    update; the acceleration logged for that step is the mean one, :math:`-v/\Delta t`.

    References
    ----------
    .. [1] Treiber & Kanagaraj, Physica A 419, 183 (2015).
    .. [2] HCOMC paper (arXiv:2507.11621), Eqs. (5)-(6).

    Examples
    --------
    >>> ballistic_step(10.0, 1.0, 0.1)
    (1.005, 10.1, 1.0)
    >>> ballistic_step(0.5, -9.0, 0.1)
    (0.013888888888888888, 0.0, -5.0)
    """
    v1 = v + a * dt
    if v1 < 0.0:  # stops within the step and stays at v = 0
        return -(v * v) / (2.0 * a), 0.0, -v / dt
    return v * dt + 0.5 * a * dt * dt, v1, a
