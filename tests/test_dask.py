"""proximity.dask: distances and closest points of dask arrays, on the
threaded scheduler and on a cluster of worker processes, equal bit for bit
to the in-process answers."""

import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from proximity import Circle, Disk, Scene, Sphere, Triangle, TriangleMesh
from proximity.results import asdict

da = pytest.importorskip("dask.array")
dask = pytest.importorskip("dask")
pdask = pytest.importorskip("proximity.dask")

from test_shipping import _sphere  # noqa: E402


def _mesh():
    return TriangleMesh(*_sphere(24))


def _cloud(n=20_000, seed=0):
    return np.random.default_rng(seed).normal(size=(n, 3)) * 1.2


def _same_fields(arrays, result):
    """Every field of the dask answer ``arrays`` (computed) equals ``result``'s, bit for bit."""
    got = dask.compute(*arrays)
    assert arrays._fields == tuple(asdict(result))
    for name, value in zip(arrays._fields, got, strict=True):
        expected = getattr(result, name)
        assert value.dtype == expected.dtype and value.shape == expected.shape, name
        assert value.tobytes() == expected.tobytes(), name


def _shapes():
    rng = np.random.default_rng(1)
    return {
        "mesh": _mesh(),
        "scene": Scene([_mesh(), Disk([0, 0, 2], [0, 0, 1], 0.5), Circle([2, 0, 0], [1, 0, 0], 0.7)]),
        "triangle": Triangle(rng.normal(size=(3, 3))),
        "triangle 2D": Triangle(rng.normal(size=(3, 2))),
        "disk": Disk([0, 0, 0], [0, 1, 1], 1.0),
        "circle": Circle([0, 0, 0], [1, 1, 0], 1.0),
    }


@pytest.mark.parametrize("kind", list(_shapes()))
def test_threaded_scheduler_answers_as_in_process(kind):
    shape = _shapes()[kind]
    points = _cloud(5000)[:, : shape.dim]
    x = da.from_array(points, chunks=(700, 1))  # columns split: brought into one chunk
    d = pdask.distance(shape, x)
    assert d.chunks == (x.chunks[0],)
    for method in shape.methods:
        got = pdask.distance(shape, x, method=method).compute(scheduler="threads")
        assert got.tobytes() == shape.distance(points, method=method).tobytes()
    with dask.config.set(scheduler="threads"):
        _same_fields(pdask.closest_point(shape, x), shape.closest_point(points))


def test_a_numpy_array_and_float32_points_are_accepted():
    mesh = _mesh()
    points = _cloud(3000).astype(np.float32)
    assert pdask.distance(mesh, points).compute().tobytes() == mesh.distance(points).tobytes()


def test_records_hold_the_fields_asked_for():
    mesh = _mesh()
    points = _cloud(3000)
    table = pdask.records(mesh, da.from_array(points, chunks=(1000, 3)), fields=["distance", "face"])
    assert table.dtype.names == ("distance", "face")
    got, expected = table.compute(), mesh.closest_point(points)
    assert got["distance"].tobytes() == expected.distance.tobytes()
    assert got["face"].tobytes() == expected.face.tobytes()


def test_records_hold_signed_distances_where_the_shape_has_them():
    sphere = Sphere([0.0, 0.0, 0.0], 1.0)
    points = _cloud(300)
    got = pdask.records(sphere, da.from_array(points, chunks=(100, 3)), fields=["signed_distance", "point"])
    assert got.dtype.names == ("signed_distance", "point")
    got = got.compute()
    assert got["signed_distance"].tobytes() == sphere.signed_distance(points).tobytes()
    assert got["point"].tobytes() == sphere.closest_point(points).point.tobytes()
    assert "signed_distance" not in pdask.records(sphere, da.from_array(points)).dtype.names
    with pytest.raises(TypeError, match="sign is an option of meshes; got a Sphere"):
        pdask.records(sphere, da.from_array(points), fields=["signed_distance"], sign="winding")
    with pytest.raises(ValueError, match="fields must be names among"):
        pdask.records(Triangle(np.eye(3)), da.from_array(points), fields=["signed_distance"])


def _shape_keys(collection):
    return [k for k in collection.__dask_graph__() if str(k).startswith("proximity-shape-")]


def _graph_bytes(collection):
    """Bytes of the graph's tasks, each pickled alone, as a scheduler sends them."""
    return sum(len(pickle.dumps(task, protocol=5)) for task in collection.__dask_graph__().values())


def test_the_shape_is_one_node_of_the_graph_under_the_threaded_scheduler():
    mesh = _mesh()
    x = da.from_array(_cloud(), chunks=(1000, 3))  # 20 chunks
    d = pdask.distance(mesh, x)
    blob = len(pickle.dumps(mesh, protocol=5))
    assert _graph_bytes(d) - _graph_bytes(x) < blob + 20_000  # once, not 20 times
    assert len(_shape_keys(d)) == 1
    # The same shape gives the same key: the graphs of two queries share it.
    assert _shape_keys(d) == _shape_keys(pdask.distance(_mesh(), x))


def test_bad_arguments_are_refused_before_any_task_runs():
    mesh = _mesh()
    x = da.from_array(_cloud(100), chunks=50)
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\); got shape \(100, 2\)"):
        pdask.distance(mesh, x[:, :2])
    with pytest.raises(ValueError, match="method must be one of"):
        pdask.distance(mesh, x, method="exact")
    with pytest.raises(ValueError, match="single shape"):
        pdask.distance(Triangle(np.zeros((4, 3, 3))), x)
    with pytest.raises(TypeError, match="proximity shape"):
        pdask.distance("mesh", x)
    with pytest.raises(ValueError, match="fields must be names"):
        pdask.records(mesh, x, fields=["distance", "primitive"])
    with pytest.raises(ValueError, match="threads must be"):
        pdask.closest_point(mesh, x, threads=0)
    with pytest.raises(ValueError, match="threads must be"):
        pdask.closest_point(mesh, x, threads=True)
    # Every message names its argument.
    with pytest.raises(ValueError, match=r"^points must be an array of shape \(N, 3\)"):
        pdask.distance(mesh, [[0, 0, 1], [0, 1]])
    with pytest.raises(ValueError, match=r"^shape must be a single shape"):
        pdask.distance(Triangle(np.zeros((4, 3, 3))), x)
    with pytest.raises(ValueError, match="^fields must be names"):
        pdask.records(mesh, x, fields=np.zeros((2, 3)))
    with pytest.raises(TypeError, match="^fields must be a str or a sequence of str"):
        pdask.records(mesh, x, fields=1.0)


def test_threads_may_be_any_integer():
    mesh = _mesh()
    x = da.from_array(_cloud(100), chunks=50)
    expected = mesh.distance(_cloud(100))
    assert pdask.distance(mesh, x, threads=np.int64(1)).compute().tobytes() == expected.tobytes()


def test_the_core_install_imports_without_dask_and_says_how_to_get_it():
    code = textwrap.dedent(
        """
        import sys
        sys.modules["dask"] = None  # as if not installed
        import numpy as np, proximity, proximity.dask
        try:
            proximity.dask.distance(proximity.Disk([0, 0, 0], [0, 0, 1], 1.0), np.zeros((3, 3)))
        except ImportError as exc:
            print(exc)
        """
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "pip install '.[scale]' in proximity's clone" in done.stdout
    done = subprocess.run(
        [sys.executable, "-c", "import sys, proximity; print('dask' in sys.modules)"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.stdout.split() == ["False"]


# --- On a cluster of two worker processes -------------------------------------------------------


def test_a_local_cluster_of_processes_answers_bit_for_bit_as_in_process(dask_client):
    mesh = _mesh()
    scene = _shapes()["scene"]
    points = _cloud()
    x = da.from_array(points, chunks=(2500, 3))
    expected = {"mesh": mesh.closest_point(points), "scene": scene.closest_point(points)}
    certified = mesh.distance(points, method="certified")
    with dask_client.as_current():
        d = pdask.distance(mesh, x, method="certified")
        # The graph refers to the shape scattered to the workers: it does not hold it.
        assert _graph_bytes(d) - _graph_bytes(x) < 0.1 * len(pickle.dumps(mesh, protocol=5))
        assert d.compute().tobytes() == certified.tobytes()
        _same_fields(pdask.closest_point(mesh, x), expected["mesh"])
        _same_fields(pdask.closest_point(scene, x), expected["scene"])
        # Each worker holds the mesh once, under its content's key.
        held = dask_client.has_what()
        assert len(held) == 2 and all(set(_shape_keys(d)) <= set(k) for k in held.values())


def test_tasks_on_two_single_threaded_workers_of_one_host_run_numba_on_one_thread_each(dask_client):
    import numba

    workers = dask_client.scheduler_info(n_workers=-1)["workers"]
    hosts = {info["host"] for info in workers.values()}
    per_host = {host: 2 for host in hosts}
    cores = dask_client.run(pdask._cores)
    limits = dask_client.run(lambda: numba.config.NUMBA_NUM_THREADS)
    for address in workers:
        got = dask_client.submit(pdask.task_threads, None, per_host, workers=[address], pure=False).result()
        assert got == max(1, min(limits[address], cores[address] // 2))
    assert pdask.task_threads(3, None) == min(3, numba.config.NUMBA_NUM_THREADS)
    assert pdask.task_threads(None, None) == numba.config.NUMBA_NUM_THREADS
