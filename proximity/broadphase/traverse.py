"""The search: the nearest stored primitive to each point, down the hierarchy.

The traversal visits the nearer child first and skips a node when a lower
bound on the distance from the point to what it holds exceeds the best
answer so far plus a slack (:mod:`.bounds` shows why that never changes the
answer).  "Nearer" is by the children's axis-aligned boxes, the larger
bound (with the oriented box) breaking ties: over a curved surface the
oriented box of a patch that turns away from the point is nearer than
that of the patch under it (its plane passes closer), so the larger bound
sent the search to the wrong side first.  The order changes only which
primitives are evaluated, never the answer (the least distance, ties to
the lowest index).  It is compiled per method and per set of kinds stored: the
method's query of each kind's rows (``row_query`` of its kernel module, see
:mod:`proximity.primitives`) is bound into it, and nothing else compiles.

Where the tree holds one kind whose module answers rows side by side for
the method (``row_batch``: the triangle's, for ``robust``), a leaf's rows
are answered :data:`~proximity.primitives.LANES` at a time, by a loop
that compiles to SIMD code, with the bits of ``row_query``, without the
rows' own cull tests: such a search reads no cull rows
(:func:`reads_cull`), which a tree of faces then need not keep.  Rows a
test would have skipped only add answers that cannot win (:mod:`.bounds`),
so the answer is the same; the cutoff is applied to the answer, as
without them.

Certified
---------
Where the certified filter leaves a primitive's answer to its exact
fallback (rational arithmetic, in Python), the kernel only knows an
interval around it (``row_interval``, from ``robust``'s bound), and uses
the interval's upper end to prune.  A point for which such a primitive
could be the nearest is finished outside the kernel
(:func:`proximity.broadphase.nearest.nearest`).
"""

import collections
import functools
import math

import numpy as np
from numba.core import types

from ..numerics import certified
from ..numerics.fp import EPS, faithful_difference
from ..primitives import LANES
from ..runtime.jit import inline, kernel, launcher, specialize
from ..runtime.loops import PAIR_OUT, PAIR_ROWS
from .bounds import SLACK, _bound_sqr, _box_sqr, _culled, _scale, _slabs_sqr

BLOCK = 64  # points per block function call
#: The largest index (see :func:`_search_block`): a constant, where ``np.iinfo``
#: in a kernel would compile two functions.
_SENTINEL = int(np.iinfo(np.int64).max)
#: Fewest blocks a thread takes at a time: a thread started for fewer would
#: cost about as much as it saves.
SEARCH_GRAIN = 4
NONE = -1  # the feature of a row with no answer

#: The arrays of a tree that the search reads.
TreeArrays = collections.namedtuple("TreeArrays", "kinds params index cull bounds child count")
#: The search's outputs; ``extra`` holds up to three of the primitive's
#: result values and ``flag`` its boolean one (see :mod:`proximity.primitives`).
Outputs = collections.namedtuple("Outputs", "distance sqr_distance point feature extra flag index undecided")


def new_outputs(n, full, exact):
    """:data:`Outputs` for ``n`` points, all but ``distance`` and ``undecided`` empty unless
    ``full``, and ``undecided`` empty unless ``exact``: only a method with an exact fallback
    (``Method.exact_fallback``) leaves answers undecided, and only its search writes them."""
    m = n if full else 0
    return Outputs(
        distance=np.empty(n),
        sqr_distance=np.empty(m),
        point=np.empty((m, 3)),
        feature=np.empty(m, np.int8),
        extra=np.empty((m, 3)),
        flag=np.empty(m, np.bool_),
        index=np.empty(m, np.int64),
        undecided=np.empty(n if exact else 0),
    )


_C2F = types.Array(types.float64, 2, "C", readonly=True)
_C2F32 = types.Array(types.float32, 2, "C", readonly=True)
_C1I = types.Array(types.int64, 1, "C", readonly=True)
#: A tree's ``index``, ``child`` and ``count`` (:data:`~._alloc.INDEX`).
_C1N = types.Array(types.int32, 1, "C", readonly=True)
_OUT1 = types.Array(types.float64, 1, "C")
_OUT2 = types.Array(types.float64, 2, "C")


def _tree_type(rows):
    """The Numba type of :data:`TreeArrays` whose ``params`` are of type ``rows``."""
    return types.NamedTuple(
        [types.Array(types.int8, 1, "C", readonly=True), rows, _C1N, _C2F32, _C2F, _C1N, _C1N], TreeArrays
    )


_TREE = _tree_type(_C2F)
#: A tree of faces read through their vertices: ``params`` is ``(vertices, faces)`` (:meth:`.tree.Tree.rows`).
_INDEXED_TREE = _tree_type(types.Tuple([_C2F, types.Array(types.int32, 2, "C", readonly=True)]))
_OUTPUTS = types.NamedTuple(
    [_OUT1, _OUT1, _OUT2, types.Array(types.int8, 1, "C"), _OUT2, types.Array(types.boolean, 1, "C"),
     types.Array(types.int64, 1, "C"), _OUT1],
    Outputs,
)  # fmt: skip


def _signatures(tree):
    """The block's and the loop's signatures for trees of type ``tree``."""
    # (block, tree, depth, magnitude, points, order, outputs, full, cutoff)
    block = types.void(
        types.int64, tree, types.int64, types.float64, _C2F, _C1I, _OUTPUTS, types.boolean, types.float64
    )
    # (handle, first block, end block, tree, ...)
    return block, types.void(types.int64, types.int64, types.int64, *block.args[1:])


_SIGNATURES = {False: _signatures(_TREE), True: _signatures(_INDEXED_TREE)}

# Bound per method and set of kinds by :func:`proximity.runtime.jit.specialize`:
# the primitives' evaluation and interval (chains over the kinds, see
# :func:`_chain`), whether the method has an exact fallback, and whether the
# previous point's answer may seed the search; where a tree of one kind
# answers several rows side by side (its kernel module's ``row_batch``, see
# :mod:`proximity.primitives`), ``BATCH`` and that function, ``ROWS``.
EVALUATE = INTERVAL = DESCEND = ROWS = None
BATCH = False
EXACT_FALLBACK = False
SEED_POINT = True
# The column of the rows' radii where the tree holds rounded primitives
# (:class:`proximity.Inflated`), else -1.
RADIUS = -1
# The links of a chain: the codes a link's kernel module answers for, its
# function, and the rest of the chain.
LOW = HIGH = 0
ROW = NEXT = CALL = None


@inline
def no_answer(i, value, full, dist, sqr, point, extra, feature, flag, prim):
    """Row ``i`` of a search's outputs without an answer: distance ``value`` (``inf``: nothing
    within the cutoff; NaN: no primitive answers), NaN points and parameters, feature
    ``NONE``, no flag and no primitive."""
    dist[i] = value
    if full:
        sqr[i] = value
        for c in range(3):
            point[i, c] = math.nan
            extra[i, c] = math.nan
        feature[i] = NONE
        flag[i] = False
        prim[i] = -1


@inline
def _lane(z, j):
    """The answer in column ``j`` of a batch's scratch ``z`` (see :mod:`proximity.primitives`)."""
    o = PAIR_OUT
    return (
        z[o, j], z[o + 1, j], z[o + 2, j], z[o + 3, j], z[o + 4, j],
        z[o + 5, j], z[o + 6, j], z[o + 7, j], z[o + 8, j],
    )  # fmt: skip


def _descend(
    tree, root, stack_node, stack_sqr, lanes, z, magnitude, px, py, pz, cap, near_x, near_y, near_z, offset,
    state,
):  # fmt: skip
    """Search ``tree`` from node ``root`` for the point ``P`` (finite), updating ``state``.

    ``state`` is the best answer so far: ``(best, best_index, best_k, upper,
    lowest, w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag)``, as
    :func:`_search_block` keeps it; nothing beyond ``min(best, cap)`` (and the
    previous closest point ``near``, unless NaN) is visited.  ``offset`` is
    added to the tree's primitive indices (the instances of a scene number
    their primitives after each other's).  ``stack_node`` and ``stack_sqr``
    hold ``depth + 1`` entries, ``lanes`` :data:`~proximity.primitives.LANES`
    and ``z`` is ``(PAIR_ROWS, LANES)``: scratch, allocated once per block.
    """
    kinds, params, index, cull, bounds, child, count = tree
    best, best_index, best_k, upper, lowest, w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag = state
    s = _scale(px, py, pz, magnitude)
    qx, qy, qz = px * s, py * s, pz * s
    cap = min(cap, best) * s  # scaled upper bound on the answer (exact: s is a power of two)
    if SEED_POINT and not math.isnan(near_x):
        dx, dy, dz = qx - near_x * s, qy - near_y * s, qz - near_z * s
        cap = min(cap, math.sqrt(dx * dx + dy * dy + dz * dz))
    reach = cap + SLACK  # scaled distance beyond which primitives are skipped
    limit = reach * reach  # its square, for the boxes
    node = root
    sp = 0
    while True:
        first, c = child[node], count[node]
        if c > 0:
            if BATCH:
                # The leaf's rows LANES at a time, answered side by side,
                # without their cull tests: a pass costs about what the tests
                # of its rows would.
                for k in range(first, first + c, LANES):
                    n = min(LANES, first + c - k)
                    for j in range(n):
                        lanes[j] = k + j
                    ROWS(params, lanes, n, px, py, pz, z)
                    for j in range(n):
                        d, sqr, x, y, zz, f, a0, a1, a2 = _lane(z, j)
                        idx = index[lanes[j]] + offset
                        if d < best or (d == best and idx < best_index):
                            best = d
                            best_index = idx
                            best_k = lanes[j]
                            w_sqr, w_x, w_y, w_z, w_feature = sqr, x, y, zz, int(f)
                            w_a0, w_a1, w_a2, w_flag = a0, a1, a2, False
                    reach = min(min(best, upper) * s, cap) + SLACK
                    limit = reach * reach
            else:
                for k in range(first, first + c):
                    if _culled(cull, k, s, qx, qy, qz, reach):
                        continue
                    r = EVALUATE(kinds, params, k, px, py, pz)
                    if RADIUS >= 0:
                        # A rounded primitive: d - R, ranked signed (negative inside).
                        r = _rounded(r, params[k, RADIUS], px, py, pz, EXACT_FALLBACK)
                    certain = True
                    if EXACT_FALLBACK:
                        if r[0] != certified.CERTAIN:
                            certain = False
                            lo, hi = INTERVAL(kinds, params, k, px, py, pz)
                            if RADIUS >= 0:
                                lo, hi = _less(lo, hi, params[k, RADIUS])
                            lowest = min(lowest, lo)
                            upper = min(upper, hi)
                    if certain:
                        d = r[1]
                        idx = index[k] + offset
                        if d < best or (d == best and idx < best_index):
                            best = d
                            best_index = idx
                            best_k = k
                            w_sqr, w_x, w_y, w_z = r[2], r[3], r[4], r[5]
                            w_feature = r[6]
                            w_a0, w_a1, w_a2 = r[7], r[8], r[9]
                            w_flag = r[10]
                    if RADIUS >= 0:
                        # The best may be negative (inside a rounded primitive).
                        reach = max(min(min(best, upper) * s, cap), 0.0) + SLACK
                    else:
                        reach = min(min(best, upper) * s, cap) + SLACK
                    limit = reach * reach
            node = -1
        else:
            left = np.int64(child[node])  # node numbers in int64: the bounds' tests compile once
            right = left + 1
            # The oriented box only where the box alone does not prune.
            bl = _box_sqr(bounds, left, s, qx, qy, qz)
            dl = bl
            if dl <= limit:
                dl = max(dl, _slabs_sqr(bounds, left, s, qx, qy, qz))
            br = _box_sqr(bounds, right, s, qx, qy, qz)
            dr = br
            if dr <= limit:
                dr = max(dr, _slabs_sqr(bounds, right, s, qx, qy, qz))
            # The nearer box first (see the module docstring); inside both, the nearer bound.
            if br < bl or (br == bl and dr < dl):
                left, right, dl, dr = right, left, dr, dl
            if dl <= limit:
                if dr <= limit:
                    stack_node[sp] = right
                    stack_sqr[sp] = dr
                    sp += 1
                node = left
            elif dr <= limit:  # ordered by the boxes, the far one may be the one left
                node = right
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
    return best, best_index, best_k, upper, lowest, w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag


def _search_block(block, tree, depth, magnitude, points, order, out, full, cutoff):
    """Nearest primitive to each point of ``block`` (points ``block * BLOCK``
    on, in the sequence ``order``); with ``full=False`` only the distances
    and ``undecided`` are written (``undecided`` by a method with an exact
    fallback alone: for the others it is empty).

    ``cutoff`` (``inf`` for none) bounds the search from the start: a point
    with nothing within it gets an infinite distance, and no primitive
    farther is visited.  The answers within it are those without a cutoff:
    the pruning never skips a primitive at most ``cutoff`` away.

    ``tree`` is a :data:`TreeArrays` record (the primitives in leaf order,
    their cull rows, the nodes as :class:`~.tree.Tree` describes them),
    ``magnitude`` the largest coordinate magnitude of the node boxes, and
    ``out`` a :data:`Outputs` record.  Points are visited in the sequence
    ``order``, so that consecutive queries walk the same part of the tree.

    Certified answers the filter leaves undecided are not known here: such
    a primitive only narrows ``[lo, hi]`` around its answer (from the robust
    one), and where one could be the nearest, ``undecided[i]`` is set to the
    distance bound below which candidates must be resolved exactly
    (otherwise NaN).
    """
    kinds, params, index, cull, bounds, child, count = tree
    dist, sqr, point, feature, extra, flag, prim, undecided = out
    n = points.shape[0]
    # Above every caller's index, which may reach past the stored count
    # where copies were left out (:func:`~.build.distinct`): an infinite
    # answer, which ties with the initial ``best``, then still wins.
    sentinel = _SENTINEL
    stack_node = np.empty(depth + 1, np.int64)
    stack_sqr = np.empty(depth + 1)
    lanes = np.empty(LANES, np.int64)
    z = np.empty((PAIR_ROWS, LANES))
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
            state = (
                best, best_index, best_k, upper, lowest,
                w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag,
            )  # fmt: skip
            near = (near_x, near_y, near_z)
            state = DESCEND(
                tree, 0, stack_node, stack_sqr, lanes, z, magnitude, px, py, pz, cutoff, *near, 0, state
            )  # fmt: skip
            best, best_index, best_k, upper, lowest = state[:5]
            w_sqr, w_x, w_y, w_z, w_feature, w_a0, w_a1, w_a2, w_flag = state[5:]
        if best_k >= 0:
            near_x, near_y, near_z = w_x, w_y, w_z
        if EXACT_FALLBACK:
            # An undecided answer could be the least (or tie with it): resolve
            # every candidate up to the bound exactly, outside the kernel.
            undecided[i] = min(best, upper) if lowest < math.inf and lowest <= min(best, cutoff) else math.nan
        finite = math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)
        if finite and (best > cutoff or (best_k < 0 and cutoff < math.inf)):
            # Nothing within the cutoff (or an answer beyond it).
            no_answer(i, math.inf, full, dist, sqr, point, extra, feature, flag, prim)
            continue
        if best_k < 0:
            no_answer(i, math.nan, full, dist, sqr, point, extra, feature, flag, prim)
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


@inline
def _rounded(r, radius, px, py, pz, certify):
    """A primitive's answer ``r`` for the primitive rounded by ``radius``:
    ``d - radius`` (the closest point stays the core's: the caller moves it
    to the rounded surface, :func:`proximity.numerics.rounding.surface_points`).
    ``certify``: the status is ``EXACT`` where ``d - radius`` is not known
    to be faithful."""
    st, d, sqr, x, y, z, f, a0, a1, a2, flag = r
    ok, e = faithful_difference(d, radius)
    if certify and not ok:
        st = certified.EXACT
    return st, e, sqr, x, y, z, f, a0, a1, a2, flag


@inline
def _less(lo, hi, radius):
    """Bounds on ``d* - radius`` from bounds on ``d*``, widened by the subtractions' rounding."""
    w = 2.0 * EPS * (abs(hi) + radius) + 5e-324
    return lo - radius - w, hi - radius + w


def _loop(handle, lo, hi, tree, depth, magnitude, points, order, out, full, cutoff):
    """:func:`_search_block` for the blocks of points ``lo .. hi - 1``."""
    for block in range(lo, hi):
        CALL(handle, block, tree, depth, magnitude, points, order, out, full, cutoff)


def _blocks(tree, depth, magnitude, points, *args):
    """The number of blocks of :func:`_loop`."""
    return (points.shape[0] + BLOCK - 1) // BLOCK


def _link(kinds, q, k, px, py, pz):
    kind = kinds[k]
    if kind >= LOW and kind <= HIGH:
        return ROW(kind, q, k, px, py, pz)
    return NEXT(kinds, q, k, px, py, pz)


def _last(kinds, q, k, px, py, pz):
    return ROW(kinds[k], q, k, px, py, pz)


def _chain(present, make, tag):
    """One function ``f(kinds, params, k, px, py, pz)`` that calls, for stored
    row ``k``, the function ``make(primitive)`` of its kind.

    Kinds whose kernel module gives them the same function (disks and
    circles) share one link, so that it is compiled once.
    """
    groups = []  # [function, low code, high code]
    for p in present:
        fn = make(p)
        if groups and groups[-1][0] is fn and groups[-1][2] == p.code - 1:
            groups[-1][2] = p.code
        else:
            groups.append([fn, p.code, p.code])
    names = "_".join(p.name for p in present)
    fn, low, high = groups[-1]
    chain = specialize(_last, f"{tag}__{names}__{low}", role="spliced", ROW=fn)
    for fn, low, high in reversed(groups[:-1]):
        bindings = dict(ROW=fn, NEXT=chain, LOW=low, HIGH=high)
        chain = specialize(_link, f"{tag}__{names}__{low}", role="spliced", **bindings)
    return chain


def _row_batch(method, present, radius, indexed):
    """The rows side by side of :func:`descent`, or None: only in a tree of one
    kind whose module offers them for the method (its answers are then
    always certain), unrounded."""
    if len(present) != 1 or radius >= 0:
        return None
    batch = getattr(present[0].kernels, "row_batch", None)
    layout = {"indexed": True} if indexed else {}
    return batch(present[0], method, **layout) if batch is not None else None


@functools.cache
def reads_cull(method, present, radius=-1):
    """Whether the search of ``method`` over trees holding the kinds ``present``
    (see :func:`descent`) reads its primitives' cull rows: not where it
    answers rows side by side."""
    return _row_batch(method, present, radius, False) is None


@functools.cache
def descent(method, present, radius=-1, indexed=False):
    """:func:`_descend` compiled for ``method``, the kinds ``present`` and the radius column;
    ``indexed``: for a tree of faces read through their vertices (``present`` is the triangle alone)."""
    suffix = "_indexed" if indexed else ""
    tag = method.name + suffix
    names = "_".join(p.name for p in present) + ("_rounded" if radius >= 0 else "")
    # Only the triangle reads its rows through vertices: the other kinds keep the one signature.
    layout = {"indexed": True} if indexed else {}
    rows = _row_batch(method, present, radius, indexed)
    return specialize(
        _descend,
        f"{tag}__{names}",
        role="inline",
        BATCH=rows is not None,
        ROWS=rows,
        EVALUATE=_chain(present, lambda p: p.kernels.row_query(p, method, **layout), tag),
        INTERVAL=_chain(present, lambda p: p.kernels.row_interval(p, **layout), "interval" + suffix),
        EXACT_FALLBACK=method.exact_fallback,
        SEED_POINT=not method.loose,
        RADIUS=radius,
    )


@functools.cache
def search_kernel(method, present, radius=-1, indexed=False):
    """The compiled search of ``method`` over trees holding the kinds
    ``present`` (:class:`~proximity.primitives.Primitive` records), with
    their radii in column ``radius`` of the rows (-1: none), as a function
    of the loop's arguments but the handle; ``indexed``: over a tree of
    faces read through their vertices (:meth:`.tree.Tree.rows`)."""
    tag = method.name + ("_indexed" if indexed else "")
    names = "_".join(p.name for p in present) + ("_rounded" if radius >= 0 else "")
    block_signature, loop_signature = _SIGNATURES[indexed]
    block = specialize(
        _search_block,
        f"{tag}__{names}",
        block_signature,
        role="pointer",
        DESCEND=descent(method, present, radius, indexed),
        EXACT_FALLBACK=method.exact_fallback,
    )
    loop = "search_indexed" if indexed else "search"
    return launcher(_loop, loop, loop_signature, block, block_signature, _blocks, SEARCH_GRAIN)


@kernel()
def _gather(cull, bounds, child, count, depth, magnitude, p, bound, out):
    """Stored primitives not culled at distance ``bound`` from ``p``, by the same tests as the search.

    Writes their positions to ``out`` and returns how many.  Every primitive
    whose computed distance is at most ``bound`` is among them.
    """
    px, py, pz = p[0], p[1], p[2]
    s = _scale(px, py, pz, magnitude)
    qx, qy, qz = px * s, py * s, pz * s
    reach = max(bound * s, 0.0) + SLACK  # a bound below 0: inside a rounded primitive
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
