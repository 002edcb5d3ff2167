"""Nearest primitive of a collection: brute force, or a bounding-volume hierarchy.

A collection is a flat list of primitives, each a triangle, a disk or a
circle, stored as one row of ``params`` and a ``kinds`` code.  The distance
from a point to the collection is the minimum, over the primitives, of the
per-primitive method's computed distance (the per-method queries of
``point_triangle.KERNELS`` and ``point_disk.KERNELS``), called with the same
arguments as a single-shape query, so that a collection answers with exactly the bits the
per-shape query gives for its nearest primitive.  Among primitives at the
same computed distance the one with the lowest index wins; primitives whose
method gives NaN (``eberly`` on a zero-area triangle) are passed over, and a
row where every primitive gives NaN has no answer.

Brute force and the hierarchy are one traversal: brute force is the
hierarchy of a single leaf holding every primitive in index order.

Hierarchy
---------
Built once, on primitive boxes, by binned surface-area heuristic (``BINS``
bins on the centroids along their longest axis, splitting until a node holds at most
``LEAF_SIZE`` primitives; nodes whose centroids coincide are cut in half by
index).  The children of a node are adjacent in memory and come after it:
the large nodes breadth first, then the subtree of each small one in a
block of its own (see :func:`_build`).

Pruning, and why it never changes the answer
--------------------------------------------
The traversal visits the nearer child first and skips a node when a lower
bound on the distance from the point to what it holds exceeds ``best +
SLACK``.  A *slab* is a vector ``u`` no longer than 1 and the range
``[h_min, h_max]`` of ``u . X`` over everything it bounds: every such ``X``
is at least ``e = max(u . P - h_max, h_min - u . P, 0)`` from ``P``.  A
node has its box and an oriented box, three slabs on orthogonal axes
``u``, ``v``, ``w``, whose excesses add in squares (``|P - X|^2 >= e_u^2 +
e_v^2 + e_w^2``); the bound is the larger of the distances to the two
boxes.  A node's ``u`` is the mean normal of its primitives, so a flat
patch has an oriented box thin along its normal and tight across it, which
prunes where the axis-aligned box would not (a point far over a tilted
patch, or inside a sphere).  A primitive has its box and the slab of its
own normal: for a point over a face's interior the slab distance is the
distance itself, so faces that are merely near are skipped without calling
the method.

These tests never skip a primitive that brute force would pick.  In units
of ``M``, the largest coordinate magnitude of the point and of every box:

* the tests run on coordinates multiplied by a power of two ``s`` with
  ``M s`` in ``[0.5, 1)`` (exact), so squares neither overflow nor lose
  anything that matters to underflow, and their rounding is a few ``eps``;
  a slab's ``u`` and range carry a few ``eps`` more, and the axes of an
  oriented box, each shortened by ``2^-40``, are orthogonal far within
  that, so the sum of squares never exceeds ``|P - X|^2``;
* every primitive lies in its box and its slab, and each method's computed
  distance is at least the true distance to them minus a few tens of
  ``eps M``: ``robust`` is within ``8 eps S`` of the true distance, with
  ``S <= 2 sqrt(3) M`` for triangles and ``S <= 5 M`` for disks and
  circles; ``certified`` is within an ulp; ``eberly``'s closest point on a
  triangle or a disk lies in the plane and the box up to the rounding of
  its coordinates;
* before any primitive is asked, ``best`` is the distance to the closest
  point found for the previous point (points are visited in spatial order,
  so it is near): that point lies on its primitive up to the rounding of
  its coordinates, so the primitive's computed distance exceeds it by a few
  ``eps M`` at most;
* ``SLACK`` is ``256 eps M``, several times the sum: a skipped primitive's
  computed distance exceeds ``best``, so even ties are visited, and the
  lowest index wins in both.

``eberly``'s circle is the exception: near the axis it takes the rim
direction from rounding noise, so its closest point can leave the plane by
up to ``R``.  For that method circles are bounded by the cube ``C +- R``
and have no slab; the tree keeps a second set of boxes for it, and no
previous closest point bounds the search.

Certified
---------
Where the certified filter leaves a primitive's answer to its exact
fallback (rational arithmetic, in Python), the kernel only knows an
interval around it, from ``robust``'s bound, and uses the interval's upper
end to prune.  A point for which such a primitive could be the nearest is
finished outside the kernel: every candidate within the bound is asked
through the per-shape certified query, exact fallback included.

The traversal is compiled per method (:func:`kernel`): the method's
triangle and disk queries are bound into it, and nothing else is compiled.
"""

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np
from numba import prange
from numba.core import types

from . import certified, methods, point_disk, point_triangle
from ._fp import EPS
from ._jit import address, function_at, inline, kernel, specialize
from .results import Feature

TRIANGLE = 0
DISK = 1
CIRCLE = 2
N_PARAMS = 10  # triangle: V0, V1, V2; disk and circle: C, unit normal, normal as given, R

LEAF_SIZE = 4
BINS = 16
SLACK = 256.0 * EPS  # pruning slack, in units of the query's magnitude M (see the module docstring)
BLOCK = 64  # points per parallel task: the unit of dynamic scheduling
NONE = int(Feature.NONE)

_C2F = types.Array(types.float64, 2, "C", readonly=True)
_C1I = types.Array(types.int64, 1, "C", readonly=True)
_C1B = types.Array(types.int8, 1, "C", readonly=True)
_OUT1 = types.Array(types.float64, 1, "C")
_OUT2 = types.Array(types.float64, 2, "C")
_OUT_I8 = types.Array(types.int8, 1, "C")
_OUT_I64 = types.Array(types.int64, 1, "C")
_OUT_B = types.Array(types.boolean, 1, "C")


# Bound per method by :func:`proximity._jit.specialize`: the method's query
# of one triangle and of one disk or circle, the primitive evaluation built
# on them, whether the method has an exact fallback, and whether the tree
# may hold disks and circles (a mesh's kernel compiles triangles alone).
TRIANGLE_QUERY = ROUND_QUERY = EVALUATE = INTERVAL = None
EXACT_FALLBACK = False
ROUNDS = True
SEED_POINT = True


def _evaluate(kinds, q, k, px, py, pz):
    """Primitive ``k``'s answer: ``(status, d, sqr, x, y, z, feature, a0, a1, a2, equidistant)``.

    ``a`` is the barycentric triple for a triangle, ``(height, radial, NaN)``
    for a disk or a circle.
    """
    if ROUNDS:
        if kinds[k] != TRIANGLE:
            st, d, sqr, x, y, z, f, e, h, r = ROUND_QUERY(
                kinds[k] == DISK, q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5],
                q[k, 6], q[k, 7], q[k, 8], q[k, 9], px, py, pz,
            )  # fmt: skip
            return st, d, sqr, x, y, z, f, h, r, math.nan, e
    st, d, sqr, x, y, z, f, b0, b1, b2 = TRIANGLE_QUERY(
        q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], q[k, 6], q[k, 7], q[k, 8], px, py, pz
    )
    return st, d, sqr, x, y, z, f, b0, b1, b2, False


def _interval(kinds, q, k, px, py, pz):
    """Bounds ``(lo, hi)`` on the certified distance from the robust one.

    ``robust`` is within ``8 eps S`` of the exact distance and ``certified``
    within one ulp of it, below ``2 eps S``; ``S`` is bounded by ``1.75`` times
    the largest coordinate difference (``sqrt(3)`` and rounding), plus ``R``
    for a disk or a circle.
    """
    if ROUNDS and kinds[k] != TRIANGLE:
        d = point_disk.robust_query(
            kinds[k] == DISK,
            q[k, 0],
            q[k, 1],
            q[k, 2],
            q[k, 3],
            q[k, 4],
            q[k, 5],
            q[k, 6],
            q[k, 7],
            q[k, 8],
            q[k, 9],
            px,
            py,
            pz,
        )[1]
        m = max(max(abs(q[k, 0] - px), abs(q[k, 1] - py)), abs(q[k, 2] - pz))
        scale = 1.75 * m + q[k, 9]
    else:
        d = point_triangle.robust(
            q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], q[k, 6], q[k, 7], q[k, 8], px, py, pz
        )[0]
        m = 0.0
        for v in range(3):
            m = max(m, max(max(abs(q[k, 3 * v] - px), abs(q[k, 3 * v + 1] - py)), abs(q[k, 3 * v + 2] - pz)))
        scale = 1.75 * m
    w = 16.0 * EPS * scale + 5e-324  # the bound's absolute term, for subnormal distances
    return d - w, d + w


@inline
def _box_sqr(bounds, node, s, qx, qy, qz):
    # Squared distance from the scaled point to the scaled box: 0 inside.
    dx = max(max(bounds[node, 0] * s - qx, qx - bounds[node, 3] * s), 0.0)
    dy = max(max(bounds[node, 1] * s - qy, qy - bounds[node, 4] * s), 0.0)
    dz = max(max(bounds[node, 2] * s - qz, qz - bounds[node, 5] * s), 0.0)
    return dx * dx + dy * dy + dz * dz


@inline
def _excess(boxes, k, c, s, qx, qy, qz):
    """How far the scaled point lies outside the slab ``(u, h_min, h_max)`` at
    ``boxes[k, c:c + 5]``: 0 within it."""
    t = boxes[k, c] * qx + boxes[k, c + 1] * qy + boxes[k, c + 2] * qz
    return max(max(t - boxes[k, c + 4] * s, boxes[k, c + 3] * s - t), 0.0)


@inline
def _bound_sqr(boxes, k, s, qx, qy, qz):
    """Squared lower bound on the distance from the scaled point to what node ``k`` holds.

    ``boxes[k]`` is ``(lo, hi)`` and three slabs ``(u, h_min, h_max)``
    across orthogonal axes; see the module docstring.
    """
    hu = _excess(boxes, k, 6, s, qx, qy, qz)
    hv = _excess(boxes, k, 11, s, qx, qy, qz)
    hw = _excess(boxes, k, 16, s, qx, qy, qz)
    return max(_box_sqr(boxes, k, s, qx, qy, qz), hu * hu + hv * hv + hw * hw)


@inline
def _culled(cull, k, s, qx, qy, qz, reach):
    """Whether stored primitive ``k`` is farther than ``reach`` (scaled) by its box or its slab.

    ``cull[k]`` is ``(lo, hi, u, h_min, h_max)``; see the module docstring.
    """
    if _box_sqr(cull, k, s, qx, qy, qz) > reach * reach:
        return True
    return _excess(cull, k, 6, s, qx, qy, qz) > reach


@inline
def _scale(px, py, pz, magnitude):
    """The power of two ``s`` that brings ``M`` (point and boxes) into ``[0.5, 1)``."""
    m = max(max(abs(px), abs(py)), max(abs(pz), magnitude))
    return math.ldexp(1.0, -max(math.frexp(m)[1], -1000))


_BLOCK_SIGNATURE = types.void(
    types.int64,
    _C1B,
    _C2F,
    _C1I,
    _C2F,
    _C2F,
    _C1I,
    _C1I,
    types.int64,
    types.float64,
    _C2F,
    _C1I,
    _OUT1,
    _OUT1,
    _OUT2,
    _OUT_I8,
    _OUT2,
    _OUT_B,
    _OUT_I64,
    _OUT1,
    types.boolean,
)
_QUERY_SIGNATURE = types.void(types.int64, *_BLOCK_SIGNATURE.args[1:])
_nearest_at = function_at(_BLOCK_SIGNATURE)


def _nearest_block(
    block,
    kinds,
    params,
    index,
    cull,
    bounds,
    child,
    count,
    depth,
    magnitude,
    points,
    order,
    dist,
    sqr,
    point,
    feature,
    extra,
    flag,
    prim,
    undecided,
    full,
):
    """Nearest primitive to each point of ``block`` (points ``block * BLOCK``
    on, in the sequence ``order``); with ``full=False`` only ``dist`` and
    ``undecided`` are written.

    ``kinds``, ``params``, ``index`` (the caller's index of each stored
    primitive) and ``cull`` (its box and slab) are in leaf order.  Node
    ``i`` is a leaf holding stored primitives ``child[i] .. child[i] +
    count[i] - 1`` when ``count[i] > 0``, and otherwise has children
    ``child[i]`` and ``child[i] + 1``; ``bounds`` are the node boxes and
    ``magnitude`` the largest coordinate magnitude among them.  Points are
    visited in the sequence ``order``, so that consecutive queries walk the
    same part of the tree.

    Certified answers the filter leaves undecided are not known here: such
    a primitive only narrows ``[lo, hi]`` around its answer (from the robust
    one), and where one could be the nearest, ``undecided[i]`` is set to the
    distance bound below which candidates must be resolved exactly
    (otherwise NaN).
    """
    n = points.shape[0]
    # Above every caller's index, which may reach past the stored count
    # where copies were left out (:func:`distinct`): an infinite answer,
    # which ties with the initial ``best``, then still wins.
    sentinel = np.iinfo(np.int64).max
    stack_node = np.empty(depth + 1, np.int64)
    stack_sqr = np.empty(depth + 1)
    # The previous point's closest point, a point of the collection: points
    # are visited in spatial order, so the distance to it is an upper bound
    # on the next point's answer that prunes from the root down.
    near_x, near_y, near_z = math.nan, math.nan, math.nan
    for j in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
        i = order[j]
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        best = math.inf
        best_index = sentinel
        best_k = -1
        upper = math.inf  # least upper bound of the undecided answers
        lowest = math.inf  # least lower bound of the undecided answers
        # The winner's answer, kept as found rather than computed again.
        w_sqr, w_x, w_y, w_z, w_a0, w_a1, w_a2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        w_feature = NONE
        w_flag = False
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            s = _scale(px, py, pz, magnitude)
            qx, qy, qz = px * s, py * s, pz * s
            cap = math.inf  # scaled upper bound on the answer
            if SEED_POINT and not math.isnan(near_x):
                dx, dy, dz = qx - near_x * s, qy - near_y * s, qz - near_z * s
                cap = math.sqrt(dx * dx + dy * dy + dz * dz)
            reach = cap + SLACK  # scaled distance beyond which primitives are skipped
            limit = reach * reach  # its square, for the boxes
            node = 0
            sp = 0
            while True:
                first, c = child[node], count[node]
                if c > 0:
                    for k in range(first, first + c):
                        if _culled(cull, k, s, qx, qy, qz, reach):
                            continue
                        r = EVALUATE(kinds, params, k, px, py, pz)
                        certain = True
                        if EXACT_FALLBACK:
                            if r[0] != certified.CERTAIN:
                                certain = False
                                lo, hi = INTERVAL(kinds, params, k, px, py, pz)
                                lowest = min(lowest, lo)
                                upper = min(upper, hi)
                        if certain:
                            d = r[1]
                            idx = index[k]
                            if d < best or (d == best and idx < best_index):
                                best = d
                                best_index = idx
                                best_k = k
                                w_sqr, w_x, w_y, w_z = r[2], r[3], r[4], r[5]
                                w_feature = r[6]
                                w_a0, w_a1, w_a2 = r[7], r[8], r[9]
                                w_flag = r[10]
                        reach = min(min(best, upper) * s, cap) + SLACK
                        limit = reach * reach
                    node = -1
                else:
                    left = child[node]
                    right = left + 1
                    dl = _bound_sqr(bounds, left, s, qx, qy, qz)
                    dr = _bound_sqr(bounds, right, s, qx, qy, qz)
                    if dr < dl:
                        left, right, dl, dr = right, left, dr, dl
                    if dl <= limit:
                        if dr <= limit:
                            stack_node[sp] = right
                            stack_sqr[sp] = dr
                            sp += 1
                        node = left
                    else:
                        node = -1
                if node < 0:
                    while sp > 0:
                        sp -= 1
                        if stack_sqr[sp] <= limit:
                            node = stack_node[sp]
                            break
                    if node < 0:
                        break
        if best_k >= 0:
            near_x, near_y, near_z = w_x, w_y, w_z
        # An undecided answer could be the least (or tie with it): resolve
        # every candidate up to the bound exactly, outside the kernel.
        undecided[i] = min(best, upper) if lowest < math.inf and lowest <= best else math.nan
        if best_k < 0:
            dist[i] = math.nan
            if full:
                sqr[i] = math.nan
                for c in range(3):
                    point[i, c] = math.nan
                    extra[i, c] = math.nan
                feature[i] = NONE
                flag[i] = False
                prim[i] = -1
            continue
        dist[i] = best
        if full:
            sqr[i] = w_sqr
            point[i, 0] = w_x
            point[i, 1] = w_y
            point[i, 2] = w_z
            feature[i] = np.int8(w_feature)
            extra[i, 0] = w_a0
            extra[i, 1] = w_a1
            extra[i, 2] = w_a2
            flag[i] = w_flag
            prim[i] = best_index


def _nearest(
    address_,
    kinds,
    params,
    index,
    cull,
    bounds,
    child,
    count,
    depth,
    magnitude,
    points,
    order,
    dist,
    sqr,
    point,
    feature,
    extra,
    flag,
    prim,
    undecided,
    full,
):
    """:func:`_nearest_block` for every block of points, on the threads; the
    method's block function is called at ``address_`` (see
    :func:`proximity._jit.function_at`), so that this loop compiles once for
    every method."""
    block_fn = _nearest_at(address_)
    for block in prange((points.shape[0] + BLOCK - 1) // BLOCK):
        block_fn(
            np.int64(block),
            kinds,
            params,
            index,
            cull,
            bounds,
            child,
            count,
            depth,
            magnitude,
            points,
            order,
            dist,
            sqr,
            point,
            feature,
            extra,
            flag,
            prim,
            undecided,
            full,
        )


@kernel()
def _gather(cull, bounds, child, count, depth, magnitude, p, bound, out):
    """Stored primitives not culled at distance ``bound`` from ``p``, by the same tests as the search.

    Writes their positions to ``out`` and returns how many.  Every primitive
    whose computed distance is at most ``bound`` is among them.
    """
    px, py, pz = p[0], p[1], p[2]
    s = _scale(px, py, pz, magnitude)
    qx, qy, qz = px * s, py * s, pz * s
    reach = bound * s + SLACK
    limit = reach * reach
    stack = np.empty(depth + 2, np.int64)
    stack[0] = 0
    sp = 1
    found = 0
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if _bound_sqr(bounds, node, s, qx, qy, qz) > limit:
            continue
        if count[node] > 0:
            for k in range(child[node], child[node] + count[node]):
                if not _culled(cull, k, s, qx, qy, qz, reach):
                    out[found] = k
                    found += 1
        else:
            stack[sp] = child[node]
            stack[sp + 1] = child[node] + 1
            sp += 2
    return found


#: Bits of each coordinate in the Morton codes of the points: a 128^3 grid.
MORTON_BITS = 7


@kernel()
def _morton_order(points):
    """The points in Morton order on a 128^3 grid over their finite bounding
    box (points with a non-finite coordinate go to the last cell): the
    sequence of their indices, stable within a cell.

    The 21-bit codes are sorted by two passes of a radix sort, on their low
    11 and high 10 bits.
    """
    n = points.shape[0]
    low = np.full(3, math.inf)
    high = np.full(3, -math.inf)
    for i in range(n):
        if math.isfinite(points[i, 0]) and math.isfinite(points[i, 1]) and math.isfinite(points[i, 2]):
            for a in range(3):
                low[a] = min(low[a], points[i, a])
                high[a] = max(high[a], points[i, a])
    top = (1 << MORTON_BITS) - 1
    span = max(max(high[0] - low[0], high[1] - low[1]), high[2] - low[2])
    inv = top / span if 0.0 < span < math.inf else 0.0
    codes = np.empty(n, np.int64)
    for i in range(n):
        code = 0
        for a in range(3):
            g = (points[i, a] - low[a]) * inv
            if not (g >= 0.0):  # NaN as well
                g = 0.0 if g < 0.0 else float(top)
            x = int(min(g, float(top)))
            # Spread the bits of x to every third position.
            for b in range(MORTON_BITS):
                code |= ((x >> b) & 1) << (3 * b + a)
        codes[i] = code
    order = np.arange(n)
    scratch = np.empty(n, np.int64)
    for shift, width in ((0, 11), (11, 3 * MORTON_BITS - 11)):
        mask = (1 << width) - 1
        starts = np.zeros((1 << width) + 1, np.int64)
        for i in range(n):
            starts[((codes[order[i]] >> shift) & mask) + 1] += 1
        for b in range(1 << width):
            starts[b + 1] += starts[b]
        for i in range(n):
            k = order[i]
            bucket = (codes[k] >> shift) & mask
            scratch[starts[bucket]] = k
            starts[bucket] += 1
        order, scratch = scratch, order
    return order


@inline
def _centroid(rows, j, a):
    # Halves first: the sum of two coordinates near 1e308 would overflow.
    return rows[j, a] * 0.5 + rows[j, 3 + a] * 0.5


@inline
def _split(i, first_child, child, count, rows, order, cmin, cmax, base, bins):
    """Split node ``i`` (primitives ``child[i] .. + count[i]``) at its best
    binned SAH plane, into nodes ``first_child`` and ``first_child + 1``.
    The centroid bounds of node ``k`` are row ``k - base`` of ``cmin`` and
    ``cmax``.

    ``rows`` holds each primitive's box in its first six columns (low and
    high corners), and its centroid is the box's center.  The centroids are
    binned along the longest axis of their bounds, in the caller's work
    array ``bins`` ``(BINS, 9)``: a count, a box, and the count and area
    right of each bin.  The rows of ``rows`` and ``order`` are partitioned
    in place (each node's rows are contiguous), and the children's centroid
    bounds are gathered on the way.
    """
    start = child[i]
    cnt = count[i]
    end = start + cnt
    columns = rows.shape[1]
    axis = -1
    widest = 0.0
    for a in range(3):
        extent = cmax[i - base, a] - cmin[i - base, a]
        if extent > widest and extent < math.inf:
            axis, widest = a, extent
    best_axis = -1
    best_bin = 0
    scale, origin = 0.0, 0.0
    if axis >= 0:
        scale = BINS / widest
        origin = cmin[i - base, axis]
        for b in range(BINS):
            bins[b, 0] = 0.0
            for c in range(3):
                bins[b, 1 + c] = math.inf
                bins[b, 4 + c] = -math.inf
        for j in range(start, end):
            b = min(int((_centroid(rows, j, axis) - origin) * scale), BINS - 1)
            bins[b, 0] += 1.0
            for c in range(3):
                bins[b, 1 + c] = min(bins[b, 1 + c], rows[j, c])
                bins[b, 4 + c] = max(bins[b, 4 + c], rows[j, 3 + c])
        # Sweep from the right, then from the left, costing each plane
        # between bins b and b + 1 as area x count on either side.
        xl, yl, zl = math.inf, math.inf, math.inf
        xh, yh, zh = -math.inf, -math.inf, -math.inf
        total = 0.0
        for b in range(BINS - 1, 0, -1):
            total += bins[b, 0]
            xl, yl, zl = min(xl, bins[b, 1]), min(yl, bins[b, 2]), min(zl, bins[b, 3])
            xh, yh, zh = max(xh, bins[b, 4]), max(yh, bins[b, 5]), max(zh, bins[b, 6])
            dx, dy, dz = xh - xl, yh - yl, zh - zl
            bins[b, 7] = total
            bins[b, 8] = dx * dy + dy * dz + dz * dx if total > 0.0 else 0.0
        xl, yl, zl = math.inf, math.inf, math.inf
        xh, yh, zh = -math.inf, -math.inf, -math.inf
        total = 0.0
        best_cost = math.inf
        for b in range(BINS - 1):
            total += bins[b, 0]
            xl, yl, zl = min(xl, bins[b, 1]), min(yl, bins[b, 2]), min(zl, bins[b, 3])
            xh, yh, zh = max(xh, bins[b, 4]), max(yh, bins[b, 5]), max(zh, bins[b, 6])
            if total == 0.0 or bins[b + 1, 7] == 0.0:
                continue
            dx, dy, dz = xh - xl, yh - yl, zh - zl
            cost = (dx * dy + dy * dz + dz * dx) * total + bins[b + 1, 8] * bins[b + 1, 7]
            if cost < best_cost:
                best_cost = cost
                best_axis = axis
                best_bin = b
    # The children's centroid bounds, left (l) and right (r).
    lx0, ly0, lz0, lx1, ly1, lz1 = math.inf, math.inf, math.inf, -math.inf, -math.inf, -math.inf
    rx0, ry0, rz0, rx1, ry1, rz1 = math.inf, math.inf, math.inf, -math.inf, -math.inf, -math.inf
    if best_axis < 0:
        # Coincident centroids (or costs beyond the float range): halves by index.
        mid = start + cnt // 2
        for j in range(start, end):
            x, y, z = _centroid(rows, j, 0), _centroid(rows, j, 1), _centroid(rows, j, 2)
            if j < mid:
                lx0, ly0, lz0 = min(lx0, x), min(ly0, y), min(lz0, z)
                lx1, ly1, lz1 = max(lx1, x), max(ly1, y), max(lz1, z)
            else:
                rx0, ry0, rz0 = min(rx0, x), min(ry0, y), min(rz0, z)
                rx1, ry1, rz1 = max(rx1, x), max(ry1, y), max(rz1, z)
    else:
        a = best_axis
        lo_j = start
        hi_j = end - 1
        while lo_j <= hi_j:
            x, y, z = _centroid(rows, lo_j, 0), _centroid(rows, lo_j, 1), _centroid(rows, lo_j, 2)
            h = x if a == 0 else (y if a == 1 else z)
            if min(int((h - origin) * scale), BINS - 1) <= best_bin:
                lx0, ly0, lz0 = min(lx0, x), min(ly0, y), min(lz0, z)
                lx1, ly1, lz1 = max(lx1, x), max(ly1, y), max(lz1, z)
                lo_j += 1
            else:
                rx0, ry0, rz0 = min(rx0, x), min(ry0, y), min(rz0, z)
                rx1, ry1, rz1 = max(rx1, x), max(ry1, y), max(rz1, z)
                # Swap rows lo_j and hi_j of every array kept in node order.
                order[lo_j], order[hi_j] = order[hi_j], order[lo_j]
                for c in range(columns):
                    rows[lo_j, c], rows[hi_j, c] = rows[hi_j, c], rows[lo_j, c]
                hi_j -= 1
        mid = lo_j
    left = first_child - base
    right = first_child + 1 - base
    cmin[left, 0], cmin[left, 1], cmin[left, 2] = lx0, ly0, lz0
    cmax[left, 0], cmax[left, 1], cmax[left, 2] = lx1, ly1, lz1
    cmin[right, 0], cmin[right, 1], cmin[right, 2] = rx0, ry0, rz0
    cmax[right, 0], cmax[right, 1], cmax[right, 2] = rx1, ry1, rz1
    child[first_child] = start
    count[first_child] = mid - start
    child[first_child + 1] = mid
    count[first_child + 1] = end - mid
    child[i] = first_child
    count[i] = 0


#: Nodes over at most this many primitives are split subtree by subtree,
#: while their rows are in cache, rather than one level of the tree at a time.
BUILD_SUBTREE = 4096


@inline
def _split_subtree(root, child, count, rows, order, cmin, cmax, bins, leaf_size):
    """Split node ``root`` and its descendants down to the leaves, breadth
    first, into nodes ``root + 1`` on, whose centroid bounds are rows of
    ``cmin``, ``cmax`` from ``root`` on.  Returns the number of nodes, the
    root included, and the depth of the deepest leaf below the root."""
    last = root + 1
    level_end = root + 1
    depth = 0
    i = root
    while i < last:
        if i == level_end:
            depth += 1
            level_end = last
        if count[i] > leaf_size:
            _split(i, last, child, count, rows, order, cmin, cmax, root, bins)
            last += 2
        i += 1
    return last - root, depth


@inline
def _subtree_task(i, child, count, cmin, cmax, block_child, block_count, rows, order, leaf_size):
    """:func:`_split_subtree` for node ``i`` of the level-by-level split, in
    the block of nodes at twice its first row, with scratch bounds."""
    base = 2 * child[i]
    scratch_min = np.empty((2 * BUILD_SUBTREE, 3))
    scratch_max = np.empty((2 * BUILD_SUBTREE, 3))
    bins = np.empty((BINS, 9))
    block_child[base] = child[i]
    block_count[base] = count[i]
    for a in range(3):
        scratch_min[0, a] = cmin[i, a]
        scratch_max[0, a] = cmax[i, a]
    return _split_subtree(
        base, block_child, block_count, rows, order, scratch_min, scratch_max, bins, leaf_size
    )


@inline
def _number_block(i, nodes, offset, child, block_child, block_count, out_child, out_count):
    """Copy node ``i``'s block of ``nodes`` nodes into the tree: block node
    ``base + t`` is node ``offset + t - 1``, and the root keeps its number."""
    base = 2 * child[i]
    for t in range(nodes):
        k = i if t == 0 else offset + t - 1
        if block_count[base + t] == 0:
            out_child[k] = offset + block_child[base + t] - base - 1
            out_count[k] = 0
        else:
            out_child[k] = block_child[base + t]
            out_count[k] = block_count[base + t]


@kernel(parallel=True)
def _build(rows, leaf_size):
    """Topology of a hierarchy over the boxes ``rows[:, 0:3]`` (low corners)
    and ``rows[:, 3:6]`` (high corners), n >= 1 rows, whose rows it puts in
    leaf order (every column, in place).

    Returns ``(child, count, order, depth)``: the nodes as in
    :func:`_nearest`, ``order[j]`` the primitive now at row ``j``, and the
    largest depth of a leaf.

    Binned SAH.  Nodes over more than :data:`BUILD_SUBTREE` primitives (and
    more than ``leaf_size``) are split one level of the tree at a time, the nodes of a level in
    parallel, each on its own contiguous rows, and numbered breadth first.
    Each smaller node is then split down to its leaves as one task, in a
    scratch block of nodes that its rows index (a node over rows ``s .. s +
    c - 1`` has at most ``2 c - 1`` nodes in its subtree, so the block at
    ``2 s`` is its own).  Its descendants are then numbered after the large
    nodes, block after block: a node's children are adjacent and come after
    it.
    """
    n = rows.shape[0]
    cap = 2 * n - 1
    # Every entry is written before it is read (np.zeros or np.arange
    # would each be a parallel loop of its own to compile).
    child = np.empty(cap, np.int64)
    count = np.empty(cap, np.int64)
    first_child = np.empty(cap, np.int64)
    cmin = np.empty((cap, 3))
    cmax = np.empty((cap, 3))
    order = np.empty(n, np.int64)
    for j in range(n):
        order[j] = j
    child[0] = 0
    for a in range(3):
        cmin[0, a] = math.inf
        cmax[0, a] = -math.inf
    for j in range(n):
        for a in range(3):
            cmin[0, a] = min(cmin[0, a], _centroid(rows, j, a))
            cmax[0, a] = max(cmax[0, a], _centroid(rows, j, a))
    count[0] = n
    large = max(leaf_size, BUILD_SUBTREE)
    n_nodes = 1
    begin = 0
    while begin < n_nodes:
        end_level = n_nodes
        for i in range(begin, end_level):
            if count[i] > large:
                first_child[i] = n_nodes
                n_nodes += 2
        # In chunks of nodes, each with its own work array for the bins.
        size = max((end_level - begin) // 16, 1)
        for chunk in prange((end_level - begin + size - 1) // size):
            bins = np.empty((BINS, 9))
            for i in range(begin + chunk * size, min(begin + (chunk + 1) * size, end_level)):
                if count[i] > large:
                    _split(i, first_child[i], child, count, rows, order, cmin, cmax, np.int64(0), bins)
        begin = end_level
    # The depth of each of those nodes (set from its parent's: an array
    # filled by NumPy here would be a parallel loop that Numba may fuse
    # with a later one of the same length), and the ones left to split.
    level = np.empty(n_nodes, np.int64)
    level[0] = 0
    roots = np.empty(n_nodes, np.int64)
    n_roots = 0
    deepest = 0
    for k in range(n_nodes):
        if count[k] == 0:
            level[child[k]] = level[k] + 1
            level[child[k] + 1] = level[k] + 1
        elif count[k] > leaf_size:
            roots[n_roots] = k
            n_roots += 1
        else:
            deepest = max(deepest, level[k])
    block_child = np.empty(2 * n, np.int64)
    block_count = np.empty(2 * n, np.int64)
    nodes = np.empty(n_roots, np.int64)
    below = np.empty(n_roots, np.int64)
    for r in prange(n_roots):
        made, levels = _subtree_task(
            roots[r], child, count, cmin, cmax, block_child, block_count, rows, order, leaf_size
        )
        nodes[r] = made
        below[r] = levels
    total = n_nodes
    offset = np.empty(n_roots, np.int64)
    for r in range(n_roots):
        offset[r] = total
        total += nodes[r] - 1
        deepest = max(deepest, level[roots[r]] + below[r])
    out_child = np.empty(total, np.int64)
    out_count = np.empty(total, np.int64)
    for k in range(n_nodes):
        out_child[k] = child[k]
        out_count[k] = count[k]
    for r in prange(n_roots):
        _number_block(roots[r], nodes[r], offset[r], child, block_child, block_count, out_child, out_count)
    return out_child, out_count, order, deepest


@inline
def _across(ux, uy, uz):
    """Two vectors ``v``, ``w`` that make with ``u`` an orthogonal frame of
    vectors no longer than 1 (zero where ``u`` is zero).

    ``v`` is ``u`` with its smallest component zeroed and the other two
    swapped, one negated, which is perpendicular to ``u`` exactly; ``w`` is
    ``u x v``.  Both are normalised and shortened as ``u`` is (see
    :func:`_shorter_than_one`), which leaves the frame's rounding far inside
    the shortening.
    """
    if abs(ux) <= abs(uy) and abs(ux) <= abs(uz):
        vx, vy, vz = 0.0, -uz, uy
    elif abs(uy) <= abs(uz):
        vx, vy, vz = uz, 0.0, -ux
    else:
        vx, vy, vz = -uy, ux, 0.0
    wx, wy, wz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    lv = math.sqrt(vx * vx + vy * vy + vz * vz)
    lw = math.sqrt(wx * wx + wy * wy + wz * wz)
    sv = (1.0 - 2.0**-40) / lv if lv > 0.0 else 0.0
    sw = (1.0 - 2.0**-40) / lw if lw > 0.0 else 0.0
    return vx * sv, vy * sv, vz * sv, wx * sw, wy * sw, wz * sw


#: Columns of a node's bounds: its box ``(lo, hi)``, then three slabs
#: ``(axis, h_min, h_max)`` on the orthogonal axes ``u``, ``v``, ``w``.
NODE_COLUMNS = 21


@inline
def _ranges(bounds, i, first, last, kinds, params, cull):
    """The ranges of node ``i``'s three slabs over stored primitives ``first .. last - 1``."""
    ux, uy, uz = bounds[i, 6], bounds[i, 7], bounds[i, 8]
    vx, vy, vz = bounds[i, 11], bounds[i, 12], bounds[i, 13]
    wx, wy, wz = bounds[i, 16], bounds[i, 17], bounds[i, 18]
    lu, hu = math.inf, -math.inf
    lv, hv = math.inf, -math.inf
    lw, hw = math.inf, -math.inf
    for k in range(first, last):
        triangle = kinds[k] == TRIANGLE
        for c in range(3 if triangle else 8):
            if triangle:
                x, y, z = params[k, 3 * c], params[k, 3 * c + 1], params[k, 3 * c + 2]
            else:
                x = cull[k, 3 if c & 1 else 0]
                y = cull[k, 4 if c & 2 else 1]
                z = cull[k, 5 if c & 4 else 2]
            h = ux * x + uy * y + uz * z
            lu, hu = min(lu, h), max(hu, h)
            h = vx * x + vy * y + vz * z
            lv, hv = min(lv, h), max(hv, h)
            h = wx * x + wy * y + wz * z
            lw, hw = min(lw, h), max(hw, h)
    for c, low, high in ((9, lu, hu), (14, lv, hv), (19, lw, hw)):
        finite = math.isfinite(low) and math.isfinite(high)
        bounds[i, c] = low if finite else -math.inf
        bounds[i, c + 1] = high if finite else math.inf


#: Nodes over at most this many primitives are fitted subtree by subtree,
#: while the subtree's primitives are in cache.
REFIT_SUBTREE = 8192


@inline
def _rows(child, count, i):
    """The stored primitives ``first .. last - 1`` under node ``i``."""
    k = i
    while count[k] == 0:
        k = child[k]
    first = child[k]
    k = i
    while count[k] == 0:
        k = child[k] + 1
    return first, child[k] + count[k]


@kernel()
def _refit_top(child, count):
    """The tasks of :func:`refit`: ``(top, tasks, start, end)``.

    ``top`` are the nodes over more than :data:`REFIT_SUBTREE` primitives,
    a node before its children; ``tasks`` the roots of the subtrees below
    them (the root itself when it is no larger).  ``start`` and ``end``
    are arrays over every node, set here for those: node ``i`` holds
    stored primitives ``start[i] .. end[i] - 1``.
    """
    m = child.shape[0]
    start = np.empty(m, np.int64)
    end = np.empty(m, np.int64)
    top = np.empty(m, np.int64)
    tasks = np.empty(m, np.int64)
    stack = np.empty(m + 1, np.int64)
    n_top = 0
    n_tasks = 0
    stack[0] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        i = stack[sp]
        first, last = _rows(child, count, i)
        start[i], end[i] = first, last
        if count[i] == 0 and last - first > REFIT_SUBTREE:
            top[n_top] = i
            n_top += 1
            stack[sp] = child[i] + 1
            stack[sp + 1] = child[i]
            sp += 2
        else:
            tasks[n_tasks] = i
            n_tasks += 1
    return top[:n_top].copy(), tasks[:n_tasks].copy(), start, end


@inline
def _merge(bounds, i, rows, first, last):
    """Node ``i``'s box and normal sum (columns 6-8) over ``rows[first:last]``,
    which hold a box and a normal (sum) in the same columns: its primitives'
    ``cull`` rows for a leaf, its two children's ``bounds`` otherwise."""
    for a in range(3):
        bounds[i, a] = math.inf
        bounds[i, 3 + a] = -math.inf
        bounds[i, 6 + a] = 0.0
    for k in range(first, last):
        for a in range(3):
            bounds[i, a] = min(bounds[i, a], rows[k, a])
            bounds[i, 3 + a] = max(bounds[i, 3 + a], rows[k, 3 + a])
            bounds[i, 6 + a] += rows[k, 6 + a]


@inline
def _frame(bounds, i):
    """Node ``i``'s axes from its normal sum: ``u`` the sum normalised and
    shortened, ``v`` and ``w`` across it (:func:`_across`)."""
    ux, uy, uz = bounds[i, 6], bounds[i, 7], bounds[i, 8]
    length = math.sqrt(ux * ux + uy * uy + uz * uz)
    if length > 0.0 and length < math.inf:
        shrink = (1.0 - 2.0**-40) / length
        ux, uy, uz = ux * shrink, uy * shrink, uz * shrink
    else:
        ux, uy, uz = 0.0, 0.0, 0.0
    vx, vy, vz, wx, wy, wz = _across(ux, uy, uz)
    bounds[i, 6], bounds[i, 7], bounds[i, 8] = ux, uy, uz
    bounds[i, 11], bounds[i, 12], bounds[i, 13] = vx, vy, vz
    bounds[i, 16], bounds[i, 17], bounds[i, 18] = wx, wy, wz


@inline
def _fit_subtree(bounds, root, start, end, child, count, kinds, params, cull):
    """Every node of the subtree at ``root``: boxes and normal sums from the
    leaves up, then, but for ``root`` itself, its frame and slab ranges."""
    # A subtree over c primitives has at most 2 c - 1 nodes.
    nodes = np.empty(2 * (end[root] - start[root]), np.int64)
    stack = np.empty(2 * (end[root] - start[root]), np.int64)
    n = 0
    stack[0] = root
    sp = 1
    while sp > 0:
        sp -= 1
        i = stack[sp]
        nodes[n] = i
        n += 1
        if count[i] == 0:
            stack[sp] = child[i] + 1
            stack[sp + 1] = child[i]
            sp += 2
    # A node comes before its descendants: backwards, they are done first.
    for t in range(n - 1, -1, -1):
        i = nodes[t]
        if count[i] > 0:
            start[i] = child[i]
            end[i] = child[i] + count[i]
            _merge(bounds, i, cull, start[i], end[i])
        else:
            start[i] = start[child[i]]
            end[i] = end[child[i] + 1]
            _merge(bounds, i, bounds, child[i], child[i] + 2)
    for t in range(1, n):
        i = nodes[t]
        _frame(bounds, i)
        _ranges(bounds, i, start[i], end[i], kinds, params, cull)


@kernel(parallel=True)
def _fit(bounds, top, tasks, start, end, child, count, kinds, params, cull):
    """The bounds of every node (see :func:`refit`).

    The subtrees at ``tasks`` are fitted one per task; then the boxes and
    normal sums of the ``top`` nodes, children first; then the frames and
    ranges of the top nodes and of the subtrees' roots, one per task.
    """
    for j in prange(tasks.shape[0]):
        _fit_subtree(bounds, tasks[j], start, end, child, count, kinds, params, cull)
    for t in range(top.shape[0] - 1, -1, -1):
        _merge(bounds, top[t], bounds, child[top[t]], child[top[t]] + 2)
    for j in prange(top.shape[0] + tasks.shape[0]):
        i = top[j] if j < top.shape[0] else tasks[j - top.shape[0]]
        _frame(bounds, i)
        _ranges(bounds, i, start[i], end[i], kinds, params, cull)


def refit(child, count, kinds, params, cull):
    """Node boxes and slabs, ``(m, NODE_COLUMNS)``, over the stored primitives.

    Each node has its box ``(lo, hi)`` and an oriented box, as three slabs
    ``(axis, h_min, h_max)``: ``u`` is the normalised sum of the primitives'
    slab directions (their normals), shortened as in
    :func:`_shorter_than_one`, and ``v``, ``w`` complete it to an orthogonal
    frame (:func:`_across`); each range is that of ``axis . X`` over the
    triangles' vertices and the corners of the other primitives' boxes, and
    an overflowing range is unbounded.  A flat patch of faces gets a thin
    box along its normal and a tight one across it, which prunes where the
    axis-aligned box alone would not (a point over a tilted patch, or near
    the center of a sphere).

    The subtrees, and the nodes above them, are fitted on the threads.
    """
    if len(child) == 1:
        # One leaf (brute force): the traversal goes straight to its
        # primitives and never tests its bounds, which need only its box,
        # the scale of the pruning tests; the slabs bound nothing.
        bounds = np.zeros((1, NODE_COLUMNS))
        bounds[0, 0:3] = cull[:, 0:3].min(axis=0)
        bounds[0, 3:6] = cull[:, 3:6].max(axis=0)
        bounds[0, 9::5] = -math.inf
        bounds[0, 10::5] = math.inf
        return bounds
    top, tasks, start, end = _refit_top(child, count)
    bounds = empty(len(child), NODE_COLUMNS)
    # Tasks differ in size by orders of magnitude: handed out one at a time.
    with numba.parallel_chunksize(1):
        _fit(bounds, top, tasks, start, end, child, count, kinds, params, cull)
    return bounds


def _readonly(array, dtype):
    array = np.ascontiguousarray(array, dtype=dtype)
    view = array.view()
    view.flags.writeable = False
    return view


@dataclass(frozen=True, eq=False)
class Tree:
    """A broad phase: primitives in leaf order and the nodes over them.

    Attributes
    ----------
    kinds : ndarray of int8, shape ``(n,)``
        ``TRIANGLE``, ``DISK`` or ``CIRCLE`` for each stored primitive.
    params : ndarray of float64, shape ``(n, 10)``
        Each stored primitive's data (see :data:`N_PARAMS`).
    index : ndarray of int64, shape ``(n,)``
        The caller's index of each stored primitive.
    child, count : ndarray of int64, shape ``(m,)``
        Node topology (see :func:`_nearest`); one leaf for brute force.
    bounds : ndarray of float64, shape ``(m, NODE_COLUMNS)``
        Node boxes and oriented boxes (see :func:`refit`).
    cull : ndarray of float64, shape ``(n, 11)``
        Each stored primitive's box and slab ``(lo, hi, u, h_min, h_max)``.
    loose_bounds, loose_cull : ndarray of float64
        The same for ``eberly`` (the same arrays unless there are circles).
    depth : int
        Depth of the deepest leaf.
    """

    kinds: np.ndarray
    params: np.ndarray
    index: np.ndarray
    child: np.ndarray
    count: np.ndarray
    bounds: np.ndarray
    cull: np.ndarray
    loose_bounds: np.ndarray
    loose_cull: np.ndarray
    depth: int

    @property
    def nodes(self):
        """Number of nodes; 1 for brute force."""
        return len(self.child)

    @functools.cached_property
    def rounds(self):
        """Whether any stored primitive is a disk or a circle."""
        return bool((self.kinds != TRIANGLE).any())

    def boxes(self, loose):
        """``(node boxes, primitive culling data, magnitude)``, tight or loose."""
        bounds, cull = (self.loose_bounds, self.loose_cull) if loose else (self.bounds, self.cull)
        # A coordinate that overflowed leaves its box unbounded, which prunes
        # nothing; the scale is set by the finite ones.
        corners = np.abs(bounds[0, :6])
        return bounds, cull, float(np.max(corners, where=np.isfinite(corners), initial=0.0))


def _shorter_than_one(u):
    # Any vector no longer than 1 gives a valid slab; shrink the rounded
    # unit vector by far more than its rounding so that it is one.
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        length = np.sqrt(np.sum(u * u, axis=1, keepdims=True))
        u = u / length * (1.0 - 2.0**-40)
    return np.where(np.isfinite(u).all(axis=1, keepdims=True), u, 0.0)


def _slab(u, points):
    """``(h_min, h_max)`` of ``u . X`` over ``points (n, k, 3)``; unbounded where it overflows."""
    with np.errstate(invalid="ignore", over="ignore"):
        h = np.einsum("nkj,nj->nk", points, u)
    ok = np.isfinite(h).all(axis=1)
    return np.where(ok, h.min(axis=1), -np.inf), np.where(ok, h.max(axis=1), np.inf)


@inline
def _triangle_row(cull, k, x0, y0, z0, x1, y1, z1, x2, y2, z2):
    """Row ``k`` of :func:`primitive_cull` for the triangle of these
    vertices: its box, and the slab of its normal shortened as
    :func:`_shorter_than_one` does."""
    cull[k, 0], cull[k, 3] = min(min(x0, x1), x2), max(max(x0, x1), x2)
    cull[k, 1], cull[k, 4] = min(min(y0, y1), y2), max(max(y0, y1), y2)
    cull[k, 2], cull[k, 5] = min(min(z0, z1), z2), max(max(z0, z1), z2)
    ex, ey, ez = x1 - x0, y1 - y0, z1 - z0
    fx, fy, fz = x2 - x0, y2 - y0, z2 - z0
    nx, ny, nz = ey * fz - ez * fy, ez * fx - ex * fz, ex * fy - ey * fx
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    shrink = (1.0 - 2.0**-40) / length if length > 0.0 else 0.0
    ux, uy, uz = nx * shrink, ny * shrink, nz * shrink
    if not (math.isfinite(ux) and math.isfinite(uy) and math.isfinite(uz)):
        ux, uy, uz = 0.0, 0.0, 0.0
    h0 = ux * x0 + uy * y0 + uz * z0
    h1 = ux * x1 + uy * y1 + uz * z1
    h2 = ux * x2 + uy * y2 + uz * z2
    low = min(min(min(math.inf, h0), h1), h2)
    high = max(max(max(-math.inf, h0), h1), h2)
    if not (math.isfinite(low) and math.isfinite(high)):
        low, high = -math.inf, math.inf
    cull[k, 6], cull[k, 7], cull[k, 8] = ux, uy, uz
    cull[k, 9], cull[k, 10] = low, high


@kernel()
def _triangle_cull(kinds, params, cull):
    """:func:`primitive_cull` for the triangles."""
    for k in range(kinds.shape[0]):
        if kinds[k] == TRIANGLE:
            p = params[k]
            _triangle_row(cull, k, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8])


def primitive_cull(kinds, params):
    """Box and slab of each primitive, ``(n, 11)``, and the loose ones for ``eberly``.

    Triangles: the vertices' extremes (exact), and the slab of the unit
    normal (none for a zero-area triangle).  Disks and circles: the center
    plus or minus ``R sqrt(1 - u_a^2)`` on each axis ``a``, computed as ``R
    sqrt(u_b^2 + u_c^2) / |u|`` so that no cancellation enters (its rounding
    is a few ``eps`` of ``R``, inside the pruning slack), and the slab of
    their plane.  Loose data bound circles by the cube ``C +- R``, without a
    slab.
    """
    n = len(kinds)
    cull = empty(n, 11)
    tri = kinds == TRIANGLE
    _triangle_cull(_readonly(kinds, np.int8), _readonly(params, np.float64), cull)
    round_ = ~tri
    loose = cull
    if round_.any():
        c = params[round_, 0:3]
        sq = params[round_, 3:6] ** 2
        r = params[round_, 9:10]
        # 1 - u_a^2 as the sum of the other two squares: subtracting from 1
        # would cancel, and the square root would magnify that to sqrt(eps).
        others = sq[:, [1, 2, 0]] + sq[:, [2, 0, 1]]
        with np.errstate(over="ignore"):
            extent = r * np.sqrt(others) / np.sqrt(sq.sum(axis=1, keepdims=True))
            cull[round_, 0:3] = c - extent
            cull[round_, 3:6] = c + extent
        u = _shorter_than_one(params[round_, 3:6])
        cull[round_, 6:9] = u
        cull[round_, 9], cull[round_, 10] = _slab(u, c[:, None, :])
        circle = kinds == CIRCLE
        if circle.any():
            loose = cull.copy()
            with np.errstate(over="ignore"):
                loose[circle, 0:3] = params[circle, 0:3] - params[circle, 9:10]
                loose[circle, 3:6] = params[circle, 0:3] + params[circle, 9:10]
            loose[circle, 6:9] = 0.0
            loose[circle, 9] = -np.inf
            loose[circle, 10] = np.inf
    return cull, loose


#: From this many rows on, :func:`take_rows` and :func:`triangle_params`
#: (in the faces' own order) gather by compiled parallel loops; below, by
#: NumPy, which loads no kernel (about 2 ms at a kernel's first call in a
#: process, or its compile): a brute-force mesh compiles none of them.
GATHER_MIN = 1 << 15


#: The size (in float64s) from which NumPy asks for transparent huge pages: 4 MiB.
HUGE_PAGE_MIN = 1 << 19


@kernel()
def _empty(rows, columns):
    return np.empty((rows, columns))


def empty(rows, columns):
    """An uninitialised float64 array ``(rows, columns)`` for the build.

    Large ones come from Numba's allocator.  NumPy asks the kernel to back
    arrays of 4 MiB and more with transparent huge pages, and where the
    kernel compacts memory to find them on demand, the first writes to
    such an array can stall for a quarter of a second.
    """
    if rows * columns < HUGE_PAGE_MIN:
        return np.empty((rows, columns))
    return _empty(rows, columns)


@kernel(parallel=True)
def _take_rows(source, rows, out):
    for m in prange(rows.shape[0]):
        k = rows[m]
        for c in range(source.shape[1]):
            out[m, c] = source[k, c]


def take_rows(source, rows):
    """``source[rows]`` for a 2D float64 ``source``, as a new C-contiguous array."""
    if len(rows) < GATHER_MIN:
        return np.ascontiguousarray(source[rows])
    out = empty(len(rows), source.shape[1])
    _take_rows(_readonly(source, np.float64), _readonly(rows, np.int64), out)
    return out


@inline
def _face_params(vertices, faces, order, params, j):
    k = order[j]
    for v in range(3):
        i = faces[k, v]
        for a in range(3):
            params[j, 3 * v + a] = vertices[i, a]
    params[j, 9] = 0.0


@kernel(parallel=True)
def _triangle_params(vertices, faces, order, params):
    for j in prange(order.shape[0]):
        _face_params(vertices, faces, order, params, np.int64(j))


def triangle_params(vertices, faces, order=None):
    """The parameters ``(F, 10)`` of the triangles ``faces`` of ``vertices``
    (those ``faces[order]``, if given): each face's nine coordinates, then
    a zero."""
    if order is None and len(faces) < GATHER_MIN:
        params = np.empty((len(faces), N_PARAMS))
        # Gathered straight into the rows; the faces index the vertices.
        np.take(vertices, faces, axis=0, out=params[:, :9].reshape(-1, 3, 3), mode="clip")
        params[:, 9] = 0.0
        return params
    order = np.arange(len(faces)) if order is None else order
    params = empty(len(order), N_PARAMS)
    _triangle_params(
        _readonly(vertices, np.float64), _readonly(faces, np.int64), _readonly(order, np.int64), params
    )
    return params


def assemble(kinds, params, index, child, count, depth, cull=None):
    """The :class:`Tree` of primitives already in leaf order, over the nodes ``child``, ``count``.

    ``cull`` is :func:`primitive_cull`'s ``(tight, loose)`` in that order,
    computed here when not given; the node bounds are fitted to them.
    """
    tight, loose = primitive_cull(kinds, params) if cull is None else cull
    kinds = _readonly(kinds, np.int8)
    params = _readonly(params, np.float64)
    child = _readonly(child, np.int64)
    count = _readonly(count, np.int64)
    tight_ro = _readonly(tight, np.float64)
    bounds = _readonly(refit(child, count, kinds, params, tight_ro), np.float64)
    if loose is tight:
        loose_ro, loose_bounds = tight_ro, bounds
    else:
        loose_ro = _readonly(loose, np.float64)
        loose_bounds = _readonly(refit(child, count, kinds, params, loose_ro), np.float64)
    return Tree(
        kinds=kinds,
        params=params,
        index=_readonly(index, np.int64),
        child=child,
        count=count,
        bounds=bounds,
        cull=tight_ro,
        loose_bounds=loose_bounds,
        loose_cull=loose_ro,
        depth=int(depth),
    )


@inline
def _mix(x, word):
    """``x`` with the 64-bit ``word`` mixed in: by a multiplication, which
    carries low bits up, and a shift, which brings the high bits down again
    (a multiplication alone leaves the hash's low bits blind to the words'
    high bits, where floats that differ mostly differ)."""
    x = (x ^ word) * np.uint64(0x9E3779B97F4A7C15)
    return x ^ (x >> np.uint64(32))


@kernel()
def _row_hashes(kinds, bits):
    """A 64-bit hash of each primitive's kind and parameter bits."""
    n = bits.shape[0]
    h = np.empty(n, np.uint64)
    for k in range(n):
        x = np.uint64(kinds[k])
        for c in range(bits.shape[1]):
            x = _mix(x, bits[k, c])
        h[k] = x
    return h


@inline
def _face_row(vertices, bits, faces, k, cull, hashes):
    i, j, m = faces[k, 0], faces[k, 1], faces[k, 2]
    _triangle_row(
        cull, k, vertices[i, 0], vertices[i, 1], vertices[i, 2], vertices[j, 0], vertices[j, 1],
        vertices[j, 2], vertices[m, 0], vertices[m, 1], vertices[m, 2],
    )  # fmt: skip
    # The hash of the face's parameters (kind 0, nine coordinates, a zero).
    x = np.uint64(TRIANGLE)
    for v in range(3):
        for a in range(3):
            x = _mix(x, bits[faces[k, v], a])
    hashes[k] = _mix(x, np.uint64(0))


@kernel(parallel=True)
def _face_rows(vertices, faces, cull, hashes):
    """:func:`primitive_cull` and :func:`_row_hashes` of the triangles
    ``faces`` of ``vertices``, in one pass over the faces."""
    bits = vertices.view(np.uint64)
    for k in prange(faces.shape[0]):
        _face_row(vertices, bits, faces, np.int64(k), cull, hashes)


def _all_different(hashes):
    """Whether the hashes, which it sorts in place, are all different."""
    hashes.sort()
    return len(hashes) < 2 or bool((hashes[1:] != hashes[:-1]).all())


def distinct(kinds, params):
    """Which primitives to store: all but exact copies (the same kind and the
    same bits) of a primitive with a lower index.

    A copy gives the same answer to every query, bit for bit, and loses
    every tie to the original, so it can never be the answer; stored, it
    would be visited at every tie (a mesh of many identical faces would
    visit them all for every point).
    """
    n = len(kinds)
    bits = params.view(np.uint64)
    keep = np.ones(n, np.bool_)
    # Distinct hashes, the usual case, are seen by a sort of the hashes
    # alone, several times faster than the stable sort of their order.
    if _all_different(_row_hashes(kinds, bits)):
        return keep
    h = _row_hashes(kinds, bits)
    order = np.argsort(h, kind="stable")
    sorted_h = h[order]
    starts = np.concatenate([[True], sorted_h[1:] != sorted_h[:-1]])
    # The first of each run of equal hashes has the lowest index (the sort is
    # stable); a later row that equals it bit for bit is a copy.
    later = np.flatnonzero(~starts)
    if len(later):
        first = order[np.maximum.accumulate(np.where(starts, np.arange(n), 0))[later]]
        rows = order[later]
        same = (bits[rows] == bits[first]).all(axis=1) & (kinds[rows] == kinds[first])
        keep[rows[same]] = False
    return keep


def brute(kinds, params):
    """The broad phase of no hierarchy: one leaf holding every primitive, in order.

    Parameters
    ----------
    kinds : ndarray of int8, shape ``(n,)``, n >= 1
    params : ndarray of float64, shape ``(n, 10)``

    Returns
    -------
    Tree
    """
    n = len(kinds)
    return assemble(kinds, params, np.arange(n), _readonly([0], np.int64), _readonly([n], np.int64), 0)


def build(kinds, params, leaf_size=LEAF_SIZE):
    """A bounding-volume hierarchy over the primitives, built once.

    Parameters
    ----------
    kinds : ndarray of int8, shape ``(n,)``, n >= 1
    params : ndarray of float64, shape ``(n, 10)``
    leaf_size : int
        Most primitives a leaf holds.

    Returns
    -------
    Tree
    """
    keep = distinct(kinds, params)
    kept = np.flatnonzero(keep)
    if len(kept) < len(kinds):
        kinds, params = kinds[kept], take_rows(params, kept)
    tight, loose = primitive_cull(kinds, params)
    # The build puts the rows of ``tight`` in leaf order; the others follow.
    child, count, order, depth = _build(tight, int(leaf_size))
    loose = tight if loose is tight else take_rows(loose, order)
    index = order if len(kept) == len(keep) else kept[order]
    kinds, params = kinds[order], take_rows(params, order)
    return assemble(kinds, params, index, child, count, depth, (tight, loose))


def build_mesh(vertices, faces, leaf_size=LEAF_SIZE):
    """:func:`build` for the triangles ``faces`` of ``vertices`` (indices
    into it), without their parameters in the faces' order: the faces'
    boxes, slabs and hashes come from the vertices in one pass, and their
    parameters are gathered once, in leaf order."""
    vertices = _readonly(vertices, np.float64)
    faces = _readonly(faces, np.int64)
    n = len(faces)
    cull = empty(n, 11)
    hashes = np.empty(n, np.uint64)
    _face_rows(vertices, faces, cull, hashes)
    kinds = np.zeros(n, np.int8)
    if not _all_different(hashes):
        return build(kinds, triangle_params(vertices, faces), leaf_size)
    child, count, order, depth = _build(cull, int(leaf_size))
    params = triangle_params(vertices, faces, order)
    return assemble(kinds, params, order, child, count, depth, (cull, cull))


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


@functools.cache
def query_kernel(method, rounds):
    """The compiled traversal of ``method`` (a :class:`~proximity.methods.Method`),
    for trees of triangles alone or (``rounds``) with disks and circles."""
    name = method.name
    tag = name if rounds else f"{name}_triangles"
    evaluate = specialize(
        _evaluate,
        tag,
        role="inline",
        TRIANGLE_QUERY=point_triangle.KERNELS[name][0],
        ROUND_QUERY=point_disk.KERNELS[name][0],
        ROUNDS=rounds,
    )
    interval = specialize(_interval, "rounds" if rounds else "triangles", role="inline", ROUNDS=rounds)
    block = specialize(
        _nearest_block,
        tag,
        _BLOCK_SIGNATURE,
        role="pointer",
        EVALUATE=evaluate,
        INTERVAL=interval,
        EXACT_FALLBACK=method.exact_fallback,
        SEED_POINT=not method.loose,
    )
    loop = specialize(_nearest, "blocks", _QUERY_SIGNATURE, parallel=True)
    return functools.partial(loop, address(block, _BLOCK_SIGNATURE))


def nearest(tree, method, points, full, loose=False):
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

    Returns
    -------
    dict of ndarray
        ``distance``, ``sqr_distance``, ``point``, ``feature``, ``extra``
        (barycentric, or height and radial), ``flag`` (equidistant) and
        ``index`` (the caller's index of the nearest primitive, -1 for none);
        all but ``distance`` empty unless ``full``.
    """
    points = _readonly(points, np.float64)
    n = points.shape[0]
    m = n if full else 0
    out = dict(
        distance=np.empty(n),
        sqr_distance=np.empty(m),
        point=np.empty((m, 3)),
        feature=np.empty(m, np.int8),
        extra=np.empty((m, 3)),
        flag=np.empty(m, np.bool_),
        index=np.empty(m, np.int64),
    )
    undecided = np.empty(n)
    bounds, cull, magnitude = tree.boxes(loose)
    order = _readonly(_visiting_order(points), np.int64)
    # Work per point varies by orders of magnitude (a point at the center of
    # a sphere is equidistant from every face), so blocks are handed out
    # one at a time rather than split evenly between threads up front.
    with numba.parallel_chunksize(1):
        query_kernel(method, tree.rounds)(
            tree.kinds,
            tree.params,
            tree.index,
            cull,
            bounds,
            tree.child,
            tree.count,
            tree.depth,
            magnitude,
            points,
            order,
            *out.values(),
            undecided,
            full,
        )
    rows = np.flatnonzero(~np.isnan(undecided))
    if len(rows):
        _resolve(tree, rows, points, undecided, out, full, cull, bounds, magnitude)
    return out


def _resolve(tree, rows, points, undecided, out, full, cull, bounds, magnitude):
    """Finish rows whose nearest primitive may be an undecided certified answer.

    Every candidate within the row's bound goes through the per-shape
    ``certified`` query, which runs the exact fallback where needed, so each
    answer is the one a single-shape query gives; the least wins, ties to
    the lowest index.
    """
    method = methods.CERTIFIED
    kinds_params = {
        TRIANGLE: lambda q, p: point_triangle.query(method, q[:, :9].reshape(-1, 3, 3), p, (len(q),), True),
        DISK: lambda q, p: point_disk.query(
            method, True, q[:, 0:3], q[:, 3:6], q[:, 6:9], q[:, 9], p, (len(q),), True
        ),
        CIRCLE: lambda q, p: point_disk.query(
            method, False, q[:, 0:3], q[:, 3:6], q[:, 6:9], q[:, 9], p, (len(q),), True
        ),
    }
    positions = np.empty(len(tree.kinds), np.int64)
    for i in rows:
        p = points[i]
        bound = undecided[i]
        found = _gather(cull, bounds, tree.child, tree.count, tree.depth, magnitude, p, bound, positions)
        candidates = positions[:found]
        answers = []  # (distance, caller's index, kind, the per-shape outputs, row)
        for code, query in kinds_params.items():
            chosen = candidates[tree.kinds[candidates] == code]
            if len(chosen) == 0:
                continue
            r = query(tree.params[chosen], p)
            for j, idx in enumerate(tree.index[chosen]):
                if not np.isnan(r["distance"][j]):
                    answers.append((float(r["distance"][j]), int(idx), code, r, j))
        if not answers:
            continue
        d, idx, code, r, j = min(answers, key=lambda a: (a[0], a[1]))
        out["distance"][i] = d
        if full:
            out["sqr_distance"][i] = r["sqr_distance"][j]
            out["point"][i] = r["point"][j]
            out["feature"][i] = r["feature"][j]
            out["index"][i] = idx
            if code == TRIANGLE:
                out["extra"][i] = r["barycentric"][j]
                out["flag"][i] = False
            else:
                out["extra"][i] = (r["height"][j], r["radial"][j], np.nan)
                out["flag"][i] = bool(r["equidistant"][j]) if code == CIRCLE else False
