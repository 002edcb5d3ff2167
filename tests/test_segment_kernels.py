"""The point-segment kernels of ``proximity.point.segment`` against the exact reference.

``robust`` within ``8 eps S + 2^-1075`` (``S = max |P - V_i|``) with its
closest point on the segment; ``certified`` within one ulp with the exact
feature wherever it answers ``CERTAIN``; ``_exact.segment``, its fallback,
faithful with the exact feature on every case.  The kernels are called
through small compiled loops, one call per family of cases.
"""

import math
from fractions import Fraction

import numba
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proximity.numerics import exact as _exact
from proximity.numerics.certified import CERTAIN, EXACT
from proximity.numerics.fp import SAFE_MAX, SAFE_MIN, UNSCALED
from proximity.point import segment as point_segment
from proximity.testing import exact
from tests import checks

Feature = exact.Feature


# -- the kernels, through compiled loops over rows (V0, V1, P) ------------------------------------------


@numba.njit
def _robust_rows(q):
    out = np.empty((q.shape[0], 7))
    for k in range(q.shape[0]):
        r = point_segment.robust(
            q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], q[k, 6], q[k, 7], q[k, 8]
        )
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = r[0], r[1], r[2], r[3]
        out[k, 4], out[k, 5], out[k, 6] = r[4], r[5], r[6]
    return out


@numba.njit
def _certified_rows(q):
    out = np.empty((q.shape[0], 8))
    for k in range(q.shape[0]):
        r = point_segment.certified(
            q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], q[k, 6], q[k, 7], q[k, 8]
        )
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = r[0], r[1], r[2], r[3]
        out[k, 4], out[k, 5], out[k, 6], out[k, 7] = r[4], r[5], r[6], r[7]
    return out


@numba.njit
def _block_rows(q):
    """The robust method as a batch block runs it: ``robust_local`` on the
    differences where :func:`~proximity.point.segment.window` says they are
    safe, :func:`~proximity.point.segment.robust` on the others."""
    out = np.empty((q.shape[0], 7))
    safe = np.empty(q.shape[0], np.bool_)
    for k in range(q.shape[0]):
        v0x, v0y, v0z, v1x, v1y, v1z = q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5]
        px, py, pz = q[k, 6], q[k, 7], q[k, 8]
        ax, ay, az, bx, by, bz = v0x - px, v0y - py, v0z - pz, v1x - px, v1y - py, v1z - pz
        _, safe[k] = point_segment.window(ax, ay, az, bx, by, bz)
        r = point_segment.finish(
            point_segment.robust_local(ax, ay, az, bx, by, bz),
            UNSCALED,
            v0x,
            v0y,
            v0z,
            v1x,
            v1y,
            v1z,
            px,
            py,
            pz,
        )
        if not safe[k]:
            r = point_segment.robust(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = r[0], r[1], r[2], r[3]
        out[k, 4], out[k, 5], out[k, 6] = r[4], r[5], r[6]
    return out, safe


@numba.njit
def _window(q):
    out = np.empty((q.shape[0], 2))
    for k in range(q.shape[0]):
        out[k, 0], out[k, 1] = point_segment.window(q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5])
    return out


def _rows(vertices, points):
    """Kernel rows from ``(n, 2, D)`` vertices and ``(n, D)`` points, D = 2 or 3 (z = 0)."""
    vertices, points = np.asarray(vertices, float), np.asarray(points, float)
    if vertices.shape[-1] == 2:
        vertices = np.concatenate([vertices, np.zeros(vertices.shape[:-1] + (1,))], axis=-1)
        points = np.concatenate([points, np.zeros(points.shape[:-1] + (1,))], axis=-1)
    return np.ascontiguousarray(np.concatenate([vertices.reshape(-1, 6), points], axis=1))


# -- the judge ----------------------------------------------------------------------------------------


def _rounded(x):
    """The float nearest the non-negative Fraction ``x``, inf where that overflows."""
    try:
        return float(x)
    except OverflowError:
        return math.inf


def judge(vertices, points):
    """Check every kernel on pairwise queries; return the number of certified
    queries that needed the exact fallback.

    ``vertices`` ``(n, 2, D)`` and ``points`` ``(n, D)``, D = 2 or 3: the
    reference runs in D dimensions, the kernels on the ``z = 0`` embedding.
    """
    vertices, points = np.asarray(vertices, float), np.asarray(points, float)
    q = _rows(vertices, points)
    robust = _robust_rows(q)
    certified = _certified_rows(q)
    dim = points.shape[1]
    fallbacks = 0
    for k in range(len(q)):
        v, p = vertices[k], points[k]
        where = f"vertices={v.tolist()!r}, point={p.tolist()!r}"
        ref = exact.segment_closest(v, p)
        d, _, x, y, z, feature, t = robust[k]
        closest = (x, y, z)[:dim]
        checks.check_segment(v, p, d, closest, Feature(int(feature)), t)
        # The robust method names its feature by t, and 0 is +0.0.
        assert math.copysign(1.0, t) == 1.0, where
        assert (t == 0.0) == (feature == Feature.VERTEX0), where
        assert (t == 1.0) == (feature == Feature.VERTEX1), where

        # The exact fallback, on every case: faithful, exact feature, the rest correctly rounded.
        xd, xs, xx, xy, xz, xf, xt = _exact.segment(q[k, :6].reshape(2, 3), q[k, 6:])
        assert exact.ulps(xd, ref.distance) < 1.0, where
        assert xf == ref.feature, (xf, set(ref.features), where)
        assert xs == _rounded(ref.sqr_distance), where
        assert xt == float(ref.t) and math.copysign(1.0, xt) == 1.0, where
        assert [xx, xy, xz][:dim] == [float(c) for c in ref.point], where
        assert xd == 0.0 or ref.sqr_distance != 0, where

        status, cd, cs, cx, cy, cz, cf, ct = certified[k]
        assert status in (CERTAIN, EXACT), where
        if status == CERTAIN:
            assert exact.ulps(cd, ref.distance) < 1.0, (cd, where)
            assert cf == ref.feature, (cf, set(ref.features), where)
            assert cd == 0.0 or ref.sqr_distance != 0, where
            if math.isfinite(_rounded(ref.sqr_distance)):
                assert exact.ulps(cs, ref.sqr_distance) <= 1.0, (cs, where)
            checks.check_segment(v, p, cd, (cx, cy, cz)[:dim], Feature(int(cf)), ct)
        else:
            fallbacks += 1
    return fallbacks


# -- families of cases --------------------------------------------------------------------------------


def _unit(rng, n):
    u = rng.normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def _perpendicular(rng, d):
    """A unit vector perpendicular (to rounding) to each row of ``d``."""
    w = np.cross(d, _unit(rng, len(d)))
    return w / np.linalg.norm(w, axis=1, keepdims=True)


def test_random_segments_and_points():
    rng = np.random.default_rng(1)
    v = rng.uniform(-1, 1, (300, 2, 3))
    p = rng.uniform(-2, 2, (300, 3))
    judge(v, p)
    judge(v[:, ::-1], p)  # the other vertex order


def test_random_segments_in_2d():
    rng = np.random.default_rng(2)
    judge(rng.uniform(-1, 1, (120, 2, 2)), rng.uniform(-2, 2, (120, 2)))


def test_vertex_order_swaps_the_certified_endpoints():
    rng = np.random.default_rng(3)
    q = _rows(rng.uniform(-1, 1, (2000, 2, 3)), rng.uniform(-2, 2, (2000, 3)))
    swapped = np.ascontiguousarray(q[:, [3, 4, 5, 0, 1, 2, 6, 7, 8]])
    a, b = _certified_rows(q), _certified_rows(swapped)
    both = (a[:, 0] == CERTAIN) & (b[:, 0] == CERTAIN)
    assert both.sum() > 1990
    flip = {float(Feature.VERTEX0): Feature.VERTEX1, float(Feature.VERTEX1): Feature.VERTEX0}
    for fa, fb in zip(a[both, 6], b[both, 6], strict=True):
        assert fb == flip.get(fa, Feature.EDGE01)


def test_zero_length_segments_are_points():
    rng = np.random.default_rng(4)
    v0 = rng.uniform(-1, 1, (60, 3))
    p = np.concatenate([rng.uniform(-2, 2, (50, 3)), v0[50:]])  # the last ten on the point
    v = np.stack([v0, v0], axis=1)
    assert judge(v, p) == 0  # a zero-length segment is decided without predicates
    r = _robust_rows(_rows(v, p))
    assert (r[:, 5] == Feature.VERTEX0).all() and (r[:, 6] == 0.0).all()
    c = _certified_rows(_rows(v, p))
    assert (c[:, 6] == Feature.VERTEX0).all() and (c[:, 0] == CERTAIN).all()


def test_segments_one_ulp_long():
    rng = np.random.default_rng(5)
    v0 = rng.uniform(-1, 1, (80, 3))
    v1 = v0.copy()
    v1[:40, 0] = np.nextafter(v0[:40, 0], np.inf)  # one coordinate
    v1[40:] = np.nextafter(v0[40:], -np.inf)  # all three
    offsets = rng.normal(size=(80, 3)) * np.repeat([1.0, 1e-16, 1e-300, 0.0], 20)[:, None]
    judge(np.stack([v0, v1], axis=1), v0 + offsets)


def test_points_on_the_segment_and_its_line():
    # Integer endpoints and t = k / 8: every point below is exactly on the line.
    rng = np.random.default_rng(6)
    v0 = rng.integers(-50, 50, (17 * 6, 3)).astype(float)
    d = rng.integers(-9, 9, (17 * 6, 3)).astype(float)
    d[np.abs(d).sum(axis=1) == 0] = 1.0
    t = np.tile(np.arange(-8, 9) / 8 * 1.5 + 0.5, 6)  # -1 to 2 in steps of 3/16
    p = v0 + t[:, None] * d
    v = np.stack([v0, v0 + d], axis=1)
    judge(v, p)
    on = (t >= 0) & (t <= 1)
    final = [
        _exact.segment(r[:6].reshape(2, 3), r[6:])[0] if c[0] == EXACT else c[1]
        for r, c in zip(_rows(v, p), _certified_rows(_rows(v, p)), strict=True)
    ]
    assert all(f == 0.0 for f in np.asarray(final)[on])
    assert all(f > 0.0 for f in np.asarray(final)[~on])


@pytest.mark.parametrize("end", [0, 1])
def test_region_boundaries_with_perpendicular_offsets(end):
    """A closest point at an endpoint moved by -1e-12, 0, +1e-12 of the segment
    along it, then a perpendicular offset of 0 to 1e6 (the point built from a
    known closest point, as the IPC toolkit's tests are)."""
    rng = np.random.default_rng(7 + end)
    cases = []
    for along in (-1e-12, 0.0, 1e-12):
        for height in (0.0, 2.0**-40, 1e-6, 1.0, 1e6):
            # Exact construction: integer edges and an integer perpendicular.
            v0 = rng.integers(-20, 20, (4, 3)).astype(float)
            d = rng.integers(1, 9, (4, 3)).astype(float) * rng.choice([-1.0, 1.0], (4, 3))
            n = np.cross(d, rng.integers(-5, 5, (4, 3)).astype(float))
            n[np.abs(n).sum(axis=1) == 0] = np.cross(d, [1.0, 0.0, 0.0])[np.abs(n).sum(axis=1) == 0]
            # And a rounded one, of any direction.
            w0 = rng.normal(size=(4, 3))
            e = rng.normal(size=(4, 3))
            m = _perpendicular(rng, e)
            for a, b, h in ((v0, d, n), (w0, e, m)):
                c = a + end * b
                p = c + along * b + height * h
                cases.append((np.stack([a, a + b], axis=1), p))
    judge(np.concatenate([c[0] for c in cases]), np.concatenate([c[1] for c in cases]))


def test_tiny_and_subnormal_coordinates():
    rng = np.random.default_rng(9)
    unit = rng.uniform(-1, 1, (60, 2, 3)), rng.uniform(-2, 2, (60, 3))
    judge(unit[0] * 1e-300, unit[1] * 1e-300)
    # On the subnormal grid: integers times 2^-1074.
    ints = rng.integers(-(2**20), 2**20, (60, 3, 3)).astype(float) * 2.0**-1074
    judge(ints[:, :2], ints[:, 2])
    # A normal segment with subnormal offsets of the point.
    judge(unit[0], unit[0][:, 0] + rng.normal(size=(60, 3)) * 2.0**-1070)


def test_huge_coordinates_and_overflowing_differences():
    rng = np.random.default_rng(10)
    v, p = rng.uniform(-1, 1, (60, 2, 3)), rng.uniform(-1, 1, (60, 3))
    judge(v * 1e300, p * 1e300)
    # Differences of finite coordinates that overflow, with a finite distance:
    # a segment spanning nearly the whole range, and a point near one end.
    big = 1.7e308
    along = rng.uniform(-1, 1, 40) * big
    v = np.array([[[-big, 0.0, 0.0], [big, 0.0, 0.0]]] * 40)
    v[:, :, 1] = rng.uniform(-1, 1, (40, 2)) * 1e300  # a slightly tilted segment
    p = np.stack([along, rng.uniform(-1, 1, 40) * 1e307, rng.uniform(-1, 1, 40) * 1e307], axis=1)
    p[:10, 0] = -big * rng.uniform(0.9, 1.0, 10)  # beyond V0 ...
    p[10:20, 0] = big * rng.uniform(0.9, 1.0, 10)  # ... or V1, differences overflowing
    judge(v, p)
    q = _rows(v, p)
    assert (_certified_rows(q)[:, 0] == EXACT).all()  # the differences overflow: the fallback decides


@pytest.mark.parametrize("offset", [1e4, 1e6, 1e8, 1e10])
def test_far_from_the_origin(offset):
    rng = np.random.default_rng(int(math.log10(offset)))
    shift = rng.uniform(-1, 1, (1, 1, 3)) * offset
    v = rng.uniform(-1, 1, (60, 2, 3)) * 1e-3 + shift
    p = v[:, 0] + rng.normal(size=(60, 3)) * 1e-3
    judge(v, p)


def test_points_far_from_short_segments():
    """The point 2^200 to 2^300 times the segment's length away: no product of
    more than two differences is formed, so no band of distances loses
    precision (the triangle's face test does, about 2^256 to 2^268)."""
    rng = np.random.default_rng(12)
    exponents = np.concatenate([np.arange(200, 301, 5), np.arange(250, 270)])
    n = len(exponents) * 4
    v0 = rng.uniform(-1, 1, (n, 3))
    v = np.stack([v0, v0 + rng.uniform(-1, 1, (n, 3))], axis=1)
    r = np.ldexp(1.0, np.repeat(exponents, 4))[:, None]
    p = v0 + _unit(rng, n) * r
    judge(v, p)
    # A point far from a short segment far from the origin.
    judge(v * 2.0**-250 + 3.0, 3.0 + _unit(rng, n))


def test_distances_far_below_the_query_size():
    """Distances 1e-163 to 1e-150 of a query of size 1, in the interior and
    at an endpoint: the double-double bounds fail below 2^-960 of S^2, and
    an edge's quotient can underflow to a false exact zero (about 1e-162
    here, where the squared distance is the smallest subnormals)."""
    rng = np.random.default_rng(15)
    n = 40
    tilt = 10.0 ** np.concatenate([rng.uniform(-163, -161, n // 2), rng.uniform(-161, -150, n // 2)])
    v = np.zeros((2 * n, 2, 3))
    v[:n, 0, 1], v[:n, 0, 2], v[:n, 1, 1] = rng.uniform(0.5, 2, n), tilt, -rng.uniform(0.5, 2, n)
    v[n:, 0, 0], v[n:, 1] = tilt, rng.uniform(0.5, 1, (n, 3))
    assert judge(v, np.zeros((2 * n, 3))) > n  # the edge cases need the fallback, and are right
    edge = np.array([[[0.0, 1.0, 1.057262777555193e-162], [0.0, -2.0, 0.0]]])
    judge(edge, np.zeros((1, 3)))


def test_window():
    """The largest difference, and whether it is in ``[2^-64, 2^64]``."""
    values = [SAFE_MIN, SAFE_MAX, np.nextafter(SAFE_MIN, 0), np.nextafter(SAFE_MAX, np.inf), 0.0, 1.0, 1e300]
    q = np.zeros((len(values) * 6, 6))
    for i, x in enumerate(values):
        for j in range(6):
            q[6 * i + j, j] = x if j % 2 else -x
            q[6 * i + j, (j + 1) % 6] = x / 4
    got = _window(q)
    for i, x in enumerate(values):
        assert (got[6 * i : 6 * i + 6, 0] == x).all()
        assert (got[6 * i : 6 * i + 6, 1] == (SAFE_MIN <= x <= SAFE_MAX)).all()


def test_the_block_recipe_gives_the_scalar_bits():
    """``window`` + ``robust_local`` + ``finish`` in the window, ``robust`` out
    of it: the same bits as ``robust`` everywhere."""
    rng = np.random.default_rng(13)
    scales = np.repeat([1.0, 1e-30, 1e30, 1e-300, 1e300, 1e-320], 500)[:, None]
    q = rng.normal(size=(len(scales), 9)) * scales
    q[::7, 3:6] = q[::7, 0:3]  # zero-length segments
    q[1::7, 6:] = q[1::7, 0:3]  # points on V0
    got, safe = _block_rows(q)
    assert safe.any() and not safe.all()
    assert np.array_equal(got.view(np.int64), _robust_rows(q).view(np.int64))


def test_the_exact_fallback_is_rare_on_random_queries():
    """Seeded, so that it can fail: well under 1 query in 10,000 needs exact arithmetic."""
    rng = np.random.default_rng(14)
    n = 400_000
    q = np.concatenate([rng.uniform(-1, 1, (n, 6)), rng.uniform(-2, 2, (n, 3))], axis=1)
    assert (_certified_rows(q)[:, 0] == EXACT).sum() < n * 1e-5


# -- generated cases ----------------------------------------------------------------------------------

coordinates = st.one_of(
    st.integers(-3, 3).map(float),  # coincidences and boundaries
    st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False),
    st.floats(-1e-200, 1e-200, allow_nan=False, allow_infinity=False),
    st.floats(-1e300, 1e300, allow_nan=False, allow_infinity=False),
)


@st.composite
def segment_queries(draw):
    """A segment and a point, the point often built from the segment: on its
    line at a dyadic parameter, or one of its endpoints, or a copy of a
    vertex as the other."""
    dim = draw(st.sampled_from([2, 3]))
    point3 = st.lists(coordinates, min_size=dim, max_size=dim)
    v0, v1, p = draw(point3), draw(point3), draw(point3)
    how = draw(st.sampled_from(["free", "line", "endpoint", "degenerate"]))
    if how == "line":
        t = draw(st.integers(-16, 32)) / 16
        p = [a + t * (b - a) for a, b in zip(v0, v1, strict=True)]
    elif how == "endpoint":
        p = list(draw(st.sampled_from([v0, v1])))
    elif how == "degenerate":
        v1 = list(v0)
    vertices, point = np.array([v0, v1]), np.array(p)
    if not (np.isfinite(vertices).all() and np.isfinite(point).all()):
        point = np.zeros(dim)
    return vertices, point


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(segment_queries())
def test_generated_queries(query):
    vertices, point = query
    judge(vertices[None], point[None])


# -- the reference itself ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("point", "sqr", "feature", "t"),
    [
        ([-1, 1, 0], 2, Feature.VERTEX0, 0),
        ([0, 3, 4], 25, Feature.VERTEX0, 0),
        ([1, 0, 2], 4, Feature.EDGE01, Fraction(1, 4)),
        ([4, 0, 0], 0, Feature.VERTEX1, 1),
        ([6, 0, 1], 5, Feature.VERTEX1, 1),
        ([3, 0, 0], 0, Feature.EDGE01, Fraction(3, 4)),
    ],
)
def test_reference_regions(point, sqr, feature, t):
    r = exact.segment_closest([[0, 0, 0], [4, 0, 0]], point)
    assert (r.sqr_distance, r.feature, r.t, r.features) == (sqr, feature, t, {feature})
    assert r.point == tuple(Fraction(4) * t if k == 0 else Fraction(0) for k in range(3))


def test_reference_degenerate_and_dimensions():
    r = exact.segment_closest([[1.5, -2.0], [1.5, -2.0]], [4.5, 2.0])
    assert (r.sqr_distance, r.feature, r.features, r.t) == (25, Feature.VERTEX0, {0, 1}, 0)
    assert float(exact.segment_distance([[0.0], [2.0]], [-3.0])) == 3.0
    assert float(exact.segment_scale([[0, 0], [4, 0]], [0, -3])) == 5.0
    with pytest.raises(ValueError, match="vertices"):
        exact.segment_closest([[0, 0, 0]], [0, 0, 0])
    with pytest.raises(ValueError, match="point"):
        exact.segment_closest([[0, 0, 0], [1, 0, 0]], [0, math.inf, 0])


@settings(max_examples=200, deadline=None)
@given(segment_queries())
def test_reference_is_the_projection(query):
    """``X`` on the segment at ``t``, and ``(P - X) . (V - X) <= 0`` for both
    endpoints: ``X`` is the projection onto the segment."""
    vertices, point = query
    r = exact.segment_closest(vertices, point)
    v0, v1 = ([Fraction(float(c)) for c in row] for row in vertices)
    p = [Fraction(float(c)) for c in point]
    assert 0 <= r.t <= 1
    assert list(r.point) == [a + r.t * (b - a) for a, b in zip(v0, v1, strict=True)]
    assert r.sqr_distance == sum((x - c) ** 2 for x, c in zip(r.point, p, strict=True))
    for v in (v0, v1):
        assert sum((c - x) * (w - x) for c, x, w in zip(p, r.point, v, strict=True)) <= 0
    assert r.feature == min(r.features)
    assert (r.feature == Feature.VERTEX0) == (r.t == 0)
