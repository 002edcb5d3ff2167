"""Adapters' pair queries: answers against the exact reference, each library's conventions, bad input.

As in ``test_adapters.py``, the ``test_*_library_*`` tests ask the library
directly and assert the behaviour the backends translate, so that an upgrade
that changes it fails here.
"""

import doctest
import importlib

import numpy as np
import pytest

import proximity
from proximity import Capsule, Disk, Point, Segment, Sphere, Triangle, TriangleMesh, adapters
from proximity.adapters import Failure
from proximity.adapters._pairs import segment_frames
from proximity.testing import exact
from proximity.testing.meshes import icosphere, torus

fcl_lib = pytest.importorskip("fcl")
pytest.importorskip("trimesh")
pybullet_lib = pytest.importorskip("pybullet")

EXACT = {
    ("segment", "segment"): exact.segment_segment_closest,
    ("segment", "triangle"): exact.segment_triangle_closest,
    ("triangle", "triangle"): exact.triangle_triangle_closest,
}


@pytest.fixture(scope="module")
def backends():
    opened = {name: adapters.get(name) for name in adapters.NAMES}
    yield opened
    for backend in opened.values():
        backend.close()


def pose(rng, translation):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = q, translation
    return m


def face_triangle(mesh, face):
    """Face ``face`` of a mesh or a posed mesh, as a Triangle in the world."""
    if isinstance(mesh, TriangleMesh):
        return Triangle(mesh.vertices[mesh.faces[face]])
    return Triangle(mesh.shape.vertices[mesh.shape.faces[face]] @ mesh.rotation.T + mesh.translation)


def pairs(rng, kind_a, kind_b, n):
    """``n`` random pairs of the kinds, the last quarter crossing (a's first vertex on b's)."""
    size = {"segment": 2, "triangle": 3}
    va = rng.normal(size=(n, size[kind_a], 3))
    vb = rng.normal(size=(n, size[kind_b], 3)) + [1.5, 0.0, 0.0]
    cross = slice(3 * n // 4, n)
    # b around a's first vertex, so that the pair touches or crosses.
    vb[cross] += va[cross, :1] - vb[cross].mean(axis=1, keepdims=True)
    shape = {"segment": Segment, "triangle": Triangle}
    return shape[kind_a](va), shape[kind_b](vb), va, vb


CASES = [
    ("fcl", "segment", "segment"),
    ("fcl", "segment", "triangle"),
    ("fcl", "triangle", "segment"),
    ("fcl", "triangle", "triangle"),
    ("trimesh", "triangle", "triangle"),
    ("pybullet", "segment", "segment"),
    ("pybullet", "segment", "triangle"),
    ("pybullet", "triangle", "triangle"),
]


@pytest.mark.parametrize(("name", "kind_a", "kind_b"), CASES)
def test_answers_are_within_the_tolerance_of_the_exact_distance(backends, name, kind_a, kind_b):
    rng = np.random.default_rng(len(name) * 10 + len(kind_a) + len(kind_b))
    a, b, va, vb = pairs(rng, kind_a, kind_b, 16)
    r = backends[name].closest_points(a, b)
    assert r.distance.shape == (16,) and r.point_a.shape == r.point_b.shape == (16, 3)
    answered = np.isin(r.failure, [Failure.OK, Failure.CONTACT])
    assert answered.sum() >= 12, [Failure(f).name for f in r.failure]
    swap = (kind_a, kind_b) not in EXACT
    for i in np.flatnonzero(answered):
        if swap:
            ref = EXACT[(kind_b, kind_a)](vb[i], va[i])
        else:
            ref = EXACT[(kind_a, kind_b)](va[i], vb[i])
        assert abs(r.distance[i] - float(ref.distance)) <= r.tolerance[i], (i, r.distance[i], ref.distance)
        if r.failure[i] == Failure.OK:
            gap = np.linalg.norm(r.point_b[i] - r.point_a[i])
            assert abs(gap - r.distance[i]) <= r.tolerance[i]
        else:  # contact: distance 0, no witness points, and the shapes within twice the tolerance
            assert r.distance[i] == 0.0 and np.isnan(r.point_a[i]).all()
            assert float(ref.distance) <= 2 * r.tolerance[i]
    assert r.model.library.split()[0] == backends[name].distribution
    assert "feature_a" in r.unknown and "feature_b" in r.unknown


def test_batches_broadcast_like_proximity(backends):
    rng = np.random.default_rng(3)
    a = Segment(rng.normal(size=(3, 1, 2, 3)))
    b = Triangle(rng.normal(size=(4, 3, 3)) + [3.0, 0.0, 0.0])
    r = backends["fcl"].closest_points(a, b)
    assert r.distance.shape == (3, 4) and r.point_b.shape == (3, 4, 3) and r.tolerance.shape == (3, 4)
    ref = proximity.distance(a, b, method="certified")
    assert (r.failure == Failure.OK).all()
    np.testing.assert_array_less(np.abs(r.distance - ref), r.tolerance)
    one = backends["fcl"].closest_points(Segment(a.vertices[2, 0]), Triangle(b.vertices[1]))
    assert np.ndim(one.distance) == 0 and one.failure == Failure.OK
    assert one.distance == r.distance[2, 1]
    assert backends["fcl"].distance(a, b).shape == (3, 4)
    for name in ("fcl", "pybullet"):
        empty = backends[name].closest_points(Segment(np.zeros((0, 2, 3))), Triangle(b.vertices[:1]))
        assert empty.distance.shape == (0,) and empty.point_a.shape == (0, 3) and empty.failure.shape == (0,)


@pytest.mark.parametrize("name", ["fcl", "pybullet"])
def test_spheres_and_capsules_are_the_libraries_rounded_shapes(backends, name):
    rng = np.random.default_rng(4)
    capsules = Capsule(rng.normal(size=(8, 2, 3)), rng.uniform(0.1, 0.4, 8))
    spheres = Sphere(rng.normal(size=(8, 3)) + [3.0, 0.0, 0.0], rng.uniform(0.1, 0.4, 8))
    tri = Triangle(rng.normal(size=(8, 3, 3)) + [0.0, 3.0, 0.0])
    for a, b in ((capsules, spheres), (spheres, tri), (capsules, tri)):
        r = backends[name].closest_points(a, b)
        ref = proximity.distance(a, b, method="certified")
        assert (r.failure == Failure.OK).all(), [Failure(f).name for f in r.failure]
        np.testing.assert_array_less(np.abs(r.distance - ref), r.tolerance)
        # Witnesses on the surfaces: at the distance of the solids from each other.
        on_a = np.abs(a.signed_distance(r.point_a)) if hasattr(a, "radius") else a.distance(r.point_a)
        np.testing.assert_array_less(on_a, r.tolerance)


def test_posed_meshes_are_given_their_pose_and_answer_as_proximity(backends):
    rng = np.random.default_rng(5)
    ring = TriangleMesh(*torus(16, 8))
    ball = TriangleMesh(*icosphere(1, 0.3))
    b = ball.transformed(pose(rng, [0.2, 0.1, 1.2]))
    a = ring.transformed(pose(rng, [0.0, 0.0, 0.1]))
    for name, faces in (("fcl", "ab"), ("trimesh", "")):
        for pair in ((ring, b), (a, b), (b, a)):
            r = backends[name].closest_points(*pair)
            ref = float(proximity.distance(*pair, method="certified"))
            assert r.failure == Failure.OK and abs(float(r.distance) - ref) <= float(r.tolerance), name
            assert "pose" in r.model.frame
            # the faces the library names hold the witnesses (trimesh names none)
            for key, side in zip("ab", pair, strict=True):
                face = int(getattr(r, f"face_{key}"))
                if key not in faces:
                    assert face == -1 and f"face_{key}" in r.unknown
                    continue
                assert face >= 0 and f"face_{key}" not in r.unknown
                assert float(face_triangle(side, face).distance(getattr(r, f"point_{key}"))) <= r.tolerance
    with pytest.raises(NotImplementedError, match=r"segment \(a\) and a mesh \(b\)"):
        backends["trimesh"].closest_points(Segment([[0, 0, 0], [1, 0, 0]]), b)


@pytest.mark.parametrize("name", ["fcl", "trimesh", "pybullet"])
def test_posed_primitives_answer_as_proximity(backends, name):
    rng = np.random.default_rng(7)
    t1, t2 = pose(rng, [0.3, -0.2, 0.5]), pose(rng, [2.0, 0.4, -0.1])
    tri = Triangle(rng.normal(size=(10, 3, 3))).transformed(t2)
    cases = [(Triangle(rng.normal(size=(10, 3, 3))), tri)]
    if name != "trimesh":
        cases += [
            (Capsule(rng.normal(size=(10, 2, 3)), 0.2).transformed(t1), tri),
            (Segment(rng.normal(size=(10, 2, 3))).transformed(t1).inflated(0.1), tri),
            (Sphere(rng.normal(size=(10, 3)), 0.3).transformed(t1), Segment(rng.normal(size=(10, 2, 3)))),
        ]
    for a, b in cases:
        r = backends[name].closest_points(a, b)
        assert np.isin(r.failure, [Failure.OK, Failure.CONTACT]).all(), [Failure(f).name for f in r.failure]
        assert (r.failure == Failure.OK).sum() >= 8
        ref = proximity.distance(a, b, method="certified")
        np.testing.assert_array_less(np.abs(r.distance - ref), r.tolerance)
        ok = r.failure == Failure.OK
        np.testing.assert_array_less(np.abs(np.linalg.norm(r.point_b - r.point_a, axis=-1) - r.distance)[ok],
                                     r.tolerance[ok])  # fmt: skip


def test_fcl_library_has_absolute_tolerances_which_the_backends_frame_removes(backends):
    rng = np.random.default_rng(9)
    a, b, va, vb = pairs(rng, "segment", "triangle", 40)
    a, b = Segment(va * 1e-4), Triangle(vb * 1e-4)
    ref = proximity.distance(a, b, method="certified")
    request = fcl_lib.DistanceRequest(enable_nearest_points=True)
    errors = []
    frames, middles, lengths = segment_frames(a.vertices)  # z along each segment
    for tri, frame, middle, length, d in zip(b.vertices, frames, middles, lengths, ref, strict=True):
        model = fcl_lib.BVHModel()
        model.beginModel(3, 1)
        model.addSubModel(tri, np.array([[0, 1, 2]]))
        model.endModel()
        capsule = fcl_lib.Capsule(0.0, float(length))
        placed = fcl_lib.CollisionObject(capsule, fcl_lib.Transform(frame, middle))
        result = fcl_lib.DistanceResult()
        got = fcl_lib.distance(fcl_lib.CollisionObject(model, fcl_lib.Transform()), placed, request, result)
        errors.append(abs(max(got, 0.0) - d) / 3e-4)
    assert max(errors) > 1e-3  # in the caller's coordinates: wrong by more than 0.1% of the size
    r = backends["fcl"].closest_points(a, b)
    assert np.isin(r.failure, [Failure.OK, Failure.CONTACT]).all()
    np.testing.assert_array_less(np.abs(r.distance - ref), r.tolerance)
    assert r.tolerance.max() < 1e-16  # 64 eps of a pair of size about 3e-4


def test_fcl_library_returns_stale_points_or_minus_one_in_contact():
    def tri(v):
        model = fcl_lib.BVHModel()
        model.beginModel(3, 1)
        model.addSubModel(np.asarray(v, float), np.array([[0, 1, 2]]))
        model.endModel()
        return fcl_lib.CollisionObject(model, fcl_lib.Transform())

    request = fcl_lib.DistanceRequest(enable_nearest_points=True)
    flat = tri([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    crossing = tri([[0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.4, 1]])
    result = fcl_lib.DistanceResult()
    assert fcl_lib.distance(flat, crossing, request, result) == 0.0
    # the two nearest points are not one point: no witness of contact
    assert np.linalg.norm(result.nearest_points[0] - result.nearest_points[1]) > 0.1
    segment = fcl_lib.CollisionObject(fcl_lib.Capsule(0.0, 2.0), fcl_lib.Transform())
    result = fcl_lib.DistanceResult()
    assert fcl_lib.distance(flat, segment, request, result) == -1.0


def test_contact_is_distance_zero_with_the_contact_code(backends):
    flat = Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    crossing = Triangle([[0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.4, 1]])
    segment = Segment([[0.2, 0.2, -1], [0.2, 0.2, 1]])
    for name, a, b in (("fcl", flat, crossing), ("fcl", flat, segment), ("trimesh", flat, crossing)):
        r = backends[name].closest_points(a, b)
        assert r.failure == Failure.CONTACT and r.distance == 0.0 and r.sqr_distance == 0.0, name
        assert np.isnan(r.point_a).all() and np.isnan(r.point_b).all() and not r.ok
    assert backends["fcl"].distance(flat, crossing) == 0.0


def test_libraries_give_overlapping_solids_a_negative_distance_and_the_backends_contact(backends):
    a = Capsule([[0, 0, -1], [0, 0, 1]], 0.5)
    b = Capsule([[0.8, -1, 0.3], [0.8, 1, 0.3]], 0.5)  # axes 0.8 apart: 0.2 deep
    assert float(proximity.signed_distance(a, b)) == pytest.approx(-0.2)
    # fcl: the depth, with a point of each surface (not a common point)
    request = fcl_lib.DistanceRequest(enable_nearest_points=True)
    result = fcl_lib.DistanceResult()
    x = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # a rotation taking z to y
    d = fcl_lib.distance(
        fcl_lib.CollisionObject(fcl_lib.Capsule(0.5, 2.0), fcl_lib.Transform()),
        fcl_lib.CollisionObject(fcl_lib.Capsule(0.5, 2.0), fcl_lib.Transform(x, np.array([0.8, 0, 0.3]))),
        request,
        result,
    )
    assert d == pytest.approx(-0.2)
    assert np.linalg.norm(result.nearest_points[0] - result.nearest_points[1]) == pytest.approx(0.2)
    # trimesh: negative for overlapping meshes
    import trimesh

    ball = trimesh.Trimesh(*icosphere(1, 1.0), process=False)
    first, second = trimesh.collision.CollisionManager(), trimesh.collision.CollisionManager()
    first.add_object("a", ball)
    moved = np.eye(4)
    moved[0, 3] = 1.5
    second.add_object("b", ball, transform=moved)
    assert first.min_distance_other(second) < 0
    for name in ("fcl", "pybullet"):
        r = backends[name].closest_points(a, b)
        assert r.failure == Failure.CONTACT and r.distance == 0.0 and np.isnan(r.point_a).all(), name
    mesh = TriangleMesh(*icosphere(1, 1.0))
    r = backends["trimesh"].closest_points(mesh, mesh.transformed(moved))
    assert r.failure == Failure.CONTACT and r.distance == 0.0


def test_a_degenerate_triangle_touching_in_fcl_is_false_touching(backends):
    # fcl's sphere against a degenerate BVH triangle is "touching" (as for the point queries);
    # its segment and triangle pairs measure it.
    collinear = Triangle([[0, 0, 0], [1, 0, 0], [3, 0, 0]])
    r = backends["fcl"].closest_points(collinear, Sphere([[0, 5, 0], [1, 6, 0]], 0.5))
    assert (r.failure == Failure.FALSE_TOUCHING).all() and np.isnan(r.distance).all()
    r = backends["fcl"].closest_points(collinear, Segment([[0, 5, 0], [1, 5, 2]]))
    assert r.failure == Failure.OK and r.distance == 5.0


def test_fcl_library_gives_sphere_against_bvh_points_in_each_objects_frame(backends):
    model = fcl_lib.BVHModel()
    model.beginModel(3, 1)
    model.addSubModel(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
    model.endModel()
    tri = fcl_lib.CollisionObject(model, fcl_lib.Transform(np.eye(3), np.array([5.0, 0, 0])))
    at = fcl_lib.Transform(np.eye(3), np.array([5.2, 0.2, 3.0]))
    ball = fcl_lib.CollisionObject(fcl_lib.Sphere(0.5), at)
    result = fcl_lib.DistanceResult()
    assert fcl_lib.distance(tri, ball, fcl_lib.DistanceRequest(enable_nearest_points=True), result) == 2.5
    # in the triangle's frame (at 5, 0, 0 in the world) and in the sphere's
    np.testing.assert_allclose(result.nearest_points[0], [0.2, 0.2, 0.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(result.nearest_points[1], [0.0, 0.0, -0.5], rtol=0, atol=1e-15)
    # the backend moves them to the world
    r = backends["fcl"].closest_points(
        Sphere([5.2, 0.2, 3.0], 0.5), Triangle([[5.0, 0, 0], [6, 0, 0], [5, 1, 0]])
    )
    assert r.failure == Failure.OK
    np.testing.assert_allclose(r.point_a, [5.2, 0.2, 2.5])
    np.testing.assert_allclose(r.point_b, [5.2, 0.2, 0.0])


def _bullet_mesh(p, client, vertices, faces, flags):
    """A static body of a GEOM_MESH: with ``faces`` a triangle mesh, without them the vertices' hull."""
    options = {} if faces is None else {"indices": faces.ravel().tolist(), "flags": flags}
    shape = p.createCollisionShape(p.GEOM_MESH, vertices=vertices.tolist(), physicsClientId=client, **options)
    return p.createMultiBody(baseMass=0, baseCollisionShapeIndex=shape, physicsClientId=client)


def test_pybullet_library_pairs_no_triangle_meshes_together():
    p = pybullet_lib
    client = p.connect(p.DIRECT)
    try:
        v, f = torus(16, 8)
        ring = _bullet_mesh(p, client, v, f, p.GEOM_FORCE_CONCAVE_TRIMESH)
        other = _bullet_mesh(p, client, v + [0.0, 0.0, 2.0], f, p.GEOM_FORCE_CONCAVE_TRIMESH)
        assert p.getClosestPoints(ring, other, 10.0, physicsClientId=client) == ()
        hull = _bullet_mesh(p, client, v + [0.0, 0.0, 2.0], None, 0)
        assert len(p.getClosestPoints(ring, hull, 10.0, physicsClientId=client)) > 0
        # one triangle given with its indices is a triangle mesh too, even without the flag
        t, face = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]])
        one = _bullet_mesh(p, client, t, face, 0)
        two = _bullet_mesh(p, client, t + [0, 0, 1], face, 0)
        assert p.getClosestPoints(one, two, 10.0, physicsClientId=client) == ()
        two = _bullet_mesh(p, client, t + [0, 0, 1], None, 0)
        # less each body's default margin of 0.001, which the backend sets to 0
        assert p.getClosestPoints(one, two, 10.0, physicsClientId=client)[0][8] == pytest.approx(0.998)
        for body in (one, two):
            p.changeDynamics(body, -1, collisionMargin=0.0, physicsClientId=client)
        assert p.getClosestPoints(one, two, 10.0, physicsClientId=client)[0][8] == pytest.approx(1.0)
    finally:
        p.disconnect(physicsClientId=client)


def test_poses_reach_pybullet_as_the_quaternions_of_their_rotations():
    from proximity.adapters._pairs import quaternion

    rng = np.random.default_rng(8)
    turns = [pose(rng, [0, 0, 0])[:3, :3] for _ in range(50)]
    # half turns about each axis, and the identity: every branch of the conversion
    turns += [np.diag(d) for d in ([1.0, -1, -1], [-1.0, 1, -1], [-1.0, -1, 1], [1.0, 1, 1])]
    for rotation in turns:
        back = np.reshape(pybullet_lib.getMatrixFromQuaternion(quaternion(rotation).tolist()), (3, 3))
        np.testing.assert_allclose(back, rotation, rtol=0, atol=1e-15)


def test_pybullet_mesh_pairs_are_the_hull_of_b_or_nothing(backends):
    ring = TriangleMesh(*torus(16, 8))
    ball = TriangleMesh(*icosphere(1, 0.2))
    # the ring's hull fills its hole, where the ball sits: a point of the hull, not of the ring
    r = backends["pybullet"].closest_points(ball, ring)
    assert r.failure == Failure.CONVEX_HULL and np.isnan(r.distance)
    assert "b: GEOM_MESH(vertices alone: their convex hull)" in r.model.primitive
    above = ball.transformed(np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2.0], [0, 0, 0, 1]]))
    r = backends["pybullet"].closest_points(ring, above)  # b convex: its hull is itself
    assert r.failure == Failure.OK
    assert abs(float(r.distance) - float(proximity.distance(ring, above))) <= float(r.tolerance)
    with adapters.get("pybullet", hull=False) as concave:
        r = concave.closest_points(ring, above)
        assert r.failure == Failure.NO_RESULT and "convex hull" not in r.model.primitive
        flat = Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        assert concave.closest_points(flat, flat.transformed(above.transform)).failure == Failure.NO_RESULT
    # with b as its hull (a triangle's hull is itself), triangles pair
    r = backends["pybullet"].closest_points(flat, flat.transformed(above.transform))
    assert r.failure == Failure.OK and abs(float(r.distance) - 2.0) <= float(r.tolerance)
    assert r.model.primitive == "a: GEOM_MESH(1 triangle); b: GEOM_MESH(vertices alone: their convex hull)"
    # a triangle in the ring's hole: the triangle is the hull, and the ring stays a ring
    hole = Triangle([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.0, 0.1, 0.0]])
    r = backends["pybullet"].closest_points(hole, ring)
    assert r.failure == Failure.OK and r.model.primitive.startswith("a: GEOM_MESH(vertices alone")
    assert abs(float(r.distance) - float(proximity.distance(hole, ring))) <= float(r.tolerance)


def test_bad_input_names_the_arguments(backends):
    seg = Segment(np.zeros((2, 2, 3)) + [[0, 0, 0], [1, 0, 0]])
    tri = Triangle(np.zeros((3, 3, 3)) + [[0, 0, 1], [1, 0, 1], [0, 1, 1]])
    fcl = backends["fcl"]
    with pytest.raises(ValueError, match=r"\ba\b.*\bb\b"):
        fcl.closest_points(seg, tri)  # batches (2,) and (3,)
    disk = Disk([0, 0, 0], [0, 0, 1], 1.0)
    with pytest.raises(NotImplementedError, match=r"\(a\).*\(b\)"):
        fcl.closest_points(disk, tri)
    with pytest.raises(NotImplementedError, match=r"a is a rounded Triangle"):
        fcl.closest_points(tri.inflated(0.1), tri)
    with pytest.raises(NotImplementedError, match=r"capsule \(a\) and a triangle \(b\)"):
        backends["trimesh"].closest_points(Capsule([[0, 0, 0], [1, 0, 0]], 0.1), tri)
    with pytest.raises(NotImplementedError, match="a is a 2D shape.*3D shapes only"):
        fcl.closest_points(Triangle([[0, 0], [1, 0], [0, 1]]), Triangle([[0, 2], [1, 2], [0, 3]]))
    with pytest.raises(TypeError, match="b must be a proximity shape"):
        fcl.closest_points(tri, "a triangle")


def test_cross_check_of_pairs_counts_contact_and_stays_within_tolerance():
    rng = np.random.default_rng(6)
    a, b, _, _ = pairs(rng, "segment", "triangle", 12)
    report = adapters.cross_check(a, b, backends=["fcl", "pybullet"], worst=2)
    assert report.shape == "Segment of batch shape (12,) and Triangle of batch shape (12,)"
    for name in ("fcl[raw]", "pybullet[raw]"):
        s = report.summary(name)
        assert s.rows == 12 and s.answered == 12 and s.beyond_tolerance == 0
        assert s.failures.get("CONTACT", 0) >= 1
    assert all(case.point == () for case in report.worst)
    assert report.table().startswith("Segment of batch shape (12,) and Triangle")


def test_trimesh_on_the_callers_coordinates_is_wrong_on_small_pairs_and_cross_check_sees_it():
    rng = np.random.default_rng(10)
    _, _, va, vb = pairs(rng, "triangle", "triangle", 40)
    a, b = Triangle(va * 1e-4), Triangle(vb * 1e-4)
    with adapters.get("trimesh", rescale=False) as raw:
        report = adapters.cross_check(a, b, backends=["trimesh", raw], rescale=True)
        assert raw.closest_points(a, b).model.frame.startswith("the world")
    assert report.summary("trimesh").beyond_tolerance == 0
    s = report.summary("trimesh[raw]")
    assert s.beyond_tolerance > 0 and s.max_relative > 1e-4


def test_cross_check_asks_fcl_in_the_callers_coordinates_where_it_is_wrong_on_small_pairs():
    # Triangle pairs of a size of 1e-4, all apart: fcl's triangle tests have absolute
    # tolerances, and in the caller's coordinates some of its distances are 0 or wrong.
    rng = np.random.default_rng(11)
    _, _, va, vb = pairs(rng, "triangle", "triangle", 400)
    va, vb = va[:300] * 1e-4, vb[:300] * 1e-4  # the last quarter crosses
    apart = proximity.distance(Triangle(va), Triangle(vb), method="certified") > 0
    a, b = Triangle(va[apart]), Triangle(vb[apart])
    report = adapters.cross_check(a, b, backends=["fcl"])
    s = report.summary("fcl[raw]")
    assert s.model.frame.startswith("the world")
    assert s.failures.get("FALSE_TOUCHING", 0) >= 2  # "touching", where the triangles are apart
    assert s.beyond_tolerance >= 5 and s.max_relative > 1e-3
    # The worst rows are wrong against the exact distance too.
    worst = report.worst[0]
    (i,) = worst.index
    exact_distance = float(exact.triangle_triangle_closest(va[apart][i], vb[apart][i]).distance)
    assert abs(worst.distance - exact_distance) > worst.tolerance
    # In a frame of each pair's own fcl is right: the rescaled mode, asked for.
    s = adapters.cross_check(a, b, backends=["fcl"], rescale=True).summary("fcl")
    assert s.answered == s.rows and s.beyond_tolerance == 0 and s.max_relative < 1e-12
    assert s.model.frame.startswith("per call: origin at the center")


def test_cross_check_leaves_out_a_backend_that_cannot_be_given_the_pair():
    ball = TriangleMesh(*icosphere(1, 1.0))
    point, capsule = Point([[3.0, 0, 0], [0, 2.5, 0]]), Capsule([[3, 0, 0], [4, 0, 0]], 0.2)
    for a, kind in ((point, "point"), (capsule, "capsule")):
        report = adapters.cross_check(a, ball)  # every backend; trimesh's pairs are of triangles and meshes
        assert [s.backend for s in report.summaries] == ["fcl[raw]", "pybullet[raw]"]
        for s in report.summaries:
            assert s.answered == s.rows and s.beyond_tolerance == 0
        (left,) = report.left_out
        assert left.backend == "trimesh[raw]"
        assert f"no pair query for a {kind} (a) and a mesh (b)" in left.reason
        table = report.table()
        assert "left out" in table and f"trimesh[raw]: {left.reason}" in table
        left_out = r"backend .trimesh\[raw\]. was left out of this cross-check: .*no pair query"
        with pytest.raises(KeyError, match=left_out):
            report.summary("trimesh[raw]")


def test_cross_check_of_a_query_no_backend_takes_leaves_every_one_out_and_proximity_still_validates():
    # proximity answers 2D pairs
    flat = Triangle([[0, 0], [1, 0], [0, 1]]), Triangle([[0, 2], [1, 2], [0, 3]])
    sphere = Sphere([0, 0, 0], 0.5), [[1.0, 0, 0]]  # no backend models a sphere for point queries
    for query, why in ((flat, "a is a 2D shape"), (sphere, "shape is a Sphere")):
        report = adapters.cross_check(*query)
        assert report.summaries == () and report.worst == ()
        assert [x.backend for x in report.left_out] == [f"{name}[raw]" for name in adapters.NAMES]
        assert all(x.reason.startswith(why) for x in report.left_out)
        assert "no backend answered" in str(report)
    # What proximity refuses, or cannot answer, is still raised.
    tri = Triangle(np.zeros((3, 3, 3)) + [[0, 0, 1], [1, 0, 1], [0, 1, 1]])
    with pytest.raises(ValueError, match=r"\ba\b.*\bb\b"):
        adapters.cross_check(Segment(np.zeros((2, 2, 3)) + [[0, 0, 0], [1, 0, 0]]), tri)
    with pytest.raises(NotImplementedError, match=r"disk \(a\) and a triangle \(b\)"):
        adapters.cross_check(Disk([0, 0, 0], [0, 0, 1], 1.0), tri)


@pytest.mark.parametrize("name", ["fcl", "trimesh", "pybullet"])
def test_backends_in_the_callers_coordinates_answer_unit_pairs_within_their_tolerance(name):
    rng = np.random.default_rng(12)
    a, b, _, _ = pairs(rng, "triangle", "triangle", 12)
    posed = b.transformed(pose(rng, [0.5, 0.0, 0.2]))
    with adapters.get(name, rescale=False) as raw, adapters.get(name) as rescaled:
        assert raw.name == f"{name}[raw]" and rescaled.name == name
        for pair in ((a, b), (a, posed)):
            r = raw.closest_points(*pair)
            assert r.model.frame.startswith("the world") and r.backend == f"{name}[raw]"
            answered = np.isin(r.failure, [Failure.OK, Failure.CONTACT])
            assert answered.all(), [Failure(f).name for f in r.failure]
            ref = proximity.distance(*pair, method="certified")
            np.testing.assert_array_less(np.abs(r.distance - ref), r.tolerance)
            # In the caller's coordinates, L is the world's magnitude and no move is added.
            assert (r.tolerance <= rescaled.closest_points(*pair).tolerance * 4).all()


def test_one_element_radius_arrays_are_rounded_shapes_of_that_radius(backends):
    tri = Triangle([[[3, 0, 0], [4, 0, 0], [3, 1, 0]]])
    axis = [[[0, 0, 0], [1, 0, 0]]]
    for a, b in (
        (Sphere(np.zeros((1, 3)), [0.5]), Sphere(np.zeros((1, 3)), 0.5)),
        (Capsule(axis, [0.2]), Capsule(axis, 0.2)),
        (Segment(axis).inflated([0.2]), Segment(axis).inflated(0.2)),
    ):
        for name in ("fcl", "pybullet"):
            got, expected = backends[name].closest_points(a, tri), backends[name].closest_points(b, tri)
            assert got.failure.tolist() == expected.failure.tolist() == [Failure.OK]
            assert got.distance.tolist() == expected.distance.tolist()
        report = adapters.cross_check(a, tri)
        assert [s.backend for s in report.summaries] == ["fcl[raw]", "pybullet[raw]"]
        assert [x.backend for x in report.left_out] == ["trimesh[raw]"]
    rounded = TriangleMesh(*icosphere(1, 1.0)).inflated([0.1])
    report = adapters.cross_check(rounded, tri)
    assert report.summaries == () and all("rounded TriangleMesh" in x.reason for x in report.left_out)


@pytest.mark.parametrize("module", ["proximity.adapters._base", "proximity.adapters.crosscheck"])
def test_pair_docstring_examples_run(module):
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
