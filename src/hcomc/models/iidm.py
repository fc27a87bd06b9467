"""Re-exports :mod:`hcomc.equations.iidm` (the IIDM variant of paper Eq. 1) for one release: import
from there."""

from hcomc.equations.iidm import iidm_accel, iidm_accel_given, iidm_acceleration, iidm_free_accel

__all__ = ["iidm_accel", "iidm_accel_given", "iidm_acceleration", "iidm_free_accel"]
