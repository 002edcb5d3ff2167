"""A quick run of every path of every shape, to compare two installs bit for bit.

    python -m proximity.testing.smoke OUT.npz [--compare REFERENCE.npz] [--jobs N]

Answers every method of every kind of primitive (one point, pairs, many
points against one shape), a mesh (hierarchy and brute force, signed
distances) and a scene of every kind, saves every output array, and with
``--compare`` exits 1 unless each is bit for bit the reference's.  ``make
numba-floor`` runs it under the oldest Numba that ``pyproject.toml``
accepts and compares with the pinned one, on two processes (``--jobs 2``).
"""

import argparse
import sys

import numba
import numpy as np

import proximity

from ..results import asdict
from . import examples
from .meshes import icosphere


def _put(out, key, value):
    if isinstance(value, np.ndarray) or np.isscalar(value):
        out[key] = np.asarray(value)
        return
    for name, field in asdict(value).items():
        out[f"{key}.{name}"] = np.asarray(field)


def _tasks(methods=None):
    """The run as tasks, ``task(out)`` putting that part's arrays in ``out``: one per kind,
    dimension and method (each with points of its own seed), per broad phase and method,
    per broad phase's signed distances and per method of the scene."""
    tasks = []
    shapes = []
    for kind, dim in examples.kinds():
        batch = examples.example(kind, (60,), dim)
        one = examples.example(kind, (), dim)
        if dim == 3:
            shapes.append(batch)
        for method in methods or batch.methods:
            seed = len(tasks)

            def task(out, kind=kind, dim=dim, batch=batch, one=one, method=method, seed=seed):
                points = np.random.default_rng(seed).normal(size=(60, dim)) * 2
                points[3] = np.nan
                key = f"{kind}{dim}.{method}"
                _put(out, f"{key}.pairs", batch.closest_point(points, method=method))
                _put(out, f"{key}.pairs.distance", batch.distance(points, method=method))
                _put(out, f"{key}.one", one.closest_point(points, method=method))
                _put(out, f"{key}.single", one.closest_point(points[0], method=method))

            tasks.append(task)
    vertices, faces = icosphere(2)
    points = np.random.default_rng(len(tasks)).normal(size=(3000, 3))

    for broad_phase in ("bvh", "brute"):
        mesh = proximity.TriangleMesh(vertices, faces, broad_phase=broad_phase)
        for method in methods or mesh.methods:

            def task(out, mesh=mesh, method=method, key=f"mesh.{broad_phase}.{method}"):
                _put(out, key, mesh.closest_point(points, method=method))

            tasks.append(task)

        def signed(out, mesh=mesh, key=f"mesh.{broad_phase}.signed"):
            _put(out, key, mesh.signed_distance(points))

        tasks.append(signed)
    scene = proximity.Scene([proximity.TriangleMesh(vertices, faces), *shapes])
    for method in methods or scene.methods:

        def task(out, method=method):
            _put(out, f"scene.{method}", scene.closest_point(points, method=method))

        tasks.append(task)
    return tasks


def answers(methods=None, part=0, parts=1):
    """Every output array of the run, by name; ``methods`` limits the methods run, and
    ``part`` of ``parts`` keeps every ``parts``-th task from the ``part``-th (see
    :func:`_tasks`), for a run split over processes."""
    out = {}
    for task in _tasks(methods)[part::parts]:
        task(out)
    return out


def compare(out, reference):
    """Names of the arrays of ``out`` that are not bit for bit those of ``reference``."""
    names = sorted(set(out) | set(reference))
    return [
        name
        for name in names
        if name not in out
        or name not in reference
        or out[name].dtype != reference[name].dtype
        or out[name].shape != reference[name].shape
        or out[name].tobytes() != reference[name].tobytes()
    ]


def _split(args):
    """The answers of a run split over ``args.jobs`` processes (this interpreter, its
    environment), merged."""
    import os
    import subprocess
    import tempfile

    extra = [f"--method={method}" for method in args.method or ()]
    out = {}
    with tempfile.TemporaryDirectory() as folder:
        paths = [os.path.join(folder, f"part{k}.npz") for k in range(args.jobs)]
        runs = [
            subprocess.Popen(
                [sys.executable, "-m", "proximity.testing.smoke", path, f"--part={k}/{args.jobs}", *extra]
            )
            for k, path in enumerate(paths)
        ]
        failed = [k for k, run in enumerate(runs) if run.wait() != 0]
        if failed:
            raise SystemExit(f"error: the smoke test's parts {failed} failed")
        for path in paths:
            with np.load(path) as answers_of_part:
                out.update(answers_of_part)
    return out


def main(argv=None):
    """Run the smoke test; returns its exit status (1 where arrays differ)."""
    parser = argparse.ArgumentParser(
        prog="python -m proximity.testing.smoke", description=__doc__.split("\n")[0]
    )
    parser.add_argument("out", help="where to save the answers (.npz)")
    parser.add_argument("--compare", help="answers to compare with (.npz)")
    parser.add_argument("--method", action="append", help="run only this method (repeatable)")
    parser.add_argument(
        "--jobs", type=int, default=1, help="split the run over this many processes (default 1)"
    )
    parser.add_argument("--part", help=argparse.SUPPRESS)  # K/N: one process's share of a split run
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error(f"--jobs must be at least 1; got {args.jobs}")
    if args.part is not None:
        part, parts = (int(n) for n in args.part.split("/"))
        np.savez(args.out, **answers(args.method, part, parts))
        return 0
    out = _split(args) if args.jobs > 1 else answers(args.method)
    np.savez(args.out, **out)
    from ..runtime import jit

    calls = "through their addresses" if jit.BY_ADDRESS else f"directly ({jit.ADDRESS_ERROR!r:.120})"
    print(f"numba {numba.__version__}, numpy {np.__version__}: {len(out)} arrays; blocks called {calls}")
    if args.compare:
        reference = dict(np.load(args.compare))
        differ = compare(out, reference)
        if differ:
            print(f"error: {len(differ)} of {len(reference)} arrays differ: {differ[:10]}", file=sys.stderr)
            return 1
        print(f"every array is bit for bit that of {args.compare}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
