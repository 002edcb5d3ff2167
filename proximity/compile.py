"""Compile every kernel ahead of time: ``python -m proximity.compile``.

A query compiles the kernels it uses at its first call and keeps them in
the disk cache (see :mod:`proximity.runtime.cache`).  Containers and CI images that
should answer their first query at once run this command after installing,
where the cache is writable, to compile every method of every shape and
path.  It prints each kernel as it is done.

Without it, the first query of a process that finds a kernel missing from
the cache prints one line on stderr saying what it compiles and roughly how
long that takes; ``PROXIMITY_QUIET=1`` in the environment silences it (see
:mod:`proximity.runtime.notice`).  The pair queries are compiled for the
pairs people ask most (single and batched segments, triangles and capsules;
meshes against meshes, posed meshes, segments, capsules, triangles and
points); other combinations of kinds in scenes compile at their first use.

Examples
--------
>>> import proximity.compile
>>> done = proximity.compile.compile_all(methods=["robust"], log=None)
>>> [name for name in done if name.startswith("disk")]  # doctest: +NORMALIZE_WHITESPACE
['disk and circle: robust, one point', 'disk and circle: robust, pairs',
 'disk and circle: robust, many points against one shape']
"""

import argparse
import sys
import time

import numpy as np

from . import methods as _methods
from . import primitives
from .pair import table as _pair_table


def _kernel_modules():
    """``(names, module)`` of every primitive kernel module, with the names of its kinds."""
    modules = {}
    for p in primitives.BY_CODE:
        modules.setdefault(p.module, []).append(p.name)
    return [(" and ".join(names), primitives.REGISTRY[names[0]].kernels) for names in modules.values()]


def _jobs(method):
    """``(description, function)`` for each kernel of ``method``."""
    from .broadphase.traverse import search_kernel
    from .runtime import batch
    from .runtime.loops import single_entry

    m = _methods.resolve(method)
    name = m.name
    jobs = []
    for kinds, module in _kernel_modules():
        if name not in module.KERNELS:
            continue
        jobs += [
            (f"{kinds}: {name}, one point", lambda module=module: single_entry(module.single_kernel(m))),
            (f"{kinds}: {name}, pairs",
             lambda module=module: batch.batch_kernel(module.LAYOUT, module.block(m, False))),
            (f"{kinds}: {name}, many points against one shape",
             lambda module=module: batch.batch_kernel(module.LAYOUT, module.block(m, True))),
        ]  # fmt: skip
    for p in primitives.offering(m):
        jobs.append((f"collection of {p.name}s: {name}", lambda p=p: search_kernel(m, (p,))))
    if primitives.TRIANGLE in primitives.offering(m):  # a mesh's tree reads its faces through their vertices
        jobs.append((f"mesh: {name}", lambda: search_kernel(m, (primitives.TRIANGLE,), -1, True)))
    jobs.append((f"collection of several kinds: {name}", lambda: search_kernel(m, primitives.offering(m))))
    return jobs


def _broad_phase():
    """The hierarchy's build, refits, candidate search and the visiting order of large batches,
    on a small mesh."""
    from .broadphase import _alloc, build, refit, traverse
    from .broadphase.nearest import _morton_order

    rng = np.random.default_rng(0)
    width = primitives.N_PARAMS
    kinds = np.zeros(8, np.int8)
    params = np.concatenate([rng.random((8, 9)), np.zeros((8, width - 9))], axis=1)
    tree = build.build_tree(kinds, params)
    # The allocation and gathers of large meshes, with the argument types they are given.
    _alloc._empty(1, 1)
    readonly = _alloc.readonly
    _alloc._take_rows(readonly(params, np.float64), readonly([1, 0], np.int64), np.empty((2, width)))
    # Enough faces for a tree of more than one leaf, which the refit fits.
    vertices = readonly(params[:, :3], np.float64)
    faces = readonly([[k, (k + 1) % 8, (k + 3) % 8] for k in range(8)], np.int64)
    refit.refit_indexed(vertices, build.build_faces(vertices, faces, 0))
    # And a tree of one leaf, whose rows are gathered alone.
    built = build.build_faces(vertices, faces[:2], 0)
    refit.refit_faces(vertices, faces[:2], built.index, built.child, built.count, built.kinds)
    points = readonly(rng.random((2, 3)), np.float64)
    _morton_order(points)
    bounds, cull, magnitude = tree.boxes(False)
    out = np.empty(len(kinds), np.int64)
    traverse._gather(cull, bounds, tree.child, tree.count, tree.depth, magnitude, points[0], 1.0, out)


def _winding():
    """The signs of the signed distance: the winding number's hierarchy, series and ray
    crossings, and the validity check (its predicates and pair tests)."""
    from .shapes.mesh import TriangleMesh

    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    tetrahedron = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], faces)
    tetrahedron.signed_distance(np.zeros((1, 3)) + 0.1)
    tetrahedron.signed_distance(np.zeros((1, 3)) + 0.1, sign="winding")
    TriangleMesh(tetrahedron.vertices, faces[1:]).winding_number(np.zeros((1, 3)) + 0.1)


def _round_frames():
    """The unit normals and checks of large batches of circles and disks."""
    from .point import disk

    one = np.ones((1, 3))
    one.flags.writeable = False  # as the shapes' arrays are
    disk.round_frames(one, one, one[0, :1], np.empty((1, 3)))


def _sides():
    """The exact sides of points on a face's plane, which the normals there take."""
    from .numerics.normals import plane_sides

    params = np.zeros((2, primitives.N_PARAMS))
    params[0, 3], params[0, 7] = 1.0, 1.0  # the triangle (0, 0, 0), (1, 0, 0), (0, 1, 0)
    params[1, 5] = params[1, 8] = params[1, 9] = 1.0  # the unit disk of the z = 0 plane
    plane_sides(np.array([0, 1], np.int8), params, np.array([[0.25, 0.25, 0.0], [0.5, 0.0, 0.0]]))


def _pairs(method):
    """The pair queries of ``method``: single pairs (rounded too), batches of each pair of kinds,
    and the descents of meshes against meshes (posed or not), segments, capsules, triangles and
    points."""
    from .pair import queries
    from .shapes.base import Point, Segment, Triangle
    from .shapes.mesh import TriangleMesh
    from .shapes.rounded import Capsule
    from .testing.meshes import icosphere

    mesh = TriangleMesh(*icosphere(1))
    lifted = np.eye(4)
    lifted[:3, 3] = [0.0, 0.0, 3.0]
    segment = Segment([[0.0, 0.0, 2.0], [1.0, 0.0, 3.0]])
    triangle = Triangle([[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.5]])
    segments = Segment(np.stack([segment.vertices] * 2))
    triangles = Triangle(np.stack([triangle.vertices] * 2))
    capsule = Capsule(segment.vertices, 0.1)
    pairs = [(segment, segment), (segment, triangle), (triangle, triangle), (capsule, capsule),
             (segments, segments), (segments, triangles), (triangles, triangles),
             (mesh, mesh), (mesh, mesh.transformed(lifted)), (segment, mesh), (segments, mesh),
             (capsule, mesh), (triangle, mesh), (Point([0.0, 0.0, 2.0]), mesh)]  # fmt: skip
    for a, b in pairs:
        queries.closest_points(a, b, method=method)
        queries.distance(a, b, method=method)


def compile_all(methods=None, log=sys.stdout):
    """Compile the kernels of ``methods`` (default: every method) and of the broad phase.

    Parameters
    ----------
    methods : sequence of str, optional
        Method names; all of :data:`proximity.methods.REGISTRY` by default.
    log : file, optional
        Where a line per kernel is printed; None for silence.

    Returns
    -------
    dict of str to float
        Seconds spent on each kernel (near zero where it was cached).
    """
    names = list(_methods.REGISTRY) if methods is None else list(methods)
    jobs = [job for name in names for job in _jobs(name)]
    for name in names:
        if all(name in p.methods for p in _pair_table.REGISTRY.values()):
            jobs.append((f"pair queries: {name}", lambda name=name: _pairs(name)))
    jobs.append(("mesh and scene: hierarchy build and search", _broad_phase))
    jobs.append(("mesh: the signs of the signed distance", _winding))
    jobs.append(("circles and disks: unit normals of large batches", _round_frames))
    jobs.append(("normals: the exact sides of points on a face's plane", _sides))
    done = {}
    for k, (description, job) in enumerate(jobs, 1):
        start = time.perf_counter()
        job()
        done[description] = time.perf_counter() - start
        if log is not None:
            print(f"[{k:2d}/{len(jobs)}] {description}: {done[description]:.1f} s", file=log, flush=True)
    return done


def parser():
    """The command's argument parser."""
    parser = argparse.ArgumentParser(
        prog="python -m proximity.compile",
        description="Compile proximity's kernels into the disk cache, so that first queries start at once.",
    )
    parser.add_argument(
        "--method",
        action="append",
        choices=list(_methods.REGISTRY),
        help="compile only this method (repeatable); default: every method",
    )
    return parser


def main(argv=None):
    """Run ``python -m proximity.compile``; returns its exit status."""
    args = parser().parse_args(argv)
    from .runtime import cache

    if not cache.CACHE:
        print("no writable cache directory: compiled kernels cannot be kept", file=sys.stderr)
        return 1
    start = time.perf_counter()
    compile_all(args.method)
    print(f"done in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
