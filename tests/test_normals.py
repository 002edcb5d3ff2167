"""``normal`` where the closest point is within rounding of the query point: faces, edges,
vertices, posed views, scenes with poses, rounded shapes and pairs, against exact sides."""

import pickle
from fractions import Fraction

import numpy as np
import pytest

import proximity
from proximity.posed import to_local, to_world
from proximity.testing.meshes import icosphere

FACE = proximity.Feature.FACE
TRANSLATIONS = [1e3, 1e4, 1e5, 1e6]


def _side(vertices, point):
    """The exact side of ``point`` of the plane of ``vertices``: the sign of
    ``(P - V0) . ((V1 - V0) x (V2 - V0))`` on the floats' exact values."""
    a, b, c, p = ([Fraction(float(x)) for x in v] for v in (*vertices, point))
    e0 = [b[i] - a[i] for i in range(3)]
    e1 = [c[i] - a[i] for i in range(3)]
    n = [e0[1] * e1[2] - e0[2] * e1[1], e0[2] * e1[0] - e0[0] * e1[2], e0[0] * e1[1] - e0[1] * e1[0]]
    value = sum((p[i] - a[i]) * n[i] for i in range(3))
    return (value > 0) - (value < 0)


def _face_normals(triangles, points, distance=None):
    """Each triangle's unit normal towards the point's exact side (its own on the plane, and
    where the query's ``distance`` is 0)."""
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    side = np.array([_side(t, p) for t, p in zip(triangles, points, strict=True)])
    if distance is not None:
        side[np.asarray(distance).reshape(-1) == 0] = 1
    return n * np.where(side < 0, -1.0, 1.0)[:, None]


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _pose(rotation, translation):
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, translation
    return pose


def _sphere():
    return proximity.TriangleMesh(*icosphere(3))


# -- the exact side ---------------------------------------------------------------------------


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1e-20, 1.0, 1e20, 1e150, 1e300])
def test_plane_sides_are_exact(scale):
    from proximity.numerics.normals import plane_sides

    rng = np.random.default_rng(11)
    n = 60
    tri = rng.normal(size=(n, 3, 3)) * scale
    # Within rounding of the plane (centroids, nudged by an ulp), on it (a vertex), and off it.
    points = tri.mean(axis=1)
    points[::3] = np.nextafter(points[::3], np.inf)
    points[1::6] = tri[1::6, 2]
    points[2::6] += rng.normal(size=(len(points[2::6]), 3)) * scale
    tri[4::12, 0, 0] *= 1e-250  # far below the others: decided in rational arithmetic
    points[4::12] = tri[4::12].mean(axis=1)
    disks = rng.normal(size=(n, 10)) * scale
    disks[:, 6:9] = rng.normal(size=(n, 3)) * rng.choice([1e-200, 1.0, 1e200], size=(n, 1))
    u = np.cross(disks[:, 6:9], rng.normal(size=(n, 3)))
    on_disk = disks[:, 0:3] + u / np.max(np.abs(u), axis=1, keepdims=True) * scale
    kinds = np.concatenate([np.zeros(n, np.int8), np.ones(n, np.int8)])
    params = np.zeros((2 * n, 10))
    params[:n, :9] = tri.reshape(n, 9)
    params[n:] = disks
    got = plane_sides(kinds, params, np.concatenate([points, on_disk]))
    want = [_side(t, p) for t, p in zip(tri, points, strict=True)]
    for row, p in zip(disks, on_disk, strict=True):
        c, normal, q = ([Fraction(float(x)) for x in v] for v in (row[0:3], row[6:9], p))
        value = sum((q[i] - c[i]) * normal[i] for i in range(3))
        want.append((value > 0) - (value < 0))
    np.testing.assert_array_equal(got, want)
    assert 0 in want and 1 in want and -1 in want


# -- point queries ----------------------------------------------------------------------------


def test_icosphere_centroids_get_their_faces_normals():
    # A centroid computed in floats is within rounding of its face (about 7e-17 off): its
    # normal is the face's, on the point's exact side, not the direction of the rounding.
    mesh = _sphere()
    triangles = mesh.vertices[mesh.faces]
    centroids = triangles.mean(axis=1)
    r = mesh.closest_point(centroids)
    assert (r.feature == FACE).all() and (r.face == np.arange(len(mesh.faces))).all()
    assert (r.distance < 1e-15).all()
    np.testing.assert_allclose(r.normal, _face_normals(triangles, centroids, r.distance), rtol=0, atol=1e-12)


@pytest.mark.parametrize("offset", TRANSLATIONS)
def test_posed_meshes_near_their_faces_get_the_faces_normals_turned(offset):
    mesh = _sphere()
    rotation = _rotation(1)
    translation = np.array([offset, -offset / 3, offset / 7])
    posed = mesh.transformed(_pose(rotation, translation))
    triangles = mesh.vertices[mesh.faces]
    world = to_world(triangles.mean(axis=1), rotation, translation)
    r = posed.closest_point(world)
    normal = np.asarray(r.normal)
    assert np.isfinite(normal).all()
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, rtol=0, atol=1e-12)
    # Decided in the mesh's frame, for the point as moved there.
    expected = _face_normals(triangles, to_local(world, rotation, translation), r.distance) @ rotation.T
    face = np.asarray(r.feature) == FACE
    assert face.mean() > 0.9
    np.testing.assert_allclose(normal[face], expected[face], rtol=0, atol=1e-12)
    # The scene of the posed mesh, moved by with_poses, answers the same normals.
    scene = proximity.Scene([mesh.transformed(np.eye(4))]).with_poses(_pose(rotation, translation)[None])
    s = scene.closest_point(world)
    assert np.isfinite(s.normal).all()
    np.testing.assert_allclose(np.asarray(s.normal)[face], expected[face], rtol=0, atol=1e-12)


def _pseudonormals(mesh, face, feature):
    """The angle-weighted pseudonormal (Baerentzen and Aanaes) of each face's vertex or
    edge ``feature``, from the mesh's faces (a closed mesh, as the icosphere is)."""
    v, f = mesh.vertices, mesh.faces
    e0, e1 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    unit = np.cross(e0, e1)
    unit /= np.linalg.norm(unit, axis=1, keepdims=True)
    out = []
    for k, code in zip(face, feature, strict=True):
        if code <= 2:  # a vertex: its faces' normals weighted by their angles there
            vertex = f[k, code]
            total = np.zeros(3)
            for j in np.flatnonzero((f == vertex).any(axis=1)):
                c = int(np.flatnonzero(f[j] == vertex)[0])
                a, b = v[f[j, (c + 1) % 3]] - v[vertex], v[f[j, (c + 2) % 3]] - v[vertex]
                total += unit[j] * np.arccos(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b))
        else:  # an edge: its two faces' normals
            i, j = f[k, code - 3], f[k, (code - 2) % 3]
            twins = np.flatnonzero((f == i).any(axis=1) & (f == j).any(axis=1))
            total = unit[twins].sum(axis=0)
        out.append(total / np.linalg.norm(total))
    return np.array(out).reshape(-1, 3)


@pytest.mark.parametrize("offset", TRANSLATIONS)
def test_posed_meshes_at_their_vertices_get_the_features_normals_turned(offset):
    # A vertex moved to the world and back is off it by the rounding of the moves, which
    # is no direction: the normal is that of the face, edge or vertex it is nearest, as
    # on the mesh itself.
    mesh = _sphere()
    rotation = _rotation(2)
    translation = np.array([-offset, offset / 5, offset / 3])
    world = to_world(mesh.vertices, rotation, translation)
    local = to_local(world, rotation, translation)
    pose = _pose(rotation, translation)
    scene = proximity.Scene([mesh.transformed(np.eye(4))]).with_poses(pose[None])
    for shape in (mesh.transformed(pose), scene):
        r = shape.closest_point(world)
        face, feature = np.asarray(r.face if hasattr(r, "face") else r.primitive), np.asarray(r.feature)
        assert (np.asarray(r.distance) > 0).any() and (feature != FACE).sum() > 20
        expected = _face_normals(mesh.vertices[mesh.faces[face]], local, r.distance)
        rest = feature != FACE
        expected[rest] = _pseudonormals(mesh, face[rest], feature[rest])
        np.testing.assert_allclose(r.normal, expected @ rotation.T, rtol=0, atol=1e-12)


def test_a_point_within_rounding_of_an_edge_gets_the_shapes_normal_there():
    # 2e6 long: the closest point is off by about eps * 1e6 along the segment, ten
    # times the distance; the normal is the segment's own, as on it.
    segment = proximity.Segment([[-1e6, 0, 0], [1e6, 0, 0]])
    on = segment.closest_point([0.3, 0.0, 0.0]).normal
    for point in ([0.3, 1e-12, 1e-13], [1.0, -1e-12, 0.0]):
        assert segment.closest_point(np.array(point)).normal.tolist() == on.tolist()
    triangle = proximity.Triangle([[-1e6, 0, 0], [1e6, 0, 0], [0, 1e6, 0]])
    r = triangle.closest_point([0.3, -1e-12, 1e-13])
    assert str(r.feature_name) == "EDGE01" and r.normal.tolist() == [0.0, 0.0, 1.0]
    # A mesh's vertex nudged by an ulp: its pseudonormal.
    mesh = _sphere()
    v = mesh.vertices[5]
    nudged = np.nextafter(v, v + [1.0, 0.0, 0.0])
    np.testing.assert_allclose(mesh.closest_point(nudged).normal, v / np.linalg.norm(v), atol=1e-6)
    np.testing.assert_array_equal(mesh.closest_point(nudged).normal, mesh.closest_point(v).normal)


@pytest.mark.parametrize("offset", [0.0, *TRANSLATIONS])
def test_triangles_and_disks_near_their_faces_get_the_faces_normals(offset):
    rng = np.random.default_rng(3)
    triangles = rng.normal(size=(300, 3, 3)) + offset
    centroids = triangles.mean(axis=1)
    r = proximity.Triangle(triangles).closest_point(centroids)
    face = np.asarray(r.feature) == FACE
    assert face.mean() > 0.9
    expected = _face_normals(triangles, centroids, r.distance)
    np.testing.assert_allclose(np.asarray(r.normal)[face], expected[face], rtol=0, atol=1e-12)
    # Disks: points of the plane (center plus in-plane offsets, rounded).
    center = rng.normal(size=(300, 3)) + offset
    normal = rng.normal(size=(300, 3))
    u = np.cross(normal, rng.normal(size=(300, 3)))
    u *= (0.5 / np.linalg.norm(u, axis=1))[:, None]
    points = center + u
    disks = proximity.Disk(center, normal, 1.0)
    r = disks.closest_point(points)
    assert (np.asarray(r.feature) == FACE).all()
    side = [np.sign(sum((Fraction(p) - Fraction(c)) * Fraction(n) for p, c, n in zip(*row, strict=True)))
            for row in zip(points.tolist(), center.tolist(), normal.tolist(), strict=True)]  # fmt: skip
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    side = np.where(np.asarray(r.distance) == 0, 1, side)  # on the disk: its own orientation
    expected = unit * np.where(side < 0, -1.0, 1.0)[:, None]
    np.testing.assert_allclose(r.normal, expected, rtol=0, atol=1e-12)


def test_2d_triangles_within_rounding_of_an_edge_get_its_outward_normal():
    rng = np.random.default_rng(10)
    v = rng.normal(size=(300, 3, 2)) + 1e3
    midpoints = (v[:, 0] + v[:, 1]) / 2  # rounded: on the edge's line, or a little off it
    r = proximity.Triangle(v).closest_point(midpoints)
    edge = np.asarray(r.feature) == proximity.Feature.EDGE01
    assert edge.mean() > 0.5
    e = v[:, 1] - v[:, 0]
    n = np.stack([e[:, 1], -e[:, 0]], axis=1) / np.linalg.norm(e, axis=1, keepdims=True)
    n *= np.where(np.einsum("ij,ij->i", v[:, 2] - v[:, 0], n) > 0, -1.0, 1.0)[:, None]  # away from V2
    np.testing.assert_allclose(np.asarray(r.normal)[edge], n[edge], rtol=0, atol=1e-12)
    inside = np.asarray(r.feature) == FACE
    assert np.isnan(np.asarray(r.normal)[inside]).all()


def test_a_scene_takes_each_shapes_own_normals():
    # A mesh in a scene keeps its pseudonormals; a posed triangle its frame's face normal.
    mesh = _sphere()
    rotation, translation = _rotation(4), np.array([1e6, 2e6, -1e6])
    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    scene = proximity.Scene([mesh, proximity.Triangle(tri).transformed(_pose(rotation, translation))])
    r = scene.closest_point(mesh.vertices[:20])
    np.testing.assert_array_equal(r.normal, mesh.closest_point(mesh.vertices[:20]).normal)
    world = to_world(np.array([[0.25, 0.25, 0.0], [0.5, 0.25, 0.0]]), rotation, translation)
    r = scene.closest_point(world)
    assert (np.asarray(r.source) == 1).all()
    local = to_local(world, rotation, translation)
    expected = _face_normals(np.array([tri, tri]), local, r.distance) @ rotation.T
    np.testing.assert_allclose(r.normal, expected, rtol=0, atol=1e-12)


def test_rounded_shapes_near_a_face_of_their_core_get_its_normal():
    # The rounded surface over a face is the face's plane moved by r: its normal is the
    # face's, which a small radius at a large offset leaves to rounding in P - point.
    rng = np.random.default_rng(5)
    offset = 1e4
    triangles = rng.normal(size=(200, 3, 3)) + offset
    slab = proximity.Triangle(triangles).inflated(1e-11)
    centroids = triangles.mean(axis=1)
    n_up = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    n_up /= np.linalg.norm(n_up, axis=1, keepdims=True)
    points = centroids + 2e-11 * n_up
    r = slab.closest_point(points)
    face = np.asarray(r.feature) == FACE
    assert face.mean() > 0.9
    expected = _face_normals(triangles, points)
    np.testing.assert_allclose(np.asarray(r.normal)[face], expected[face], rtol=0, atol=1e-12)
    # A capsule: points on its side get the radial direction.
    capsule = proximity.Capsule([[0, 0, 0], [0, 0, 4]], 0.5)
    angle = rng.uniform(0, 2 * np.pi, 100)
    radial = np.stack([np.cos(angle), np.sin(angle), np.zeros(100)], axis=1)
    points = radial * 0.5 + [0, 0, 2]
    np.testing.assert_allclose(capsule.closest_point(points).normal, radial, rtol=0, atol=1e-12)


def test_normals_of_posed_results_survive_indexing_pickling_and_cutoffs():
    mesh = _sphere()
    posed = mesh.transformed(_pose(_rotation(6), [1e5, 0, 0]))
    world = to_world(mesh.vertices[mesh.faces].mean(axis=1), posed.rotation, posed.translation)
    r = posed.closest_point(world)
    np.testing.assert_array_equal(r[3:9].normal, r.normal[3:9])
    np.testing.assert_array_equal(r[4].normal, r.normal[4])
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(r)).normal, r.normal)
    cut = posed.closest_point(np.concatenate([world, world + 10.0]), max_distance=1.0)
    normal = np.asarray(cut.normal)
    np.testing.assert_array_equal(normal[: len(world)], r.normal)
    assert np.isnan(normal[len(world) :]).all()


# -- pairs ------------------------------------------------------------------------------------


def _pairs():
    rng = np.random.default_rng(7)
    mesh = _sphere()

    def normal(*shape):
        return rng.normal(size=shape)

    return [
        (proximity.Triangle(normal(40, 3, 3)), proximity.Triangle(normal(40, 3, 3) + 2.0)),
        (proximity.Segment(normal(40, 2, 3)), proximity.Triangle(normal(40, 3, 3) + 2.0)),
        (proximity.Point(normal(40, 3) * 3), mesh),
        (mesh, proximity.Segment(normal(40, 2, 3) * 3)),
        (proximity.Capsule(normal(40, 2, 3), 0.1), proximity.Sphere(normal(40, 3) + 3, 0.2)),
        (mesh, mesh.transformed(_pose(_rotation(8), [3.0, 0.5, 0.0]))),
    ]


@pytest.mark.parametrize("k", range(len(_pairs())))
def test_pair_normals_point_from_a_to_b(k):
    a, b = _pairs()[k]
    r = proximity.closest_points(a, b)
    normal = np.asarray(r.normal)
    assert normal.shape == np.shape(r.point_a)
    d = np.asarray(r.distance)
    apart = d > 1e-6
    assert apart.any()
    v = (np.asarray(r.point_b) - np.asarray(r.point_a))[apart]
    np.testing.assert_allclose(normal[apart], v / d[apart][..., None], rtol=0, atol=1e-9)
    np.testing.assert_allclose(proximity.closest_points(b, a).normal, -normal, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(r.swapped().normal, -normal + 0.0)
    if np.ndim(d):
        np.testing.assert_array_equal(r[1:3].normal, normal[1:3])
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(r)).normal, normal)


def test_pair_normals_where_they_touch_come_from_a_face():
    floor = proximity.Triangle([[0, 0, 0], [4, 0, 0], [0, 4, 0]])
    below = proximity.Segment([[1, 1, 0], [1, 1, -3]])
    above = proximity.Segment([[1, 1, 5], [1, 1, 0]])
    assert proximity.closest_points(floor, below).normal.tolist() == [0.0, 0.0, -1.0]
    assert proximity.closest_points(floor, above).normal.tolist() == [0.0, 0.0, 1.0]
    assert proximity.closest_points(below, floor).normal.tolist() == [0.0, 0.0, 1.0]
    # Two segments crossing have no direction of separation.
    a = proximity.Segment([[0, 0, 0], [4, 0, 0]])
    b = proximity.Segment([[1, -1, 0], [1, 1, 0]])
    assert np.isnan(proximity.closest_points(a, b).normal).all()
    # Face on face, within rounding, far from the origin and posed: the face's normal.
    mesh = _sphere()
    rotation, translation = _rotation(9), np.array([1e6, -1e6, 5e5])
    tri = mesh.vertices[mesh.faces[17]]
    piece = proximity.Triangle(tri.mean(axis=0) + 0.1 * (tri - tri.mean(axis=0)))  # inside face 17
    r = proximity.closest_points(mesh.transformed(_pose(rotation, translation)), piece.transformed(
        _pose(rotation, translation)))  # fmt: skip
    assert np.isfinite(r.normal).all() and int(r.face_a) == 17
    n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    expected = n / np.linalg.norm(n) @ rotation.T
    assert min(np.abs(r.normal - expected).max(), np.abs(r.normal + expected).max()) <= 1e-12


def test_pair_normals_of_scenes_of_instances():
    mesh = _sphere()
    scene = proximity.Scene([mesh.transformed(np.eye(4)), mesh.transformed(np.eye(4))])
    T = np.tile(np.eye(4), (2, 1, 1))
    T[1, 0, 3] = 1e6
    moved = scene.with_poses(T)
    r = proximity.closest_points(moved, proximity.Point([[1e6 + 3, 0, 0], [0, 0, -3]]))
    np.testing.assert_allclose(r.normal, [[1, 0, 0], [0, 0, -1]], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(r.source_a, [1, 0])
    np.testing.assert_array_equal(r[1].normal, r.normal[1])
    np.testing.assert_array_equal(r.swapped().normal, -r.normal + 0.0)
