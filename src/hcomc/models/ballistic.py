"""Re-exports :mod:`hcomc.equations.integrate` (the ballistic step) for one release: import from
there."""

from hcomc.equations.integrate import ballistic_step

__all__ = ["ballistic_step"]
