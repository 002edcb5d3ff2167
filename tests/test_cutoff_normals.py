"""``max_distance=`` and ``normal``, on every kind of shape, meshes, scenes and rounded shapes."""

import math

import numpy as np
import pytest

import proximity
from proximity.results import asdict
from proximity.testing import examples
from proximity.testing.meshes import box_points, icosphere, near_points

KINDS = [name if dim == 3 else f"{name}{dim}d" for name, dim in examples.kinds()]


def make(kind, batch=()):
    name, dim = (kind[:-2], 2) if kind.endswith("2d") else (kind, 3)
    return examples.example(name, batch, dim)


def _mesh():
    return proximity.TriangleMesh(*icosphere(3))


def _scene():
    rng = np.random.default_rng(3)
    return proximity.Scene(
        [
            _mesh(),
            proximity.Segment(rng.normal(size=(30, 2, 3)) * 2),
            proximity.Capsule(rng.normal(size=(10, 2, 3)) * 2, 0.1),
            proximity.Disk(rng.normal(size=(10, 3)) * 2, rng.normal(size=(10, 3)), rng.random(10)),
        ]
    )


SHAPES = {
    **{kind: (lambda kind=kind: make(kind, (5,))) for kind in KINDS},
    "mesh": _mesh,
    "mesh brute": lambda: proximity.TriangleMesh(*icosphere(0), broad_phase="brute"),
    "scene": _scene,
    "rounded triangle": lambda: make("triangle", (5,)).inflated(0.25),
    "rounded mesh": lambda: _mesh().inflated(0.1),
}


def _points(shape, n=600, seed=0):
    rng = np.random.default_rng(seed)
    batch = shape.batch_shape
    return rng.normal(size=(n,) + (1,) * len(batch) + (shape.dim,)) * 2.0


@pytest.mark.parametrize("name", list(SHAPES))
def test_cutoff_rows_within_are_the_same_bits_and_rows_beyond_are_infinite(name):
    shape = SHAPES[name]()
    points = _points(shape)
    points[:2] = np.nan  # NaN rows stay NaN rows
    points[2] = np.inf
    for method in shape.methods:
        full = shape.closest_point(points, method=method)
        limit = float(np.nanmedian(full.distance))
        cut = shape.closest_point(points, method=method, max_distance=limit)
        within = (np.asarray(full.distance) <= limit) | np.isnan(full.distance)
        assert np.isnan(full.distance).any() and (~within).any()
        for field, value in asdict(full).items():
            got = np.asarray(getattr(cut, field))
            np.testing.assert_array_equal(got[within], np.asarray(value)[within], err_msg=f"{name} {field}")
            beyond = got[~within]
            if field in ("distance", "sqr_distance"):
                assert np.isposinf(beyond).all(), field
            elif field == "feature":
                assert (beyond == proximity.Feature.NONE).all()
            elif beyond.dtype == np.bool_:
                assert not beyond.any(), field
            elif beyond.dtype.kind == "i":
                assert (beyond == -1).all(), field
            else:
                assert np.isnan(beyond).all(), field
        d = shape.distance(points, method=method, max_distance=limit)
        np.testing.assert_array_equal(d, cut.distance)


def test_a_cutoff_of_zero_keeps_the_points_on_the_shape():
    mesh = _mesh()
    points = np.concatenate([mesh.vertices[:10], mesh.vertices[:10] * 1.5])
    d = mesh.distance(points, max_distance=0.0)
    assert (d[:10] == 0).all() and np.isposinf(d[10:]).all()


@pytest.mark.parametrize(
    "bad, error", [(-1.0, ValueError), (math.nan, ValueError), ("1", TypeError), (True, TypeError)]
)
def test_bad_cutoffs_name_the_argument(bad, error):
    for shape in (make("triangle"), _mesh(), make("segment").inflated(1.0)):
        with pytest.raises(error, match="max_distance"):
            shape.distance([[0.0, 0.0, 5.0]], max_distance=bad)


@pytest.mark.parametrize(
    "bad, error", [(-1.0, ValueError), (math.nan, ValueError), ("2", TypeError), (True, TypeError)]
)
def test_pair_queries_and_grids_refuse_the_cutoffs_point_queries_refuse(bad, error):
    # One validation for every cutoff: the pair queries (of primitives, of
    # meshes, of a scene of instances) and the signed grid name it alike.
    mesh = _mesh()
    segment = make("segment")
    instances = proximity.Scene([mesh.transformed(np.eye(4))])
    for query in (proximity.closest_points, proximity.distance, proximity.signed_distance):
        for a, b in ((segment, segment), (mesh, segment), (instances, segment)):
            with pytest.raises(error, match="max_distance must be"):
                query(a, b, max_distance=bad)
    with pytest.raises(error, match="max_distance must be"):
        mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 2, 2), max_distance=bad)


def test_a_cutoff_may_be_a_numpy_number():
    # NumPy scalars and 0-d arrays are numbers, for points and pairs alike.
    a = proximity.Segment([[0, 0, 0], [1, 0, 0]])
    b = proximity.Segment([[0, 0, 1], [1, 0, 1]])
    for limit in (np.float64(2.0), np.array(2.0), np.int64(2)):
        assert proximity.distance(a, b, max_distance=limit) == 1.0
        assert a.distance([0, 0, 1], max_distance=limit) == 1.0
    assert np.isposinf(proximity.distance(a, b, max_distance=np.array(0.5)))
    with pytest.raises(TypeError, match=r"max_distance must be a number or None; got ndarray"):
        a.distance([0, 0, 1], max_distance=np.array([2.0]))


def test_rounded_signed_distances_beyond_the_cutoff_are_positive_infinity():
    pill = proximity.Capsule([[0, 0, 0], [0, 0, 4]], 0.5)
    signed = pill.signed_distance([[0, 0, 2], [3, 0, 2], [9, 0, 2]], max_distance=3.0)
    assert signed.tolist() == [-0.5, 2.5, math.inf]


@pytest.mark.parametrize("sign", ["auto", "winding"])
def test_mesh_signed_distances_beyond_the_cutoff_are_infinite_by_side(sign):
    # A sphere inside an inverted larger one: a shell, whose hollow is
    # outside; points in the solid more than 0.3 from both surfaces get -inf.
    small, faces = icosphere(3)
    vertices = np.concatenate([small, small * 3.0])
    shell = proximity.TriangleMesh(vertices, np.concatenate([faces[:, ::-1], faces + len(small)]))
    rng = np.random.default_rng(4)
    points = rng.normal(size=(600, 3)) * 2.0
    points[0] = np.nan
    full = shell.signed_distance(points, sign=sign)
    cut = shell.signed_distance(points, sign=sign, max_distance=0.3)
    within = np.abs(full) <= 0.3
    np.testing.assert_array_equal(cut[within], full[within])
    beyond = ~within & ~np.isnan(full)
    assert beyond.sum() > 100 and (full[beyond] < 0).any() and (full[beyond] > 0).any()
    np.testing.assert_array_equal(cut[beyond], np.where(full[beyond] < 0, -math.inf, math.inf))
    assert np.isnan(cut[0])
    r = shell.signed(points, sign=sign, max_distance=0.3)
    np.testing.assert_array_equal(r.signed_distance, cut)
    assert r.certain[beyond].all()
    # Posed, the same answers at the moved points.
    T = np.eye(4)
    T[:3, 3] = [5.0, -1.0, 2.0]
    posed = shell.transformed(T).signed_distance(points + T[:3, 3], sign=sign, max_distance=0.3)
    np.testing.assert_array_equal(np.isinf(posed), np.isinf(cut))


# -- normals ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(SHAPES))
def test_normals_off_the_shape_point_from_the_closest_point_to_the_query(name):
    shape = SHAPES[name]()
    points = _points(shape, n=200, seed=1)
    points[3] = np.nan
    r = shape.closest_point(points)
    normal = np.asarray(r.normal)
    assert normal.shape == np.shape(r.point)
    d = np.asarray(r.distance)
    off = d > 0
    p = np.broadcast_to(points, np.shape(r.point))
    expected = (p[off] - np.asarray(r.point)[off]) / d[off][:, None]
    np.testing.assert_allclose(normal[off], expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(normal[off], axis=-1), 1.0, rtol=0, atol=1e-12)
    assert np.isnan(normal[np.isnan(d)]).all()
    one = r[0] if np.ndim(r.distance) else r
    np.testing.assert_array_equal(
        np.asarray(one.normal), normal.reshape(np.shape(normal))[0] if np.ndim(r.distance) else normal
    )


def test_normals_on_the_shape_are_its_normals():
    tri = proximity.Triangle([[0, 0, 0], [2, 0, 0], [0, 2, 0]])
    assert tri.closest_point([0.5, 0.5, 0]).normal.tolist() == [0, 0, 1]
    flipped = proximity.Triangle([[0, 0, 0], [0, 2, 0], [2, 0, 0]])
    assert flipped.closest_point([[0.5, 0.5, 0]]).normal.tolist() == [[0, 0, -1]]
    disk = proximity.Disk([0, 0, 0], [0, 0, -3], 1.0)
    assert disk.closest_point([[0.5, 0, 0], [1, 0, 0]]).normal.tolist() == [[0, 0, -1], [0, 0, -1]]
    ring = proximity.Circle([0, 0, 0], [0, 0, 1], 1.0)
    assert ring.closest_point([1, 0, 0]).normal.tolist() == [0, 0, 1]  # the axis, by convention
    # A closed mesh: the angle-weighted pseudonormal of the vertex, outwards.
    mesh = _mesh()
    v = mesh.vertices[7]
    n = mesh.closest_point(v).normal
    np.testing.assert_allclose(n, v / np.linalg.norm(v), atol=1e-6)
    # A rounded shape: the rounded surface's outward normal, inside it too.
    ball = proximity.Sphere([0, 0, 0], 2.0)
    assert ball.closest_point([[0, 0.5, 0], [0, 0, 7]]).normal.tolist() == [[0, 1, 0], [0, 0, 1]]


def test_normals_survive_indexing_and_pickling():
    import pickle

    mesh = _mesh()
    points = near_points(np.random.default_rng(4), mesh.vertices, mesh.faces, 50, 1e-3)
    r = mesh.closest_point(points)
    back = pickle.loads(pickle.dumps(r))
    np.testing.assert_array_equal(back.normal, r.normal)
    np.testing.assert_array_equal(r[7:9].normal, r.normal[7:9])
    box = box_points(np.random.default_rng(5), mesh.vertices, 50)
    assert np.isfinite(mesh.closest_point(box).normal).all()
