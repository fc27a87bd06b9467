"""Re-exports :mod:`hcomc.equations.lane_change` (paper Eqs. 4-6) for one release: import from
there."""

from hcomc.equations.lane_change import (
    lateral_offset,
    lateral_state,
    quintic_coefficients,
    quintic_shape,
    quintic_shape_scalar,
)

__all__ = [
    "lateral_offset",
    "lateral_state",
    "quintic_coefficients",
    "quintic_shape",
    "quintic_shape_scalar",
]
