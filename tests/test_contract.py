"""The query contract, over every shape and method: shapes, dtypes, errors."""

import numpy as np
import pytest

import proximity
from proximity import Circle, Disk, Feature, Triangle
from proximity import shapes as shapes_module
from proximity.testing import scenes

TRI = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


def make(kind, batch=()):
    """A shape of ``kind`` with batch shape ``batch``, all members distinct."""
    count = int(np.prod(batch, dtype=int))
    offsets = np.arange(count, dtype=float).reshape(batch + (1,))
    if kind == "triangle":
        return Triangle(np.asarray(TRI) + offsets[..., None])
    if kind == "triangle2d":
        return Triangle(np.asarray(TRI)[:, :2] + offsets[..., None])
    cls = Circle if kind == "circle" else Disk
    return cls(center=np.zeros(batch + (3,)) + offsets, normal=[0.0, 0.0, 1.0], radius=1.0 + offsets[..., 0])


KINDS = ["triangle", "triangle2d", "circle", "disk"]
QUERIES = [
    pytest.param(lambda s, p, **kw: proximity.closest_point(s, p, **kw).distance, id="closest_point"),
    pytest.param(lambda s, p, **kw: proximity.distance(s, p, **kw), id="distance"),
    pytest.param(lambda s, p, **kw: s.closest_point(p, **kw).distance, id="method.closest_point"),
    pytest.param(lambda s, p, **kw: s.distance(p, **kw), id="method.distance"),
]
METHODS = ["robust", "eberly", "certified"]


def points_for(shape, lead, seed=0):
    return np.random.default_rng(seed).normal(size=lead + (shape.dim,)) * 2.0


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("query", QUERIES)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize(
    "shape_batch, point_lead, out",
    [
        ((), (), ()),
        ((), (5,), (5,)),
        ((5,), (5,), (5,)),
        ((4,), (5, 1), (5, 4)),
        ((2, 1, 3), (4, 1), (2, 4, 3)),
        ((3,), (), (3,)),
        ((0,), (0,), (0,)),
    ],
)
def test_broadcasting(kind, query, method, shape_batch, point_lead, out):
    shape = make(kind, shape_batch)
    points = points_for(shape, point_lead)
    d = query(shape, points, method=method)
    assert np.shape(d) == out
    # Every broadcast element is the answer of its own single query.
    s_full = np.broadcast_to(np.arange(int(np.prod(shape_batch, dtype=int))).reshape(shape_batch), out)
    p_full = np.broadcast_to(points, out + (shape.dim,))
    for index in np.ndindex(*out):
        single = make_single(shape, np.unravel_index(s_full[index], shape_batch) if shape_batch else ())
        assert np.asarray(d)[index] == single.distance(p_full[index], method=method)


def make_single(shape, index):
    if isinstance(shape, Triangle):
        return Triangle(shape.vertices[index])
    b = np.broadcast_to
    batch = shape.batch_shape
    return type(shape)(
        b(shape.center, batch + (3,))[index],
        b(shape.normal, batch + (3,))[index],
        b(shape.radius, batch)[index],
    )


@pytest.mark.parametrize("kind", KINDS)
def test_zero_d_results_are_scalars(kind):
    shape = make(kind)
    r = shape.closest_point(points_for(shape, ()))
    assert isinstance(r.distance, np.float64)
    assert isinstance(r.sqr_distance, np.float64)
    assert type(r.feature) is np.int8  # like every other field: a NumPy scalar
    assert r.point.shape == (shape.dim,)
    assert isinstance(shape.distance(points_for(shape, ())), np.float64)


@pytest.mark.parametrize("kind", KINDS)
def test_result_fields_and_shapes(kind):
    shape = make(kind, (4,))
    r = shape.closest_point(points_for(shape, (4,)))
    assert r.distance.shape == r.sqr_distance.shape == r.feature.shape == (4,)
    assert r.point.shape == (4, shape.dim)
    assert r.distance.dtype == np.float64 and r.feature.dtype == np.int8
    if isinstance(shape, Triangle):
        assert r.barycentric.shape == (4, 3)
        np.testing.assert_allclose(r.barycentric.sum(axis=-1), 1.0, rtol=0, atol=1e-15)
    else:
        assert r.height.shape == r.radial.shape == (4,)
    assert hasattr(r, "equidistant") == (kind == "circle")
    with pytest.raises(AttributeError):
        r.distance = 0
    with pytest.raises(ValueError):
        r.distance[0] = 0.0


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.float32, np.float64])
@pytest.mark.parametrize("kind", KINDS)
def test_dtypes_convert_to_float64(kind, dtype):
    shape = make(kind)
    expected = shape.distance(np.ones(shape.dim))
    assert shape.distance(np.ones(shape.dim, dtype=dtype)).dtype == np.float64
    assert shape.distance(np.ones(shape.dim, dtype=dtype)) == expected
    if kind == "triangle":
        assert Triangle(np.asarray(TRI, dtype=dtype)).vertices.dtype == np.float64
    if kind == "disk":
        d = Disk(np.zeros(3, dtype), np.array([0, 0, 1], dtype), dtype(1))
        assert d.center.dtype == d.normal.dtype == d.radius.dtype == np.float64


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("kind", KINDS)
def test_non_finite_points_give_nan_rows_only(kind, method):
    shape = make(kind)
    points = points_for(shape, (4,))
    points[1, 0] = np.nan
    points[2, -1] = np.inf
    points[3, 0] = -np.inf
    clean = shape.closest_point(points[:1], method=method)
    r = shape.closest_point(points, method=method)
    assert r.distance[0] == clean.distance[0]
    assert (
        np.isnan(r.distance[1:]).all() and np.isnan(r.point[1:]).all() and np.isnan(r.sqr_distance[1:]).all()
    )
    assert (r.feature[1:] == Feature.NONE).all()
    assert np.isnan(shape.distance(points, method=method)[1:]).all()


def test_shape_data_are_frozen():
    vertices = np.array(TRI)
    tri = Triangle(vertices)
    with pytest.raises(ValueError):
        tri.vertices[0, 0] = 1.0
    with pytest.raises(AttributeError):
        tri.vertices = vertices


@pytest.mark.parametrize(
    "build, match",
    [
        (
            lambda: Triangle([[0, 0, 0], [1, 0, 0]]),
            r"vertices must have shape \(\.\.\., 3, D\).*got shape \(2, 3\)",
        ),
        (lambda: Triangle(np.zeros((3, 4))), r"vertices must have shape .*got shape \(3, 4\)"),
        (lambda: Triangle(np.zeros((3, 1))), r"vertices must have shape .*got shape \(3, 1\)"),
        (lambda: Triangle(np.zeros(3)), r"vertices must have shape .*got shape \(3,\)"),
        (
            lambda: Triangle([[0, 0, 0], [1, np.nan, 0], [0, 1, 0]]),
            r"vertices must be finite; got nan at index \(1, 1\)",
        ),
        (lambda: Triangle([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]]), r"vertices must be finite"),
        (lambda: Triangle([["a", "b", "c"]] * 3), r"vertices must be a real numeric array"),
        (lambda: Triangle(np.zeros((3, 3), complex)), r"vertices must be a real numeric array.*complex"),
        (lambda: Triangle([[0, 0], [1, 0, 0], [0, 1]]), r"vertices must be an array of shape"),
        (lambda: Circle([0, 0], [0, 0, 1], 1), r"center must have shape \(\.\.\., 3\); got shape \(2,\)"),
        (
            lambda: Circle([0, 0, 0], [0, 0, 0], 1),
            r"normal must be non-zero; got a zero vector at index \(\)",
        ),
        (
            lambda: Disk([0, 0, 0], [[0, 0, 1], [0, 0, 0]], 1),
            r"normal must be non-zero; got a zero vector at index \(1,\)",
        ),
        (lambda: Disk([0, 0, 0], [0, 0, 1], -1.0), r"radius must be >= 0; got -1.0"),
        (lambda: Disk([0, 0, 0], [0, 0, 1], np.nan), r"radius must be finite"),
        (lambda: Circle([0, np.inf, 0], [0, 0, 1], 1), r"center must be finite"),
        (lambda: Circle(np.zeros((2, 3)), np.ones((3, 3)), 1), r"center, normal and radius do not broadcast"),
    ],
)
def test_bad_shape_data_raise_at_construction(build, match):
    with pytest.raises(ValueError, match=match):
        build()


@pytest.mark.parametrize("kind", KINDS)
def test_bad_points_and_methods(kind):
    shape = make(kind, (3,))
    dim = shape.dim
    with pytest.raises(
        ValueError, match=rf"points must have shape \(\.\.\., {dim}\); got shape \(3, {dim + 1}\)"
    ):
        shape.distance(np.zeros((3, dim + 1)))
    with pytest.raises(ValueError, match=r"points must have shape"):
        shape.distance(1.0)
    with pytest.raises(ValueError, match=r"points \(4,\), \w+ \(3,\)"):
        shape.closest_point(np.zeros((4, dim)))
    with pytest.raises(ValueError, match=r"method must be one of .*got 'exact'"):
        shape.distance(np.zeros(dim), method="exact")
    with pytest.raises(ValueError, match=r"points must be a real numeric array"):
        shape.distance(np.array(["x"] * dim))


def test_module_functions_reject_non_shapes():
    with pytest.raises(TypeError, match="shape must be a proximity shape"):
        proximity.distance(np.zeros((3, 3)), [0, 0, 0])


def test_method_is_keyword_only():
    with pytest.raises(TypeError):
        proximity.distance(make("triangle"), [0, 0, 0], "eberly")


def test_shapes_follow_the_protocol():
    for kind in KINDS:
        assert isinstance(make(kind), proximity.Shape)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("kind", ["triangle", "circle", "disk"])
def test_single_point_fast_path_matches_the_batch_path(kind, method):
    """One point against one shape takes a separate path; its answers are the batch's."""
    shape = make(kind)
    points = points_for(shape, (50,), seed=3)
    points[7] = [np.nan, 0.0, 0.0]
    points[8] = shape.vertices[1] if kind == "triangle" else shape.center
    batch = shape.closest_point(points, method=method)
    for k, p in enumerate(points):
        strided = np.stack([p, p], axis=1)[:, 0]  # a non-contiguous view
        reversed_ = p[::-1].copy()[::-1]  # a negative stride
        frozen = p.copy()
        frozen.flags.writeable = False
        for query in (p, tuple(p), list(p), strided, reversed_, frozen, p.astype(">f8")):
            single = shape.closest_point(query, method=method)
            expected = batch[k]
            assert type(single) is type(expected)
            for name, value in vars(expected).items():
                np.testing.assert_array_equal(getattr(single, name), value, err_msg=name)
            assert not single.point.flags.writeable
            assert type(single.feature) is np.int8
            np.testing.assert_array_equal(shape.distance(query, method=method), expected.distance)


def _points_against(center, scene_points, rng):
    """The scene's points, plus rows that leave the compiled loops' safe
    window (far away and very near), ties on small integers, and NaN."""
    far = center + rng.normal(size=(40, 3)) * 1e200
    near = center + rng.normal(size=(40, 3)) * 1e-200
    grid = rng.integers(-2, 3, size=(40, 3)).astype(float)
    points = np.concatenate([scene_points, far, near, grid])
    points[[5, 150, 299]] = [np.nan, 0.0, 0.0]
    return rng.permutation(points)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("family", scenes.TRIANGLE_FAMILIES, ids=lambda f: f.label)
def test_one_triangle_takes_the_same_bits_as_pairs(family, method):
    """A batch against one triangle has its own compiled loop; every field
    matches the same triangle repeated, which takes the general loop."""
    rng = np.random.default_rng(11)
    scene = family(rng, 300)
    points = _points_against(scene.vertices[0, 0], scene.points, rng)
    one = Triangle(scene.vertices[0]).closest_point(points, method=method)
    pairs = Triangle(np.repeat(scene.vertices[:1], len(points), axis=0)).closest_point(points, method=method)
    for name, value in vars(pairs).items():
        np.testing.assert_array_equal(getattr(one, name), value, err_msg=name)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("cls", [Circle, Disk])
@pytest.mark.parametrize("family", scenes.DISK_FAMILIES, ids=lambda f: f.label)
def test_one_circle_or_disk_takes_the_same_bits_as_pairs(family, cls, method):
    """:func:`test_one_triangle_takes_the_same_bits_as_pairs` for circles and disks."""
    rng = np.random.default_rng(12)
    scene = family(rng, 300)
    points = _points_against(scene.center[0], scene.points, rng)
    one = cls(scene.center[0], scene.normal[0], scene.radius[0]).closest_point(points, method=method)
    n = len(points)
    repeated = cls(
        np.tile(scene.center[0], (n, 1)), np.tile(scene.normal[0], (n, 1)), np.repeat(scene.radius[:1], n)
    )
    pairs = repeated.closest_point(points, method=method)
    for name, value in vars(pairs).items():
        np.testing.assert_array_equal(getattr(one, name), value, err_msg=name)


# From this many circles or disks on, a compiled loop checks the arrays and
# computes the unit normals; it must raise the same errors and give the same bits.
LARGE = shapes_module._COMPILED_UNIT


@pytest.mark.parametrize(
    "field, row, value, match",
    [
        ("center", 9, np.inf, r"center must be finite; got inf at index \(9, 2\)"),
        ("normal", 9, np.nan, r"normal must be finite; got nan at index \(9, 2\)"),
        ("radius", 9, np.nan, r"radius must be finite; got nan at index \(9,\)"),
        ("radius", 9, -1.0, r"radius must be >= 0; got -1.0 at index \(9,\)"),
        ("normal", 9, 0.0, r"normal must be non-zero; got a zero vector at index \(9,\)"),
    ],
)
@pytest.mark.parametrize("broadcast", [False, True])
def test_large_batches_raise_the_same_errors(field, row, value, match, broadcast):
    n = LARGE + 5
    data = {"center": np.zeros((n, 3)), "normal": np.ones((n, 3)), "radius": np.ones(n)}
    if broadcast and field != "center":
        data["center"] = np.zeros(3)  # checked apart from the compiled loop
    if broadcast and field != "radius":
        data["radius"] = np.float64(1.0)
    if field == "radius":
        data["radius"][row] = value
    elif field == "normal" and value == 0.0:
        data["normal"][row] = 0.0
    else:
        data[field][row, 2] = value
    with pytest.raises(ValueError, match=match):
        Disk(**data)


def test_large_batches_have_the_unit_normals_of_small_ones():
    rng = np.random.default_rng(11)
    n = LARGE + 1000
    # Exponents over the whole float range, and components far apart in size.
    normal = (rng.random((n, 3)) - 0.5) * np.exp2(rng.integers(-1000, 1020, (n, 1)))
    normal *= np.exp2(rng.integers(-60, 1, (n, 3)))
    normal[::5, 1] = 0.0
    normal[::7] = rng.random((len(normal[::7]), 3)) + 0.01
    assert np.isfinite(normal).all() and normal.any(axis=1).all()
    large = Circle(np.zeros((n, 3)), normal, np.ones(n))
    assert np.array_equal(large._unit_normal.view(np.int64), shapes_module._unit(normal).view(np.int64))
    for k in range(0, n, 997):
        assert np.array_equal(large._unit_normal[k], Circle(np.zeros(3), normal[k], 1.0)._unit_normal)
