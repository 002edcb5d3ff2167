"""Triangle meshes: brute force and BVH agree bit for bit, and with the per-triangle method.

And the answers are within the robust bound of the exact reference.
"""

import importlib
import tracemalloc

import numpy as np
import pytest

import proximity
from proximity import Feature, TriangleMesh, broadphase
from proximity.broadphase import build as build_module
from proximity.broadphase import refit as refit_module
from proximity.shapes.scene import BRUTE_FORCE_MAX
from proximity.testing import exact
from proximity.testing.meshes import box_points, icosphere, near_points, soup, torus

# The module, which the package's ``broadphase.nearest`` (the function) hides.
nearest_module = importlib.import_module("proximity.broadphase.nearest")

EPS = 2.0**-52
METHODS = list(TriangleMesh.methods)
FIELDS = ("distance", "sqr_distance", "point", "feature", "barycentric", "face")


def _meshes():
    rng = np.random.default_rng(7)
    return {
        "icosphere": icosphere(2),  # 320 faces
        "torus": torus(16, 10),  # 320 faces
        # A third of the faces collinear, with two or with three coincident vertices.
        "soup": soup(rng, 240, size=0.15, degenerate=0.3),
    }


MESHES = _meshes()


def _points(name, n=300, seed=3):
    vertices, faces = MESHES[name]
    rng = np.random.default_rng(seed)
    size = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
    return np.concatenate(
        [
            near_points(rng, vertices, faces, n // 3, 0.02 * size),
            box_points(rng, vertices, n // 3),
            vertices[rng.integers(0, len(vertices), n // 6)],  # exactly on the mesh
            rng.normal(size=(n // 6, 3)) * 10 * size,  # far away
        ]
    )


def assert_same(a, b):
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_a_large_mesh_has_larger_leaves_and_answers_as_brute_force_and_as_refitted(monkeypatch):
    """A mesh over ``LARGE_TREE`` faces (here lowered) gets leaves of up to
    ``LARGE_LEAF_SIZE`` faces, and answers as brute force, and as its refit
    to other vertices answers as a mesh built afresh on them, bit for bit."""
    vertices, faces = torus(40, 20)
    monkeypatch.setattr(build_module, "LARGE_TREE", len(faces))
    mesh = TriangleMesh(vertices, faces, broad_phase="bvh")
    count = mesh._tree.count
    assert count.max() == build_module.LARGE_LEAF_SIZE > broadphase.LEAF_SIZE
    rng = np.random.default_rng(11)
    points = np.concatenate([near_points(rng, vertices, faces, 400, 1e-3), rng.normal(size=(400, 3))])
    brute = TriangleMesh(vertices, faces, broad_phase="brute")
    moved = vertices * [1.3, 0.8, 1.1] + rng.normal(size=vertices.shape) * 0.01
    refit, fresh = mesh.with_vertices(moved), TriangleMesh(moved, faces, broad_phase="bvh")
    np.testing.assert_array_equal(refit._tree.count, count)
    for method in METHODS:
        assert_same(brute.closest_point(points, method=method), mesh.closest_point(points, method=method))
        assert_same(fresh.closest_point(points, method=method), refit.closest_point(points, method=method))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", sorted(MESHES))
def test_brute_force_and_bvh_agree_bit_for_bit(name, method):
    vertices, faces = MESHES[name]
    points = _points(name)
    brute = TriangleMesh(vertices, faces, broad_phase="brute")
    bvh = TriangleMesh(vertices, faces, broad_phase="bvh")
    assert (brute.broad_phase, bvh.broad_phase) == ("brute", "bvh")
    assert bvh._tree.nodes > 1
    assert_same(brute.closest_point(points, method=method), bvh.closest_point(points, method=method))
    np.testing.assert_array_equal(brute.distance(points, method=method), bvh.distance(points, method=method))


@pytest.mark.parametrize(
    "leaf_size", [1, broadphase.LEAF_SIZE, build_module.LARGE_LEAF_SIZE, build_module.BUILD_SUBTREE + 1000]
)
def test_a_large_hierarchy_answers_as_brute_force_for_any_leaf_size(leaf_size):
    """20,480 faces, more than the build splits as whole subtrees and the
    refit fits as whole subtrees: the nodes above them take the other paths."""
    vertices, faces = icosphere(5)
    assert len(faces) > max(build_module.BUILD_SUBTREE, refit_module.REFIT_SUBTREE)
    kinds, params = np.zeros(len(faces), np.int8), broadphase.face_params(vertices, faces)
    tree = broadphase.build_tree(kinds, params, leaf_size)
    # Leaves hold at most leaf_size faces, and only nodes over more are split.
    size = tree.count.copy()
    for i in range(tree.nodes - 1, -1, -1):  # children come after their parent
        if tree.count[i] == 0:
            size[i] = size[tree.child[i]] + size[tree.child[i] + 1]
    leaf = tree.count > 0
    assert size[leaf].max() <= leaf_size < size[~leaf].min() and size[0] == len(faces)
    assert tree.nodes > 1
    brute = broadphase.brute(kinds, params)
    points = np.concatenate(
        [
            near_points(np.random.default_rng(5), vertices, faces, 200, 0.02),
            box_points(np.random.default_rng(6), vertices, 200),
        ]
    )
    method = proximity.methods.resolve("robust")
    ours, theirs = (
        broadphase.nearest(tree, method, points, True),
        broadphase.nearest(brute, method, points, True),
    )
    for field in ("distance", "point", "feature", "extra", "index"):
        np.testing.assert_array_equal(ours[field], theirs[field], err_msg=field)


@pytest.mark.parametrize("leaf_size", [1, 3, broadphase.LEAF_SIZE, build_module.LARGE_LEAF_SIZE, 13, None])
def test_leaves_answered_side_by_side_answer_as_each_face_alone(leaf_size):
    """The robust search answers a leaf's faces ``LANES`` at a time (a kernel
    module's ``row_batch``), the faces whose differences from the point leave
    the safe window again on the scalar path: triangles of every size from
    1e-200 to 1 around the origin, and points at every such distance, so
    that one group of faces holds both; leaves of any size (None: one leaf,
    brute force), faces from rows or read through their vertices."""
    from proximity.numerics.fp import SAFE_MIN

    rng = np.random.default_rng(17)
    scales = 10.0 ** rng.uniform(-200, 0, (400, 1))
    corners = scales[:160, None] * rng.normal(size=(160, 3, 3))
    points = scales[160:] * rng.normal(size=(240, 3))
    per_face = proximity.Triangle(corners).closest_point(points[:, None, :])
    face = np.argmin(per_face.distance, axis=1)  # the first of equal distances
    rows = np.arange(len(points))
    # Both sides of the window among the answers.
    m = np.abs(corners[face] - points[:, None, :]).max(axis=(1, 2))
    assert (m < SAFE_MIN).sum() > 10 and (m >= SAFE_MIN).sum() > 10
    kinds, params = np.zeros(len(corners), np.int8), corners.reshape(-1, 9)
    method = proximity.methods.resolve("robust")
    if leaf_size is None:
        tree, broad_phase = broadphase.brute(kinds, params), "brute"
    else:
        tree, broad_phase = broadphase.build_tree(kinds, params, leaf_size), "bvh"
    ours = broadphase.nearest(tree, method, points, True)
    vertices, faces = corners.reshape(-1, 3), np.arange(3 * len(corners)).reshape(-1, 3)
    mesh = TriangleMesh(vertices, faces, broad_phase=broad_phase).closest_point(points)
    for field, name in (("distance",) * 2, ("point",) * 2, ("feature",) * 2, ("extra", "barycentric")):
        expected = getattr(per_face, name)[rows, face]
        np.testing.assert_array_equal(ours[field], expected, err_msg=field)
        np.testing.assert_array_equal(getattr(mesh, name), expected, err_msg=name)
    np.testing.assert_array_equal(ours["index"], face)
    np.testing.assert_array_equal(mesh.face, face)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", sorted(MESHES))
def test_the_mesh_answers_with_the_nearest_faces_own_answer(name, method):
    """The distance is the least per-triangle distance (NaN faces passed over), ties to the lowest index."""
    vertices, faces = MESHES[name]
    points = _points(name, n=120)
    r = TriangleMesh(vertices, faces).closest_point(points, method=method)
    per_face = proximity.Triangle(vertices[faces]).closest_point(points[:, None, :], method=method)
    with np.errstate(invalid="ignore"):
        face = np.nanargmin(per_face.distance, axis=1)
    rows = np.arange(len(points))
    np.testing.assert_array_equal(r.face, face)
    for field in ("distance", "sqr_distance", "point", "feature", "barycentric"):
        np.testing.assert_array_equal(getattr(r, field), getattr(per_face, field)[rows, face], err_msg=field)


def _exact_nearest(tri, p):
    """``(exact squared distance, nearest face)`` over every face."""
    return min((exact.triangle_sqr_distance(t, p), f) for f, t in enumerate(tri))


@pytest.mark.parametrize("name", sorted(MESHES))
def test_robust_is_within_its_bound_of_the_exact_distance_to_the_mesh(name):
    vertices, faces = MESHES[name]
    tri = vertices[faces]
    points = _points(name, n=60, seed=11)[::4]
    r = TriangleMesh(vertices, faces).closest_point(points)
    for k, p in enumerate(points):
        sqr, nearest = _exact_nearest(tri, p)
        # The minimum over faces moves by at most the bound of either face.
        scale = max(exact.triangle_scale(tri[nearest], p), exact.triangle_scale(tri[r.face[k]], p))
        error = exact.error_in_units(float(r.distance[k]), exact.triangle_distance(tri[nearest], p), scale)
        assert error <= 8.0, (name, p.tolist(), error)


@pytest.mark.parametrize("name", sorted(MESHES))
def test_points_on_vertices_are_at_distance_zero(name):
    vertices, faces = MESHES[name]
    used = np.unique(faces)
    mesh = TriangleMesh(vertices, faces)
    for method in ("robust", "certified"):
        r = mesh.closest_point(vertices[used], method=method)
        assert (r.distance == 0).all() and (r.sqr_distance == 0).all(), method
        np.testing.assert_array_equal(r.point, vertices[used])
        assert np.isin(r.feature, [Feature.VERTEX0, Feature.VERTEX1, Feature.VERTEX2]).all()


def test_points_on_faces_are_within_the_bound_of_zero():
    """Points exactly on faces (dyadic vertices and weights): robust <= 8 eps S, certified exactly 0."""
    rng = np.random.default_rng(5)
    vertices = rng.integers(-64, 64, size=(40, 3)).astype(np.float64)
    faces = np.array([rng.choice(40, 3, replace=False) for _ in range(60)])
    tri = vertices[faces]
    pick = rng.integers(0, len(faces), 24)
    weights = rng.integers(1, 8, size=(24, 3)) / 16.0  # dyadic, so every product and sum below is exact
    weights[:, 0] = 1.0 - weights[:, 1] - weights[:, 2]
    points = np.einsum("ni,nij->nj", weights, tri[pick])  # exact: small integers times 2^-k
    assert all(exact.triangle_sqr_distance(tri[f], p) == 0 for f, p in zip(pick, points, strict=True))
    mesh = TriangleMesh(vertices, faces)
    r = mesh.closest_point(points)
    for k, p in enumerate(points):
        scale = exact.triangle_scale(tri[pick[k]], p)
        assert exact.error_in_units(float(r.distance[k]), 0, scale) <= 8.0
    assert (mesh.distance(points, method="certified") == 0).all()


def test_degenerate_faces_are_queried_like_any_other():
    """A mesh of one collinear and one point-like face: robust answers for the segment and the point."""
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [5, 5, 5]])
    mesh = TriangleMesh(vertices, [[0, 1, 2], [3, 3, 3]], broad_phase="bvh")
    r = mesh.closest_point([[1.5, 2.0, 0.0], [5.0, 5.0, 6.0], [3.0, 0.0, 0.0]])
    assert r.distance.tolist() == [2.0, 1.0, 1.0]
    assert r.face.tolist() == [0, 1, 0]
    np.testing.assert_array_equal(r.point, [[1.5, 0, 0], [5, 5, 5], [2, 0, 0]])
    # eberly gives NaN for a point-like face (0 / 0): no answer, rather than a wrong one.
    point_like = TriangleMesh(vertices, [[3, 3, 3], [3, 3, 3]], broad_phase="bvh")
    e = point_like.closest_point([[1.5, 2.0, 0.0]], method="eberly")
    assert np.isnan(e.distance).all() and (e.face == -1).all() and (e.feature == Feature.NONE).all()
    assert point_like.distance([5.0, 5.0, 8.0]) == 3.0


@pytest.mark.parametrize("scale, offset", [(1e-200, 0.0), (1e200, 0.0), (1.0, 1e10), (2.0**-1000, 0.0)])
def test_extreme_coordinates_keep_brute_force_and_bvh_equal(scale, offset):
    vertices, faces = MESHES["torus"]
    vertices = vertices * scale + offset
    points = _points("torus", n=90) * scale + offset
    # certified's exact fallback cannot round a squared distance beyond the float range (at 1e200).
    for method in [m for m in METHODS if not (m == "certified" and scale > 1e150)]:
        brute = TriangleMesh(vertices, faces, broad_phase="brute").closest_point(points, method=method)
        bvh = TriangleMesh(vertices, faces, broad_phase="bvh").closest_point(points, method=method)
        assert_same(brute, bvh)
        if method == "robust":
            assert np.isfinite(bvh.distance).all()


def test_an_infinite_answer_after_a_left_out_copy_is_the_same_with_the_hierarchy():
    """``eberly``'s squared distance overflows to inf for a point ``1e200``
    from a unit triangle, and is NaN (no answer) on a triangle of edges
    ``1e200``.  The answer is inf, from the unit triangle, with either broad
    phase, though the hierarchy leaves out the copy of the large triangle
    and so stores fewer primitives than the unit triangle's index."""
    unit = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    point = [0.5, 0.5, 1e200]
    vertices = np.concatenate([unit * 1e200, unit])
    for broad_phase in ("brute", "bvh"):
        mesh = TriangleMesh(vertices, [[0, 1, 2], [0, 1, 2], [3, 4, 5]], broad_phase=broad_phase)
        r = mesh.closest_point(point, method="eberly")
        assert (r.distance, r.face, r.feature) == (np.inf, 2, Feature.FACE), broad_phase
        large = proximity.Triangle(unit * 1e200)
        shapes = [large, large, proximity.Triangle(unit)]
        r = proximity.Scene(shapes, broad_phase=broad_phase).closest_point(point, method="eberly")
        assert (r.distance, r.primitive) == (np.inf, 2), broad_phase


def test_permuting_faces_permutes_the_answer():
    vertices, faces = MESHES["icosphere"]
    points = _points("icosphere", n=60)
    order = np.random.default_rng(2).permutation(len(faces))
    a = TriangleMesh(vertices, faces).closest_point(points)
    b = TriangleMesh(vertices, faces[order]).closest_point(points)
    np.testing.assert_array_equal(a.distance, b.distance)
    # Same face, unless another face is at exactly the same distance (an edge or a vertex).
    d_faces = proximity.Triangle(vertices[faces]).distance(points[:, None, :])
    assert (d_faces[np.arange(len(points)), order[b.face]] == a.distance).all()


def test_shapes_scalars_nan_rows_and_frozen_results():
    vertices, faces = MESHES["icosphere"]
    mesh = TriangleMesh(vertices, faces)
    assert isinstance(mesh, proximity.Shape) and mesh.batch_shape == () and mesh.dim == 3
    one = mesh.closest_point([0.0, 0.0, 3.0])
    assert np.ndim(one.distance) == 0 and type(one.feature) is np.int8 and one.point.shape == (3,)
    assert np.ndim(one.face) == 0
    assert isinstance(proximity.distance(mesh, [0.0, 0.0, 3.0]), np.floating)
    grid = mesh.closest_point(np.zeros((2, 5, 3)) + [0.0, 0.0, 2.0])
    assert (
        grid.distance.shape == (2, 5)
        and grid.point.shape == (2, 5, 3)
        and grid.barycentric.shape == (2, 5, 3)
    )
    assert not grid.distance.flags.writeable and not grid.face.flags.writeable
    assert mesh.closest_point(np.zeros((0, 3))).distance.shape == (0,)
    r = mesh.closest_point([[np.nan, 0, 0], [0, 0, 2], [np.inf, 0, 0]])
    assert np.isnan(r.distance[[0, 2]]).all() and r.face[[0, 2]].tolist() == [-1, -1]
    assert r.feature[0] == Feature.NONE and np.isfinite(r.distance[1]) and r.face[1] >= 0
    with pytest.raises(AttributeError):
        mesh.vertices = vertices
    assert not mesh.vertices.flags.writeable and not mesh.faces.flags.writeable


def test_the_broad_phase_is_chosen_by_size():
    vertices, faces = soup(np.random.default_rng(1), BRUTE_FORCE_MAX + 1)
    assert TriangleMesh(vertices, faces[:BRUTE_FORCE_MAX]).broad_phase == "brute"
    assert TriangleMesh(vertices, faces).broad_phase == "bvh"


@pytest.mark.parametrize(
    "vertices, faces, kwargs, message",
    [
        ([[0, 0, 0], [1, 0, 0]], [[0, 1, 1]], {}, None),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], {}, r"vertices must have shape \(V, 3\); got shape \(3, 2\)"),
        ([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], [[0, 1, 2]], {}, "vertices must be finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.0, 1.5, 2.0]], {}, r"got 1\.5 at index \(0, 1\) of a float"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[True, False, True]], {}, "faces must be an integer array"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], {}, r"0 <= index < 3; got 3 at index \(0, 2\)"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, -1, 2]], {}, "got -1"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.zeros((0, 3), int), {}, r"F >= 1; got shape \(0, 3\)"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], {"broad_phase": "kd"}, "broad_phase must be one of"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2], [0, 1]], {}, r"^faces must be an array of shape"),
    ],
)
def test_invalid_meshes_are_refused_with_a_message_naming_the_argument(vertices, faces, kwargs, message):
    if message is None:
        TriangleMesh(vertices, faces, **kwargs)  # a degenerate face is valid
        return
    with pytest.raises(ValueError, match=message):
        TriangleMesh(vertices, faces, **kwargs)


def test_invalid_queries_are_refused():
    mesh = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"points must have shape \(\.\.\., 3\); got shape \(4, 2\)"):
        mesh.distance(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="method must be one of"):
        mesh.closest_point([0, 0, 1], method="fast")


@pytest.mark.parametrize("bad", [[[0, 0, 1], [0, 1]], [["a", "b", "c"]], {"a": 1}, [[2**1100, 0, 0]]])
def test_the_trimesh_drop_in_names_points_it_cannot_read(bad):
    from proximity.trimesh_compat import ProximityQuery, closest_point, signed_distance

    mesh = ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    for query in (closest_point, signed_distance, lambda m, p: ProximityQuery(m).vertex(p)):
        with pytest.raises(ValueError, match=r"^points must be an array of shape \(n, 3\)"):
            query(mesh, bad)


# -- the trimesh drop-in ---------------------------------------------------------------


def test_trimesh_drop_in_returns_trimeshs_tuple():
    from proximity.trimesh_compat import closest_point

    vertices, faces = MESHES["icosphere"]
    points = _points("icosphere", n=60)
    closest, distance, triangle_id = closest_point((vertices, faces), points)
    assert closest.shape == (60, 3) and distance.shape == (60,) and triangle_id.shape == (60,)
    assert closest.dtype == np.float64 and distance.dtype == np.float64 and triangle_id.dtype == np.int64
    assert closest.flags.writeable
    r = TriangleMesh(vertices, faces).closest_point(points)
    np.testing.assert_array_equal(distance, r.distance)
    # The same face but where the closest point is on an edge or a vertex, which the face chosen holds too.
    on_face = r.feature == proximity.Feature.FACE
    np.testing.assert_array_equal(triangle_id[on_face], r.face[on_face])
    chosen = proximity.Triangle(vertices[faces[triangle_id]]).distance(points)
    np.testing.assert_allclose(chosen, r.distance, rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match=r"points must be \(n, 3\), or \(3,\) for one point"):
        closest_point((vertices, faces), [[0.0, 0.0, 1.0, 2.0]])
    with pytest.raises(TypeError, match="mesh must be"):
        closest_point(vertices, points)


def test_trimesh_drop_ins_take_one_point():
    from proximity.trimesh_compat import ProximityQuery, closest_point, signed_distance

    vertices, faces = MESHES["icosphere"]
    points = _points("icosphere", n=12)
    query = ProximityQuery((vertices, faces))
    for function in (closest_point, query.on_surface, query.vertex, signed_distance, query.signed_distance):
        mesh = () if getattr(function, "__self__", None) is query else ((vertices, faces),)
        batch = function(*mesh, points)
        one = function(*mesh, points[3])
        if not isinstance(one, tuple):
            one, batch = (one,), (batch,)
        for a, b in zip(one, batch, strict=True):
            assert np.shape(a) == np.shape(b)[1:] and np.asarray(a).dtype == b.dtype
            np.testing.assert_array_equal(a, b[3])
            if np.ndim(a) == 0:
                assert isinstance(a, np.generic)


# A roof: two faces meeting along the edge from (0, 0, 0) to (0, 1, 0), face 0
# sloping down along -x (normal (-1, 0, 1) / sqrt 2), face 1 flat along +x
# (normal +z).  Points with x < 0 < x + z are beyond the ridge: both faces
# hold their closest point, on the ridge, at the same distance.
ROOF = ([[0, 0, 0], [0, 1, 0], [-1, 0, -1], [1, 0, 0]], [[0, 1, 2], [0, 3, 1]])


@pytest.mark.parametrize(
    "point, face, tie",
    [
        ([-0.05, 0.5, 1.0], 1, True),  # the flat face's normal points more nearly at the point
        ([-0.9, 0.5, 1.0], 0, True),  # the sloped face's does
        ([0.3, 0.5, 0.1], 1, False),  # above the flat face itself
    ],
)
def test_trimesh_drop_in_picks_the_face_facing_the_point_where_faces_tie(point, face, tie):
    from proximity.trimesh_compat import closest_point

    closest, distance, triangle_id = closest_point(ROOF, [point])
    assert triangle_id.tolist() == [face]
    each = proximity.Triangle(np.asarray(ROOF[0], float)[ROOF[1]]).distance(point)
    assert distance[0] == each.min() and bool(each[0] == each[1]) is tie


def test_trimesh_drop_in_ties_go_as_trimeshs():
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("rtree")
    pytest.importorskip("scipy")
    from proximity import trimesh_compat

    tm = trimesh.creation.icosphere(subdivisions=1)
    rng = np.random.default_rng(5)
    directions = rng.normal(size=(400, 3))
    points = directions / np.linalg.norm(directions, axis=1, keepdims=True) * rng.uniform(1.05, 2.0, (400, 1))
    ours = trimesh_compat.closest_point(tm, points)[2]
    theirs = trimesh.proximity.closest_point(tm, points)[2]
    r = TriangleMesh(tm).closest_point(points)
    edge = np.isin(r.feature, [proximity.Feature.EDGE01, proximity.Feature.EDGE12, proximity.Feature.EDGE20])
    # Beyond an edge, both faces are trimesh's two candidates: the same choice.
    assert edge.sum() > 50 and (ours[edge] == theirs[edge]).all()
    assert (ours[edge] != r.face[edge]).any()  # and not always the lowest index
    on_face = r.feature == proximity.Feature.FACE
    assert (ours[on_face] == theirs[on_face]).all()


def test_trimesh_drop_in_agrees_with_trimesh():
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("rtree")
    pytest.importorskip("scipy")
    from proximity import trimesh_compat

    vertices, faces = MESHES["torus"]
    tm = trimesh.Trimesh(vertices, faces, process=False)
    rng = np.random.default_rng(4)
    points = box_points(rng, vertices, 200) * 1.5
    theirs = trimesh.proximity.closest_point(tm, points)
    ours = trimesh_compat.closest_point(tm, points)
    assert [type(a) for a in ours] == [type(a) for a in theirs]
    assert [a.shape for a in ours] == [a.shape for a in theirs]
    assert [a.dtype for a in ours] == [a.dtype for a in theirs]
    # Torus faces of size 0.1: trimesh's absolute tolerances cost it nothing here.
    np.testing.assert_allclose(ours[1], theirs[1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours[0], theirs[0], rtol=0, atol=1e-12)
    d = proximity.Triangle(vertices[faces]).distance(points[:, None, :])
    # The ids differ only where another face is at the same distance.
    assert np.allclose(d[np.arange(len(points)), theirs[2]], ours[1], rtol=0, atol=1e-12)
    # The mesh is converted once and kept while unchanged.
    assert trimesh_compat._mesh(tm) is trimesh_compat._mesh(tm)
    tm.vertices = tm.vertices + 1.0
    moved = trimesh_compat.closest_point(tm, points)[1]
    np.testing.assert_array_equal(moved, TriangleMesh(vertices + 1.0, faces).distance(points))


# -- the adapters ------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["fcl", "trimesh", "pybullet"])
def test_adapters_answer_for_meshes_within_their_documented_tolerance(name):
    import adapters

    pytest.importorskip({"fcl": "fcl", "trimesh": "trimesh", "pybullet": "pybullet"}[name])
    if name == "trimesh":
        pytest.importorskip("rtree")
        pytest.importorskip("scipy")
    vertices, faces = MESHES["torus"]
    mesh = TriangleMesh(vertices, faces)
    rng = np.random.default_rng(8)
    # Off the surface: fcl and pybullet give no nearest point in contact.
    points = box_points(rng, vertices, 40) * 1.3
    points = points[mesh.distance(points) > 0.05]
    with adapters.get(name) as backend:
        r = backend.closest_point(mesh, points)
    assert type(r.result) is proximity.MeshResult and r.result.distance.shape == (len(points),)
    assert (np.asarray(r.failure) == adapters.Failure.OK).all()
    ours = mesh.closest_point(points)
    assert (np.abs(r.distance - ours.distance) <= r.tolerance).all()
    assert r.model.primitive == backend.primitives["mesh"]
    if "face" in r.unknown:
        assert (r.result.face == -1).all()
    else:
        # The library's face is a nearest one: at our distance, up to the tolerance.
        d = proximity.Triangle(vertices[faces[r.result.face]]).distance(points)
        assert (np.abs(d - ours.distance) <= r.tolerance).all()


@pytest.mark.parametrize("exact_ranges", [refit_module.EXACT_RANGES, 16])
@pytest.mark.parametrize("scale", [2.0**-1000, 1e-40, 1.0, 1e39, 2.0**1000])
@pytest.mark.parametrize("offset", [0.0, 3.0])
def test_the_bounds_a_tree_keeps_hold_what_they_bound(scale, offset, exact_ranges, monkeypatch):
    """Every node's box and slabs hold its faces' vertices, its axes make a
    matrix of norm at most 1 (so that their excesses add in squares), and
    every cull row, kept in float32, holds its face, at scales beyond
    float32's range too; and the answers are brute force's.  The slab
    ranges of a node over at most ``EXACT_RANGES`` faces are exact, those
    above merged from its children's (with as few as 16 too, so that most
    nodes of this small mesh are)."""
    monkeypatch.setattr(refit_module, "EXACT_RANGES", exact_ranges)
    monkeypatch.setattr(refit_module, "EXACT_TREE", 0)  # merged ranges on this small mesh too
    vertices, faces = soup(np.random.default_rng(4), 400, degenerate=0.2)
    vertices = (vertices + offset) * scale
    mesh = TriangleMesh(vertices, faces)
    tree = mesh._tree
    assert tree.culling(False).dtype == np.float32
    corners = tree.params[:, :9].reshape(-1, 3, 3)
    cull = tree.culling(False).astype(np.float64)
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    assert (lo >= cull[:, :3]).all() and (hi <= cull[:, 3:6]).all()
    assert (np.linalg.norm(cull[:, 6:9], axis=1) <= 1.0).all()
    # Within the few eps of the coordinates' magnitude that the pruning allows for.
    slack = 16 * EPS * np.abs(corners).max()
    h = np.einsum("nvc,nc->nv", corners, cull[:, 6:9])
    assert (h >= cull[:, 9:10] - slack).all() and (h <= cull[:, 10:11] + slack).all()
    first, last = np.empty(tree.nodes, np.int64), np.empty(tree.nodes, np.int64)
    for i in range(tree.nodes - 1, -1, -1):  # children come after their parent
        if tree.count[i] > 0:
            first[i], last[i] = tree.child[i], tree.child[i] + tree.count[i]
        else:
            first[i], last[i] = first[tree.child[i]], last[tree.child[i] + 1]
    inner = np.flatnonzero(tree.count == 0)
    assert (tree.child[inner] > inner).all()  # which the fit relies on
    bounds = tree.bounds
    for i in range(tree.nodes):
        points = corners[first[i] : last[i]].reshape(-1, 3)
        # The box is the points' extremes, exactly.
        assert (bounds[i, :3] == points.min(axis=0)).all() and (bounds[i, 3:6] == points.max(axis=0)).all(), i
        frame = bounds[i, [6, 7, 8, 11, 12, 13, 16, 17, 18]].reshape(3, 3)
        assert np.linalg.norm(frame, 2) <= 1.0, i
        for c in (6, 11, 16):
            h = points @ bounds[i, c : c + 3]
            assert (h >= bounds[i, c + 3] - slack).all() and (h <= bounds[i, c + 4] + slack).all(), (i, c)
            if np.isfinite(bounds[i, c + 3 : c + 5]).all() and last[i] - first[i] <= exact_ranges:
                # The slab's range is the extremes of the points' projections,
                # each rounded as the fit rounds it.
                u = bounds[i, c : c + 3]
                exact_h = points[:, 0] * u[0] + points[:, 1] * u[1] + points[:, 2] * u[2]
                assert bounds[i, c + 3] == exact_h.min() and bounds[i, c + 4] == exact_h.max(), (i, c)
    points = box_points(np.random.default_rng(5), vertices, 300)
    brute = TriangleMesh(vertices, faces, broad_phase="brute")
    assert_same(brute.closest_point(points), mesh.closest_point(points))


# --- Large batches: the visiting order and the memory a query takes ----------------------------


def _numpy_morton_order(points):
    """The Morton order as NumPy computed it before the compiled sort (the
    reference): cells of a 128^3 grid over the finite points' box, NaN and
    ``+inf`` in the last cell of their axis, ``-inf`` in the first, and two
    stable sorts of the codes' low 11 and high 10 bits."""
    top = (1 << nearest_module.MORTON_BITS) - 1
    kept = points[np.isfinite(points).all(axis=1)]
    if len(kept) == 0:
        return np.arange(len(points))
    low, high = kept.min(axis=0), kept.max(axis=0)
    with np.errstate(invalid="ignore", over="ignore"):
        span = float(np.max(high - low))
        inv = top / span if 0.0 < span < np.inf else 0.0
        g = (points - low) * inv
        g = np.where(g >= 0.0, g, np.where(g < 0.0, 0.0, float(top)))
        cells = np.minimum(g, float(top)).astype(np.int64)
    spread = nearest_module._SPREAD
    code = spread[cells[:, 0]] | (spread[cells[:, 1]] << 1) | (spread[cells[:, 2]] << 2)
    first = np.argsort((code & 0x7FF).astype(np.uint16), kind="stable")
    return first[np.argsort((code[first] >> 11).astype(np.uint16), kind="stable")]


def _batches():
    rng = np.random.default_rng(11)
    holes = rng.uniform(-1, 1, (20_000, 3))
    holes[rng.random(holes.shape) < 0.03] = np.nan
    holes[rng.random(holes.shape) < 0.03] = np.inf
    holes[rng.random(holes.shape) < 0.03] = -np.inf
    same = np.ones((6000, 3))
    same[::7, 1], same[::11, 2], same[::13, 0] = -np.inf, np.nan, np.inf
    wide = rng.uniform(-1, 1, (6000, 3))
    wide[0, 0], wide[1, 0], wide[2, 1] = -1e308, 1e308, -np.inf  # an extent beyond the float range
    return {
        "uniform": rng.uniform(-1, 1, (30_000, 3)),
        "clustered": np.concatenate([rng.normal(c, 1e-4, (5000, 3)) for c in rng.uniform(-9, 9, (6, 3))]),
        "on a few cells": rng.integers(0, 3, (20_000, 3)).astype(float),  # runs of one cell to keep stable
        "non-finite": holes,
        "one point, repeated": same,
        "none finite": np.full((5000, 3), np.nan),
        "wider than the float range": wide,
        "flat": np.c_[rng.uniform(size=(8000, 2)), np.zeros(8000)],
        "subnormal": rng.uniform(size=(8000, 3)) * 1e-310,
        "huge": rng.uniform(-1, 1, (8000, 3)) * 1e300,
        "empty": np.zeros((0, 3)),
        "one": np.ones((1, 3)),
    }


BATCHES = _batches()


@pytest.mark.parametrize("one_pass", [False, True])
@pytest.mark.parametrize("name", list(BATCHES))
def test_the_compiled_morton_order_is_numpys_permutation(name, one_pass, monkeypatch):
    """The compiled sort gives the permutation NumPy's stable sorts gave, by
    either of its sorts (one counting pass over every cell, or two over the
    codes' low and high bits)."""
    monkeypatch.setattr(nearest_module, "ONE_PASS_MIN", 0 if one_pass else 1 << 62)
    points = BATCHES[name]
    order = nearest_module._morton_order(points)
    assert order.dtype == np.int64 and order.flags.writeable
    np.testing.assert_array_equal(order, _numpy_morton_order(points))


def test_a_batch_wider_than_the_float_range_is_answered_as_its_points_one_by_one():
    """Points from -1e308 to 1e308 span more than the float range: the grid's
    scale was inf * 0 = NaN for the farthest, whose cell index then failed
    the lookup of its code (IndexError) in any batch large enough to sort."""
    vertices, faces = MESHES["icosphere"]
    mesh = TriangleMesh(vertices, faces)
    points = np.random.default_rng(12).uniform(-2, 2, (nearest_module.SORT_MIN + 10, 3))
    points[0, 0], points[1, 0], points[2] = -1e308, 1e308, [0.0, 1e308, -1e308]
    batch = mesh.closest_point(points)
    one_by_one = [mesh.closest_point(p) for p in points[:3]] + [mesh.closest_point(points[3:100])]
    for name in FIELDS:
        joined = np.concatenate([np.reshape(getattr(r, name), (-1,) + getattr(batch, name).shape[1:])
                                 for r in one_by_one])  # fmt: skip
        np.testing.assert_array_equal(getattr(batch, name)[:100], joined, err_msg=name)
    assert np.isfinite(batch.distance).all()


def _traced_peak(function, *args, **kwargs):
    """The peak of the memory NumPy (and Python) allocate while ``function`` runs, in bytes."""
    tracemalloc.start()
    try:
        function(*args, **kwargs)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize(
    "query, method, most",
    [
        # The distances (8 bytes a point) and the visiting order (8).
        ("distance", "robust", 20),
        # And the bound of the rows certified's filter leaves undecided (8).
        ("distance", "certified", 28),
        # The result's 74 bytes a point and the order.
        ("closest_point", "robust", 88),
    ],
)
def test_a_large_batch_takes_little_memory_beyond_its_answers(query, method, most):
    """The peak of NumPy's allocations in a query of a million points, per
    point: the answers, the visiting order and, only for a method with an
    exact fallback, the bound of the undecided rows (its sort's scratch is
    gone before the outputs are made).  Before, the order's NumPy sort took
    80 bytes a point with the outputs already allocated, and ``undecided``
    was made for every method."""
    vertices, faces = icosphere(4)
    mesh = TriangleMesh(vertices, faces)
    points = np.random.default_rng(13).uniform(-1.2, 1.2, (1_000_000, 3))
    getattr(mesh, query)(points[: 2 * nearest_module.SORT_MIN], method=method)  # compiled, tree bounds made
    peak = _traced_peak(getattr(mesh, query), points, method=method)
    assert peak <= most * len(points), peak / len(points)
