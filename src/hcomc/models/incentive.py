"""Re-exports :mod:`hcomc.equations.incentive` (paper Eq. 17) for one release: import from there."""

from hcomc.equations.incentive import mobil_incentive

__all__ = ["mobil_incentive"]
