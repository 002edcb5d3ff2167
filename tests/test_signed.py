"""Signed distance and containment of closed meshes.

Distances are checked against the exact reference; signs against what is
known of each solid (a convex polytope's face planes, a box's extents, the
analytic torus away from its tessellation) and against the winding number,
on random points and on points 1e-9 of the size off faces, edges and
vertices, after rigid motions and 1e6 away from the origin.
"""

import pickle

import numpy as np
import pytest

from proximity import TriangleMesh
from proximity.signs import signed as _signed
from proximity.testing import exact
from proximity.testing.meshes import box_points, near_points

trimesh = pytest.importorskip("trimesh")


def _closed_meshes():
    box = trimesh.creation.box(extents=[1.0, 2.0, 0.5])
    return {
        "icosphere": trimesh.creation.icosphere(subdivisions=2),  # 320 faces
        "box": box,
        "torus": trimesh.creation.torus(1.0, 0.35, major_sections=24, minor_sections=12),
    }


MESHES = {name: (np.asarray(m.vertices), np.asarray(m.faces)) for name, m in _closed_meshes().items()}


def _size(vertices):
    return float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))


def _truth(name, vertices, faces, points):
    """``(inside, known)``: the sign from the solid itself, where it is known without doubt."""
    if name == "box":
        half = vertices.max(axis=0)
        return (np.abs(points) < half).all(axis=1), np.ones(len(points), bool)
    if name == "icosphere":
        # Convex: inside the polytope iff on the inner side of every face's plane.
        tri = vertices[faces]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        height = np.einsum("fj,nfj->nf", normal, points[:, None, :] - tri[None, :, 0])
        return height.max(axis=1) < 0, np.abs(height).min(axis=1) > 1e-12
    # The analytic torus, where the point is farther from it than the tessellation strays.
    ring = np.hypot(points[:, 0], points[:, 1]) - 1.0
    analytic = np.hypot(ring, points[:, 2]) - 0.35
    stray = 1.35 * (1 - np.cos(np.pi / 24)) + 0.35 * (1 - np.cos(np.pi / 12))
    return analytic < 0, np.abs(analytic) > 2 * stray


def _off_features(vertices, faces, rng, height):
    """Points ``height`` off the surface, both sides, above face interiors, edges and vertices.

    Each moves from a point of the surface along a direction that the
    surface's side there decides: a face's normal; the sum of the two
    faces' normals at an edge's midpoint; at a vertex, the sum of its faces'
    normals.  Returns ``(points, outside)``.
    """
    tri = vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    n = 60
    f = rng.integers(0, len(faces), n)
    w = rng.uniform(0.1, 1.0, (n, 3))
    w /= w.sum(axis=1, keepdims=True)
    on_faces, face_dirs = np.einsum("ni,nij->nj", w, tri[f]), unit[f]
    # Edges: the midpoint of a shared edge, and the two faces there.
    adjacency = trimesh.Trimesh(vertices, faces, process=False)
    index = rng.integers(0, len(adjacency.face_adjacency), n)
    pairs, shared = adjacency.face_adjacency[index], adjacency.face_adjacency_edges[index]
    on_edges = vertices[shared].mean(axis=1)
    edge_dirs = unit[pairs[:, 0]] + unit[pairs[:, 1]]
    vertex = rng.integers(0, len(vertices), n)
    vertex_dirs = np.zeros((len(vertices), 3))
    np.add.at(vertex_dirs, faces.reshape(-1), np.repeat(unit, 3, axis=0))
    on_vertices, vertex_dirs = vertices[vertex], vertex_dirs[vertex]
    base = np.concatenate([on_faces, on_edges, on_vertices])
    dirs = np.concatenate([face_dirs, edge_dirs, vertex_dirs])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    side = np.where(np.arange(len(base)) % 2 == 0, 1.0, -1.0)
    return base + side[:, None] * height * dirs, side > 0


def _points(name, seed=0):
    vertices, faces = MESHES[name]
    rng = np.random.default_rng(seed)
    size = _size(vertices)
    centre = vertices.mean(axis=0)
    return np.concatenate(
        [
            centre + 1.5 * (box_points(rng, vertices, 300) - centre),
            near_points(rng, vertices, faces, 200, 0.01 * size),
        ]
    )


# -- distances ------------------------------------------------------------------------


@pytest.mark.parametrize("method", TriangleMesh.methods)
@pytest.mark.parametrize("name", sorted(MESHES))
def test_the_magnitude_is_the_distance_bit_for_bit(name, method):
    mesh = TriangleMesh(*MESHES[name])
    points = _points(name)
    signed = mesh.signed_distance(points, method=method)
    np.testing.assert_array_equal(np.abs(signed), mesh.distance(points, method=method))


@pytest.mark.parametrize("name", sorted(MESHES))
def test_signed_distances_are_within_the_robust_bound_of_the_exact_distance(name):
    vertices, faces = MESHES[name]
    tri = vertices[faces]
    points = _points(name, seed=5)[::25]
    signed = TriangleMesh(vertices, faces).signed_distance(points)
    for p, s in zip(points, signed, strict=True):
        nearest = min(range(len(tri)), key=lambda f, p=p: exact.triangle_sqr_distance(tri[f], p))
        d_exact = exact.triangle_distance(tri[nearest], p)
        error = exact.error_in_units(abs(float(s)), d_exact, exact.triangle_scale(tri[nearest], p))
        assert error <= 8.0, (name, p.tolist(), error)


# -- signs ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(MESHES))
def test_signs_of_random_points_match_the_solid(name):
    vertices, faces = MESHES[name]
    points = _points(name, seed=1)
    mesh = TriangleMesh(vertices, faces)
    inside, known = _truth(name, vertices, faces, points)
    assert known.sum() > 0.5 * len(points) and 0.1 < inside[known].mean() < 0.9
    signed = mesh.signed_distance(points)
    assert ((signed < 0) == inside)[known].all()
    np.testing.assert_array_equal(mesh.contains(points), signed <= 0)
    # The winding number is a second, independent answer, on every point.
    assert ((mesh.signed_distance(points, sign="winding") < 0) == (signed < 0)).all()


@pytest.mark.parametrize("height", [1e-9, 1e-6, 1e-3])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_signs_just_off_faces_edges_and_vertices(name, height):
    vertices, faces = MESHES[name]
    rng = np.random.default_rng(2)
    points, outside = _off_features(vertices, faces, rng, height * _size(vertices))
    mesh = TriangleMesh(vertices, faces)
    r = mesh.closest_point(points)
    # Every kind of closest feature is there: vertices (0-2), edges (3-5) and faces (6).
    assert set(np.digitize(r.feature, [3, 6]).tolist()) == {0, 1, 2}
    signed = mesh.signed_distance(points)
    assert (signed > 0).tolist() == outside.tolist()
    if name != "torus":  # convex: the face planes say it too
        inside, known = _truth(name, vertices, faces, points)
        assert known.all() and (inside == ~outside).all()


@pytest.mark.parametrize("name", sorted(MESHES))
def test_signs_survive_rigid_motions_and_offsets_of_1e6(name):
    vertices, faces = MESHES[name]
    rng = np.random.default_rng(3)
    size = _size(vertices)
    points, outside = _off_features(vertices, faces, rng, 1e-9 * size)
    points = np.concatenate([points, _points(name, seed=3)])
    expected = TriangleMesh(vertices, faces).signed_distance(points) > 0
    assert (expected[: len(outside)] == outside).all()
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))  # a rotation
    for rotation, shift in [
        (q, rng.normal(size=3)),
        (np.eye(3), np.full(3, 1e6)),
        (q, np.array([1e6, -3e6, 2e6])),
    ]:
        moved = TriangleMesh(vertices @ rotation.T + shift, faces)
        signed = moved.signed_distance(points @ rotation.T + shift)
        assert ((signed > 0) == expected).all(), (name, shift)


def test_points_on_the_surface_get_plus_zero():
    vertices, faces = MESHES["icosphere"]
    mesh = TriangleMesh(vertices, faces)
    signed = mesh.signed_distance(vertices)
    assert (signed == 0).all() and not np.signbit(signed).any()
    assert mesh.contains(vertices).all()
    # Exactly on faces of a box: certified gives 0 there.
    box = TriangleMesh(*MESHES["box"])
    on = np.array([[0.5, 0.25, 0.125], [-0.25, 1.0, 0.0], [0.125, -0.5, -0.25]])
    signed = box.signed_distance(on, method="certified")
    assert (signed == 0).all() and not np.signbit(signed).any()


def test_nan_rows_shapes_scalars_and_read_only_results():
    mesh = TriangleMesh(*MESHES["icosphere"])
    signed = mesh.signed_distance([[0, 0, 0], [np.nan, 0, 0], [0, 0, 3], [np.inf, 0, 0]])
    assert signed[0] < 0 and signed[2] > 0 and np.isnan(signed[[1, 3]]).all()
    assert mesh.contains([[0, 0, 0], [np.nan, 0, 0]]).tolist() == [True, False]
    assert not signed.flags.writeable
    grid = np.zeros((2, 4, 3)) + [0.0, 0.0, 2.0]
    assert mesh.signed_distance(grid).shape == (2, 4) and mesh.contains(grid).shape == (2, 4)
    one = mesh.signed_distance([0.0, 0.0, 0.0])
    assert np.ndim(one) == 0 and one < 0
    assert isinstance(mesh.contains([0.0, 0.0, 2.0]), np.bool_)
    assert mesh.signed_distance(np.zeros((0, 3))).shape == (0,)
    with pytest.raises(ValueError, match="sign must be one of"):
        mesh.signed_distance([0, 0, 0], sign="parity")
    with pytest.raises(TypeError, match="keyword-only"):
        mesh.signed_distance([0, 0, 0], "robust")
    with pytest.raises(ValueError, match="points must have shape"):
        mesh.contains(np.zeros((3, 2)))


@pytest.mark.parametrize("sign", ["auto", "pseudonormal", "winding"])
def test_reversed_faces_keep_the_sign(sign):
    """Inside is where the winding number is not 0: the same whichever way the faces point."""
    vertices, faces = MESHES["torus"]
    points = _points("torus")
    ours = TriangleMesh(vertices, faces).signed_distance(points, sign=sign)
    flipped = TriangleMesh(vertices, faces[:, ::-1])
    theirs = flipped.signed_distance(points, sign=sign)
    # The distances may differ in the last bit (the faces' vertices come in another order).
    assert (np.sign(theirs) == np.sign(ours)).all()
    np.testing.assert_allclose(theirs, ours, rtol=1e-14, atol=0)
    assert (ours != 0).all() and 0.1 < (ours < 0).mean() < 0.9
    assert flipped.validity.inverted and not TriangleMesh(vertices, faces).validity.inverted


# -- degenerate faces ---------------------------------------------------------------------

OCTAHEDRON = (
    np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float),
    np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]),
)


def _inside_octahedron(points):
    return np.abs(points).sum(axis=1) < 1


def _near_segment(a, b, rng, n=40, height=1e-9):
    """Points ``height`` (relative) off segment ``ab`` of the octahedron, in every direction around it."""
    t = rng.uniform(0.0, 1.0, n)
    t[:4] = [0.0, 0.5, 1.0, 0.25]
    base = a + t[:, None] * (b - a)
    direction = rng.normal(size=(n, 3))
    return base + height * direction / np.linalg.norm(direction, axis=1, keepdims=True)


def test_a_zero_area_face_leaves_its_points_to_the_winding_number(monkeypatch):
    """Edge (0, 2) of the octahedron split at its midpoint 6 by a collinear face (0, 2, 6), listed first."""
    vertices = np.vstack([OCTAHEDRON[0], [[0.5, 0.5, 0.0]]])  # exactly the midpoint of vertices 0 and 2
    faces = [list(f) for f in OCTAHEDRON[1]]
    faces.remove([0, 2, 4])
    faces = [[0, 2, 6], [0, 6, 4], [6, 2, 4]] + faces  # (2, 0, 5) stays across the old edge
    mesh = TriangleMesh(vertices, faces)
    rng = np.random.default_rng(4)
    points = _near_segment(vertices[0], vertices[2], rng)
    calls = []
    winding = TriangleMesh._winding_sides

    def counted(mesh, points, distance):
        calls.append(len(points))
        return winding(mesh, points, distance)

    monkeypatch.setattr(TriangleMesh, "_winding_sides", counted)
    r = mesh.closest_point(points)
    assert (r.face == 0).any()  # the degenerate face is the nearest for some
    signed = mesh.signed_distance(points)
    assert calls and calls[0] >= (r.face == 0).sum()
    inside = _inside_octahedron(points)
    assert ((signed < 0) == inside).all() and 0 < inside.sum() < len(points)
    # Points of the box around it, with no doubt about their side, are right too.
    far = rng.uniform(-1.2, 1.2, (400, 3))
    far = far[np.abs(np.abs(far).sum(axis=1) - 1) > 1e-6]
    assert ((mesh.signed_distance(far) < 0) == _inside_octahedron(far)).all()


def test_a_collapsed_face_is_left_out_of_the_surface(monkeypatch):
    """A face (0, 0, 2) with a repeated index, first in the list, over the octahedron's edge (0, 2).

    The surface is closed without it, and its sides are the edge's and
    vertex 0's: the pseudonormal decides every point, none is left to the
    winding number."""
    vertices, faces = OCTAHEDRON
    mesh = TriangleMesh(vertices, np.vstack([[[0, 0, 2]], faces]))
    rng = np.random.default_rng(6)
    points = _near_segment(vertices[0], vertices[2], rng, n=200, height=1e-6)
    r = mesh.closest_point(points)
    assert (r.face == 0).sum() >= 10
    monkeypatch.setattr(TriangleMesh, "_winding_sides", None)  # not called
    inside = _inside_octahedron(points)
    assert ((mesh.signed_distance(points) < 0) == inside).all() and 0 < inside.sum() < len(points)


# -- meshes that are not closed ----------------------------------------------------------


@pytest.mark.parametrize(
    "faces, message",
    [
        (OCTAHEDRON[1][1:], r"edge \(\d, \d\) of face \d has no face running it .*a boundary"),
        (np.vstack([OCTAHEDRON[1], [[0, 2, 5]]]), "more than two faces meet there"),
        (np.vstack([OCTAHEDRON[1][:7], OCTAHEDRON[1][7:, ::-1]]), "orientation"),
    ],
    ids=["hole", "three faces on an edge", "one face reversed"],
)
def test_meshes_that_are_not_closed_are_refused_unless_the_winding_number_is_asked_for(faces, message):
    mesh = TriangleMesh(OCTAHEDRON[0], faces)
    with pytest.raises(ValueError, match=message) as caught:
        mesh.signed_distance([0.0, 0.0, 0.0])
    assert "sign='winding'" in str(caught.value)
    with pytest.raises(ValueError, match="closed"):
        mesh.contains([0.0, 0.0, 0.0])
    # The winding number answers; with one face of eight missing the centre is still 7/8 inside.
    signed = mesh.signed_distance([[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]], sign="winding")
    assert signed[0] < 0 < signed[1]
    assert mesh.contains([0.0, 0.0, 0.1], sign="winding")


@pytest.mark.parametrize("name", sorted(MESHES))
def test_points_the_pseudonormal_leaves_undecided_get_the_same_sign_from_the_winding_number(
    name, monkeypatch
):
    vertices, faces = MESHES[name]
    points = np.concatenate(
        [_points(name, seed=9), _off_features(vertices, faces, np.random.default_rng(9), 1e-9)[0]]
    )
    decided = TriangleMesh(vertices, faces).signed_distance(points)
    calls = []
    winding = TriangleMesh._winding_sides

    def counted(mesh, points, distance):
        calls.append(len(points))
        return winding(mesh, points, distance)

    monkeypatch.setattr(TriangleMesh, "_winding_sides", counted)
    monkeypatch.setattr(_signed, "MARGIN", 1.0)  # a margin no product clears: every point undecided
    np.testing.assert_array_equal(TriangleMesh(vertices, faces).signed_distance(points), decided)
    assert calls == [len(points)]


def test_winding_numbers_are_one_inside_and_zero_outside_a_closed_mesh():
    vertices, faces = MESHES["torus"]
    points = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, -1.1, 0.1], [3.0, 3.0, 3.0]])
    w = _signed.winding_numbers(vertices, faces, points)
    np.testing.assert_allclose(w, [1.0, 0.0, 1.0, 0.0], atol=1e-12)


# -- pickling ---------------------------------------------------------------------------


def test_pickled_meshes_keep_their_signs_and_send_no_cache():
    mesh = TriangleMesh(*MESHES["torus"])
    points = _points("torus")
    before = mesh.signed_distance(points)
    assert mesh._signs is not None
    copy = pickle.loads(pickle.dumps(mesh))
    assert copy._signs is None
    np.testing.assert_array_equal(copy.signed_distance(points), before)
    assert len(pickle.dumps(mesh)) == len(pickle.dumps(TriangleMesh(*MESHES["torus"])))


# -- the trimesh drop-ins ----------------------------------------------------------------


@pytest.mark.parametrize("name", ["icosphere", "torus", "box"])
def test_trimesh_drop_ins_agree_with_trimesh(name):
    pytest.importorskip("rtree")
    pytest.importorskip("scipy")
    from proximity import trimesh_compat

    tm = _closed_meshes()[name]
    points = _points(name, seed=7)
    theirs = trimesh.proximity.signed_distance(tm, points)
    ours = trimesh_compat.signed_distance(tm, points)
    assert type(ours) is type(theirs) and ours.shape == theirs.shape and ours.dtype == theirs.dtype
    assert ours.flags.writeable
    # trimesh's convention, positive inside: the opposite of TriangleMesh.signed_distance.
    np.testing.assert_array_equal(ours, -TriangleMesh(tm).signed_distance(points))
    # The same side wherever trimesh decides one (it calls points within tol.merge positive).
    decided = np.abs(theirs) > trimesh.tol.merge
    assert decided.mean() > 0.95 and (np.sign(ours) == np.sign(theirs))[decided].all()
    # trimesh's distance is to a face it found, ours to the nearest: never farther, nearly always equal.
    assert (np.abs(ours) <= np.abs(theirs) + 1e-12).all()
    assert np.isclose(np.abs(ours), np.abs(theirs), rtol=0, atol=1e-12).mean() >= 0.98

    query, their_query = trimesh_compat.ProximityQuery(tm), trimesh.proximity.ProximityQuery(tm)
    np.testing.assert_array_equal(query.signed_distance(points), ours)
    for a, b in zip(query.on_surface(points), trimesh_compat.closest_point(tm, points), strict=True):
        np.testing.assert_array_equal(a, b)
    distance, vertex = query.vertex(points)
    their_distance, their_vertex = their_query.vertex(points)
    np.testing.assert_allclose(distance, their_distance, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(vertex, their_vertex)


def test_trimesh_drop_ins_refuse_what_they_cannot_answer():
    from proximity import trimesh_compat

    with pytest.raises(ValueError, match=r"points must be \(n, 3\)"):
        trimesh_compat.signed_distance(OCTAHEDRON, [[0.0, 0.0]])
    with pytest.raises(ValueError, match="needs a closed mesh"):
        trimesh_compat.signed_distance((OCTAHEDRON[0], OCTAHEDRON[1][1:]), [[0.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"points must be \(n, 3\)"):
        trimesh_compat.ProximityQuery(OCTAHEDRON).vertex(np.zeros((2, 2)))
