"""The API around the kernels: installation, validation, construction, reprs,
pickling, read-only results, threads and processes."""

import copy
import importlib.metadata
import os
import pathlib
import pickle
import subprocess
import sys
import textwrap
import tracemalloc
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import proximity
from proximity import Circle, Disk, Feature, Scene, Triangle, TriangleMesh
from proximity.results import asdict

ROOT = pathlib.Path(__file__).resolve().parent.parent
UNIT = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
SQUARE = ([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])


def _run(code, timeout=300, env=None, cwd=None):
    """Run ``code`` in a new interpreter; its completed process."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, **(env or {})},
        cwd=cwd,
    )


def shapes():
    """One of every kind of shape, each with points to ask it."""
    rng = np.random.default_rng(5)
    tris = rng.normal(size=(6, 3, 3))
    mesh_v = rng.normal(size=(30, 3))
    mesh_f = rng.integers(0, 30, size=(40, 3))
    return {
        "triangle": Triangle(UNIT),
        "triangles": Triangle(tris),
        "triangle 2D": Triangle(rng.normal(size=(4, 3, 2))),
        "disk": Disk([0, 0, 0], [0, 0, 1], 1.0),
        "disks": Disk(rng.normal(size=(6, 3)), rng.normal(size=(6, 3)), rng.uniform(0.1, 2, 6)),
        "circle": Circle([0, 0, 0], [0, 1, 1], 2.0),
        "mesh brute": TriangleMesh(*SQUARE),
        "mesh bvh": TriangleMesh(mesh_v, mesh_f),
        "scene": Scene([Triangle(tris), Disk([3, 0, 0], [0, 0, 1], 1.0), Circle([0, 3, 0], [1, 0, 0], 1.0)]),
    }


def points_for(shape, n=6):
    rng = np.random.default_rng(9)
    points = rng.normal(size=(n, shape.dim)) * 2
    if shape.batch_shape:
        points = rng.normal(size=shape.batch_shape + (shape.dim,)) * 2
    return points


# --- Installation ------------------------------------------------------------------------------


def test_distribution_is_proximity3d_and_adapters_install_inside_the_package(tmp_path):
    assert importlib.metadata.version("proximity3d") == proximity.__version__
    # Outside the repository, as an installed package is used.
    done = _run(
        """
        import importlib.util, proximity.adapters
        print(proximity.adapters.__name__)
        print(importlib.util.find_spec("adapters") is None)
        """,
        cwd=tmp_path,
        env={"PYTHONPATH": ""},
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["proximity.adapters", "True"]


def test_license_matches_pyproject():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License")
    assert 'license = "MIT"' in (ROOT / "pyproject.toml").read_text()


def test_make_clean_cache_deletes_numba_cache_files_only(tmp_path):
    cache = tmp_path / "proximity" / "__pycache__"
    cache.mkdir(parents=True)
    for name in ("k.point_triangle-1.py311.nbi", "k.point_triangle-1.py311.1.nbc", "shapes.cpython-311.pyc"):
        (cache / name).write_bytes(b"x")
    done = subprocess.run(
        ["make", "-f", str(ROOT / "Makefile"), "-C", str(tmp_path), "clean-cache"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in cache.iterdir()) == ["shapes.cpython-311.pyc"]


# --- The function form, validation and errors -------------------------------------------------


def test_function_form_takes_proximity_shapes_only():
    class Lookalike:  # has every attribute of the Shape protocol
        batch_shape, dim, methods = (), 3, ("robust",)

        def closest_point(self, points, *, method="robust"):
            return None

        def distance(self, points, *, method="robust"):
            return 0.0

    with pytest.raises(TypeError, match="shape must be a proximity shape"):
        proximity.distance(Lookalike(), [0, 0, 0])
    tri = Triangle(UNIT)
    p = np.array([0.2, 0.2, 1.0])
    assert proximity.distance(tri, p) == tri.distance(p) == 1.0
    assert proximity.closest_point(tri, p).point.tolist() == tri.closest_point(p).point.tolist()


BAD_POINTS = {
    "strings": ["1", "2", "3"],
    "booleans": [True, False, True],
    "complex": [1j, 0, 0],
    "int beyond float": [10**400, 0, 0],
    "ragged": [[1, 2, 3], [1, 2]],
}


@pytest.mark.parametrize("kind", ["triangle", "disk", "circle", "mesh brute", "scene"])
@pytest.mark.parametrize("bad", BAD_POINTS, ids=list(BAD_POINTS))
def test_single_point_path_refuses_what_the_batch_path_refuses(kind, bad):
    shape = shapes()[kind]
    value = BAD_POINTS[bad]
    messages = []
    for points in (value, [value]):  # one point (the fast path), then a batch of it
        for call in (shape.distance, shape.closest_point, lambda p, s=shape: proximity.distance(s, p)):
            with pytest.raises(ValueError, match="^points must be") as info:
                call(points)
            messages.append(str(info.value).split(";")[0])
    assert len(set(messages)) == 1, messages


@pytest.mark.parametrize("kind", ["triangle", "triangles", "disk", "mesh bvh", "scene"])
def test_method_must_be_a_known_str_and_keyword_only(kind):
    shape = shapes()[kind]
    name = type(shape).__name__
    p = points_for(shape)
    for points in (p, p[..., 0, :] if shape.batch_shape == () else p):
        with pytest.raises(TypeError, match=r"method must be a str.*got list \['robust'\]"):
            shape.distance(points, method=["robust"])
        with pytest.raises(TypeError, match=r"method must be a str"):
            shape.closest_point(points, method=None)
        with pytest.raises(ValueError, match="method must be one of"):
            shape.closest_point(points, method="exact")
        for function in ("distance", "closest_point"):
            with pytest.raises(TypeError, match=rf"^{name}\.{function}\(\).*method is keyword-only"):
                getattr(shape, function)(points, "robust")
    with pytest.raises(TypeError, match=r"^distance\(\).*method is keyword-only"):
        proximity.distance(shape, p, "robust")


def test_errors_name_the_public_class():
    with pytest.raises(TypeError, match=r"^Disk\.__init__\(\) missing 1 required positional argument"):
        Disk([0, 0, 0], [0, 0, 1])
    with pytest.raises(TypeError, match=r"^Circle\.__init__\(\)"):
        Circle([0, 0, 0])
    with pytest.raises(TypeError, match=r"^Triangle\.distance\(\) missing"):
        Triangle(UNIT).distance()
    with pytest.raises(TypeError, match=r"^TriangleMesh\.closest_point\(\) missing"):
        TriangleMesh(*SQUARE).closest_point()
    with pytest.raises(TypeError, match=r"^Scene\.distance\(\) missing"):
        Scene([Triangle(UNIT)]).distance()


@pytest.mark.parametrize("kind", list(shapes()))
def test_shapes_are_immutable(kind):
    shape = shapes()[kind]
    with pytest.raises(AttributeError, match="immutable"):
        shape.batch_shape = (7,)
    with pytest.raises(AttributeError, match="immutable"):
        del shape.dim


# --- Construction -----------------------------------------------------------------------------


def _peak(function, *args):
    tracemalloc.start()
    try:
        result = function(*args)
        return result, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("dtype", [np.float32, np.int64, ">f8"])
def test_triangle_construction_converts_other_input_in_one_copy(dtype):
    vertices = (np.random.default_rng(1).normal(size=(100_000, 3, 3)) * 100).astype(dtype)
    size = vertices.size * 8  # bytes of the float64 copy
    tri, peak = _peak(Triangle, vertices)
    assert peak < 1.2 * size, peak / size
    assert not np.shares_memory(tri.vertices, vertices)
    assert (tri.vertices == vertices).all()


@pytest.mark.parametrize("writeable", [True, False])
def test_c_contiguous_float64_input_is_viewed_not_copied(writeable):
    vertices = np.random.default_rng(2).normal(size=(50_000, 3, 3))
    vertices.flags.writeable = writeable
    tri, peak = _peak(Triangle, vertices)
    assert np.shares_memory(tri.vertices, vertices) and peak < 0.2 * vertices.nbytes
    assert not tri.vertices.flags.writeable and vertices.flags.writeable == writeable
    assert np.shares_memory(Triangle(tri.vertices).vertices, tri.vertices)
    center, normal, radius = vertices[:, 0], vertices[:, 1].copy(), np.ones(50_000)
    disk = Disk(center, normal, radius)
    assert np.shares_memory(disk.normal, normal) and np.shares_memory(disk.radius, radius)
    assert not np.shares_memory(disk.center, center)  # a strided view: copied once


def test_copy_true_gives_the_shape_its_own_data():
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    tri = Triangle(vertices, copy=True)
    circle = Circle(vertices[0], vertices[1] + 1, np.float64(1.0), copy=True)
    expected = tri.distance([3.0, 2.0, 1.0]), circle.distance([3.0, 2.0, 1.0])
    vertices[...] = 7.0
    assert not np.shares_memory(tri.vertices, vertices)
    assert (tri.distance([3.0, 2.0, 1.0]), circle.distance([3.0, 2.0, 1.0])) == expected


def test_triangle_mesh_takes_a_trimesh_or_any_object_with_vertices_and_faces():
    class Mesh:
        vertices = np.array(SQUARE[0], dtype=float)
        faces = np.array(SQUARE[1])

    points = [[0.25, 0.75, 2.0], [2.0, 0.5, 0.0]]
    expected = TriangleMesh(*SQUARE).closest_point(points)
    got = TriangleMesh(Mesh(), broad_phase="bvh").closest_point(points)
    assert got.distance.tolist() == expected.distance.tolist() and got.face.tolist() == [1, 0]
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box()
    mesh = TriangleMesh(box)
    assert mesh.faces.tolist() == box.faces.tolist() and mesh.vertices.tolist() == box.vertices.tolist()
    assert float(mesh.distance([0, 0, 3])) == 2.5
    with pytest.raises(TypeError, match="vertices and faces arrays, or one mesh object with vertices and"):
        TriangleMesh(np.zeros((3, 3)))


# --- Results: features, reprs, read-only ------------------------------------------------------


def test_one_point_feature_is_an_int8_scalar_and_names_cover_arrays():
    tri = Triangle(UNIT)
    r = tri.closest_point([0.2, 0.2, 1.0])
    assert type(r.feature) is np.int8 and r.feature == Feature.FACE
    assert np.ndim(r.feature) == 0 and r.feature.dtype == np.dtype(np.int8)
    assert r.feature_name == "FACE"
    batch = tri.closest_point([[2, 0, 0], [0.2, 0.2, 1], [np.nan, 0, 0]])
    assert batch.feature_name.tolist() == ["VERTEX1", "FACE", "NONE"]
    assert Feature.names(np.arange(-1, 8).reshape(3, 3)).tolist() == [
        ["NONE", "VERTEX0", "VERTEX1"],
        ["VERTEX2", "EDGE01", "EDGE12"],
        ["EDGE20", "FACE", "RIM"],
    ]
    with pytest.raises(ValueError, match="Feature codes"):
        Feature.names([8])
    with pytest.raises(TypeError, match="integer array"):
        Feature.names([0.5])


def test_reprs_show_the_data_abbreviated_for_big_batches():
    tri = Triangle(UNIT)
    assert repr(tri).startswith("Triangle(vertices=array([[0., 0., 0.],")
    big = repr(Triangle(np.arange(9000.0).reshape(1000, 3, 3)))
    assert "..." in big and "shape=(1000, 3, 3)" in big and len(big) < 1500
    assert repr(Disk([1, 2, 3], [0, 0, 1], 0.5)) == (
        "Disk(center=array([1., 2., 3.]), normal=array([0., 0., 1.]), radius=array(0.5))"
    )
    assert repr(TriangleMesh(*SQUARE)).startswith("TriangleMesh(\n    vertices=array([[0., 0., 0.],")
    assert "broad_phase='brute'" in repr(TriangleMesh(*SQUARE))
    assert repr(Scene([tri])) == "Scene([<Triangle batch_shape=()>], broad_phase='brute')"
    r = tri.closest_point(np.zeros((5000, 3)))
    text = repr(r)
    assert text.startswith("TriangleResult(\n    distance=array([0., 0., ..., 0., 0.], shape=(5000,)),")
    assert "feature=array([0, 0, ..., 0, 0], shape=(5000,), dtype=int8)" in text and len(text) < 1000
    assert "distance=array(1.)" in repr(tri.closest_point([0.2, 0.2, 1.0]))


def _arrays(result):
    return [v for v in asdict(result).values() if isinstance(v, np.ndarray)]


@pytest.mark.parametrize("n", [1, 7, 100_000])  # 100,000 points: outputs on recycled memory
@pytest.mark.parametrize("kind", ["triangles", "disks", "circle", "mesh bvh", "scene", "triangle"])
def test_no_result_array_or_its_base_is_writeable(kind, n):
    shape = shapes()[kind]
    points = np.random.default_rng(3).normal(size=(n,) + shape.batch_shape + (shape.dim,))
    for r in (shape.closest_point(points), shape.closest_point(points[0])):
        assert _arrays(r)
        for value in _arrays(r):
            assert not value.flags.writeable
            with pytest.raises(ValueError, match="WRITEABLE"):
                value.flags.writeable = True
            base = value.base
            while isinstance(base, np.ndarray):
                assert not base.flags.writeable
                base = base.base


# --- Pickling and copies ----------------------------------------------------------------------


def _same(a, b):
    assert type(a) is type(b)
    for name, value in asdict(a).items():
        np.testing.assert_array_equal(np.asarray(getattr(b, name)), np.asarray(value), strict=True)


@pytest.mark.parametrize("kind", list(shapes()))
def test_shapes_pickle_copy_and_deepcopy(kind, monkeypatch):
    shape = shapes()[kind]
    points = points_for(shape)
    expected = shape.closest_point(points)
    blob = pickle.dumps(shape)
    from proximity import broadphase

    def no_rebuild(*args, **kwargs):
        raise AssertionError("the tree was rebuilt")

    for name in ("build_tree", "build_faces", "brute"):
        monkeypatch.setattr(broadphase, name, no_rebuild)
    for other in (pickle.loads(blob), copy.copy(shape), copy.deepcopy(shape)):
        assert type(other) is type(shape) and repr(other) == repr(shape)
        _same(expected, other.closest_point(points))
        for method in shape.methods:
            assert (other.distance(points, method=method) == shape.distance(points, method=method)).all()
        for name in other._slots():
            value = getattr(other, name)
            for array in vars(value).values() if name == "_tree" else [value]:
                if isinstance(array, np.ndarray):
                    assert not array.flags.writeable
        with pytest.raises(AttributeError, match="immutable"):
            other.dim = 2


@pytest.mark.parametrize("n", [None, 3])
@pytest.mark.parametrize("kind", ["triangle", "disk", "circle", "mesh brute", "scene"])
def test_results_pickle_and_stay_read_only(kind, n):
    shape = shapes()[kind]
    points = points_for(shape)
    r = shape.closest_point(points[0] if n is None else points[:n])
    back = pickle.loads(pickle.dumps(r))
    _same(r, back)
    for value in _arrays(back):
        assert not value.flags.writeable
        with pytest.raises(ValueError, match="WRITEABLE"):
            value.flags.writeable = True


# --- Threads ----------------------------------------------------------------------------------


def test_threads_sets_numbas_threads_for_the_block_and_restores_them():
    import numba

    tri = Triangle(np.random.default_rng(4).normal(size=(3, 3)))
    points = np.random.default_rng(5).normal(size=(20_000, 3))
    before = numba.get_num_threads()
    with proximity.threads(1) as n:
        assert n == 1 and numba.get_num_threads() == 1
        one = tri.distance(points)
    assert numba.get_num_threads() == before
    with proximity.threads() as n:
        assert n == numba.config.NUMBA_NUM_THREADS == numba.get_num_threads()
    assert (one == tri.distance(points)).all()
    with proximity.threads(np.int64(1)) as n:  # any integer
        assert n == 1 and type(n) is int and numba.get_num_threads() == 1
    bad_values = [(0, ValueError), (numba.config.NUMBA_NUM_THREADS + 1, ValueError), (1.0, TypeError)]
    for bad, error in bad_values + [(True, TypeError), (np.True_, TypeError), (np.float64(1), TypeError)]:
        with pytest.raises(error, match="^n must be"):
            with proximity.threads(bad):
                pass


def _mixed_queries():
    """Query functions over every kind of shape, path and method."""
    rng = np.random.default_rng(8)
    calls = []
    for shape in shapes().values():
        batch = rng.normal(size=(3000,) + shape.batch_shape + (shape.dim,))
        for method in shape.methods:
            calls.append(lambda s=shape, p=batch, m=method: s.closest_point(p, method=m).point)
            if shape.batch_shape == () and shape.dim == 3 and not isinstance(shape, Scene | TriangleMesh):
                single = batch[0]
                calls.append(lambda s=shape, p=single, m=method: s.closest_point(p, method=m).point)
            calls.append(lambda s=shape, p=batch, m=method: s.distance(p, method=m))
    return calls


def test_eight_python_threads_give_the_single_threaded_answers_bit_for_bit():
    calls = _mixed_queries()
    expected = [call() for call in calls]
    order = np.random.default_rng(0).permutation(np.repeat(np.arange(len(calls)), 3))
    with ThreadPoolExecutor(8) as pool:
        got = list(pool.map(lambda i: (i, calls[i]()), order))
    for i, value in got:
        np.testing.assert_array_equal(value, expected[i], strict=True)


def test_workqueue_layer_serialises_python_threads_instead_of_aborting():
    # Numba's workqueue layer aborts the process when two threads launch
    # kernels at once; proximity runs its launches one at a time there.
    done = _run(
        """
        from concurrent.futures import ThreadPoolExecutor
        import numpy as np, numba, proximity
        tri = proximity.Triangle(np.random.default_rng(0).normal(size=(50, 3, 3)))
        disk = proximity.Disk([0, 0, 0], [0, 0, 1], 1.0)
        points = np.random.default_rng(1).normal(size=(20_000, 1, 3))
        expected = tri.distance(points).tobytes(), disk.distance(points).tobytes()
        def work(i):
            shape = (tri, disk)[i % 2]
            return shape.distance(points).tobytes() == expected[i % 2]
        with ThreadPoolExecutor(8) as pool:
            ok = all(pool.map(work, range(64)))
        print(numba.threading_layer(), ok)
        """,
        env={"NUMBA_THREADING_LAYER": "workqueue"},
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["workqueue", "True"]


# --- Processes --------------------------------------------------------------------------------


@pytest.mark.parametrize("start", ["fork", "spawn", "forkserver"])
def test_process_pools_work_after_queries_have_run(start, tmp_path):
    # Under fork, GNU OpenMP's layer terminated every child forked after a
    # query, and the pool hung; under spawn and forkserver, shapes must pickle.
    script = tmp_path / "pool.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import multiprocessing, numpy as np, proximity

            def work(args):
                shape, points = args
                return shape.closest_point(points).distance

            if __name__ == "__main__":
                tri = proximity.Triangle(np.random.default_rng(0).normal(size=(2, 3, 3)))
                mesh = proximity.TriangleMesh(np.random.default_rng(1).normal(size=(20, 3)),
                                              np.random.default_rng(2).integers(0, 20, size=(30, 3)))
                points = np.random.default_rng(3).normal(size=(5000, 2, 3))
                expected = [tri.closest_point(points).distance, mesh.closest_point(points).distance]
                with multiprocessing.get_context({start!r}).Pool(2) as pool:
                    got = pool.map(work, [(tri, points), (mesh, points)])
                print(all((a == b).all() for a, b in zip(got, expected, strict=True)))
            """
        )
    )
    result = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=240, cwd=ROOT
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split() == ["True"]
