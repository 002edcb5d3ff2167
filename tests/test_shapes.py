"""Each shape's constructor: validation messages, frozen data, and the
batches against one shape that have compiled loops of their own, on every
scene family."""

import numpy as np
import pytest

from proximity import Circle, Disk, Triangle
from proximity.results import asdict
from proximity.shapes import base as shapes_module
from proximity.testing import scenes

METHODS = ["robust", "eberly", "certified"]
TRI = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


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
    for name, value in asdict(pairs).items():
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
    for name, value in asdict(pairs).items():
        np.testing.assert_array_equal(getattr(one, name), value, err_msg=name)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("cls", [Circle, Disk])
@pytest.mark.parametrize("one", [True, False], ids=["one", "pairs"])
def test_circle_and_disk_batches_over_many_calls_take_the_bits_of_single_queries(cls, one, method):
    """A call of a disk or circle block function works through several
    blocks: over an ``(I, J)`` loop whose rows are no multiple of a block,
    longer than a call's span, every query has the bits of its own
    single-point query, for the distance alone and the full answer."""
    rng = np.random.default_rng(13)
    scene = scenes.disk_well_conditioned(rng, 300)
    n_j = 2 * 8 * 128 + 77  # more than one call's blocks, the last block short
    if one:
        # Every other point: strides that do not merge, so the loop keeps two dimensions.
        shape = cls(scene.center[0], scene.normal[0], scene.radius[0])
        points = _points_against(scene.center[0], scene.points, rng)
        points = np.resize(points, (2, 2 * n_j, 3))[:, ::2]
        singles = [shape] * 2
    else:
        shape = cls(scene.center[:2, None], scene.normal[:2, None], scene.radius[:2, None])
        points = _points_against(scene.center[0], scene.points, rng)
        points = np.resize(points, (1, n_j, 3))
        singles = [cls(scene.center[i], scene.normal[i], scene.radius[i]) for i in range(2)]
    full = shape.closest_point(points, method=method)
    distance = shape.distance(points, method=method)
    assert distance.shape == full.distance.shape == (2, n_j)
    for i in range(2):
        for j in range(n_j):
            point = points[i if one else 0, j]
            single = singles[i].closest_point(point, method=method)
            np.testing.assert_array_equal(distance[i, j], single.distance)
            for name, value in asdict(single).items():
                np.testing.assert_array_equal(getattr(full, name)[i, j], value, err_msg=name)


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
