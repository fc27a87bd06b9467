"""Re-exports :mod:`hcomc.equations.idm` (paper Eq. 1) for one release: import from there."""

from hcomc.equations.idm import (
    S_MIN,
    desired_gap,
    desired_gap_scalar,
    equilibrium_gap,
    idm_accel,
    idm_accel_given,
    idm_acceleration,
    idm_free_power,
    power,
)

__all__ = [
    "S_MIN",
    "desired_gap",
    "desired_gap_scalar",
    "equilibrium_gap",
    "idm_accel",
    "idm_accel_given",
    "idm_acceleration",
    "idm_free_power",
    "power",
]
