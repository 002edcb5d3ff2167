"""Start-up never fails: read-only installs, and no writable cache at all."""

import os
import pathlib
import shutil
import subprocess
import sys

import proximity

QUERY = (
    "import warnings, numpy as np, proximity; "
    "print(float(proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).distance([0.25, 0.25, 2.0])))"
)


def _run(tmp_path, cache_home):
    """Run a query with a copy of the package whose own cache directory cannot be made."""
    package = tmp_path / "site" / "proximity"
    shutil.copytree(
        pathlib.Path(proximity.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__")
    )
    # A file where each folder's cache directory would go: even root cannot make them, as
    # in a read-only install.
    for folder in [package, *(d for d in package.rglob("*") if d.is_dir())]:
        (folder / "__pycache__").write_text("")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(tmp_path / "site"), XDG_CACHE_HOME=str(cache_home), HOME=str(cache_home))
    return subprocess.run(
        [sys.executable, "-c", QUERY], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600
    )


def test_read_only_package_uses_the_user_cache(tmp_path):
    cache_home = tmp_path / "home"
    result = _run(tmp_path, cache_home)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "2.0"
    assert "RuntimeWarning" not in result.stderr
    assert any(p.suffix == ".nbi" for p in cache_home.rglob("*")), "nothing cached in the user cache"


def test_no_writable_cache_warns_and_still_answers(tmp_path):
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("")
    result = _run(tmp_path, blocker / "home")  # under a file: cannot be created
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "2.0"
    assert "no writable cache directory" in result.stderr


# Eight threads of a new process make their first queries at once: single
# points and batches, on a triangle and a disk.  The first query loads Numba,
# so they race to load it.
FIRST_QUERIES = """
import sys, threading
import numpy as np
import proximity

shapes = [
    proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
    proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1),
]
points = np.random.default_rng(0).normal(size=(2000, 3))
barrier = threading.Barrier(8)
answers, errors = {}, []

def first_query(i):
    shape, batch = shapes[i % 2], i % 4 >= 2
    barrier.wait()
    try:
        answers[i] = shape.distance(points if batch else points[0])
    except Exception as error:
        errors.append(f"thread {i}: {type(error).__name__}: {error}")

threads = [threading.Thread(target=first_query, args=(i,)) for i in range(8)]
for t in threads:
    t.start()
for t in threads:
    t.join()
try:  # and the process still answers
    answers["after"] = shapes[0].distance(points)
except Exception as error:
    errors.append(f"after: {type(error).__name__}: {error}")
if errors:
    sys.exit("\\n".join(errors))
np.save(sys.stdout.buffer, np.concatenate([np.ravel(answers[k]) for k in [*range(8), "after"]]))
"""


def test_first_queries_from_threads_at_once(tmp_path):
    import io

    import numpy as np

    points = np.random.default_rng(0).normal(size=(2000, 3))
    shapes = [
        proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
        proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1),
    ]
    # Also compiles the kernels into the cache the new processes load them from.
    expected = np.concatenate(
        [np.ravel(shapes[i % 2].distance(points if i % 4 >= 2 else points[0])) for i in range(8)]
        + [shapes[0].distance(points)]
    )
    # The race is lost in a fraction of processes (about half on two cores
    # before the fix, fewer on more): 24 processes, two at a time.
    failures = []
    for _ in range(12):
        runs = [
            subprocess.Popen(
                [sys.executable, "-c", FIRST_QUERIES], stdout=subprocess.PIPE, stderr=subprocess.PIPE
            )
            for _ in range(2)
        ]
        for run in runs:
            out, err = run.communicate(timeout=600)
            if run.returncode != 0:
                failures.append(err.decode().strip().splitlines()[-1])
            else:
                np.testing.assert_array_equal(np.load(io.BytesIO(out)), expected)
    assert not failures, f"{len(failures)} of 24 processes failed; the first: {failures[0]}"


# --- The line a cold first query prints ---------------------------------------------------------

# The cheapest first query: one point against one point (about a second of
# compiling, most of it the compiler's own start).
FIRST_POINT = "import proximity; print(float(proximity.Point([0, 0, 0]).distance([3.0, 4.0, 0.0])))"


def _first_point(cache, **env):
    environ = {k: v for k, v in os.environ.items() if k != "PROXIMITY_QUIET"}
    environ.update(NUMBA_CACHE_DIR=str(cache), **env)
    return subprocess.run(
        [sys.executable, "-c", FIRST_POINT], capture_output=True, text=True, env=environ, timeout=600
    )


def test_a_cold_compile_says_so_once_and_a_warm_run_says_nothing(tmp_path):
    cold = _first_point(tmp_path / "cache")
    assert cold.returncode == 0, cold.stderr
    assert cold.stdout.strip() == "5.0"
    lines = cold.stderr.splitlines()
    assert len(lines) == 1, cold.stderr
    assert lines[0].startswith("proximity: compiling the robust kernels of one-point queries")
    assert "python -m proximity.compile" in lines[0] and "PROXIMITY_QUIET=1" in lines[0]
    warm = _first_point(tmp_path / "cache")
    assert warm.returncode == 0, warm.stderr
    assert warm.stdout.strip() == "5.0"
    assert warm.stderr == ""


def test_the_compile_line_is_printed_once_and_can_be_silenced(monkeypatch, capsys):
    from proximity.runtime import notice as _notice

    def _robust_block__robust__e1b9(): ...

    _robust_block__robust__e1b9.__module__ = "proximity.point.triangle"
    monkeypatch.setattr(_notice, "_said", set())
    monkeypatch.setenv("PROXIMITY_QUIET", "0")
    _notice.compiling(_robust_block__robust__e1b9)
    _notice.compiling(_robust_block__robust__e1b9)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the robust kernels of batch queries" in err
    monkeypatch.setattr(_notice, "_said", set())
    monkeypatch.setenv("PROXIMITY_QUIET", "1")
    _notice.compiling(_robust_block__robust__e1b9)
    assert capsys.readouterr().err == ""


def test_each_kind_of_first_use_says_so_once(monkeypatch, capsys):
    """A process that compiles a one-point query, then a mesh's search, then a pair query is
    told about each, once, in one wording."""
    from proximity.runtime import notice as _notice

    def kernel(module, name):
        def f(): ...

        f.__module__, f.__qualname__ = module, name
        return f

    monkeypatch.setattr(_notice, "_said", set())
    monkeypatch.setenv("PROXIMITY_QUIET", "0")
    firsts = [kernel("proximity.point.point", "_single__robust__e1b9"),
              kernel("proximity.broadphase.traverse", "_loop__robust__e1b9"),
              kernel("proximity.pair.descent", "_descend__robust__e1b9")]  # fmt: skip
    for f in firsts + firsts:
        _notice.compiling(f)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 3, lines
    for line, what in zip(lines, ("one-point queries", "meshes and scenes", "pair queries"), strict=True):
        assert line.startswith(f"proximity: compiling the robust kernels of {what}"), line
        assert line.endswith("set PROXIMITY_QUIET=1 to hide this line."), line


def test_the_compile_line_names_the_hierarchy_for_meshes():
    from proximity.broadphase import build
    from proximity.runtime import notice as _notice

    what, seconds = _notice.describe(build.build_tree)
    assert what.startswith("kernels of meshes and scenes") and seconds


def test_the_compile_line_names_the_predicates_for_normals_at_a_face():
    from proximity.numerics import orient as _orient
    from proximity.runtime import notice as _notice

    what, seconds = _notice.describe(_orient.plane_sides)
    assert what.startswith("kernels of exact orientation predicates (of normals at a face") and seconds
