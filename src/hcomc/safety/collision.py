"""Collision detection between vehicles modelled as oriented rectangles (paper Section II-C).

Each vehicle is a closed rectangle of length ``L`` and width ``W`` [m]. Its reference point
``(x, y)`` is the centre of the **front bumper**: ``x`` is the longitudinal position [m],
``y`` the lateral position of the vehicle's centre line [m], and ``heading`` [rad] is measured
from the +x axis (``heading = atan2(ẏ, ẋ)``). The rectangle's centre is
therefore at ``(x - L/2 cos h, y - L/2 sin h)``.

Two closed rectangles intersect if and only if

1. some edge of one intersects some edge of the other (16 edge pairs), each pair tested with
   the quick-rejection test on the segments' axis-aligned bounding boxes followed by the
   straddle test of Eq. (7), where a cross-product product ``<= 0`` counts (touching counts
   as a collision), or
2. one rectangle lies entirely inside the other, so that no edges meet. Then every corner of
   the inner rectangle is inside the outer one, so testing one corner each way suffices
   (point-in-polygon check).

Each test has one home, a scalar numba-compiled kernel (:func:`segment_pair_intersects`,
:func:`point_in_quad`, :func:`quads_collide`, :func:`vehicle_pair_collides`) that the
simulation step calls per pair; the array functions apply it over arbitrary leading batch
shapes with NumPy broadcasting. :func:`vehicle_pair_collides` also has a bounding-circle
prefilter, so in large, mostly sparse batches only nearby pairs pay for the exact test.

Floating-point note: the predicates are evaluated in float64 without exact arithmetic.
They are exact when the corner coordinates and their differences and cross products are
exactly representable, e.g. small integer or half-integer coordinates. Otherwise a pair that
is within a few ulps of touching may be classified either way.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray

__all__ = [
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

#: Relative slack of the bounding-circle prefilters of :func:`vehicles_collide` [-]. Each disc
#: radius sum is widened by this fraction of the coordinate scale, so rounding can never make
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
    """Eq. (7) for one pair of closed segments P1P2, Q1Q2: the one implementation behind
    :func:`segments_intersect` and every rectangle test."""
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
    in boundary order, either orientation: the one implementation behind
    :func:`point_in_rectangle`."""
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
    implementation behind :func:`rectangles_collide`."""
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
    front-right (``c, s`` = cos, sin of the heading): the one implementation behind
    :func:`rectangle_corners`."""
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
    """Whether vehicles A and B collide: the one implementation behind
    :func:`vehicles_collide` (same arguments, one pair), prefilters included."""
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


def _as_points(a: ArrayLike, name: str, trailing: tuple[int, ...]) -> FloatArray:
    """Convert to float64 and check the trailing shape (``(2,)`` or ``(4, 2)``)."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.shape[max(arr.ndim - len(trailing), 0) :] != trailing:
        raise ValueError(
            f"{name} must have shape (..., {', '.join(map(str, trailing))}), got {arr.shape}"
        )
    return arr


def rectangle_corners(
    x: ArrayLike,
    y: ArrayLike,
    heading: ArrayLike,
    length: ArrayLike,
    width: ArrayLike,
) -> FloatArray:
    r"""Corners of vehicle rectangles, counter-clockwise (paper Section II-C).

    With the reference point at the front-bumper centre, in the vehicle frame (``u`` forward,
    ``v`` to the left) the corners are front-right ``(0, -W/2)``, front-left ``(0, W/2)``,
    rear-left ``(-L, W/2)`` and rear-right ``(-L, -W/2)``. They are mapped to the road frame by

    .. math::

        X = x + u \cos h - v \sin h, \qquad Y = y + u \sin h + v \cos h .

    Parameters
    ----------
    x : array_like
        Longitudinal position of the front-bumper centre [m].
    y : array_like
        Lateral position of the vehicle's centre line [m].
    heading : array_like
        Heading ``h`` measured counter-clockwise from the +x axis [rad].
    length : array_like
        Vehicle length ``L`` [m], > 0.
    width : array_like
        Vehicle width ``W`` [m], > 0.

    All inputs are broadcast together to a batch shape ``S``.

    Returns
    -------
    FloatArray
        Corner coordinates [m], shape ``S + (4, 2)``, in counter-clockwise order
        (front-right, front-left, rear-left, rear-right); the last axis is ``(x, y)``.

    Examples
    --------
    >>> rectangle_corners(10.0, 0.0, 0.0, 5.0, 2.0).tolist()
    [[10.0, -1.0], [10.0, 1.0], [5.0, 1.0], [5.0, -1.0]]
    """
    xb, yb, hb, lb, wb = (
        np.ascontiguousarray(a).reshape(-1)
        for a in np.broadcast_arrays(
            *(np.asarray(a, dtype=np.float64) for a in (x, y, heading, length, width))
        )
    )
    shape = np.broadcast_shapes(*(np.shape(a) for a in (x, y, heading, length, width)))
    return _corners_array(xb, yb, hb, lb, wb).reshape((*shape, 4, 2))


@kernel
def _corners_array(x, y, h, length, width):
    out = np.empty((x.size, 4, 2))
    cx, cy = np.empty(4), np.empty(4)
    for i in range(x.size):
        corners_into(x[i], y[i], math.cos(h[i]), math.sin(h[i]), length[i], width[i], cx, cy)
        out[i, :, 0], out[i, :, 1] = cx, cy
    return out


def segments_intersect(p1: ArrayLike, p2: ArrayLike, q1: ArrayLike, q2: ArrayLike) -> BoolArray:
    r"""Whether closed segments ``P1P2`` and ``Q1Q2`` intersect (paper Eq. 7).

    Two steps:

    1. **Quick rejection.** If the axis-aligned bounding boxes of the segments do not overlap
       (closed boxes, so touching boxes overlap), the segments cannot intersect.
    2. **Straddle test** (Eq. 7 with ``<=``, so touching counts):

       .. math::

           \big((P_1 - Q_1) \times (Q_2 - Q_1)\big)\,\big((P_2 - Q_1) \times (Q_2 - Q_1)\big)
           \le 0 \;\wedge\;
           \big((Q_1 - P_1) \times (P_2 - P_1)\big)\,\big((Q_2 - P_1) \times (P_2 - P_1)\big)
           \le 0 .

    For colinear segments all four cross products vanish and the straddle test always
    passes; the bounding-box test then decides correctly, because two segments on one line
    overlap if and only if their bounding boxes do. T-junctions and shared endpoints count as
    intersections.

    Parameters
    ----------
    p1, p2 : array_like
        End points of the first segment [m], shape ``(..., 2)``.
    q1, q2 : array_like
        End points of the second segment [m], shape ``(..., 2)``.

    The leading shapes are broadcast together.

    Returns
    -------
    BoolArray
        Shape: the broadcast leading shape. True where the closed segments share a point.
        NaN coordinates give False.

    Examples
    --------
    >>> bool(segments_intersect([0, 0], [2, 2], [0, 2], [2, 0]))
    True
    >>> bool(segments_intersect([0, 0], [1, 0], [2, 0], [3, 0]))  # colinear, disjoint
    False
    """
    pts = [
        _as_points(p, name, (2,)) for p, name in ((p1, "p1"), (p2, "p2"), (q1, "q1"), (q2, "q2"))
    ]
    shape = np.broadcast_shapes(*(p.shape[:-1] for p in pts))
    flat = [np.broadcast_to(p, (*shape, 2)).reshape(-1, 2) for p in pts]
    return _segments_array(*flat).reshape(shape)


@kernel
def _segments_array(a1, a2, b1, b2):
    out = np.empty(a1.shape[0], dtype=np.bool_)
    for i in range(a1.shape[0]):
        out[i] = segment_pair_intersects(
            a1[i, 0], a1[i, 1], a2[i, 0], a2[i, 1], b1[i, 0], b1[i, 1], b2[i, 0], b2[i, 1]
        )
    return out


def point_in_rectangle(points: ArrayLike, corners: ArrayLike) -> BoolArray:
    r"""Whether points lie inside or on the boundary of convex quadrilaterals.

    A point ``P`` is in the closed convex polygon with corners ``C_0 … C_3`` if and only if
    the cross products :math:`(C_{i+1} - C_i) \times (P - C_i)` are all ``>= 0``
    (counter-clockwise corners) or all ``<= 0`` (clockwise corners), so either orientation
    is accepted.

    Parameters
    ----------
    points : array_like
        Points [m], shape ``(..., 2)``.
    corners : array_like
        Corners of convex quadrilaterals in boundary order [m], shape ``(..., 4, 2)``, e.g.
        from :func:`rectangle_corners`.

    The leading shapes are broadcast together.

    Returns
    -------
    BoolArray
        Shape: the broadcast leading shape. True where the point is inside or on the boundary.

    Examples
    --------
    >>> sq = [[0, 0], [1, 0], [1, 1], [0, 1]]
    >>> point_in_rectangle([[0.5, 0.5], [1.0, 0.3], [1.5, 0.5]], sq).tolist()
    [True, True, False]
    """
    pts = _as_points(points, "points", (2,))
    cor = _as_points(corners, "corners", (4, 2))
    shape = np.broadcast_shapes(pts.shape[:-1], cor.shape[:-2])
    flat_p = np.broadcast_to(pts, (*shape, 2)).reshape(-1, 2)
    flat_c = np.broadcast_to(cor, (*shape, 4, 2)).reshape(-1, 4, 2)
    return _points_array(flat_p, flat_c).reshape(shape)


@kernel
def _points_array(p, c):
    out = np.empty(p.shape[0], dtype=np.bool_)
    for i in range(p.shape[0]):
        out[i] = point_in_quad(p[i, 0], p[i, 1], c[i, :, 0].copy(), c[i, :, 1].copy())
    return out


def rectangles_collide(corners_a: ArrayLike, corners_b: ArrayLike) -> BoolArray:
    """Whether closed rectangles (convex quadrilaterals) intersect (paper Section II-C, Eq. 7).

    The rectangles collide if any of the 4 × 4 edge pairs intersects (quick rejection plus
    straddle test, :func:`segments_intersect`, Eq. 7) **or** one rectangle contains the
    other. If no edges meet, the rectangles are either disjoint or nested, and then every
    corner of the inner one is inside the outer one, so one corner is tested each way with
    :func:`point_in_rectangle`. Touching (a shared boundary point) counts as a collision.

    Parameters
    ----------
    corners_a, corners_b : array_like
        Corners [m], shape ``(..., 4, 2)``, in boundary order (either orientation), e.g. from
        :func:`rectangle_corners`. The leading shapes are broadcast together.

    Returns
    -------
    BoolArray
        Shape: the broadcast leading shape. True where the rectangles share at least one point.

    See Also
    --------
    vehicles_collide : the same test from vehicle states, with a cheap prefilter.
    """
    a = _as_points(corners_a, "corners_a", (4, 2))
    b = _as_points(corners_b, "corners_b", (4, 2))
    shape = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    flat_a = np.broadcast_to(a, (*shape, 4, 2)).reshape(-1, 4, 2)
    flat_b = np.broadcast_to(b, (*shape, 4, 2)).reshape(-1, 4, 2)
    return _quads_array(flat_a, flat_b).reshape(shape)


@kernel
def _quads_array(a, b):
    out = np.empty(a.shape[0], dtype=np.bool_)
    for i in range(a.shape[0]):
        out[i] = quads_collide(
            a[i, :, 0].copy(), a[i, :, 1].copy(), b[i, :, 0].copy(), b[i, :, 1].copy()
        )
    return out


def vehicles_collide(
    xa: ArrayLike,
    ya: ArrayLike,
    ha: ArrayLike,
    la: ArrayLike,
    wa: ArrayLike,
    xb: ArrayLike,
    yb: ArrayLike,
    hb: ArrayLike,
    lb: ArrayLike,
    wb: ArrayLike,
) -> BoolArray:
    r"""Whether vehicles A and B collide (closed rectangles intersect; Section II-C, Eq. 7).

    This is :func:`rectangles_collide` applied to :func:`rectangle_corners` of both vehicles,
    behind a bounding-circle prefilter, so that in large, mostly sparse batches only nearby
    pairs pay for the exact test:

    1. Trigonometry-free stage: whatever the heading, a rectangle lies in the disc about its
       front-bumper centre with radius :math:`R = \sqrt{L^2 + W^2/4}`; pairs with
       :math:`\lVert (x_a, y_a) - (x_b, y_b) \rVert > R_a + R_b` cannot collide.
    2. On the survivors: each rectangle lies in the disc about its centre
       :math:`(x - \tfrac L2 \cos h,\; y - \tfrac L2 \sin h)` with radius equal to its
       half-diagonal :math:`r = \tfrac12\sqrt{L^2 + W^2}`; pairs whose centre distance exceeds
       :math:`r_a + r_b` cannot collide.

    The exact test runs only on the pairs that pass both stages (index subsets), and the
    results are scattered back. Both thresholds are widened by a small relative slack
    (``1e-9`` of the coordinate scale), so rounding can never make the prefilter reject a
    pair that the exact test accepts (e.g. rectangles touching corner to corner along their
    diagonals): the result equals
    ``rectangles_collide(rectangle_corners(A), rectangle_corners(B))`` for every pair.

    Parameters
    ----------
    xa, ya : array_like
        Front-bumper centre of vehicle A: longitudinal [m] and lateral [m] position.
    ha : array_like
        Heading of A from the +x axis [rad].
    la, wa : array_like
        Length and width of A [m].
    xb, yb, hb, lb, wb : array_like
        The same for vehicle B.

    All ten inputs are broadcast together to a batch shape ``S``.

    Returns
    -------
    BoolArray
        Shape ``S``. True where the two vehicles' rectangles share at least one point
        (touching counts).

    Examples
    --------
    Two 5 m × 1.8 m cars in the same lane, bumper gaps 0 and 1 cm:

    >>> vehicles_collide(10.0, 0.0, 0.0, 5.0, 1.8, [15.0, 15.01], 0.0, 0.0, 5.0, 1.8).tolist()
    [True, False]
    """
    args = (xa, ya, ha, la, wa, xb, yb, hb, lb, wb)
    shape = np.broadcast_shapes(*(np.shape(v) for v in args))
    flat = [
        np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=np.float64), shape)).reshape(-1)
        for v in args
    ]
    return _vehicles_array(*flat).reshape(shape)


@kernel
def _vehicles_array(xa, ya, ha, la, wa, xb, yb, hb, lb, wb):
    out = np.empty(xa.size, dtype=np.bool_)
    for i in range(xa.size):
        out[i] = vehicle_pair_collides(
            xa[i], ya[i], ha[i], la[i], wa[i], xb[i], yb[i], hb[i], lb[i], wb[i]
        )
    return out
