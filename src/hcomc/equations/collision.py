r"""Collision detection between vehicles modelled as oriented rectangles, paper Eq. (7).

The paper's collision detection model (Section II-C) tests whether two "potential collision
boundaries" :math:`P_1P_2` and :math:`Q_1Q_2` of the rectangular vehicle models intersect, in
two steps: a quick rejection test, which excludes segments that cannot intersect, and the
straddle test of Eq. (7): :math:`P_1`, :math:`P_2` lie on opposite sides of the line
:math:`Q_1Q_2` and :math:`Q_1`, :math:`Q_2` on opposite sides of the line :math:`P_1P_2`,

.. math::
   (P_1Q_1 \times Q_1Q_2) \cdot (P_2Q_1 \times Q_1Q_2) < 0, \qquad
   (Q_1P_1 \times P_1P_2) \cdot (Q_2P_1 \times P_1P_2) < 0 .

The paper leaves the rectangles' geometry and the boundary cases open; the choices made here
follow.

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

Each test has one implementation, a scalar numba-compiled kernel (``segment_pair_intersects``,
``point_in_quad``, ``quads_collide``, ``corners_into``, ``vehicle_pair_collides``, exported
here from the private module ``_collision_kernels``) that the simulation step and the HCOMC
prediction call per pair; the public functions here apply them over arbitrary leading batch
shapes with NumPy broadcasting.
``vehicle_pair_collides`` also has a bounding-circle prefilter, so in large, mostly sparse
batches only nearby pairs pay for the exact test.

Floating-point note: the predicates are evaluated in float64 without exact arithmetic.
They are exact when the corner coordinates and their differences and cross products are
exactly representable, e.g. small integer or half-integer coordinates. Otherwise a pair that
is within a few ulps of touching may be classified either way.

References
----------
.. [1] Wang, Wang, Pan, Jiao and Claudel, HCOMC, arXiv:2507.11621, Section II-C, Eq. (7).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray
from hcomc.equations._collision_kernels import (
    corners_into,
    point_in_quad,
    quads_collide,
    segment_pair_intersects,
    vehicle_pair_collides,
)

__all__ = [
    "point_in_rectangle",
    "rectangle_corners",
    "rectangles_collide",
    "segments_intersect",
    "vehicles_collide",
]


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
def _corners_array(
    x: np.ndarray, y: np.ndarray, h: np.ndarray, length: np.ndarray, width: np.ndarray
) -> np.ndarray:
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

    Notes
    -----
    The paper writes Eq. (7) with strict inequalities, which miss segments that touch or lie
    on one line; touching counts as a collision here (``<= 0``), and the quick rejection on
    closed bounding boxes, which the paper names without a formula, settles the colinear
    case. The sign of each product is taken from the signs of its factors, so that neither
    underflow nor overflow can change the verdict.

    References
    ----------
    .. [1] HCOMC paper (arXiv:2507.11621), Section II-C, Eq. (7).

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
def _segments_array(a1: np.ndarray, a2: np.ndarray, b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
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
def _points_array(p: np.ndarray, c: np.ndarray) -> np.ndarray:
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
def _quads_array(a: np.ndarray, b: np.ndarray) -> np.ndarray:
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
def _vehicles_array(
    xa: np.ndarray, ya: np.ndarray, ha: np.ndarray, la: np.ndarray, wa: np.ndarray,
    xb: np.ndarray, yb: np.ndarray, hb: np.ndarray, lb: np.ndarray, wb: np.ndarray,
) -> np.ndarray:  # fmt: skip
    out = np.empty(xa.size, dtype=np.bool_)
    for i in range(xa.size):
        out[i] = vehicle_pair_collides(
            xa[i], ya[i], ha[i], la[i], wa[i], xb[i], yb[i], hb[i], lb[i], wb[i]
        )
    return out
