"""Re-exports :mod:`hcomc.equations.car_following` (paper Eqs. 1 and 3) for one release: import
from there."""

from hcomc.equations.car_following import (
    follow_accel,
    follow_accel_given,
    follow_acceleration,
    free_term,
)

__all__ = ["follow_accel", "follow_accel_given", "follow_acceleration", "free_term"]
