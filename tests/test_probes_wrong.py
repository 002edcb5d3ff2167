"""Wrong answers found by probing: each a short reproducer of the case that was wrong."""

import numpy as np
import pytest

import proximity
from proximity.testing import meshes

METHODS = ["robust", "certified"]
SPHERE = meshes.icosphere(2)  # 320 faces


@pytest.mark.parametrize("method", METHODS)
def test_rounded_meshes_whose_cores_cross_are_as_deep_as_their_radii(method):
    # A certain crossing of the cores ended the search with d - r = 0, the
    # radii forgotten: 0.0 for every order, inflated side and method.
    a = proximity.TriangleMesh(*SPHERE)
    b = proximity.TriangleMesh(SPHERE[0] + [0.5, 0.3, 0.1], SPHERE[1])
    assert proximity.distance(a, b, method=method) == 0.0
    moved = np.eye(4)
    moved[:3, 3] = [0.5, 0.3, 0.1]
    for x, y, depth in [
        (a.inflated(0.1), b, -0.1),
        (b, a.inflated(0.1), -0.1),
        (a.inflated(0.1), b.inflated(0.2), -(0.1 + 0.2)),
        (a.inflated(0.25), a.transformed(moved), -0.25),
        (a.transformed(moved), a.inflated(0.25), -0.25),
        (proximity.Capsule([[0.0, 0.0, 0.5], [0.0, 0.0, 1.5]], 0.125), a, -0.125),
        (a, proximity.Capsule([[0.0, 0.0, 0.5], [0.0, 0.0, 1.5]], 0.125), -0.125),
    ]:
        assert proximity.signed_distance(x, y, method=method) == depth
        r = proximity.closest_points(x, y, method=method)
        assert r.distance == 0.0
    # A sphere whose centre lies on the surface: its depth is its radius, to the centre's rounding.
    centre = SPHERE[0][0]
    for x, y in ((proximity.Sphere(centre, 0.125), a), (a, proximity.Sphere(centre, 0.125))):
        assert abs(proximity.signed_distance(x, y, method=method) + 0.125) <= 1e-15


@pytest.mark.parametrize("method", METHODS)
def test_separated_rounded_meshes_keep_their_answers(method):
    a = proximity.TriangleMesh(*SPHERE)
    b = proximity.TriangleMesh(SPHERE[0] + [2.5, 0.0, 0.0], SPHERE[1])
    d = proximity.distance(a, b, method=method)
    assert 0.4 < d < 0.6
    assert proximity.signed_distance(a.inflated(0.125), b, method=method) == d - 0.125
    assert proximity.signed_distance(a, b.inflated(0.125), method=method) == d - 0.125


def _overlapping_boxes():
    """Two boxes as one closed manifold mesh that intersects itself: not a solid."""
    first = meshes.box([0, 0, 0], [2, 2, 2])
    second = meshes.box([1, 0.5, 0.5], [3, 1.5, 1.5])
    return proximity.TriangleMesh(np.vstack([first[0], second[0]]), np.vstack([first[1], second[1] + 8]))


@pytest.mark.parametrize("before", [[], ["auto"], ["pseudonormal"], ["auto", "pseudonormal"]])
def test_pseudonormal_signs_of_a_mesh_that_is_not_a_solid_warn_and_are_not_certain_at_every_call(before):
    # The warning was once per mesh, spent by whichever call came first, and
    # the pseudonormal's sides were certain: (2.1, 1, 1), inside the second
    # box by the winding number, was outside, certain, without a warning.
    import warnings

    mesh = _overlapping_boxes()
    assert not mesh.validity.solid
    points = [[2.1, 1.0, 1.0], [1.9, 1.9, 1.9]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for sign in before:
            mesh.signed(points, sign=sign)
    with pytest.warns(RuntimeWarning, match="pseudonormal signs can be wrong") as caught:
        r = mesh.signed(points, sign="pseudonormal")
    assert len(caught) == 1
    assert not r.certain.any()
    truth = mesh.signed(points, sign="winding")
    assert truth.certain.all() and truth.contains.tolist() == [True, True]
    for call in (
        lambda: mesh.signed_distance(points, sign="pseudonormal"),
        lambda: mesh.contains(points, sign="pseudonormal"),
        lambda: mesh.sdf_grid([0, 0, 0], [3, 2, 2], (9, 9, 9), sign="pseudonormal"),
    ):
        with pytest.warns(RuntimeWarning, match="pseudonormal signs can be wrong") as caught:
            call()
        assert len(caught) == 1


def test_pseudonormal_signs_of_a_solid_stay_certain_and_silent():
    import warnings

    mesh = proximity.TriangleMesh(*meshes.box([0, 0, 0], [2, 2, 2]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = mesh.signed([[1.0, 1.0, 1.9], [1.0, 1.0, 2.1]], sign="pseudonormal")
    assert r.certain.tolist() == [True, True] and r.contains.tolist() == [True, False]


def _crossings(rng, n, scale):
    """``n`` segments ``(n, 2, 3)`` and triangles ``(n, 3, 3)`` at ``scale``, each segment crossing
    its triangle's open face (checked in rational arithmetic)."""
    from proximity.numerics.orient import orient3d_fraction as orient

    triangles = rng.normal(size=(n, 3, 3)) * scale
    inner = np.einsum("ni,nij->nj", rng.dirichlet([1.0, 1.0, 1.0], size=n), triangles)
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    direction = normal / np.linalg.norm(normal, axis=1)[:, None] + 0.5 * rng.normal(size=(n, 3))
    reach = rng.uniform(0.2, 1.0, size=(n, 2, 1)) * scale
    segments = np.stack([inner - reach[:, 0] * direction, inner + reach[:, 1] * direction], axis=1)
    for (a0, a1), (v0, v1, v2) in zip(segments[:50], triangles[:50], strict=True):
        assert orient(v0, v1, v2, a0) * orient(v0, v1, v2, a1) == -1
        assert orient(a0, a1, v0, v1) == orient(a0, a1, v1, v2) == orient(a0, a1, v2, v0) != 0
    return segments, triangles


def _on_segment(point, segments, scale):
    """Whether each point is within rounding of its segment (all ``(n, ...)``)."""
    e = segments[:, 1] - segments[:, 0]
    s = np.einsum("ij,ij->i", point - segments[:, 0], e) / np.einsum("ij,ij->i", e, e)
    off = point - (segments[:, 0] + s[:, None] * e)
    return (np.linalg.norm(off, axis=1) <= 1e-14 * scale) & (s >= 0.0) & (s <= 1.0)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_robust_segments_crossing_triangles_are_at_distance_zero_with_one_point(scale):
    # The crossing candidate's point is rounded off the plane: 2,000 of 2,000
    # crossings got a distance of 1e-17 to 7e-16 (times the scale) and two points.
    rng = np.random.default_rng(7)
    segments, triangles = _crossings(rng, 400, scale)
    batch = proximity.closest_points(proximity.Segment(segments), proximity.Triangle(triangles))
    assert (batch.distance == 0.0).all() and (batch.point_a == batch.point_b).all()
    assert _on_segment(batch.point_a, segments, scale).all()
    distances = proximity.distance(proximity.Segment(segments), proximity.Triangle(triangles))
    np.testing.assert_array_equal(distances, 0.0)
    swapped = proximity.closest_points(proximity.Triangle(triangles), proximity.Segment(segments))
    assert (swapped.distance == 0.0).all()
    np.testing.assert_array_equal(swapped.point_a, batch.point_b)
    for k in range(20):
        one = proximity.closest_points(proximity.Segment(segments[k]), proximity.Triangle(triangles[k]))
        assert one.distance == 0.0 and (one.point_a == one.point_b).all()
        np.testing.assert_array_equal(one.point_a, batch.point_a[k])
        assert proximity.distance(proximity.Segment(segments[k]), proximity.Triangle(triangles[k])) == 0.0


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_robust_segments_and_capsules_crossing_a_mesh_are_at_distance_zero(scale):
    mesh = proximity.TriangleMesh(SPHERE[0] * scale, SPHERE[1])
    rng = np.random.default_rng(11)
    out = rng.normal(size=(60, 3))
    out /= np.linalg.norm(out, axis=1)[:, None]
    # From near the centre to beyond the sphere: each crosses the surface.
    segments = np.stack([0.3 * scale * rng.uniform(-1, 1, size=(60, 3)), 1.5 * scale * out], axis=1)
    for a, b in ((proximity.Segment(segments), mesh), (mesh, proximity.Segment(segments))):
        r = proximity.closest_points(a, b)
        assert (r.distance == 0.0).all() and (r.point_a == r.point_b).all()
        assert (proximity.distance(a, b) == 0.0).all()
    radius = 0.01 * scale
    capsules = proximity.Capsule(segments, radius)
    assert (proximity.signed_distance(capsules, mesh) == -radius).all()
    assert (proximity.signed_distance(mesh, capsules) == -radius).all()
    for k in range(10):
        one = proximity.Capsule(segments[k], radius)
        assert proximity.distance(one, mesh) == 0.0 and proximity.signed_distance(one, mesh) == -radius
        assert proximity.distance(proximity.Segment(segments[k]), mesh) == 0.0


def test_robust_segments_that_miss_a_triangle_by_a_hair_keep_their_distance():
    # Beside an edge by 1e-13, and ending 1e-13 short of the face: not crossings.
    triangle = proximity.Triangle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    beside = proximity.Segment([[0.5, -1e-13, -1.0], [0.5, -1e-13, 1.0]])
    short = proximity.Segment([[0.25, 0.25, -1.0], [0.25, 0.25, -1e-13]])
    for segment in (beside, short):
        for method in METHODS:
            d = proximity.distance(segment, triangle, method=method)
            assert d == pytest.approx(1e-13, rel=1e-3)


@pytest.mark.parametrize("band", [None, 1.0])
def test_a_grid_whose_corners_differ_by_more_than_the_float_range_has_its_points(band):
    # np.linspace(-1e308, 1e308, n) overflows in upper - lower: its points were NaN, and so were
    # 26 of the 27 signed distances, without a word.
    import warnings

    mesh = proximity.TriangleMesh(*meshes.box([0, 0, 0], [1, 1, 1]))
    corners = [
        ([-1e308] * 3, [1e308] * 3, (3, 3, 3)),
        ([-1.7e308, 0, -1.7e308], [1.7e308, 1, 1e308], (5, 2, 4)),
    ]
    for low, high, shape in corners:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            grid = mesh.sdf_grid(low, high, shape, max_distance=band)
        axes = [2.0 * np.linspace(lo / 2, hi / 2, n) for lo, hi, n in zip(low, high, shape, strict=True)]
        assert [a[0] for a in axes] == low and [a[-1] for a in axes] == high
        points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
        expected = np.asarray(mesh.signed_distance(points.reshape(-1, 3))).reshape(shape)
        if band is not None:
            expected = np.where(np.abs(expected) > band, np.copysign(np.inf, expected), expected)
        assert not np.isnan(grid).any()
        np.testing.assert_array_equal(grid, expected)
    # Corners whose difference is finite keep np.linspace's points.
    low, high = [-1e307, 0.0, 0.0], [1e307, 1.0, 1.0]
    grid = mesh.sdf_grid(low, high, (3, 2, 2))
    axes = [np.linspace(lo, hi, n) for lo, hi, n in zip(low, high, (3, 2, 2), strict=True)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    np.testing.assert_array_equal(grid.reshape(-1), mesh.signed_distance(points))


def test_rounding_a_rounded_shape_past_the_float_range_is_refused_naming_the_radius():
    # 1e308 + 1e308 is inf: Sphere(c, 1e308).inflated(1e308) took an infinite radius, which
    # Sphere(c, inf) refuses.
    message = r"radius must be finite: rounding a shape of radius 1e\+308 by 1e\+308 gives inf"
    with pytest.raises(ValueError, match=message):
        proximity.Sphere([0.0, 0.0, 0.0], 1e308).inflated(1e308)
    with pytest.raises(ValueError, match=message + r" at index \(1,\)"):
        proximity.Sphere([0.0, 0.0, 0.0], [1.0, 1e308]).inflated(1e308)
    with pytest.raises(ValueError, match=message):  # through a posed view, whose queries add them
        proximity.Sphere([0.0, 0.0, 0.0], 1e308).transformed(np.eye(4)).inflated(1e308)
    with pytest.raises(ValueError, match="radius must be finite; got inf"):
        proximity.Sphere([0.0, 0.0, 0.0], np.inf)
    assert proximity.Sphere([0.0, 0.0, 0.0], 1e308).inflated(7e307).radius == 1e308 + 7e307
