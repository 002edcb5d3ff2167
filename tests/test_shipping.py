"""Shipping shapes and results to other processes: compact pickles that
unpickle without building a hierarchy, and the same answers, bit for bit,
in a forked or spawned worker."""

import copy
import dataclasses
import pathlib
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import proximity
from proximity import Circle, Disk, Scene, Triangle, TriangleMesh, broadphase
from proximity.broadphase import build as build_module
from proximity.results import asdict

ROOT = pathlib.Path(__file__).resolve().parent.parent


def _sphere(n=40):
    """A closed mesh of ``2 n (n - 1)`` faces: a UV sphere."""
    theta, phi = np.meshgrid(np.linspace(0, np.pi, n + 1)[1:-1], np.linspace(0, 2 * np.pi, n, endpoint=False))
    ring = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    vertices = np.concatenate([ring.transpose(1, 0, 2).reshape(-1, 3), [[0, 0, 1], [0, 0, -1]]])
    rows, top, bottom = n - 1, len(vertices) - 2, len(vertices) - 1
    faces = []
    for i in range(rows):
        for j in range(n):
            a, b = i * n + j, i * n + (j + 1) % n
            if i + 1 < rows:
                faces += [[a, a + n, b], [b, a + n, b + n]]
    for j in range(n):
        faces += [[top, j, (j + 1) % n], [bottom, (rows - 1) * n + (j + 1) % n, (rows - 1) * n + j]]
    return vertices, np.array(faces)


def collections():
    rng = np.random.default_rng(11)
    vertices, faces = _sphere()
    mesh = TriangleMesh(vertices, faces)
    return {
        "mesh bvh": mesh,
        "mesh brute": TriangleMesh(vertices, faces, broad_phase="brute"),
        "scene with circles": Scene(
            [
                mesh,
                Triangle(rng.normal(size=(30, 3, 2))),
                Disk(rng.normal(size=(20, 3)), rng.normal(size=(20, 3)), rng.uniform(0.1, 1, 20)),
                Circle(rng.normal(size=(20, 3)), rng.normal(size=(20, 3)), rng.uniform(0.1, 1, 20)),
            ]
        ),
    }


def _forbid_building(monkeypatch):
    def built(*args, **kwargs):
        raise AssertionError("a hierarchy was built on unpickling")

    for name in ("build_tree", "build_faces", "brute"):
        monkeypatch.setattr(broadphase, name, built)
    monkeypatch.setattr(build_module, "_build", built)


def _assert_same_answers(shape, back, points):
    """Every method's full answer of ``back`` is ``shape``'s, bit for bit."""
    for method in shape.methods:
        a, b = shape.closest_point(points, method=method), back.closest_point(points, method=method)
        for name, value in asdict(a).items():
            np.testing.assert_array_equal(getattr(b, name), value, strict=True)


@pytest.mark.parametrize("kind", list(collections()))
def test_unpickled_collections_hold_the_same_tree_bit_for_bit_without_building_it(kind, monkeypatch):
    shape = collections()[kind]
    blob = pickle.dumps(shape, protocol=pickle.HIGHEST_PROTOCOL)
    _forbid_building(monkeypatch)
    back = pickle.loads(blob)
    for field in dataclasses.fields(broadphase.Tree):
        a, b = getattr(shape._tree, field.name), getattr(back._tree, field.name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and a.shape == b.shape, field.name
            assert a.tobytes() == b.tobytes(), field.name
            assert not b.flags.writeable and b.flags.c_contiguous, field.name
        else:
            assert a == b, field.name
    _assert_same_answers(shape, back, np.random.default_rng(2).normal(size=(2000, 3)) * 1.5)


@pytest.mark.parametrize("kind", list(collections()))
def test_node_bounds_in_a_pickle_of_an_earlier_version_are_not_read(kind):
    # Earlier versions pickled the node bounds (a box and one slab, 11
    # columns); the tree comes back with this version's bounds.
    shape = collections()[kind]
    state = copy.deepcopy(shape.__getstate__())
    tree = shape._tree
    state["_hierarchy"]["bounds"] = tree.bounds[:, :11].copy()
    loose = tree.loose
    state["_hierarchy"]["loose_bounds"] = tree.loose_bounds[:, :11].copy() if loose else None
    back = type(shape).__new__(type(shape))
    back.__setstate__(state)
    for name in ("bounds", "loose_bounds", "child", "index"):
        assert getattr(back._tree, name).tobytes() == getattr(tree, name).tobytes(), name
    _assert_same_answers(shape, back, np.random.default_rng(3).normal(size=(500, 3)) * 1.5)


@pytest.mark.parametrize("kind", list(collections()))
def test_collections_pickle_their_data_and_the_hierarchy_s_decisions_only(kind):
    shape = collections()[kind]
    blob = pickle.dumps(shape, protocol=pickle.HIGHEST_PROTOCOL)
    tree = shape._tree
    decisions = tree.index.nbytes + tree.child.nbytes + tree.count.nbytes
    if isinstance(shape, TriangleMesh):
        own = shape.vertices.nbytes + shape.faces.nbytes
    else:
        own = sum(len(pickle.dumps(s, protocol=pickle.HIGHEST_PROTOCOL)) for s in shape.shapes)
        own += shape.offsets.nbytes + shape._kinds.nbytes
    assert len(blob) <= own + decisions + 4096
    # Everything the tree holds would be several times larger.
    held = [getattr(tree, f.name) for f in dataclasses.fields(tree) if f.name != "depth"]
    whole = sum(a.nbytes for a in held if a is not None)
    assert len(blob) < 0.5 * (own + whole)


@pytest.mark.parametrize("kind", ["triangle 2D", "triangle", "disk", "circles"])
def test_shapes_pickle_their_own_arrays_only(kind, monkeypatch):
    rng = np.random.default_rng(4)
    shape = {
        "triangle 2D": Triangle(rng.normal(size=(1000, 3, 2))),
        "triangle": Triangle(rng.normal(size=(3, 3))),
        "disk": Disk([0, 0, 0], [0, 0, 2], 1.0),
        "circles": Circle(rng.normal(size=(1000, 3)), rng.normal(size=(1000, 3)), 1.0),
    }[kind]
    blob = pickle.dumps(shape, protocol=pickle.HIGHEST_PROTOCOL)
    stored = shape.__getstate__()
    assert not set(stored) & set(shape._derived)
    own = sum(value.nbytes for value in stored.values() if isinstance(value, np.ndarray))
    assert len(blob) <= own + 1024
    back = pickle.loads(blob)
    for name in shape._derived:
        a, b = getattr(shape, name), getattr(back, name)
        assert (a is None and b is None) or (a.tobytes() == b.tobytes() and not b.flags.writeable)
    points = rng.normal(size=(500,) + shape.batch_shape + (shape.dim,))
    np.testing.assert_array_equal(back.distance(points), shape.distance(points), strict=True)
    if shape.batch_shape == ():
        # The one-point path runs on the restored arguments.
        one = points[0]
        np.testing.assert_array_equal(back.closest_point(one).point, shape.closest_point(one).point)


@pytest.mark.parametrize("n", [5, 300_000])  # 300,000 points: results on recycled memory
def test_results_pickle_no_more_than_their_arrays(n):
    mesh = collections()["mesh bvh"]
    r = mesh.closest_point(np.random.default_rng(6).normal(size=(n, 3)))
    blob = pickle.dumps(r, protocol=pickle.HIGHEST_PROTOCOL)
    # Its fields and its normals, which a result pickles (the query they are made from stays).
    arrays = sum(np.asarray(value).nbytes for value in asdict(r).values()) + r.normal.nbytes
    assert len(blob) <= arrays + 2048
    back = pickle.loads(blob)
    for name in [*asdict(r), "normal"]:
        np.testing.assert_array_equal(getattr(back, name), getattr(r, name), strict=True)
        assert not getattr(back, name).flags.writeable


@pytest.mark.parametrize("start", ["fork", "spawn"])
def test_workers_answer_for_shipped_collections_bit_for_bit_without_building(start, tmp_path):
    # The workers' broad phase cannot build a hierarchy: unpickling must not.
    # They send back whole results, which the parent compares field by field.
    script = tmp_path / "ship.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import multiprocessing, pickle, sys
            import numpy as np
            from proximity.results import asdict
            sys.path.insert(0, {str(ROOT / "tests")!r})
            from test_shipping import collections

            def forbid():
                from proximity import broadphase
                from proximity.broadphase import build
                def built(*args, **kwargs):
                    raise AssertionError("built in a worker")
                broadphase.build_tree = broadphase.build_faces = broadphase.brute = build._build = built

            def work(args):
                shape, points = args
                return shape.closest_point(points), shape.distance(points, method="certified")

            if __name__ == "__main__":
                shapes = list(collections().values())
                points = np.random.default_rng(3).normal(size=(4000, 3)) * 1.5
                expected = [work((shape, points)) for shape in shapes]
                with multiprocessing.get_context({start!r}).Pool(2, initializer=forbid) as pool:
                    got = pool.map(work, [(shape, points) for shape in shapes])
                ok = True
                for (r, d), (r2, d2) in zip(expected, got, strict=True):
                    ok &= type(r) is type(r2) and d.tobytes() == d2.tobytes()
                    for name, value in asdict(r).items():
                        ok &= np.asarray(value).tobytes() == np.asarray(getattr(r2, name)).tobytes()
                print(ok, len(got))
            """
        )
    )
    result = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=240, cwd=ROOT
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split() == ["True", "3"]


def test_a_pickle_holding_the_whole_tree_still_loads():
    # The state of a collection pickled with its tree in it.
    mesh = collections()["mesh bvh"]
    state = {name: getattr(mesh, name) for name in mesh._slots()}
    back = TriangleMesh.__new__(TriangleMesh)
    back.__setstate__(pickle.loads(pickle.dumps(state)))
    points = np.random.default_rng(1).normal(size=(100, 3))
    np.testing.assert_array_equal(back.distance(points), mesh.distance(points), strict=True)
    assert proximity.distance(back, points).tobytes() == mesh.distance(points).tobytes()
