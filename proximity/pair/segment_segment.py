"""Distance between two segments.

Follows D. Eberly, *Robust Computation of Distance Between Line Segments*
(Geometric Tools, 2015), in its notation: the segments are ``P(s) = P0 + s
(P1 - P0)`` and ``Q(t) = Q0 + t (Q1 - Q0)`` over ``s, t`` in ``[0, 1]`` (here
``P`` is shape a and ``Q`` shape b), and the squared distance ``R(s, t) = |P(s)
- Q(t)|^2`` is a convex quadratic over the unit square.  Its minimum lies
either inside the square, where the gradient vanishes, or on one of the
square's four edges ``s = 0``, ``s = 1``, ``t = 0``, ``t = 1``, each of which is
the distance from an endpoint of one segment to the other segment (the
document's Section 2).  The document's robust algorithm finds the minimum by
a constrained conjugate-gradient search (Section 5); the two methods here
keep its formulation but decide the interior case differently.

``robust``
    Every candidate is a pair of points, one on each segment, and the
    answer is the nearest of five: each of the four endpoints against the
    other segment (a clamped projection that never divides by zero), and
    one interior candidate, a point of ``P`` chosen where the lines cross
    when seen along their common normal ``n = (P1 - P0) x (Q1 - Q0)``,
    against ``Q``.  There is no parallel or degenerate case: a
    zero-length segment is its point, and for parallel segments the
    interior candidate is merely one more pair of points.

    * All six differences of the four endpoints (``Q0 - P0``, ``Q1 - P0``,
      ``Q0 - P1``, ``Q1 - P1``, ``P1 - P0``, ``Q1 - Q0``) are taken from the
      inputs, each rounded once, so the distance never comes from
      subtracting two large absolute points.  Outside ``[2^-64, 2^64]``
      they are scaled by a power of two (coordinates from 1e-300 to 1e300),
      after quartering the inputs where a difference overflowed.
    * Each candidate is the distance between two points on the segments,
      up to the rounding of the points: no candidate is below the exact
      distance ``d*`` by more than that rounding.
    * If the closest points include an endpoint, its candidate is within
      the error of a point-segment query of ``d*``.  Otherwise the closest
      points are interior: ``d*^2 = D^2 + g^2`` with ``D`` the distance
      between the lines (along ``n``) and ``g`` the distance between the two
      segments projected along ``n``, which cross.  The interior candidate
      takes ``s = h0 / (h0 - h1)``, where ``h_i = (P_i - Q0) . (f x n)``
      (``f = Q1 - Q0``) are the signed distances of the endpoints from the
      plane through ``Q`` spanned by ``f`` and ``n``, scaled by ``|f| |n|``;
      both are computed with accurate cross products and a compensated dot
      product, so each errs by at most ``eta``, a few ``eps |P_i - Q0|`` in
      distance units, however nearly parallel the segments are.  The point
      ``P(s)`` (or, where ``s`` was clamped, an endpoint of ``P``) is then
      within ``eta`` of the line of ``Q`` in the projection, and a point of
      ``P`` that close to that line is within ``eta`` of the segment ``Q``,
      or else an endpoint of ``Q`` is within ``eta`` of the segment ``P``
      (the crossing point lies inside both).  One candidate is therefore
      within ``sqrt(D^2 + eta^2) <= d* + eta``.  Nearly parallel segments
      thus need no special case: where ``s`` is ill-conditioned the error
      moves ``P(s)`` along a direction in which the distance hardly changes.

    Summing these terms (the rounding of the differences, ``eta``, the
    point-segment query and the square root) gives, for every finite input,
    ``|d - d*| <= 16 eps S + 2^-1075``, with ``S`` the largest coordinate
    difference between the four endpoints (the absolute term is the
    rounding of a subnormal distance).  The witness points lie within that
    bound of their segments and ``|pa - pb|`` equals ``d`` within it (plus
    the rounding of their coordinates); an endpoint is reported exactly.
    ``tests/test_pair_kernels.py`` checks all of it against exact rational
    arithmetic, near-parallel and far-from-the-origin pairs included.

``robust_unscaled``
    :func:`robust` without its scaling, bit for bit its answer wherever the
    differences lie in the safe window, which it reports: the SIMD pass of
    a batch loop, the rest redone with :func:`robust`.

``certified``
    The closest features and a faithfully rounded distance, or a request
    for the exact fallback (:func:`proximity.numerics.exact.segment_segment`), by
    the filter of :mod:`proximity.numerics.certified`.  The pair of features that
    holds the minimum is decided by the optimality conditions of ``R`` on
    the square (gradient zero along a free parameter, pointing outward at
    a clamped one), which are signs of polynomials in the differences:
    ``(P_i - Q_j) . f`` and ``(Q_j - P_i) . e`` (``e = P1 - P0``) of degree
    2 for the clamps, and ``n . ((P_i - Q0) x f)`` and ``n . ((Q_j - P0) x
    e)`` of degree 4 for the free parameters (``h_i`` above, which equal
    ``-s |n|^2`` and ``(1 - s) |n|^2`` at the lines' closest points).  Each
    is evaluated in float with a rigorous bound on its rounding, and a
    feature pair is taken only when every one of its conditions holds
    strictly beyond its bound: the minimum is then unique and lies in that
    pair.  The squared distance is then ``|P_i - Q_j|^2`` for two
    vertices, ``|(P_i - Q0) x f|^2 / |f|^2`` for a vertex and an edge, and
    ``(n . (P0 - Q0))^2 / |n|^2`` for two edges, in double-double from
    the exact differences.

    A zero-length segment (its endpoints exactly equal) is its first
    endpoint.  Where a condition is undecided (pairs within rounding of two
    regions, parallel segments, where several feature pairs hold closest
    points, and crossing segments, whose zero distance only exact
    arithmetic can confirm), the exact fallback decides.  Ties go to the
    lowest ``(feature_a, feature_b)`` codes (vertices before the edge, then
    shape a's feature first): for parallel segments, the first endpoint
    whose projection falls on the other segment.
"""

import math

from numba import literal_unroll

from ..features import EDGE01, NONE, VERTEX0, VERTEX1
from ..numerics import certified as cf
from ..numerics.dd import sqr as dd_sqr
from ..numerics.fp import SAFE_MAX, SAFE_MIN, UNSCALED, cross_accurate, dot3_accurate, pow2_scale, unscale
from ..point.segment import project
from ..runtime.jit import inline, part


@inline
def _differences(q, a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z):
    """The six differences of the inputs times ``q`` (a power of two), each rounded once:
    ``e = A1 - A0``, ``f = B1 - B0``, ``w_ij = B_j - A_i``."""
    e = (a1x * q - a0x * q, a1y * q - a0y * q, a1z * q - a0z * q)
    f = (b1x * q - b0x * q, b1y * q - b0y * q, b1z * q - b0z * q)
    w00 = (b0x * q - a0x * q, b0y * q - a0y * q, b0z * q - a0z * q)
    w01 = (b1x * q - a0x * q, b1y * q - a0y * q, b1z * q - a0z * q)
    w10 = (b0x * q - a1x * q, b0y * q - a1y * q, b0z * q - a1z * q)
    w11 = (b1x * q - a1x * q, b1y * q - a1y * q, b1z * q - a1z * q)
    return e, f, w00, w01, w10, w11


@inline
def _max3(v):
    return max(max(abs(v[0]), abs(v[1])), abs(v[2]))


@inline
def _largest(e, f, w00, w01, w10, w11):
    """The largest of the differences' coordinates, in absolute value."""
    return max(max(max(_max3(e), _max3(f)), max(_max3(w00), _max3(w01))), max(_max3(w10), _max3(w11)))


@inline
def _scaled(v, f1, f2):
    """``v * f1 * f2``, the factors of :func:`~._fp.pow2_scale` applied in turn."""
    return v[0] * f1 * f2, v[1] * f1 * f2, v[2] * f1 * f2


@inline
def _neg(v):
    return -v[0], -v[1], -v[2]


@inline
def absolute(o, r, g):
    """The coordinate ``o + r`` of a witness, ``r`` computed in a frame scaled by ``g``.

    Where the sum overflows although the witness (a point of a shape with
    finite coordinates) does not, it is formed at a quarter of the scale.
    """
    x = o + unscale(r, g)
    quarter = (o * 0.25 + unscale(r, (g[0] * 0.25, g[1] * 0.25, g[2]))) * 4.0
    return x if abs(x) <= 1.7976931348623157e308 else quarter


@inline
def _feature(s):
    """The feature of a segment at parameter ``s``: an endpoint where the clamp put it."""
    return VERTEX0 if s == 0.0 else (VERTEX1 if s == 1.0 else EDGE01)


@inline
def _interior(e, f, w00, w01, w10):
    """The interior candidate: where segment a crosses the plane through b
    spanned by ``f`` and the common normal ``n``, and b's closest point to it.

    Returns ``(sqr_distance, px, py, pz, x, y, z, s, t)`` with ``p`` the point
    of a relative to ``A0`` and ``(x, y, z)`` the point of b relative to ``p``.
    """
    nx, ny, nz = cross_accurate(e[0], e[1], e[2], f[0], f[1], f[2])
    qx, qy, qz = cross_accurate(f[0], f[1], f[2], nx, ny, nz)
    h0 = -dot3_accurate(qx, qy, qz, w00[0], w00[1], w00[2])
    h1 = -dot3_accurate(qx, qy, qz, w10[0], w10[1], w10[2])
    den = h0 - h1
    # Parallel lines (den = 0) leave s free: any point of a serves.
    s = min(max(h0 / (den if den != 0.0 else 1.0), 0.0), 1.0)
    s = s if den != 0.0 else 0.0
    px, py, pz = s * e[0], s * e[1], s * e[2]
    d, x, y, z, t = project(
        w00[0] - px, w00[1] - py, w00[2] - pz, f[0], f[1], f[2], w01[0] - px, w01[1] - py, w01[2] - pz
    )
    return d, px, py, pz, x, y, z, s, t


@inline
def _robust_local(e, f, w00, w01, w10, w11):
    """The five candidates and the nearest, on differences in the safe window.

    Returns ``(sqr_distance, base, rel_a, rel_b, s, t)``: the witness points
    are ``base + rel_a`` and ``base + rel_b``, with ``base`` the index of an
    endpoint (0, 1: ``A0``, ``A1``; 2, 3: ``B0``, ``B1``).  Every candidate is
    computed and one selected without branches, so that a loop of queries
    compiles to SIMD code; ties go to the earlier candidate.
    """
    # Each endpoint against the other segment (the edges of the square).
    d1, x1, y1, z1, t1 = project(w00[0], w00[1], w00[2], f[0], f[1], f[2], w01[0], w01[1], w01[2])
    d2, x2, y2, z2, t2 = project(w10[0], w10[1], w10[2], f[0], f[1], f[2], w11[0], w11[1], w11[2])
    m00, m10, m01, m11 = _neg(w00), _neg(w10), _neg(w01), _neg(w11)
    d3, x3, y3, z3, s3 = project(m00[0], m00[1], m00[2], e[0], e[1], e[2], m10[0], m10[1], m10[2])
    d4, x4, y4, z4, s4 = project(m01[0], m01[1], m01[2], e[0], e[1], e[2], m11[0], m11[1], m11[2])

    d5, px, py, pz, x5, y5, z5, s5, t5 = _interior(e, f, w00, w01, w10)

    c = 1
    best = d1
    c = 2 if d2 < best else c
    best = d2 if d2 < best else best
    c = 3 if d3 < best else c
    best = d3 if d3 < best else best
    c = 4 if d4 < best else c
    best = d4 if d4 < best else best
    c = 5 if d5 < best else c
    best = d5 if d5 < best else best

    base = 0 if c == 1 else (1 if c == 2 else (2 if c == 3 else (3 if c == 4 else 0)))
    ax = 0.0 if c <= 2 else (x3 if c == 3 else (x4 if c == 4 else px))
    ay = 0.0 if c <= 2 else (y3 if c == 3 else (y4 if c == 4 else py))
    az = 0.0 if c <= 2 else (z3 if c == 3 else (z4 if c == 4 else pz))
    bx = x1 if c == 1 else (x2 if c == 2 else (0.0 if c <= 4 else px + x5))
    by = y1 if c == 1 else (y2 if c == 2 else (0.0 if c <= 4 else py + y5))
    bz = z1 if c == 1 else (z2 if c == 2 else (0.0 if c <= 4 else pz + z5))
    s = 0.0 if c == 1 else (1.0 if c == 2 else (s3 if c == 3 else (s4 if c == 4 else s5)))
    t = t1 if c == 1 else (t2 if c == 2 else (0.0 if c == 3 else (1.0 if c == 4 else t5)))
    return best, base, ax, ay, az, bx, by, bz, s, t


@inline
def _finish(r, g, a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z):
    """Undo the scaling ``g``, make the witnesses absolute and name their features.

    An endpoint is reported exactly, and a zero distance has one point as
    both witnesses.
    """
    sqr, base, ax, ay, az, bx, by, bz, s, t = r
    ox = a0x if base == 0 else (a1x if base == 1 else (b0x if base == 2 else b1x))
    oy = a0y if base == 0 else (a1y if base == 1 else (b0y if base == 2 else b1y))
    oz = a0z if base == 0 else (a1z if base == 1 else (b0z if base == 2 else b1z))
    fa = _feature(s)
    fb = _feature(t)
    pax = a0x if fa == VERTEX0 else (a1x if fa == VERTEX1 else absolute(ox, ax, g))
    pay = a0y if fa == VERTEX0 else (a1y if fa == VERTEX1 else absolute(oy, ay, g))
    paz = a0z if fa == VERTEX0 else (a1z if fa == VERTEX1 else absolute(oz, az, g))
    pbx = b0x if fb == VERTEX0 else (b1x if fb == VERTEX1 else absolute(ox, bx, g))
    pby = b0y if fb == VERTEX0 else (b1y if fb == VERTEX1 else absolute(oy, by, g))
    pbz = b0z if fb == VERTEX0 else (b1z if fb == VERTEX1 else absolute(oz, bz, g))
    zero = sqr == 0.0
    pbx = pax if zero else pbx
    pby = pay if zero else pby
    pbz = paz if zero else pbz
    dist = unscale(math.sqrt(sqr), g)
    return dist, unscale(unscale(sqr, g), g), pax, pay, paz, pbx, pby, pbz, fa, fb, s, t


@part
def robust(a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z):
    """Robust segment-segment query for any finite input; see the module docstring.

    Returns ``(distance, sqr_distance, pax, pay, paz, pbx, pby, pbz,
    feature_a, feature_b, s, t)``: the witness points on segment a
    (``A0 A1``) and segment b (``B0 B1``), their features (``VERTEX0``,
    ``VERTEX1`` or ``EDGE01``) and their parameters along each segment.
    """
    args = (a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z)
    e, f, w00, w01, w10, w11 = _differences(1.0, *args)
    m = _largest(e, f, w00, w01, w10, w11)
    g = UNSCALED  # undoes the scaling of the differences
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        e, f, w00, w01, w10, w11 = _differences(0.25, *args)
        m = _largest(e, f, w00, w01, w10, w11)
        g = (4.0, 4.0, 1.0)
    if m == 0.0:
        return 0.0, 0.0, a0x, a0y, a0z, a0x, a0y, a0z, VERTEX0, VERTEX0, 0.0, 0.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        e, f, w00, w01 = _scaled(e, f1, f2), _scaled(f, f1, f2), _scaled(w00, f1, f2), _scaled(w01, f1, f2)
        w10, w11 = _scaled(w10, f1, f2), _scaled(w11, f1, f2)
        g = (g[0] / f1 / f2, g[1] / f1, 1.0 / f2)
    return _finish(_robust_local(e, f, w00, w01, w10, w11), g, *args)


@inline
def robust_unscaled(a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z):
    """:func:`robust` without its scaling, for the SIMD pass of a batch loop.

    Returns ``(in_window, distance, ...)``: the fields of :func:`robust`,
    bit for bit its answer where ``in_window`` (the largest difference is
    within ``[2^-64, 2^64]``); elsewhere they are to be recomputed with
    :func:`robust`.  Branch-free: a loop of these compiles to SIMD code.
    """
    args = (a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z)
    e, f, w00, w01, w10, w11 = _differences(1.0, *args)
    m = _largest(e, f, w00, w01, w10, w11)
    r = _finish(_robust_local(e, f, w00, w01, w10, w11), UNSCALED, *args)
    return (m >= SAFE_MIN) & (m <= SAFE_MAX), *r


# -- certified -----------------------------------------------------------------

# The feature pairs in code order, as (feature_a, feature_b).
_PAIRS = (
    (VERTEX0, VERTEX0),
    (VERTEX0, VERTEX1),
    (VERTEX0, EDGE01),
    (VERTEX1, VERTEX0),
    (VERTEX1, VERTEX1),
    (VERTEX1, EDGE01),
    (EDGE01, VERTEX0),
    (EDGE01, VERTEX1),
    (EDGE01, EDGE01),
)


@inline
def _dot_sign(u, v):
    """Sign of ``u . v`` (vectors of rounded exact differences), or 0 if undecided."""
    value = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    bound = abs(u[0]) * abs(v[0]) + abs(u[1]) * abs(v[1]) + abs(u[2]) * abs(v[2])
    return cf._sign(value, cf.PRED2 * bound)


@inline
def _triple_sign(n, abs_n, w, d):
    """Sign of ``n . (w x d)``, with ``n`` a cross product of differences and
    ``abs_n`` the same cross product of their absolute values; 0 if undecided."""
    kx, ky, kz = w[1] * d[2] - w[2] * d[1], w[2] * d[0] - w[0] * d[2], w[0] * d[1] - w[1] * d[0]
    Kx, Ky, Kz = cf._cross_abs(abs(w[0]), abs(w[1]), abs(w[2]), abs(d[0]), abs(d[1]), abs(d[2]))
    value = n[0] * kx + n[1] * ky + n[2] * kz
    return cf._sign(value, cf.PRED4 * (abs_n[0] * Kx + abs_n[1] * Ky + abs_n[2] * Kz))


@inline
def _and3(x, y, z):
    """Three-valued AND (1 true, 0 undecided, -1 false)."""
    return min(min(x, y), z)


@inline
def _is(sign, want):
    """Three-valued ``sign == want`` of a decided or undecided (0) sign."""
    return 0 if sign == 0 else (1 if sign == want else -1)


@inline
def _classify(e, f, w00, w01, w10, w11, point_a, point_b):
    """The pair of features holding the minimum, as an index into
    :data:`_PAIRS`, or -1 when the float predicates cannot decide.

    The inputs are the leading parts of the exact differences (each rounded
    once).  A pair is taken only when all its optimality conditions hold
    strictly beyond their error bounds; the minimum is then unique, so the
    pair is also the lowest that holds one.  ``point_a`` (``point_b``): the
    segment's endpoints are exactly equal, so that all its features hold
    the closest point and the lowest, ``VERTEX0``, is the answer: its
    conditions are set to hold and those of the others to fail.
    """
    # Clamps: alpha_ij = (A_i - B_j) . f and beta_ji = (B_j - A_i) . e.
    a00 = -_dot_sign(w00, f)
    a01 = -_dot_sign(w01, f)
    a10 = -_dot_sign(w10, f)
    a11 = -_dot_sign(w11, f)
    b00 = _dot_sign(w00, e)
    b01 = _dot_sign(w10, e)
    b10 = _dot_sign(w01, e)
    b11 = _dot_sign(w11, e)
    # Free parameters: h_i = n . ((A_i - B0) x f) and k_j = n . ((B_j - A0) x e).
    n = (e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0])
    abs_n = cf._cross_abs(abs(e[0]), abs(e[1]), abs(e[2]), abs(f[0]), abs(f[1]), abs(f[2]))
    h0 = -_triple_sign(n, abs_n, w00, f)
    h1 = -_triple_sign(n, abs_n, w10, f)
    k0 = _triple_sign(n, abs_n, w00, e)
    k1 = _triple_sign(n, abs_n, w01, e)
    b00, b01, b10, b11 = (-1, -1, -1, -1) if point_a else (b00, b01, b10, b11)
    h0 = 1 if point_a else h0
    a00, a01, a10, a11 = (-1, -1, -1, -1) if point_b else (a00, a01, a10, a11)
    k0 = -1 if point_b else k0
    holds = (
        min(_is(b00, -1), _is(a00, -1)),
        min(_is(b10, -1), _is(a01, 1)),
        _and3(_is(a00, 1), _is(a01, -1), _is(h0, 1)),
        min(_is(b01, 1), _is(a10, -1)),
        min(_is(b11, 1), _is(a11, 1)),
        _and3(_is(a10, 1), _is(a11, -1), _is(h1, -1)),
        _and3(_is(b00, 1), _is(b01, -1), _is(k0, -1)),
        _and3(_is(b10, 1), _is(b11, -1), _is(k1, 1)),
        min(min(_is(h0, -1), _is(h1, 1)), min(_is(k0, 1), _is(k1, -1))),
    )
    result = -1
    for index in literal_unroll((8, 7, 6, 5, 4, 3, 2, 1, 0)):
        result = index if holds[index] == 1 else result
    return result


@inline
def _lead(v):
    """The leading parts of a double-double vector."""
    return v[0], v[2], v[4]


@inline
def _edge_sqr(w, d):
    """``|w x d|^2 / |d|^2`` of double-double vectors, with its error bound."""
    k = cf.cross3(w[0], w[1], w[2], w[3], w[4], w[5], d[0], d[1], d[2], d[3], d[4], d[5])
    nh, nl, dn = cf.norm2_bounded(k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7], k[8])
    mh, ml, dm = cf.sum_sq(d[0], d[1], d[2], d[3], d[4], d[5])
    return cf.ratio(nh, nl, dn, mh, ml, dm)


@inline
def _lines_sqr(e, f, w):
    """``(n . w)^2 / |n|^2`` with ``n = e x f``, in double-double, with its error bound."""
    n = cf.cross3(e[0], e[1], e[2], e[3], e[4], e[5], f[0], f[1], f[2], f[3], f[4], f[5])
    th, tl, dt = cf._dot_bounded(n, (n[6], n[7], n[8]), w)
    th2, tl2 = dd_sqr(th, tl)
    dt2 = 2.0 * abs(th) * dt + dt * dt + 8.0 * cf.U * cf.U * abs(th2)
    gh, gl, dg = cf.norm2_bounded(n[0], n[1], n[2], n[3], n[4], n[5], n[6], n[7], n[8])
    return cf.ratio(th2, tl2, dt2, gh, gl, dg)


_FAIL = (
    cf.EXACT, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
    NONE, NONE, math.nan, math.nan,
)  # fmt: skip


@part
def certified(a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z):
    """Certified segment-segment query for any finite input, or a request for
    the exact fallback; see the module docstring.

    Returns ``(status, distance, ...)``: the fields of :func:`robust` after
    a status, :data:`~proximity.numerics.certified.CERTAIN` (the distance is
    faithfully rounded and the features are exact) or
    :data:`~proximity.numerics.certified.EXACT` (the other values are then
    meaningless).
    """
    e = cf.dd_vec(a0x, a0y, a0z, a1x, a1y, a1z)
    f = cf.dd_vec(b0x, b0y, b0z, b1x, b1y, b1z)
    w00 = cf.dd_vec(a0x, a0y, a0z, b0x, b0y, b0z)
    w01 = cf.dd_vec(a0x, a0y, a0z, b1x, b1y, b1z)
    w10 = cf.dd_vec(a1x, a1y, a1z, b0x, b0y, b0z)
    w11 = cf.dd_vec(a1x, a1y, a1z, b1x, b1y, b1z)
    m = _largest(_lead(e), _lead(f), _lead(w00), _lead(w01), _lead(w10), _lead(w11))
    if not m < math.inf:
        return _FAIL  # a difference of two finite coordinates overflowed
    if m == 0.0:
        return cf.CERTAIN, 0.0, 0.0, a0x, a0y, a0z, a0x, a0y, a0z, VERTEX0, VERTEX0, 0.0, 0.0
    g = 1.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        e, o1 = cf.scale_vec(e, f1, f2)
        f, o2 = cf.scale_vec(f, f1, f2)
        w00, o3 = cf.scale_vec(w00, f1, f2)
        w01, o4 = cf.scale_vec(w01, f1, f2)
        w10, o5 = cf.scale_vec(w10, f1, f2)
        w11, o6 = cf.scale_vec(w11, f1, f2)
        if not (o1 & o2 & o3 & o4 & o5 & o6):
            return _FAIL
        g = (1.0 / f1) * (1.0 / f2)
        if not g < math.inf:
            return _FAIL
    le, lf, l00, l01, l10, l11 = _lead(e), _lead(f), _lead(w00), _lead(w01), _lead(w10), _lead(w11)
    point_a = (e[0] == 0.0) & (e[2] == 0.0) & (e[4] == 0.0)
    point_b = (f[0] == 0.0) & (f[2] == 0.0) & (f[4] == 0.0)
    index = _classify(le, lf, l00, l01, l10, l11, point_a, point_b)
    if index < 0:
        return _FAIL
    fa, fb = _PAIRS[index]
    # The squared distance in double-double, and the witnesses in float
    # relative to ``base`` (an endpoint, as in :func:`_robust_local`).
    if fa != EDGE01 and fb != EDGE01:
        w = w00 if index == 0 else (w01 if index == 1 else (w10 if index == 3 else w11))
        sh, sl, delta = cf.sum_sq(w[0], w[1], w[2], w[3], w[4], w[5])
        base, ax, ay, az, bx, by, bz = 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        s, t = (0.0 if fa == VERTEX0 else 1.0), (0.0 if fb == VERTEX0 else 1.0)
    elif fb == EDGE01 and fa != EDGE01:
        w, lw0, lw1 = (w00, l00, l01) if fa == VERTEX0 else (w10, l10, l11)
        sh, sl, delta = _edge_sqr(w, f)
        _, bx, by, bz, t = project(lw0[0], lw0[1], lw0[2], lf[0], lf[1], lf[2], lw1[0], lw1[1], lw1[2])
        base, ax, ay, az, s = (0 if fa == VERTEX0 else 1), 0.0, 0.0, 0.0, (0.0 if fa == VERTEX0 else 1.0)
    elif fa == EDGE01 and fb != EDGE01:
        w, lw0, lw1 = (w00, l00, l10) if fb == VERTEX0 else (w01, l01, l11)
        sh, sl, delta = _edge_sqr(w, e)
        _, ax, ay, az, s = project(-lw0[0], -lw0[1], -lw0[2], le[0], le[1], le[2], -lw1[0], -lw1[1], -lw1[2])
        base, bx, by, bz, t = (2 if fb == VERTEX0 else 3), 0.0, 0.0, 0.0, (0.0 if fb == VERTEX0 else 1.0)
    else:
        sh, sl, delta = _lines_sqr(e, f, w00)
        _, ax, ay, az, x, y, z, s, t = _interior(le, lf, l00, l01, l10)
        base, bx, by, bz = 0, ax + x, ay + y, az + z
    ok, d, sqr = cf.faithful_sqrt(sh, sl, delta)
    d = d * g
    ok = ok & ((d >= 2.2250738585072014e-308) | (d == 0.0)) & (d < math.inf)
    if not ok:
        return _FAIL
    args = (a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z)
    # The witnesses as the robust method makes them absolute, with the
    # features fixed: a clamped float parameter cannot change them.
    r = _finish((sqr, base, ax, ay, az, bx, by, bz, s, t), (g, g, 1.0), *args)
    return cf.CERTAIN, d, sqr * g * g, r[2], r[3], r[4], r[5], r[6], r[7], fa, fb, s, t
