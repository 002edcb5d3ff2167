"""The closest pair of primitives of two collections: a simultaneous descent of both hierarchies.

Each side is a :class:`PairTree`: a collection's tree (a mesh's or a
scene's), or a batch of primitives as a forest of one-primitive leaves
(:func:`forest`).  A query starts at a pair of nodes (the roots, or a
batch member against the other side's root) and descends: a pair of
leaves evaluates its pairs of primitives through the pair registry
(:mod:`proximity.pair.table`, :func:`proximity.pair.kernels.row_query`), any
other pair of nodes splits the larger node (a leaf is never split) and
visits the nearer child first, skipping a pair of nodes or primitives
whose lower bound exceeds the best answer so far plus a slack.  Nothing
here names a kind of primitive; the kinds present on each side choose the
pair functions compiled into the search (a chain, as in :mod:`proximity.broadphase.traverse`).

Side b may be posed: a 3 x 4 matrix ``[R | t]`` maps its stored
coordinates ``x`` to ``R x + t`` in side a's frame, applied on the fly to
its nodes' bounds and to the vertices of its primitives, each coordinate
computed as ``((r0 x + r1 y) + r2 z) + t``, which defines the posed
primitives: the answers are those of these vertices.

Pruning never changes the answer
--------------------------------
:mod:`.node_bounds` gives the lower bounds on node pairs and primitive
pairs, and why, with :data:`SLACK` ``= 256 eps M``, a skipped pair's
computed answer exceeds the best one.  The search therefore returns the
least computed answer over all pairs of primitives, ties to the lowest
``(index_a, index_b)``, as brute force does.  Two points of the sides
(one per node) bound the answer from above from the first levels on.  One
exception, for speed: a search without rounded rows stops at the first
pair found at distance 0 (no pair can be nearer: its ``d - r`` is
``-(r_a + r_b)``, the sides' radii), which need not be the lowest such
pair.  Intersecting primitives rarely compute to exactly 0 (the crossing
point is rounded), so the robust search certifies a pair it
finds within ``64 eps M`` of 0: where it certainly intersects, its answer
is the certified one, exactly 0 with the crossing point on both sides, and
the search stops there too.

Evaluation
----------
Where every pair of primitives is of one kind pair answered by a pair
kernel (two meshes), the pairs that pass the tests are gathered
:data:`~proximity.pair.kernels.CAP` at a time and evaluated by a loop
over the kernel's ``robust_unscaled`` that compiles to SIMD code (the
first leaves at once, so that the best answer bounds the search early);
otherwise one by one.  The certified method searches with the robust
answers and keeps the *finalists*, the pairs whose certified answer could
be the least (within ``64 eps M`` of their robust one), certifies them at
the end, and stops early where one is certainly at distance 0.

Certified
---------
Where a finalist's certified answer is undecided (or its ``d - r`` is not
known faithful), or there are more finalists than :data:`FINALISTS`, the
query is finished in Python (:func:`proximity.pair.composite.closest`):
every pair of primitives within the least upper bound, certified, exact
fallback included.
"""

import collections
import functools
import math

import numpy as np
from numba.core import types

from .. import primitives
from ..broadphase.bounds import _scale
from ..broadphase.traverse import _SENTINEL
from ..numerics import certified
from ..numerics.fp import EPS, faithful_difference, two_sum
from ..runtime.jit import inline, kernel, part, specialize
from . import table
from .node_bounds import (  # noqa: F401  (node_data: for the driver)
    box_gap2,
    centre_gap,
    first,
    held,
    hull_gap,
    lb2,
    node_arrays,
    node_data,
    node_lb2,
    plain_box,
    pose_row,
    posed_box,
    row_box,
    size,
    upper,
)
from .node_bounds import frame as node_frame

#: Pruning slack, in units of ``M`` (see the module docstring).
SLACK = 256.0 * EPS

#: One side of a descent: primitives in leaf order and their cull rows
#: (:class:`~.tree.Tree`'s arrays of the same names), and the table of its
#: nodes (:func:`.node_bounds.node_arrays`).
PairTree = collections.namedtuple("PairTree", "kinds params index cull nodes")
#: Per query: the starting nodes, the radii of the sides' rounded shapes
#: (added to every row's own), and the cutoff (``max_distance``, or inf).
Queries = collections.namedtuple("Queries", "start_a start_b radius_a radius_b cutoff")
#: Per query: the answer.  ``signed`` is ``d - r_a - r_b``, ``distance`` the
#: cores' ``d``; ``index_*`` the caller's indices, ``row_*`` the stored
#: positions of the closest primitives, ``radius_*`` their total radii;
#: ``undecided`` as in :mod:`proximity.broadphase.traverse`.
Outputs = collections.namedtuple(
    "Outputs",
    "signed distance sqr_distance point_a point_b feature_a feature_b extra_a extra_b index_a index_b "
    "row_a row_b radius_a radius_b undecided",
)

_VERTICES = primitives.vertex_counts()
_N = primitives.N_PARAMS
NK = len(primitives.BY_CODE)

#: A query's answer where no pair is within the cutoff.
_NOTHING = (math.nan,) * 9 + (-1.0, -1.0) + (math.nan,) * 6

# Bound by specialize: the pair functions (chains over the pairs of kinds
# present), the method's properties, the layout of the sides' rows.
EVALUATE = CERTIFY = EVAL_BLOCK = TOUCHING = None
EXACT_FALLBACK = False
# Whether the pairs of primitives are evaluated CAP at a time by EVAL_BLOCK (SIMD), on
# scratch of Z_ROWS rows, each side's row SIDE_A and SIDE_B values wide.
SIMD = False
CAP = 32
Z_ROWS = 35
SIDE_A = SIDE_B = 9
#: The most finalists a certified query keeps before it is resolved in Python.
FINALISTS = 64
POSED = False
RADIUS_A = RADIUS_B = -1  # the column of each side's row radii, -1: none
ZERO_STOPS = True
#: Whether the robust search certifies a pair found within rounding of 0, so
#: that intersecting primitives give exactly 0 and end it (no row radii).
TOUCH = False
UPPER = True  # whether points of the nodes bound the answer (no row radii)
LOW = HIGH = 0
ROW = NEXT = None


def _array(dtype, ndim, readonly=True):
    return types.Array(dtype, ndim, "C", readonly=readonly)


_F1, _F2, _I1 = _array(types.float64, 1), _array(types.float64, 2), _array(types.int64, 1)
# The cull rows as trees keep them, in float32 (see proximity.broadphase.bounds.stored_cull).
_C2 = _array(types.float32, 2)
# A tree's index (proximity.broadphase._alloc.INDEX).
_N1 = _array(types.int32, 1)
_TREE = types.NamedTuple([_array(types.int8, 1), _F2, _N1, _C2, _F2], PairTree)
_QUERIES = types.NamedTuple([_I1, _I1, _F1, _F1, _F1], Queries)
_W1, _W2 = _array(types.float64, 1, False), _array(types.float64, 2, False)
_WI, _W8 = _array(types.int64, 1, False), _array(types.int8, 1, False)
_OUTPUTS = types.NamedTuple([_W1, _W1, _W1, _W2, _W2, _W8, _W8, _W2, _W2, _WI, _WI, _WI, _WI, _W1, _W1, _W1],
                            Outputs)  # fmt: skip
#: The descent's signature: a range of queries, both sides, the pose, depth, magnitude, queries,
#: outputs, full.
_SIGNATURE = types.void(
    types.int64, types.int64, _TREE, _TREE, _F2, types.int64, types.float64, _QUERIES, _OUTPUTS, types.boolean
)


@inline
def _radii(ra, rb, certify):
    """``(r, exact)``: the total radius ``ra + rb`` rounded, and whether the sum is exact."""
    r, err = two_sum(ra, rb)
    return r, (err == 0.0) or not certify


# -- the search -----------------------------------------------------------------------


def _descend(lo, hi, A, B, pose, depth, magnitude, queries, out, full):
    """Queries ``lo .. hi - 1``: the least answer over the pairs of primitives below each
    query's starting nodes (see the module docstring).  With ``full=False`` only ``signed``,
    ``distance`` and ``undecided`` are written.  One serial kernel that releases the GIL, run
    on Python threads a range of queries at a time (:func:`proximity.runtime.threads.spread`): a
    parallel loop would compile the search twice more (its parfor and a second body)."""
    for q in range(lo, hi):
        _one(q, A, B, pose, depth, magnitude, queries, out, full)


@inline
def _win(fs, ist, win, answer, e, ra, rb, ia, ib, ka, kb):
    """Stored pair ``ka``, ``kb`` (the caller's ``ia``, ``ib``) the winner so far: ``e`` its
    ``d - r``, ``ra``, ``rb`` its radii, ``answer`` its 17 values (see :func:`_consider`)."""
    fs[0], fs[2], fs[3] = e, ra, rb
    ist[0], ist[1], ist[2], ist[3] = ia, ib, ka, kb
    for k in range(17):
        win[k] = answer[k]


def _consider(r, ka, kb, row_ra, row_rb, q, A, B, queries, magnitude, fs, ist, win, fin, fin_lo, tb):
    """Take the robust answer ``r`` (17 values) of stored pair ``ka``, ``kb`` into the state:
    ``fs = [best, best_hi, radius_a, radius_b]``, ``ist = [index_a, index_b, row_a, row_b,
    finalists, flags]`` (flags: 1 done, 2 finalists overflowed), ``win`` the winner's answer;
    with the certified method, ``fin`` (pairs) and ``fin_lo`` the finalists."""
    ra = row_ra + queries.radius_a[q]
    rb = row_rb + queries.radius_b[q]
    radius = ra + rb
    e = r[1] - radius
    ia, ib = A.index[ka], B.index[kb]
    if not EXACT_FALLBACK:
        if TOUCH:
            if r[1] != 0.0 and r[1] <= 64.0 * EPS * magnitude:
                # Possibly touching: where the pair certainly intersects, its
                # distance is exactly 0 and the search ends (see the module docstring).
                c = TOUCHING(A.kinds[ka], A.params, ka, B.kinds[kb], tb, 0, r[9], r[10])
                if c[0] == certified.CERTAIN and c[1] == 0.0:
                    # The cores cross: d - r is -(r_a + r_b), the least any pair can give.
                    _win(fs, ist, win, c, 0.0 - radius, ra, rb, ia, ib, ka, kb)
                    ist[5] |= 1
                    return
        if e < fs[0] or (e == fs[0] and (ia < ist[0] or (ia == ist[0] and ib < ist[1]))):
            _win(fs, ist, win, r, e, ra, rb, ia, ib, ka, kb)
            if ZERO_STOPS and r[1] == 0.0:
                ist[5] |= 1
        return
    w = 64.0 * EPS * magnitude + 2.0 * EPS * (abs(r[1]) + radius) + 5e-324
    lo = e - w
    if lo <= fs[1]:
        if ZERO_STOPS and lo <= 0.0:
            # Possibly touching: certified now, and a certain 0 ends the search.
            c = CERTIFY(A.kinds[ka], A.params, ka, B.kinds[kb], tb, 0)
            if c[0] == certified.CERTAIN and c[1] == 0.0:
                # d is exactly 0: d - r is -(r_a + r_b), correctly rounded, and no pair is less.
                fs[1] = 0.0 - radius
                _win(fs, ist, win, c, 0.0 - radius, ra, rb, ia, ib, ka, kb)
                ist[5] |= 1
                return
        n = ist[4]
        if n < fin.shape[0]:
            fin[n, 0], fin[n, 1] = ka, kb
            fin_lo[n] = lo
            ist[4] = n + 1
        else:
            ist[5] |= 2
    fs[1] = min(fs[1], e + w)


def _flush(z, n, cand, cand_r, q, A, B, queries, magnitude, fs, ist, win, fin, fin_lo, tb, posed, pose):
    """The robust answers of the ``n`` candidates gathered in ``z``, taken into the state."""
    EVAL_BLOCK(z, n)
    first = z.shape[0] - 17
    for i in range(n):
        if ist[5] & 1:
            return
        r = (certified.CERTAIN, z[first, i], z[first + 1, i], z[first + 2, i], z[first + 3, i],
             z[first + 4, i], z[first + 5, i], z[first + 6, i], z[first + 7, i], z[first + 8, i],
             z[first + 9, i], z[first + 10, i], z[first + 11, i], z[first + 12, i], z[first + 13, i],
             z[first + 14, i], z[first + 15, i])  # fmt: skip
        if (EXACT_FALLBACK and ZERO_STOPS) or (TOUCH and r[1] <= 64.0 * EPS * magnitude):
            pose_row(B.params, cand[i, 1], B.kinds[cand[i, 1]], pose, tb, posed)
        _consider(r, cand[i, 0], cand[i, 1], cand_r[i, 0], cand_r[i, 1], q, A, B, queries, magnitude,
                  fs, ist, win, fin, fin_lo, tb)  # fmt: skip


def _reach(fs, cutoff, rout, s):
    """The scaled distance beyond which pairs are skipped: past the best answer so far (the
    least upper bound of the certified ones), and past ``fs[4]``, the least distance between
    two points of the sides less the radii."""
    bound = fs[1] if EXACT_FALLBACK else fs[0]
    return max((min(min(bound, fs[4]), cutoff) + rout) * s, 0.0) + SLACK


@inline
def _push(h_lb, h_a, h_b, n, lb, a, b):
    """Push ``(lb, a, b)`` on the binary min-heap of ``n`` entries, which has room for it
    (:func:`_room`): returns its new size.  Nothing returns the arrays, whose references
    would be counted on every push."""
    i = n
    while i > 0:
        parent = (i - 1) >> 1
        if h_lb[parent] <= lb:
            break
        h_lb[i], h_a[i], h_b[i] = h_lb[parent], h_a[parent], h_b[parent]
        i = parent
    h_lb[i], h_a[i], h_b[i] = lb, a, b
    return n + 1


@part
def _room(h_lb, h_a, h_b, n):
    """The heap's arrays, twice as long, with its ``n`` entries."""
    grown_lb, grown_a, grown_b = np.empty(2 * n), np.empty(2 * n, np.int64), np.empty(2 * n, np.int64)
    grown_lb[:n], grown_a[:n], grown_b[:n] = h_lb[:n], h_a[:n], h_b[:n]
    return grown_lb, grown_a, grown_b


@inline
def _pop(h_lb, h_a, h_b, n):
    """Remove the least entry of the heap of ``n`` entries: returns its two nodes."""
    a, b = h_a[0], h_b[0]
    n -= 1
    lb, la, lb_ = h_lb[n], h_a[n], h_b[n]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= n:
            break
        if c + 1 < n and h_lb[c + 1] < h_lb[c]:
            c += 1
        if h_lb[c] >= lb:
            break
        h_lb[i], h_a[i], h_b[i] = h_lb[c], h_a[c], h_b[c]
        i = c
    if n > 0:
        h_lb[i], h_a[i], h_b[i] = lb, la, lb_
    return a, b


def _one(q, A, B, pose, depth, magnitude, queries, out, full):
    kinds_a, qa, index_a, cull_a, nodes_a = A
    kinds_b, qb, index_b, cull_b, nodes_b = B
    s = _scale(0.0, 0.0, 0.0, magnitude)
    tb = np.empty((1, qb.shape[1]))
    # Node pairs to visit, least lower bound first.
    h_lb, h_a, h_b = np.empty(256), np.empty(256, np.int64), np.empty(256, np.int64)
    n_heap = 0
    rout = queries.radius_a[q] + queries.radius_b[q]
    cutoff = queries.cutoff[q]
    fs = np.array([math.inf, math.inf, 0.0, 0.0, math.inf])
    big = _SENTINEL
    ist = np.array([big, big, -1, -1, 0, 0], np.int64)
    win = np.empty(17)
    fin = np.empty((FINALISTS, 2), np.int64)
    fin_lo = np.empty(FINALISTS)
    z = np.empty((Z_ROWS, CAP))
    cand = np.empty((CAP, 2), np.int64)
    cand_r = np.empty((CAP, 2))
    n_cand = 0
    reach = _reach(fs, cutoff, rout, s)
    limit = reach * reach
    na, nb = queries.start_a[q], queries.start_b[q]
    lb0 = node_lb2(nodes_a, na, nodes_b, nb, pose, s, POSED)
    if lb0 <= limit:
        n_heap = _push(h_lb, h_a, h_b, n_heap, lb0, na, nb)
    # The nearer child of the pair just split, taken next without the heap where nothing
    # in the heap is nearer (half the heap's traffic).
    pending, p_lb, p_a, p_b = False, 0.0, 0, 0
    while True:
        if pending and p_lb <= limit and (n_heap == 0 or p_lb <= h_lb[0]):
            pending = False
            na, nb = p_a, p_b
        else:
            if pending:
                pending = False
                if p_lb <= limit:
                    if n_heap == h_lb.shape[0]:
                        h_lb, h_a, h_b = _room(h_lb, h_a, h_b, n_heap)
                    n_heap = _push(h_lb, h_a, h_b, n_heap, p_lb, p_a, p_b)
                continue
            if n_heap == 0 or h_lb[0] > limit:
                if n_cand == 0:
                    break
                # Candidates wait: their answers may prune what is left.
                _flush(z, n_cand, cand, cand_r, q, A, B, queries, magnitude, fs, ist, win, fin, fin_lo, tb,
                       POSED, pose)  # fmt: skip
                n_cand = 0
                reach = _reach(fs, cutoff, rout, s)
                limit = reach * reach
                if ist[5] & 1:
                    break
                continue
            na, nb = _pop(h_lb, h_a, h_b, n_heap)
            n_heap -= 1
        leaf_a, leaf_b = held(nodes_a, na) > 0, held(nodes_b, nb) > 0
        if leaf_a and leaf_b:
            for kb in range(first(nodes_b, nb), first(nodes_b, nb) + held(nodes_b, nb)):
                kind_b = kinds_b[kb]
                nv_b = _VERTICES[kind_b]
                pose_row(qb, kb, kind_b, pose, tb, POSED)
                row_rb = qb[kb, RADIUS_B] if RADIUS_B >= 0 else 0.0
                box_b = row_box(tb, 0, nv_b, cull_b, kb, row_rb, s)
                for ka in range(first(nodes_a, na), first(nodes_a, na) + held(nodes_a, na)):
                    kind_a = kinds_a[ka]
                    if box_gap2(plain_box(cull_a, ka, s), box_b) > limit:
                        continue
                    if hull_gap(cull_a, ka, tb, 0, nv_b, row_rb, s) > reach:
                        continue
                    row_ra = qa[ka, RADIUS_A] if RADIUS_A >= 0 else 0.0
                    if not POSED and hull_gap(cull_b, kb, qa, ka, _VERTICES[kind_a], row_ra, s) > reach:
                        continue
                    if centre_gap(qa, ka, _VERTICES[kind_a], row_ra, tb, 0, nv_b, row_rb, s) > reach:
                        continue
                    if SIMD:
                        for c in range(SIDE_A):
                            z[c, n_cand] = qa[ka, c]
                        for c in range(SIDE_B):
                            z[SIDE_A + c, n_cand] = tb[0, c]
                        cand[n_cand, 0], cand[n_cand, 1] = ka, kb
                        cand_r[n_cand, 0], cand_r[n_cand, 1] = row_ra, row_rb
                        n_cand += 1
                        if n_cand == CAP:
                            _flush(z, n_cand, cand, cand_r, q, A, B, queries, magnitude, fs, ist, win, fin,
                                   fin_lo, tb, POSED, pose)  # fmt: skip
                            n_cand = 0
                            pose_row(qb, kb, kind_b, pose, tb, POSED)
                    else:
                        r = EVALUATE(kind_a, qa, ka, kind_b, tb, 0)
                        _consider(r, ka, kb, row_ra, row_rb, q, A, B, queries, magnitude, fs, ist, win, fin,
                                  fin_lo, tb)  # fmt: skip
                    if ist[5] & 1:
                        break
                    reach = _reach(fs, cutoff, rout, s)
                    limit = reach * reach
                if ist[5] & 1:
                    break
            if SIMD and n_cand > 0 and fs[0] == math.inf and fs[1] == math.inf:
                # Nothing known yet: the first leaves' answers bound the rest of the search.
                _flush(z, n_cand, cand, cand_r, q, A, B, queries, magnitude, fs, ist, win, fin, fin_lo, tb,
                       POSED, pose)  # fmt: skip
                n_cand = 0
                reach = _reach(fs, cutoff, rout, s)
                limit = reach * reach
        else:
            split_a = leaf_b or (not leaf_a and size(nodes_a, na) >= size(nodes_b, nb))
            # The frame of the node kept is computed once for both children.
            if split_a:
                c1 = first(nodes_a, na)
                c2 = c1 + 1
                fb = node_frame(nodes_b, nb, pose, s, POSED)
                box_b = posed_box(nodes_b, nb, pose, s, POSED)
                box_1, box_2 = plain_box(nodes_a, c1, s), plain_box(nodes_a, c2, s)
                # The boxes first: the frames only where they do not prune.
                d1, d2 = box_gap2(box_1, box_b), box_gap2(box_2, box_b)
                if d1 <= limit:
                    d1 = lb2(node_frame(nodes_a, c1, pose, s, False), box_1, fb, box_b, limit)
                if d2 <= limit:
                    d2 = lb2(node_frame(nodes_a, c2, pose, s, False), box_2, fb, box_b, limit)
                o1, o2 = nb, nb
            else:
                o1 = first(nodes_b, nb)
                o2 = o1 + 1
                fa = node_frame(nodes_a, na, pose, s, False)
                box_a = plain_box(nodes_a, na, s)
                box_1, box_2 = (
                    posed_box(nodes_b, o1, pose, s, POSED),
                    posed_box(nodes_b, o2, pose, s, POSED),
                )
                d1, d2 = box_gap2(box_a, box_1), box_gap2(box_a, box_2)
                if d1 <= limit:
                    d1 = lb2(fa, box_a, node_frame(nodes_b, o1, pose, s, POSED), box_1, limit)
                if d2 <= limit:
                    d2 = lb2(fa, box_a, node_frame(nodes_b, o2, pose, s, POSED), box_2, limit)
                c1, c2 = na, na
            if UPPER:
                # Two points of the sides bound the answer from above, from the first levels on.
                u1 = upper(nodes_a, c1, nodes_b, o1, pose, s, POSED)
                u2 = upper(nodes_a, c2, nodes_b, o2, pose, s, POSED)
                u = min(u1, u2) / s - rout
                if u < fs[4]:
                    fs[4] = u
                    reach = _reach(fs, cutoff, rout, s)
                    limit = reach * reach
            if d2 < d1:
                d1, c1, o1, d2, c2, o2 = d2, c2, o2, d1, c1, o1
            if d1 <= limit:
                pending, p_lb, p_a, p_b = True, d1, c1, o1
            if d2 <= limit:
                if n_heap == h_lb.shape[0]:
                    h_lb, h_a, h_b = _room(h_lb, h_a, h_b, n_heap)
                n_heap = _push(h_lb, h_a, h_b, n_heap, d2, c2, o2)
        if ist[5] & 1:
            break
    undecided = math.nan
    if EXACT_FALLBACK and not ist[5] & 1:
        undecided = _finish(q, A, B, pose, queries, fs, ist, win, fin, fin_lo, tb)
    out.undecided[q] = undecided
    found = ist[2] >= 0 and fs[0] <= cutoff and math.isnan(undecided)
    out.signed[q] = fs[0] if found else math.inf
    out.distance[q] = win[1] if found else math.inf
    if not full:
        return
    w = (win[0], win[1], win[2], win[3], win[4], win[5], win[6], win[7], win[8], win[9], win[10], win[11],
         win[12], win[13], win[14], win[15], win[16]) if found else _NOTHING  # fmt: skip
    out.sqr_distance[q] = w[2] if found else math.inf
    out.point_a[q, 0], out.point_a[q, 1], out.point_a[q, 2] = w[3], w[4], w[5]
    out.point_b[q, 0], out.point_b[q, 1], out.point_b[q, 2] = w[6], w[7], w[8]
    out.feature_a[q] = np.int8(w[9])
    out.feature_b[q] = np.int8(w[10])
    out.extra_a[q, 0], out.extra_a[q, 1], out.extra_a[q, 2] = w[11], w[12], w[13]
    out.extra_b[q, 0], out.extra_b[q, 1], out.extra_b[q, 2] = w[14], w[15], w[16]
    out.index_a[q] = ist[0] if found else -1
    out.index_b[q] = ist[1] if found else -1
    out.row_a[q] = ist[2] if found else -1
    out.row_b[q] = ist[3] if found else -1
    out.radius_a[q] = fs[2] if found else math.nan
    out.radius_b[q] = fs[3] if found else math.nan


def _finish(q, A, B, pose, queries, fs, ist, win, fin, fin_lo, tb):
    """The certified winner among the finalists (those still within ``best_hi``), into the
    state; returns NaN, or the bound to resolve the query in Python below where a finalist
    is undecided or they overflowed."""
    best_hi = fs[1]
    if ist[5] & 2:
        return best_hi
    fs[0] = math.inf
    big = _SENTINEL
    ist[0], ist[1], ist[2], ist[3] = big, big, -1, -1
    for i in range(ist[4]):
        if fin_lo[i] > best_hi:
            continue
        ka, kb = fin[i, 0], fin[i, 1]
        pose_row(B.params, kb, B.kinds[kb], pose, tb, POSED)
        c = CERTIFY(A.kinds[ka], A.params, ka, B.kinds[kb], tb, 0)
        row_ra = A.params[ka, RADIUS_A] if RADIUS_A >= 0 else 0.0
        row_rb = B.params[kb, RADIUS_B] if RADIUS_B >= 0 else 0.0
        ra = row_ra + queries.radius_a[q]
        rb = row_rb + queries.radius_b[q]
        radius, exact_sum = _radii(ra, rb, True)
        ok, e = faithful_difference(c[1], radius)
        if not (c[0] == certified.CERTAIN and ok and exact_sum):
            return best_hi
        ia, ib = A.index[ka], B.index[kb]
        if e < fs[0] or (e == fs[0] and (ia < ist[0] or (ia == ist[0] and ib < ist[1]))):
            _win(fs, ist, win, c, e, ra, rb, ia, ib, ka, kb)
    return math.nan


def _link(kind_a, qa, ka, kind_b, qb, kb):
    code = kind_a * NK + kind_b
    if code >= LOW and code <= HIGH:
        return ROW(kind_a, qa, ka, kind_b, qb, kb)
    return NEXT(kind_a, qa, ka, kind_b, qb, kb)


def _last(kind_a, qa, ka, kind_b, qb, kb):
    return ROW(kind_a, qa, ka, kind_b, qb, kb)


def _chain(present, method):
    """One function of two stored rows that calls the pair function of their kinds
    (``present``: :class:`~proximity.pair.table.Pair` records, in code order)."""
    tag = f"{method.name}__" + "_".join(p.name for p in present)
    fn = pairs_kernels().row_query(present[-1], method)
    chain = specialize(_last, f"{tag}__{present[-1].code}", role="inline", ROW=fn)
    for p in reversed(present[:-1]):
        fn = pairs_kernels().row_query(p, method)
        bindings = dict(ROW=fn, NEXT=chain, LOW=p.code, HIGH=p.code)
        chain = specialize(_link, f"{tag}__{p.code}", role="inline", **bindings)
    return chain


def pairs_kernels():
    from ..runtime import lazy

    return lazy.load("proximity.pair.kernels")


def _nothing(z, n):
    pass


@functools.cache
def descent_kernel(method, present, posed, radius_a, radius_b):
    """The compiled descent of ``method`` over the pairs of kinds ``present`` (Pair records in
    code order), side b ``posed`` or not, with row radii in columns ``radius_a``, ``radius_b``
    (-1: none)."""
    from ..methods import CERTIFIED, ROBUST

    names = "_".join(p.name for p in present)
    tag = f"{method.name}__{names}__{int(posed)}_{radius_a}_{radius_b}"
    pk = pairs_kernels()
    touch_row = None
    if not method.exact_fallback and radius_a < 0 and radius_b < 0 and len(present) == 1:
        touch_row = pk.touch_row(present[0])
    touch = touch_row is not None
    simd = len(present) == 1 and not present[0].point
    one_pair = present[0]
    bindings = dict(
        EVALUATE=_chain(present, ROBUST),
        CERTIFY=_chain(present, CERTIFIED) if method.exact_fallback else _chain(present, ROBUST),
        TOUCH=touch,
        TOUCHING=touch_row or specialize(_nothing, "nothing", role="inline"),
        EXACT_FALLBACK=method.exact_fallback,
        POSED=posed,
        RADIUS_A=radius_a,
        RADIUS_B=radius_b,
        ZERO_STOPS=radius_a < 0 and radius_b < 0,
        UPPER=radius_a < 0 and radius_b < 0,
        SIMD=simd,
        EVAL_BLOCK=pk.candidates(one_pair) if simd else specialize(_nothing, "nothing", role="inline"),
        CAP=pk.CAP,
        Z_ROWS=pk.candidate_rows(one_pair) if simd else 1,
        SIDE_A=3 * one_pair.a.vertices,
        SIDE_B=3 * one_pair.b.vertices,
    )
    helpers = {}
    for name, func in (
        ("_reach", _reach),
        ("_consider", _consider),
        ("_finish", _finish),
        ("_flush", _flush),
    ):
        helpers[name] = specialize(func, tag, role="inline", **bindings, **helpers)
    one = specialize(_one, tag, role="part", **bindings, **helpers)
    descend = specialize(_descend, tag, _SIGNATURE, nogil=True, _one=one)
    # The entry point skips Numba's dispatch (typing 40 arrays costs more than a small query):
    # the caller passes exactly the types of _SIGNATURE.
    return descend.overloads[tuple(_SIGNATURE.args)].entry_point


# -- sides --------------------------------------------------------------------------


def from_tree(tree):
    """The :class:`PairTree` of a collection's :class:`~.tree.Tree` (tight boxes)."""
    nodes, _, params = node_data(tree)
    return PairTree(tree.kinds, params, tree.index, tree.culling(False), nodes)


def forest(kinds, params):
    """A batch of primitives as a :class:`PairTree` of one-primitive leaves: node ``k`` holds
    primitive ``k``, bounded by its box and its slab; queries start at its leaves."""
    from ..broadphase._alloc import indices, readonly
    from ..broadphase.bounds import primitive_cull, stored_cull

    cull = primitive_cull(kinds, params)[0]
    n = len(kinds)
    bounds = np.zeros((n, 21))
    bounds[:, :6] = cull[:, :6]
    bounds[:, 6:11] = cull[:, 6:11]
    bounds[:, 14::5] = -math.inf
    bounds[:, 15::5] = math.inf
    kinds, params = readonly(kinds, np.int8), readonly(params, np.float64)
    index, bounds = indices(np.arange(n)), readonly(bounds, np.float64)
    child, count = indices(np.arange(n)), indices(np.ones(n, np.int64))
    nodes = node_arrays(kinds, params, bounds, child, count)
    stored = readonly(stored_cull(cull), np.float32)
    return PairTree(kinds, params, index, stored, nodes)


@functools.cache
def present_pairs(kinds_a, kinds_b, names):
    """The :class:`~proximity.pair.table.Pair` records of the kinds ``kinds_a`` (Primitive records)
    against ``kinds_b``, in code order; NotImplementedError (naming ``names``) for a pair with
    no query."""
    found = [table.lookup(ka, kb, names) for ka in kinds_a for kb in kinds_b]
    return tuple(sorted(found, key=lambda p: p.code))


def magnitude(m_a, m_b, pose, radius):
    """``M``: the largest coordinate magnitude of both sides' (posed) boxes (``m_a``, ``m_b``
    unposed) and of the radii."""
    if pose is not None:
        m_b = max(sum(abs(x) for x in row[:3]) * m_b + abs(row[3]) for row in pose.tolist())
    return max(m_a, m_b, float(radius))


def side_magnitude(side):
    """The largest finite coordinate magnitude of a forest's boxes."""
    rows = side.nodes[:, :6]
    return float(np.max(np.abs(rows), where=np.isfinite(rows), initial=0.0))


@kernel()
def _gather(A, B, pose, posed, depth, magnitude, start_a, start_b, reach_distance, col_a, col_b, out):
    """The pairs of stored primitives below nodes ``start_a``, ``start_b`` not pruned at
    ``reach_distance`` (the bound on ``d - r`` plus the outer radii) by the search's tests:
    written to ``out`` (as many as fit); returns how many there are."""
    kinds_a, qa, index_a, cull_a, nodes_a = A
    kinds_b, qb, index_b, cull_b, nodes_b = B
    s = _scale(0.0, 0.0, 0.0, magnitude)
    reach = max(reach_distance * s, 0.0) + SLACK
    limit = reach * reach
    tb = np.empty((1, qb.shape[1]))
    stack_a = np.empty(2 * depth + 4, np.int64)
    stack_b = np.empty(2 * depth + 4, np.int64)
    stack_a[0], stack_b[0] = start_a, start_b
    sp = 1
    found = 0
    while sp > 0:
        sp -= 1
        na, nb = stack_a[sp], stack_b[sp]
        if node_lb2(nodes_a, na, nodes_b, nb, pose, s, posed) > limit:
            continue
        leaf_a, leaf_b = held(nodes_a, na) > 0, held(nodes_b, nb) > 0
        if leaf_a and leaf_b:
            for kb in range(first(nodes_b, nb), first(nodes_b, nb) + held(nodes_b, nb)):
                nv_b = _VERTICES[kinds_b[kb]]
                pose_row(qb, kb, kinds_b[kb], pose, tb, posed)
                row_rb = qb[kb, col_b] if col_b >= 0 else 0.0
                box_b = row_box(tb, 0, nv_b, cull_b, kb, row_rb, s)
                for ka in range(first(nodes_a, na), first(nodes_a, na) + held(nodes_a, na)):
                    if box_gap2(plain_box(cull_a, ka, s), box_b) > limit:
                        continue
                    if hull_gap(cull_a, ka, tb, 0, nv_b, row_rb, s) > reach:
                        continue
                    row_ra = qa[ka, col_a] if col_a >= 0 else 0.0
                    if not posed and hull_gap(cull_b, kb, qa, ka, _VERTICES[kinds_a[ka]], row_ra, s) > reach:
                        continue
                    if centre_gap(qa, ka, _VERTICES[kinds_a[ka]], row_ra, tb, 0, nv_b, row_rb, s) > reach:
                        continue
                    if found < out.shape[0]:
                        out[found, 0], out[found, 1] = ka, kb
                    found += 1
        elif leaf_b or (not leaf_a and size(nodes_a, na) >= size(nodes_b, nb)):
            stack_a[sp], stack_b[sp] = first(nodes_a, na), nb
            stack_a[sp + 1], stack_b[sp + 1] = first(nodes_a, na) + 1, nb
            sp += 2
        else:
            stack_a[sp], stack_b[sp] = na, first(nodes_b, nb)
            stack_a[sp + 1], stack_b[sp + 1] = na, first(nodes_b, nb) + 1
            sp += 2
    return found


def gather(side_a, side_b, pose, depth, magnitude, queries, q, bound, column):
    """The stored positions ``(k, 2)`` of every pair of primitives of query ``q`` whose
    ``d - r`` could be at most ``bound`` (pose None: side b unposed)."""
    pose_array = np.zeros((3, 4)) if pose is None else pose
    reach = bound + queries.radius_a[q] + queries.radius_b[q]
    args = (side_a, side_b, pose_array, pose is not None, depth, magnitude, queries.start_a[q],
            queries.start_b[q], reach, column[0], column[1])  # fmt: skip
    out = np.empty((64, 2), np.int64)
    found = _gather(*args, out)
    if found > len(out):
        out = np.empty((found, 2), np.int64)
        _gather(*args, out)
    return out[:found]
