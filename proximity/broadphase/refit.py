"""Node bounds, fitted to the primitives below each node.

Each node has its box and an oriented box (three slabs); the pruning tests
that read them, and why they never change an answer, are in
:mod:`.bounds`.
"""

import dataclasses
import functools
import math

import numpy as np

from .. import primitives
from ..runtime import pool, threads
from ..runtime.jit import inline, kernel, specialize, spliced
from ._alloc import INDEX, empty, empty_ints, readonly, take_rows_into
from .bounds import CULL_COLUMNS, FACE_COLUMNS, plane_row

#: Each primitive kind's number of points it is the hull of, by code.
_VERTICES = primitives.vertex_counts()
N_PARAMS = primitives.N_PARAMS


#: Nodes over at most this many primitives are refitted subtree by subtree
#: (:func:`refit_faces`), while the subtree's primitives are in cache.
REFIT_SUBTREE = 8192


@spliced
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


@spliced
def _refit_top(child, count, top, tasks, start, end):
    """The tasks of :func:`fit_indexed`: ``(n_top, n_tasks)``, the first entries of
    ``top`` and ``tasks`` set.

    ``top`` are the nodes over more than :data:`REFIT_SUBTREE` primitives,
    a node before its children; ``tasks`` the roots of the subtrees below
    them (the root itself when it is no larger).  ``start`` and ``end``
    are arrays over every node, set here for those: node ``i`` holds
    stored primitives ``start[i] .. end[i] - 1``.
    """
    m = child.shape[0]
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
    return n_top, n_tasks


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


@spliced
def _merge_leaf(bounds, i, first, last, kinds, params, cull, normals, vertices):
    """Leaf ``i``'s box and normal sum (columns 6-8) over its stored
    primitives ``first .. last - 1``: the extremes of the points of those
    that are hulls of points (their cull rows' boxes, exactly, where they
    are not rounded), the boxes of the ``cull`` rows of the others; the
    normals of their ``normals`` rows (the tree's float32 ones, which a
    tree of hulls alone keeps instead of its float64 ``cull`` rows)."""
    rounded = params.shape[1] > N_PARAMS
    for a in range(3):
        bounds[i, a] = math.inf
        bounds[i, 3 + a] = -math.inf
        bounds[i, 6 + a] = 0.0
    for k in range(first, last):
        n = vertices[kinds[k]]
        if n > 0 and not rounded:
            for c in range(n):
                for a in range(3):
                    bounds[i, a] = min(bounds[i, a], params[k, 3 * c + a])
                    bounds[i, 3 + a] = max(bounds[i, 3 + a], params[k, 3 * c + a])
        else:
            for a in range(3):
                bounds[i, a] = min(bounds[i, a], cull[k, a])
                bounds[i, 3 + a] = max(bounds[i, 3 + a], cull[k, 3 + a])
        for a in range(3):
            bounds[i, 6 + a] += normals[k, 6 + a]


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


@spliced
def _across(ux, uy, uz):
    """Two vectors ``v``, ``w`` that make with ``u`` an orthogonal frame of
    vectors no longer than 1 (zero where ``u`` is zero).

    ``v`` is ``u`` with its smallest component zeroed and the other two
    swapped, one negated, which is perpendicular to ``u`` exactly; ``w`` is
    ``u x v``.  Both are normalised and shortened as ``u`` is (see
    :func:`_frame`), which leaves the frame's rounding far inside
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
def _ranges(bounds, i, first, last, kinds, params, cull, vertices):
    """The ranges of node ``i``'s three slabs over stored primitives ``first .. last - 1``.

    A primitive that is the hull of points (``vertices[kind]`` of them, at
    the start of its row) counts by its points, widened by its radius
    where it is rounded (rows wider than ``N_PARAMS``: the axes are no
    longer than 1), any other by the eight corners of its box (widened
    already).
    """
    rounded = params.shape[1] > N_PARAMS
    ux, uy, uz = bounds[i, 6], bounds[i, 7], bounds[i, 8]
    vx, vy, vz = bounds[i, 11], bounds[i, 12], bounds[i, 13]
    wx, wy, wz = bounds[i, 16], bounds[i, 17], bounds[i, 18]
    lu, hu = math.inf, -math.inf
    lv, hv = math.inf, -math.inf
    lw, hw = math.inf, -math.inf
    for k in range(first, last):
        n = vertices[kinds[k]]
        grow = params[k, N_PARAMS] * (1.0 + 2.0**-50) if rounded and n > 0 else 0.0
        for c in range(n if n > 0 else 8):
            if n > 0:
                x, y, z = params[k, 3 * c], params[k, 3 * c + 1], params[k, 3 * c + 2]
            else:
                x = cull[k, 3 if c & 1 else 0]
                y = cull[k, 4 if c & 2 else 1]
                z = cull[k, 5 if c & 4 else 2]
            h = ux * x + uy * y + uz * z
            lu, hu = min(lu, h - grow), max(hu, h + grow)
            h = vx * x + vy * y + vz * z
            lv, hv = min(lv, h - grow), max(hv, h + grow)
            h = wx * x + wy * y + wz * z
            lw, hw = min(lw, h - grow), max(hw, h + grow)
    for c, low, high in ((9, lu, hu), (14, lv, hv), (19, lw, hw)):
        finite = math.isfinite(low) and math.isfinite(high)
        bounds[i, c] = low if finite else -math.inf
        bounds[i, c + 1] = high if finite else math.inf


@spliced
def _subtree_nodes(root, start, end, child, count):
    """``(nodes, n)``: the ``n`` nodes of the subtree at ``root``, each before
    its descendants (``start[root]``, ``end[root]`` its range of primitives)."""
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
    return nodes, n


@inline
def _box_range(bounds, c, ax, ay, az):
    """The range of ``a . X`` over node ``c``'s box."""
    lo, hi = 0.0, 0.0
    for d, a in ((0, ax), (1, ay), (2, az)):
        if a >= 0.0:
            lo += a * bounds[c, d]
            hi += a * bounds[c, 3 + d]
        else:
            lo += a * bounds[c, 3 + d]
            hi += a * bounds[c, d]
    return lo, hi


@inline
def _oriented(bounds, c, e):
    """Node ``c``'s slab at column ``e`` as its axis over its squared length
    ``n`` (about 1), and its middle and half width: the oriented box's
    point ``X`` is ``sum (e . X) e / n``."""
    x, y, z = bounds[c, e], bounds[c, e + 1], bounds[c, e + 2]
    n = x * x + y * y + z * z
    return (
        x / n,
        y / n,
        z / n,
        (bounds[c, e + 3] + bounds[c, e + 4]) * 0.5,
        (bounds[c, e + 4] - bounds[c, e + 3]) * 0.5,
    )


@inline
def _ranges_merged(bounds, i, child):
    """The ranges of node ``i``'s three slabs from its children's: along
    each of its axes ``a``, the union over both children of the range of
    ``a . X`` over the child's box, narrowed by the range over its oriented
    box where its frame is set and its slabs are finite; widened by
    ``2^-36`` of node ``i``'s box's magnitude, far more than the rounding
    of the projections and the frames' departure from orthogonality (see
    :func:`refit_faces`)."""
    magnitude = 0.0
    for d in range(6):
        magnitude = max(magnitude, abs(bounds[i, d]))
    widen = magnitude * 2.0**-36
    lu, hu = math.inf, -math.inf
    lv, hv = math.inf, -math.inf
    lw, hw = math.inf, -math.inf
    for c in range(child[i], child[i] + 2):
        ux, uy, uz = bounds[c, 6], bounds[c, 7], bounds[c, 8]
        framed = ux * ux + uy * uy + uz * uz > 0.25
        # Columns as int64, not literals, so that _oriented compiles once.
        six = np.int64(6)
        e0, e1, e2 = _oriented(bounds, c, six), _oriented(bounds, c, six + 5), _oriented(bounds, c, six + 10)
        for axis in (6, 11, 16):
            ax, ay, az = bounds[i, axis], bounds[i, axis + 1], bounds[i, axis + 2]
            lo, hi = _box_range(bounds, c, ax, ay, az)
            if framed:
                centre, half = 0.0, 0.0
                for ex, ey, ez, middle, width in (e0, e1, e2):
                    along = ax * ex + ay * ey + az * ez
                    centre += along * middle
                    half += abs(along) * width
                if math.isfinite(centre) and math.isfinite(half):
                    lo = max(lo, centre - half)
                    hi = min(hi, centre + half)
            if axis == 6:
                lu, hu = min(lu, lo), max(hu, hi)
            elif axis == 11:
                lv, hv = min(lv, lo), max(hv, hi)
            else:
                lw, hw = min(lw, lo), max(hw, hi)
    for c, low, high in ((9, lu, hu), (14, lv, hv), (19, lw, hw)):
        finite = math.isfinite(low) and math.isfinite(high) and math.isfinite(widen)
        bounds[i, c] = low - widen if finite else -math.inf
        bounds[i, c + 1] = high + widen if finite else math.inf


@inline
def _gather_rows(vertices, faces, order, params, cull, first, last):
    """Rows ``first .. last - 1``: the coordinates of faces ``faces[order]``,
    then zeros, and their cull rows."""
    for k in range(first, last):
        f = order[k]
        for v in range(3):
            i = faces[f, v]
            for a in range(3):
                params[k, 3 * v + a] = vertices[i, a]
        for c in range(9, params.shape[1]):
            params[k, c] = 0.0
        p = params[k]
        plane_row(cull, k, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8])


@kernel()
def _gather_faces(vertices, faces, order, params, cull):
    """Every row of a tree of one leaf (see :func:`_gather_rows`)."""
    _gather_rows(vertices, faces, order, params, cull, 0, order.shape[0])


@spliced
def _indexed_rows(vertices, faces, first, last):
    """``(params, cull)`` of stored faces ``first .. last - 1`` of a tree of
    faces read through their vertices (:attr:`.tree.Tree.faces`), in new
    arrays: the faces' coordinates and their float64 cull rows."""
    params = np.empty((last - first, FACE_COLUMNS))
    cull = np.empty((last - first, CULL_COLUMNS))
    for k in range(first, last):
        r = k - first
        for v in range(3):
            i = faces[k, v]
            for a in range(3):
                params[r, 3 * v + a] = vertices[i, a]
        p = params[r]
        plane_row(cull, r, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8])
    return params, cull


#: The steps of :func:`_fit_indexed`.
_TASKS, _SUBTREES, _ABOVE, _ROOTS, _TOP = 0, 1, 2, 3, 4


#: Whether :func:`_fit_indexed` merges ranges (bound by :func:`_fit_kernel`).
MERGED = True


def _fit_indexed(
    step, lo, hi, most, vertices, faces, bounds, top, tasks, start, end, child, count, kinds, hull
):  # fmt: skip
    """One step of :func:`fit_indexed`, whose docstring says what each does:
    ``(n_top, n_tasks)`` for ``_TASKS`` (:func:`_refit_top`), zeros for the others.

    One kernel, with one call of each helper (spliced into it, or compiled
    once for it), so that a first build compiles each once: every step but
    the first goes through the one loop, over the subtrees' roots or the
    nodes above them, and takes its part of it.  Compiled twice
    (:func:`_fit_kernel`): with merged ranges (``MERGED``), and without,
    for a fit whose every node's ranges are exact, which a first build of
    a small mesh then compiles alone.
    """
    if step == _TASKS:
        return _refit_top(child, count, top, tasks, start, end)
    whole = step == _SUBTREES
    # The subtrees' roots (_SUBTREES, _ROOTS), or the nodes above them,
    # children first (_ABOVE, _TOP).
    roots = tasks[lo:hi] if whole or step == _ROOTS else top[::-1]
    for j in range(roots.shape[0]):
        root = roots[j]
        # The rows of the faces whose points the step reads: the subtree's,
        # or those of a node with exact ranges, or none.
        first, last = start[root], end[root]
        if not whole and (step == _ABOVE or (count[root] == 0 and last - first > most)):
            last = first
        params, cull = _indexed_rows(vertices, faces, first, last)
        if whole:
            nodes, n = _subtree_nodes(root, start, end, child, count)
        else:
            nodes, n = np.empty(1, np.int64), 1
            nodes[0] = root
        # Boxes and normal sums from the leaves up (_SUBTREES: every node
        # of the subtree; _ABOVE: the node), then, children first, frames
        # and ranges (_SUBTREES: the subtree's nodes but its root, whose
        # frame would overwrite the sum the nodes above read; _ROOTS, _TOP:
        # the node).
        boxes = whole or step == _ABOVE
        for t in range(n - 1 if boxes else -1, -1, -1):
            i = nodes[t]
            if count[i] > 0:
                start[i] = child[i]
                end[i] = child[i] + count[i]
                rows, a, b = cull, start[i] - first, end[i] - first
            else:
                start[i] = start[child[i]]
                end[i] = end[child[i] + 1]
                rows, a, b = bounds, np.int64(child[i]), np.int64(child[i] + 2)
            _merge(bounds, i, rows, a, b)
        frames = 0 if whole else (-1 if step != _ABOVE else n - 1)
        for t in range(n - 1, frames, -1):
            # The node's frame, and its ranges: exact for a leaf and a node
            # over at most ``most`` faces, its children's otherwise.
            i = nodes[t]
            _frame(bounds, i)
            if count[i] > 0 or end[i] - start[i] <= most:
                _ranges(bounds, i, start[i] - first, end[i] - first, kinds[first:last], params, cull, hull)
            elif MERGED:
                _ranges_merged(bounds, i, child)
    return 0, 0


#: Subtrees' roots per call of the roots' step of :func:`fit_indexed`.
_ROOTS_CHUNK = 64


def fit_indexed(vertices, faces, bounds, child, count, kinds, most):
    """The bounds ``bounds`` (``(m, NODE_COLUMNS)``) of the nodes of a tree
    of faces read through their vertices, fitted to its faces ``faces``
    (each one's three rows of ``vertices``, the tree's, in its order).

    The subtrees' roots and the nodes above them first (``_TASKS``,
    :func:`_refit_top`).  Each face's float64 row and cull row are
    computed from its vertices (:func:`_indexed_rows`) for one subtree of
    at most :data:`REFIT_SUBTREE` faces at a time, and the subtree's nodes
    fitted while its rows are in cache, on the threads (``_SUBTREES``);
    then the boxes and normal sums of the nodes above the subtrees
    (``_ABOVE``), the subtrees' roots' frames and ranges (``_ROOTS``: a
    root's frame overwrites its sum, which the nodes above read first) and
    the nodes above (``_TOP``, children first).  Slab ranges are exact for
    the leaves and the nodes over at most ``most`` faces, merged from the
    children's above (see :func:`refit_indexed`); with ``most`` at least
    the number of faces, every node's are exact, and the fit's kernel is
    the one without merging.  Nothing is kept of the faces' rows.
    """
    m = len(child)
    # No node holds more than every face: then no range is merged.
    fit = _fit_kernel(most < len(faces))
    top, tasks, start, end = empty_ints(m), empty_ints(m), empty_ints(m), empty_ints(m)
    args = (most, vertices, faces, bounds, top, tasks, start, end, child, count, kinds, _VERTICES)
    n_top, n_tasks = fit(_TASKS, 0, 0, *args)
    top, tasks = top[:n_top], tasks[:n_tasks]
    args = (most, vertices, faces, bounds, top, tasks, start, end, child, count, kinds, _VERTICES)
    threads.spread(lambda lo, hi: fit(_SUBTREES, lo, hi, *args), len(tasks))
    fit(_ABOVE, 0, 0, *args)
    threads.spread(lambda lo, hi: fit(_ROOTS, lo, hi, *args), len(tasks), _ROOTS_CHUNK)
    fit(_TOP, 0, 0, *args)
    return bounds


@functools.cache
def _fit_kernel(merged):
    """:func:`_fit_indexed`, with merged ranges or without (every node's exact)."""
    return specialize(_fit_indexed, "merged" if merged else "exact", nogil=True, MERGED=merged)


#: The steps of :func:`_fit_step`.
_BOXES, _FRAMES, _MERGED = 0, 1, 2

#: Nodes over at most this many primitives get exact slab ranges at a
#: build (:func:`refit`, :func:`fit_indexed`); those above, their
#: children's merged.
EXACT_RANGES = 512
assert EXACT_RANGES <= REFIT_SUBTREE
#: A build of at most this many faces gives every node exact ranges
#: (:func:`build_ranges`): a millisecond or two more on 65,536 faces, and
#: a first build compiles no merging.
EXACT_TREE = 1 << 16


def build_ranges(n):
    """The ``most`` of :func:`fit_indexed` at a build of ``n`` faces: nodes
    over more faces get merged ranges (every node's exact up to
    :data:`EXACT_TREE` faces)."""
    return n if n <= EXACT_TREE else EXACT_RANGES


@kernel(nogil=True)
def _fit_step(step, lo, hi, most, bounds, start, end, child, count, kinds, params, cull, normals, vertices):
    """One step of :func:`refit`; one kernel for all, so that a first build compiles one.

    ``_BOXES``: every node's box and normal sum, and its range of stored
    primitives ``start[i] .. end[i] - 1``, from the last node back: the
    children of a node come after it (see :func:`~.build._build`), so they
    are done first.  ``_FRAMES``: the frames and exact slab ranges of the
    leaves and nodes ``lo .. hi - 1`` over at most ``most`` primitives.
    ``_MERGED``: the frames of the other nodes, and their ranges from their
    children's (:func:`_ranges_merged`), from the last node back.
    """
    if step == _BOXES:
        for i in range(child.shape[0] - 1, -1, -1):
            if count[i] > 0:
                start[i] = child[i]
                end[i] = child[i] + count[i]
                _merge_leaf(bounds, i, start[i], end[i], kinds, params, cull, normals, vertices)
            else:
                start[i] = start[child[i]]
                end[i] = end[child[i] + 1]
                _merge(bounds, i, bounds, np.int64(child[i]), child[i] + 2)
    elif step == _FRAMES:
        for i in range(lo, hi):
            if count[i] > 0 or end[i] - start[i] <= most:
                _frame(bounds, i)
                _ranges(bounds, i, start[i], end[i], kinds, params, cull, vertices)
    else:
        for i in range(child.shape[0] - 1, -1, -1):
            if count[i] == 0 and end[i] - start[i] > most:
                _frame(bounds, i)
                _ranges_merged(bounds, i, child)


#: Ranges of nodes per thread of the frames' step of :func:`refit`.
_FRAME_RANGES_PER_THREAD = 8


def refit(child, count, kinds, params, cull, normals=None):
    """Node boxes and slabs, ``(m, NODE_COLUMNS)``, over the stored primitives.

    ``cull`` are their cull rows, whose boxes bound the primitives that are
    not unrounded hulls of points (those are bounded by their points);
    ``normals`` the rows whose slab axes are summed into the nodes' ``u``
    (``cull`` unless given: a tree passes its float32 rows, the same
    whether it was built or unpickled).

    Each node has its box ``(lo, hi)`` and an oriented box, as three slabs
    ``(axis, h_min, h_max)``: ``u`` is the normalised sum of the primitives'
    slab directions (their normals), shortened by ``2^-40``, and ``v``,
    ``w`` complete it to an orthogonal frame (:func:`_across`); each range
    is that of ``axis . X`` over the points of primitives that are hulls of
    points and over the corners of the other primitives' boxes, and an
    overflowing range is unbounded.  A flat patch of faces gets a thin
    box along its normal and a tight one across it, which prunes where the
    axis-aligned box alone would not (a point over a tilted patch, or near
    the center of a sphere).

    The boxes in one pass from the leaves up; the frames and ranges, a node
    at a time, on the threads, in ranges of nodes of about equal numbers of
    primitives.  Exact ranges cost O(primitives) per level of the tree; a
    refit (:func:`refit_faces`) merges them instead.
    """
    normals = cull if normals is None else normals
    if len(child) == 1:
        # One leaf (brute force): the traversal goes straight to its
        # primitives and never tests its bounds, which need only its box,
        # the scale of the pruning tests; the slabs bound nothing.
        bounds = np.zeros((1, NODE_COLUMNS))
        bounds[0, 0:6] = _leaf_box(kinds, params, cull)
        bounds[0, 9::5] = -math.inf
        bounds[0, 10::5] = math.inf
        return bounds
    m = len(child)
    bounds = empty(m, NODE_COLUMNS)
    start, end = empty_ints(m), empty_ints(m)
    params = readonly(params, np.float64)
    cull, normals = readonly(cull, cull.dtype), readonly(normals, normals.dtype)
    tree = (start, end, child, count, kinds, params, cull, normals, _VERTICES)
    most = EXACT_RANGES
    _fit_step(_BOXES, 0, 0, most, bounds, *tree)
    # A node's frame and exact ranges cost one pass over its primitives:
    # ranges of nodes cut at about equal sums of those (the root alone may be one).
    sizes = end - start
    cost = np.cumsum(np.where((count > 0) | (sizes <= most), sizes, 0))
    pieces = _FRAME_RANGES_PER_THREAD * threads.current()
    cuts = np.searchsorted(cost, cost[-1] * np.arange(1, pieces) / pieces, side="right")
    cuts = np.unique(np.concatenate([[0], cuts, [m]]))
    threads.spread(lambda lo, hi: _fit_step(_FRAMES, cuts[lo], cuts[hi], most, bounds, *tree), len(cuts) - 1)
    if count[0] == 0 and sizes[0] > most:
        _fit_step(_MERGED, 0, 0, most, bounds, *tree)
    return bounds


def _leaf_box(kinds, params, cull):
    """The box ``(lo, hi)`` of every stored primitive, as :func:`_merge_leaf` bounds them."""
    lo, hi = np.full(3, math.inf), np.full(3, -math.inf)
    rounded = params.shape[1] > N_PARAMS
    for p in primitives.present(kinds):
        rows = kinds == p.code
        if p.vertices and not rounded:
            points = params[rows, : 3 * p.vertices].reshape(-1, 3)
            lo, hi = np.minimum(lo, points.min(axis=0)), np.maximum(hi, points.max(axis=0))
        else:
            lo = np.minimum(lo, cull[rows, 0:3].min(axis=0))
            hi = np.maximum(hi, cull[rows, 3:6].max(axis=0))
    return np.concatenate([lo, hi])


def refit_faces(vertices, faces, order, child, count, kinds):
    """``(params, cull, bounds)`` of a tree of one leaf (brute force) whose
    faces' vertices moved: the rows of ``faces[order]`` of ``vertices``, their
    cull rows and the leaf's bounds (see :func:`refit_indexed` for trees of
    more nodes)."""
    params = pool.empty((len(order), FACE_COLUMNS))
    cull = pool.empty((len(order), CULL_COLUMNS))
    vertices, faces, order = (
        readonly(vertices, np.float64),
        readonly(faces, np.int64),
        readonly(order, INDEX),
    )
    _gather_faces(vertices, faces, order, params, cull)
    return params, cull, refit(child, count, kinds, params, cull)


def refit_indexed(vertices, tree):
    """The tree of faces read through their vertices ``tree`` (of more than
    one node) over the moved ``vertices`` (the mesh's, in its order): the
    same nodes and faces, the nodes' bounds fitted to the faces in one pass
    per subtree while its faces are in cache; the faces' rows are held for
    one subtree at a time, never for the whole tree.

    Only the leaves' slab ranges are exact; a node above them takes the
    union of its children's ranges along its axis, each child's from its
    box narrowed by its oriented box (:func:`_ranges_merged`), which costs
    O(nodes) rather than O(primitives) per level, and is looser where the
    children's frames turn away from the node's.  Such a range holds
    everything below: the oriented box's corners ``sum h_e e / |e|^2`` are
    exact for orthogonal axes, the frames depart from orthogonality by a
    few ``eps`` and the projections round by a few ``eps`` of the box's
    magnitude, which the ``2^-36`` widening covers many times over.
    """
    # On recycled memory (:mod:`proximity.runtime.pool`): a refit per frame writes
    # over the memory of the frame before, once that mesh is gone, rather than
    # the system's fresh pages, whose first writes cost as much as the refit.
    sources = readonly(tree.sources, np.int64)
    rows = pool.empty((len(sources), 3))
    take_rows_into(readonly(vertices, np.float64), sources, rows)
    bounds = pool.empty((len(tree.child), NODE_COLUMNS))
    rows = readonly(rows, np.float64)
    fit_indexed(rows, tree.faces, bounds, tree.child, tree.count, tree.kinds, 0)
    bounds = readonly(bounds, np.float64)
    return dataclasses.replace(tree, bounds=bounds, loose_bounds=bounds, vertices=rows)
