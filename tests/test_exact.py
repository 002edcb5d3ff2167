"""Tests of the exact reference in ``proximity/testing/exact.py`` against hand-computed answers.

The reference judges the library, so it is checked here on its own: one case
per Voronoi region with the answer worked out by hand, degenerate triangles,
power-of-two rescalings (exact, so the squared distance must scale by exactly
``4**k``), and a property test that verifies each answer with the projection
inequality instead of trusting the enumeration of features.
"""

import itertools
import math
from fractions import Fraction

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proximity.testing import exact
from proximity.testing.exact import Feature

F = Fraction
VERTEX0, VERTEX1, VERTEX2, EDGE01, EDGE12, EDGE20, FACE, RIM = Feature

# The vertices spanning each triangle feature.
SUPPORT = {
    VERTEX0: {0},
    VERTEX1: {1},
    VERTEX2: {2},
    EDGE01: {0, 1},
    EDGE12: {1, 2},
    EDGE20: {0, 2},
    FACE: {0, 1, 2},
}

# Right triangle in the z = 0 plane; every answer below is worked out by hand.
RIGHT = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]]

# (point, sqr_distance, feature, closest point, barycentric)
RIGHT_CASES = [
    ([1, 1, 3], 9, FACE, (1, 1, 0), (F(1, 2), F(1, 4), F(1, 4))),
    ([1, 1, -3], 9, FACE, (1, 1, 0), (F(1, 2), F(1, 4), F(1, 4))),
    ([1, 2, 0], 0, FACE, (1, 2, 0), (F(1, 4), F(1, 4), F(1, 2))),
    ([2, -3, 4], 25, EDGE01, (2, 0, 0), (F(1, 2), F(1, 2), 0)),
    ([3, 3, 1], 3, EDGE12, (2, 2, 0), (0, F(1, 2), F(1, 2))),
    ([-1, 2, 2], 5, EDGE20, (0, 2, 0), (F(1, 2), 0, F(1, 2))),
    ([-1, -2, 3], 14, VERTEX0, (0, 0, 0), (1, 0, 0)),
    ([6, -1, 0], 5, VERTEX1, (4, 0, 0), (0, 1, 0)),
    ([-1, 7, 2], 14, VERTEX2, (0, 4, 0), (0, 0, 1)),
    # On the boundary between regions: above an edge point, the open face
    # does not contain the foot, so the edge wins; above a vertex, the vertex.
    ([2, 0, 5], 25, EDGE01, (2, 0, 0), (F(1, 2), F(1, 2), 0)),
    ([0, 0, 5], 25, VERTEX0, (0, 0, 0), (1, 0, 0)),
    ([4, -2, 1], 5, VERTEX1, (4, 0, 0), (0, 1, 0)),
    # Exactly on the triangle.
    ([2, 0, 0], 0, EDGE01, (2, 0, 0), (F(1, 2), F(1, 2), 0)),
    ([0, 4, 0], 0, VERTEX2, (0, 4, 0), (0, 0, 1)),
]


def as_fractions(values):
    return tuple(F(float(x)) for x in values)


def check(result, sqr, feature, point, bary, features=None):
    assert result.sqr_distance == sqr
    assert result.feature == feature
    assert result.point == tuple(F(x) for x in point)
    assert result.barycentric == tuple(F(x) for x in bary)
    assert result.features == frozenset(features or {feature})


@pytest.mark.parametrize(("point", "sqr", "feature", "closest", "bary"), RIGHT_CASES)
def test_triangle_regions(point, sqr, feature, closest, bary):
    check(exact.triangle_closest(RIGHT, point), sqr, feature, closest, bary)


def test_feature_sqr_distances():
    # Above (1, 1, 0): closed edges 01 and 20 are nearest at (1, 0, 0) and
    # (0, 1, 0), edge 12 at (2, 2, 0).
    result = exact.triangle_closest(RIGHT, [1, 1, 3])
    assert result.feature_sqr_distances == (11, 19, 19, 10, 11, 10, 9)
    # Beyond vertex 1 the closed edges 01 and 12 are nearest at that vertex.
    result = exact.triangle_closest(RIGHT, [6, -1, 0])
    assert result.feature_sqr_distances == (37, 5, 61, 5, 5, 37, 5)


def relabel(feature, order):
    """Feature of the triangle ``vertices[order]`` matching `feature`."""
    moved = {order.index(i) for i in SUPPORT[feature]}
    return next(f for f, s in SUPPORT.items() if s == moved)


@pytest.mark.parametrize("order", list(itertools.permutations(range(3))))
@pytest.mark.parametrize(("point", "sqr", "feature", "closest", "bary"), RIGHT_CASES)
def test_triangle_vertex_order(order, point, sqr, feature, closest, bary):
    vertices = [RIGHT[i] for i in order]
    result = exact.triangle_closest(vertices, point)
    check(result, sqr, relabel(feature, list(order)), closest, [bary[i] for i in order])


@pytest.mark.parametrize("k", [-1070, -1000, -600, 0, 600, 1000])
@pytest.mark.parametrize(("point", "sqr", "feature", "closest", "bary"), RIGHT_CASES)
def test_triangle_power_of_two_scaling(k, point, sqr, feature, closest, bary):
    # Coordinates are integers below 8, so 2**k times them is exact even in
    # the subnormal range (k = -1070) and below the overflow threshold.
    scale = 2.0**k
    vertices = np.array(RIGHT) * scale
    result = exact.triangle_closest(vertices, np.array(point, dtype=float) * scale)
    assert result.sqr_distance == sqr * F(2) ** (2 * k)
    assert result.point == tuple(F(x) * F(2) ** k for x in closest)
    assert result.feature == feature
    assert result.barycentric == tuple(F(x) for x in bary)


@pytest.mark.parametrize("x", [1e300, 1e-300, 5e-324])
def test_triangle_decimal_magnitudes(x):
    # Only multiplications by powers of two, which are exact for these x.
    vertices = [[0, 0, 0], [4 * x, 0, 0], [0, 4 * x, 0]]
    result = exact.triangle_closest(vertices, [x, x, 2 * x])
    assert result.sqr_distance == 4 * F(x) ** 2
    assert result.feature == FACE
    assert result.point == (F(x), F(x), 0)
    assert result.barycentric == (F(1, 2), F(1, 4), F(1, 4))


def test_triangle_mixed_magnitudes():
    # A 1e-300 triangle seen from 1e300: the vertices are numerically one
    # point, yet the reference still picks the exactly nearest one.
    t = 1e-300
    vertices = [[0, 0, 0], [t, 0, 0], [0, t, 0]]
    result = exact.triangle_closest(vertices, [1e300, 1e300, 0])
    assert result.feature == EDGE12
    assert result.point == (F(t) / 2, F(t) / 2, 0)
    assert result.sqr_distance == 2 * (F(1e300) - F(t) / 2) ** 2


def test_translation_and_axis_permutation():
    # Translating by a dyadic vector and permuting axes are exact motions.
    shift = np.array([0.5, -1.25, 3.0])
    for axes in itertools.permutations(range(3)):
        vertices = (np.array(RIGHT) + shift)[:, axes]
        for point, sqr, feature, _, bary in RIGHT_CASES:
            result = exact.triangle_closest(vertices, (np.array(point) + shift)[list(axes)])
            assert (result.sqr_distance, result.feature) == (sqr, feature)
            assert result.barycentric == tuple(F(b) for b in bary)


# -- degenerate triangles -----------------------------------------------------


def test_collinear_vertex_inside_opposite_edge():
    # V2 is the midpoint of edge 01: its vertex and edge 01 tie.
    vertices = [[0, 0, 0], [2, 0, 0], [1, 0, 0]]
    check(
        exact.triangle_closest(vertices, [1, 3, 4]),
        25,
        VERTEX2,
        (1, 0, 0),
        (0, 0, 1),
        {VERTEX2, EDGE01},
    )
    check(
        exact.triangle_closest(vertices, [1.5, 0, 2]),
        4,
        EDGE01,
        (1.5, 0, 0),
        (F(1, 4), F(3, 4), 0),
        {EDGE01, EDGE12},
    )
    check(exact.triangle_closest(vertices, [-1, 0, 0]), 1, VERTEX0, (0, 0, 0), (1, 0, 0))
    check(exact.triangle_closest(vertices, [3, 0, 1]), 2, VERTEX1, (2, 0, 0), (0, 1, 0))


def test_collinear_generic_direction():
    # V2 = V0 + 3 (V1 - V0) exactly; P projects inside edge 12 only.
    vertices = [[1, 1, 1], [2, 3, 4], [4, 7, 10]]
    point = [3, 5, 7]  # on the line, between V1 and V2
    check(
        exact.triangle_closest(vertices, point),
        0,
        EDGE12,
        (3, 5, 7),
        (0, F(1, 2), F(1, 2)),
        {EDGE12, EDGE20},
    )
    offset = [3 + 2, 5 - 1, 7]  # (2, -1, 0) is orthogonal to (1, 2, 3)
    result = exact.triangle_closest(vertices, offset)
    assert result.sqr_distance == 5
    assert result.point == (3, 5, 7)


def test_two_coincident_vertices():
    vertices = [[1, 1, 1], [1, 1, 1], [3, 1, 1]]
    check(
        exact.triangle_closest(vertices, [0, 1, 1]),
        1,
        VERTEX0,
        (1, 1, 1),
        (1, 0, 0),
        {VERTEX0, VERTEX1},
    )
    check(
        exact.triangle_closest(vertices, [2, 1, 5]),
        16,
        EDGE12,
        (2, 1, 1),
        (0, F(1, 2), F(1, 2)),
        {EDGE12, EDGE20},
    )


def test_all_coincident_vertices():
    vertices = [[1, 2, 3]] * 3
    check(
        exact.triangle_closest(vertices, [1, 2, 5]),
        4,
        VERTEX0,
        (1, 2, 3),
        (1, 0, 0),
        {VERTEX0, VERTEX1, VERTEX2},
    )


# -- 2D -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("point", "sqr", "feature", "closest"),
    [
        ([1, 1], 0, FACE, (1, 1)),
        ([3, 3], 2, EDGE12, (2, 2)),
        ([2, -1], 1, EDGE01, (2, 0)),
        ([-1, -1], 2, VERTEX0, (0, 0)),
        ([-3, 8], 25, VERTEX2, (0, 4)),
    ],
)
def test_triangle_2d(point, sqr, feature, closest):
    result = exact.triangle_closest([[0, 0], [4, 0], [0, 4]], point)
    assert (result.sqr_distance, result.feature) == (sqr, feature)
    assert result.point == closest


# -- certificate: the projection inequality ------------------------------------

coordinates = st.one_of(
    # Small integers make degenerate and boundary configurations common.
    st.integers(-3, 3).map(float),
    st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False),
    st.floats(-1e-200, 1e-200, allow_nan=False, allow_infinity=False),
)


@st.composite
def triangle_queries(draw):
    dim = draw(st.sampled_from([2, 3]))
    vertices = draw(st.lists(st.lists(coordinates, min_size=dim, max_size=dim), min_size=3, max_size=3))
    point = draw(st.lists(coordinates, min_size=dim, max_size=dim))
    return vertices, point


@settings(max_examples=300, deadline=None)
@given(triangle_queries())
def test_triangle_answer_is_certified_projection(query):
    vertices, point = query
    result = exact.triangle_closest(vertices, point)
    v = [as_fractions(row) for row in vertices]
    p = as_fractions(point)
    x = result.point
    bary = result.barycentric

    # x is the point of the feature with the given barycentric coordinates.
    assert sum(bary) == 1
    assert {i for i in range(3) if bary[i] != 0} == SUPPORT[result.feature]
    assert all(b > 0 for b in bary if b != 0)
    assert x == tuple(sum(b * vi[k] for b, vi in zip(bary, v, strict=True)) for k in range(len(p)))
    assert result.sqr_distance == sum((xk - pk) ** 2 for xk, pk in zip(x, p, strict=True))
    # x is the projection onto the convex hull iff (P - x).(Vi - x) <= 0 for
    # every vertex.
    for vi in v:
        assert sum((pk - xk) * (vk - xk) for pk, xk, vk in zip(p, x, vi, strict=True)) <= 0
    assert result.feature == min(result.features)
    # Closed-feature distances: a vertex's own, never below the minimum, and
    # equal to it exactly for the features containing the closest point.
    closed = result.feature_sqr_distances
    for i in range(3):
        assert closed[i] == sum((vk - pk) ** 2 for vk, pk in zip(v[i], p, strict=True))
    assert closed[FACE] == result.sqr_distance
    assert all(closed[f] >= result.sqr_distance for f in Feature if f != RIM)
    assert all(closed[f] == result.sqr_distance for f in result.features)


# -- pairs of shapes ----------------------------------------------------------------

PAIR_REFERENCES = {
    (2, 2): exact.segment_segment_closest,
    (2, 3): exact.segment_triangle_closest,
    (3, 3): exact.triangle_triangle_closest,
}
# Small integers make ties (parallel, coplanar, touching, degenerate) common.
pair_coordinates = st.one_of(st.integers(-3, 3).map(float), coordinates)


@st.composite
def pair_queries(draw):
    ka, kb = draw(st.sampled_from(sorted(PAIR_REFERENCES)))
    coordinate = st.sampled_from([pair_coordinates, st.integers(-3, 3).map(float)]).flatmap(lambda c: c)
    a = draw(st.lists(st.lists(coordinate, min_size=3, max_size=3), min_size=ka, max_size=ka))
    b = draw(st.lists(st.lists(coordinate, min_size=3, max_size=3), min_size=kb, max_size=kb))
    return a, b


@settings(max_examples=300, deadline=None)
@given(pair_queries())
def test_pair_answer_is_certified_by_a_separating_slab(query):
    """The witnesses are points of the shapes and the planes through them,
    perpendicular to ``point_b - point_a``, have shape a on one side and shape
    b on the other: no pair of points is closer.  The features are the
    witnesses' carriers and the lowest of the tie set."""
    a, b = query
    result = PAIR_REFERENCES[len(a), len(b)](a, b)
    va, vb = [as_fractions(row) for row in a], [as_fractions(row) for row in b]
    pa, pb = result.point_a, result.point_b
    for weights, vertices, point, feature in (
        (result.weights_a, va, pa, result.feature_a),
        (result.weights_b, vb, pb, result.feature_b),
    ):
        assert sum(weights) == 1 and all(w >= 0 for w in weights)
        assert {i for i, w in enumerate(weights) if w != 0} == SUPPORT[feature]
        assert point == tuple(sum(w * v[k] for w, v in zip(weights, vertices, strict=True)) for k in range(3))
    v = tuple(y - x for x, y in zip(pa, pb, strict=True))
    assert result.sqr_distance == sum(x * x for x in v)
    for u in va:
        assert sum((uk - xk) * vk for uk, xk, vk in zip(u, pa, v, strict=True)) <= 0
    for u in vb:
        assert sum((uk - yk) * vk for uk, yk, vk in zip(u, pb, v, strict=True)) >= 0
    # The reported pair is the lowest of those holding a closest pair, found
    # by another route (whether relative interiors meet), and each of those
    # is at the minimum as a pair of closed features.
    assert (result.feature_a, result.feature_b) == min(result.features)
    closed = result.feature_sqr_distances
    assert all(closed[pair] == result.sqr_distance for pair in result.features)
    assert all(distance >= result.sqr_distance for distance in closed.values())


def test_pair_ties_and_intersections():
    # Coplanar triangles overlapping in an area: every pair of features that
    # meets is in the tie set, the face pair included.
    a = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]]
    r = exact.triangle_triangle_closest(a, [[1.0, 1.0, 0.0], [5.0, 1.0, 0.0], [1.0, 5.0, 0.0]])
    assert r.sqr_distance == 0 and (FACE, FACE) in r.features
    # The lowest: a's edge 12 crosses b's edge 01 at (3, 1, 0).
    assert (r.feature_a, r.feature_b) == (EDGE12, EDGE01) and r.point_a == as_fractions([3, 1, 0])
    assert r.features == {
        (EDGE12, EDGE01),
        (EDGE12, EDGE20),
        (EDGE12, FACE),
        (FACE, VERTEX0),
        (FACE, EDGE01),
        (FACE, EDGE20),
        (FACE, FACE),
    }
    # A triangle through another along a segment: its ends are edge-face pairs.
    r = exact.triangle_triangle_closest(a, [[1.0, 1.0, -1.0], [1.0, 1.0, 1.0], [5.0, 5.0, 1.0]])
    assert r.features == {(EDGE12, FACE), (FACE, EDGE01), (FACE, FACE)}
    # A segment lying in a triangle's plane, parallel to an edge, above the face.
    r = exact.segment_triangle_closest([[1.0, 1.0, 2.0], [2.0, 1.0, 2.0]], a)
    assert r.sqr_distance == 4 and (r.feature_a, r.feature_b) == (VERTEX0, FACE)
    assert r.features == {(VERTEX0, FACE), (VERTEX1, FACE), (EDGE01, FACE)}
    # Zero-length and zero-area shapes: their points are their vertices'.
    r = exact.segment_triangle_closest(
        [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]], [[0.0] * 3, [2.0, 2.0, 0.0], [4.0, 4.0, 0.0]]
    )
    assert r.sqr_distance == 1
    assert r.features == {(VERTEX0, EDGE01), (VERTEX0, EDGE20), (VERTEX1, EDGE01), (VERTEX1, EDGE20)}
    assert (r.feature_a, r.feature_b) == (VERTEX0, EDGE01)


def test_pair_scale():
    a, b = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[0.0, 3.0, 0.0], [0.0, 0.0, -2.0], [0.5, 0.5, 0.5]]
    assert exact.pair_scale(a, b) == 3
    assert exact.pair_scale(b, a) == 3


# -- circle and disk -----------------------------------------------------------

ORIGIN, Z2 = [0.0, 0.0, 0.0], [0.0, 0.0, 2.0]


def test_circle_on_axis():
    result = exact.circle_closest(ORIGIN, Z2, 3.0, [0, 0, 4])
    assert result.distance == 5
    assert (result.sqr_height, result.sqr_radial) == (16, 0)
    assert result.on_axis
    assert result.feature == RIM
    assert result.point is None

    irrational = exact.circle_closest([1, 2, 3], [0, -5, 0], 1.0, [1, 3, 3])
    with mpmath.workprec(exact.PREC):
        assert irrational.distance == mpmath.sqrt(2)
    assert irrational.on_axis


def test_disk_on_axis():
    result = exact.disk_closest(ORIGIN, Z2, 3.0, [0, 0, -4])
    assert result.distance == 4
    assert result.on_axis
    assert result.feature == FACE
    assert result.point == (0, 0, 0)


def test_zero_radius_is_a_point():
    result = exact.circle_closest(ORIGIN, Z2, 0.0, [0, 0, 4])
    assert (result.distance, result.point) == (4, (0, 0, 0))
    result = exact.circle_closest(ORIGIN, Z2, 0.0, [3, 0, 4])
    assert (result.distance, result.point) == (5, (0, 0, 0))


@pytest.mark.parametrize("shape", ["circle", "disk"])
def test_pythagorean_rim(shape):
    # q = 10, R = 7, h = 4: distance 5 to the rim point (4.2, 5.6, 0).
    closest = getattr(exact, f"{shape}_closest")
    result = closest(ORIGIN, Z2, 7.0, [6, 8, 4])
    assert result.distance == 5
    assert (result.sqr_height, result.sqr_radial) == (16, 100)
    assert result.feature == RIM
    assert not result.on_axis
    with mpmath.workprec(exact.PREC):
        expected = (mpmath.mpf("4.2"), mpmath.mpf("5.6"), 0)
        assert all(abs(a - b) < mpmath.mpf(2) ** -250 for a, b in zip(result.point, expected, strict=True))


def test_disk_above_face():
    result = exact.disk_closest(ORIGIN, Z2, 3.0, [1, 2, 4])
    assert result.distance == 4
    assert result.feature == FACE
    assert result.point == (1, 2, 0)


def test_disk_in_plane():
    inside = exact.disk_closest(ORIGIN, Z2, 3.0, [1, 2, 0])
    assert (inside.distance, inside.feature) == (0, FACE)
    outside = exact.disk_closest(ORIGIN, Z2, 3.0, [10, 0, 0])
    assert (outside.distance, outside.feature) == (7, RIM)
    assert outside.point == (3, 0, 0)


def test_circle_in_plane_inside():
    result = exact.circle_closest(ORIGIN, Z2, 3.0, [1, 2, 0])
    with mpmath.workprec(exact.PREC):
        assert abs(result.distance - (3 - mpmath.sqrt(5))) < mpmath.mpf(2) ** -250


def test_point_on_rim():
    # q == R exactly: the disk reports FACE (q**2 <= R**2), distance 0.
    disk = exact.disk_closest(ORIGIN, Z2, 3.0, [0, 3, 0])
    circle = exact.circle_closest(ORIGIN, Z2, 3.0, [0, 3, 0])
    assert (disk.distance, disk.feature) == (0, FACE)
    assert (circle.distance, circle.feature) == (0, RIM)


def test_tilted_unnormalized_normal():
    # N = (1, 1, 0), D = (3, 3, 4): h**2 = 36 / 2 = 18, q**2 = 34 - 18 = 16.
    center = [1.0, 1.0, 1.0]
    point = [4.0, 4.0, 5.0]
    for length in [1.0, 1e-100, 1e100]:
        normal = [length, length, 0.0]
        ring = exact.circle_closest(center, normal, 1.0, point)
        assert (ring.sqr_height, ring.sqr_radial) == (18, 16)
        with mpmath.workprec(exact.PREC):
            assert ring.distance == mpmath.sqrt(27)  # 18 + (4 - 1)**2
            assert exact.disk_distance(center, normal, 5.0, point) == mpmath.sqrt(18)
            assert exact.circle_distance(center, normal, 5.0, point) == mpmath.sqrt(19)
        assert exact.disk_closest(center, normal, 5.0, point).feature == FACE
        assert exact.disk_closest(center, normal, 1.0, point).feature == RIM


@pytest.mark.parametrize("k", [-1074, -1000, -500, 500, 990])
def test_circle_power_of_two_scaling(k):
    s = 2.0**k
    # Coordinates 4s, 6s, 7s, 8s are exact; the distance is exactly 5s.
    ring = exact.circle_closest(ORIGIN, [0, 0, s], 7 * s, [6 * s, 8 * s, 4 * s])
    assert ring.distance == 5 * exact.to_mpf(F(2) ** k)
    assert (ring.sqr_height, ring.sqr_radial) == (16 * F(s) ** 2, 100 * F(s) ** 2)
    disk = exact.disk_closest(ORIGIN, [0, 0, 1], 7 * s, [2 * s, 3 * s, 4 * s])
    assert disk.distance == 4 * exact.to_mpf(F(2) ** k)


@pytest.mark.parametrize("x", [1e300, 1e-300])
def test_circle_decimal_magnitudes(x):
    center = [x, 0.0, 0.0]  # 2x - x == x exactly
    result = exact.circle_closest(center, [0, 0, 1], x / 2, [2 * x, 0, 0])
    assert result.distance == exact.to_mpf(F(x) / 2)
    result = exact.disk_closest(center, [0, 0, 1], x, [x, 0, 4 * x])
    assert result.distance == exact.to_mpf(4 * F(x))
    assert result.on_axis


# -- scales and error measures --------------------------------------------------


def test_scales():
    assert exact.triangle_scale([[0, 0], [4, 0], [0, 4]], [0, -3]) == 7
    assert exact.circle_scale(ORIGIN, 2.0, [3, 4, 0]) == 7


def test_error_in_units():
    assert exact.error_in_units(1.0 + 2**-52, 1, 1) == 1
    assert exact.error_in_units(1.0 + 2**-52, 1, 4) == 0.25
    assert exact.error_in_units(1.0, 1, 0) == 0
    assert exact.error_in_units(1.0, F(1, 3), 0) == math.inf
    assert exact.error_in_units(math.nan, 1, 1) == math.inf
    assert exact.error_in_units(-math.inf, 1, 1) == math.inf
    # 1e300 and 1e-300 scales neither overflow nor underflow.
    assert exact.error_in_units(1e300, F(1e300) + F(1e300) / 2**60, 1e300) == 2**-8
    assert exact.error_in_units(1e-300, F(1e-300) * (1 - F(1, 2**52)), 1e-300) == 1


def test_ulps():
    assert exact.ulps(1.0 + 2**-52, 1) == 1
    assert exact.ulps(1 / 3, F(1, 3)) == 1 / 3  # fl(1/3) = 1/3 - 2**-54 / 3
    assert exact.ulps(1.0, 1 - F(1, 2**60)) == 2**-8  # ulp of the float nearest, 1.0
    assert exact.ulps(5e-324, 0) == 1
    assert exact.ulps(0.0, 0) == 0
    assert exact.ulps(1e300, F(1e300) + F(math.ulp(1e300)) / 2) == 0.5
    # Beyond the float range the unit is the top binade's spacing, 2**971.
    assert exact.ulps(1.7976931348623157e308, F(2) ** 1024) == 1
    with mpmath.workprec(exact.PREC):
        sqrt2 = mpmath.sqrt(2)
    assert exact.ulps(math.sqrt(2), sqrt2) <= 0.5
    assert exact.ulps(math.inf, 1) == math.inf
    assert exact.ulps(math.nan, 1) == math.inf


def test_to_mpf_never_rounds_to_float():
    third = exact.to_mpf(F(1, 3))
    assert third != mpmath.mpf(1 / 3)
    assert exact.to_mpf(F(1, 2**1100)) > 0
    assert exact.to_mpf(5e-324) == mpmath.mpf(2) ** -1074
    with mpmath.workprec(exact.PREC):
        assert exact.to_mpf(10**400) == mpmath.mpf(10**400)
        assert abs(third * 3 - 1) <= mpmath.mpf(2) ** -exact.PREC


def test_global_precision_is_restored():
    before = mpmath.mp.prec
    exact.circle_distance(ORIGIN, Z2, 3.0, [1, 2, 3])
    exact.triangle_distance(RIGHT, [1, 1, 1])
    exact.ulps(1.0, F(1, 3))
    assert mpmath.mp.prec == before


# -- input validation -------------------------------------------------------------


@pytest.mark.parametrize(
    ("function", "args"),
    [
        (exact.triangle_closest, (RIGHT, [0, 0, math.nan])),
        (exact.triangle_closest, ([[0, 0, 0], [1, 0, 0], [0, math.inf, 0]], [0, 0, 0])),
        (exact.triangle_closest, (RIGHT, [0, 0])),
        (exact.triangle_closest, (RIGHT[:2], [0, 0, 0])),
        (exact.circle_closest, (ORIGIN, [0, 0, 0], 1.0, [1, 2, 3])),
        (exact.disk_closest, (ORIGIN, Z2, -1.0, [1, 2, 3])),
        (exact.disk_closest, (ORIGIN, Z2, math.nan, [1, 2, 3])),
        (exact.circle_closest, ([0, 0], [0, 1], 1.0, [1, 2])),
    ],
)
def test_invalid_input_raises(function, args):
    with pytest.raises(ValueError):
        function(*args)


def test_pairwise():
    triangles = np.array([RIGHT, RIGHT])
    points = np.array([[1, 1, 3], [6, -1, 0]], dtype=float)
    assert exact.pairwise(exact.triangle_sqr_distance, triangles, points) == [9, 5]
    distances = exact.pairwise(
        exact.disk_distance, [ORIGIN] * 2, [Z2] * 2, [3.0, 7.0], [[0, 0, 4], [6, 8, 4]]
    )
    assert distances == [4, 5]
