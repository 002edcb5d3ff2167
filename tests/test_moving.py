"""Moving objects: posed views, instances, refitted meshes."""

import pickle
import tracemalloc

import numpy as np
import pytest

import proximity
from proximity import broadphase
from proximity.broadphase.refit import REFIT_SUBTREE
from proximity.numerics.rigid import to_local, to_world
from proximity.results import asdict
from proximity.shapes import posed as posed_module
from proximity.testing import exact, examples
from proximity.testing.meshes import icosphere, near_points, soup, torus

EPS = 2.0**-52


def _pose(seed, spread=5.0):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rotation, rng.normal(size=3) * spread
    return T


def _moved(T, points):
    return points @ T[:3, :3].T + T[:3, 3]


SHAPES = {
    "triangle": lambda: examples.example("triangle", (6,)),
    "segment": lambda: examples.example("segment", (6,)),
    "disk": lambda: examples.example("disk", (6,)),
    "circle": lambda: examples.example("circle", (6,)),
    "point": lambda: examples.example("point", (6,)),
    "mesh": lambda: proximity.TriangleMesh(*torus(16, 8)),
    "scene": lambda: proximity.Scene(
        [proximity.TriangleMesh(*icosphere(1)), proximity.Disk([3, 0, 0], [0, 0, 1], 1.0)]
    ),
    "capsule": lambda: proximity.Capsule([[0, 0, 0], [0, 0, 2]], 0.5),
}


@pytest.mark.parametrize("name", list(SHAPES))
def test_posed_shapes_answer_as_the_shape_at_the_moved_points(name):
    shape = SHAPES[name]()
    T = _pose(1)
    posed = shape.transformed(T)
    world = np.random.default_rng(2).normal(size=(300,) + (1,) * len(shape.batch_shape) + (3,)) * 3 + T[:3, 3]
    local = to_local(world, T[:3, :3], T[:3, 3])  # as the view moves them
    for method in shape.methods:
        r, core = posed.closest_point(world, method=method), shape.closest_point(local, method=method)
        np.testing.assert_array_equal(r.distance, core.distance)
        np.testing.assert_array_equal(r.feature, core.feature)
        np.testing.assert_allclose(r.point, _moved(T, np.asarray(core.point)), rtol=0, atol=1e-13)
        np.testing.assert_allclose(r.normal, np.asarray(core.normal) @ T[:3, :3].T, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(posed.distance(world, method=method), r.distance)


def _summed(points, rotation, translation, inverse):
    """``R^T (P - t)`` (``inverse``) or ``R P + t``, each coordinate one expression summed left to right."""
    if inverse:
        d = points - translation
        columns = [d[..., 0] * rotation[0, c] + d[..., 1] * rotation[1, c] + d[..., 2] * rotation[2, c]
                   for c in range(3)]  # fmt: skip
        return np.stack(columns, axis=-1)
    p = points
    rows = [p[..., 0] * rotation[c, 0] + p[..., 1] * rotation[c, 1] + p[..., 2] * rotation[c, 2]
            for c in range(3)]  # fmt: skip
    return np.stack(rows, axis=-1) + translation


@pytest.mark.parametrize("shape", [(3,), (1, 3), (5000, 3), (7, 11, 3), (0, 3)])
def test_points_move_with_the_bits_of_the_sums_written_out(shape):
    """``to_local`` and ``to_world`` sum each coordinate in the order the
    instanced search does, without a temporary a partial sum: the same bits
    as the expressions, NaN, inf, subnormal and huge coordinates included."""
    rng = np.random.default_rng(8)
    T = _pose(9, spread=1e3)
    points = rng.normal(size=shape) * 10.0 ** rng.integers(-310, 300, size=shape)
    points.reshape(-1)[::17] = np.nan
    points.reshape(-1)[::23] = -np.inf
    for move, inverse in [(to_local, True), (to_world, False)]:
        got, want = move(points, T[:3, :3], T[:3, 3]), _summed(points, T[:3, :3], T[:3, 3], inverse)
        assert got.shape == want.shape and got.dtype == want.dtype
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))


@pytest.mark.parametrize("move", [to_local, to_world])
def test_points_move_with_two_temporaries_of_one_coordinate(move):
    """NumPy's peak allocations moving a million points: the moved points (24
    bytes a point) and two arrays of one coordinate (16), where the
    expressions' partial sums, ``P - t`` and the columns stacked took 72."""
    T = _pose(14)
    points = np.random.default_rng(15).normal(size=(1_000_000, 3))
    tracemalloc.start()
    try:
        move(points, T[:3, :3], T[:3, 3])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= 41 * len(points), peak / len(points)  # and a megabyte of whatever else runs


def _answers(shape, points):
    """Every answer of ``shape`` at ``points``: its queries' arrays and the result's fields and normals."""
    r = shape.closest_point(points)
    out = {f"closest_point.{name}": np.asarray(value) for name, value in asdict(r).items()}
    out["normal"] = np.asarray(r.normal)
    out["distance"] = shape.distance(points)
    out["far"] = shape.distance(points, max_distance=0.5)
    if hasattr(shape.shape, "signed_distance"):
        out["signed_distance"] = shape.signed_distance(points)
    if hasattr(shape.shape, "contains"):
        out["contains"] = shape.contains(points)
    return out


@pytest.mark.parametrize("name", ["mesh", "scene", "capsule", "one triangle", "rounded mesh"])
def test_a_posed_shape_answers_a_large_batch_a_part_at_a_time_as_all_at_once(name, monkeypatch):
    """A posed shape without a batch of its own moves and asks a large batch
    ``CHUNK`` points at a time (here lowered; the parts sorted or not as the
    whole is): every answer, flag and normal is the one the whole batch asked
    at once gives, bit for bit, of the batch's shape."""
    make = {
        "one triangle": lambda: proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
        "rounded mesh": lambda: proximity.TriangleMesh(*torus(16, 8)).inflated(0.1),
    }.get(name, SHAPES.get(name))
    posed = make().transformed(_pose(10))
    points = np.random.default_rng(11).normal(size=(50, 200, 3)) * 2 + _pose(10)[:3, 3]
    whole = _answers(posed, points)
    monkeypatch.setattr(posed_module, "CHUNK", 4500)  # parts of 4500, 4500 and 1000 points
    parts = _answers(posed, points)
    assert whole.keys() == parts.keys()
    for key, value in whole.items():
        part = parts[key]
        assert part.shape == value.shape == points.shape[:-1] + value.shape[2:], key
        assert part.dtype == value.dtype and part.flags.writeable == value.flags.writeable, key
        np.testing.assert_array_equal(part, value, err_msg=key)


@pytest.mark.parametrize("query, most", [("distance", 24), ("closest_point", 100)])
def test_a_posed_mesh_asks_a_large_batch_with_little_memory_beyond_its_answers(query, most, monkeypatch):
    """The peak of NumPy's allocations in a posed mesh's query of a million
    points, per point: the answers (8 and 74 bytes), and the moved part and
    its query's scratch, of ``CHUNK`` points (here 2^17: 8 bytes a point of
    the batch).  The whole batch was moved at once, through temporaries of
    every partial sum, before the mesh was asked."""
    monkeypatch.setattr(posed_module, "CHUNK", 1 << 17)
    posed = proximity.TriangleMesh(*icosphere(4)).transformed(_pose(12, spread=0.1))
    points = np.random.default_rng(13).uniform(-1.2, 1.2, (1_000_000, 3))
    getattr(posed, query)(points[:10_000])  # compiled, the tree's bounds made
    tracemalloc.start()
    try:
        getattr(posed, query)(points)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= most * len(points), peak / len(points)


def test_the_normal_on_a_posed_mesh_is_the_meshs_at_the_moved_point():
    """Where a point is on the posed mesh (distance 0), its normal is the
    mesh's at the point the query moved, rotated: the face's side, not the
    direction of a rounding.  It was the mesh's at the point moved again by
    BLAS's product, whose rounding differs from the query's sums: a third of
    these points were then off the surface by an ulp, their normals the
    direction of that ulp (some pointing inwards)."""
    mesh = proximity.TriangleMesh(*icosphere(2))
    rng = np.random.default_rng(16)
    on = 0
    for seed in range(20):
        T = _pose(seed, spread=1.0)
        posed = mesh.transformed(T)
        world = np.asarray(posed.closest_point(rng.normal(size=(500, 3)) * 2 + T[:3, 3]).point)
        r = posed.closest_point(world)
        rows = np.asarray(r.distance) == 0
        moved = to_local(world[rows], T[:3, :3], T[:3, 3])
        want = np.asarray(mesh.closest_point(moved).normal) @ T[:3, :3].T
        np.testing.assert_allclose(np.asarray(r.normal)[rows], want, rtol=0, atol=1e-15, err_msg=seed)
        on += rows.sum()
    assert on >= 20


def test_a_posed_mesh_is_within_the_robust_bound_of_the_mesh_built_moved():
    vertices, faces = torus(24, 12)
    T = _pose(3, spread=100.0)
    posed = proximity.TriangleMesh(vertices, faces).transformed(T)
    moved = proximity.TriangleMesh(_moved(T, vertices), faces)
    points = _moved(T, near_points(np.random.default_rng(4), vertices, faces, 400, 1e-2))
    a, b = posed.distance(points), moved.distance(points)
    for k in range(0, 400, 40):
        face = moved.closest_point(points[k]).face
        tri = moved.vertices[moved.faces[face]]
        scale = float(exact.triangle_scale(tri, points[k])) + float(np.linalg.norm(points[k] - T[:3, 3]))
        assert abs(a[k] - b[k]) <= 16 * EPS * scale, k


def test_posing_composes_and_costs_nothing_per_face():
    mesh = proximity.TriangleMesh(*icosphere(3))
    A, B = _pose(5), _pose(6)
    twice = mesh.transformed(A).transformed(B)
    assert twice.shape is mesh and twice.shape._tree is mesh._tree
    np.testing.assert_allclose(twice.transform, B @ A, rtol=0, atol=1e-14)
    points = np.random.default_rng(7).normal(size=(50, 3)) * 4
    np.testing.assert_allclose(
        twice.distance(points), mesh.transformed(B @ A).distance(points), rtol=0, atol=1e-13
    )


@pytest.mark.parametrize(
    "T, match",
    [
        (np.eye(3), "4x4"),
        (np.full((4, 4), np.nan), "finite"),
        (np.diag([2.0, 1, 1, 1]), "rigid"),
        (np.diag([-1.0, 1, 1, 1]), "reflection"),
        (np.vstack([np.eye(4)[:3], [0, 0, 1, 1]]), "last row"),
    ],
)
def test_bad_transforms_name_the_argument(T, match):
    with pytest.raises(ValueError, match=f"transform must .*{match}"):
        proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).transformed(T)


def test_rigid_accepts_rotations_within_the_tolerance_and_names_the_rest():
    from proximity.numerics.rigid import RIGID_TOLERANCE, rigid

    turn = np.eye(4)
    turn[:3, :3], turn[:3, 3] = _pose(3)[:3, :3], [1.0, -2.0, 3.0]
    r, t = rigid(turn)
    np.testing.assert_array_equal(r, turn[:3, :3])
    np.testing.assert_array_equal(t, turn[:3, 3])
    for stretch, ok in ((0.75, True), (1.5, False)):  # near the tolerance: decided as in batches
        T = turn.copy()
        T[:3, 0] *= 1.0 + stretch * RIGID_TOLERANCE / 2
        if ok:
            np.testing.assert_array_equal(rigid(T)[0], T[:3, :3])
            np.testing.assert_array_equal(rigid(T[None])[0][0], T[:3, :3])
        else:
            with pytest.raises(ValueError, match="must be rigid"):
                rigid(T)


def test_instances_share_their_mesh_and_answer_as_the_meshes_built_moved():
    vertices, faces = icosphere(3)
    mesh = proximity.TriangleMesh(vertices, faces)
    poses = [_pose(10 + k, spread=4.0) for k in range(12)]
    extra = proximity.Disk([0, 0, 9], [0, 0, 1], 1.0)
    scene = proximity.Scene([*(mesh.transformed(T) for T in poses), extra])
    flat = proximity.Scene([*(proximity.TriangleMesh(_moved(T, vertices), faces) for T in poses), extra])
    assert all(s.shape._tree is mesh._tree for s in scene.shapes[:-1])
    points = np.random.default_rng(8).normal(size=(2000, 3)) * 6
    for method in scene.methods:
        a, b = scene.closest_point(points, method=method), flat.closest_point(points, method=method)
        np.testing.assert_allclose(a.distance, b.distance, rtol=0, atol=64 * EPS * 30)
        same = a.primitive == b.primitive
        assert same.mean() > 0.9
        np.testing.assert_array_equal(a.source, np.searchsorted(scene.offsets, a.primitive, side="right") - 1)
        np.testing.assert_allclose(a.point[same], b.point[same], rtol=0, atol=1e-12)
    # A new frame: only the poses change.
    moved = [_pose(30 + k, spread=4.0) for k in range(12)]
    again = scene.with_poses(np.array(moved))
    fresh = proximity.Scene([*(mesh.transformed(T) for T in moved), extra])
    np.testing.assert_array_equal(again.distance(points), fresh.distance(points))
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(again)).distance(points), fresh.distance(points))
    with pytest.raises(ValueError, match=r"transforms must have shape \(12, 4, 4\)"):
        scene.with_poses(np.array(moved[:3]))


@pytest.mark.parametrize("loose", [False, True])
def test_a_posed_scene_of_instances_in_a_scene_answers_as_its_instances_posed(loose):
    # A posed scene of instances brings its instances, posed by both poses,
    # and its loose primitives posed by its own: the same bits as those
    # members posed one by one, its primitives numbered as in the flat scene.
    vertices, faces = icosphere(1)
    mesh = proximity.TriangleMesh(vertices, faces)
    A, B, C = (_pose(40 + k, spread=3.0) for k in range(3))
    triangle = proximity.Triangle([[0, 0, 4], [1, 0, 4], [0, 1, 5]])
    last = proximity.Scene([triangle]) if loose else mesh.transformed(B)
    inner = proximity.Scene([mesh.transformed(A), triangle if loose else mesh.transformed(B)])
    nested = proximity.Scene([inner.transformed(C), mesh])
    flat = proximity.Scene([mesh.transformed(A).transformed(C), last.transformed(C), mesh])
    points = np.random.default_rng(9).normal(size=(500, 3)) * 5
    a, b = nested.closest_point(points), flat.closest_point(points)
    for name, value in asdict(b).items():
        if name != "source":
            np.testing.assert_array_equal(getattr(a, name), value, err_msg=name)
    np.testing.assert_array_equal(a.source, np.where(b.source == 2, 1, 0))
    moved = nested.with_poses(np.array([B]))
    np.testing.assert_array_equal(
        moved.distance(points),
        proximity.Scene([mesh.transformed(A).transformed(B), last.transformed(B), mesh]).distance(points),
    )
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(nested)).distance(points), b.distance)
    segments = proximity.Segment(np.random.default_rng(10).normal(size=(20, 2, 3)) * 5)
    pa, pb = proximity.closest_points(nested, segments), proximity.closest_points(flat, segments)
    for name in ("distance", "point_a", "point_b", "feature_a", "primitive_a"):
        np.testing.assert_array_equal(getattr(pa, name), getattr(pb, name), err_msg=name)


@pytest.mark.parametrize("skew", [0.0, 1e-10])
def test_instances_skip_only_instances_that_cannot_hold_the_answer(skew):
    # Each instance answers as its posed view alone (the same moved point),
    # so the scene's answer is the least of theirs, bit for bit, ties to the
    # lowest primitive; with rotations orthonormal only to ``skew`` too.
    vertices, faces = icosphere(2)
    mesh = proximity.TriangleMesh(vertices, faces)
    poses = []
    for k in range(20):
        T = _pose(50 + k, spread=3.0)
        T[:3, :3] += skew * np.random.default_rng(k).normal(size=(3, 3))
        poses.append(T)
    scene = proximity.Scene([mesh.transformed(T) for T in poses])
    # Enough points to be queried in spatial order, in blocks that each keep
    # only the instances near them.
    points = np.random.default_rng(5).normal(size=(6000, 3)) * 5
    got = scene.closest_point(points)
    each = np.array([mesh.transformed(T).distance(points) for T in poses])
    least = each.min(axis=0)
    np.testing.assert_array_equal(got.distance, least)
    first = np.argmax(each == least, axis=0)
    np.testing.assert_array_equal(got.source, first)
    near = scene.distance(points, max_distance=0.5)
    np.testing.assert_array_equal(near, np.where(least <= 0.5, least, np.inf))
    exact = scene.distance(points[:500], method="certified")
    each = np.array([mesh.transformed(T).distance(points[:500], method="certified") for T in poses])
    np.testing.assert_array_equal(exact, each.min(axis=0))


def test_an_instance_sphere_passes_through_the_farthest_vertex_of_its_mesh():
    # The lower bound of an instance's faces: every vertex within the sphere
    # (exactly, up to the slack of the bounds), and no wider than they need,
    # where the corners of the leaves' boxes reach beyond the surface.
    from fractions import Fraction

    from proximity.broadphase.instances import BOX_SLACK

    tree = proximity.TriangleMesh(*icosphere(3))._tree
    centre, radius = tree.sphere(False)
    magnitude = tree.boxes(False)[2]
    farthest = max(
        sum((Fraction(float(a)) - Fraction(float(c))) ** 2 for a, c in zip(v, centre, strict=True))
        for v in tree.vertices
    )
    assert Fraction(radius - BOX_SLACK * magnitude) ** 2 <= farthest <= Fraction(radius * (1 + 4 * EPS)) ** 2
    assert tree.sphere(True)[1] > 1.1 * radius  # the leaves' corners (for eberly's loose boxes)


_TETRAHEDRON = (
    np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float),
    [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
)


@pytest.mark.parametrize("shape", [torus(40, 20), _TETRAHEDRON], ids=["tree", "one leaf"])
def test_a_refitted_mesh_answers_as_one_built_afresh_bit_for_bit(shape):
    vertices, faces = shape
    mesh = proximity.TriangleMesh(vertices, faces)
    rng = np.random.default_rng(9)
    moved = vertices * [1.3, 0.8, 1.1] + rng.normal(size=vertices.shape) * 0.01
    refit = mesh.with_vertices(moved)
    fresh = proximity.TriangleMesh(moved, faces)
    points = np.concatenate([near_points(rng, moved, faces, 1500, 1e-3), rng.normal(size=(1500, 3))])
    for method in mesh.methods:
        a, b = refit.closest_point(points, method=method), fresh.closest_point(points, method=method)
        for name, value in asdict(b).items():
            np.testing.assert_array_equal(getattr(a, name), value, err_msg=name)
    np.testing.assert_array_equal(refit.signed_distance(points), fresh.signed_distance(points))
    with pytest.raises(ValueError, match="vertices must have shape"):
        mesh.with_vertices(moved[:-1])
    with pytest.raises(ValueError, match="vertices must be finite"):
        mesh.with_vertices(np.where(np.arange(len(moved))[:, None] == 3, np.nan, moved))


def test_a_mesh_whose_tree_keeps_its_faces_rows_is_built_again(monkeypatch):
    # Faces whose hashes collide at the build are sorted out by the general
    # build, whose tree keeps the faces' rows; a refit of such a tree builds
    # the moved mesh afresh.
    monkeypatch.setattr(broadphase.build, "_all_different", lambda hashes: False)
    vertices, faces = torus(20, 10)
    mesh = proximity.TriangleMesh(vertices, faces)
    assert not mesh._tree.indexed and len(mesh._tree.child) > 1
    moved = vertices * [1.2, 0.9, 1.0]
    refit = mesh.with_vertices(moved)
    fresh = proximity.TriangleMesh(moved, faces)
    points = np.random.default_rng(4).normal(size=(500, 3))
    for name, value in asdict(fresh.closest_point(points)).items():
        np.testing.assert_array_equal(getattr(refit.closest_point(points), name), value, err_msg=name)


@pytest.mark.parametrize(
    ("kind", "scale"),
    [(kind, scale) for kind in ("sphere", "soup") for scale in (1.0, 1e-30, 1e30)] + [("large sphere", 1.0)],
)
def test_refitted_bounds_hold_every_face_below(kind, scale):
    # The refit merges its children's ranges rather than measuring them:
    # every node's box and slabs must still hold the vertices of its faces,
    # after a twist that turns the faces far from their frames; with faces
    # of zero area (no normal) among them too; and in a tree refitted in
    # several subtrees and the nodes above them (``REFIT_SUBTREE``).
    if kind == "sphere":
        vertices, faces = icosphere(3)
    elif kind == "large sphere":
        vertices, faces = icosphere(5)
        assert len(faces) > 2 * REFIT_SUBTREE
    else:
        vertices, faces = soup(np.random.default_rng(3), 600, degenerate=0.3)
        vertices = vertices - 0.5
    vertices = vertices * scale
    mesh = proximity.TriangleMesh(vertices, faces)
    x, y, z = vertices.T
    angle = 1.5 * z / scale
    twisted = np.stack([np.cos(angle) * x - np.sin(angle) * y, np.sin(angle) * x + np.cos(angle) * y, z], 1)
    tree = mesh.with_vertices(twisted)._tree
    corners = tree.params[:, :9].reshape(-1, 3, 3)
    child, count, bounds = tree.child, tree.count, tree.bounds

    def rows(i):
        # A node's faces are those of its leftmost leaf to its rightmost one.
        first = last = i
        while count[first] == 0:
            first = child[first]
        while count[last] == 0:
            last = child[last] + 1
        return np.arange(child[first], child[last] + count[last])

    for i in range(len(child)):
        points = corners[rows(i)].reshape(-1, 3)
        assert (points >= bounds[i, :3]).all() and (points <= bounds[i, 3:6]).all()
        # Within the few eps of the coordinates' magnitude that the pruning
        # allows for (a leaf's ranges are measured, and round as NumPy's do).
        slack = 16 * EPS * np.abs(points).max()
        for c in (6, 11, 16):
            h = points @ bounds[i, c : c + 3]
            assert (h >= bounds[i, c + 3] - slack).all() and (h <= bounds[i, c + 4] + slack).all(), (i, c)
