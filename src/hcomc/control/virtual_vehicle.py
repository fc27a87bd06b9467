"""Re-exports :mod:`hcomc.equations.virtual_vehicle` (the cubic virtual vehicles of paper
Eqs. 8-13) for one release: import from there. The states of a plan's virtual vehicles at a
time, within and after its horizon, are
:func:`hcomc.control.hierarchical.controller.virtual_states`."""

from hcomc.equations.virtual_vehicle import (
    cubic_coefficients,
    cubic_extremes,
    cubic_into,
    cubic_minima,
    cubic_point,
    cubic_state,
)

__all__ = [
    "cubic_coefficients",
    "cubic_extremes",
    "cubic_into",
    "cubic_minima",
    "cubic_point",
    "cubic_state",
]
