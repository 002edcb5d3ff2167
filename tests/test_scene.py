"""Scenes of triangles, disks and circles.

A scene answers with the nearest primitive's own answer, the same by brute
force and by BVH.
"""

import numpy as np
import pytest

import proximity
from proximity import Circle, Disk, Feature, Scene, Triangle, TriangleMesh
from proximity.testing.meshes import icosphere

FIELDS = (
    "distance",
    "sqr_distance",
    "point",
    "feature",
    "primitive",
    "source",
    "barycentric",
    "height",
    "radial",
    "equidistant",
)


def _shapes(seed=0, n=40):
    """Triangles (one batch of 3D, one of 2D), disks and circles scattered in a cube of side 4."""
    rng = np.random.default_rng(seed)
    tri = rng.uniform(-2, 2, (n, 1, 3)) + rng.normal(0, 0.3, (n, 3, 3))
    flat = rng.uniform(-2, 2, (n // 4, 1, 2)) + rng.normal(0, 0.3, (n // 4, 3, 2))
    centers = rng.uniform(-2, 2, (n, 3))
    normals = rng.normal(size=(n, 3))
    normals[::5] = [0.0, 0.0, 3.0]  # axis-aligned: flat boxes
    radii = rng.uniform(0.0, 0.5, n)
    radii[7] = 0.0
    return [
        Triangle(tri.reshape(n // 4, 4, 3, 3)),
        Disk(centers[: n // 2], normals[: n // 2], radii[: n // 2]),
        Triangle(flat),
        Circle(centers[n // 2 :], normals[n // 2 :], radii[n // 2 :]),
    ]


def _points(shapes, seed=1, n=300):
    rng = np.random.default_rng(seed)
    circles = shapes[3]
    on_axis = circles.center[:10] + circles._unit_normal[:10] * rng.normal(0, 1, (10, 1))
    near_axis = on_axis + rng.normal(0, 1e-9, (10, 3))
    on_rim = shapes[1].center[:5].copy()
    return np.concatenate(
        [rng.uniform(-3, 3, (n, 3)), on_axis, near_axis, on_rim, rng.normal(0, 30, (20, 3))]
    )


def per_primitive(shapes, points, method):
    """Every primitive's answer for every point, ``(points, primitives)``, from the shapes' own queries."""
    answers = []
    for shape in shapes:
        lead = points[:, None, :] if len(shape.batch_shape) == 1 else points[:, None, None, :]
        if isinstance(shape, Triangle) and shape.dim == 2:
            shape = Triangle(np.concatenate([shape.vertices, np.zeros(shape.vertices.shape[:-1] + (1,))], -1))
        r = shape.closest_point(lead, method=method)
        answers.append(np.asarray(r.distance).reshape(len(points), -1))
    return np.concatenate(answers, axis=1)


def assert_same(a, b):
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.mark.parametrize("method", ["robust", "eberly", "certified"])
def test_brute_force_and_bvh_agree_bit_for_bit(method):
    shapes = _shapes()
    points = _points(shapes)
    brute = Scene(shapes, broad_phase="brute")
    bvh = Scene(shapes, broad_phase="bvh")
    assert bvh._tree.nodes > 1
    assert_same(brute.closest_point(points, method=method), bvh.closest_point(points, method=method))


@pytest.mark.parametrize("method", ["robust", "eberly", "certified"])
def test_the_scene_answers_with_the_nearest_primitives_own_answer(method):
    shapes = _shapes()
    points = _points(shapes)
    scene = Scene(shapes)
    r = scene.closest_point(points, method=method)
    d = per_primitive(shapes, points, method)
    with np.errstate(invalid="ignore"):
        nearest = np.nanargmin(d, axis=1)
    np.testing.assert_array_equal(r.primitive, nearest)
    np.testing.assert_array_equal(r.distance, d[np.arange(len(points)), nearest])
    # primitive -> source shape -> element of its batch
    np.testing.assert_array_equal(r.source, np.searchsorted(scene.offsets, nearest, side="right") - 1)
    for k in range(0, len(points), 37):
        shape = shapes[r.source[k]]
        element = np.unravel_index(r.primitive[k] - scene.offsets[r.source[k]], shape.batch_shape)
        if isinstance(shape, Triangle):
            vertices = shape.vertices[element]
            if shape.dim == 2:  # a scene embeds 2D triangles in z = 0
                vertices = np.concatenate([vertices, np.zeros((3, 1))], axis=1)
            alone = Triangle(vertices).closest_point(points[k], method=method)
            np.testing.assert_array_equal(r.point[k], alone.point)
            np.testing.assert_array_equal(r.barycentric[k], alone.barycentric)
            assert np.isnan(r.height[k]) and not r.equidistant[k]
        else:
            one = type(shape)(shape.center[element], shape.normal[element], shape.radius[element])
            alone = one.closest_point(points[k], method=method)
            np.testing.assert_array_equal(r.point[k], alone.point)
            assert (r.height[k], r.radial[k]) == (alone.height, alone.radial)
            assert np.isnan(r.barycentric[k]).all()
        assert r.feature[k] == alone.feature and r.distance[k] == alone.distance


def test_points_on_a_circles_axis_are_equidistant_and_disks_stay_analytic():
    ring = Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=2.0)
    plate = Disk(center=[10, 0, 0], normal=[0, 0, 1], radius=1.0)
    scene = Scene([ring, plate])
    r = scene.closest_point([[0, 0, 1.5], [10.25, 0, 0.5], [12, 0, 0]])
    assert r.distance.tolist() == [2.5, 0.5, 1.0]
    assert r.equidistant.tolist() == [True, False, False]
    assert [Feature(f).name for f in r.feature] == ["RIM", "FACE", "RIM"]
    assert r.source.tolist() == [0, 1, 1] and r.primitive.tolist() == [0, 1, 1]
    np.testing.assert_array_equal(r.height, [1.5, 0.5, 0.0])


def test_eberly_circles_near_their_axis_are_not_pruned_wrongly():
    """eberly's rim point leaves the circle's plane near the axis; the BVH bounds circles loosely for it."""
    rng = np.random.default_rng(9)
    centers = rng.uniform(-1, 1, (64, 3)) * 4
    normals = rng.normal(size=(64, 3))
    circles = Circle(centers, normals, rng.uniform(0.5, 1.0, 64))
    u = circles._unit_normal
    points = (centers + u * rng.uniform(-0.3, 0.3, (64, 1)) + rng.normal(0, 1e-15, (64, 3))).reshape(-1, 3)
    brute = Scene([circles], broad_phase="brute").closest_point(points, method="eberly")
    bvh = Scene([circles], broad_phase="bvh").closest_point(points, method="eberly")
    assert_same(brute, bvh)


def test_a_mesh_in_a_scene_contributes_its_faces():
    vertices, faces = icosphere(1)
    mesh = TriangleMesh(vertices, faces)
    plate = Disk([0, 0, 3], [0, 0, 1], 1.0)
    scene = Scene([plate, mesh])
    points = np.random.default_rng(2).normal(size=(100, 3)) * 2
    r = scene.closest_point(points)
    d_mesh = mesh.distance(points)
    d_plate = plate.distance(points)
    np.testing.assert_array_equal(r.distance, np.minimum(d_plate, d_mesh))
    from_mesh = r.source == 1
    np.testing.assert_array_equal(r.primitive[from_mesh] - 1, mesh.closest_point(points[from_mesh]).face)
    assert len(scene) == 1 + len(faces)


def test_methods_are_those_every_kind_offers_and_the_broad_phase_follows_size():
    few = Scene([Triangle(np.eye(3)), Disk([0, 0, 0], [0, 0, 1], 1.0)])
    assert few.methods == tuple(m for m in Triangle.methods if m in Disk.methods)
    assert few.broad_phase == "brute" and few.batch_shape == () and few.dim == 3
    assert isinstance(few, proximity.Shape)
    many = Scene(_shapes())
    assert many.broad_phase == "bvh"
    forced = Scene(_shapes(), broad_phase="brute")
    assert forced.broad_phase == "brute"


def test_shapes_nan_rows_and_scalars():
    scene = Scene(_shapes())
    one = scene.closest_point([0.0, 0.0, 0.0])
    assert np.ndim(one.distance) == 0 and type(one.feature) is np.int8 and np.ndim(one.primitive) == 0
    assert float(proximity.distance(scene, [0.0, 0.0, 0.0])) == float(one.distance)
    r = scene.closest_point(np.full((2, 3, 3), np.nan))
    assert r.distance.shape == (2, 3) and np.isnan(r.distance).all()
    assert (r.primitive == -1).all() and (r.source == -1).all() and (r.feature == Feature.NONE).all()
    assert not r.equidistant.any()


@pytest.mark.parametrize(
    "shapes, error, message",
    [
        (Triangle(np.eye(3)), TypeError, "shapes must be a list or tuple"),
        (
            [Triangle(np.eye(3)), "disk"],
            TypeError,
            r"shapes\[1\] must be a proximity shape \(Triangle, Segment, Point, Disk, Circle, TriangleMesh",
        ),
        ([], ValueError, "at least one primitive"),
        ([Triangle(np.zeros((0, 3, 3)))], ValueError, "at least one primitive"),
    ],
)
def test_invalid_scenes_are_refused(shapes, error, message):
    with pytest.raises(error, match=message):
        Scene(shapes)
