"""The nearest stored primitive to each point of a batch, and the certified rows finished exactly."""

import math

import numpy as np

from .. import primitives
from ..numerics.rounding import certify_difference
from ._alloc import readonly
from .traverse import TreeArrays, _gather, new_outputs, reads_cull, search_kernel

#: Bits of each coordinate in the Morton codes of the points: a 128^3 grid.
MORTON_BITS = 7


def _spread():
    """Each ``MORTON_BITS``-bit number with its bits spread to every third position."""
    x = np.arange(1 << MORTON_BITS)
    out = np.zeros(len(x), np.int64)
    for b in range(MORTON_BITS):
        out |= ((x >> b) & 1) << (3 * b)
    return out


_SPREAD = _spread()


def _morton_order(points):
    """The points in Morton order on a 128^3 grid over their finite bounding
    box (points with a non-finite coordinate go to the last cell): the
    sequence of their indices, stable within a cell.

    In NumPy, so that no batch size compiles a kernel of its own: the
    21-bit codes are sorted by two stable passes on their low 11 and high 10
    bits, each a radix sort of 16-bit keys.
    """
    top = (1 << MORTON_BITS) - 1
    every = bool(np.isfinite(points).all())
    kept = points if every else points[np.isfinite(points).all(axis=1)]
    if len(kept) == 0:
        return np.arange(len(points))
    low, high = kept.min(axis=0), kept.max(axis=0)
    span = float(np.max(high - low))
    inv = top / span if 0.0 < span < math.inf else 0.0
    with np.errstate(invalid="ignore", over="ignore"):
        g = (points - low) * inv
        if not every:  # NaN and +inf to the last cell, -inf to the first
            g = np.where(g >= 0.0, g, np.where(g < 0.0, 0.0, float(top)))
        cells = np.minimum(g, float(top)).astype(np.int64)
    code = _SPREAD[cells[:, 0]] | (_SPREAD[cells[:, 1]] << 1) | (_SPREAD[cells[:, 2]] << 2)
    first = np.argsort((code & 0x7FF).astype(np.uint16), kind="stable")
    return first[np.argsort((code[first] >> 11).astype(np.uint16), kind="stable")]


#: Batches at least this large are queried in Morton order of the points.
SORT_MIN = 4096


def _visiting_order(points):
    """Morton order of the points: neighbours in space are queried one after the other.

    Consecutive queries then walk the same nodes and faces, which stay in
    cache; with points in random order every query fetches its path from
    memory.  The order changes only the time, never an answer.
    """
    if len(points) < SORT_MIN:
        return np.arange(len(points))
    return _morton_order(points)


def nearest(tree, method, points, full, loose=False, cutoff=math.inf):
    """Nearest primitive to each of the validated points ``(n, 3)``.

    Parameters
    ----------
    tree : Tree
    method : Method
    points : ndarray of float64, shape ``(n, 3)``
    full : bool
        Whether to fill every output or only ``distance``.
    loose : bool
        Use the loose boxes (``eberly``).
    cutoff : float
        Rows with nothing within this distance get an infinite distance (and
        NaN, ``NONE`` and -1 in the other outputs); the search prunes beyond it.

    Returns
    -------
    dict of ndarray
        ``distance``, ``sqr_distance``, ``point``, ``feature``, ``extra``
        (barycentric, or height and radial), ``flag`` (equidistant) and
        ``index`` (the caller's index of the nearest primitive, -1 for none);
        all but ``distance`` empty unless ``full``.
    """
    points = readonly(points, np.float64)
    n = points.shape[0]
    out = new_outputs(n, full)
    # A tree of one kind gets a search compiled for that kind alone; any
    # other, the one search for every kind that offers the method (not one
    # per combination).
    kinds = tree.present if len(tree.present) == 1 else primitives.offering(method)
    bounds, cull, magnitude = tree.boxes(loose, reads_cull(method, kinds, tree.radius))
    arrays = TreeArrays(tree.kinds, tree.rows(), tree.index, cull, bounds, tree.child, tree.count)
    order = readonly(_visiting_order(points), np.int64)
    # Work per point varies by orders of magnitude (a point at the center of
    # a sphere is equidistant from every face), so blocks are handed out
    # one at a time rather than split evenly between threads up front.
    search = search_kernel(method, kinds, tree.radius, tree.indexed)
    search(arrays, tree.depth, magnitude, points, order, out, full, float(cutoff))
    rows = np.flatnonzero(~np.isnan(out.undecided))
    if len(rows):
        _resolve(tree, rows, points, out, full, tree.culling(loose), bounds, magnitude, cutoff)
    result = out._asdict()
    del result["undecided"]
    return result


def _resolve(tree, rows, points, out, full, cull, bounds, magnitude, cutoff):
    """Finish rows whose nearest primitive may be an undecided certified answer.

    Every candidate within the row's bound goes through the per-shape
    ``certified`` query, which runs the exact fallback where needed, so each
    answer is the one a single-shape query gives; the least wins, ties to
    the lowest index.
    """
    positions = np.empty(len(tree.kinds), np.int64)
    for i in rows:
        p = points[i]
        bound = out.undecided[i]
        found = _gather(cull, bounds, tree.child, tree.count, tree.depth, magnitude, p, bound, positions)
        candidates = positions[:found]
        answers = []  # (distance, caller's index, the kind's answers, row)
        for primitive in tree.present:
            chosen = candidates[tree.kinds[candidates] == primitive.code]
            if len(chosen) == 0:
                continue
            r = primitive.kernels.resolve(primitive.code, tree.params_of(chosen), p)
            if tree.radius >= 0:  # rounded primitives: d - R, certified
                rows = [(primitive, tree.params[k], p) for k in chosen]
                radius = tree.params[chosen, tree.radius]
                d = r["distance"]
                e = certify_difference(d - radius, d, radius, lambda bad, rows=rows: [rows[b] for b in bad])
                r = dict(r, distance=e)
            for j, idx in enumerate(tree.index[chosen]):
                if not np.isnan(r["distance"][j]):
                    answers.append((float(r["distance"][j]), int(idx), r, j))
        if not answers:
            continue
        d, idx, r, j = min(answers, key=lambda a: (a[0], a[1]))
        if d > cutoff:
            out.distance[i] = math.inf
            if full:
                out.index[i], out.feature[i], out.flag[i] = -1, -1, False
                out.sqr_distance[i] = math.inf
                out.point[i] = out.extra[i] = np.nan
            continue
        out.distance[i] = d
        if full:
            out.index[i] = idx
            for name in ("sqr_distance", "point", "feature", "extra", "flag"):
                getattr(out, name)[i] = r[name][j]
