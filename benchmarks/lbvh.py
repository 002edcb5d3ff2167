"""The build's topology: binned SAH (the package's) against a Morton-code LBVH.

    python -m benchmarks.lbvh [--quick] [--rounds N] [--out FILE]

The LBVH (:func:`lbvh`) sorts the faces' box centres by their 30-bit Morton
codes (10 bits an axis, on the grid of the centres' bounds; a radix sort of
three passes of 10 bits) and splits each range of the sorted order at the
highest bit in which its first and last codes differ (a range of equal
codes in half), until a node holds at most ``leaf_size`` faces: the radix
tree of Karras (2012) with its subtrees of at most ``leaf_size`` leaves
collapsed, built top down on one thread.  Nodes are numbered as the
package's hierarchy requires (``broadphase/build.py``): a node's two
children adjacent and after it, the left child's subtree in one block
after the pair.  The nodes' bounds are then fitted exactly as for the SAH
tree, so the answers are the same bits; the search's speed alone depends
on the topology.

Each mesh is built twice, with ``proximity.broadphase.build._build``
replaced by :func:`lbvh` for the second, and measured on one thread,
alternately, in process CPU time: the topology step alone (on copies of
the same cull rows) and the whole ``TriangleMesh(V, F)``, the least of
``--rounds``; ``distance`` of 20,000 points near the surface and 20,000 in
1.5 times the bounding box, median and range of ``--rounds`` calls.  Every
distance, point and face of ``closest_point`` is checked equal between the
two trees.  Also printed: the nodes a face, the deepest leaf and the SAH
cost of each tree (node areas over the root's, inner nodes at 1, faces
at 1).  ``docs/performance.md`` ("The build: binned SAH against LBVH") has
the results.
"""

import argparse
import json
import time

import numba
import numpy as np

import proximity
from proximity.broadphase import build
from proximity.testing.meshes import near_points, peer_mesh

MESHES = (
    ("icosphere 20,480", ("icosphere", 5)),
    ("torus 20,000", ("torus", (100, 100))),
    ("icosphere 1,310,720", ("icosphere", 8)),
    ("torus 1,000,000", ("torus", (1000, 500))),
)
BITS = 10
POINTS = 20_000


@numba.njit(nogil=True)
def _spread_bits(x):
    # The 10 bits of x two bits apart: bit b to bit 3 b.
    x = (x | (x << np.uint64(16))) & np.uint64(0x030000FF)
    x = (x | (x << np.uint64(8))) & np.uint64(0x0300F00F)
    x = (x | (x << np.uint64(4))) & np.uint64(0x030C30C3)
    return (x | (x << np.uint64(2))) & np.uint64(0x09249249)


@numba.njit(nogil=True)
def morton_codes(rows):
    """The 30-bit Morton code of each box's centre (``rows[:, 0:6]``) on a
    grid of ``2**10`` cells an axis over the centres' bounds."""
    n = rows.shape[0]
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for j in range(n):
        for a in range(3):
            c = rows[j, a] * 0.5 + rows[j, 3 + a] * 0.5
            lo[a] = min(lo[a], c)
            hi[a] = max(hi[a], c)
    scale = np.empty(3)
    for a in range(3):
        scale[a] = (1 << BITS) / (hi[a] - lo[a]) if hi[a] > lo[a] else 0.0
    codes = np.empty(n, np.uint64)
    top = (1 << BITS) - 1
    for j in range(n):
        code = np.uint64(0)
        for a in range(3):
            c = rows[j, a] * 0.5 + rows[j, 3 + a] * 0.5
            cell = min(int((c - lo[a]) * scale[a]), top)
            code |= _spread_bits(np.uint64(cell)) << np.uint64(2 - a)
        codes[j] = code
    return codes


@numba.njit(nogil=True)
def radix_order(codes):
    """The stable order of the 30-bit ``codes``: three passes of 10 bits.
    Returns ``(order, sorted codes)``."""
    n = codes.shape[0]
    order = np.arange(n)
    keys = codes.copy()
    order2 = np.empty(n, np.int64)
    keys2 = np.empty(n, np.uint64)
    counts = np.empty(1 << BITS, np.int64)
    mask = np.uint64((1 << BITS) - 1)
    for shift in range(0, 3 * BITS, BITS):
        counts[:] = 0
        for j in range(n):
            counts[(keys[j] >> np.uint64(shift)) & mask] += 1
        total = 0
        for d in range(1 << BITS):
            c = counts[d]
            counts[d] = total
            total += c
        for j in range(n):
            d = (keys[j] >> np.uint64(shift)) & mask
            k = counts[d]
            counts[d] = k + 1
            keys2[k] = keys[j]
            order2[k] = order[j]
        keys, keys2 = keys2, keys
        order, order2 = order2, order
    return order, keys


@numba.njit(nogil=True)
def _split_point(codes, s, e):
    """Where the sorted ``codes[s:e]`` change at the highest bit in which
    ``codes[s]`` and ``codes[e - 1]`` differ; the middle if they are equal."""
    x = codes[s] ^ codes[e - 1]
    if x == 0:
        return (s + e) // 2
    bit = np.uint64(1) << np.uint64(63 - _leading_zeros(x))
    lo, hi = s + 1, e - 1  # codes[hi] has the bit, codes[s] has not
    while lo < hi:
        m = (lo + hi) // 2
        if codes[m] & bit:
            hi = m
        else:
            lo = m + 1
    return lo


@numba.njit(nogil=True)
def _leading_zeros(x):
    n = 0
    while not x & (np.uint64(1) << np.uint64(63 - n)):
        n += 1
    return n


@numba.njit(nogil=True)
def radix_tree(codes, leaf_size):
    """``(child, count, depth)`` of the radix tree over the sorted ``codes``,
    leaves of at most ``leaf_size``, numbered depth first by pairs."""
    n = codes.shape[0]
    child = np.empty(2 * n - 1, np.int64)
    count = np.empty(2 * n - 1, np.int64)
    stack = np.empty((128, 4), np.int64)
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = 0, 0, n, 0
    top = 1
    nodes = 1
    deepest = 0
    while top > 0:
        top -= 1
        i, s, e, d = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
        if e - s <= leaf_size:
            child[i] = s
            count[i] = e - s
            deepest = max(deepest, d)
            continue
        m = _split_point(codes, s, e)
        child[i] = nodes
        count[i] = 0
        # The right child below the left one on the stack: the left one's
        # subtree is numbered first, in one block after the pair.
        stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = nodes + 1, m, e, d + 1
        stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2], stack[top + 1, 3] = nodes, s, m, d + 1
        top += 2
        nodes += 2
    return child[:nodes].copy(), count[:nodes].copy(), deepest


@numba.njit(nogil=True)
def _permute_rows(rows, order):
    """``rows[:] = rows[order]`` in place, cycle by cycle: no copy of the rows
    (whose pages, fresh, cost more than the moves)."""
    done = np.zeros(order.shape[0], np.bool_)
    held = np.empty(rows.shape[1])
    for start in range(order.shape[0]):
        if done[start]:
            continue
        held[:] = rows[start]
        j = start
        while True:
            done[j] = True
            k = order[j]
            if k == start:
                rows[j] = held
                break
            rows[j] = rows[k]
            j = k


def lbvh(rows, leaf_size, permute=True):
    """``build._build`` by LBVH: ``(child, count, order, depth)``, the rows put
    in leaf order in place unless not ``permute`` (``build_faces`` reads only
    ``order`` of a tree of more than one node)."""
    order, codes = radix_order(morton_codes(rows))
    child, count, depth = radix_tree(codes, np.int64(leaf_size))
    if permute:
        _permute_rows(rows, order)
    return child, count, order, int(depth)


def lbvh_faces(rows, leaf_size):
    """:func:`lbvh` as ``build_faces`` needs it: the rows left in their order."""
    return lbvh(rows, leaf_size, permute=False)


def sah_cost(tree):
    """The SAH cost of a tree over its fitted boxes: the areas of the inner
    nodes, plus those of the leaves times their faces, over the root's."""
    box = tree.bounds[:, :6]
    d = np.maximum(box[:, 3:] - box[:, :3], 0.0)
    area = d[:, 0] * d[:, 1] + d[:, 1] * d[:, 2] + d[:, 2] * d[:, 0]
    weight = np.where(tree.count > 0, tree.count, 1)
    return float(np.sum(area * weight) / area[0])


def face_rows(V, F):
    """The cull rows ``build_faces`` hands to ``_build``."""
    V, F = np.ascontiguousarray(V, np.float64), np.ascontiguousarray(F, np.int64)
    n = len(F)
    cull = np.empty((n, build.CULL_COLUMNS))
    hashes = np.empty(n, np.uint64)
    build._faces(
        build._FACE_ROWS,
        V,
        F,
        build._NO_ORDER,
        np.int64(proximity.primitives.TRIANGLE.code),
        cull,
        hashes,
        build._NO_PARAMS,
        n,
    )
    return cull


def cpu(f, *args):
    t = time.process_time()
    out = f(*args)
    return time.process_time() - t, out


def measure(name, spec, rounds):
    V, F = peer_mesh(*spec)
    rng = np.random.default_rng(0)
    near = near_points(rng, V, F, POINTS, 0.01 * np.ptp(V, axis=0).max())
    lo, hi = V.min(0), V.max(0)
    points = {"near": near, "box": (lo + hi) / 2 + (rng.random((POINTS, 3)) - 0.5) * 1.5 * (hi - lo)}
    sah = build._build
    builds = {"sah": sah, "lbvh": lbvh_faces}
    topology = {"sah": sah, "lbvh": lbvh, "lbvh_faces": lbvh_faces}
    rows = face_rows(V, F)
    leaf = build.default_leaf_size(len(F))
    res = {k: {"topology": [], "whole": [], "near": [], "box": []} for k in builds}
    res["lbvh"]["topology_unpermuted"] = []
    meshes = {}
    try:
        with proximity.threads(1):
            for k, f in builds.items():
                build._build = f
                meshes[k] = proximity.TriangleMesh(V, F)  # and the compiles
            for _ in range(rounds):
                for k, f in topology.items():
                    key = "topology_unpermuted" if k == "lbvh_faces" else "topology"
                    res[k.split("_")[0]][key].append(cpu(f, rows.copy(), leaf)[0])
                for k, f in builds.items():
                    build._build = f
                    res[k]["whole"].append(cpu(proximity.TriangleMesh, V, F)[0])
            build._build = sah
            same = True
            for P in points.values():
                a, b = meshes["sah"].closest_point(P), meshes["lbvh"].closest_point(P)
                same &= all(
                    np.array_equal(getattr(a, f), getattr(b, f)) for f in ("distance", "point", "face")
                )
            for _ in range(rounds):
                for k, m in meshes.items():
                    for s, P in points.items():
                        res[k][s].append(cpu(m.distance, P)[0])
    finally:
        build._build = sah
    out = {"mesh": name, "faces": len(F), "leaf_size": leaf, "same": bool(same)}
    for k, m in meshes.items():
        tree = m._tree
        # build_faces read the order alone: a tree of more than one node, fitted to the faces' vertices.
        assert len(tree.child) > 1 and tree.faces is not None
        out[k] = {
            "nodes_per_face": len(tree.child) / len(F),
            "depth": tree.depth,
            "sah_cost": sah_cost(tree),
            **{key: [x * 1e3 for x in v] for key, v in res[k].items()},
        }
    return out


def line(r, points=("near", "box")):
    cells = [r["mesh"], "same" if r["same"] else "DIFFERENT"]
    for k in ("sah", "lbvh"):
        x = r[k]
        cells.append(
            f"{k}: {x['nodes_per_face']:.3f} n/f, depth {x['depth']}, cost {x['sah_cost']:.0f}; "
            f"topology {min(x['topology']):.1f}"
            + (f" ({min(x['topology_unpermuted']):.1f} unpermuted)" if "topology_unpermuted" in x else "")
            + f", whole {min(x['whole']):.1f} ms; "
            + ", ".join(f"{s} {np.median(x[s]):.1f} ({min(x[s]):.1f}-{max(x[s]):.1f})" for s in points)
        )
    return " | ".join(cells)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the 20k-face meshes alone")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--out", default=None, help="a JSON file of every timing")
    args = parser.parse_args()
    results = []
    for name, spec in MESHES[:2] if args.quick else MESHES:
        results.append(measure(name, spec, args.rounds))
        print(line(results[-1]), flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
