"""Shapes far smaller than their distance from the point, against the exact reference.

``robust`` scales the differences ``V - P`` (``P - C`` for a circle or a disk)
so that the largest is about 1.  The shape's own terms can be far smaller:
the square of a triangle's normal is a fourth power of its edges, and a
circle's radial part can be shorter than ``2^-511`` of the radius.  The
sweeps below put the point ``2^200`` to ``2^300`` triangle sizes away (and
the circle's radius ``2^500`` to ``2^546`` times the point's offset from its
center), at every integer exponent, in two frames: the shape near the origin
and the point far (the scalar path, which scales), and the point near with
the shape tiny (the safe window, where batches run their SIMD loop).

The point lies far along one coordinate axis, so that the differences keep
the triangle's extent in the other two and lose it along the axis: the
triangle the method sees is flattened across the axis, and the point's
shadow falls inside it (three times in four) or near it.
"""

import mpmath
import numpy as np
import pytest

import proximity
from proximity.testing import exact
from tests.checks import BOUND, check_round, check_triangle

EXPONENTS = range(200, 301)
CIRCLE_EXPONENTS = range(500, 546)
FRAMES = ("far point", "tiny shape")
# A triangle's size when many points at every exponent meet one shape in the
# safe window (``2^-62`` to ``2^39`` away): its normal's square, whatever the
# distance, is subnormal there.
TINY = 2.0**-262


def _frame(frame, k):
    """The factor of every coordinate: 1, or ``2^-k`` to bring the point near."""
    return 1.0 if frame == "far point" else 2.0**-k


def _far_point(rng, vertices, k):
    """A point ``2^k`` to ``2^(k+1)`` away along a random axis, its shadow
    on the triangle (three times in four) or near it."""
    point = rng.dirichlet([1.0, 1.0, 1.0]) @ vertices if rng.random() < 0.75 else rng.uniform(-1, 1, 3)
    point[rng.integers(3)] = rng.choice([-1.0, 1.0]) * rng.uniform(1, 2) * 2.0**k
    return point


def _triangle_cases(frame, seed, per_exponent):
    rng = np.random.default_rng(seed)
    vertices, points = [], []
    for k in EXPONENTS:
        for _ in range(per_exponent):
            v = rng.uniform(-1, 1, (3, 3))
            vertices.append(v * _frame(frame, k))
            points.append(_far_point(rng, v, k) * _frame(frame, k))
    return np.array(vertices), np.array(points)


@pytest.mark.parametrize("frame", FRAMES)
def test_triangles_keep_the_bound_from_2_200_to_2_300_sizes_away(frame):
    vertices, points = _triangle_cases(frame, 1, 2)
    batch = proximity.Triangle(vertices).closest_point(points)
    for i in range(len(points)):
        check_triangle(vertices[i], points[i], proximity.Triangle(vertices[i]).closest_point(points[i]))
        check_triangle(vertices[i], points[i], batch[i])


@pytest.mark.parametrize("frame", FRAMES)
def test_many_points_against_one_triangle_keep_the_bound(frame):
    size = 1.0 if frame == "far point" else TINY
    rng = np.random.default_rng(2)
    for _ in range(2):
        v = rng.uniform(-1, 1, (3, 3))
        points = np.array([_far_point(rng, v, k) for k in EXPONENTS]) * size
        result = proximity.Triangle(v * size).closest_point(points)
        for i in range(len(points)):
            check_triangle(v * size, points[i], result[i])


def _error_within_bound(d, d_exact, scale, where):
    with mpmath.workprec(exact.PREC):
        error = abs(exact.to_mpf(float(d)) - exact.to_mpf(d_exact))
        limit = BOUND * exact.to_mpf(exact.EPS) * exact.to_mpf(scale)
        assert error <= limit, f"{where}: error {mpmath.nstr(error, 5)} > {mpmath.nstr(limit, 5)}"


@pytest.mark.parametrize("frame", FRAMES)
def test_meshes_and_scenes_keep_the_bound_and_answer_as_their_nearest_face(frame):
    """A soup of four faces and a point at every exponent, its shadow on one of
    them; a scene adds a unit disk at the origin, as far as the faces."""
    rng = np.random.default_rng(3)
    vertices = rng.uniform(-1, 1, (12, 3))
    faces = np.arange(12).reshape(4, 3)
    points = np.array([_far_point(rng, vertices[faces[rng.integers(4)]], k) for k in EXPONENTS])
    size = 1.0 if frame == "far point" else TINY
    vertices, points = vertices * size, points * size
    disk = proximity.Disk([0.0, 0.0, 0.0], rng.normal(size=3), size)
    per_face = proximity.Triangle(vertices[faces]).closest_point(points[:, None])
    per_disk = disk.closest_point(points)
    both = np.concatenate([per_face.distance, per_disk.distance[:, None]], axis=1)
    exact_faces = [[exact.triangle_distance(vertices[f], p) for f in faces] for p in points]
    exact_disk = [exact.disk_distance(disk.center, disk.normal, disk.radius, p) for p in points]
    for broad_phase in ("brute", "bvh"):
        mesh = proximity.TriangleMesh(vertices, faces, broad_phase=broad_phase)
        scene = proximity.Scene([mesh, disk], broad_phase=broad_phase)
        r = mesh.closest_point(points)
        s = scene.closest_point(points)
        np.testing.assert_array_equal(r.distance, per_face.distance.min(axis=1))
        np.testing.assert_array_equal(r.face, per_face.distance.argmin(axis=1))
        np.testing.assert_array_equal(s.distance, both.min(axis=1))
        np.testing.assert_array_equal(s.primitive, both.argmin(axis=1))
        for i, p in enumerate(points):
            scale = max(exact.triangle_scale(vertices[f], p) for f in faces)
            where = f"{broad_phase}, point {p.tolist()!r}"
            _error_within_bound(r.distance[i], min(exact_faces[i]), scale, f"mesh, {where}")
            check_triangle(vertices[faces[r.face[i]]], p, r[i])
            scene_scale = max(scale, exact.circle_scale(disk.center, disk.radius, p))
            nearest = min(*exact_faces[i], exact_disk[i])
            _error_within_bound(s.distance[i], nearest, scene_scale, f"scene, {where}")


def _circle_cases(frame, seed):
    """A circle of radius ``2^k`` to ``2^(k+1)`` at every exponent, and a point
    about 1 from its center: ``2^-k`` of the radius from its axis."""
    rng = np.random.default_rng(seed)
    centers, normals, radii, points = [], [], [], []
    for k in CIRCLE_EXPONENTS:
        for _ in range(2):
            c = rng.uniform(-1, 1, 3)
            n = rng.normal(size=3)
            if rng.random() < 0.5:
                n = np.zeros(3)
                n[rng.integers(3)] = rng.choice([-1.0, 1.0])
            f = _frame(frame, k)
            centers.append(c * f)
            normals.append(n)
            radii.append(rng.uniform(1, 2) * 2.0**k * f)
            points.append((c + rng.normal(size=3)) * f)
    return np.array(centers), np.array(normals), np.array(radii), np.array(points)


ROUND_METHODS = ("robust", "certified")


@pytest.mark.parametrize("method", ROUND_METHODS)
@pytest.mark.parametrize("frame", FRAMES)
def test_circles_and_disks_keep_their_rim_point_on_the_rim(frame, method):
    """The point is 2^-500 to 2^-546 of the radius from the axis: the closest
    point of a circle stays on it, one point at a time and in a batch."""
    c, n, r, p = _circle_cases(frame, 4)
    for kind, shape in (("circle", proximity.Circle), ("disk", proximity.Disk)):
        batch = shape(c, n, r).closest_point(p, method=method)
        for i in range(len(p)):
            single = shape(c[i], n[i], r[i]).closest_point(p[i], method=method)
            check_round(kind, c[i], n[i], r[i], p[i], single)
            check_round(kind, c[i], n[i], r[i], p[i], batch[i])
            if method == "certified":
                reference = exact.circle_distance if kind == "circle" else exact.disk_distance
                assert exact.ulps(float(single.distance), reference(c[i], n[i], r[i], p[i])) < 1.0


@pytest.mark.parametrize("method", ROUND_METHODS)
@pytest.mark.parametrize("frame", FRAMES)
def test_many_points_against_one_circle_keep_its_rim_point_on_the_rim(frame, method):
    # The radius is 2^520 (out of the safe window) or 1 (in it, for the SIMD loop).
    radius = 2.0**520 if frame == "far point" else 1.0
    center = np.array([0.25, -0.5, 0.75]) * radius * 2.0**-500
    normal = np.array([0.3, -0.8, 0.5])
    rng = np.random.default_rng(5)
    k = np.repeat(np.array(CIRCLE_EXPONENTS, float), 2)
    points = center + rng.normal(size=(len(k), 3)) * radius * 2.0 ** -k[:, None]
    result = proximity.Circle(center, normal, radius).closest_point(points, method=method)
    for i in range(len(points)):
        check_round("circle", center, normal, radius, points[i], result[i])


@pytest.mark.parametrize("method", ROUND_METHODS)
@pytest.mark.parametrize("frame", FRAMES)
def test_scenes_answer_with_the_circles_own_rim_point(frame, method):
    c, n, r, p = _circle_cases(frame, 6)
    # The scene's triangle is farther than every circle from its point.
    far = proximity.Triangle(np.eye(3) * 4.0 * r.max())
    for i in range(0, len(p), 3):
        ring = proximity.Circle(c[i], n[i], r[i])
        got = proximity.Scene([far, ring]).closest_point(p[i], method=method)
        alone = ring.closest_point(p[i], method=method)
        assert got.primitive == 1
        assert (got.distance, got.point.tolist()) == (alone.distance, alone.point.tolist())
        check_round("circle", c[i], n[i], r[i], p[i], got)
