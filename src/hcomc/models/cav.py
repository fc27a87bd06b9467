"""Re-exports :mod:`hcomc.equations.cav` (paper Eq. 3) for one release: import from there."""

from hcomc.equations.cav import S_MIN_CAH, acc_accel, acc_acceleration, cah_accel, cah_acceleration

__all__ = ["S_MIN_CAH", "acc_accel", "acc_acceleration", "cah_accel", "cah_acceleration"]
