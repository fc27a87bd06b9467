"""Re-exports :mod:`hcomc.equations.transition` (paper Eq. 14) for one release: import from
there."""

from hcomc.equations.transition import (
    DEFAULT_TOLERANCE,
    blend,
    blend_acceleration,
    transition_gamma,
    transition_parameters,
    transition_psi,
    transition_weight,
)

__all__ = [
    "DEFAULT_TOLERANCE",
    "blend",
    "blend_acceleration",
    "transition_gamma",
    "transition_parameters",
    "transition_psi",
    "transition_weight",
]
