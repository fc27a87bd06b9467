"""Thresholds of the surrogate safety measures (time to collision, DRAC), shared by the
measures of a logged run (:mod:`hcomc.metrics.surrogate`) and those of a corridor run's merge
events (:mod:`hcomc.metrics.corridor.events`)."""

from __future__ import annotations

__all__ = ["CLOSING_SPEED"]

CLOSING_SPEED = 0.1
"""Minimum closing speed v_follower - v_leader for TTC and DRAC [m/s]: slower closing is
treated as not closing in (TTC infinite, DRAC 0)."""
