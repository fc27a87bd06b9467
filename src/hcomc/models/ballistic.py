"""The ballistic integration step every simulator and prediction in hcomc takes.

One step of length ``dt`` [s] with a constant acceleration ``a`` [m/s^2], the update of SUMO's
ballistic scheme (Treiber & Kanagaraj, "Comparing numerical integration schemes for
time-continuous car-following models", Physica A 419, 2015): the vehicle travels
``v dt + a dt^2 / 2`` and ends at ``v + a dt``. A vehicle whose speed would turn negative within
the step stops exactly at v = 0 after ``v^2 / (2 |a|)``, and the acceleration it actually had
over the step is ``-v / dt``; vehicles never reverse. The engine's step, the controllers'
prediction, the lane-change game's forward simulation and the corridor engine all call
:func:`ballistic_step`, so that a plan is predicted with the motion that then executes it.
"""

from __future__ import annotations

from hcomc._jit import kernel


@kernel(inline="always")
def ballistic_step(v: float, a: float, dt: float) -> tuple[float, float, float]:
    """Distance travelled [m], end speed [m/s] and applied acceleration [m/s^2] of one step.

    v : speed at the start of the step [m/s], v >= 0.
    a : acceleration held over the step [m/s^2].
    dt : step length [s].
    """
    v1 = v + a * dt
    if v1 < 0.0:  # stops within the step and stays at v = 0
        return -(v * v) / (2.0 * a), 0.0, -v / dt
    return v * dt + 0.5 * a * dt * dt, v1, a
