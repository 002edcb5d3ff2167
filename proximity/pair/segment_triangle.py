"""Distance between a segment and a triangle.

Follows D. Eberly, *Distance Between a Line Segment and a Triangle*
(Geometric Tools, 2019), in its formulation: with the segment ``P(s) = P0 +
s (P1 - P0)``, ``s`` in ``[0, 1]`` (shape a) and the triangle ``T = b0 V0 +
b1 V1 + b2 V2`` over barycentrics ``b >= 0`` summing to 1 (shape b), the
squared distance is a convex quadratic over the product of the interval and
the triangle.  Its minimum is either where the segment crosses the
triangle (distance 0) or on the boundary of that domain: an endpoint of the
segment against the triangle (two point-triangle queries) or the segment
against an edge (three segment-segment queries), the document's reduction.

``robust``
    The nearest of nine candidates, each a pair of points on the shapes:
    each endpoint against the triangle (:func:`proximity.point.triangle._robust_local`),
    each vertex against the segment, the interior candidate of the segment
    against each edge (:func:`.segment_segment._interior`), and the point
    where the segment crosses the triangle's plane against the triangle.
    The nine cover the candidates of the document's five sub-queries (an
    endpoint against an edge is never nearer than against the triangle).
    Every candidate is computed and one selected without branches, so that a
    loop of queries compiles to SIMD code.

    * The differences of the inputs (``V_k - P_i``, ``P1 - P0`` and the
      edges) are rounded once each, scaled by a power of two outside ``[2^-64,
      2^64]`` (coordinates from 1e-300 to 1e300), after quartering the inputs
      where a difference overflowed.
    * No candidate is below the exact distance ``d*`` by more than the
      rounding of its points.  If the closest points include an endpoint of
      the segment, a vertex or an edge point of the triangle, the candidate
      of that sub-query is within its own bound (``8 eps S`` for the
      point-triangle queries, the segment-segment argument for the edges).
      Otherwise the segment crosses the face (``d* = 0``): the crossing
      parameter comes from the heights ``h_i = n . (P_i - V0)`` over the
      normal ``n`` (accurate cross product, compensated dot product), each
      within ``eta``, a few ``eps S``, so the crossing candidate's point is
      within ``eta`` of the plane.  Where its projection falls outside the
      face (a segment nearly parallel to the plane), the part of the segment
      between it and the true crossing, all within ``eta`` of the plane,
      passes over an edge, whose candidate is then within ``eta``.

    For every finite input, ``|d - d*| <= 16 eps S + 2^-1075`` with ``S`` the
    largest coordinate difference between the five vertices.  The witness
    points lie within that bound of their shapes and are ``d`` apart within
    it; vertices are reported exactly, and a zero distance has one point as
    both witnesses.  ``tests/test_pair_kernels.py`` checks this against
    exact rational arithmetic.

    * A crossing is exactly 0.  The crossing candidate's point is rounded
      off the plane, so an answer within ``32 eps S`` of 0 (and not 0) is
      decided by the exact orientation predicates of
      :mod:`proximity.numerics.orient` on the inputs (a float filter first):
      where the segment's endpoints lie strictly on either side of the
      plane and its line strictly inside the three edges, the answer is
      the crossing candidate at distance 0, its point on the segment as
      both witnesses, the face as the triangle's feature (inputs whose
      differences exceed :data:`CROSS_MAX` keep the candidates' answer).

``robust_unscaled``
    :func:`robust` without its scaling, bit for bit its answer wherever the
    differences lie in the safe window and the answer is not within rounding
    of a crossing, which it reports: the SIMD pass of a batch loop, the rest
    redone with :func:`robust`.

``certified``
    The robust answer names a feature pair; the optimality conditions of
    that pair (the closest point of each shape to the other's lies strictly
    inside its feature, and the vector between them points strictly into
    the feature's normal cone on both sides) are signs of polynomials of
    degree 2 to 4 in the differences, evaluated in float with rigorous error
    bounds as in :mod:`proximity.numerics.certified`.  When all hold strictly, the
    minimum is unique and lies in that pair, which is therefore the lowest
    that holds one; its squared distance is then computed in double-double
    from the exact differences (``|X|^2``, ``|X x E|^2 / |E|^2`` or ``(n .
    X)^2 / |n|^2``) and rounded faithfully.  A segment crossing the face is
    certain when its endpoints lie strictly on either side of the plane and
    its line strictly inside the three edges: the distance is then exactly
    0, with the crossing point as both witnesses.

    A zero-length segment (its endpoints exactly equal) is its first
    endpoint.  Everything else (pairs within rounding of another region,
    parallel features, touching that is not a proper crossing, zero-area
    triangles) goes to the exact fallback
    :func:`proximity.numerics.exact.segment_triangle`.
    Ties go to the lowest ``(feature_a, feature_b)`` codes: the segment's
    feature first, vertices before the edge, then the triangle's vertices,
    edges and face.
"""

import math

from ..features import EDGE01, EDGE12, EDGE20, FACE, NONE, VERTEX0, VERTEX1, VERTEX2
from ..numerics import certified as cf
from ..numerics.fp import EPS, SAFE_MAX, SAFE_MIN, UNSCALED, cross_accurate, dot3_accurate, pow2_scale
from ..numerics.orient import DOUBT, orient3d
from ..point.segment import project
from ..point.triangle import _robust_local as _point_local
from ..runtime.jit import inline, part
from .segment_segment import (
    _dot_sign,
    _edge_sqr,
    _feature,
    _interior,
    _lines_sqr,
    _max3,
    _scaled,
    _triple_sign,
    absolute,
)

F_VERTEX0, F_VERTEX1, F_VERTEX2 = float(VERTEX0), float(VERTEX1), float(VERTEX2)
F_EDGE01, F_EDGE12, F_EDGE20 = float(EDGE01), float(EDGE12), float(EDGE20)
F_FACE = float(FACE)
#: ``(32 eps)^2``: a squared distance at most this times ``S^2`` may be a crossing (whose
#: robust distance is within ``16 eps S`` of 0), which is then decided exactly.
NEAR = (32.0 * EPS) ** 2
#: The largest coordinate difference at which the orientation predicates are taken on the
#: inputs: their products of three differences stay far from overflow.
CROSS_MAX = 2.0**256


@inline
def _sub(x, y):
    return x[0] - y[0], x[1] - y[1], x[2] - y[2]


@inline
def _neg(v):
    return -v[0], -v[1], -v[2]


@inline
def _differences(q, a0, a1, v0, v1, v2):
    """Differences of the inputs times ``q`` (a power of two), each rounded once:
    ``e = A1 - A0``, ``w0[k] = V_k - A0``, ``w1[k] = V_k - A1`` and the edges
    ``g = (V1 - V0, V2 - V1, V0 - V2)``."""
    a0, a1 = (a0[0] * q, a0[1] * q, a0[2] * q), (a1[0] * q, a1[1] * q, a1[2] * q)
    v0, v1, v2 = (
        (v0[0] * q, v0[1] * q, v0[2] * q),
        (v1[0] * q, v1[1] * q, v1[2] * q),
        (v2[0] * q, v2[1] * q, v2[2] * q),
    )
    e = _sub(a1, a0)
    w0 = (_sub(v0, a0), _sub(v1, a0), _sub(v2, a0))
    w1 = (_sub(v0, a1), _sub(v1, a1), _sub(v2, a1))
    g = (_sub(v1, v0), _sub(v2, v1), _sub(v0, v2))
    return e, w0, w1, g


@inline
def _largest(e, w0, w1, g):
    m = max(_max3(e), max(max(_max3(w0[0]), _max3(w0[1])), _max3(w0[2])))
    m = max(m, max(max(_max3(w1[0]), _max3(w1[1])), _max3(w1[2])))
    return max(m, max(max(_max3(g[0]), _max3(g[1])), _max3(g[2])))


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
    )


@inline
def _point_candidate(r, base, s):
    """An endpoint of the segment against the triangle, as a candidate."""
    _, sqr, x, y, z, feature, b0, b1, b2 = r
    return (sqr, base, 0.0, 0.0, 0.0, x, y, z, s, float(feature), b0, b1, b2)


@inline
def _vertex_candidate(w0, w1, e, k):
    """Vertex ``k`` against the segment, as a candidate."""
    m0, m1 = _neg(w0), _neg(w1)
    sqr, x, y, z, s = project(m0[0], m0[1], m0[2], e[0], e[1], e[2], m1[0], m1[1], m1[2])
    return (
        sqr, 2.0 + k, x, y, z, 0.0, 0.0, 0.0, s,
        float(k), 1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0,
    )  # fmt: skip


@inline
def _edge_candidate(e, w0, w1, g, k):
    """The segment's interior candidate against edge ``k`` (from ``V_k`` to ``V_{k+1}``)."""
    start, end = k, (k + 1) % 3
    sqr, px, py, pz, x, y, z, s, t = _interior(e, g[k], w0[start], w0[end], w1[start])
    code = F_EDGE01 if k == 0 else (F_EDGE12 if k == 1 else F_EDGE20)
    code = float(start) if t == 0.0 else (float(end) if t == 1.0 else code)
    b = (1.0 - t, t, 0.0) if k == 0 else ((0.0, 1.0 - t, t) if k == 1 else (t, 0.0, 1.0 - t))
    return (sqr, 0.0, px, py, pz, px + x, py + y, pz + z, s, code, b[0], b[1], b[2])


@inline
def _crossing_candidate(e, w0, w1, g):
    """Where the segment crosses the triangle's plane, against the triangle."""
    nx, ny, nz = cross_accurate(g[0][0], g[0][1], g[0][2], -g[2][0], -g[2][1], -g[2][2])
    h0 = -dot3_accurate(nx, ny, nz, w0[0][0], w0[0][1], w0[0][2])
    h1 = -dot3_accurate(nx, ny, nz, w1[0][0], w1[0][1], w1[0][2])
    den = h0 - h1
    # A segment parallel to the plane (den = 0): any point of it serves.
    s = min(max(h0 / (den if den != 0.0 else 1.0), 0.0), 1.0)
    s = s if den != 0.0 else 0.0
    p = (s * e[0], s * e[1], s * e[2])
    _, sqr, x, y, z, feature, b0, b1, b2 = _point_local(*_sub(w0[0], p), *_sub(w0[1], p), *_sub(w0[2], p))
    return (sqr, 0.0, p[0], p[1], p[2], p[0] + x, p[1] + y, p[2] + z, s, float(feature), b0, b1, b2)


@inline
def _robust_local(e, w0, w1, g):
    """The nine candidates and the nearest, on differences in the safe window.

    Returns ``(sqr_distance, base, ax, ay, az, bx, by, bz, s, feature_b, b0,
    b1, b2)`` as floats: the witnesses are ``base + (ax, ay, az)`` and ``base
    + (bx, by, bz)`` with ``base`` the index of a vertex (0, 1: ``A0``,
    ``A1``; 2 to 4: ``V0`` to ``V2``).  Ties go to the earlier candidate.
    """
    # Written out rather than looped over k: constant indices into the
    # tuples keep the loop over queries free of stack traffic, so that it
    # compiles to SIMD code.
    best = _point_candidate(_point_local(*w0[0], *w0[1], *w0[2]), 0.0, 0.0)
    c = _point_candidate(_point_local(*w1[0], *w1[1], *w1[2]), 1.0, 1.0)
    best = _pick(c[0] < best[0], c, best)
    c = _vertex_candidate(w0[0], w1[0], e, 0)
    best = _pick(c[0] < best[0], c, best)
    c = _vertex_candidate(w0[1], w1[1], e, 1)
    best = _pick(c[0] < best[0], c, best)
    c = _vertex_candidate(w0[2], w1[2], e, 2)
    best = _pick(c[0] < best[0], c, best)
    c = _edge_candidate(e, w0, w1, g, 0)
    best = _pick(c[0] < best[0], c, best)
    c = _edge_candidate(e, w0, w1, g, 1)
    best = _pick(c[0] < best[0], c, best)
    c = _edge_candidate(e, w0, w1, g, 2)
    best = _pick(c[0] < best[0], c, best)
    c = _crossing_candidate(e, w0, w1, g)
    return _pick(c[0] < best[0], c, best)


@part
def _crosses(a0, a1, v0, v1, v2):
    """Whether the segment ``A0 A1`` certainly crosses the open triangle ``V0 V1 V2``, by
    exact orientation predicates on the inputs (a float filter first): its endpoints strictly
    on either side of the plane, its line strictly inside the three edges.  False where a
    predicate is 0 (touching, coplanar) or doubtful (see :data:`~proximity.numerics.orient.DOUBT`)."""
    below0 = orient3d(*v0, *v1, *v2, *a0)
    below1 = orient3d(*v0, *v1, *v2, *a1)
    if below0 == DOUBT or below1 == DOUBT or below0 * below1 != -1:
        return False
    o0 = orient3d(*a0, *a1, *v0, *v1)
    if o0 == 0 or o0 == DOUBT:
        return False
    return orient3d(*a0, *a1, *v1, *v2) == o0 and orient3d(*a0, *a1, *v2, *v0) == o0


@inline
def _clear(sqr, m):
    """Whether a squared distance ``sqr`` is 0 or beyond the rounding of a crossing, ``m``
    the largest difference (the same units)."""
    return (sqr == 0.0) | (sqr > NEAR * m * m)


@inline
def _crossing_zero(r, e, w0, w1, g, a0, a1, v0, v1, v2):
    """The answer ``r`` of :func:`_robust_local`, or where it is within rounding of 0 and the
    segment certainly crosses the face, the crossing candidate at distance exactly 0: the
    segment's point where it meets the plane as both witnesses."""
    if not _clear(r[0], _largest(e, w0, w1, g)) and _crosses(a0, a1, v0, v1, v2):
        c = _crossing_candidate(e, w0, w1, g)
        return (0.0, 0.0, c[2], c[3], c[4], c[2], c[3], c[4], c[8], F_FACE, c[10], c[11], c[12])
    return r


@inline
def _finish(r, g, a0, a1, v0, v1, v2):
    """Undo the scaling ``g``, make the witnesses absolute (vertices exactly)
    and name their features; a zero distance has one point as both witnesses."""
    sqr, base, ax, ay, az, bx, by, bz, s, fb, b0, b1, b2 = r
    o = a0 if base == 0.0 else (a1 if base == 1.0 else (v0 if base == 2.0 else (v1 if base == 3.0 else v2)))
    fa = _feature(s)
    vb = v0 if fb == F_VERTEX0 else (v1 if fb == F_VERTEX1 else v2)
    pa = a0 if fa == VERTEX0 else a1
    if fa == EDGE01:
        pa = (absolute(o[0], ax, g), absolute(o[1], ay, g), absolute(o[2], az, g))
    pb = vb
    if fb > F_VERTEX2:
        pb = (absolute(o[0], bx, g), absolute(o[1], by, g), absolute(o[2], bz, g))
    pb = pa if sqr == 0.0 else pb
    dist = math.sqrt(sqr) * g[0] if g[0] != math.inf else math.sqrt(sqr) * g[1] * g[2]
    sqr = sqr * g[0] * g[0] if g[0] != math.inf else sqr * g[1] * g[1] * g[2] * g[2]
    return dist, sqr, pa[0], pa[1], pa[2], pb[0], pb[1], pb[2], fa, int(fb), s, b0, b1, b2


@part
def robust(a0x, a0y, a0z, a1x, a1y, a1z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z):
    """Robust segment-triangle query for any finite input; see the module docstring.

    Returns ``(distance, sqr_distance, pax, pay, paz, pbx, pby, pbz,
    feature_a, feature_b, s, b0, b1, b2)``: the witness points on the
    segment ``A0 A1`` and on the triangle ``V0 V1 V2``, their features, the
    segment's parameter and the triangle witness's barycentric coordinates.
    """
    a0, a1 = (a0x, a0y, a0z), (a1x, a1y, a1z)
    v0, v1, v2 = (v0x, v0y, v0z), (v1x, v1y, v1z), (v2x, v2y, v2z)
    e, w0, w1, g = _differences(1.0, a0, a1, v0, v1, v2)
    m = _largest(e, w0, w1, g)
    decide = m <= CROSS_MAX  # whether a crossing is decided exactly
    scale = UNSCALED  # undoes the scaling of the differences
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        e, w0, w1, g = _differences(0.25, a0, a1, v0, v1, v2)
        m = _largest(e, w0, w1, g)
        scale = (4.0, 4.0, 1.0)
    if m == 0.0:
        return 0.0, 0.0, a0x, a0y, a0z, a0x, a0y, a0z, VERTEX0, VERTEX0, 0.0, 1.0, 0.0, 0.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        e = _scaled(e, f1, f2)
        w0 = (_scaled(w0[0], f1, f2), _scaled(w0[1], f1, f2), _scaled(w0[2], f1, f2))
        w1 = (_scaled(w1[0], f1, f2), _scaled(w1[1], f1, f2), _scaled(w1[2], f1, f2))
        g = (_scaled(g[0], f1, f2), _scaled(g[1], f1, f2), _scaled(g[2], f1, f2))
        scale = (scale[0] / f1 / f2, scale[1] / f1, 1.0 / f2)
    r = _robust_local(e, w0, w1, g)
    if decide:
        r = _crossing_zero(r, e, w0, w1, g, a0, a1, v0, v1, v2)
    return _finish(r, scale, a0, a1, v0, v1, v2)


@inline
def robust_unscaled(a0x, a0y, a0z, a1x, a1y, a1z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z):
    """:func:`robust` without its scaling, for the SIMD pass of a batch loop:
    ``(in_window, distance, ...)`` as :func:`.segment_segment.robust_unscaled`; an answer
    within rounding of a crossing is reported outside the window too, for :func:`robust`
    to decide the crossing exactly."""
    a0, a1 = (a0x, a0y, a0z), (a1x, a1y, a1z)
    v0, v1, v2 = (v0x, v0y, v0z), (v1x, v1y, v1z), (v2x, v2y, v2z)
    e, w0, w1, g = _differences(1.0, a0, a1, v0, v1, v2)
    m = _largest(e, w0, w1, g)
    r = _robust_local(e, w0, w1, g)
    clear = _clear(r[0], m)
    r = _finish(r, UNSCALED, a0, a1, v0, v1, v2)
    return (m >= SAFE_MIN) & (m <= SAFE_MAX) & clear, *r


# -- certified -----------------------------------------------------------------


@inline
def _cross_sign(a, b, c, d):
    """Sign of ``(a x b) . (c x d)`` (rounded exact differences), 0 if undecided."""
    n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    abs_n = cf._cross_abs(abs(a[0]), abs(a[1]), abs(a[2]), abs(b[0]), abs(b[1]), abs(b[2]))
    return _triple_sign(n, abs_n, c, d)


@inline
def _normal_sign(n, abs_n, v):
    """Sign of ``n . v`` with ``n`` a cross product of differences (degree 3), 0 if undecided."""
    value = n[0] * v[0] + n[1] * v[1] + n[2] * v[2]
    bound = abs_n[0] * abs(v[0]) + abs_n[1] * abs(v[1]) + abs_n[2] * abs(v[2])
    return cf._sign(value, cf.PRED4 * bound)


@inline
def _cross_of(a, b):
    """``a x b`` and the same product of absolute values, for the bounds."""
    n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    return n, cf._cross_abs(abs(a[0]), abs(a[1]), abs(a[2]), abs(b[0]), abs(b[1]), abs(b[2]))


@inline
def _edges_of(k):
    """Edge ``k``'s start, end and opposite vertex."""
    return k, (k + 1) % 3, (k + 2) % 3


@inline
def _holds(fa, fb, e, w0, w1, g, point_a):
    """Whether the optimality conditions of the feature pair ``(fa, fb)``
    hold strictly, beyond the error bounds of their float evaluation.

    ``e``, ``w0``, ``w1``, ``g`` are the leading parts of the exact
    differences (see :func:`_differences`).  A vertex ``A_i`` of the segment
    has its other endpoint along ``d_i`` (``e`` or ``-e``); edge ``k`` of the
    triangle runs from ``V_k`` along ``g[k]``, with ``V_m`` opposite.  A
    segment whose endpoints are exactly equal (``point_a``) is its first
    endpoint, whatever the direction.
    """
    if point_a:
        fa = VERTEX0 if fa == VERTEX0 else NONE
    if fa == NONE:
        return False
    if fa != EDGE01:
        i = 0 if fa == VERTEX0 else 1
        w = w0 if i == 0 else w1
        d = e if i == 0 else _neg(e)
        if fb <= VERTEX2:
            j = fb
            # A_i's cone: (V_j - A_i) . d_i < 0; V_j's: (A_i - V_j) . edge < 0 on both edges.
            return (
                (point_a | (_dot_sign(w[j], d) == -1))
                & (_dot_sign(w[j], g[j]) == 1)
                & (_dot_sign(w[j], g[(j + 2) % 3]) == -1)
            )
        if fb != FACE:
            j, end, m = _edges_of(fb - EDGE01)
            gk = g[fb - EDGE01]
            # A_i projects strictly inside the edge and strictly outside the
            # triangle across it; the edge point's offset leaves the segment.
            return (
                (_dot_sign(w[j], gk) == -1)
                & (_dot_sign(w[end], gk) == 1)
                & (_cross_sign(w[j], gk, g[m], gk) == -1)
                & (point_a | (_cross_sign(d, gk, w[j], gk) == -1))
            )
        n, abs_n = _cross_of(g[0], _neg(g[2]))
        # A_i projects strictly inside the face, and the segment leaves the plane on A_i's side.
        inside = (
            (_triple_sign(n, abs_n, w[0], g[0]) == 1)
            & (_triple_sign(n, abs_n, w[1], g[1]) == 1)
            & (_triple_sign(n, abs_n, w[2], g[2]) == 1)
        )
        return inside & (point_a | (-_normal_sign(n, abs_n, w[0]) * _normal_sign(n, abs_n, d) == 1))
    if fb <= VERTEX2:
        j = fb
        # V_j projects strictly inside the segment; the offset leaves the triangle at V_j.
        return (
            (_dot_sign(w0[j], e) == 1)
            & (_dot_sign(w1[j], e) == -1)
            & (_cross_sign(g[j], e, w0[j], e) == 1)
            & (_cross_sign(g[(j + 2) % 3], e, w0[j], e) == -1)
        )
    if fb != FACE:
        j, end, m = _edges_of(fb - EDGE01)
        gk = g[fb - EDGE01]
        n, abs_n = _cross_of(e, gk)
        # The lines' closest points strictly inside both (as in
        # segment_segment._classify), and the offset leaves the triangle
        # across the edge.
        h0 = -_triple_sign(n, abs_n, w0[j], gk)
        h1 = -_triple_sign(n, abs_n, w1[j], gk)
        k0 = _triple_sign(n, abs_n, w0[j], e)
        k1 = _triple_sign(n, abs_n, w0[end], e)
        across = _normal_sign(n, abs_n, w0[j]) * _normal_sign(n, abs_n, g[m]) == -1
        return (h0 == -1) & (h1 == 1) & (k0 == 1) & (k1 == -1) & across
    # The segment crosses the open face: its endpoints strictly on either side
    # of the plane, its line strictly inside the three edges.
    n, abs_n = _cross_of(g[0], _neg(g[2]))
    sides = _normal_sign(n, abs_n, w0[0]) * _normal_sign(n, abs_n, w1[0]) == -1
    o0 = _cross_sign_triple(e, w0[0], w0[1])
    o1 = _cross_sign_triple(e, w0[1], w0[2])
    o2 = _cross_sign_triple(e, w0[2], w0[0])
    return sides & (o0 != 0) & (o0 == o1) & (o1 == o2)


@inline
def _cross_sign_triple(a, b, c):
    """Sign of ``a . (b x c)`` (degree 3), 0 if undecided."""
    n, abs_n = _cross_of(b, c)
    return _normal_sign(n, abs_n, a)


@inline
def _dd_sub(p, q):
    """``p - q`` of two float points, exactly, as a double-double vector."""
    return cf.dd_vec(q[0], q[1], q[2], p[0], p[1], p[2])


@inline
def _dd_neg(v):
    return -v[0], -v[1], -v[2], -v[3], -v[4], -v[5]


@inline
def _lead(v):
    return v[0], v[2], v[4]


@inline
def _sqr_distance(fa, fb, e, w0, w1, g):
    """The squared distance of the feature pair in double-double, with its bound."""
    if fa != EDGE01:
        w = w0 if fa == VERTEX0 else w1
        if fb <= VERTEX2:
            return cf.sum_sq(*w[fb])
        if fb != FACE:
            return _edge_sqr(w[fb - EDGE01], g[fb - EDGE01])
        return _lines_sqr(g[0], _dd_neg(g[2]), w[0])
    if fb <= VERTEX2:
        return _edge_sqr(w0[fb], e)
    if fb != FACE:
        return _lines_sqr(e, g[fb - EDGE01], w0[fb - EDGE01])
    return 0.0, 0.0, 0.0


_FAIL = (
    cf.EXACT, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
    NONE, NONE, math.nan, math.nan, math.nan, math.nan,
)  # fmt: skip


@inline
def _scale_all(e, w0, w1, g, f1, f2):
    e, o1 = cf.scale_vec(e, f1, f2)
    a, o2 = cf.scale_vec(w0[0], f1, f2)
    b, o3 = cf.scale_vec(w0[1], f1, f2)
    c, o4 = cf.scale_vec(w0[2], f1, f2)
    w0 = (a, b, c)
    a, o5 = cf.scale_vec(w1[0], f1, f2)
    b, o6 = cf.scale_vec(w1[1], f1, f2)
    c, o7 = cf.scale_vec(w1[2], f1, f2)
    w1 = (a, b, c)
    a, o8 = cf.scale_vec(g[0], f1, f2)
    b, o9 = cf.scale_vec(g[1], f1, f2)
    c, o10 = cf.scale_vec(g[2], f1, f2)
    ok = o1 & o2 & o3 & o4 & o5 & o6 & o7 & o8 & o9 & o10
    return e, w0, w1, (a, b, c), ok


@part
def certified(a0x, a0y, a0z, a1x, a1y, a1z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z):
    """Certified segment-triangle query for any finite input, or a request for
    the exact fallback; see the module docstring.

    Returns ``(status, distance, ...)``: the fields of :func:`robust` after
    a status, :data:`~proximity.numerics.certified.CERTAIN` (the distance is
    faithfully rounded and the features are exact) or
    :data:`~proximity.numerics.certified.EXACT` (the other values are then
    meaningless).
    """
    r = robust(a0x, a0y, a0z, a1x, a1y, a1z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z)
    fa, fb = r[8], r[9]
    a0, a1 = (a0x, a0y, a0z), (a1x, a1y, a1z)
    v0, v1, v2 = (v0x, v0y, v0z), (v1x, v1y, v1z), (v2x, v2y, v2z)
    e = _dd_sub(a1, a0)
    w0 = (_dd_sub(v0, a0), _dd_sub(v1, a0), _dd_sub(v2, a0))
    w1 = (_dd_sub(v0, a1), _dd_sub(v1, a1), _dd_sub(v2, a1))
    g = (_dd_sub(v1, v0), _dd_sub(v2, v1), _dd_sub(v0, v2))
    lw0 = (_lead(w0[0]), _lead(w0[1]), _lead(w0[2]))
    lw1 = (_lead(w1[0]), _lead(w1[1]), _lead(w1[2]))
    m = _largest(_lead(e), lw0, lw1, (_lead(g[0]), _lead(g[1]), _lead(g[2])))
    if not m < math.inf:
        return _FAIL  # a difference of two finite coordinates overflowed
    if m == 0.0:
        return (cf.CERTAIN, *r)
    scale = 1.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        e, w0, w1, g, ok = _scale_all(e, w0, w1, g, f1, f2)
        scale = (1.0 / f1) * (1.0 / f2)
        if not (ok and scale < math.inf):
            return _FAIL
    le = _lead(e)
    lw0 = (_lead(w0[0]), _lead(w0[1]), _lead(w0[2]))
    lw1 = (_lead(w1[0]), _lead(w1[1]), _lead(w1[2]))
    lg = (_lead(g[0]), _lead(g[1]), _lead(g[2]))
    point_a = (e[0] == 0.0) & (e[2] == 0.0) & (e[4] == 0.0)
    if not _holds(fa, fb, le, lw0, lw1, lg, point_a):
        return _FAIL
    sh, sl, delta = _sqr_distance(fa, fb, e, w0, w1, g)
    ok, d, sqr = cf.faithful_sqrt(sh, sl, delta)
    d = d * scale
    ok = ok & ((d >= 2.2250738585072014e-308) | (d == 0.0)) & (d < math.inf)
    if not ok:
        return _FAIL
    # The robust witnesses; a certain crossing has the segment's point as both.
    pb = (r[2], r[3], r[4]) if d == 0.0 else (r[5], r[6], r[7])
    return cf.CERTAIN, d, sqr * scale * scale, r[2], r[3], r[4], pb[0], pb[1], pb[2], fa, fb, *r[10:]
