"""The query contract, over every kind of primitive and method: shapes, dtypes, errors.

The kinds come from the primitive registry (:mod:`proximity.primitives`),
their shapes from :mod:`proximity.testing.examples`: a new primitive is
covered here without naming it.
"""

import numpy as np
import pytest

import proximity
from proximity import Feature, primitives
from proximity.results import asdict
from proximity.testing import examples

KINDS = [name if dim == 3 else f"{name}{dim}d" for name, dim in examples.kinds()]


def make(kind, batch=()):
    """A shape of ``kind`` (a primitive's name, ``2d`` appended for 2D) with batch shape ``batch``."""
    name, dim = (kind[:-2], 2) if kind.endswith("2d") else (kind, 3)
    return examples.example(name, batch, dim)


def primitive(kind):
    return primitives.REGISTRY[kind[:-2] if kind.endswith("2d") else kind]


#: Every kind with every method it offers.
KIND_METHODS = [
    pytest.param(kind, method, id=f"{kind}-{method}") for kind in KINDS for method in primitive(kind).methods
]
QUERIES = [
    pytest.param(lambda s, p, **kw: proximity.closest_point(s, p, **kw).distance, id="closest_point"),
    pytest.param(lambda s, p, **kw: proximity.distance(s, p, **kw), id="distance"),
    pytest.param(lambda s, p, **kw: s.closest_point(p, **kw).distance, id="method.closest_point"),
    pytest.param(lambda s, p, **kw: s.distance(p, **kw), id="method.distance"),
]


def points_for(shape, lead, seed=0):
    return np.random.default_rng(seed).normal(size=lead + (shape.dim,)) * 2.0


@pytest.mark.parametrize("kind, method", KIND_METHODS)
@pytest.mark.parametrize("query", QUERIES)
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
        single = shape[np.unravel_index(s_full[index], shape_batch)] if shape_batch else shape
        assert np.asarray(d)[index] == single.distance(p_full[index], method=method)


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
    for name, width in primitive(kind).extra:
        value = getattr(r, name)
        assert value.shape == ((4, width) if width > 1 else (4,)), name
        assert value.dtype == (np.bool_ if width == 0 else np.float64), name
    extra = {name for name, _ in primitive(kind).extra}
    common = {"distance", "sqr_distance", "point", "feature"}
    assert set(asdict(r)) == common | extra
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
    # The constructor converts every array it takes.
    arrays = [np.asarray(getattr(shape, name)) for name, _ in shape._fields]
    again = type(shape)(*(np.round(a).astype(dtype) for a in arrays))
    assert all(getattr(again, name).dtype == np.float64 for name, _ in shape._fields)


@pytest.mark.parametrize("kind, method", KIND_METHODS)
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


KIND_METHODS_3D = [case for case in KIND_METHODS if not case.values[0].endswith("2d")]


def _on_shape(shape):
    """A point of the shape: the first vertex, or the center."""
    return shape._rows()[1][0, : shape.dim]


@pytest.mark.parametrize("kind, method", KIND_METHODS_3D)
def test_single_point_fast_path_matches_the_batch_path(kind, method):
    """One point against one shape takes a separate path; its answers are the batch's."""
    shape = make(kind)
    points = points_for(shape, (50,), seed=3)
    points[7] = [np.nan, 0.0, 0.0]
    points[8] = _on_shape(shape)
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
            for name, value in asdict(expected).items():
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


@pytest.mark.parametrize("kind, method", KIND_METHODS_3D)
def test_one_shape_takes_the_same_bits_as_pairs(kind, method):
    """A batch against one shape has its own compiled loop where the kind
    has one; every field matches the same shape repeated (the general loop)."""
    rng = np.random.default_rng(13)
    one = make(kind)
    points = _points_against(_on_shape(one), rng.normal(size=(180, 3)) * 2, rng)
    arrays = [np.asarray(getattr(one, name)) for name, _ in one._fields]
    repeated = type(one)(*(np.repeat(a[None], len(points), axis=0) for a in arrays))
    a, b = one.closest_point(points, method=method), repeated.closest_point(points, method=method)
    for name, value in asdict(b).items():
        np.testing.assert_array_equal(getattr(a, name), value, err_msg=name)
