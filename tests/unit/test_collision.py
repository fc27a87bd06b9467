"""Tests for hcomc.equations.collision (paper Section II-C, Eq. 7).

The ground truth is shapely (GEOS), whose ``intersects`` predicate treats polygons as closed
sets, so touching counts, as in our convention. shapely is a test-only dependency.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon

from hcomc._typing import BoolArray, FloatArray
from hcomc.equations.collision import (
    point_in_rectangle,
    rectangle_corners,
    rectangles_collide,
    segments_intersect,
    vehicles_collide,
)
from hcomc.safety import collision

CAR_L = 5.0  # [m]
CAR_W = 1.8  # [m]
LANE = 3.75  # [m]


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _shapely_collide(ca: FloatArray, cb: FloatArray) -> BoolArray:
    """Ground truth: closed-polygon intersection by shapely, vectorised over pairs."""
    return np.asarray(shapely.intersects(shapely.polygons(ca), shapely.polygons(cb)))


def _rect_from_edges(p0: FloatArray, u: FloatArray, w: FloatArray) -> FloatArray:
    """Rectangle corners ``p0, p0+u, p0+u+w, p0+w`` (orientation = sign of u × w)."""
    return np.stack([p0, p0 + u, p0 + u + w, p0 + w], axis=-2)


def _random_int_dirs(rng: np.random.Generator, n: int) -> FloatArray:
    """Random non-zero integer direction vectors with components in [-3, 3]."""
    d = rng.integers(-3, 4, size=(n, 2))
    zero = ~d.any(axis=1)
    d[zero] = (1, 0)
    return d.astype(np.float64)


def _integer_rects(rng: np.random.Generator, n: int, span: int) -> FloatArray:
    """Rotated rectangles with exact integer corners (edges k1*(a, b) and k2*(-b, a))."""
    e = _random_int_dirs(rng, n)
    u = e * rng.integers(1, 4, size=(n, 1))
    w = np.stack([-e[:, 1], e[:, 0]], axis=1) * rng.integers(1, 4, size=(n, 1))
    p0 = rng.integers(-span, span + 1, size=(n, 2)).astype(np.float64)
    return _rect_from_edges(p0, u, w)


def _shuffle_exact(
    rng: np.random.Generator, ca: FloatArray, cb: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Exact symmetries: common 90-degree rotation, corner roll, orientation flip, swap A/B."""
    n = ca.shape[0]
    k = rng.integers(0, 4, size=n)
    for _ in range(3):  # rotate by 90 degrees k times: (x, y) -> (-y, x), exact
        sel = k > 0
        ca[sel] = np.stack([-ca[sel, :, 1], ca[sel, :, 0]], axis=-1)
        cb[sel] = np.stack([-cb[sel, :, 1], cb[sel, :, 0]], axis=-1)
        k = k - 1
    rows = np.arange(n)[:, None]
    ca = ca[rows, (np.arange(4) + rng.integers(0, 4, size=(n, 1))) % 4]
    cb = cb[rows, (np.arange(4) + rng.integers(0, 4, size=(n, 1))) % 4]
    flip = rng.random(n) < 0.5
    ca[flip] = ca[flip, ::-1]
    swap = rng.random(n) < 0.5
    ca[swap], cb[swap] = cb[swap].copy(), ca[swap].copy()
    return ca, cb


def _near_random_pairs(rng: np.random.Generator, n: int) -> tuple[FloatArray, FloatArray]:
    """Random rotated rectangles near each other (mix of crossing and not)."""
    x = rng.uniform(-100, 100, n)
    y = rng.uniform(-100, 100, n)
    ca = rectangle_corners(
        x, y, rng.uniform(-np.pi, np.pi, n), rng.uniform(1, 8, n), rng.uniform(0.5, 3, n)
    )
    cb = rectangle_corners(
        x + rng.uniform(-6, 6, n),
        y + rng.uniform(-6, 6, n),
        rng.uniform(-np.pi, np.pi, n),
        rng.uniform(1, 8, n),
        rng.uniform(0.5, 3, n),
    )
    return ca, cb


def _axis_aligned_touching(
    rng: np.random.Generator, n: int, gap: float
) -> tuple[FloatArray, FloatArray]:
    """Axis-aligned half-integer rectangles edge to edge (shared edge part or corner)."""
    ax0 = rng.integers(-20, 20, n) / 2
    ay0 = rng.integers(-20, 20, n) / 2
    aw = rng.integers(1, 12, n) / 2
    ah = rng.integers(1, 12, n) / 2
    bw = rng.integers(1, 12, n) / 2
    bh = rng.integers(1, 12, n) / 2
    bx0 = ax0 + aw + gap
    # B's lower edge anywhere from "touching A's bottom corner" to "touching A's top corner".
    steps = rng.integers(0, (2 * (ah + bh)).astype(int) + 1)
    by0 = ay0 - bh + steps / 2

    def box(x0: FloatArray, y0: FloatArray, w: FloatArray, h: FloatArray) -> FloatArray:
        return np.stack(
            [
                np.stack(c, axis=-1)
                for c in ((x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h))
            ],
            axis=-2,
        )

    return _shuffle_exact(rng, box(ax0, ay0, aw, ah), box(bx0, by0, bw, bh))


def _vertex_touching(
    rng: np.random.Generator, n: int, separate: bool
) -> tuple[FloatArray, FloatArray]:
    """Rotated integer rectangles; a vertex of B lies on an edge (or vertex) of A, B outside A.

    A has edge 0 along k1*e with integer points p0 + j*e. B starts at such a point and has
    both edge vectors in the outer half-plane of that edge. If ``separate``, B is shifted by
    the outward normal, which leaves a gap of at least 1 m.
    """
    e = _random_int_dirs(rng, n)
    k1 = rng.integers(1, 4, size=(n, 1))
    ca = _rect_from_edges(
        rng.integers(-10, 11, size=(n, 2)).astype(np.float64),
        e * k1,
        np.stack([-e[:, 1], e[:, 0]], axis=1) * rng.integers(1, 4, size=(n, 1)),
    )
    normal = np.stack([e[:, 1], -e[:, 0]], axis=1)  # outward for a CCW rectangle
    touch = ca[:, 0] + e * rng.integers(0, k1[:, 0] + 1)[:, None]
    f = _random_int_dirs(rng, n)
    ub = f * rng.integers(1, 4, size=(n, 1))
    wb = np.stack([-f[:, 1], f[:, 0]], axis=1) * rng.integers(1, 4, size=(n, 1))
    ub *= np.where(np.sum(ub * normal, axis=1) < 0, -1.0, 1.0)[:, None]
    wb *= np.where(np.sum(wb * normal, axis=1) < 0, -1.0, 1.0)[:, None]
    cb = _rect_from_edges(touch + normal if separate else touch, ub, wb)
    return _shuffle_exact(rng, ca, cb)


def _contained_pairs(rng: np.random.Generator, n: int) -> tuple[FloatArray, FloatArray]:
    """A small rectangle strictly inside a large one (no edge intersections at all)."""
    la, wa = rng.uniform(6, 10, n), rng.uniform(3, 5, n)  # half-dims >= 1.5
    ha = rng.uniform(-np.pi, np.pi, n)
    cx, cy = rng.uniform(-50, 50, n), rng.uniform(-50, 50, n)
    ca = rectangle_corners(cx + 0.5 * la * np.cos(ha), cy + 0.5 * la * np.sin(ha), ha, la, wa)
    lb, wb = rng.uniform(0.2, 1.0, n), rng.uniform(0.1, 0.5, n)  # half-diagonal <= 0.56
    hb = rng.uniform(-np.pi, np.pi, n)
    r = rng.uniform(0, 0.9, n)
    phi = rng.uniform(-np.pi, np.pi, n)
    bx, by = cx + r * np.cos(phi), cy + r * np.sin(phi)  # centre offset <= 0.9
    cb = rectangle_corners(bx + 0.5 * lb * np.cos(hb), by + 0.5 * lb * np.sin(hb), hb, lb, wb)
    return ca, cb


def _far_pairs(rng: np.random.Generator, n: int) -> tuple[FloatArray, FloatArray]:
    """Clearly separated: centre distance > sum of half-diagonals + 1 m."""
    la, wa, lb, wb = (rng.uniform(1, 8, n) for _ in range(4))
    dist = 0.5 * (np.hypot(la, wa) + np.hypot(lb, wb)) + rng.uniform(1, 50, n)
    phi = rng.uniform(-np.pi, np.pi, n)
    ha = rng.uniform(-np.pi, np.pi, n)
    ca = rectangle_corners(0.5 * la * np.cos(ha), 0.5 * la * np.sin(ha), ha, la, wa)
    hb = rng.uniform(-np.pi, np.pi, n)
    cb = rectangle_corners(
        dist * np.cos(phi) + 0.5 * lb * np.cos(hb), dist * np.sin(phi) + 0.5 * lb * np.sin(hb),
        hb, lb, wb,
    )  # fmt: skip
    return ca, cb


def _near_tangent(ca: FloatArray, cb: FloatArray, eps: float = 1e-9) -> BoolArray:
    """Pairs whose answer changes when A is grown or shrunk by ``eps`` [m]."""
    pa, pb = shapely.polygons(ca), shapely.polygons(cb)
    grown = shapely.intersects(shapely.buffer(pa, eps), pb)
    shrunk = shapely.intersects(shapely.buffer(pa, -eps), pb)
    return np.asarray(grown != shrunk)


# --------------------------------------------------------------------------------------------
# agreement with shapely
# --------------------------------------------------------------------------------------------


def test_agrees_with_shapely_on_mixed_random_pairs() -> None:
    """>= 10,000 pairs: crossing, exact touching, containment, separated; exact agreement."""
    rng = np.random.default_rng(20250713)

    # Random float pairs near each other; drop the (rare) cases within 1e-9 m of touching.
    na, nb = _near_random_pairs(rng, 4000)
    keep = ~_near_tangent(na, nb)
    assert keep.sum() >= 3990
    na, nb = na[keep], nb[keep]

    # Exactly representable configurations (integer / half-integer coordinates).
    ia, ib = _shuffle_exact(rng, _integer_rects(rng, 3000, 4), _integer_rects(rng, 3000, 4))
    ta, tb = _axis_aligned_touching(rng, 600, gap=0.0)
    sa, sb = _axis_aligned_touching(rng, 300, gap=0.5)
    va, vb = _vertex_touching(rng, 600, separate=False)
    wa, wb = _vertex_touching(rng, 300, separate=True)
    ca, cb = _contained_pairs(rng, 500)
    fa, fb = _far_pairs(rng, 1000)

    a = np.concatenate([na, ia, ta, sa, va, wa, ca, cb, fa])
    b = np.concatenate([nb, ib, tb, sb, vb, wb, cb, ca, fb])
    assert a.shape[0] >= 10_000

    truth = _shapely_collide(a, b)
    ours = rectangles_collide(a, b)
    np.testing.assert_array_equal(ours, truth)

    # The mix really exercises every branch.
    nt = _shapely_collide(na, nb)
    assert 0.2 < nt.mean() < 0.8
    assert _shapely_collide(ta, tb).all()
    assert _shapely_collide(va, vb).all()
    assert not _shapely_collide(sa, sb).any()
    assert not _shapely_collide(wa, wb).any()
    assert _shapely_collide(ca, cb).all()
    assert not _shapely_collide(fa, fb).any()
    touching = shapely.area(shapely.intersection(shapely.polygons(ta), shapely.polygons(tb)))
    assert np.all(touching == 0.0)
    # Integer set contains many degenerate (zero-area) contacts.
    pi, pj = shapely.polygons(ia), shapely.polygons(ib)
    degenerate = shapely.intersects(pi, pj) & (shapely.area(shapely.intersection(pi, pj)) == 0)
    assert degenerate.sum() > 50


def test_containment_without_edge_intersections() -> None:
    """Nested rectangles have no intersecting edges: only the point-in-polygon check finds them."""
    rng = np.random.default_rng(7)
    ca, cb = _contained_pairs(rng, 200)
    nxt = [1, 2, 3, 0]
    edges = segments_intersect(
        ca[:, :, None, :], ca[:, nxt, None, :], cb[:, None, :, :], cb[:, None, nxt, :]
    )
    assert not edges.any()
    assert rectangles_collide(ca, cb).all()
    assert rectangles_collide(cb, ca).all()
    assert point_in_rectangle(cb, ca[:, None]).all()


def _composed_reference(ca: FloatArray, cb: FloatArray) -> BoolArray:
    """Rectangle test spelled out with the public building blocks: 16 edge pairs + containment."""
    nxt = [1, 2, 3, 0]
    edges = segments_intersect(
        ca[..., :, None, :], ca[..., nxt, None, :], cb[..., None, :, :], cb[..., None, nxt, :]
    ).any(axis=(-2, -1))
    return np.asarray(
        edges | point_in_rectangle(cb[..., 0, :], ca) | point_in_rectangle(ca[..., 0, :], cb)
    )


def test_rectangles_collide_equals_composed_eq7_test() -> None:
    """The compiled pair kernel is bitwise the composed Eq. (7) test of the public blocks."""
    rng = np.random.default_rng(17)
    na, nb = _near_random_pairs(rng, 3000)
    ia, ib = _shuffle_exact(rng, _integer_rects(rng, 3000, 3), _integer_rects(rng, 3000, 3))
    a, b = np.concatenate([na, ia]), np.concatenate([nb, ib])
    expected = _composed_reference(a, b)
    np.testing.assert_array_equal(rectangles_collide(a, b), expected)


def test_rectangles_collide_broadcasts() -> None:
    rng = np.random.default_rng(8)
    ca = _integer_rects(rng, 3, 2)[:, None]  # (3, 1, 4, 2)
    cb = _integer_rects(rng, 5, 2)  # (5, 4, 2)
    got = rectangles_collide(ca, cb)
    assert got.shape == (3, 5)
    np.testing.assert_array_equal(got, _shapely_collide(*np.broadcast_arrays(ca, cb)))
    assert rectangles_collide(ca[0, 0], cb[0]).shape == ()
    assert rectangles_collide(np.zeros((0, 4, 2)), cb[0]).shape == (0,)


def test_agrees_with_shapely_polygon_objects() -> None:
    """A few pairs through the ``shapely.geometry.Polygon`` object API as well."""
    rng = np.random.default_rng(3)
    ca, cb = _near_random_pairs(rng, 200)
    truth = [Polygon(p).intersects(Polygon(q)) for p, q in zip(ca, cb, strict=True)]
    np.testing.assert_array_equal(rectangles_collide(ca, cb), truth)


# --------------------------------------------------------------------------------------------
# segments_intersect (Eq. 7)
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("p1", "p2", "q1", "q2", "expected"),
    [
        pytest.param((0, 0), (2, 2), (0, 2), (2, 0), True, id="crossing-X"),
        pytest.param((0, 0), (2, 0), (1, 0), (1, 3), True, id="T-junction"),
        pytest.param((0, 0), (2, 0), (1, 1e-12), (1, 3), False, id="T-junction-near-miss"),
        pytest.param((0, 0), (2, 0), (0, 1), (2, 1), False, id="parallel-disjoint"),
        pytest.param((0, 0), (2, 0), (1, 0), (3, 0), True, id="colinear-overlap"),
        pytest.param((0, 0), (2, 2), (1, 1), (3, 3), True, id="colinear-overlap-diagonal"),
        pytest.param((0, 0), (0, 2), (0, 1), (0, 5), True, id="colinear-overlap-vertical"),
        pytest.param((0, 0), (1, 0), (2, 0), (3, 0), False, id="colinear-disjoint"),
        pytest.param((0, 0), (1, 1), (2, 2), (3, 3), False, id="colinear-disjoint-diagonal"),
        pytest.param((0, 0), (1, 1), (1, 1), (2, 0), True, id="shared-endpoint"),
        pytest.param((0, 0), (1, 0), (1, 0), (2, 0), True, id="colinear-shared-endpoint"),
        pytest.param((0, 0), (1, 0), (1, 0), (1, 0), True, id="degenerate-point-on-end"),
        pytest.param((0, 0), (1, 1), (3, 0), (2, 1), False, id="lines-cross-outside"),
        pytest.param((0, 0), (4, 0), (1, -1), (3, 1), True, id="proper-crossing"),
        pytest.param((0, 0), (4, 0), (5, -1), (5, 1), False, id="bbox-rejected"),
    ],
)
def test_segments_intersect_hand_cases(
    p1: tuple[float, float],
    p2: tuple[float, float],
    q1: tuple[float, float],
    q2: tuple[float, float],
    expected: bool,
) -> None:
    for args in ((p1, p2, q1, q2), (p2, p1, q1, q2), (q1, q2, p1, p2), (q2, q1, p2, p1)):
        result = segments_intersect(*args)
        assert result.shape == ()
        assert bool(result) is expected


def test_segments_intersect_broadcasts() -> None:
    q1 = np.array([[0.0, 2.0], [5.0, 5.0]])  # (2, 2)
    q2 = np.array([[2.0, 0.0], [6.0, 6.0]])
    out = segments_intersect([0.0, 0.0], [2.0, 2.0], q1[:, None, :], q2[None, :, :])
    assert out.shape == (2, 2)
    # Only (0, 2)-(2, 0) crosses P; (0, 2)-(6, 6) and (5, 5)-(2, 0) meet the line y = x only at
    # (6, 6) and (5, 5), beyond P; (5, 5)-(6, 6) is colinear with P but disjoint.
    expected = [[True, False], [False, False]]
    np.testing.assert_array_equal(out, expected)


def test_input_shape_is_validated() -> None:
    with pytest.raises(ValueError, match="p1 must have shape"):
        segments_intersect([0.0, 0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="corners_b must have shape"):
        rectangles_collide(np.zeros((4, 2)), np.zeros((3, 2)))


# --------------------------------------------------------------------------------------------
# rectangle_corners and point_in_rectangle
# --------------------------------------------------------------------------------------------


def test_rectangle_corners_geometry() -> None:
    rng = np.random.default_rng(11)
    n = 500
    x, y = rng.uniform(-100, 100, n), rng.uniform(-100, 100, n)
    h, L, W = rng.uniform(-np.pi, np.pi, n), rng.uniform(1, 10, n), rng.uniform(0.5, 3, n)
    c = rectangle_corners(x, y, h, L, W)
    assert c.shape == (n, 4, 2)
    # Counter-clockwise: positive shoelace area equal to L * W.
    cx, cy = c[..., 0], c[..., 1]
    area = 0.5 * np.sum(cx * np.roll(cy, -1, axis=-1) - np.roll(cx, -1, axis=-1) * cy, axis=-1)
    np.testing.assert_allclose(area, L * W, rtol=1e-12)
    # Centre at the front bumper minus L/2 along the heading.
    np.testing.assert_allclose(cx.mean(axis=-1), x - 0.5 * L * np.cos(h), atol=1e-12)
    np.testing.assert_allclose(cy.mean(axis=-1), y - 0.5 * L * np.sin(h), atol=1e-12)
    # Front edge (corners 0, 1) is centred on (x, y), width W.
    np.testing.assert_allclose(c[:, :2].mean(axis=1), np.stack([x, y], axis=1), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(c[:, 1] - c[:, 0], axis=1), W, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(c[:, 2] - c[:, 1], axis=1), L, rtol=1e-12)


def test_rectangle_corners_reference_and_broadcast() -> None:
    c = rectangle_corners(10.0, 2.0, np.pi / 2, 4.0, 2.0)
    np.testing.assert_allclose(c, [[11, 2], [9, 2], [9, -2], [11, -2]], atol=1e-12)
    c = rectangle_corners(np.zeros((3, 1)), 0.0, np.zeros((1, 5)), 5.0, np.ones(5))
    assert c.shape == (3, 5, 4, 2)


def test_point_in_rectangle_cases() -> None:
    sq = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    pts = np.array([[1.0, 0.5], [2.0, 0.5], [2.0, 1.0], [0.0, 0.0], [2.5, 0.5], [1.0, -0.1]])
    expected = [True, True, True, True, False, False]
    np.testing.assert_array_equal(point_in_rectangle(pts, sq), expected)
    np.testing.assert_array_equal(point_in_rectangle(pts, sq[::-1]), expected)  # clockwise
    rot = rectangle_corners(0.0, 0.0, 0.3, 4.0, 2.0)
    centre = np.array([-2.0 * math.cos(0.3), -2.0 * math.sin(0.3)])
    assert point_in_rectangle(centre, rot)
    assert not point_in_rectangle(centre + np.array([10.0, 0.0]), rot)


# --------------------------------------------------------------------------------------------
# Hypothesis properties: symmetry, translation and rotation invariance
# --------------------------------------------------------------------------------------------

_coord = st.floats(-50.0, 50.0, allow_nan=False, allow_infinity=False)
_offset = st.floats(-8.0, 8.0, allow_nan=False, allow_infinity=False)
_angle = st.floats(-math.pi, math.pi, allow_nan=False, allow_infinity=False)
_length = st.floats(0.5, 10.0, allow_nan=False, allow_infinity=False)
_width = st.floats(0.3, 4.0, allow_nan=False, allow_infinity=False)

Pair = tuple[float, float, float, float, float, float, float, float, float, float]


@st.composite
def _vehicle_pairs(draw: st.DrawFn) -> Pair:
    """Two vehicles (x, y, heading, length, width) with B within a few metres of A."""
    xa, ya = draw(_coord), draw(_coord)
    return (
        xa, ya, draw(_angle), draw(_length), draw(_width),
        xa + draw(_offset), ya + draw(_offset), draw(_angle), draw(_length), draw(_width),
    )  # fmt: skip


def _corners(v: Sequence[float]) -> tuple[FloatArray, FloatArray]:
    return rectangle_corners(*v[:5]), rectangle_corners(*v[5:])


def _assume_robust(v: Pair) -> bool:
    """Keep only pairs clearly apart (distance > 1e-6) or clearly overlapping (area > 1e-6)."""
    ca, cb = _corners(v)
    pa, pb = Polygon(ca), Polygon(cb)
    d = pa.distance(pb)
    truth = bool(d == 0.0)
    assume(pa.intersection(pb).area > 1e-6 if truth else d > 1e-6)
    return truth


@settings(max_examples=150, deadline=None)
@given(_vehicle_pairs())
def test_property_symmetric(v: Pair) -> None:
    ca, cb = _corners(v)
    assert bool(rectangles_collide(ca, cb)) == bool(rectangles_collide(cb, ca))
    assert bool(vehicles_collide(*v)) == bool(vehicles_collide(*v[5:], *v[:5]))


@settings(max_examples=150, deadline=None)
@given(
    _vehicle_pairs(),
    st.floats(-1000.0, 1000.0, allow_nan=False),
    st.floats(-1000.0, 1000.0, allow_nan=False),
)
def test_property_translation_invariant(v: Pair, tx: float, ty: float) -> None:
    truth = _assume_robust(v)
    moved = list(v)
    for i in (0, 5):
        moved[i] += tx
        moved[i + 1] += ty
    m = tuple(moved)
    assert bool(rectangles_collide(*_corners(v))) is truth
    assert bool(rectangles_collide(*_corners(m))) is truth
    assert bool(vehicles_collide(*m)) is truth


@settings(max_examples=150, deadline=None)
@given(_vehicle_pairs(), _angle)
def test_property_rotation_invariant(v: Pair, theta: float) -> None:
    truth = _assume_robust(v)
    c, s = math.cos(theta), math.sin(theta)
    rotated = list(v)
    for i in (0, 5):
        x, y = v[i], v[i + 1]
        rotated[i], rotated[i + 1] = c * x - s * y, s * x + c * y
        rotated[i + 2] = v[i + 2] + theta
    r = tuple(rotated)
    assert bool(rectangles_collide(*_corners(v))) is truth
    assert bool(rectangles_collide(*_corners(r))) is truth
    assert bool(vehicles_collide(*r)) is truth


# --------------------------------------------------------------------------------------------
# vehicles_collide
# --------------------------------------------------------------------------------------------


def _exact_reference(*v: FloatArray | float) -> BoolArray:
    return rectangles_collide(rectangle_corners(*v[:5]), rectangle_corners(*v[5:]))


def test_vehicles_collide_equals_exact_test_on_large_batch() -> None:
    rng = np.random.default_rng(99)
    n = 20_000
    xa = rng.uniform(0, 2000, n)
    ya = rng.choice([0.0, LANE], n) + rng.normal(0, 0.5, n)
    near = rng.random(n) < 0.25
    xb = np.where(near, xa + rng.uniform(-12, 12, n), rng.uniform(0, 2000, n))
    yb = np.where(near, ya + rng.uniform(-4, 4, n), rng.choice([0.0, LANE], n))
    ha, hb = rng.normal(0, 0.3, n), rng.normal(0, 0.3, n)
    la, lb = rng.uniform(4, 12, n), rng.uniform(4, 12, n)
    wa, wb = rng.uniform(1.6, 2.6, n), rng.uniform(1.6, 2.6, n)
    args = (xa, ya, ha, la, wa, xb, yb, hb, lb, wb)
    got = vehicles_collide(*args)
    assert got.shape == (n,)
    assert got.dtype == np.bool_
    np.testing.assert_array_equal(got, _exact_reference(*args))
    assert 100 < got.sum() < n // 4  # both outcomes well represented


def test_vehicles_collide_broadcast_shapes() -> None:
    rng = np.random.default_rng(5)
    xa = rng.uniform(0, 30, (4, 1, 1))
    xb = rng.uniform(0, 30, (1, 6, 7))
    yb = rng.uniform(-3, 3, (1, 1, 7))
    args = (xa, 0.0, 0.0, CAR_L, CAR_W, xb, yb, rng.normal(0, 0.2, (6, 1)), CAR_L, CAR_W)
    got = vehicles_collide(*args)
    assert got.shape == (4, 6, 7)
    np.testing.assert_array_equal(got, _exact_reference(*args))
    scalar = vehicles_collide(0.0, 0.0, 0.0, CAR_L, CAR_W, 100.0, 0.0, 0.0, CAR_L, CAR_W)
    assert scalar.shape == ()
    assert not scalar


def test_adjacent_lanes_never_collide() -> None:
    dx = np.linspace(-20.0, 20.0, 4001)
    got = vehicles_collide(500.0, 0.0, 0.0, CAR_L, CAR_W, 500.0 + dx, LANE, 0.0, CAR_L, CAR_W)
    assert not got.any()


@pytest.mark.parametrize("x_rear", [0.0, 100.0, 1234.5])
def test_same_lane_bumper_gap(x_rear: float) -> None:
    """Leader's rear bumper at the follower's front bumper touches; a 1 cm gap does not."""
    follower = (x_rear, LANE, 0.0, CAR_L, CAR_W)
    touching = (x_rear + CAR_L, LANE, 0.0, CAR_L, CAR_W)
    gap = (x_rear + CAR_L + 0.01, LANE, 0.0, CAR_L, CAR_W)
    assert vehicles_collide(*follower, *touching)
    assert vehicles_collide(*touching, *follower)
    assert not vehicles_collide(*follower, *gap)
    assert not vehicles_collide(*gap, *follower)


def test_prefilter_keeps_diagonal_corner_contact() -> None:
    """Corner-to-corner contact along the diagonals: centre distance = sum of half-diagonals."""
    # A occupies x in [-5, 0], y in [-0.9, 0.9]; B occupies x in [0, 5], y in [0.9, 2.7].
    args = (0.0, 0.0, 0.0, CAR_L, CAR_W, CAR_L, CAR_W, 0.0, CAR_L, CAR_W)
    assert _exact_reference(*args)
    assert vehicles_collide(*args)
    assert vehicles_collide(*args[5:], *args[:5])


def test_prefilter_decides_far_pairs_and_keeps_close_ones() -> None:
    """2000 pairs, 3 within the discs: exactly the close pairs can collide, far ones never."""
    xb = np.full(2000, 1000.0)
    xb[:4] = [2.0, 5.0, 5.2, 9.0]  # 3 pass the prefilter (centre distance <= 5.31 m)
    got = collision.vehicles_collide(0.0, 0.0, 0.0, CAR_L, CAR_W, xb, 0.0, 0.0, CAR_L, CAR_W)
    np.testing.assert_array_equal(got[:3], [True, True, False])
    assert not got[3:].any()
    assert not collision.vehicle_pair_collides(0.0, 0.0, 0.0, CAR_L, CAR_W, 1e3, 0.0, 0.0, 5, 2)


def test_prefilter_never_rejects_corner_to_corner_contacts() -> None:
    """The prefilter keeps every pair that the exact test (rounding included) accepts.

    B = A point-reflected through one of A's corners: the rectangles touch at that corner
    only, and the centre distance equals the sum of half-diagonals up to rounding.
    """
    rng = np.random.default_rng(2)
    n = 5000
    xa, ya = rng.uniform(-2000, 2000, n), rng.uniform(-10, 10, n)
    ha = rng.uniform(-np.pi, np.pi, n)
    la, wa = rng.uniform(3, 12, n), rng.uniform(1.5, 3, n)
    corner = rectangle_corners(xa, ya, ha, la, wa)[np.arange(n), rng.integers(0, 4, n)]
    xb, yb = 2 * corner[:, 0] - xa, 2 * corner[:, 1] - ya
    far = rng.random(n) < 0.5  # interleaved far pairs: the exact test runs on a subset
    xb[far] += 500.0
    args = (xa, ya, ha, la, wa, xb, yb, ha + np.pi, la, wa)
    exact = _exact_reference(*args)
    assert exact.sum() > n // 8  # rounding makes many of these count as touching
    assert not exact[far].any()
    np.testing.assert_array_equal(vehicles_collide(*args), exact)
