"""The certified method: faithfully rounded distances, exact features, exact zeros."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

import proximity
from proximity import Circle, Disk, Feature, Triangle
from proximity.testing import exact, scenes
from tests import strategies

VOLUME = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def check_triangle(vertices, point, r):
    ref = exact.triangle_closest(vertices, point)
    context = (np.asarray(vertices).tolist(), np.asarray(point).tolist())
    assert exact.ulps(float(r.distance), ref.distance) < 1.0, context
    assert r.feature == ref.feature, (r.feature, ref.features, context)
    if ref.sqr_distance == 0:
        assert r.distance == 0.0, context


@pytest.mark.parametrize("family", sorted(strategies.TRIANGLE_FAMILIES))
def test_triangles_within_one_ulp(family):
    @VOLUME
    @given(strategies.TRIANGLE_FAMILIES[family])
    def check(scene):
        r = Triangle(scene.vertices).closest_point(scene.points, method="certified")
        for k in range(len(scene.points)):
            check_triangle(scene.vertices[k], scene.points[k], r[k])

    check()


@pytest.mark.parametrize("kind", ["disk", "circle"])
@pytest.mark.parametrize("family", sorted(strategies.DISK_FAMILIES))
def test_circles_and_disks_within_one_ulp(family, kind):
    closest = exact.disk_closest if kind == "disk" else exact.circle_closest
    cls = Disk if kind == "disk" else Circle

    @VOLUME
    @given(strategies.DISK_FAMILIES[family])
    def check(scene):
        r = cls(scene.center, scene.normal, scene.radius).closest_point(scene.points, method="certified")
        for k in range(len(scene.points)):
            ref = closest(scene.center[k], scene.normal[k], scene.radius[k], scene.points[k])
            context = (
                scene.center[k].tolist(),
                scene.normal[k].tolist(),
                scene.radius[k],
                scene.points[k].tolist(),
            )
            assert exact.ulps(float(r.distance[k]), ref.distance) < 1.0, context
            assert r.feature[k] == ref.feature, context
            if kind == "circle":
                assert r.equidistant[k] == ref.on_axis, context

    check()


def test_points_on_the_triangle_give_exactly_zero():
    # Dyadic coordinates, so that the points below are exactly on the triangle.
    v = np.array([[0.5, -1.25, 3.0], [2.75, 0.5, -1.0], [-1.0, 1.5, 0.25]])
    tri = Triangle(v)
    on = [
        *v,  # the vertices
        (v[0] + v[1]) / 2,  # edge midpoints
        (v[1] + v[2]) / 2,
        (v[2] + v[0]) / 2,
        (v[0] + v[1] + 2 * v[2]) / 4,  # a point of the face
    ]
    features = [
        Feature.VERTEX0,
        Feature.VERTEX1,
        Feature.VERTEX2,
        Feature.EDGE01,
        Feature.EDGE12,
        Feature.EDGE20,
    ]
    for point, feature in zip(on, [*features, Feature.FACE], strict=True):
        assert exact.triangle_sqr_distance(v, point) == 0  # the construction is exact
        r = tri.closest_point(point, method="certified")
        assert r.distance == 0.0 and r.sqr_distance == 0.0
        assert r.feature == feature
    batch = tri.distance(np.array(on), method="certified")
    assert (batch == 0.0).all()


def test_points_on_circles_and_disks_give_exactly_zero():
    disk = Disk([1.0, 2.0, 3.0], [0.0, 0.0, 5.0], 2.0)
    circle = Circle([1.0, 2.0, 3.0], [0.0, 0.0, 5.0], 2.0)
    on_rim = [[3.0, 2.0, 3.0], [1.0, 0.0, 3.0]]
    assert (disk.distance(on_rim + [[1.5, 2.5, 3.0]], method="certified") == 0.0).all()
    assert (circle.distance(on_rim, method="certified") == 0.0).all()


def test_degenerate_ties_go_to_the_lowest_feature_code():
    # V1 == V2: the closest point is inside edges 01 and 20 (and 12 is a point).
    tri = Triangle([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    assert tri.closest_point([1.0, 1.0, 0.0], method="certified").feature == Feature.EDGE01
    assert tri.closest_point([5.0, 1.0, 0.0], method="certified").feature == Feature.VERTEX1
    # Collinear, V0 in the middle: V0 beats edges 01 and 20 that hold it too.
    line = Triangle([[0.0, 0.0, 0.0], [-2.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    assert line.closest_point([0.0, 3.0, 0.0], method="certified").feature == Feature.VERTEX0


def test_the_fallback_is_rare_on_well_conditioned_scenes():
    """Fewer than 1 query in 10,000 needs exact arithmetic (seeded, so it can fail)."""
    scene = scenes.well_conditioned(np.random.default_rng(11), 200_000)
    proximity.certified_stats(reset=True)
    Triangle(scene.vertices).distance(scene.points, method="certified")
    stats = proximity.certified_stats()
    assert stats["queries"] == 200_000
    assert stats["exact"] < 20

    disks = scenes.disk_well_conditioned(np.random.default_rng(12), 100_000)
    proximity.certified_stats(reset=True)
    Disk(disks.center, disks.normal, disks.radius).distance(disks.points, method="certified")
    assert proximity.certified_stats()["exact"] < 10


def test_the_fallback_is_counted():
    proximity.certified_stats(reset=True)
    tri = Triangle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    tri.distance([[0.25, 0.25, 1.0], [0.5, 0.0, 0.0]], method="certified")  # the second is on an edge
    tri.closest_point([0.5, 0.5, 0.0], method="certified")
    assert proximity.certified_stats(reset=True) == {"queries": 3, "exact": 2}
    assert proximity.certified_stats() == {"queries": 0, "exact": 0}


def test_distances_beyond_the_float_range_do_not_raise():
    """Coordinates near the float limit: the exact fallback rounds to inf, never raises."""
    huge = 1.7e308
    tri = Triangle([[1e300, 1e300, 1e300], [-1e300, -1e300, 1e300], [1e300, -1e300, -1e300]])
    d = tri.distance([[-huge, huge, -huge], [huge, huge, huge], [0.0, 0.0, 0.0]], method="certified")
    assert np.isinf(d[:2]).all() and np.isfinite(d[2])
    for cls in (Disk, Circle):
        shape = cls([1e300, 1e300, 1e300], [1.0, 1.0, 1.0], 1e300)
        r = shape.closest_point([[-huge, -huge, -huge], [1e308, -1e308, 0.0]], method="certified")
        assert np.isinf(r.distance[0]) and np.isfinite(r.distance[1])


def test_distances_far_below_the_query_size():
    """Squared distances under 2^-960 of the query's size squared: the
    double-double error bounds fail there (their low parts are subnormal),
    and a quotient can underflow to a false exact zero, so the filter must
    leave them to the exact fallback.  A sliver's face 1e-30 to 1e-10 above
    it, 1e-150 to 1e-130 thin, and an edge 7e-163 from the point."""
    rng = np.random.default_rng(21)
    n = 300
    v = np.zeros((n, 3, 3))
    v[:, 1, 0] = 1.0
    v[:, 2, 0], v[:, 2, 1] = 0.5, 10.0 ** rng.uniform(-150, -130, n)
    p = np.empty((n, 3))
    p[:, 0], p[:, 1] = rng.uniform(0.3, 0.7, n), v[:, 2, 1] * rng.uniform(0.2, 0.4, n)
    p[:, 2] = 10.0 ** rng.uniform(-30, -10, n)
    r = Triangle(v).closest_point(p, method="certified")
    for k in range(n):
        check_triangle(v[k], p[k], r[k])
    edge, point = [[0.0, 1.0, 1.057262777555193e-162], [0.0, -2.0, 0.0], [0.0, 0.0, 5.0]], [0.0, 0.0, -1e-170]
    check_triangle(edge, point, Triangle(edge).closest_point(point, method="certified"))
