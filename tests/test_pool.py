"""Recycled output memory: reused only once nothing refers to it."""

import threading

import numpy as np
import pytest

import proximity
from proximity.runtime import pool as _pool

N = 100_000  # 800 kB a column: every (N, 3) output is recycled, (N,) ones are not
FIELDS = ("point", "barycentric")


def shape_and_points():
    rng = np.random.default_rng(7)
    return proximity.Triangle(rng.normal(size=(N, 3, 3))), rng.normal(size=(N, 3))


def address(array):
    return array.__array_interface__["data"][0]


def test_a_dropped_result_is_reused_and_the_new_one_is_right():
    tri, points = shape_and_points()
    expected = tri.closest_point(points[::-1])
    proximity.release_memory()
    first = tri.closest_point(points)
    before = {address(getattr(first, name)) for name in FIELDS}
    del first
    assert _pool.kept() == 2 * N * 3 * 8
    second = tri.closest_point(points[::-1])
    assert {address(getattr(second, name)) for name in FIELDS} == before
    assert _pool.kept() == 0
    for name in ("distance", "point", "feature", "barycentric"):
        np.testing.assert_array_equal(getattr(second, name), getattr(expected, name))


def test_memory_in_use_is_never_reused():
    tri, points = shape_and_points()
    proximity.release_memory()
    result = tri.closest_point(points)
    in_use = address(result.point)
    kept_view = result.point[::7]  # the result goes, a view of one of its fields stays
    copy = kept_view.copy()
    del result
    others = [tri.closest_point(points[::-1]) for _ in range(3)]
    np.testing.assert_array_equal(kept_view, copy)
    assert in_use not in {address(getattr(r, name)) for r in others for name in FIELDS}
    assert not kept_view.flags.writeable


def test_capacity_and_release():
    tri, points = shape_and_points()
    proximity.release_memory()
    results = [tri.closest_point(points) for _ in range(4)]
    del results
    assert 0 < _pool.kept() <= _pool.CAPACITY
    assert proximity.release_memory() > 0
    assert _pool.kept() == 0


def test_small_outputs_are_not_recycled():
    tri, points = shape_and_points()
    proximity.release_memory()
    proximity.Triangle(np.eye(3)).closest_point(points)  # (N, 3) outputs of float64: 2.4 MB each
    assert _pool.kept() > 0
    proximity.release_memory()
    proximity.Triangle(np.eye(3)).closest_point(points[: N // 10])
    assert _pool.kept() == 0


@pytest.mark.parametrize("kind", ["triangle", "disk"])
def test_threads_dropping_results_get_right_answers(kind):
    rng = np.random.default_rng(3)
    if kind == "triangle":
        shape = proximity.Triangle(rng.normal(size=(3, 3)))
    else:
        shape = proximity.Disk(rng.normal(size=3), rng.normal(size=3), 1.5)
    batches = [rng.normal(size=(N, 3)) for _ in range(4)]
    expected = [shape.closest_point(b) for b in batches]
    failures = []

    def work(k):
        for _ in range(5):
            r, e = shape.closest_point(batches[k]), expected[k]
            if not (np.array_equal(r.point, e.point) and np.array_equal(r.distance, e.distance)):
                failures.append(k)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert failures == []
