"""The method registry drives every method through every shape and path."""

import ast
import os
import subprocess
import sys

import numpy as np
import pytest

import proximity
from proximity import methods, primitives
from proximity.testing import exact

RNG = np.random.default_rng(11)
VERTICES = RNG.normal(size=(6, 3, 3))
POINTS = RNG.normal(size=(6, 3)) * 2
CENTERS, NORMALS, RADII = RNG.normal(size=(6, 3)), RNG.normal(size=(6, 3)), RNG.uniform(0.5, 2, 6)


def _shapes():
    """``(name, batch of 6 shapes, one shape, exact distance of shape k to point)``."""
    yield (
        "triangle",
        proximity.Triangle(VERTICES),
        proximity.Triangle(VERTICES[0]),
        (lambda k, p: exact.triangle_distance(VERTICES[k], p)),
    )
    for cls, reference in ((proximity.Disk, exact.disk_distance), (proximity.Circle, exact.circle_distance)):
        yield (
            cls.__name__.lower(),
            cls(CENTERS, NORMALS, RADII),
            cls(CENTERS[0], NORMALS[0], RADII[0]),
            (lambda k, p, reference=reference: reference(CENTERS[k], NORMALS[k], RADII[k], p)),
        )


def _within_bound(method, d, d_exact, scale):
    if method is methods.ROBUST:
        return exact.error_in_units(d, d_exact, scale) <= 8.0
    if method is methods.CERTIFIED:
        return exact.ulps(d, d_exact) < 1.0
    return np.isfinite(d)  # eberly promises nothing, but these inputs are well conditioned


@pytest.mark.parametrize("name", list(methods.REGISTRY))
def test_every_method_through_every_shape_and_path(name):
    method = methods.REGISTRY[name]
    for kind, batch, one, reference in _shapes():
        pairs = batch.closest_point(POINTS, method=name)
        against_one = one.closest_point(POINTS, method=name)
        for k, p in enumerate(POINTS):
            single = one.closest_point(p, method=name)
            # The one-point fast path and the batch kernels give the same bits.
            assert single.distance.tobytes() == against_one.distance[k].tobytes(), (kind, name, k)
            assert single.point.tobytes() == against_one.point[k].tobytes(), (kind, name, k)
            for d, shape_index in ((pairs.distance[k], k), (against_one.distance[k], 0)):
                scale = (
                    exact.triangle_scale(VERTICES[shape_index], p)
                    if kind == "triangle"
                    else exact.circle_scale(CENTERS[shape_index], RADII[shape_index], p)
                )
                assert _within_bound(method, float(d), reference(shape_index, p), scale), (kind, name, k)
    mesh = proximity.TriangleMesh(VERTICES.reshape(-1, 3), np.arange(18).reshape(-1, 3))
    scene = proximity.Scene([mesh, proximity.Disk(CENTERS, NORMALS, RADII)])
    for collection in (mesh, scene):
        d = collection.distance(POINTS, method=name)
        assert np.isfinite(d).all() and d.shape == (6,)


def test_compile_all_covers_every_method():
    from proximity import compile as compile_module

    jobs = [description for name in methods.REGISTRY for description, _ in compile_module._jobs(name)]
    for name in methods.REGISTRY:
        offering = primitives.offering(methods.resolve(name))
        modules = {p.module for p in offering}
        # One point, pairs and one shape per kernel module; a collection of each kind and of several;
        # and a mesh's, whose tree reads its faces through their vertices.
        expected = 3 * len(modules) + len(offering) + 1 + (primitives.TRIANGLE in offering)
        assert sum(f": {name}" in job for job in jobs) == expected, name


@pytest.mark.parametrize(
    "method, error",
    [("fast", ValueError), (["robust"], TypeError), (None, TypeError), (1, TypeError)],
)
def test_unknown_methods_are_refused_at_the_boundary(method, error):
    tri = proximity.Triangle(VERTICES[0])
    for call in (tri.distance, tri.closest_point):
        with pytest.raises(error, match="method must be"):
            call(POINTS, method=method)
        with pytest.raises(error, match="method must be"):
            call(POINTS[0], method=method)


_RECORD = """
from numba.core import event

recorder = event.RecordingListener()
event.register("numba:compile", recorder)
"""
# The kernels compiled, of those kept in the disk cache (helpers compiled
# into their callers compile again with every new caller).
_COMPILED = """
started = [ev.data["dispatcher"] for _, ev in recorder.buffer if ev.is_start]
print(sorted({d.py_func.__qualname__ for d in started if type(d._cache).__name__ != "NullCache"}))
"""
_QUERIES = """
import numpy as np, proximity

rng = np.random.default_rng(0)
# A grid of 2 x 129^2 faces: above the size from which the build gathers rows
# in compiled loops.
g = np.stack(np.meshgrid(np.arange(130.0), np.arange(130.0), indexing="ij"), axis=-1).reshape(-1, 2)
vertices = np.column_stack([g, np.sin(g[:, 0]) * np.cos(g[:, 1])])
i = (np.arange(129)[:, None] * 130 + np.arange(129)).ravel()
faces = np.concatenate([np.column_stack([i, i + 130, i + 1]), np.column_stack([i + 1, i + 130, i + 131])])
n = 70_000  # above the batch from which disks' unit normals are computed by a compiled loop
disk = proximity.Disk(rng.random((10, 3)), rng.random(3) + 0.1, 1.0)
mesh = proximity.TriangleMesh(vertices, faces)
shapes = [
    proximity.Disk(rng.random((n, 3)), rng.random((n, 3)) + 0.1, rng.random(n)),
    proximity.TriangleMesh(vertices[:20], [[0, 1, 2], [2, 1, 3]]),  # brute force
    mesh,
    proximity.Scene([mesh, disk]),
]
for shape in shapes:
    shape.distance(rng.random((n, 3)) * 100, method="eberly")
mesh.signed_distance(rng.random((10, 3)) * 100, method="eberly", sign="winding")
# Refits: of the tree, and of a tree of one leaf.
mesh.with_vertices(vertices * 1.5)
shapes[1].with_vertices(vertices[:20] * 1.5)
"""


def test_a_new_process_loads_what_compile_all_compiled(tmp_path):
    """What ``python -m proximity.compile`` leaves in the cache is what the
    queries load: the kernels it compiles by hand (the hierarchy's build and
    search, the gathers of large meshes, the visiting order of large
    batches, the disks' unit normals, the winding number) have the argument
    types the queries give them.  (The
    methods' kernels have fixed signatures; they are left out, to keep the
    test short.)"""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def compiled(code):
        command = [sys.executable, "-c", _RECORD + code + _COMPILED]
        run = subprocess.run(command, env=env, check=True, capture_output=True, text=True)
        return set(ast.literal_eval(run.stdout.strip().splitlines()[-1]))

    ahead = compiled("import proximity.compile; proximity.compile.compile_all([], log=None)")
    # A specialised kernel is named after its function, its tag and a stamp of the sources.
    names = {name.split("__")[0] for name in ahead}
    expected = {"_build_step", "_face_step", "_fit_step", "_fit_indexed", "_gather_faces", "_empty"}
    expected |= {"_take_rows", "_morton"}
    assert expected | {"round_frames"} <= names
    assert not compiled(_QUERIES) & ahead


def test_the_public_numba_fallback_answers_with_the_same_bits(tmp_path):
    """Blocks called directly (Numba's public API) rather than through their
    address (its private internals, used where they work, as with the pinned
    Numba) give the same bits, on every kind's batches, a mesh and a scene; a run
    split over two processes gives every array of the whole run."""
    reference = tmp_path / "address.npz"
    command = [sys.executable, "-m", "proximity.testing.smoke", "--method", "robust"]
    first = subprocess.run([*command, str(reference)], capture_output=True, text=True, check=True)
    assert "through their addresses" in first.stdout
    env = dict(os.environ, PROXIMITY_NUMBA_PUBLIC="1")
    # Split over two processes (as `make numba-floor` runs it): the same arrays, no fewer.
    compare = [*command, str(tmp_path / "direct.npz"), "--jobs", "2", "--compare", str(reference)]
    second = subprocess.run(compare, env=env, capture_output=True, text=True)
    assert second.returncode == 0, second.stderr[-2000:]
    assert "blocks called directly" in second.stdout and "bit for bit" in second.stdout
