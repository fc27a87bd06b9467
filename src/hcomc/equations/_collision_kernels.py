"""The collision tests of one pair, compiled: segments, quadrilaterals, vehicles (Eq. 7).

Each test of :mod:`hcomc.equations.collision` (which states the geometry and the
floating-point behaviour) has its one implementation here, a scalar numba-compiled kernel
that the simulation step and the HCOMC prediction call per pair (imported from
:mod:`hcomc.equations.collision`, which exports them) and that the array functions there
apply over batches: the straddle test of Eq. (7)
(:func:`segment_pair_intersects`), point in quadrilateral (:func:`point_in_quad`), the
rectangle test (:func:`quads_collide`), a vehicle's corners (:func:`corners_into`), and the
vehicle test with its bounding-circle prefilter (:func:`vehicle_pair_collides`).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel

__all__ = [
    "corners_into",
    "point_in_quad",
    "quads_collide",
    "segment_pair_intersects",
    "vehicle_pair_collides",
]

#: Relative slack of the bounding-circle prefilters of :func:`vehicle_pair_collides` [-]. Each
#: disc radius sum is widened by this fraction of the coordinate scale, so rounding can never make
#: the prefilter reject a pair that the exact test accepts (e.g. rectangles touching corner to
#: corner along their diagonals, where the centre distance equals the sum of half-diagonals).
_PREFILTER_REL_SLACK = 1e-9


@kernel
def _straddles(d1: float, d2: float) -> bool:
    """``d1 · d2 <= 0``: opposite signs, or either is zero (touching counts).

    Evaluated from the signs rather than the product, so tiny values cannot underflow to a
    spurious zero product and huge ones cannot overflow. NaN gives True here; the
    bounding-box test (always combined with this one) rejects NaN.
    """
    return not ((d1 > 0.0 and d2 > 0.0) or (d1 < 0.0 and d2 < 0.0))


@kernel
def segment_pair_intersects(
    p1x: float, p1y: float, p2x: float, p2y: float,
    q1x: float, q1y: float, q2x: float, q2y: float,
) -> bool:  # fmt: skip
    """Eq. (7) for one pair of closed segments P1P2, Q1Q2: the compiled kernel of
    :func:`~hcomc.equations.collision.segments_intersect` and every rectangle test."""
    # 1. Quick rejection: the segments' axis-aligned bounding boxes must overlap (closed).
    if max(min(p1x, p2x), min(q1x, q2x)) > min(max(p1x, p2x), max(q1x, q2x)):
        return False
    if max(min(p1y, p2y), min(q1y, q2y)) > min(max(p1y, p2y), max(q1y, q2y)):
        return False
    if math.isnan(p1x + p1y + p2x + p2y + q1x + q1y + q2x + q2y):
        return False
    # 2. Straddle test with "<= 0": P1, P2 on opposite sides of (or on) line Q1Q2 ...
    qx, qy = q2x - q1x, q2y - q1y
    d1 = (p1x - q1x) * qy - (p1y - q1y) * qx
    d2 = (p2x - q1x) * qy - (p2y - q1y) * qx
    # ... and Q1, Q2 on opposite sides of (or on) line P1P2.
    px, py = p2x - p1x, p2y - p1y
    d3 = (q1x - p1x) * py - (q1y - p1y) * px
    d4 = (q2x - p1x) * py - (q2y - p1y) * px
    return _straddles(d1, d2) and _straddles(d3, d4)


@kernel
def point_in_quad(px: float, py: float, cx: np.ndarray, cy: np.ndarray) -> bool:
    """Whether point P lies in (or on) the convex quadrilateral with corners ``cx, cy`` (4,)
    in boundary order, either orientation: the compiled kernel of
    :func:`~hcomc.equations.collision.point_in_rectangle`."""
    pos = neg = False
    for i in range(4):
        k = (i + 1) % 4
        side = (cx[k] - cx[i]) * (py - cy[i]) - (cy[k] - cy[i]) * (px - cx[i])
        pos = pos or side > 0.0
        neg = neg or side < 0.0
        if not (side >= 0.0 or side <= 0.0):  # NaN
            return False
    return not (pos and neg)


@kernel
def quads_collide(ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray) -> bool:
    """Whether two closed convex quadrilaterals (corners (4,) each, boundary order) share a
    point: an edge pair meets (Eq. 7) or one contains a corner of the other. The one
    implementation behind :func:`~hcomc.equations.collision.rectangles_collide`."""
    for i in range(4):
        i1 = (i + 1) % 4
        for j in range(4):
            j1 = (j + 1) % 4
            if segment_pair_intersects(ax[i], ay[i], ax[i1], ay[i1], bx[j], by[j], bx[j1], by[j1]):
                return True
    return point_in_quad(bx[0], by[0], ax, ay) or point_in_quad(ax[0], ay[0], bx, by)


@kernel
def corners_into(
    x: float, y: float, c: float, s: float, length: float, width: float,
    cx: np.ndarray, cy: np.ndarray,
) -> None:  # fmt: skip
    """Write the corners of one vehicle into ``cx, cy`` (4,), counter-clockwise from the
    front-right (``c, s`` = cos, sin of the heading): the compiled kernel of
    :func:`~hcomc.equations.collision.rectangle_corners`."""
    half_w = 0.5 * width
    ws = half_w * s
    wc = half_w * c
    rear_x = x - length * c  # rear-bumper centre
    rear_y = y - length * s
    cx[0], cy[0] = x + ws, y - wc  # front-right (u = 0, v = -W/2)
    cx[1], cy[1] = x - ws, y + wc  # front-left (u = 0, v = W/2)
    cx[2], cy[2] = rear_x - ws, rear_y + wc  # rear-left (u = -L, v = W/2)
    cx[3], cy[3] = rear_x + ws, rear_y - wc  # rear-right (u = -L, v = -W/2)


@kernel
def _within(dx: float, dy: float, reach: float, scale: float) -> bool:
    """Bounding-circle test ``dx² + dy² <= reach²`` with the relative slack; NaN gives False.

    ``reach`` is widened by ``_PREFILTER_REL_SLACK`` times (``reach`` + the largest absolute
    coordinate ``scale``), which dominates the rounding error of the corner coordinates.
    """
    reach = reach + _PREFILTER_REL_SLACK * (reach + scale)
    return dx * dx + dy * dy <= reach * reach


@kernel
def vehicle_pair_collides(
    xa: float, ya: float, ha: float, la: float, wa: float,
    xb: float, yb: float, hb: float, lb: float, wb: float,
) -> bool:  # fmt: skip
    """Whether vehicles A and B collide: the compiled kernel of
    :func:`~hcomc.equations.collision.vehicles_collide` (same arguments, one pair), prefilters
    included."""
    # Stage 1: discs about the front-bumper centres (no trigonometry).
    reach = math.sqrt(la * la + 0.25 * wa * wa) + math.sqrt(lb * lb + 0.25 * wb * wb)
    scale = max(abs(xa), abs(ya), abs(xb), abs(yb))
    if not _within(xa - xb, ya - yb, reach, scale):
        return False
    # Stage 2: discs about the rectangle centres, radius = half-diagonal.
    ca, sa, cb, sb = math.cos(ha), math.sin(ha), math.cos(hb), math.sin(hb)
    cxa, cya = xa - 0.5 * la * ca, ya - 0.5 * la * sa
    cxb, cyb = xb - 0.5 * lb * cb, yb - 0.5 * lb * sb
    reach = 0.5 * (math.sqrt(la * la + wa * wa) + math.sqrt(lb * lb + wb * wb))
    scale = max(abs(cxa), abs(cya), abs(cxb), abs(cyb))
    if not _within(cxa - cxb, cya - cyb, reach, scale):
        return False
    # Exact test (Eq. 7 plus containment).
    ax, ay, bx, by = np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    corners_into(xa, ya, ca, sa, la, wa, ax, ay)
    corners_into(xb, yb, cb, sb, lb, wb, bx, by)
    return quads_collide(ax, ay, bx, by)
