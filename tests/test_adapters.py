"""Adapters: agreement with proximity, and each library's known conventions as documented behaviour.

The tests of library behaviour (``test_fcl_*``, ``test_pybullet_*``,
``test_trimesh_*``) ask the library directly, without the adapter, and assert
what the adapters' documentation says it does; a library upgrade that
changes one of them fails here and is noticed.
"""

import dataclasses
import doctest
import gc
import importlib
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import proximity
from proximity import Circle, Disk, Feature, Triangle, adapters
from proximity.adapters import Failure
from proximity.adapters._base import error_scale
from proximity.adapters._common import EPS, plane_frame, sagitta, segments_for

LIBRARIES = {"fcl": "fcl", "trimesh": "trimesh", "pybullet": "pybullet"}


def _installed(module):
    try:
        __import__(module)
    except ImportError:
        return False
    return True


BACKENDS = [
    pytest.param(name, marks=pytest.mark.skipif(not _installed(module), reason=f"{module} not installed"))
    for name, module in LIBRARIES.items()
]


@pytest.fixture(scope="module")
def backends():
    opened = {}
    yield opened
    for backend in opened.values():
        backend.close()


@pytest.fixture
def backend(request, backends):
    name = request.param
    if name not in backends:
        backends[name] = adapters.get(name)
    return backends[name]


def rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def good_triangles(rng, n, size=1.0):
    """Rotated, stretched equilateral triangles: no slivers, size about ``size``."""
    base = np.array([[1.0, 0.0, 0.0], [-0.5, 0.75**0.5, 0.0], [-0.5, -(0.75**0.5), 0.0]])
    tri = np.stack([(base * rng.uniform(0.5, 1.0, 3)) @ rotation(rng).T for _ in range(n)])
    return (tri + rng.normal(size=(n, 1, 3))) * size


def scene(kind, rng):
    """A well-conditioned batch of 4 shapes of ``kind``, and points ``(5, 1, D)`` against them."""
    if kind in ("triangle", "triangle2d"):
        tri = good_triangles(rng, 4)
        if kind == "triangle2d":
            shape = Triangle(tri[..., :2])
            # A 2D point inside a triangle touches it, where fcl gives no
            # nearest point (tested below): keep the points off the triangles.
            points = rng.normal(size=(5, 1, 2)) * 2.0
            while proximity.distance(shape, points).min() < 0.05:
                points = rng.normal(size=(5, 1, 2)) * 2.0
            return shape, points
        shape = Triangle(tri)
    else:
        cls = Disk if kind == "disk" else Circle
        shape = cls(rng.normal(size=(4, 3)), rng.normal(size=(4, 3)), rng.uniform(0.3, 2.0, 4))
    return shape, rng.normal(size=(5, 1, shape.dim)) * 2.0


def documented_tolerance(backend, shape, points, tol=None):
    """bound + rtol (S + M), computed here from the documentation, not by the backend."""
    s = error_scale(shape, points)
    p = np.broadcast_to(np.asarray(points, dtype=float), s.shape + (shape.dim,))
    m = np.max(np.abs(p), axis=-1)
    if isinstance(shape, Triangle):
        v = np.broadcast_to(shape.vertices, s.shape + (3, shape.dim))
        m = np.maximum(m, np.max(np.abs(v), axis=(-1, -2)))
        bound = np.zeros(s.shape)
    else:
        m = np.maximum(m, np.max(np.abs(np.broadcast_to(shape.center, s.shape + (3,))), axis=-1))
        radius = np.broadcast_to(shape.radius, s.shape)
        tessellated = isinstance(shape, Circle) or backend.name.startswith("trimesh")
        bound = sagitta(radius, segments_for(radius, tol)) if tessellated else np.zeros(s.shape)
    return bound + backend.rtol * (s + m)


# --- Registry and missing libraries -------------------------------------------------------------


def test_available_lists_exactly_the_importable_libraries():
    expected = [name for name, module in LIBRARIES.items() if _installed(module)]
    assert adapters.available() == expected
    assert adapters.NAMES == ("fcl", "trimesh", "pybullet")


@pytest.mark.parametrize(
    "name, module, distribution",
    [("fcl", "fcl", "python-fcl"), ("trimesh", "trimesh", "trimesh"), ("pybullet", "pybullet", "pybullet")],
)
def test_missing_library_names_the_extra_to_install(monkeypatch, name, module, distribution):
    monkeypatch.setitem(sys.modules, module, None)  # makes `import module` raise ImportError
    with pytest.raises(
        ImportError, match=rf"{distribution} is not installed.*pip install '\.\[adapters\]' in proximity's"
    ):
        adapters.get(name)
    assert name not in adapters.available()


def test_available_does_not_swallow_other_errors(monkeypatch):
    from proximity.adapters import fcl_backend

    def broken():
        raise RuntimeError("the library is broken, not missing")

    monkeypatch.setattr(fcl_backend, "load", broken)
    with pytest.raises(RuntimeError, match="broken, not missing"):
        adapters.available()


def test_unknown_backend_is_refused():
    with pytest.raises(ValueError, match="unknown backend 'ode'"):
        adapters.get("ode")


# --- Tessellation -------------------------------------------------------------------------------


@pytest.mark.parametrize("tol", [None, 1e-2, 1e-6, 0.3])
def test_segments_are_the_fewest_that_meet_the_tolerance(tol):
    # Radii up to where K stays under the cap of 65536 segments.
    radius = np.geomspace(1e-3, 1e3 if tol != 1e-6 else 10.0, 61)
    k = segments_for(radius, tol)
    limit = 1e-3 * radius if tol is None else np.full_like(radius, tol)
    assert (k >= 3).all()
    # The sagitta, computed independently in the textbook form, meets the limit...
    assert (radius * (1 - np.cos(np.pi / k)) <= limit * (1 + 1e-9)).all()
    # ...and one segment fewer does not (unless K is already the minimum of 3).
    fewer = k > 3
    assert (radius[fewer] * (1 - np.cos(np.pi / (k[fewer] - 1))) > limit[fewer]).all()


def test_segments_for_a_relative_default_and_edge_cases():
    assert segments_for([1.0, 5.0, 1e-9]).tolist() == [71, 71, 71]
    assert segments_for([0.0], 1e-3).tolist() == [3]
    with pytest.raises(ValueError, match="more than 65536 segments"):
        segments_for([1.0], 1e-12)
    with pytest.raises(ValueError, match="positive finite"):
        segments_for([1.0], 0.0)


# --- Agreement on well-conditioned scenes -------------------------------------------------------


@pytest.mark.parametrize("kind", ["triangle", "triangle2d", "disk", "circle"])
@pytest.mark.parametrize("backend", BACKENDS, indirect=True)
def test_backends_agree_with_proximity_within_their_documented_tolerance(backend, kind):
    rng = np.random.default_rng(["triangle", "triangle2d", "disk", "circle"].index(kind))
    shape, points = scene(kind, rng)
    r = backend.closest_point(shape, points)
    reference = proximity.closest_point(shape, points)

    assert type(r.result) is type(reference)
    assert r.distance.shape == r.failure.shape == r.tolerance.shape == (5, 4)
    assert r.point.shape == (5, 4, shape.dim)
    assert (r.failure == Failure.OK).all()
    np.testing.assert_allclose(r.tolerance, documented_tolerance(backend, shape, points), rtol=1e-12)
    assert (np.abs(r.distance - reference.distance) <= r.tolerance).all()
    # The nearest point is on the shape and at the distance returned.
    assert (proximity.distance(shape, r.point) <= r.tolerance).all()
    gap = np.linalg.norm(r.point - np.broadcast_to(points, r.point.shape), axis=-1)
    assert (np.abs(gap - r.distance) <= r.tolerance).all()
    np.testing.assert_array_equal(r.sqr_distance, r.distance**2)
    # What no library gives is marked unknown, not invented.
    assert (r.feature == Feature.NONE).all()
    assert "feature" in r.unknown
    for name in r.unknown:
        value = getattr(r, name)
        if value.dtype.kind == "f":
            assert np.isnan(value).all()


@pytest.mark.parametrize("backend", BACKENDS, indirect=True)
def test_tessellation_error_reaches_the_sagitta_and_no_more(backend):
    # A point on the circle halfway between two polygon corners is the
    # farthest from the polygon: the model's distance is the sagitta itself.
    center, normal, radius = np.array([0.5, -1.0, 2.0]), np.array([0.3, 0.4, 1.0]), 1.5
    u, v = plane_frame(normal[None, :] / np.linalg.norm(normal))
    for tol in (None, 1e-2, 1e-5):
        k = int(segments_for([radius], tol)[0])
        theta = np.pi / k
        point = center + radius * (np.cos(theta) * u[0] + np.sin(theta) * v[0])
        r = backend.closest_point(Circle(center, normal, radius), point, tol=tol)
        assert int(r.model.segments) == k
        assert float(r.model.bound) == pytest.approx(radius * (1 - np.cos(np.pi / k)), rel=1e-6)
        assert float(r.distance) == pytest.approx(float(r.model.bound), rel=1e-6)
        assert float(r.distance) <= float(r.tolerance)


def test_trimesh_disk_is_a_fan_of_k_triangles():
    pytest.importorskip("trimesh")
    with adapters.get("trimesh") as tm:
        disk = Disk([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 2.0)
        k = int(segments_for([2.0])[0])
        theta = np.pi / k
        u, v = plane_frame(np.array([[0.0, 0.0, 1.0]]))
        # Just outside the rim, between two corners: the fan is short of it by the sagitta.
        point = 2.0 * (np.cos(theta) * u[0] + np.sin(theta) * v[0]) * 1.01
        r = tm.closest_point(disk, point)
        assert r.model.primitive == "fan of K triangles"
        assert float(r.distance) == pytest.approx(0.02 + float(sagitta(2.0, k)), rel=1e-9)


@pytest.mark.parametrize("backend", BACKENDS, indirect=True)
def test_nan_points_are_not_sent_and_are_marked(backend):
    tri = Triangle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    r = backend.closest_point(tri, [[0.2, 0.2, 1.0], [np.nan, 0.0, 0.0], [0.0, np.inf, 0.0]])
    assert r.failure.tolist() == [Failure.OK, Failure.NAN_INPUT, Failure.NAN_INPUT]
    assert np.isnan(r.distance[1:]).all() and np.isnan(r.point[1:]).all() and np.isnan(r.tolerance[1:]).all()
    assert r.distance[0] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("backend", BACKENDS, indirect=True)
def test_a_single_query_gives_scalars_and_a_frozen_result(backend):
    disk = Disk([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0)
    r = backend.closest_point(disk, [0.5, 0.0, 2.0])
    assert isinstance(r.failure, Failure) and r.failure is Failure.OK
    assert np.ndim(r.distance) == 0 and float(r.distance) == pytest.approx(2.0, abs=1e-4)
    assert r.distance is r.result.distance
    assert float(backend.distance(disk, [0.5, 0.0, 2.0])) == float(r.distance)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.failure = Failure.NO_RESULT
    with pytest.raises(ValueError):
        r.point[0] = 1.0
    with pytest.raises(AttributeError):
        r.barycentric  # a disk result has none  # noqa: B018


def test_every_failed_row_is_nan_and_every_nan_row_failed():
    pytest.importorskip("fcl")
    with adapters.get("fcl") as fcl:
        # Points in the disk's plane, inside and outside the rim, and off it.
        rng = np.random.default_rng(5)
        points = rng.uniform(-2, 2, size=(200, 3)) * [1, 1, 0]
        points[::3, 2] = 0.5
        r = fcl.closest_point(Disk([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0), points)
        failed = r.failure != Failure.OK
        assert failed.any() and (~failed).any()
        np.testing.assert_array_equal(np.isnan(r.distance), failed)
        np.testing.assert_array_equal(np.isnan(r.point).all(axis=1), failed)


# --- fcl: documented behaviour ------------------------------------------------------------------


def _fcl_distance(geometry, transform, point):
    import fcl

    result = fcl.DistanceResult()
    d = fcl.distance(
        fcl.CollisionObject(geometry, transform),
        fcl.CollisionObject(fcl.Sphere(0.0), fcl.Transform(np.asarray(point, dtype=float))),
        fcl.DistanceRequest(enable_nearest_points=True),
        result,
    )
    return d, result.nearest_points


def _fcl_triangle(vertices):
    import fcl

    model = fcl.BVHModel()
    model.beginModel(3, 1)
    model.addSubModel(np.asarray(vertices, dtype=float), np.array([[0, 1, 2]]))
    model.endModel()
    return model


def test_fcl_trianglep_has_no_distance_against_a_sphere():
    fcl = pytest.importorskip("fcl")
    tri = fcl.TriangleP(np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0]))
    d, _ = _fcl_distance(tri, fcl.Transform(), [0.25, 0.25, 2.0])
    assert d >= 1.7e308  # DBL_MAX, not 2.0: why the backend uses a one-triangle BVHModel


DEGENERATE = {
    "collinear": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]],
    "two coincide": [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
    "a point": [[1.0, 1.0, 1.0]] * 3,
}


@pytest.mark.parametrize("name", DEGENERATE)
def test_fcl_calls_a_degenerate_triangle_touching(name):
    fcl = pytest.importorskip("fcl")
    tri = DEGENERATE[name]
    points = [[0.5, 3.0, 0.0], [5.0, 5.0, 5.0], [-3.0, 0.0, 1.0]]
    for p in points:
        d, _ = _fcl_distance(_fcl_triangle(tri), fcl.Transform(), p)
        assert abs(d) <= 1e-14, (
            "fcl now measures degenerate triangles: update the fcl backend's documentation"
        )
    with adapters.get("fcl") as backend:
        r = backend.closest_point(Triangle(tri), points)
    assert (r.failure == Failure.FALSE_TOUCHING).all()
    assert np.isnan(r.distance).all() and np.isnan(r.point).all()


def test_fcl_returns_no_nearest_point_in_contact():
    fcl = pytest.importorskip("fcl")
    # A triangle in the plane z = 10, far from the origin, and points exactly in it.
    tri = np.array([[10.0, 10.0, 10.0], [12.0, 10.0, 10.0], [10.0, 12.0, 10.0]])
    points = np.array([[10.5, 10.5, 10.0], [11.0, 10.25, 10.0], [10.25, 11.5, 10.0]])
    for p in points:
        d, _ = _fcl_distance(_fcl_triangle(tri), fcl.Transform(), p)
        assert d == 0.0
    with adapters.get("fcl") as backend:
        r = backend.closest_point(Triangle(tri), points)
    # The nearest points are whatever was in memory: not on the triangle, or
    # not at distance 0 from the point.
    assert np.isin(r.failure, [Failure.POINT_OFF_SHAPE, Failure.INCONSISTENT]).all()
    assert np.isnan(r.point).all()


def test_fcl_flat_cylinder_is_an_exact_disk_but_for_the_sentinel_in_its_plane():
    fcl = pytest.importorskip("fcl")
    radius = 2.0
    inside = [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [1.9, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.0, -1e-300]]
    outside = [[0.0, 0.0, 1.0], [1.0, 0.0, -1.0], [3.0, 0.0, 1.0], [2.1, 0.0, 0.0], [1.0, 0.0, 1e-12]]
    disk = Disk([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], radius)
    for p in inside:
        assert _fcl_distance(fcl.Cylinder(radius, 0.0), fcl.Transform(), p)[0] == -1.0
    for p in outside:
        d, _ = _fcl_distance(fcl.Cylinder(radius, 0.0), fcl.Transform(), p)
        assert d == pytest.approx(float(proximity.distance(disk, p)), rel=4 * EPS)
    with adapters.get("fcl") as backend:
        r = backend.closest_point(disk, inside + outside)
    assert (r.failure[:5] == Failure.SENTINEL).all() and np.isnan(r.distance[:5]).all()
    assert (r.failure[5:] == Failure.OK).all()


# --- pybullet: documented behaviour -------------------------------------------------------------


@pytest.fixture
def bullet():
    p = pytest.importorskip("pybullet")
    client = p.connect(p.DIRECT)
    yield p, client
    p.disconnect(physicsClientId=client)


def _bullet_closest(p, client, body, point, radius=1e-9):
    sphere = p.createCollisionShape(p.GEOM_SPHERE, radius=radius, physicsClientId=client)
    probe = p.createMultiBody(0, sphere, basePosition=list(point), physicsClientId=client)
    try:
        return p.getClosestPoints(body, probe, 100.0, physicsClientId=client)
    finally:
        p.removeBody(probe, physicsClientId=client)


@pytest.mark.parametrize("name", DEGENERATE)
def test_pybullet_gives_no_result_for_a_degenerate_triangle(bullet, name):
    p, client = bullet
    shape = p.createCollisionShape(
        p.GEOM_MESH, vertices=DEGENERATE[name], indices=[0, 1, 2], physicsClientId=client
    )
    body = p.createMultiBody(0, shape, physicsClientId=client)
    assert _bullet_closest(p, client, body, [0.5, 3.0, 0.0]) == ()
    with adapters.get("pybullet") as backend:
        r = backend.closest_point(Triangle(DEGENERATE[name]), [[0.5, 3.0, 0.0], [5.0, 5.0, 5.0]])
    assert (r.failure == Failure.NO_RESULT).all() and np.isnan(r.distance).all()


@pytest.mark.parametrize("radius", [1.0, 0.1])
def test_pybullet_thin_cylinder_margin_bias(bullet, radius):
    p, client = bullet
    shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=radius, height=0.0, physicsClientId=client)
    body = p.createMultiBody(0, shape, physicsClientId=client)
    margin = p.getDynamicsInfo(body, -1, physicsClientId=client)[-1]
    assert margin == pytest.approx(0.001)
    disk = Disk([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], radius)
    # 45 degrees off the rim's plane: the default margin squares the rim off.
    point = [radius * 1.5, 0.0, radius * 0.5]
    exact = float(proximity.distance(disk, point))
    biased = _bullet_closest(p, client, body, point)[0][8] + 1e-9
    assert biased - exact == pytest.approx((math.sqrt(2) - 1) * margin, rel=1e-6)
    # A bias of the same length whatever the radius: 0.04% of 1, 0.4% of 0.1.
    assert (biased - exact) / radius == pytest.approx(4.142e-4 / radius, rel=1e-3)
    p.changeDynamics(body, -1, collisionMargin=0.0, physicsClientId=client)
    assert p.getDynamicsInfo(body, -1, physicsClientId=client)[-1] == 0.0
    assert abs(_bullet_closest(p, client, body, point)[0][8] + 1e-9 - exact) < 1e-10
    with adapters.get("pybullet") as backend:
        r = backend.closest_point(disk, point)
    assert r.model.margin == 0.0
    assert abs(float(r.distance) - exact) <= 1e-10 * radius


def test_pybullet_refuses_radius_zero_and_reports_at_most_16_points(bullet):
    p, client = bullet
    for kwargs in (
        {"shapeType": p.GEOM_SPHERE, "radius": 0.0},
        {"shapeType": p.GEOM_CAPSULE, "radius": 0.0, "height": 1.0},
    ):
        with pytest.raises(p.error):
            p.createCollisionShape(physicsClientId=client, **kwargs)
    count = 32
    shape = p.createCollisionShapeArray(
        shapeTypes=[p.GEOM_CAPSULE] * count,
        radii=[1e-9] * count,
        lengths=[0.1] * count,
        collisionFramePositions=[[0.0, 0.0, 0.2 * i] for i in range(count)],
        physicsClientId=client,
    )
    body = p.createMultiBody(0, shape, physicsClientId=client)
    # Why the circle's capsules are not one compound body.
    assert len(_bullet_closest(p, client, body, [0.3, 0.0, 3.0])) == 16


def test_pybullet_does_not_leak_clients_or_bodies_over_10000_queries():
    p = pytest.importorskip("pybullet")
    from proximity.adapters.pybullet_backend import RESET_EVERY

    rng = np.random.default_rng(7)
    backend = adapters.get("pybullet")
    client = backend.client
    for _ in range(100):
        # 10 triangles, 10 points each: 100 queries, 10 shapes per call.
        tri = Triangle(good_triangles(rng, 10))
        r = backend.closest_point(tri, rng.normal(size=(10, 10, 3)))
        assert (r.failure == Failure.OK).all()
        assert backend.num_bodies() <= 2
        assert backend.client == client
        assert p.getConnectionInfo(physicsClientId=client)["isConnected"] == 1
    # 1000 shapes were created and removed: the server was reset on the way,
    # so it holds fewer than RESET_EVERY collision shapes (a new shape's id
    # is their count).
    probe = p.createCollisionShape(p.GEOM_SPHERE, radius=1.0, physicsClientId=client)
    assert probe < RESET_EVERY
    backend.close()
    assert p.getConnectionInfo(physicsClientId=client)["isConnected"] == 0
    with pytest.raises(RuntimeError, match="closed"):
        backend.closest_point(tri, [0.0, 0.0, 0.0])
    backend.close()  # closing twice is harmless


def test_pybullet_clients_are_released_by_close_context_and_garbage_collection():
    p = pytest.importorskip("pybullet")
    ids = set()
    for _ in range(20):
        with adapters.get("pybullet") as backend:
            ids.add(backend.client)
        assert p.getConnectionInfo(physicsClientId=backend.client)["isConnected"] == 0
    assert len(ids) == 1  # the same id is reused: nothing stays connected
    backend = adapters.get("pybullet")
    client = backend.client
    del backend
    gc.collect()
    assert p.getConnectionInfo(physicsClientId=client)["isConnected"] == 0


def test_pybullet_is_accurate_on_micrometre_triangles_in_the_shapes_frame():
    pytest.importorskip("pybullet")
    rng = np.random.default_rng(11)
    tri = Triangle(good_triangles(rng, 20, size=1e-6))
    points = tri.vertices.mean(axis=1) + rng.normal(size=(20, 3)) * 1e-6
    with adapters.get("pybullet") as backend:
        r = backend.closest_point(tri, points)
    relative = np.abs(r.distance - proximity.distance(tri, points)) / error_scale(tri, points)
    assert (r.failure == Failure.OK).all() and relative.max() < 1e-12


# --- trimesh: documented behaviour --------------------------------------------------------------


def test_trimesh_absolute_tolerance_breaks_sub_millimetre_triangles():
    trimesh = pytest.importorskip("trimesh")
    assert trimesh.tol.zero == pytest.approx(1e-13)
    rng = np.random.default_rng(3)
    tri = Triangle(good_triangles(rng, 200, size=1e-4))
    points = tri.vertices.mean(axis=1) + rng.normal(size=(200, 3)) * 1e-4
    exact = proximity.distance(tri, points)
    scale = error_scale(tri, points)

    found = trimesh.triangles.closest_point(np.asarray(tri.vertices), points)
    raw_error = np.abs(np.linalg.norm(found - points, axis=1) - exact) / scale
    assert raw_error.max() > 0.01  # wrong by more than 1% of the triangle's scale
    # The points trimesh returns are on the triangle, just not the closest.
    assert (proximity.distance(tri, found) <= 64 * EPS * scale).all()

    with adapters.get("trimesh", rescale=False) as raw:
        r = raw.closest_point(tri, points)
    assert (r.failure == Failure.OK).all()  # no translation can see it...
    assert (np.abs(r.distance - exact) > r.tolerance).sum() >= 10  # ...but the comparison does
    with adapters.get("trimesh") as rescaled:
        r = rescaled.closest_point(tri, points)
    assert (r.failure == Failure.OK).all() and (np.abs(r.distance - exact) <= r.tolerance).all()


# --- cross_check and the command ----------------------------------------------------------------


def test_cross_check_counts_failures_and_ranks_disagreements():
    names = adapters.available()
    if not names:
        pytest.skip("no backend library installed")
    tri = Triangle([DEGENERATE["collinear"], DEGENERATE["a point"], [[0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    points = [[0.5, 3.0, 0.0], [5.0, 5.0, 5.0], [0.2, 0.2, 1.0]]
    report = adapters.cross_check(tri, points)
    # By default every library is asked in the caller's coordinates.
    raw = [f"{name}[raw]" for name in names]
    assert [s.backend for s in report.summaries] == raw and report.left_out == ()
    assert report.reference in ("certified", "robust")
    for s in report.summaries:
        assert s.rows == 3 and s.answered + sum(s.failures.values()) == 3
        assert s.model.frame == "caller's coordinates"
    if "fcl" in names:
        s = report.summary("fcl[raw]")
        assert s.answered == 1 and dict(s.failures) == {"FALSE_TOUCHING": 2}
    if "pybullet" in names:
        assert dict(report.summary("pybullet[raw]").failures) == {"NO_RESULT": 2}
    if "trimesh" in names:
        s = report.summary("trimesh[raw]")
        assert s.answered == 3 and s.beyond_tolerance == 0 and s.max_relative < 1e-15
    for name in raw:
        ratios = [c.ratio for c in report.worst if c.backend == name]
        assert ratios == sorted(ratios, reverse=True)
    table = report.table()
    for name in raw:
        assert name in table
    with pytest.raises(KeyError):
        report.summary("ode")


def test_cross_check_sees_trimesh_raw_disagreement_and_leaves_given_backends_open():
    pytest.importorskip("trimesh")
    rng = np.random.default_rng(3)
    tri = Triangle(good_triangles(rng, 100, size=1e-4))
    points = tri.vertices.mean(axis=1) + rng.normal(size=(100, 3)) * 1e-4
    raw = adapters.get("trimesh", rescale=False)
    # A backend given as an object is asked as it was made; one given by name, with rescale.
    report = adapters.cross_check(tri, points, backends=["trimesh", raw], worst=2, rescale=True)
    assert report.summary("trimesh").beyond_tolerance == 0
    s = report.summary("trimesh[raw]")
    assert s.beyond_tolerance > 0 and s.max_relative > 0.01
    worst = [c for c in report.worst if c.backend == "trimesh[raw]"]
    assert len(worst) == 2 and worst[0].ratio > 1
    assert worst[0].disagreement == pytest.approx(abs(worst[0].distance - worst[0].reference))
    assert (raw.closest_point(tri, points).failure == Failure.OK).all()  # still usable


def test_cross_check_asks_point_queries_in_the_callers_coordinates_unless_asked_to_rescale():
    for library in ("trimesh", "pybullet"):
        pytest.importorskip(library)
    # Disks of a radius of about 1e-5: trimesh's region tests have absolute tolerances (on
    # the fan's triangles), and pybullet's probe of radius 1e-9 is 1e-4 of the disk.
    rng = np.random.default_rng(8)
    disk = Disk(rng.normal(size=(50, 3)) * 1e-5, rng.normal(size=(50, 3)), rng.uniform(0.2, 2.0, 50) * 1e-5)
    points = np.asarray(disk.center) + rng.normal(size=(50, 3)) * 1e-5
    report = adapters.cross_check(disk, points, backends=["trimesh", "pybullet"])
    for name in ("trimesh[raw]", "pybullet[raw]"):
        s = report.summary(name)
        assert s.model.frame == "caller's coordinates"
        assert s.beyond_tolerance + sum(s.failures.values()) >= 5, (name, s)
    report = adapters.cross_check(disk, points, backends=["trimesh", "pybullet"], rescale=True)
    for name in ("trimesh", "pybullet"):
        s = report.summary(name)
        assert s.model.frame.startswith("per ")
        assert s.answered == 50 and s.beyond_tolerance == 0, (name, s)


@pytest.mark.parametrize("name", [p.values[0] for p in BACKENDS], ids=[p.values[0] for p in BACKENDS])
def test_backends_in_the_callers_coordinates_agree_on_unit_scenes(name):
    pytest.importorskip(LIBRARIES[name])
    with adapters.get(name, rescale=False) as backend:
        assert backend.name == f"{name}[raw]" and backend.rescale is False
        for seed, kind in enumerate(("triangle", "triangle2d", "disk", "circle")):
            shape, points = scene(kind, np.random.default_rng(seed))
            r = backend.closest_point(shape, points)
            assert r.backend == f"{name}[raw]" and r.model.frame == "caller's coordinates"
            assert (r.failure == Failure.OK).all(), (kind, [Failure(f).name for f in r.failure.ravel()])
            np.testing.assert_allclose(r.tolerance, documented_tolerance(backend, shape, points), rtol=1e-12)
            assert (np.abs(r.distance - proximity.distance(shape, points)) <= r.tolerance).all(), kind
            assert (proximity.distance(shape, r.point) <= r.tolerance).all(), kind


def test_check_command_asks_in_the_frames_asked(capsys):
    from proximity.adapters import check

    pytest.importorskip("trimesh")
    assert check.main(["-n", "2", "--backend", "trimesh", "--frames", "both"]) == 0
    out = capsys.readouterr().out
    verdicts = [line.split(":")[0] for line in out.splitlines() if line.startswith("trimesh")]
    assert verdicts[-2:] == ["trimesh[raw]", "trimesh"]
    assert check.main(["-n", "2", "--backend", "trimesh", "--frames", "rescaled"]) == 0
    out = capsys.readouterr().out
    assert "\ntrimesh " in out and "trimesh[raw]" not in out


@pytest.mark.parametrize(
    "module",
    [
        "proximity.adapters",
        "proximity.adapters._base",
        "proximity.adapters.crosscheck",
        "proximity.adapters.fcl_backend",
        "proximity.adapters.trimesh_backend",
        "proximity.adapters.pybullet_backend",
    ],
)
def test_docstring_examples_run(module):
    for library in LIBRARIES.values():
        pytest.importorskip(library)
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


def test_documentation_examples_run():
    for library in LIBRARIES.values():
        pytest.importorskip(library)
    path = pathlib.Path(__file__).parent.parent / "docs" / "adapters.md"
    result = doctest.testfile(str(path), module_relative=False, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


def test_check_command_prints_a_table_per_group(capsys):
    from proximity.adapters import check

    if not adapters.available():
        pytest.skip("no backend library installed")
    assert check.main(["-n", "4", "--seed", "2"]) == 0
    out = capsys.readouterr().out
    for label in ("## triangles", "## degenerate triangles", "## disks", "## circles"):
        assert label in out
    for name in adapters.available():
        name = f"{name}[raw]"  # in the caller's coordinates, by default
        assert f"\n{name} " in out
        verdicts = [line for line in out.splitlines() if line.startswith(f"{name}: ")]
        assert len(verdicts) == 1 and "documented tolerance" in verdicts[0]
    assert "largest disagreements" in out
    assert out.startswith("Each table compares") and "  >tol " in out and "## verdict" in out


def test_check_command_prints_no_library_banner():
    pytest.importorskip("pybullet")
    done = subprocess.run(
        [sys.executable, "-m", "proximity.adapters.check", "-n", "1", "--backend", "pybullet"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert "build time" not in done.stdout + done.stderr
    assert done.stdout.startswith("Each table compares")


def test_cross_check_prints_as_its_table():
    pytest.importorskip("trimesh")
    disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    report = adapters.cross_check(disk, [[0.5, 0, 2], [3, 0, 0]], backends=["trimesh"])
    assert str(report) == repr(report) == report.table()
    assert report.table().startswith("Disk of batch shape () against proximity")
