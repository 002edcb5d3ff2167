"""The kernel cache's faults: damaged files and full disks still answer, right.

Each test runs new processes with their own ``NUMBA_CACHE_DIR``, and
compares their answers with those of a process that started with an empty
cache.
"""

import ast
import os
import resource
import shutil
import signal
import subprocess
import sys
import warnings

import pytest

from tests import disks

# A single point (its kernel compiled lazily, at the first call) and a batch
# (its block and loop kernels compiled for their signatures at once).
SINGLE = """
import numpy as np, proximity
tri = proximity.Triangle([[0, 0, 0], [1, 0, 0.5], [0.2, 1, 0]])
print([float(tri.distance([0.3, 0.4, 2.0]))])
"""
BATCH = (
    SINGLE
    + """
print(tri.distance(np.random.default_rng(0).normal(size=(1000, 3))).tolist())
"""
)
# Appended to a query: the kernels kept in the disk cache that were compiled
# rather than loaded.
RECORD = """
from numba.core import event

recorder = event.RecordingListener()
event.register("numba:compile", recorder)
"""
COMPILED = """
started = [ev.data["dispatcher"] for _, ev in recorder.buffer if ev.is_start]
print(sorted({d.py_func.__qualname__ for d in started if type(d._cache).__name__ != "NullCache"}))
"""
UNWRITABLE = "the kernel cache cannot be written"


def _run(code, cache, limit_file_size=False):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))

    def no_writes():
        # Writing past the limit then fails with EFBIG, as a full disk fails
        # with ENOSPC, instead of killing the process.
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (0, resource.RLIM_INFINITY))

    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
        preexec_fn=no_writes if limit_file_size else None,
    )
    assert result.returncode == 0, result.stderr
    return result


@pytest.fixture(scope="module")
def filled_cache(tmp_path_factory):
    """A cache filled by a process that started with none, and that process's answers."""
    cache = tmp_path_factory.mktemp("cache")
    return cache, _run(BATCH, cache).stdout


# One kernel's file per case: the index or a data file, cut in half or
# emptied (an interrupted copy, a disk that filled up while it was written).
@pytest.mark.parametrize(
    "kernel, suffix, damage",
    [
        ("_single__robust", ".nbi", "truncated"),
        ("_loop__blocks", ".nbi", "empty"),
        ("_robust_block", ".nbc", "truncated"),
        ("_single__robust", ".nbc", "empty"),
    ],
)
def test_a_damaged_entry_is_compiled_again_and_replaced(filled_cache, tmp_path, kernel, suffix, damage):
    filled, expected = filled_cache
    cache = tmp_path / "cache"
    shutil.copytree(filled, cache)
    damaged = [p for p in cache.rglob(f"*{suffix}") if f".{kernel}_" in p.name]
    assert len(damaged) == 1, damaged
    path = damaged[0]
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2] if damage == "truncated" else b"")

    recovered = _run(RECORD + BATCH + COMPILED, cache)
    answers, compiled = recovered.stdout.rsplit("\n", 2)[:2]
    assert answers + "\n" == expected
    assert [name.split("__")[0] for name in ast.literal_eval(compiled)] == [kernel.split("__")[0]]
    assert "Warning" not in recovered.stderr
    # The entry was written again: the next process loads every kernel.
    again = _run(RECORD + BATCH + COMPILED, cache)
    assert again.stdout == expected + "[]\n"


def test_a_cache_that_cannot_be_written_compiles_in_memory(filled_cache, tmp_path):
    """Files can be made in the cache directory, but nothing written to
    them, as on a full disk: the kernels are compiled in memory, with one
    warning."""
    _, expected = filled_cache
    result = _run(BATCH, tmp_path / "cache", limit_file_size=True)
    assert result.stdout == expected
    assert result.stderr.count(UNWRITABLE) == 1, result.stderr


def test_a_cache_on_a_full_disk(filled_cache, tmpfs):
    _, expected = filled_cache
    expected = expected.splitlines()[0] + "\n"  # the single point's answer
    disk = tmpfs(1 << 20)
    warm = disk / "warm"
    assert _run(SINGLE, warm).stdout == expected  # with room to keep the kernel
    disks.fill(disk)
    # A full disk still serves the kernels it holds, with no warning ...
    result = _run(RECORD + SINGLE + COMPILED, warm)
    assert result.stdout == expected + "[]\n"
    assert "Warning" not in result.stderr
    # ... and kernels it cannot hold are compiled in memory, with one warning.
    result = _run(SINGLE, disk / "cold")
    assert result.stdout == expected
    assert result.stderr.count(UNWRITABLE) == 1, result.stderr
    assert "No space left on device" in result.stderr


def test_without_numba_s_private_cache_kernels_compile_in_memory(monkeypatch):
    """Where Numba's dispatchers no longer hold their cache where
    ``_guard_numba_cache`` looks, kernels are compiled without a disk cache,
    with one warning, rather than with an unguarded one."""
    from proximity.runtime import cache as _cache

    assert not _cache._guard_numba_cache(object())
    monkeypatch.setattr(_cache, "CACHE", True)
    monkeypatch.setattr(_cache, "_guarded", True)
    monkeypatch.setattr(_cache, "_guard_numba_cache", lambda dispatcher: False)

    def twice(x):
        return 2 * x

    with pytest.warns(RuntimeWarning, match="cannot be guarded"):
        first = _cache.compiled(twice)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        second = _cache.compiled(twice, ("float64(float64)",))
    assert not caught  # warned once
    assert first(2.5) == second(2.5) == 5.0
    assert type(first._cache).__name__ == type(second._cache).__name__ == "NullCache"


def test_the_cache_stamp_covers_every_folder_of_the_package():
    """A kernel inlines helpers of other modules, which Numba does not watch: the stamp in every
    cached kernel's name hashes every source file of the package, in every folder, so that an
    edit anywhere compiles the kernels again rather than loading stale ones."""
    from pathlib import Path

    import proximity
    from proximity.runtime import jit

    package = Path(proximity.__file__).parent
    every = {str(p.relative_to(package)) for p in package.rglob("*.py") if "__pycache__" not in p.parts}
    stamped = {name for name, _ in jit.stamped_sources()}
    assert stamped == every
    assert {"__init__.py", "pair/descent.py", "point/triangle.py", "numerics/orient.py"} <= stamped
