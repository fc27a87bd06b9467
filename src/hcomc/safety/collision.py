"""Re-exports :mod:`hcomc.equations.collision` (paper Eq. 7), with its compiled one-pair
kernels, for one release: import from there."""

from hcomc.equations.collision import (
    corners_into,
    point_in_quad,
    point_in_rectangle,
    quads_collide,
    rectangle_corners,
    rectangles_collide,
    segment_pair_intersects,
    segments_intersect,
    vehicle_pair_collides,
    vehicles_collide,
)

__all__ = [
    "corners_into",
    "point_in_quad",
    "point_in_rectangle",
    "quads_collide",
    "rectangle_corners",
    "rectangles_collide",
    "segment_pair_intersects",
    "segments_intersect",
    "vehicle_pair_collides",
    "vehicles_collide",
]
