"""Bounds on the distance between two nodes, or two primitives, of two hierarchies.

The tests of the simultaneous descent (:mod:`.descent`), and why pruning by
them never changes its answer.

Lower bounds
------------
For convex sets ``X`` and ``Y`` and any orthogonal axes ``u, v, w`` no
longer than 1, ``dist(X, Y)^2 >= g_u^2 + g_v^2 + g_w^2``, where ``g_u`` is
the gap between the intervals of ``u . X`` and ``u . Y``: the closest
pair's difference has at least that component along each axis.  Three
such sums bound a pair of nodes, the largest wins:

* over the coordinate axes: the two boxes;
* over side a's oriented box's axes (:mod:`proximity.broadphase.refit`: the mean normal ``u``
  and two axes across it), between a's slabs and b's oriented box;
* over side b's axes, the same the other way round;
* along the line between the two centres (one axis), which separates
  nodes far apart best.

A node's oriented box is kept per node (:func:`node_arrays`) as a
parallelepiped ``{c + sum_j t_j h_j A_j : |t_j| <= 1}`` over its slabs'
axes ``A_j``; where a slab is unbounded (a leaf of one primitive, whose
only slab is its normal), the node's box stands in for it, over the
coordinate axes.  The projection of a parallelepiped on an axis ``u`` is
``u . c +- sum_j |u . A_j| h_j``, which holds for side b's posed axes
``R A_j`` too, whatever the rounding of ``R``: it is the image of the
parallelepiped.  Axes longer than 1 (a posed axis rounded up) divide
their gap by their length.

A pair of primitives is bounded by their boxes and by each one's slab
(its plane's normal) against the other's vertices, widened by the rows'
radii.  The distance between two points of the sides (``rep``, the first
vertex below each node) bounds the answer from above.

Why nothing that matters is pruned
----------------------------------
The tests run on coordinates scaled by a power of two ``s`` with ``M s``
in ``[0.5, 1)``, ``M`` the largest coordinate magnitude of both sides'
(posed) roots and radii, as :mod:`proximity.broadphase.bounds` does, so that squares neither
overflow nor lose what matters to underflow.  The slabs' axes are
shortened by ``2^-40`` and orthogonal far within it; a parallelepiped's
half-widths are widened by ``2^-30`` over its axes' lengths, so that it
holds its node despite their rounding; posing a box or a vertex rounds a
few ``eps M``.  With the pair methods' errors (``robust``: ``16 eps S``,
``S <= 2 M``; ``certified``: an ulp) these add to well under the slack,
``256 eps M`` (:data:`.descent.SLACK`), so a pair is skipped only where its
computed answer exceeds the best one.
"""

import math
import weakref

import numpy as np

from .. import primitives
from ..runtime.jit import inline, kernel

_VERTICES = primitives.vertex_counts()

#: Columns of a node's row in the table the descent reads (:func:`node_arrays`), 32 a
#: node (four cache lines), so that a node's tests read one place: its box (low and
#: high corners), its parallelepiped's centre, half-widths, own half-widths along its
#: axes (the Gram terms, which turning the axes keeps) and axes (:func:`frame`), a
#: point below it (:func:`upper`), and its ``child`` and ``count`` as
#: :class:`~.tree.Tree` keeps them.
CENTRE, HALF, OWN, AXES, REP, CHILD, COUNT = 6, 9, 12, 15, 24, 27, 28
NODE_WIDTH = 32

_cache = weakref.WeakKeyDictionary()


def node_data(tree):
    """``(nodes, magnitude, params)`` of a :class:`~.tree.Tree`: its nodes' table, the largest
    finite coordinate magnitude of its root box, and its rows (:attr:`~.tree.Tree.params`,
    gathered once where the tree reads its faces through their vertices), computed once per
    tree."""
    data = _cache.get(tree)
    if data is None:
        params = tree.params
        nodes = node_arrays(tree.kinds, params, tree.bounds, tree.child, tree.count)
        root = [abs(x) for x in tree.bounds[0, :6].tolist() if math.isfinite(x)]
        data = _cache[tree] = (nodes, max(root, default=0.0), params)
    return data


def node_arrays(kinds, params, bounds, child, count):
    """The table of nodes ``bounds``, ``child``, ``count`` over stored rows ``params``."""
    # Rows start on cache lines (64 bytes), so that each is four lines, not five.
    flat = np.zeros(len(child) * NODE_WIDTH + 8)
    skip = (-flat.ctypes.data % 64) // 8
    nodes = flat[skip : skip + len(child) * NODE_WIDTH].reshape(len(child), NODE_WIDTH)
    _fill(kinds, params, bounds, child, count, _VERTICES, nodes)
    nodes.flags.writeable = False
    return nodes


@inline
def _slab(bounds, n, c0):
    """One slab's share of a frame: ``A m / |A|^2``, the half-width over ``|A|^2``, and
    whether it is bounded."""
    ux, uy, uz = bounds[n, c0], bounds[n, c0 + 1], bounds[n, c0 + 2]
    q = ux * ux + uy * uy + uz * uz
    lo, hi = bounds[n, c0 + 3], bounds[n, c0 + 4]
    ok = q > 0.0 and lo > -math.inf and hi < math.inf
    m = (lo * 0.5 + hi * 0.5) / q if ok else 0.0
    h = (hi * 0.5 - lo * 0.5) / q * (1.0 + 2.0**-30) if ok else 0.0
    return ux * m, uy * m, uz * m, h, ok


@kernel()
def _fill(kinds, params, bounds, child, count, vertices, nodes):
    for n in range(child.shape[0]):
        for c in range(6):
            nodes[n, c] = bounds[n, c]
        nodes[n, CHILD], nodes[n, COUNT] = child[n], count[n]
        x0, y0, z0, h0, ok0 = _slab(bounds, n, 6)
        x1, y1, z1, h1, ok1 = _slab(bounds, n, 11)
        x2, y2, z2, h2, ok2 = _slab(bounds, n, 16)
        if ok0 and ok1 and ok2:
            nodes[n, CENTRE], nodes[n, CENTRE + 1] = x0 + x1 + x2, y0 + y1 + y2
            nodes[n, CENTRE + 2] = z0 + z1 + z2
            nodes[n, HALF], nodes[n, HALF + 1], nodes[n, HALF + 2] = h0, h1, h2
            for j in range(3):
                for c in range(3):
                    nodes[n, AXES + 3 * j + c] = bounds[n, 6 + 5 * j + c]
            a0 = (bounds[n, 6], bounds[n, 7], bounds[n, 8])
            a1 = (bounds[n, 11], bounds[n, 12], bounds[n, 13])
            a2 = (bounds[n, 16], bounds[n, 17], bounds[n, 18])
            # The projection of the parallelepiped on each of its axes (Gram terms), widened
            # by 2^-30 so that the rounding of posed axes' dot products stays within it.
            g01, g02, g12 = abs(_dot(a0, a1)), abs(_dot(a0, a2)), abs(_dot(a1, a2))
            widen = 1.0 + 2.0**-30
            nodes[n, OWN] = (_dot(a0, a0) * h0 + g01 * h1 + g02 * h2) * widen
            nodes[n, OWN + 1] = (g01 * h0 + _dot(a1, a1) * h1 + g12 * h2) * widen
            nodes[n, OWN + 2] = (g02 * h0 + g12 * h1 + _dot(a2, a2) * h2) * widen
        else:
            # The box itself, over the coordinate axes.
            for a in range(3):
                nodes[n, CENTRE + a] = bounds[n, a] * 0.5 + bounds[n, 3 + a] * 0.5
                nodes[n, HALF + a] = bounds[n, 3 + a] * 0.5 - bounds[n, a] * 0.5
                nodes[n, OWN + a] = nodes[n, HALF + a]
                nodes[n, AXES + 4 * a] = 1.0
    # Children come after their parents: backwards, a node's first child is done.
    for n in range(child.shape[0] - 1, -1, -1):
        if count[n] > 0:
            k = child[n]
            ok = vertices[kinds[k]] > 0
            for c in range(3):
                nodes[n, REP + c] = params[k, c] if ok else math.nan
        else:
            for c in range(3):
                nodes[n, REP + c] = nodes[child[n], REP + c]


# -- nodes ----------------------------------------------------------------------------


@inline
def gap(lo1, hi1, lo2, hi2):
    """The gap between two intervals: 0 where they overlap (and where a bound is NaN)."""
    g = max(lo1 - hi2, lo2 - hi1)
    return g if g > 0.0 else 0.0


@inline
def box_gap2(a, b):
    """Squared distance between two boxes given as centres and half-extents."""
    gx = gap(a[0] - a[3], a[0] + a[3], b[0] - b[3], b[0] + b[3])
    gy = gap(a[1] - a[4], a[1] + a[4], b[1] - b[4], b[1] + b[4])
    gz = gap(a[2] - a[5], a[2] + a[5], b[2] - b[5], b[2] + b[5])
    return gx * gx + gy * gy + gz * gz


@inline
def plain_box(bounds, n, s):
    """Row ``n``'s box (``bounds[n, :6]``, low and high corners) as centre and half-extents, scaled."""
    cx = bounds[n, 0] * 0.5 + bounds[n, 3] * 0.5
    cy = bounds[n, 1] * 0.5 + bounds[n, 4] * 0.5
    cz = bounds[n, 2] * 0.5 + bounds[n, 5] * 0.5
    ex = bounds[n, 3] * 0.5 - bounds[n, 0] * 0.5
    ey = bounds[n, 4] * 0.5 - bounds[n, 1] * 0.5
    ez = bounds[n, 5] * 0.5 - bounds[n, 2] * 0.5
    return cx * s, cy * s, cz * s, ex * s, ey * s, ez * s


@inline
def posed(pose, x, y, z):
    """``R (x, y, z) + t``, each coordinate ``((r0 x + r1 y) + r2 z) + t``."""
    return (
        ((pose[0, 0] * x + pose[0, 1] * y) + pose[0, 2] * z) + pose[0, 3],
        ((pose[1, 0] * x + pose[1, 1] * y) + pose[1, 2] * z) + pose[1, 3],
        ((pose[2, 0] * x + pose[2, 1] * y) + pose[2, 2] * z) + pose[2, 3],
    )


@inline
def _turned(pose, x, y, z):
    return (
        pose[0, 0] * x + pose[0, 1] * y + pose[0, 2] * z,
        pose[1, 0] * x + pose[1, 1] * y + pose[1, 2] * z,
        pose[2, 0] * x + pose[2, 1] * y + pose[2, 2] * z,
    )


@inline
def posed_box(bounds, n, pose, s, is_posed):
    """Row ``n``'s box, posed where ``is_posed`` (the box of the posed box: ``R c + t`` and
    ``|R| e``), as centre and half-extents, scaled."""
    if not is_posed:
        return plain_box(bounds, n, s)
    b = plain_box(bounds, n, 1.0)
    cx, cy, cz = posed(pose, b[0], b[1], b[2])
    fx = abs(pose[0, 0]) * b[3] + abs(pose[0, 1]) * b[4] + abs(pose[0, 2]) * b[5]
    fy = abs(pose[1, 0]) * b[3] + abs(pose[1, 1]) * b[4] + abs(pose[1, 2]) * b[5]
    fz = abs(pose[2, 0]) * b[3] + abs(pose[2, 1]) * b[4] + abs(pose[2, 2]) * b[5]
    return cx * s, cy * s, cz * s, fx * s, fy * s, fz * s


@inline
def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@inline
def frame(nodes, n, pose, s, is_posed):
    """Node ``n``'s parallelepiped, scaled and posed where ``is_posed``:
    ``(c, (A0, A1, A2), h, (r0, r1, r2))`` with ``r_j`` its own half-width along ``A_j``."""
    c = (nodes[n, CENTRE], nodes[n, CENTRE + 1], nodes[n, CENTRE + 2])
    h = (nodes[n, HALF] * s, nodes[n, HALF + 1] * s, nodes[n, HALF + 2] * s)
    a0 = (nodes[n, AXES], nodes[n, AXES + 1], nodes[n, AXES + 2])
    a1 = (nodes[n, AXES + 3], nodes[n, AXES + 4], nodes[n, AXES + 5])
    a2 = (nodes[n, AXES + 6], nodes[n, AXES + 7], nodes[n, AXES + 8])
    if is_posed:
        c = posed(pose, c[0], c[1], c[2])
        a0 = _turned(pose, a0[0], a0[1], a0[2])
        a1 = _turned(pose, a1[0], a1[1], a1[2])
        a2 = _turned(pose, a2[0], a2[1], a2[2])
    c = (c[0] * s, c[1] * s, c[2] * s)
    return c, (a0, a1, a2), h, (nodes[n, OWN] * s, nodes[n, OWN + 1] * s, nodes[n, OWN + 2] * s)


@inline
def _norm_gap(g, a):
    q = _dot(a, a)
    return g / math.sqrt(q) if q > 1.0 else g


@inline
def lb2(fa, box_a, fb, box_b, limit):
    """Squared lower bound (scaled) on the distance between two nodes, from their frames
    (:func:`frame`) and boxes: the largest of the sums of the module docstring, or the first
    found above ``limit`` (which prunes the pair whatever the others)."""
    g = box_gap2(box_a, box_b)
    if g > limit:
        return g
    ca, (a0, a1, a2), ha, ra = fa
    cb, (b0, b1, b2), hb, rb = fb
    # C[i][j] = A_i . B_j
    c00, c01, c02 = abs(_dot(a0, b0)), abs(_dot(a0, b1)), abs(_dot(a0, b2))
    c10, c11, c12 = abs(_dot(a1, b0)), abs(_dot(a1, b1)), abs(_dot(a1, b2))
    c20, c21, c22 = abs(_dot(a2, b0)), abs(_dot(a2, b1)), abs(_dot(a2, b2))
    dx, dy, dz = cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2]
    # Along a's axes: a's own half-width against b's projected one.
    g0 = abs(a0[0] * dx + a0[1] * dy + a0[2] * dz) - ra[0] - (c00 * hb[0] + c01 * hb[1] + c02 * hb[2])
    g1 = abs(a1[0] * dx + a1[1] * dy + a1[2] * dz) - ra[1] - (c10 * hb[0] + c11 * hb[1] + c12 * hb[2])
    g2 = abs(a2[0] * dx + a2[1] * dy + a2[2] * dz) - ra[2] - (c20 * hb[0] + c21 * hb[1] + c22 * hb[2])
    g0, g1, g2 = _norm_gap(max(g0, 0.0), a0), _norm_gap(max(g1, 0.0), a1), _norm_gap(max(g2, 0.0), a2)
    ga = g0 * g0 + g1 * g1 + g2 * g2
    if ga > limit:
        return ga
    # Along b's axes.
    h0 = abs(b0[0] * dx + b0[1] * dy + b0[2] * dz) - rb[0] - (c00 * ha[0] + c10 * ha[1] + c20 * ha[2])
    h1 = abs(b1[0] * dx + b1[1] * dy + b1[2] * dz) - rb[1] - (c01 * ha[0] + c11 * ha[1] + c21 * ha[2])
    h2 = abs(b2[0] * dx + b2[1] * dy + b2[2] * dz) - rb[2] - (c02 * ha[0] + c12 * ha[1] + c22 * ha[2])
    h0, h1, h2 = _norm_gap(max(h0, 0.0), b0), _norm_gap(max(h1, 0.0), b1), _norm_gap(max(h2, 0.0), b2)
    gb = h0 * h0 + h1 * h1 + h2 * h2
    if gb > limit:
        return gb
    # Along the line between the centres, which separates far nodes best.
    dd = dx * dx + dy * dy + dz * dz
    gc = 0.0
    if dd > 0.0:
        length = math.sqrt(dd)
        k = (1.0 - 2.0**-40) / length
        u = (dx * k, dy * k, dz * k)
        reach_a = abs(_dot(u, a0)) * ha[0] + abs(_dot(u, a1)) * ha[1] + abs(_dot(u, a2)) * ha[2]
        reach_b = abs(_dot(u, b0)) * hb[0] + abs(_dot(u, b1)) * hb[1] + abs(_dot(u, b2)) * hb[2]
        gc = max((u[0] * dx + u[1] * dy + u[2] * dz) - reach_a - reach_b, 0.0)
    return max(max(max(g, ga), gb), gc * gc)


@inline
def node_lb2(nodes_a, na, nodes_b, nb, pose, s, is_posed):
    """Squared lower bound (scaled) on the distance between nodes ``na`` and ``nb``."""
    fa = frame(nodes_a, na, pose, s, False)
    fb = frame(nodes_b, nb, pose, s, is_posed)
    return lb2(fa, plain_box(nodes_a, na, s), fb, posed_box(nodes_b, nb, pose, s, is_posed), math.inf)


@inline
def size(bounds, n):
    """The squared diagonal of row ``n``'s box: which node of a pair to split."""
    ex, ey, ez = bounds[n, 3] - bounds[n, 0], bounds[n, 4] - bounds[n, 1], bounds[n, 5] - bounds[n, 2]
    return ex * ex + ey * ey + ez * ez


@inline
def upper(nodes_a, na, nodes_b, nb, pose, s, is_posed):
    """The distance (scaled) between the points ``rep`` of nodes ``na`` and ``nb`` (b posed):
    an upper bound on the distance between what they hold; NaN where a side has none."""
    x, y, z = nodes_b[nb, REP], nodes_b[nb, REP + 1], nodes_b[nb, REP + 2]
    if is_posed:
        x, y, z = posed(pose, x, y, z)
    dx = nodes_a[na, REP] * s - x * s
    dy = nodes_a[na, REP + 1] * s - y * s
    dz = nodes_a[na, REP + 2] * s - z * s
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@inline
def first(nodes, n):
    """Node ``n``'s first child, or first stored primitive where it is a leaf."""
    return np.int64(nodes[n, CHILD])


@inline
def held(nodes, n):
    """How many stored primitives node ``n`` holds: 0 where it has children."""
    return np.int64(nodes[n, COUNT])


# -- primitives -------------------------------------------------------------------------


@inline
def pose_row(qb, kb, kind, pose, tb, is_posed):
    """Row ``kb`` of ``qb`` into ``tb[0]``, its vertices posed where ``is_posed`` (the rest copied)."""
    nv = _VERTICES[kind]
    for c in range(qb.shape[1]):
        tb[0, c] = qb[kb, c]
    if is_posed:
        for v in range(nv):
            x, y, z = posed(pose, qb[kb, 3 * v], qb[kb, 3 * v + 1], qb[kb, 3 * v + 2])
            tb[0, 3 * v], tb[0, 3 * v + 1], tb[0, 3 * v + 2] = x, y, z


@inline
def hull_gap(cull, k, rows, j, nv, grow, s):
    """The gap (scaled) along primitive ``k``'s slab to the ``nv`` points at the start of row
    ``j`` of ``rows``, widened by ``grow``: 0 where it has no slab or they are no hull."""
    ux, uy, uz = cull[k, 6], cull[k, 7], cull[k, 8]
    if nv == 0 or (ux == 0.0 and uy == 0.0 and uz == 0.0):
        return 0.0
    low, high = math.inf, -math.inf
    for v in range(nv):
        h = ux * rows[j, 3 * v] + uy * rows[j, 3 * v + 1] + uz * rows[j, 3 * v + 2]
        low, high = min(low, h), max(high, h)
    return gap(cull[k, 9] * s, cull[k, 10] * s, (low - grow) * s, (high + grow) * s)


@inline
def centre_gap(ra, ka, nva, grow_a, rb, kb, nvb, grow_b, s):
    """The gap (scaled) between the ``nva`` points of row ``ka`` of ``ra`` and the ``nvb`` of row
    ``kb`` of ``rb``, each widened by its radius, along the line between their first points'
    mean and the other's: tight for primitives far apart; 0 where a side is no hull."""
    if nva == 0 or nvb == 0:
        return 0.0
    ax, ay, az = _mean(ra, ka, nva, s)
    bx, by, bz = _mean(rb, kb, nvb, s)
    dx, dy, dz = bx - ax, by - ay, bz - az
    dd = dx * dx + dy * dy + dz * dz
    if not dd > 0.0:
        return 0.0
    k = (1.0 - 2.0**-40) / math.sqrt(dd)
    ux, uy, uz = dx * k, dy * k, dz * k
    high_a, low_b = -math.inf, math.inf
    for v in range(nva):
        high_a = max(high_a, (ux * ra[ka, 3 * v] + uy * ra[ka, 3 * v + 1] + uz * ra[ka, 3 * v + 2]) * s)
    for v in range(nvb):
        low_b = min(low_b, (ux * rb[kb, 3 * v] + uy * rb[kb, 3 * v + 1] + uz * rb[kb, 3 * v + 2]) * s)
    g = (low_b - grow_b * s) - (high_a + grow_a * s)
    return g if g > 0.0 else 0.0


@inline
def _mean(rows, k, nv, s):
    x, y, z = 0.0, 0.0, 0.0
    for v in range(nv):
        x, y, z = x + rows[k, 3 * v] * s, y + rows[k, 3 * v + 1] * s, z + rows[k, 3 * v + 2] * s
    return x / nv, y / nv, z / nv


@inline
def row_box(rows, j, nv, cull, k, grow, s):
    """The box (centre, half-extents, scaled) of the ``nv`` points of row ``j``, widened by
    ``grow``; where they are no hull, ``cull[k]``'s box."""
    if nv == 0:
        return plain_box(cull, k, s)
    lx, ly, lz = math.inf, math.inf, math.inf
    hx, hy, hz = -math.inf, -math.inf, -math.inf
    for v in range(nv):
        x, y, z = rows[j, 3 * v], rows[j, 3 * v + 1], rows[j, 3 * v + 2]
        lx, ly, lz = min(lx, x), min(ly, y), min(lz, z)
        hx, hy, hz = max(hx, x), max(hy, y), max(hz, z)
    return (
        (lx * 0.5 + hx * 0.5) * s, (ly * 0.5 + hy * 0.5) * s, (lz * 0.5 + hz * 0.5) * s,
        (hx * 0.5 - lx * 0.5 + grow) * s, (hy * 0.5 - ly * 0.5 + grow) * s, (hz * 0.5 - lz * 0.5 + grow) * s,
    )  # fmt: skip
