"""A quick run of every path of every shape, to compare two installs bit for bit.

    python -m proximity.testing.smoke OUT.npz [--compare REFERENCE.npz]

Answers every method of every kind of primitive (one point, pairs, many
points against one shape), a mesh (hierarchy and brute force, signed
distances) and a scene of every kind, saves every output array, and with
``--compare`` exits 1 unless each is bit for bit the reference's.  ``make
numba-floor`` runs it under the oldest Numba that ``pyproject.toml``
accepts and compares with the pinned one.
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


def answers(methods=None):
    """Every output array of the run, by name; ``methods`` limits the methods run."""
    rng = np.random.default_rng(0)
    out = {}
    shapes = []
    for kind, dim in examples.kinds():
        batch = examples.example(kind, (60,), dim)
        one = examples.example(kind, (), dim)
        if dim == 3:
            shapes.append(batch)
        points = rng.normal(size=(60, dim)) * 2
        points[3] = np.nan
        for method in methods or batch.methods:
            key = f"{kind}{dim}.{method}"
            _put(out, f"{key}.pairs", batch.closest_point(points, method=method))
            _put(out, f"{key}.pairs.distance", batch.distance(points, method=method))
            _put(out, f"{key}.one", one.closest_point(points, method=method))
            _put(out, f"{key}.single", one.closest_point(points[0], method=method))
    vertices, faces = icosphere(2)
    points = rng.normal(size=(3000, 3))
    for broad_phase in ("bvh", "brute"):
        mesh = proximity.TriangleMesh(vertices, faces, broad_phase=broad_phase)
        for method in methods or mesh.methods:
            _put(out, f"mesh.{broad_phase}.{method}", mesh.closest_point(points, method=method))
        _put(out, f"mesh.{broad_phase}.signed", mesh.signed_distance(points))
    scene = proximity.Scene([proximity.TriangleMesh(vertices, faces), *shapes])
    for method in methods or scene.methods:
        _put(out, f"scene.{method}", scene.closest_point(points, method=method))
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


def main(argv=None):
    """Run the smoke test; returns its exit status (1 where arrays differ)."""
    parser = argparse.ArgumentParser(
        prog="python -m proximity.testing.smoke", description=__doc__.split("\n")[0]
    )
    parser.add_argument("out", help="where to save the answers (.npz)")
    parser.add_argument("--compare", help="answers to compare with (.npz)")
    parser.add_argument("--method", action="append", help="run only this method (repeatable)")
    args = parser.parse_args(argv)
    out = answers(args.method)
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
