"""Microbenchmarks with pytest-benchmark: ``pytest benchmarks --benchmark-only``.

They live here, apart from the test suite (``tests/``, which ``make test``
runs and which never collects this directory), and time one call at a time
on seeded well-conditioned scenes, with pytest-benchmark's own calibration
and statistics:

* ``test_batch``: every method of each shape on a batch of queries, pairwise;
* ``test_single``: one point against one shape, the call a narrow phase
  makes from Python;
* ``test_backend``: each installed library, through its adapter, on a small
  batch (each row builds the library's model of its shape).

``python -m benchmarks`` is the full study (accuracy, failures, sweeps);
these are for watching the speed of one kernel while working on it, e.g.
``pytest benchmarks --benchmark-only -k "batch and triangle"``.
"""

import dataclasses

import numpy as np
import pytest

from benchmarks import accuracy
from proximity import adapters
from proximity.testing import scenes

BATCH = 100_000
BACKEND_BATCH = 256
SEED = 0

FAMILIES = {"triangle": scenes.well_conditioned, "disk": scenes.disk_well_conditioned}
FAMILIES["circle"] = scenes.disk_well_conditioned


def _scene(kind, n):
    return FAMILIES[kind](np.random.default_rng(SEED), n)


def _methods(kind):
    return accuracy.shape_of(kind, _scene(kind, 1)).methods


CASES = [(kind, method) for kind in FAMILIES for method in _methods(kind)]


@pytest.fixture(scope="module")
def batches():
    """``{kind: (shape, points)}``: a seeded batch of pairwise queries per query type."""
    out = {}
    for kind in FAMILIES:
        scene = _scene(kind, BATCH)
        out[kind] = (accuracy.shape_of(kind, scene), scene.points)
    return out


@pytest.mark.parametrize(("kind", "method"), CASES)
def test_batch(benchmark, batches, kind, method):
    shape, points = batches[kind]
    shape.closest_point(points, method=method)  # loads the compiled kernel outside the timing
    benchmark.group = f"{kind}: batch of {BATCH} pairs"
    benchmark.extra_info["queries"] = BATCH
    result = benchmark(shape.closest_point, points, method=method)
    assert np.isfinite(result.distance).all()


@pytest.mark.parametrize(("kind", "method"), CASES)
def test_single(benchmark, kind, method):
    scene = _scene(kind, 1)
    # The first query alone: a single shape (no batch dimensions) and a point of shape (3,).
    single = type(scene)(**{f.name: getattr(scene, f.name)[0] for f in dataclasses.fields(scene)})
    shape = accuracy.shape_of(kind, single)
    point = np.ascontiguousarray(single.points)
    shape.closest_point(point, method=method)  # loads the one-query kernel outside the timing
    benchmark.group = f"{kind}: one point, one shape"
    result = benchmark(shape.closest_point, point, method=method)
    assert np.isfinite(result.distance)


@pytest.mark.parametrize("kind", list(FAMILIES))
@pytest.mark.parametrize("name", adapters.NAMES)
def test_backend(benchmark, kind, name):
    if name not in adapters.available():
        pytest.skip(f"{name} is not installed")
    scene = _scene(kind, BACKEND_BATCH)
    shape = accuracy.shape_of(kind, scene)
    with adapters.get(name) as backend:
        # One query first, outside the timing: it imports the library.
        backend.closest_point(accuracy.shape_of(kind, _scene(kind, 1)), scene.points[:1])
        benchmark.group = f"{kind}: libraries, batch of {BACKEND_BATCH} pairs"
        benchmark.extra_info["queries"] = BACKEND_BATCH
        result = benchmark(backend.closest_point, shape, scene.points)
    assert result.ok.any()
