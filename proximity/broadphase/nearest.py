"""The nearest stored primitive to each point of a batch, and the certified rows finished exactly."""

import math

import numpy as np
from numba.core import types

from .. import primitives
from ..numerics.rounding import certify_difference
from ..runtime.jit import specialize
from ._alloc import readonly
from .traverse import TreeArrays, _gather, new_outputs, reads_cull, search_kernel

#: Bits of each coordinate in the Morton codes of the points: a 128^3 grid.
MORTON_BITS = 7
#: The largest cell coordinate, and the number of cells.
_TOP = (1 << MORTON_BITS) - 1
_CELLS = 1 << (3 * MORTON_BITS)
#: The two passes of the sort of smaller batches: the codes' low bits, then the rest.
_LOW_BITS = 11
_LOW_MASK = (1 << _LOW_BITS) - 1
#: From this many points on, the codes are sorted in one counting pass over
#: every cell: its counts (16 MiB) cost at most 8 bytes a point, and no
#: second array of indices is needed.  Smaller batches take two passes over
#: 2^11 and 2^10 counts, through a 4-byte index a point.
ONE_PASS_MIN = 1 << 21


def _spread():
    """Each ``MORTON_BITS``-bit number with its bits spread to every third position."""
    x = np.arange(1 << MORTON_BITS)
    out = np.zeros(len(x), np.int64)
    for b in range(MORTON_BITS):
        out |= ((x >> b) & 1) << (3 * b)
    return out


_SPREAD = _spread()


def _morton(points, codes, counts, spare, order):
    """The Morton order of ``points`` into ``order`` (see :func:`_morton_order`).

    ``codes`` holds a code a point; ``counts`` and ``spare`` are scratch:
    where ``spare`` is empty, ``counts`` has an entry a cell, and the codes
    are sorted in one counting pass; else ``spare`` has an index a point,
    ``counts`` at least ``2^11`` entries, and the sort takes two stable
    counting passes, on the codes' low 11 bits and then on the rest.

    One function without helpers: each would be compiled on its own, and
    this is compiled at a first large batch.
    """
    n = points.shape[0]
    # The box of the finite points.
    lx, ly, lz = math.inf, math.inf, math.inf
    hx, hy, hz = -math.inf, -math.inf, -math.inf
    for i in range(n):
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        if math.isfinite(x) and math.isfinite(y) and math.isfinite(z):
            lx, ly, lz = min(lx, x), min(ly, y), min(lz, z)
            hx, hy, hz = max(hx, x), max(hy, y), max(hz, z)
    if not lx <= hx:  # no finite point: the order they come in
        for i in range(n):
            order[i] = i
        return
    span = max(max(hx - lx, hy - ly), hz - lz)
    # An extent beyond the float range (or none) puts every point in one cell
    # but those whose offset from the corner overflows (inf * 0: NaN, the last).
    inv = _TOP / span if 0.0 < span < math.inf else 0.0
    low = (lx, ly, lz)
    for i in range(n):
        code = 0
        for c in range(3):
            # (v - low) * inv truncated to 0 .. _TOP: below 0 (-inf) the first cell, NaN the last.
            g = (points[i, c] - low[c]) * inv
            cell = _TOP
            if g >= 0.0:
                cell = int(min(g, float(_TOP)))
            elif g < 0.0:
                cell = 0
            code |= _SPREAD[cell] << c
        codes[i] = code
    one = spare.shape[0] == 0
    for step in range(1 if one else 2):
        # Keys (code >> shift) & (keys - 1); the passes run least significant first.
        shift = _LOW_BITS if step == 1 else 0
        keys = _CELLS if one else (_LOW_MASK + 1 if step == 0 else _CELLS >> _LOW_BITS)
        for k in range(keys):
            counts[k] = 0
        for i in range(n):
            counts[(codes[i] >> shift) & (keys - 1)] += 1
        start = 0  # counts[k]: where the run of key k starts
        for k in range(keys):
            c = counts[k]
            counts[k] = start
            start += c
        for j in range(n):
            i = j if step == 0 else np.int64(spare[j])
            k = (codes[i] >> shift) & (keys - 1)
            if one or step == 1:
                order[counts[k]] = i
            else:
                spare[counts[k]] = i
            counts[k] += 1


_MORTON_SIGNATURE = types.void(
    types.Array(types.float64, 2, "C", readonly=True),
    types.Array(types.uint32, 1, "C"),
    types.Array(types.int64, 1, "C"),
    types.Array(types.uint32, 1, "C"),
    types.Array(types.int64, 1, "C"),
)


def _morton_order(points):
    """The points in Morton order on a 128^3 grid over their finite bounding
    box: the sequence of their indices, stable within a cell.

    A point with a non-finite coordinate is placed by its finite ones, NaN
    and ``+inf`` in the last cell of their axis and ``-inf`` in the first
    (the last, too, where the finite points span no extent, or one beyond
    the float range, where every point is in one cell but those whose
    offset overflows).

    One compiled kernel of one signature, so that no batch size compiles
    a kernel of its own; it allocates nothing, its arrays are NumPy's:
    with the order, 16 bytes a point below :data:`ONE_PASS_MIN` points
    and at most 20 from there on, where NumPy's temporaries and sorts of
    the codes took 80.
    """
    points = readonly(points, np.float64)
    n = points.shape[0]
    one_pass = n >= ONE_PASS_MIN
    codes = np.empty(n, np.uint32)
    counts = np.empty(_CELLS if one_pass else _LOW_MASK + 1, np.int64)
    spare = np.empty(0 if one_pass else n, np.uint32)
    order = np.empty(n, np.int64)
    specialize(_morton, "fixed", _MORTON_SIGNATURE)(points, codes, counts, spare, order)
    return order


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
    # The order before the outputs: its sort's scratch is gone before they are written.
    order = readonly(_visiting_order(points), np.int64)
    out = new_outputs(n, full, method.exact_fallback)
    # A tree of one kind gets a search compiled for that kind alone; any
    # other, the one search for every kind that offers the method (not one
    # per combination).
    kinds = tree.present if len(tree.present) == 1 else primitives.offering(method)
    bounds, cull, magnitude = tree.boxes(loose, reads_cull(method, kinds, tree.radius))
    arrays = TreeArrays(tree.kinds, tree.rows(), tree.index, cull, bounds, tree.child, tree.count)
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
