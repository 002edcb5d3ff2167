"""Signs users can trust: defective meshes get right signs or a warning, never a silently wrong one.

The truth is the exact integer winding number (signed ray crossings in
rational arithmetic); inside means nonzero.  Points are random in a box
around each mesh and 1e-9 of its size off its surface, both sides.
"""

import warnings

import numpy as np
import pytest

from proximity import TriangleMesh
from proximity.signs import validity
from proximity.testing import winding as exact_winding
from proximity.testing.meshes import box, defective, icosphere, near_points

DEFECTIVE = defective()
CLOSED = [name for name in DEFECTIVE if name != "open"]
SOLIDS = {"inverted", "split seams", "zero-area face", "cavity"}


def _points(vertices, faces, seed=0):
    rng = np.random.default_rng(seed)
    size = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
    lo, hi = vertices.min(axis=0) - 0.2 * size, vertices.max(axis=0) + 0.2 * size
    near = near_points(rng, vertices, faces, 300, 1e-9 * size)
    return np.concatenate([rng.uniform(lo, hi, (700, 3)), near])


def _truth(vertices, faces, points):
    return exact_winding.winding_numbers(vertices, faces, points) != 0


@pytest.mark.parametrize("name", CLOSED)
def test_defective_meshes_are_recognised(name):
    v = TriangleMesh(*DEFECTIVE[name]).validity
    assert v.closed
    assert v.solid == (name in SOLIDS), v.reason
    assert v.inverted == (name == "inverted")
    assert (v.reason is None) == v.solid
    expected = {
        "overlapping boxes": "intersects itself",
        "nested shells": "nested or overlap",
        "pushed octahedron": "intersects itself",
        "internal sheet": "not a manifold",
    }
    if name in expected:
        assert expected[name] in v.reason


@pytest.mark.parametrize("name", CLOSED)
def test_the_default_sign_is_right_on_every_defective_mesh_or_it_warns_once(name):
    vertices, faces = DEFECTIVE[name]
    points = _points(vertices, faces)
    truth = _truth(vertices, faces, points)
    assert 0.05 < truth.mean() < 0.95
    mesh = TriangleMesh(vertices, faces)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        signed = mesh.signed_distance(points)
        again = mesh.contains(points)
    # Right everywhere, solid or not: a mesh that is not a solid is left to the winding number.
    assert ((signed < 0) == truth).all()
    assert (again == truth).all()
    said = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    if name in SOLIDS:
        assert said == []
    else:
        assert len(said) == 1 and "does not bound a solid" in said[0] and "winding number" in said[0]
    r = mesh.signed(points)
    assert r.certain.all()
    np.testing.assert_array_equal(r.signed_distance, signed)


@pytest.mark.parametrize("name", CLOSED)
def test_the_winding_number_sign_is_right_on_every_closed_mesh(name):
    vertices, faces = DEFECTIVE[name]
    points = _points(vertices, faces, seed=1)
    mesh = TriangleMesh(vertices, faces)
    r = mesh.signed(points, sign="winding")
    assert r.certain.all()
    assert ((r.signed_distance < 0) == _truth(vertices, faces, points)).all()
    np.testing.assert_array_equal(np.abs(r.signed_distance), mesh.distance(points))


def test_the_pseudonormal_asked_for_on_a_mesh_that_is_not_a_solid_warns():
    vertices, faces = DEFECTIVE["overlapping boxes"]
    mesh = TriangleMesh(vertices, faces)
    with pytest.warns(RuntimeWarning, match="pseudonormal signs can be wrong"):
        mesh.signed_distance([[0.5, 0.6, 0.0]], sign="pseudonormal")
    # Inside the first box and the second: the winding number is 2.
    assert mesh.signed_distance([[0.5, 0.6, 0.0]]) < 0 and mesh.contains([0.5, 0.6, 0.0])
    with pytest.raises(ValueError, match="closed manifold mesh"):
        TriangleMesh(*DEFECTIVE["internal sheet"]).signed_distance([0, 0, 0], sign="pseudonormal")


def test_split_seams_are_closed_and_get_the_merged_mesh_s_signs():
    """Every face on vertices of its own, as textured files load: closed by position."""
    vertices, faces = DEFECTIVE["split seams"]
    merged = TriangleMesh(*box([-1, -1, -1], [1, 1, 1]))
    split = TriangleMesh(vertices, faces)
    points = _points(*box([-1, -1, -1], [1, 1, 1]), seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(split.signed_distance(points), merged.signed_distance(points))
        np.testing.assert_array_equal(split.signed_distance(points, sign="pseudonormal"),
                                      merged.signed_distance(points))  # fmt: skip
    assert split.validity.solid


def test_trimesh_unmerged_vertices_are_accepted():
    trimesh = pytest.importorskip("trimesh")
    tm = trimesh.creation.icosphere(subdivisions=2)
    tm.unmerge_vertices()
    mesh = TriangleMesh(tm)
    points = np.random.default_rng(3).uniform(-1.2, 1.2, (300, 3))
    truth = np.linalg.norm(points, axis=1) < 0.95
    sure = np.abs(np.linalg.norm(points, axis=1) - 0.975) > 0.03
    assert ((mesh.signed_distance(points) < 0) == truth)[sure].all()
    pytest.importorskip("rtree")
    from proximity import trimesh_compat

    assert ((trimesh_compat.signed_distance(tm, points) > 0) == truth)[sure].all()


@pytest.mark.parametrize("sign", ["auto", "pseudonormal", "winding"])
def test_points_near_a_zero_area_face_get_the_right_sign(sign):
    """A box edge split by a collinear face of zero area; points 1e-12 to 3e-9 off it."""
    vertices, faces = DEFECTIVE["zero-area face"]
    mesh = TriangleMesh(vertices, faces)
    rng = np.random.default_rng(4)
    n = 300
    z = rng.uniform(-1, 1, n)
    height = np.exp(rng.uniform(np.log(1e-12), np.log(3e-9), n))
    angle = rng.uniform(0, 2 * np.pi, n)
    points = np.stack([-1 + height * np.cos(angle), -1 + height * np.sin(angle), z], axis=1)
    points = np.concatenate([points, [[-1.000000001914884, -1.0000000005772514, -0.23781466995926992]]])
    truth = _truth(vertices, faces, points)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = mesh.signed(points, sign=sign)
    assert ((r.signed_distance < 0) == truth).all() and r.certain.all()
    assert 0.1 < truth.mean() < 0.6


def test_open_meshes_are_refused_by_default_and_uncertain_near_their_holes():
    vertices, faces = DEFECTIVE["open"]
    mesh = TriangleMesh(vertices, faces)
    with pytest.raises(ValueError, match=r"needs a closed mesh, and it is not closed: edge .* boundary"):
        mesh.signed_distance([0.0, 0.0, 0.0])
    assert not mesh.validity.closed and not mesh.validity.solid
    r = mesh.signed([[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]], sign="winding")
    assert r.certain.all() and r.contains.tolist() == [True, False]
    # One face missing: in its plane, inside it, the winding number is exactly 1/2.
    sphere_v, sphere_f = icosphere(2)
    hole = sphere_v[sphere_f[0]].mean(axis=0)
    r = TriangleMesh(sphere_v, sphere_f[1:]).signed([hole, hole * 0.5, hole * 2], sign="winding")
    assert r.certain.tolist() == [False, True, True] and r.contains[1:].tolist() == [True, False]


def test_certain_is_false_on_the_surface_and_for_nan():
    mesh = TriangleMesh(*box([-1, -1, -1], [1, 1, 1]))
    r = mesh.signed([[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [np.nan, 0, 0], [0.5, 0.0, 0.0], [3, 0, 0]])
    assert r.certain.tolist() == [False, False, False, True, True]
    assert r.contains.tolist() == [True, True, False, True, False]
    assert r.signed_distance.shape == (5,) and not r.certain.flags.writeable
    one = mesh.signed([0.5, 0.0, 0.0])
    assert np.ndim(one.signed_distance) == 0 and one.certain


def test_the_warning_is_given_once_per_mesh():
    vertices, faces = DEFECTIVE["nested shells"]
    mesh = TriangleMesh(vertices, faces)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(3):
            mesh.signed_distance([[0.0, 0.0, 0.0]])
            mesh.contains([[0.0, 0.0, 0.0]])
    assert len(caught) == 1
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        TriangleMesh(vertices, faces).signed_distance([[0.0, 0.0, 0.0]])
    assert len(caught) == 1


@pytest.mark.parametrize(
    "second, meets",
    [
        # A triangle through the first's interior.
        ([[0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.4, 1]], True),
        # A vertex on the first's interior, not shared.
        ([[0.25, 0.25, 0], [1, 1, 1], [1, 0, 1]], True),
        # Coplanar, overlapping.
        ([[0.1, 0.1, 0], [2, 0.1, 0], [0.1, 2, 0]], True),
        # Coplanar, apart; and above, apart.
        ([[2, 2, 0], [3, 2, 0], [2, 3, 0]], False),
        ([[0, 0, 1e-12], [1, 0, 1e-12], [0, 1, 1e-12]], False),
        # Sharing vertex (0, 0, 0): an edge along the first's edge; folded onto it; apart.
        ([[0, 0, 0], [0.5, 0, 0], [0, 0, 1]], True),
        ([[0, 0, 0], [0.5, 0.1, 0], [0.1, 0.5, 0]], True),
        ([[0, 0, 0], [-1, 0, 0], [0, 0, -1]], False),
        # Sharing edge (0, 0, 0)-(1, 0, 0): folded onto it (coplanar, same side); hinged.
        ([[0, 0, 0], [1, 0, 0], [0.5, 0.5, 0]], True),
        ([[0, 0, 0], [1, 0, 0], [0.5, -0.5, 0]], False),
        ([[0, 0, 0], [1, 0, 0], [0.5, 0.5, 0.5]], False),
    ],
)
def test_pairs_of_faces_meet_exactly_where_they_do(second, meets):
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], second], dtype=float)
    vertices, inverse = np.unique(tri.reshape(-1, 3), axis=0, return_inverse=True)
    faces = inverse.reshape(2, 3)
    for order in ([0, 1], [1, 0]):
        ids = validity.merged_faces(vertices, faces[order])
        h = TriangleMesh(vertices, faces[order])._hierarchy()
        live = np.ones(2, dtype=bool)
        hit, doubt = np.empty(2, np.int64), np.empty(2, np.int64)
        zero = np.full((2, 3), -1, np.int64)
        validity._intersections(h.triangles, ids[h.index], zero, live, h.boxes, h.child, h.count, hit, doubt)
        assert (doubt < 0).all() and (hit[0] == 1) == meets
