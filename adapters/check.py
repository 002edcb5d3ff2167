"""Cross-check every installed backend against proximity on a generated scene.

Run ``python -m proximity.adapters.check`` for the default scene, or
``python -m proximity.adapters.check --help`` for the options.  The scene has groups
of well-conditioned triangles, disks and circles, and groups built to show
each library's known failure modes: degenerate and sub-millimetre
triangles, points on a triangle's face, points in a disk's plane.  The
libraries are asked in the caller's coordinates (the backends named
``<name>[raw]``); ``--frames rescaled`` asks them in the backends' frames of
each query's own instead, and ``--frames both`` asks each library both ways.
"""

import argparse
import sys
import time

import numpy as np

import proximity

from ._common import INSTALL_HINT
from .crosscheck import cross_check
from .registry import NAMES, available, get

#: ``--frames``: the values of ``rescale`` each library is asked with.
FRAMES = {"caller": (False,), "rescaled": (True,), "both": (False, True)}


def _rotation(rng, n):
    q, r = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    return q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]


def _good_triangles(rng, n, size):
    # An equilateral triangle, stretched by at most 2x, rotated and moved:
    # well-conditioned, with no sliver angles.
    base = np.array([[1.0, 0.0, 0.0], [-0.5, 0.75**0.5, 0.0], [-0.5, -(0.75**0.5), 0.0]])
    stretch = rng.uniform(0.5, 1.0, size=(n, 1, 3))
    tri = np.einsum("nij,nkj->nki", _rotation(rng, n), base * stretch)
    return tri * size[:, None, None] + rng.normal(size=(n, 1, 3)) * size[:, None, None]


def _around(rng, centers, size, spread=1.5):
    return centers + rng.normal(size=centers.shape) * spread * size[:, None]


def scene(n, seed=0):
    """The generated scene: a list of ``(label, shape, points)``.

    Parameters
    ----------
    n : int
        Rows per group: one point against each of ``n`` shapes.
    seed : int
        Seed of the random generator.
    """
    rng = np.random.default_rng(seed)
    groups = []

    ones = np.ones(n)
    tri = _good_triangles(rng, n, ones)
    groups.append(("triangles", proximity.Triangle(tri), _around(rng, tri.mean(axis=1), ones)))

    tiny = 10.0 ** rng.uniform(-4, -3, n)
    tri = _good_triangles(rng, n, tiny)
    groups.append(
        (
            "sub-millimetre triangles (1e-4 to 1e-3)",
            proximity.Triangle(tri),
            _around(rng, tri.mean(axis=1), tiny),
        )
    )

    tri = _good_triangles(rng, n, ones)
    weights = rng.dirichlet([1.0, 1.0, 1.0], size=n)
    groups.append(
        ("triangles, points on the face", proximity.Triangle(tri), np.einsum("ni,nij->nj", weights, tri))
    )

    # Degenerate triangles, exactly so: coordinates on a grid of 1/8, so that
    # a + d and a + 3 d are exactly collinear with a.
    a = np.round(rng.normal(size=(n, 3)) * 8) / 8
    d = np.round(rng.normal(size=(n, 3)) * 8) / 8 + 0.125
    # Rows 0, 3, ... are collinear, rows 1, 4, ... have two coincident
    # vertices, rows 2, 5, ... are a point.
    degenerate = np.stack([a, a, a], axis=1)
    degenerate[0::3, 1] += d[0::3]
    degenerate[0::3, 2] += 3 * d[0::3]
    degenerate[1::3, 2] += d[1::3]
    groups.append(("degenerate triangles", proximity.Triangle(degenerate), _around(rng, a, ones)))

    center, normal = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    radius = rng.uniform(0.2, 2.0, n)
    groups.append(("disks", proximity.Disk(center, normal, radius), _around(rng, center, radius)))

    disk = proximity.Disk(center, normal, radius)
    direction = rng.normal(size=(n, 3))
    unit_normal = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    direction -= np.sum(direction * unit_normal, axis=1, keepdims=True) * unit_normal
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    inside = center + direction * (rng.uniform(0.0, 0.95, n) * radius)[:, None]
    groups.append(("disks, points in the plane inside the rim", disk, inside))

    center, normal = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    radius = rng.uniform(0.2, 2.0, n)
    groups.append(("circles", proximity.Circle(center, normal, radius), _around(rng, center, radius)))
    return groups


def main(argv=None):
    """Run the cross-check on the generated scene and print one table per group."""
    parser = argparse.ArgumentParser(
        prog="python -m proximity.adapters.check", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed of the scene (default 0)")
    parser.add_argument("-n", type=int, default=40, help="rows per group of the scene (default 40)")
    parser.add_argument(
        "--tol",
        type=float,
        default=None,
        help="modelling tolerance of tessellated circles and disks, in length units "
        "(default 1e-3 of each radius)",
    )
    parser.add_argument(
        "--backend",
        action="append",
        choices=NAMES,
        default=None,
        help="backend to ask; repeat for several (default: every installed one)",
    )
    parser.add_argument(
        "--frames",
        choices=tuple(FRAMES),
        default="caller",
        help="where the libraries are asked: in the caller's coordinates (default; backends named "
        "<name>[raw]), in the backends' rescaled frames of each query's own, or both",
    )
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error("-n must be at least 1")

    names = available() if args.backend is None else list(dict.fromkeys(args.backend))
    if not names:
        print(f"no backend library is installed: {INSTALL_HINT}", file=sys.stderr)
        return 1

    start = time.perf_counter()
    backends = [get(name, rescale=rescale) for name in names for rescale in FRAMES[args.frames]]
    print(LEGEND)
    reports = []
    try:
        for label, shape, points in scene(args.n, args.seed):
            report = cross_check(shape, points, backends=backends, tol=args.tol, worst=1)
            reports.append(report)
            print(f"## {label}")
            print(report.table())
            print()
    finally:
        for backend in backends:
            backend.close()
    print("## verdict")
    for backend in backends:
        summaries = [s for r in reports for s in r.summaries if s.backend == backend.name]
        left_out = sum(x.backend == backend.name for r in reports for x in r.left_out)
        print(verdict(backend.name, summaries, left_out))
    print()
    print(
        f"{len(backends)} backends, seed {args.seed}, {args.n} rows per group, "
        f"{time.perf_counter() - start:.1f} s"
    )
    return 0


#: What the columns of the tables mean, printed before them.
LEGEND = """\
Each table compares every backend with proximity's most accurate method on one group of queries.
  model          what the backend built (tessellated disks and circles say K and the modelling bound)
  answered       rows with an answer; the others are counted under failures by reason
  max |dd|/S     largest |d_backend - d_proximity| over answered rows, relative to the query's scale S
  median |dd|/S  the median of the same
  max |dd|       largest absolute disagreement, in length units
  >tol           answered rows outside the tolerance the backend documents (0 is expected)
  failures       rows not answered, by reason (the Failure codes of docs/adapters.md)
"""


def verdict(name, summaries, left_out=0):
    """One line on a backend over every group: within its tolerance or not, what it left
    unanswered, and of how many groups it was left out (it could not be given their queries)."""
    rows = sum(s.rows for s in summaries)
    answered = sum(s.answered for s in summaries)
    beyond = sum(s.beyond_tolerance for s in summaries)
    failures = {}
    for s in summaries:
        for reason, count in s.failures.items():
            failures[reason] = failures.get(reason, 0) + count
    if beyond:
        head = f"{name}: OUTSIDE its documented tolerance on {beyond} of {answered} answered rows"
    else:
        head = f"{name}: within its documented tolerance on all {answered} answered rows"
    if failures:
        listed = ", ".join(f"{reason} {count}" for reason, count in sorted(failures.items()))
        line = f"{head}; {rows - answered} of {rows} rows not answered ({listed})"
    else:
        line = f"{head}; every one of {rows} rows answered"
    if left_out:
        line += f"; left out of {left_out} group{'s' if left_out > 1 else ''} (see each table)"
    return line


if __name__ == "__main__":
    sys.exit(main())
