"""Re-exports :mod:`hcomc.equations.collision` (its compiled one-pair kernels of paper Eq. 7) for
one release: import from there."""

from hcomc.equations.collision import (
    corners_into,
    point_in_quad,
    quads_collide,
    segment_pair_intersects,
    vehicle_pair_collides,
)

__all__ = [
    "corners_into",
    "point_in_quad",
    "quads_collide",
    "segment_pair_intersects",
    "vehicle_pair_collides",
]
