"""Segments, points and rounded solids against the exact reference, through the public shapes.

``Segment`` and ``Point`` answer as their kernels do (``tests/test_segment_kernels.py``
checks those case by case); here the facades' paths (one point, pairs, many
points against one shape), and the rounded solids built on every kind of
core: ``robust`` within ``8 eps S + 2^-1075`` with ``S = S_core + r``,
``certified`` within one ulp of the exact ``d* - r`` (near the surface too,
where the subtraction cancels), closest points on the rounded surface.
"""

import math
import zlib

import mpmath
import numpy as np
import pytest

import proximity
from proximity.testing import exact
from tests import checks

EPS = 2.0**-52
METHODS = ["robust", "certified"]


def _exact_core(kind, shape_args, point):
    """``(d*, S)`` of one core query, as mpf."""
    if kind == "triangle":
        return exact.triangle_distance(shape_args, point), exact.triangle_scale(shape_args, point)
    if kind == "segment":
        return exact.segment_distance(shape_args, point), exact.segment_scale(shape_args, point)
    if kind == "point":
        v = np.stack([shape_args, shape_args])
        return exact.segment_distance(v, point), exact.segment_scale(v, point)
    center, normal, radius = shape_args
    distance = exact.disk_distance if kind == "disk" else exact.circle_distance
    return distance(center, normal, radius, point), exact.circle_scale(center, radius, point)


def _cores(kind, rng, n, scale=1.0, offset=0.0):
    """``n`` random cores of ``kind``: the shape (a batch) and each member's arguments."""
    if kind == "triangle":
        v = rng.normal(size=(n, 3, 3)) * scale + offset
        return proximity.Triangle(v), list(v)
    if kind == "segment":
        v = rng.normal(size=(n, 2, 3)) * scale + offset
        return proximity.Segment(v), list(v)
    if kind == "point":
        v = rng.normal(size=(n, 3)) * scale + offset
        return proximity.Point(v), list(v)
    c = rng.normal(size=(n, 3)) * scale + offset
    u = rng.normal(size=(n, 3))
    r = rng.random(n) * scale
    cls = proximity.Disk if kind == "disk" else proximity.Circle
    return cls(c, u, r), list(zip(c, u, r, strict=True))


KINDS = ["triangle", "segment", "point", "disk", "circle"]


def _check_rounded(kind, args, radius, point, method, result, signed):
    d_core, s_core = _exact_core(kind, args, point)
    with mpmath.workprec(exact.PREC):
        e_star = d_core - exact.to_mpf(float(radius))
        scale = s_core + exact.to_mpf(float(radius))
        where = f"{kind} {args!r}, radius {radius!r}, point {point.tolist()!r}, {method}"
        if method == "certified":
            assert exact.ulps(float(signed), e_star) < 1.0, where
            expected = max(e_star, 0)
            assert exact.ulps(float(result.distance), expected) < 1.0, where
        else:
            assert exact.error_in_units(float(signed), e_star, scale) <= 8.0, where
            assert exact.error_in_units(float(result.distance), max(e_star, 0), scale) <= 8.0, where
        assert float(result.distance) == max(float(signed), 0.0), where
        # The closest point is on the rounded surface: r from the core.
        on = _exact_core(kind, args, np.asarray(result.point))[0]
        allowed = 8 * EPS * scale + checks.point_slack(result.point) * 4
        assert abs(on - exact.to_mpf(float(radius))) <= allowed, (mpmath.nstr(on, 20), where)
        if float(result.distance) > 0:
            gap = checks.exact_norm(point, result.point) - exact.to_mpf(float(result.distance))
            assert abs(gap) <= allowed, where


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize(
    "scale, offset",
    [(1.0, 0.0), (1e-200, 0.0), (1e200, 0.0), (1e-3, 1e10)],
    ids=["unit", "tiny", "huge", "far"],
)
def test_rounded_solids_against_the_exact_reference(kind, method, scale, offset):
    # A seed of its own per case, the same in every run (hash() of a string is not).
    rng = np.random.default_rng(zlib.crc32(repr((kind, method, scale)).encode()))
    n = 40
    core, args = _cores(kind, rng, n, scale, offset)
    radius = rng.random(n) * 2 * scale
    solid = core.inflated(radius)
    points = rng.normal(size=(n, 3)) * 2 * scale + offset
    # Points within rounding of the surface (d - r cancels), from the core's own closest points.
    near = core.closest_point(points)
    direction = points - near.point
    length = np.linalg.norm(direction, axis=1, keepdims=True)
    surface = near.point + direction / np.where(length > 0, length, 1) * radius[:, None]
    points[::2] = surface[::2] * (1 + rng.choice([-1e-15, 0.0, 1e-15], size=(n // 2, 1)))
    r = solid.closest_point(points, method=method)
    signed = solid.signed_distance(points, method=method)
    assert np.array_equal(solid.distance(points, method=method), r.distance)
    for k in range(n):
        _check_rounded(kind, args[k], radius[k], points[k], method, r[k], signed[k])
        single = proximity.Inflated(_member(core, k), radius[k])
        assert single.signed_distance(points[k], method=method) == signed[k]


def _member(core, k):
    if isinstance(core, proximity.Point):
        return proximity.Point(core.position[k])
    if isinstance(core, (proximity.Triangle, proximity.Segment)):
        return type(core)(core.vertices[k])
    return type(core)(core.center[k], core.normal[k], core.radius[k])


@pytest.mark.parametrize("method", METHODS)
def test_points_on_the_core_reach_the_surface_along_its_normal(method):
    tri = proximity.Triangle([[0, 0, 0], [2, 0, 0], [0, 2, 1]])
    pill = proximity.Capsule([[0, 0, 0], [0, 0, 4]], 0.5)
    ball = proximity.Sphere([1, 2, 3], 0.25)
    cases = [
        (tri.inflated(0.5), [0.5, 0.5, 0.25], -0.5),
        (pill, [0, 0, 2], -0.5),
        (pill, [0, 0, 4], -0.5),
        (ball, [1, 2, 3], -0.25),
    ]
    for solid, p, depth in cases:
        r = solid.closest_point(p, method=method)
        assert solid.signed_distance(p, method=method) == depth
        assert float(r.distance) == 0.0
        assert math.isclose(float(np.linalg.norm(np.asarray(r.point) - p)), -depth, rel_tol=1e-15)
        assert float(solid.core.distance(r.point)) == pytest.approx(-depth, rel=1e-15)


@pytest.mark.parametrize("scale", [1.0, 1e-200, 1e200])
def test_a_point_near_the_core_reaches_the_surface_by_the_radius(scale):
    # The surface point follows P - c normalised by its own length: an error
    # of c across the plane (a few ulps of the coordinates) moves the point by
    # as much, not by r / d times as much.
    disk = proximity.Disk(np.array([3.0, -2.0, 1.0]) * scale, [1, 2, 2], 1.5 * scale)
    solid = disk.inflated(4.0 * scale)
    rng = np.random.default_rng(8)
    on = disk.closest_point(rng.normal(size=(200, 3)) * scale + disk.center).point
    points = on + np.array([1, 2, 2]) / 3 * 1e-3 * 4.0 * scale * rng.choice([-1, 1], size=(200, 1))
    for method in METHODS:
        r = solid.closest_point(points, method=method)
        for k in range(len(points)):
            d_core, s_core = _exact_core("disk", (disk.center, disk.normal, disk.radius), r.point[k])
            allowed = 8 * EPS * (s_core + 4.0 * scale) + checks.point_slack(r.point[k]) * 4
            assert abs(d_core - exact.to_mpf(4.0 * scale)) <= allowed, (k, method)


@pytest.mark.parametrize("method", METHODS)
def test_a_spindle_torus_sends_points_near_the_axis_to_its_cusps(method):
    # A circle of radius 1 rounded by 2: the balls of opposite sides overlap
    # across the axis, whose surface meets it at the cusps (0, 0, +-sqrt(3)).
    # From a point near the axis the path away from the nearest circle point
    # crosses the axis; the nearest surface point is the cusp on its side.
    spindle = proximity.Circle([0, 0, 0], [0, 0, 1], 1.0).inflated(2.0)
    points = np.array([[0.1, 0.0, 0.2], [0.0, -0.05, -0.5], [0.8, 0.0, 0.1], [1.5, 0.0, 0.1]])
    r = spindle.closest_point(points, method=method)
    cusp = math.sqrt(3.0)
    np.testing.assert_allclose(r.point[0], [0, 0, cusp], atol=4e-16)
    np.testing.assert_allclose(r.point[1], [0, 0, -cusp], atol=4e-16)
    np.testing.assert_allclose(r.normal[:2], [[0, 0, 1], [0, 0, -1]])
    # From (0.8, 0, 0.1) too: 2 from (1, 0, 0) along (-0.2, 0, 0.1) is past the axis.
    np.testing.assert_allclose(r.point[2], [0, 0, cusp], atol=4e-16)
    # Outside the circle, the surface point 2 from the nearest circle point.
    length = math.hypot(0.5, 0.1)
    np.testing.assert_allclose(r.point[3], [1 + 2 * 0.5 / length, 0, 2 * 0.1 / length])
    # Every one on the surface: 2 from the circle.
    np.testing.assert_allclose(spindle.core.distance(r.point), 2.0, rtol=1e-15)
    assert (np.asarray(r.distance) == 0).all()


def test_named_forms_are_their_cores_inflated():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(50, 3))
    c, v = rng.normal(size=(4, 3)), rng.normal(size=(4, 2, 3))
    assert np.array_equal(
        proximity.Sphere(c, [0.5, 1, 0, 2]).distance(points[:, None]),
        proximity.Point(c).inflated([0.5, 1, 0, 2]).distance(points[:, None]),
    )
    assert np.array_equal(
        proximity.Capsule(v, 0.3).distance(points[:, None]),
        proximity.Segment(v).inflated(0.3).distance(points[:, None]),
    )
    assert proximity.Sphere(c[0], 1.0).inflated(0.5).radius == 1.5
    assert np.array_equal(
        proximity.Point(c).distance(points[:, None]), proximity.Point(c).inflated(0).distance(points[:, None])
    )


@pytest.mark.parametrize(
    "build, error, match",
    [
        (lambda: proximity.Sphere([0, 0, 0], -1.0), ValueError, r"radius must be >= 0; got -1.0"),
        (lambda: proximity.Sphere([0, 0, 0], np.nan), ValueError, r"radius must be finite"),
        (lambda: proximity.Capsule([[0, 0, 0], [1, 0, 0]], np.inf), ValueError, r"radius must be finite"),
        (
            lambda: proximity.Capsule([[0, 0, 0]], 1.0),
            ValueError,
            r"vertices must have shape \(\.\.\., 2, D\)",
        ),
        (lambda: proximity.Segment([[0, 0, 0], [np.nan, 0, 0]]), ValueError, r"vertices must be finite"),
        (
            lambda: proximity.Segment(np.zeros((3, 3))),
            ValueError,
            r"vertices must have shape \(\.\.\., 2, D\)",
        ),
        (lambda: proximity.Point([[0, 0, 0, 0]]), ValueError, r"position must have shape \(\.\.\., D\)"),
        (
            lambda: proximity.Segment(np.zeros((4, 2, 3))).inflated(np.ones(3)),
            ValueError,
            r"core \(4,\), radius",
        ),
        (lambda: proximity.Inflated([[0, 0, 0]], 1.0), TypeError, r"core must be a proximity shape"),
    ],
)
def test_bad_input_names_the_argument(build, error, match):
    with pytest.raises(error, match=match):
        build()


def test_segments_have_no_eberly_method():
    with pytest.raises(ValueError, match=r"method must be one of \('robust', 'certified'\); got 'eberly'"):
        proximity.Segment([[0, 0, 0], [1, 0, 0]]).distance([0, 1, 0], method="eberly")


def test_compiled_surface_points_have_the_numpy_forms_bits():
    """The compiled rows of 3D surface points against the NumPy form (any dimension), bit for
    bit, on rows with NaNs, infinities, zeros, subnormals and points on or next to the core."""
    from proximity.numerics import rounding

    rng = np.random.default_rng(7)
    n = 20_000
    specials = np.array([np.nan, np.inf, -np.inf, 0.0, -0.0, 5e-324, 1e308, -1e308, 1e-300])

    def column(shape):
        x = rng.normal(size=shape) * 10.0 ** rng.integers(-20, 20, size=shape)
        mask = rng.random(shape) < 0.05
        x[mask] = rng.choice(specials, size=mask.sum())
        return x

    p, c = column((n, 3)), column((n, 3))
    c[: n // 10] = p[: n // 10]  # on the core
    c[n // 10 : n // 5] = p[n // 10 : n // 5] * (1 + 1e-16 * rng.normal(size=(n // 10, 3)))
    with np.errstate(over="ignore", invalid="ignore"):
        d = np.linalg.norm(p - c, axis=-1)
    # Not the rows' own distance: rows with NaN coordinates and a finite d.
    d[n // 5 : n // 2] = np.abs(column(n // 2 - n // 5))
    r = np.abs(column(n))
    r[rng.random(n) < 0.1] = 0.0
    point, lost = np.empty((n, 3)), np.empty(n, np.bool_)
    rounding.surface_rows(p, c, d, r, point, lost)
    expected, expected_lost = rounding.surface_numpy(p, c, d, r)
    assert lost.any() and not lost.all()
    np.testing.assert_array_equal(lost, expected_lost)
    assert (np.isnan(point) == np.isnan(expected)).all()
    finite = ~np.isnan(expected)
    assert (point[finite].view(np.int64) == expected[finite].view(np.int64)).all()
