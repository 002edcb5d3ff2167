"""The build: a bounding-volume hierarchy over a collection's primitives.

Hierarchy
---------
Built once, on primitive boxes, by binned surface-area heuristic (``BINS``
bins on the centroids along their longest axis, splitting until a node holds at most
``LEAF_SIZE`` primitives; nodes whose centroids coincide are cut in half by
index).  The children of a node are adjacent in memory and come after it:
the large nodes breadth first, then the subtree of each small one in a
block of its own (see :func:`_build`).

Brute force is the hierarchy of a single leaf holding every primitive in
index order (:func:`brute`).  Exact copies of a primitive are not stored
(:func:`distinct`).
"""

import math

import numpy as np

from .. import primitives
from ..runtime import threads
from ..runtime.jit import inline, kernel, spliced
from ._alloc import GATHER_MIN, INDEX, check_size, empty, empty_ints, indices, readonly, take_rows
from .bounds import CULL_COLUMNS, FACE_COLUMNS, plane_row, primitive_cull, stored_cull
from .refit import NODE_COLUMNS, build_ranges, fit_indexed, refit, refit_faces, refit_indexed
from .tree import Tree

LEAF_SIZE = 4
#: Most primitives a leaf holds in a tree over at least :data:`LARGE_TREE`
#: primitives (see :func:`default_leaf_size`).
LARGE_LEAF_SIZE = 16
LARGE_TREE = 1 << 19
BINS = 16


def default_leaf_size(n):
    """Most primitives a leaf holds in a tree over ``n`` primitives.

    Leaves of up to :data:`LEAF_SIZE` give about 0.62 nodes a primitive;
    leaves of up to :data:`LARGE_LEAF_SIZE`, 0.17, which is about 78 bytes a face
    fewer of node bounds and topology, and a faster build.  The finer tree
    prunes better where many faces are near a point's distance (points far
    from the surface), which pays on trees that stay in cache; on large ones
    the smaller tree is read from memory faster than the finer one prunes,
    and the robust search answers a leaf's faces side by side, four at a
    time (``docs/performance.md``, "Memory of a mesh", has the
    measurements).
    """
    return LARGE_LEAF_SIZE if n >= LARGE_TREE else LEAF_SIZE


@inline
def _centroid(rows, j, a):
    # Halves first: the sum of two coordinates near 1e308 would overflow.
    return rows[j, a] * 0.5 + rows[j, 3 + a] * 0.5


@inline
def _centre(rows, j):
    """The three coordinates of :func:`_centroid`: one compile, where calls
    with the constants 0, 1 and 2 would compile one per constant."""
    return (
        rows[j, 0] * 0.5 + rows[j, 3] * 0.5,
        rows[j, 1] * 0.5 + rows[j, 4] * 0.5,
        rows[j, 2] * 0.5 + rows[j, 5] * 0.5,
    )


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
    axis = np.int64(-1)  # not the constant -1, which would compile a variant of _centroid for it
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
            x, y, z = _centre(rows, j)
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
            x, y, z = _centre(rows, lo_j)
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


@spliced
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


@spliced
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


#: The steps of :func:`_build_step`.
_ROOT, _LEVEL, _SUBTREES, _NUMBER = 0, 1, 2, 3


@kernel(nogil=True)
def _build_step(
    step, lo, hi, nodes, firsts, rows, order, child, count, cmin, cmax,
    block_child, block_count, leaf_size, made, below, out_child, out_count,
):  # fmt: skip
    """One step of :func:`_build`, on the tasks ``lo .. hi - 1``; one kernel
    for every step, so that a first build compiles one.

    ``_ROOT``: the rows' order and the root's centroid bounds.  ``_LEVEL``:
    :func:`_split` of the nodes ``nodes[lo:hi]`` into the nodes at
    ``firsts[lo:hi]``.  ``_SUBTREES``: :func:`_split_subtree` of each node
    ``nodes[lo:hi]``, in the block of nodes at twice its first row, with
    scratch bounds; its number of nodes and depth to ``made`` and
    ``below``.  ``_NUMBER``: the blocks of those nodes copied into the
    tree, from the nodes ``firsts[lo:hi]`` on (:func:`_number_block`).
    """
    if step == _ROOT:
        for j in range(order.shape[0]):
            order[j] = j
        for a in range(3):
            cmin[0, a] = math.inf
            cmax[0, a] = -math.inf
        for j in range(rows.shape[0]):
            for a in range(3):
                cmin[0, a] = min(cmin[0, a], _centroid(rows, j, a))
                cmax[0, a] = max(cmax[0, a], _centroid(rows, j, a))
    elif step == _LEVEL:
        bins = np.empty((BINS, 9))
        for t in range(lo, hi):
            _split(nodes[t], firsts[t], child, count, rows, order, cmin, cmax, np.int64(0), bins)
    elif step == _SUBTREES:
        scratch_min = np.empty((2 * BUILD_SUBTREE, 3))
        scratch_max = np.empty((2 * BUILD_SUBTREE, 3))
        bins = np.empty((BINS, 9))
        for r in range(lo, hi):
            i = nodes[r]
            base = 2 * child[i]
            block_child[base] = child[i]
            block_count[base] = count[i]
            for a in range(3):
                scratch_min[0, a] = cmin[i, a]
                scratch_max[0, a] = cmax[i, a]
            made[r], below[r] = _split_subtree(
                base, block_child, block_count, rows, order, scratch_min, scratch_max, bins, leaf_size
            )
    else:
        for r in range(lo, hi):
            _number_block(nodes[r], made[r], firsts[r], child, block_child, block_count, out_child, out_count)


def _build(rows, leaf_size):
    """Topology of a hierarchy over the boxes ``rows[:, 0:3]`` (low corners)
    and ``rows[:, 3:6]`` (high corners), n >= 1 rows, whose rows it puts in
    leaf order (every column, in place).

    Returns ``(child, count, order, depth)``: the nodes as in
    :func:`_nearest`, ``order[j]`` the primitive now at row ``j``, and the
    largest depth of a leaf.

    Binned SAH.  Nodes over more than :data:`BUILD_SUBTREE` primitives (and
    more than ``leaf_size``) are split one level of the tree at a time, the
    nodes of a level side by side, each on its own contiguous rows, and
    numbered breadth first.  Each smaller node is then split down to its
    leaves as one task, in a scratch block of nodes that its rows index (a
    node over rows ``s .. s + c - 1`` has at most ``2 c - 1`` nodes in its
    subtree, so the block at ``2 s`` is its own).  Its descendants are then
    numbered after the large nodes, block after block: a node's children
    are adjacent and come after it.

    The steps are one serial kernel (:func:`_build_step`), run side by side
    on Python threads (:func:`proximity.runtime.threads.spread`): a kernel of
    parallel loops takes seconds longer to compile, at the first build on
    a machine.
    """
    leaf_size = np.int64(leaf_size)
    n = rows.shape[0]
    cap = 2 * n - 1
    # Every entry is written before it is read.
    child, count, order = empty_ints(cap), empty_ints(cap), empty_ints(n)
    cmin, cmax = empty(cap, 3), empty(cap, 3)
    none = np.empty(0, np.int64)

    def run(step, nodes, firsts, lo, hi, blocks=(none, none), made=none, below=none, out=(none, none)):
        _build_step(
            step, lo, hi, nodes, firsts, rows, order, child, count, cmin, cmax,
            *blocks, leaf_size, made, below, *out,
        )  # fmt: skip

    run(_ROOT, none, none, 0, 0)
    child[0] = 0
    count[0] = n
    large = max(leaf_size, BUILD_SUBTREE)
    n_nodes = 1
    begin = 0
    while begin < n_nodes:
        nodes = begin + np.flatnonzero(count[begin:n_nodes] > large)
        firsts = n_nodes + 2 * np.arange(len(nodes), dtype=np.int64)
        begin, n_nodes = n_nodes, n_nodes + 2 * len(nodes)
        threads.spread(
            lambda lo, hi, nodes=nodes, firsts=firsts: run(_LEVEL, nodes, firsts, lo, hi), len(nodes)
        )
    # The depth of each of those nodes (a node comes before its children),
    # and the ones left to split.
    top_child, top_count = child[:n_nodes], count[:n_nodes]
    level = np.zeros(n_nodes, np.int64)
    for k in np.flatnonzero(top_count == 0).tolist():
        level[top_child[k]] = level[top_child[k] + 1] = level[k] + 1
    roots = np.flatnonzero(top_count > leaf_size)
    deepest = int(np.max(level[(top_count > 0) & (top_count <= leaf_size)], initial=0))
    blocks = (empty_ints(2 * n), empty_ints(2 * n))
    made = np.empty(len(roots), np.int64)
    below = np.empty(len(roots), np.int64)
    threads.spread(
        lambda lo, hi: run(_SUBTREES, roots, none, lo, hi, blocks, made, below), len(roots), _SUBTREE_CHUNK
    )
    # Each subtree's nodes but its root after the large nodes, block after block.
    offset = n_nodes + np.cumsum(made - 1) - (made - 1)
    total = n_nodes + int(np.sum(made - 1))
    if len(roots):
        deepest = max(deepest, int(np.max(level[roots] + below)))
    out = (empty_ints(total), empty_ints(total))
    out[0][:n_nodes] = top_child
    out[1][:n_nodes] = top_count
    threads.spread(
        lambda lo, hi: run(_NUMBER, roots, offset, lo, hi, blocks, made, below, out),
        len(roots),
        _NUMBER_CHUNK,
    )
    return out[0], out[1], order, deepest


#: Subtrees split, and numbered, per call of the kernel: each is over a few thousand primitives at most.
_SUBTREE_CHUNK = 4
_NUMBER_CHUNK = 64


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


@spliced
def _face_row(vertices, bits, faces, k, kind, cull, hashes):
    i, j, m = faces[k, 0], faces[k, 1], faces[k, 2]
    plane_row(
        cull, k, vertices[i, 0], vertices[i, 1], vertices[i, 2], vertices[j, 0], vertices[j, 1],
        vertices[j, 2], vertices[m, 0], vertices[m, 1], vertices[m, 2],
    )  # fmt: skip
    # The hash of the face's parameters (its kind, nine coordinates, a zero).
    x = np.uint64(kind)
    for v in range(3):
        for a in range(3):
            x = _mix(x, bits[faces[k, v], a])
    hashes[k] = _mix(x, np.uint64(0))


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


@spliced
def _face_params(vertices, faces, order, params, j):
    k = order[j]
    for v in range(3):
        i = faces[k, v]
        for a in range(3):
            params[j, 3 * v + a] = vertices[i, a]
    for c in range(9, params.shape[1]):
        params[j, c] = 0.0


#: The steps of :func:`_face_step`.
_FACE_ROWS, _FACE_PARAMS = 0, 1
#: Faces per call of :func:`_face_step`.
_FACE_CHUNK = 8192


@kernel(nogil=True)
def _face_step(step, lo, hi, vertices, bits, faces, order, kind, cull, hashes, params):
    """One pass over the faces ``lo .. hi - 1`` (of ``faces`` of ``vertices``,
    whose bits are ``bits``, hulls of three points of kind ``kind``); one
    kernel for both passes.

    ``_FACE_ROWS``: their :func:`primitive_cull` rows and :func:`_row_hashes`.
    ``_FACE_PARAMS``: the parameters of the faces ``faces[order[lo:hi]]``.
    """
    if step == _FACE_ROWS:
        for k in range(lo, hi):
            _face_row(vertices, bits, faces, k, kind, cull, hashes)
    else:
        for j in range(lo, hi):
            _face_params(vertices, faces, order, params, j)


# The arguments of :func:`_face_step` that a pass does not use.
_NO_ORDER = readonly(np.empty(0, np.int64), np.int64)
_NO_CULL = np.empty((0, CULL_COLUMNS))
_NO_HASHES = np.empty(0, np.uint64)
_NO_PARAMS = np.empty((0, primitives.N_PARAMS))


def _faces(step, vertices, faces, order, kind, cull, hashes, params, n):
    """:func:`_face_step` over ``n`` faces, on the threads."""
    bits = vertices.view(np.uint64)  # here: a view in a kernel compiles a function of its own
    threads.spread(
        lambda lo, hi: _face_step(step, lo, hi, vertices, bits, faces, order, kind, cull, hashes, params),
        n,
        _FACE_CHUNK,
    )


def face_params(vertices, faces, order=None, width=primitives.N_PARAMS):
    """The stored rows ``(F, width)`` of the faces ``faces`` of ``vertices``
    (those ``faces[order]``, if given), hulls of three points: each face's
    nine coordinates, then zeros.  A collection of several kinds has rows
    of ``N_PARAMS`` columns (the default); a tree of faces alone keeps
    :data:`FACE_COLUMNS`."""
    if order is None and len(faces) < GATHER_MIN:
        params = np.empty((len(faces), width))
        # Gathered straight into the rows; the faces index the vertices.
        np.take(vertices, faces, axis=0, out=params[:, :9].reshape(-1, 3, 3), mode="clip")
        params[:, 9:] = 0.0
        return params
    order = readonly(np.arange(len(faces)) if order is None else order, np.int64)
    params = empty(len(order), width)
    vertices, faces = readonly(vertices, np.float64), readonly(faces, np.int64)
    _faces(_FACE_PARAMS, vertices, faces, order, np.int64(0), _NO_CULL, _NO_HASHES, params, len(order))
    return params


@kernel()
def _renumber(faces, order, number, out):
    """Each face ``faces[order[j]]``'s vertices renumbered into ``out[j]`` in the
    order of their first use, ``number`` (-1 for none yet) the new number of
    each vertex; returns how many vertices are used."""
    used = 0
    for j in range(order.shape[0]):
        k = order[j]
        for v in range(3):
            i = faces[k, v]
            if number[i] < 0:
                number[i] = used
                used += 1
            out[j, v] = number[i]
    return used


def leaf_faces(vertices, faces, order):
    """``(vertices, faces, sources)`` of the faces ``faces[order]`` (leaf order)
    of ``vertices``, as a tree reads them (:attr:`.tree.Tree.faces`): the
    vertices they use, in the order of first use, each face's three rows of
    them (int32), so that the faces of a leaf read nearby rows, and the index
    in ``vertices`` of each row (int32, :attr:`.tree.Tree.sources`)."""
    faces = readonly(faces, np.int64)
    number = np.full(len(vertices), -1, np.int64)
    out = np.empty((len(order), 3), np.int32)
    used = _renumber(faces, readonly(order, INDEX), number, out)
    first = np.empty(used, np.int64)
    kept = np.flatnonzero(number >= 0)
    first[number[kept]] = kept
    out.flags.writeable = False
    return readonly(take_rows(readonly(vertices, np.float64), first), np.float64), out, indices(first)


def moved_faces(vertices, tree):
    """:func:`leaf_faces` of a tree of faces read through their vertices, for
    its faces over moved ``vertices``: the same rows, renumbered as before."""
    rows = readonly(take_rows(readonly(vertices, np.float64), tree.sources), np.float64)
    return rows, tree.faces, tree.sources


def refitted(tree, vertices, faces, empty=np.empty):
    """The tree of the faces ``faces`` of moved ``vertices``, ``tree`` (built
    on them, with none left out) refitted: :func:`.refit.refit_indexed`, or
    the rows of a tree of one leaf gathered anew (its cull rows in arrays
    from ``empty``)."""
    if len(tree.child) > 1:
        return refit_indexed(vertices, tree)
    params, cull, bounds = refit_faces(vertices, faces, tree.index, tree.child, tree.count, tree.kinds)
    read = (lambda: moved_faces(vertices, tree)) if tree.indexed else None
    return assemble(
        tree.kinds, params, tree.index, tree.child, tree.count, tree.depth, (cull, cull), bounds,
        empty=empty, faces=read,
    )  # fmt: skip


def faces_reader(vertices, faces, index):
    """A function giving :func:`leaf_faces` of the faces ``faces[index]`` (leaf
    order), for :func:`assemble`; None where copies of a face were left out
    (:func:`distinct`), whose tree keeps rows."""
    if len(index) != len(faces):
        return None
    return lambda: leaf_faces(vertices, faces, index)


def restored_faces(vertices, faces, index, child, count, depth):
    """The tree of the faces ``faces`` of ``vertices`` that a build gave, from
    its decisions (``index``, ``child``, ``count``, ``depth``), fitted as the
    build fits it (:func:`_fitted_faces`): a tree of more than one node
    with no face left out; None for any other, which keeps rows."""
    if len(child) == 1 or len(index) != len(faces):
        return None
    kinds = np.full(len(index), primitives.TRIANGLE.code, np.int8)
    vertices, faces = readonly(vertices, np.float64), readonly(faces, np.int64)
    return _fitted_faces(vertices, faces, kinds, indices(index), indices(child), indices(count), depth)


def assemble(
    kinds, params, index, child, count, depth, cull=None, bounds=None, stored=None, empty=np.empty, faces=None
):
    """The :class:`Tree` of primitives already in leaf order, over the nodes ``child``, ``count``.

    ``cull`` is :func:`primitive_cull`'s ``(tight, loose)`` in that order,
    computed here when neither it nor ``stored`` is given; the node bounds
    are fitted to them unless given (those of the tight rows: a tree
    without loose rows).  The tree keeps them as :func:`stored_cull` gives
    them, in float32, in arrays from ``empty(shape, dtype)``; a tree of
    unrounded hulls of points alone may give those rows (``stored``)
    instead of ``cull``, having dropped the float64 ones.  ``faces``: a
    function giving :func:`leaf_faces` of a tree of faces, which then keeps
    them instead of ``params``: called once the nodes are fitted and
    ``params`` let go (the caller keeping no reference to them), so that the
    build's peak holds the faces' rows or their vertices, not both.
    """
    kinds = readonly(kinds, np.int8)
    params = readonly(params, np.float64)
    child = indices(child)
    count = indices(count)
    if stored is not None:
        tight = loose = tight_ro = readonly(stored, np.float32)
    else:
        tight, loose = primitive_cull(kinds, params) if cull is None else cull
        same = loose is tight
        tight = readonly(tight, np.float64)
        loose = tight if same else loose
        tight_ro = readonly(stored_cull(tight, empty), np.float32)
    if bounds is None:
        bounds = refit(child, count, kinds, params, tight, tight_ro)
    bounds = readonly(bounds, np.float64)
    if loose is tight:
        loose_ro, loose_bounds = tight_ro, bounds
    else:
        loose = readonly(loose, np.float64)
        loose_ro = readonly(stored_cull(loose, empty), np.float32)
        loose_bounds = readonly(refit(child, count, kinds, params, loose, loose_ro), np.float64)
    read = (None, None, None)
    if faces is not None:
        # The faces read through their vertices, which give their cull rows
        # where a search needs them (:meth:`.tree.Tree.culling`).
        del params
        read = faces()
        params = tight_ro = loose_ro = None
    return Tree(
        kinds=kinds,
        stored_params=params,
        index=indices(index),
        child=child,
        count=count,
        bounds=bounds,
        cull=tight_ro,
        loose_bounds=loose_bounds,
        loose_cull=loose_ro,
        depth=int(depth),
        vertices=read[0],
        faces=read[1],
        sources=read[2],
    )


def brute(kinds, params):
    """The broad phase of no hierarchy: one leaf holding every primitive, in order.

    Parameters
    ----------
    kinds : ndarray of int8, shape ``(n,)``, n >= 1
    params : ndarray of float64, shape ``(n, N_PARAMS)``

    Returns
    -------
    Tree
    """
    n = len(kinds)
    check_size(n)
    return assemble(kinds, params, np.arange(n), [0], [n], 0)


def build_tree(kinds, params, leaf_size=None):
    """A bounding-volume hierarchy over the primitives, built once.

    Parameters
    ----------
    kinds : ndarray of int8, shape ``(n,)``, n >= 1
    params : ndarray of float64, shape ``(n, N_PARAMS)``
    leaf_size : int, optional
        Most primitives a leaf holds; :func:`default_leaf_size` of the distinct
        primitives unless given.

    Returns
    -------
    Tree

    Raises
    ------
    ValueError
        If there are more than ``2**30`` primitives.
    """
    check_size(len(kinds))
    keep = distinct(kinds, params)
    kept = np.flatnonzero(keep)
    if len(kept) < len(kinds):
        kinds, params = kinds[kept], take_rows(params, kept)
    tight, loose = primitive_cull(kinds, params)
    size = default_leaf_size(len(kinds)) if leaf_size is None else int(leaf_size)
    # The build puts the rows of ``tight`` in leaf order; the others follow.
    child, count, order, depth = _build(tight, size)
    loose = tight if loose is tight else take_rows(loose, order)
    index = indices(order if len(kept) == len(keep) else kept[order])
    kinds, params = kinds[order], take_rows(params, order)
    del order
    return assemble(kinds, params, index, indices(child), indices(count), depth, (tight, loose))


def _fitted_faces(vertices, faces, kinds, index, child, count, depth):
    """The :class:`Tree` of the faces ``faces[index]`` (leaf order) of
    ``vertices`` over the nodes ``child``, ``count`` (more than one): the
    faces read through their vertices (:func:`leaf_faces`) and the nodes'
    bounds fitted to them (:func:`.refit.fit_indexed`), without the faces'
    rows for more than a subtree at a time."""
    rows, corners, sources = leaf_faces(vertices, faces, index)
    bounds = empty(len(child), NODE_COLUMNS)
    kinds = readonly(kinds, np.int8)
    fit_indexed(rows, corners, bounds, child, count, kinds, build_ranges(len(corners)))
    bounds = readonly(bounds, np.float64)
    return Tree(
        kinds=kinds, stored_params=None, index=index, child=child, count=count,
        bounds=bounds, cull=None, loose_bounds=bounds, loose_cull=None, depth=int(depth), vertices=rows,
        faces=corners, sources=sources,
    )  # fmt: skip


def build_faces(vertices, faces, kind, leaf_size=None):
    """:func:`build_tree` for the faces ``faces`` of ``vertices`` (indices into
    it), primitives of kind ``kind`` that are hulls of three points, without
    their parameters in the faces' order: the faces' boxes, slabs and
    hashes come from the vertices in one pass; the tree reads its faces
    through their vertices, and its nodes are fitted to them a subtree at
    a time (:func:`_fitted_faces`).  A tree of one leaf gathers the faces'
    rows, :data:`FACE_COLUMNS` wide, once, in leaf order."""
    check_size(len(faces), "faces")
    vertices = readonly(vertices, np.float64)
    faces = readonly(faces, np.int64)
    n = len(faces)
    cull = empty(n, CULL_COLUMNS)
    hashes = np.empty(n, np.uint64)
    _faces(_FACE_ROWS, vertices, faces, _NO_ORDER, np.int64(kind), cull, hashes, _NO_PARAMS, n)
    kinds = np.full(n, kind, np.int8)
    if not _all_different(hashes):
        return build_tree(kinds, face_params(vertices, faces, width=FACE_COLUMNS), leaf_size)
    child, count, order, depth = _build(cull, default_leaf_size(n) if leaf_size is None else int(leaf_size))
    if len(child) > 1:
        del cull, hashes
        index = indices(order)
        del order
        return _fitted_faces(vertices, faces, kinds, index, indices(child), indices(count), depth)
    # The float32 rows the tree keeps, and the float64 ones dropped before
    # the faces' rows are gathered and the nodes fitted (to the faces'
    # points), which halves the build's peak.
    stored = stored_cull(cull)
    del cull, hashes
    # The topology in 32 bits before the nodes are fitted, the 64-bit arrays
    # of the build let go; the faces' rows, gathered for the fit alone, are
    # held by assemble alone, which lets them go before the tree's vertices
    # are gathered: the build's peak is what it keeps.
    index, child, count = indices(order), indices(child), indices(count)
    del order
    return assemble(
        kinds, face_params(vertices, faces, index, FACE_COLUMNS), index, child, count, depth, stored=stored,
        faces=lambda: leaf_faces(vertices, faces, index),
    )  # fmt: skip
