"""Re-exports :mod:`hcomc.equations._broadcast` for one release: import from there."""

from hcomc.equations._broadcast import broadcast_apply

__all__ = ["broadcast_apply"]
