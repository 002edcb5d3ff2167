"""Distance between two triangles.

Follows Geometric Tools' triangle-triangle query (D. Eberly, ``DistTriangle3Triangle3``):
the distance between triangles ``A`` (shape a, vertices ``A0 A1 A2``) and
``B`` (shape b, ``B0 B1 B2``) is the least of the segment-triangle
distances of each edge of one against the other, which is the reduction of
*Distance Between a Line Segment and a Triangle* (Geometric Tools, 2019)
applied six times.  Witnesses carry barycentric coordinates over each
triangle's vertices.

``robust``
    The nearest of 21 candidates, each a pair of points on the triangles,
    the union of the six segment-triangle queries' candidates without
    repeats: each vertex of one triangle against the other (six
    point-triangle queries), the interior candidate of each edge of ``A``
    against each edge of ``B`` (nine), and where each edge of one crosses
    the other's plane, against that triangle (six).  The argument of
    :mod:`.segment_triangle` carries over: every candidate is a pair of
    points on the shapes, and the lowest feature pair holding the closest
    points (a vertex against anything, two edges, or an edge crossing a
    face) has a candidate within ``eta`` of it.  Two faces never need one:
    where their closest points are interior to both, the faces are parallel
    and a lower pair holds closest points too.  Every candidate is computed
    and one selected without branches.

    For every finite input, ``|d - d*| <= 16 eps S + 2^-1075`` with ``S`` the
    largest coordinate difference between the six vertices, with the
    scaling, witnesses and features of :mod:`.segment_triangle`.

``robust_unscaled``
    As in :mod:`.segment_triangle`: the SIMD pass of a batch loop.

``certified``
    As :mod:`.segment_triangle`: the robust pair's optimality conditions are
    verified strictly (a vertex or an edge of ``A`` is checked as the
    endpoint or interior of each edge of ``A`` holding it against ``B``, plus
    ``A``'s own cone at an edge, and symmetrically for a face of ``A``
    against a vertex of ``B``), then the distance is rounded faithfully from
    double-double.  Intersecting triangles touch along a segment whose ends
    are edges crossing faces; the answer is the lowest pair: every vertex of
    ``A`` certainly off ``B`` (strictly off its plane or beyond an edge),
    then ``A``'s edges in order until one certainly crosses ``B``'s open face
    (the others certainly missing ``B``), else the same for ``B``'s edges
    against ``A``.  The distance is then
    exactly 0, with the crossing point as both witnesses.  Everything else
    goes to :func:`proximity.numerics.exact.triangle_triangle`.  Ties go to the
    lowest ``(feature_a, feature_b)`` codes.
"""

import math

from ..features import EDGE01, EDGE12, EDGE20, FACE, NONE, VERTEX0, VERTEX1, VERTEX2
from ..numerics import certified as cf
from ..numerics.fp import SAFE_MAX, SAFE_MIN, UNSCALED, pow2_scale
from ..point.triangle import _robust_local as _point_local
from ..runtime.jit import inline, part
from .segment_segment import _interior, _max3, _scaled, _triple_sign, absolute
from .segment_triangle import (
    _cross_of,
    _cross_sign,
    _cross_sign_triple,
    _crossing_candidate,
    _dd_neg,
    _dd_sub,
    _holds,
    _lead,
    _neg,
    _normal_sign,
    _sqr_distance,
    _sub,
)


@inline
def _differences(q, a, b):
    """Differences of the inputs times ``q`` (a power of two), each rounded once:
    ``w[i][j] = B_j - A_i`` and the edges ``ga``, ``gb`` (``V_{k+1} - V_k``)."""
    a = tuple_scaled(a, q)
    b = tuple_scaled(b, q)
    w = (
        (_sub(b[0], a[0]), _sub(b[1], a[0]), _sub(b[2], a[0])),
        (_sub(b[0], a[1]), _sub(b[1], a[1]), _sub(b[2], a[1])),
        (_sub(b[0], a[2]), _sub(b[1], a[2]), _sub(b[2], a[2])),
    )
    ga = (_sub(a[1], a[0]), _sub(a[2], a[1]), _sub(a[0], a[2]))
    gb = (_sub(b[1], b[0]), _sub(b[2], b[1]), _sub(b[0], b[2]))
    return w, ga, gb


@inline
def tuple_scaled(v, q):
    """Three points times ``q``."""
    return (
        (v[0][0] * q, v[0][1] * q, v[0][2] * q),
        (v[1][0] * q, v[1][1] * q, v[1][2] * q),
        (v[2][0] * q, v[2][1] * q, v[2][2] * q),
    )


@inline
def _max9(t):
    return max(max(_max3(t[0]), _max3(t[1])), _max3(t[2]))


@inline
def _largest(w, ga, gb):
    return max(max(max(_max9(w[0]), _max9(w[1])), _max9(w[2])), max(_max9(ga), _max9(gb)))


@inline
def _scale3(t, f1, f2):
    return _scaled(t[0], f1, f2), _scaled(t[1], f1, f2), _scaled(t[2], f1, f2)


@inline
def _frame_a(w, ga, gb, k):
    """Edge ``k`` of ``A`` (from ``A_k`` to ``A_{k+1}``) against ``B``, as the
    differences of :mod:`.segment_triangle`: ``(e, w0, w1, g)``."""
    p, q = k, (k + 1) % 3
    return ga[k], w[p], w[q], gb


@inline
def _frame_b(w, ga, gb, k):
    """Edge ``k`` of ``B`` against ``A``, the roles swapped."""
    r, u = k, (k + 1) % 3
    w0 = (_neg(w[0][r]), _neg(w[1][r]), _neg(w[2][r]))
    w1 = (_neg(w[0][u]), _neg(w[1][u]), _neg(w[2][u]))
    return gb[k], w0, w1, ga


@inline
def _on_edge(k, s):
    """The feature code (as a float) and barycentrics of the point at parameter
    ``s`` along edge ``k``: an end vertex where the clamp put it."""
    p, q = k, (k + 1) % 3
    code = float(EDGE01) if k == 0 else (float(EDGE12) if k == 1 else float(EDGE20))
    code = float(p) if s == 0.0 else (float(q) if s == 1.0 else code)
    b = (1.0 - s, s, 0.0) if k == 0 else ((0.0, 1.0 - s, s) if k == 1 else (s, 0.0, 1.0 - s))
    return code, b[0], b[1], b[2]


@inline
def _pick(better, new, old):
    """``new if better else old``, element by element, for candidate tuples."""
    return (
        new[0] if better else old[0],
        new[1] if better else old[1],
        new[2] if better else old[2],
        new[3] if better else old[3],
        new[4] if better else old[4],
        new[5] if better else old[5],
        new[6] if better else old[6],
        new[7] if better else old[7],
        new[8] if better else old[8],
        new[9] if better else old[9],
        new[10] if better else old[10],
        new[11] if better else old[11],
        new[12] if better else old[12],
        new[13] if better else old[13],
        new[14] if better else old[14],
        new[15] if better else old[15],
    )


@inline
def _keep(best, c):
    """The nearer of two candidates, the first on a tie."""
    return _pick(c[0] < best[0], c, best)


# A candidate: (sqr_distance, base, ax, ay, az, bx, by, bz, feature_a,
# feature_b, a0, a1, a2, b0, b1, b2), all floats; the witnesses are base +
# (ax, ay, az) and base + (bx, by, bz), base the index of a vertex (0 to 2:
# A0 to A2, 3 to 5: B0 to B2).


@inline
def _vertex_a(w, i):
    """Vertex ``A_i`` against ``B``."""
    _, sqr, x, y, z, fb, b0, b1, b2 = _point_local(*w[i][0], *w[i][1], *w[i][2])
    one = (1.0 if i == 0 else 0.0, 1.0 if i == 1 else 0.0, 1.0 if i == 2 else 0.0)
    return (sqr, float(i), 0.0, 0.0, 0.0, x, y, z, float(i), float(fb), one[0], one[1], one[2], b0, b1, b2)


@inline
def _vertex_b(w, j):
    """Vertex ``B_j`` against ``A``."""
    _, sqr, x, y, z, fa, a0, a1, a2 = _point_local(*_neg(w[0][j]), *_neg(w[1][j]), *_neg(w[2][j]))
    one = (1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0)
    return (sqr, 3.0 + j, x, y, z, 0.0, 0.0, 0.0, float(fa), float(j), a0, a1, a2, one[0], one[1], one[2])


@inline
def _edges(w, ga, gb, k, m):
    """The interior candidate of edge ``k`` of ``A`` against edge ``m`` of ``B``."""
    p, q = k, (k + 1) % 3
    r, u = m, (m + 1) % 3
    sqr, px, py, pz, x, y, z, s, t = _interior(ga[k], gb[m], w[p][r], w[p][u], w[q][r])
    fa, a0, a1, a2 = _on_edge(k, s)
    fb, b0, b1, b2 = _on_edge(m, t)
    return (sqr, float(p), px, py, pz, px + x, py + y, pz + z, fa, fb, a0, a1, a2, b0, b1, b2)


@inline
def _crossing_a(w, ga, gb, k):
    """Where edge ``k`` of ``A`` crosses ``B``'s plane, against ``B``."""
    c = _crossing_candidate(*_frame_a(w, ga, gb, k))
    fa, a0, a1, a2 = _on_edge(k, c[8])
    return (c[0], float(k), c[2], c[3], c[4], c[5], c[6], c[7], fa, c[9], a0, a1, a2, c[10], c[11], c[12])


@inline
def _crossing_b(w, ga, gb, k):
    """Where edge ``k`` of ``B`` crosses ``A``'s plane, against ``A``."""
    c = _crossing_candidate(*_frame_b(w, ga, gb, k))
    fb, b0, b1, b2 = _on_edge(k, c[8])
    return (c[0], 3.0 + k, c[5], c[6], c[7], c[2], c[3], c[4], c[9], fb, c[10], c[11], c[12], b0, b1, b2)


@inline
def _robust_local(w, ga, gb):
    """The 21 candidates and the nearest, on differences in the safe window;
    ties go to the earlier candidate."""
    # Written out rather than looped: constant indices into the tuples keep
    # the loop over queries free of stack traffic, so that it compiles to
    # SIMD code (see segment_triangle._robust_local).
    best = _vertex_a(w, 0)
    best = _keep(best, _vertex_a(w, 1))
    best = _keep(best, _vertex_a(w, 2))
    best = _keep(best, _vertex_b(w, 0))
    best = _keep(best, _vertex_b(w, 1))
    best = _keep(best, _vertex_b(w, 2))
    best = _keep(best, _edges(w, ga, gb, 0, 0))
    best = _keep(best, _edges(w, ga, gb, 0, 1))
    best = _keep(best, _edges(w, ga, gb, 0, 2))
    best = _keep(best, _edges(w, ga, gb, 1, 0))
    best = _keep(best, _edges(w, ga, gb, 1, 1))
    best = _keep(best, _edges(w, ga, gb, 1, 2))
    best = _keep(best, _edges(w, ga, gb, 2, 0))
    best = _keep(best, _edges(w, ga, gb, 2, 1))
    best = _keep(best, _edges(w, ga, gb, 2, 2))
    best = _keep(best, _crossing_a(w, ga, gb, 0))
    best = _keep(best, _crossing_b(w, ga, gb, 0))
    best = _keep(best, _crossing_a(w, ga, gb, 1))
    best = _keep(best, _crossing_b(w, ga, gb, 1))
    best = _keep(best, _crossing_a(w, ga, gb, 2))
    return _keep(best, _crossing_b(w, ga, gb, 2))


@inline
def _vertex(a, b, index):
    """Vertex ``index`` (a float: 0 to 2 of ``a``, 3 to 5 of ``b``), by selects."""
    in_b = b[0] if index == 3.0 else (b[1] if index == 4.0 else b[2])
    return a[0] if index == 0.0 else (a[1] if index == 1.0 else (a[2] if index == 2.0 else in_b))


@inline
def _finish(r, g, a, b):
    """Undo the scaling ``g``, make the witnesses absolute (vertices exactly)
    and name their features; a zero distance has one point as both witnesses."""
    sqr, base, ax, ay, az, bx, by, bz, fa, fb, a0, a1, a2, b0, b1, b2 = r
    # Selects, not indices: a tuple indexed at run time goes through memory.
    o = _vertex(a, b, base)
    pa = (absolute(o[0], ax, g), absolute(o[1], ay, g), absolute(o[2], az, g))
    pa = _vertex(a, a, fa) if fa <= float(VERTEX2) else pa
    pb = (absolute(o[0], bx, g), absolute(o[1], by, g), absolute(o[2], bz, g))
    pb = _vertex(b, b, fb) if fb <= float(VERTEX2) else pb
    pb = pa if sqr == 0.0 else pb
    dist = math.sqrt(sqr) * g[0] if g[0] != math.inf else math.sqrt(sqr) * g[1] * g[2]
    sqr = sqr * g[0] * g[0] if g[0] != math.inf else sqr * g[1] * g[1] * g[2] * g[2]
    return dist, sqr, pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], int(fa), int(fb), a0, a1, a2, b0, b1, b2


@part
def robust(a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z):
    """Robust triangle-triangle query for any finite input; see the module docstring.

    Returns ``(distance, sqr_distance, pax, pay, paz, pbx, pby, pbz,
    feature_a, feature_b, a0, a1, a2, b0, b1, b2)``: the witness points on
    triangles ``A0 A1 A2`` and ``B0 B1 B2``, their features and their
    barycentric coordinates.
    """
    a = ((a0x, a0y, a0z), (a1x, a1y, a1z), (a2x, a2y, a2z))
    b = ((b0x, b0y, b0z), (b1x, b1y, b1z), (b2x, b2y, b2z))
    w, ga, gb = _differences(1.0, a, b)
    m = _largest(w, ga, gb)
    scale = UNSCALED  # undoes the scaling of the differences
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        w, ga, gb = _differences(0.25, a, b)
        m = _largest(w, ga, gb)
        scale = (4.0, 4.0, 1.0)
    if m == 0.0:
        return 0.0, 0.0, a0x, a0y, a0z, a0x, a0y, a0z, VERTEX0, VERTEX0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        w = (_scale3(w[0], f1, f2), _scale3(w[1], f1, f2), _scale3(w[2], f1, f2))
        ga, gb = _scale3(ga, f1, f2), _scale3(gb, f1, f2)
        scale = (scale[0] / f1 / f2, scale[1] / f1, 1.0 / f2)
    return _finish(_robust_local(w, ga, gb), scale, a, b)


@inline
def robust_unscaled(a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z):
    """:func:`robust` without its scaling, for the SIMD pass of a batch loop:
    ``(in_window, distance, ...)`` as :func:`.segment_segment.robust_unscaled`."""
    a = ((a0x, a0y, a0z), (a1x, a1y, a1z), (a2x, a2y, a2z))
    b = ((b0x, b0y, b0z), (b1x, b1y, b1z), (b2x, b2y, b2z))
    w, ga, gb = _differences(1.0, a, b)
    m = _largest(w, ga, gb)
    r = _finish(_robust_local(w, ga, gb), UNSCALED, a, b)
    return (m >= SAFE_MIN) & (m <= SAFE_MAX), *r


# -- certified -----------------------------------------------------------------


@inline
def _outside(n, abs_n, w, g):
    """Whether a point (``w``: the triangle's vertices relative to it) lies
    certainly outside the closed triangle: strictly off its plane, or
    strictly beyond one of its edges."""
    off = _normal_sign(n, abs_n, w[0]) != 0
    beyond = (
        (_triple_sign(n, abs_n, w[0], g[0]) == -1)
        | (_triple_sign(n, abs_n, w[1], g[1]) == -1)
        | (_triple_sign(n, abs_n, w[2], g[2]) == -1)
    )
    return off | beyond


@inline
def _crosses(e, w0, w1, g):
    """Three-valued: 1 when the segment ``(e, w0, w1)`` certainly crosses the
    triangle's open face at one point, -1 when it certainly misses the
    closed triangle, 0 when undecided."""
    n, abs_n = _cross_of(g[0], _neg(g[2]))
    side0 = _normal_sign(n, abs_n, w0[0])
    side1 = _normal_sign(n, abs_n, w1[0])
    o0 = _cross_sign_triple(e, w0[0], w0[1])
    o1 = _cross_sign_triple(e, w0[1], w0[2])
    o2 = _cross_sign_triple(e, w0[2], w0[0])
    inside = (o0 != 0) & (o0 == o1) & (o1 == o2)
    outside = (o0 * o1 == -1) | (o1 * o2 == -1) | (o2 * o0 == -1)
    apart = (side0 != 0) & (side0 == side1)
    across = side0 * side1 == -1
    # One endpoint in the plane, the other strictly off it: the segment
    # meets the plane at that endpoint only.
    at0 = (side0 == 0) & (side1 != 0) & _outside(n, abs_n, w0, g)
    at1 = (side1 == 0) & (side0 != 0) & _outside(n, abs_n, w1, g)
    return 1 if across & inside else (-1 if apart | (across & outside) | at0 | at1 else 0)


@inline
def _intersection(w, ga, gb):
    """The lowest feature pair where the triangles certainly intersect, as
    ``(side, edge)``: side 0 for an edge of ``A`` crossing ``B``'s face, 1 for an
    edge of ``B`` crossing ``A``'s; ``(-1, -1)`` when undecided or apart."""
    nb, abs_nb = _cross_of(gb[0], _neg(gb[2]))
    off = _outside(nb, abs_nb, w[0], gb) & _outside(nb, abs_nb, w[1], gb) & _outside(nb, abs_nb, w[2], gb)
    if not off:
        return -1, -1
    for k in range(3):
        c = _crosses(*_frame_a(w, ga, gb, k))
        if c == 0:
            return -1, -1
        if c == 1:
            return 0, k
    na, abs_na = _cross_of(ga[0], _neg(ga[2]))
    for j in range(3):
        off &= _outside(na, abs_na, _frame_b(w, ga, gb, j)[1], ga)
    if not off:
        return -1, -1
    for k in range(3):
        c = _crosses(*_frame_b(w, ga, gb, k))
        if c == 0:
            return -1, -1
        if c == 1:
            return 1, k
    return -1, -1


@inline
def _across_sign(fa_edge, fb, w, ga, gb):
    """For edge ``fa_edge`` of ``A`` holding the closest point against vertex
    or edge ``fb`` of ``B``: whether the offset to ``B`` leaves ``A`` strictly
    across that edge (``A``'s own cone, which the segment-triangle
    conditions of the edge do not see)."""
    k = fa_edge
    p, o = k, (k + 2) % 3
    e = ga[k]
    opposite = _neg(ga[o])  # A_o - A_p
    if fb <= VERTEX2:
        # B_j's projection onto the edge's line, offset away from A_o.
        return _cross_sign(w[p][fb], e, opposite, e) == -1
    m = fb - EDGE01
    n, abs_n = _cross_of(e, gb[m])
    # ((A_p - B_r) . n) ((A_o - A_p) . n) > 0, with n the edges' common normal.
    return -_normal_sign(n, abs_n, w[p][m]) * _normal_sign(n, abs_n, opposite) == 1


@inline
def _verify(fa, fb, w, ga, gb):
    """Whether the optimality conditions of ``(fa, fb)`` hold strictly."""
    if fa <= VERTEX2:
        i = fa
        # As the first endpoint of edge i and the second of edge i - 1.
        return _holds(VERTEX0, fb, *_frame_a(w, ga, gb, i), False) & _holds(
            VERTEX1, fb, *_frame_a(w, ga, gb, (i + 2) % 3), False
        )
    if fa != FACE:
        if fb == FACE:
            return False
        k = fa - EDGE01
        return _holds(EDGE01, fb, *_frame_a(w, ga, gb, k), False) & _across_sign(k, fb, w, ga, gb)
    if fb > VERTEX2:
        return False
    j = fb
    return _holds(VERTEX0, FACE, *_frame_b(w, ga, gb, j), False) & _holds(
        VERTEX1, FACE, *_frame_b(w, ga, gb, (j + 2) % 3), False
    )


@inline
def _dd_frame_a(w, ga, gb, k):
    p, q = k, (k + 1) % 3
    return ga[k], w[p], w[q], gb


@inline
def _dd_frame_b(w, ga, gb, k):
    r, u = k, (k + 1) % 3
    w0 = (_dd_neg(w[0][r]), _dd_neg(w[1][r]), _dd_neg(w[2][r]))
    w1 = (_dd_neg(w[0][u]), _dd_neg(w[1][u]), _dd_neg(w[2][u]))
    return gb[k], w0, w1, ga


@inline
def _sqr(fa, fb, w, ga, gb):
    """The verified pair's squared distance in double-double, with its bound."""
    if fa <= VERTEX2:
        return _sqr_distance(VERTEX0, fb, *_dd_frame_a(w, ga, gb, fa))
    if fa != FACE:
        return _sqr_distance(EDGE01, fb, *_dd_frame_a(w, ga, gb, fa - EDGE01))
    return _sqr_distance(VERTEX0, FACE, *_dd_frame_b(w, ga, gb, fb))


_FAIL = (
    cf.EXACT, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
    NONE, NONE, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
)  # fmt: skip


@inline
def _lead3(t):
    return _lead(t[0]), _lead(t[1]), _lead(t[2])


@inline
def _dd_scale3(t, f1, f2):
    x, o1 = cf.scale_vec(t[0], f1, f2)
    y, o2 = cf.scale_vec(t[1], f1, f2)
    z, o3 = cf.scale_vec(t[2], f1, f2)
    return (x, y, z), o1 & o2 & o3


@inline
def _exact_frame(args):
    """``(ok, zero, a, b, w, lw, ga, gb, scale)`` of a certified query: the vertices, the
    exact differences as double-doubles (scaled where their leads would under- or
    overflow), their leads ``lw``, the edges, and the scale undone at the end; ``ok`` False
    where a difference overflowed, ``zero`` where every difference is 0."""
    a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z = args
    a = ((a0x, a0y, a0z), (a1x, a1y, a1z), (a2x, a2y, a2z))
    b = ((b0x, b0y, b0z), (b1x, b1y, b1z), (b2x, b2y, b2z))
    w = (
        (_dd_sub(b[0], a[0]), _dd_sub(b[1], a[0]), _dd_sub(b[2], a[0])),
        (_dd_sub(b[0], a[1]), _dd_sub(b[1], a[1]), _dd_sub(b[2], a[1])),
        (_dd_sub(b[0], a[2]), _dd_sub(b[1], a[2]), _dd_sub(b[2], a[2])),
    )
    ga = (_dd_sub(a[1], a[0]), _dd_sub(a[2], a[1]), _dd_sub(a[0], a[2]))
    gb = (_dd_sub(b[1], b[0]), _dd_sub(b[2], b[1]), _dd_sub(b[0], b[2]))
    lw = (_lead3(w[0]), _lead3(w[1]), _lead3(w[2]))
    m = _largest(lw, _lead3(ga), _lead3(gb))
    ok = m < math.inf  # a difference of two finite coordinates overflowed otherwise
    scale = 1.0
    if ok and m != 0.0 and (m < SAFE_MIN or m > SAFE_MAX):
        f1, f2 = pow2_scale(m)
        w0, o0 = _dd_scale3(w[0], f1, f2)
        w1, o1 = _dd_scale3(w[1], f1, f2)
        w2, o2 = _dd_scale3(w[2], f1, f2)
        ga, o3 = _dd_scale3(ga, f1, f2)
        gb, o4 = _dd_scale3(gb, f1, f2)
        w = (w0, w1, w2)
        scale = (1.0 / f1) * (1.0 / f2)
        ok = o0 & o1 & o2 & o3 & o4 & (scale < math.inf)
        lw = (_lead3(w[0]), _lead3(w[1]), _lead3(w[2]))
    return ok, m == 0.0, a, b, w, lw, ga, gb, scale


@inline
def _crossing_features(fa, fb):
    """Whether the robust features are an edge of one triangle crossing the other's face."""
    return ((fa == FACE) & (fb != FACE) & (fb > VERTEX2)) | ((fb == FACE) & (fa != FACE) & (fa > VERTEX2))


@inline
def _touching(a, b, lw, lga, lgb, scale):
    """Where the triangles certainly intersect (their robust features an edge crossing a
    face), the certified answer: distance 0, the crossing point as both witnesses, the
    lowest crossing pair; a request for the exact fallback otherwise."""
    side, k = _intersection(lw, lga, lgb)
    if side < 0:
        return _FAIL
    # The crossing point, as the robust method computes it, for both witnesses.
    c = _crossing_a(lw, lga, lgb, k) if side == 0 else _crossing_b(lw, lga, lgb, k)
    touching = (0.0, *c[1:])
    q = _finish(touching, (scale, scale, 1.0), a, b)
    fa = EDGE01 + k if side == 0 else FACE
    fb = FACE if side == 0 else EDGE01 + k
    return cf.CERTAIN, 0.0, 0.0, q[2], q[3], q[4], q[2], q[3], q[4], fa, fb, *q[10:]


@part
def certified(a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z):
    """Certified triangle-triangle query for any finite input, or a request
    for the exact fallback; see the module docstring.

    Returns ``(status, distance, ...)``: the fields of :func:`robust` after
    a status, :data:`~proximity.numerics.certified.CERTAIN` (the distance is
    faithfully rounded and the features are exact) or
    :data:`~proximity.numerics.certified.EXACT` (the other values are then
    meaningless).
    """
    args = (a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z)
    r = robust(*args)
    ok, zero, a, b, w, lw, ga, gb, scale = _exact_frame(args)
    if not ok:
        return _FAIL
    if zero:
        return (cf.CERTAIN, *r)
    fa, fb = r[8], r[9]
    lga, lgb = _lead3(ga), _lead3(gb)
    if _crossing_features(fa, fb):
        return _touching(a, b, lw, lga, lgb, scale)
    if not _verify(fa, fb, lw, lga, lgb):
        return _FAIL
    sh, sl, delta = _sqr(fa, fb, w, ga, gb)
    ok, d, sqr = cf.faithful_sqrt(sh, sl, delta)
    d = d * scale
    ok = ok & ((d >= 2.2250738585072014e-308) | (d == 0.0)) & (d < math.inf)
    if not ok:
        return _FAIL
    pb = (r[2], r[3], r[4]) if d == 0.0 else (r[5], r[6], r[7])
    return cf.CERTAIN, d, sqr * scale * scale, r[2], r[3], r[4], pb[0], pb[1], pb[2], fa, fb, *r[10:]


@part
def touching(
    fa, fb, a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z
):
    """:func:`certified` where the robust features ``fa``, ``fb`` are an edge crossing a face
    and the triangles certainly intersect (distance exactly 0, the crossing point on both),
    and a request for the exact fallback everywhere else: what the ``robust`` search of two
    meshes asks of a pair it finds within rounding of 0, so that intersecting meshes give 0
    without compiling the whole certified query into it."""
    args = (a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z, b0x, b0y, b0z, b1x, b1y, b1z, b2x, b2y, b2z)
    ok, zero, a, b, w, lw, ga, gb, scale = _exact_frame(args)
    if not ok or zero or not _crossing_features(fa, fb):
        return _FAIL
    return _touching(a, b, lw, _lead3(ga), _lead3(gb), scale)
