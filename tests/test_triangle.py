"""Point-triangle queries against the exact reference."""

import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proximity import Feature, Triangle
from proximity.testing import exact
from tests import strategies
from tests.checks import BOUND, check_triangle

F = Feature
EPS = 2.0**-52
# With B = V0, E0 = V1 - V0 and E1 = V2 - V0 Eberly's (s, t) are (x, y).
UNIT = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

# One known case per region of Figure 1 of Eberly's document: (point, feature, closest, squared distance).
REGIONS = {
    0: ([0.25, 0.25, 1.0], F.FACE, [0.25, 0.25, 0.0], 1.0),
    1: ([1.0, 1.0, 0.0], F.EDGE12, [0.5, 0.5, 0.0], 0.5),
    2: ([-1.0, 2.5, 0.0], F.VERTEX2, [0.0, 1.0, 0.0], 3.25),
    3: ([-1.0, 0.5, 0.0], F.EDGE20, [0.0, 0.5, 0.0], 1.0),
    4: ([-1.0, -1.0, 0.0], F.VERTEX0, [0.0, 0.0, 0.0], 2.0),
    5: ([0.5, -1.0, 0.0], F.EDGE01, [0.5, 0.0, 0.0], 1.0),
    6: ([2.5, -1.0, 0.0], F.VERTEX1, [1.0, 0.0, 0.0], 3.25),
}
METHODS = ["robust", "eberly"]


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("region", sorted(REGIONS))
def test_one_known_case_per_region(region, method):
    point, feature, closest, sqr = REGIONS[region]
    r = Triangle(UNIT).closest_point(point, method=method)
    assert r.feature == feature
    assert r.sqr_distance == sqr
    assert r.distance == np.sqrt(sqr)
    np.testing.assert_array_equal(r.point, closest)
    check_triangle(UNIT, point, r)


def region_of(s, t):
    """The region of Figure 1 holding the unconstrained minimiser (s, t)."""
    if s + t <= 1:
        return 4 if s < 0 and t < 0 else 3 if s < 0 else 5 if t < 0 else 0
    return 2 if s < 0 else 6 if t < 0 else 1


# Triangles obtuse at V0, V1 and V2: only there can a corner region (4, 6 and
# 2) end on either adjacent edge as well as at its vertex.
OBTUSE = [
    np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 1.0, 0.0]]),
    np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0, 0.0]]),
    np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.3, 0.0]]),
]


@pytest.mark.parametrize("method", METHODS)
def test_every_branch_of_every_region(method):
    """A grid over (s, t) reaches each region and each way it can end."""
    seen = set()
    grid = np.arange(-2.05, 3.0, 0.25)
    for vertices in OBTUSE:
        b, e0, e1 = vertices[0], vertices[1] - vertices[0], vertices[2] - vertices[0]
        tri = Triangle(vertices)
        for s, t in itertools.product(grid, grid):
            point = b + s * e0 + t * e1 + [0.0, 0.0, 0.5]
            r = tri.closest_point(point, method=method)
            ref = exact.triangle_closest(vertices, point)
            assert r.feature == ref.feature, (vertices.tolist(), s, t)
            check_triangle(vertices, point, r)
            seen.add((region_of(s, t), int(ref.feature)))
    corner = {
        2: (F.EDGE12, F.VERTEX2, F.EDGE20),
        4: (F.EDGE01, F.VERTEX0, F.EDGE20),
        6: (F.EDGE01, F.VERTEX1, F.EDGE12),
    }
    for region, features in corner.items():
        assert {(region, int(f)) for f in features} <= seen, region
    assert {0, 1, 3, 5} <= {region for region, _ in seen}


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("height", [0.0, 1.0])
@pytest.mark.parametrize("offset", [-1e-12, 0.0, 1e-12])
def test_region_boundaries(offset, height, method):
    """Points at +-1e-12 across every boundary line of Figure 1."""
    tri = Triangle(UNIT)
    along = np.linspace(-1.5, 2.5, 17)
    cases = []
    for u in along:
        cases.append((offset, u))  # s = 0
        cases.append((u, offset))  # t = 0
        cases.append((u, 1.0 - u + offset))  # s + t = 1
    points = np.array([[s, t, height] for s, t in cases])
    r = tri.closest_point(points, method=method)
    for k, point in enumerate(points):
        check_triangle(UNIT, point, r[k])


@pytest.mark.parametrize("family", sorted(strategies.TRIANGLE_FAMILIES))
def test_robust_bound_on_every_family(family):
    @settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(strategies.TRIANGLE_FAMILIES[family])
    def check(scene):
        r = Triangle(scene.vertices).closest_point(scene.points)
        for k in range(len(scene.points)):
            check_triangle(scene.vertices[k], scene.points[k], r[k])

    check()


@settings(max_examples=80, deadline=None)
@given(strategies.triangle_scenes(), st.permutations([0, 1, 2]))
def test_vertex_permutation(scene, order):
    d = Triangle(scene.vertices).distance(scene.points)
    permuted = scene.vertices[:, order]
    r = Triangle(permuted).closest_point(scene.points)
    for k in range(len(scene.points)):
        check_triangle(permuted[k], scene.points[k], r[k])
        scale = float(exact.triangle_scale(scene.vertices[k], scene.points[k]))
        assert abs(r.distance[k] - d[k]) <= 2 * BOUND * EPS * scale
    # The barycentric coordinates follow the vertices, as well as the
    # triangle's conditioning allows: on a face of height h they are fixed
    # only to about eps * S / h, so they rebuild the point to eps * S * L / h.
    rebuilt = np.sum(r.barycentric[:, :, None] * permuted, axis=1)
    for k in range(len(scene.points)):
        v, p = permuted[k], scene.points[k]
        tol = 64 * EPS * (np.max(np.abs(v)) + np.max(np.abs(p)))
        if r.feature[k] == F.FACE:
            # Scale-free, so that 1e-300 and 1e300 coordinates neither under- nor overflow.
            m = np.max(np.abs(v - p))
            w = (v - p) / m
            longest = max(np.linalg.norm(w[i] - w[i - 1]) for i in range(3))
            twice_area = np.linalg.norm(np.cross(w[1] - w[0], w[2] - w[0]))
            tol += 16 * EPS * m * (np.max(np.linalg.norm(w, axis=1)) * longest**2 / twice_area)
        assert np.max(np.abs(rebuilt[k] - r.point[k])) <= tol, (v.tolist(), p.tolist(), r.barycentric[k])


@settings(max_examples=80, deadline=None)
@given(strategies.triangle_scenes(), strategies.rigid_motions())
def test_rigid_motion(scene, motion):
    """Distances survive a rotation and translation, up to the motion's own rounding."""
    d = Triangle(scene.vertices).distance(scene.points)
    moved_vertices = motion.apply(scene.vertices)
    moved_points = motion.apply(scene.points)
    if not (np.isfinite(moved_vertices).all() and np.isfinite(moved_points).all()):
        return  # coordinates near 1e308 overflow when rotated: nothing to compare
    r = Triangle(moved_vertices).closest_point(moved_points)
    for k in range(len(scene.points)):
        check_triangle(moved_vertices[k], moved_points[k], r[k])
        # Rounding the motion moves every coordinate by a few eps of the largest.
        size = (
            np.max(np.abs(scene.vertices[k]))
            + np.max(np.abs(scene.points[k]))
            + np.max(np.abs(motion.translation))
        )
        scale = float(exact.triangle_scale(scene.vertices[k], scene.points[k]))
        assert abs(r.distance[k] - d[k]) <= 2 * BOUND * EPS * scale + 16 * EPS * size
