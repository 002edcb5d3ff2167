"""Exact fallback of the certified method: rational arithmetic in Python.

Used only for the queries the filtered float path cannot decide (points
within rounding of a region boundary or on the shape, degenerate triangles),
so its speed matters little.  Every float is taken at its exact binary value
(``Fraction(float)`` is exact).

Triangles run the region algorithm of Eberly's document (Listings 1-8) exactly, which is
correct in rational arithmetic for every non-degenerate triangle; a
zero-area triangle is the segment hull of its edges.  Segments are the
clamped projection, exact.  Square roots are taken
with integer square roots: to a precision fixed in advance where the value is
rational, and with refinement until the rounding is decided where it is not
(a circle's rim).
"""

import math
from fractions import Fraction
from math import isqrt

from ..features import Feature

_MAX = Fraction(float.fromhex("0x1.fffffffffffffp+1023"))


def _float(x):
    """The float nearest a Fraction (correctly rounded), inf beyond the range."""
    try:
        return float(x)  # correctly rounded, up to the largest float's half ulp above it
    except OverflowError:
        return math.inf if x > 0 else -math.inf


def _sqrt_bounds(x, bits):
    """``(lo, hi)`` with ``lo <= sqrt(x) <= hi`` and ``hi - lo`` about ``2^-bits sqrt(x)``."""
    n, d = x.numerator, x.denominator
    # Scale by 4^k so that the integer square root has about `bits` bits.
    k = (2 * bits - (n.bit_length() - d.bit_length())) // 2 + 1
    if k >= 0:
        root = isqrt(n * 4**k // d)
    else:
        root = isqrt(n // (d * 4 ** (-k)))
    scale = Fraction(2) ** -k
    return root * scale, (root + 1) * scale


def faithful_sqrt(lo2, hi2=None):
    """A float within one ulp of ``sqrt(x)`` for every ``x`` in ``[lo2, hi2]``.

    ``lo2 == hi2`` (the default) is an exact square; otherwise returns None
    when the interval is too wide to decide the rounding.
    """
    hi2 = lo2 if hi2 is None else hi2
    if hi2 == 0:
        return 0.0
    lo, _ = _sqrt_bounds(lo2, 80) if lo2 > 0 else (Fraction(0), None)
    _, hi = _sqrt_bounds(hi2, 80)
    r = _float((lo + hi) / 2)
    if math.isinf(r):
        return r if lo > _MAX else None
    below, above = math.nextafter(r, 0.0), math.nextafter(r, math.inf)
    # Beyond the largest float every value above it rounds to inf or to it.
    if Fraction(below) ** 2 < lo2 and (math.isinf(above) or hi2 < Fraction(above) ** 2):
        return r
    return None


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b, strict=True))


def _sub(a, b):
    return [x - y for x, y in zip(a, b, strict=True)]


def _project(p, a, b):
    """``(t, x)``: the closest point ``x = a + t (b - a)`` to ``p`` on the
    closed segment ``ab``; ``t = 0`` for a zero-length segment."""
    e = _sub(b, a)
    ee = _dot(e, e)
    t = min(max(_dot(_sub(p, a), e) / ee, Fraction(0)), Fraction(1)) if ee else Fraction(0)
    return t, [a[k] + t * e[k] for k in range(len(a))]


def _on_open_segment(x, a, b):
    """Whether ``x`` lies strictly inside the non-degenerate segment ``ab``."""
    e = _sub(b, a)
    ee = _dot(e, e)
    if ee == 0:
        return False
    t = Fraction(_dot(_sub(x, a), e), ee)
    return 0 < t < 1 and all(a[i] + t * e[i] == x[i] for i in range(len(x)))


def _eberly_region(d, a, b, c, e):
    """Listings 1-8 in exact arithmetic, for ``det = ac - b^2 > 0``; ``(s, t)``."""
    det = a * c - b * b
    s = b * e - c * d
    t = b * d - a * e
    zero, one = Fraction(0), Fraction(1)
    if s + t <= det:
        if s < 0 and t < 0:  # region 4
            if d < 0:
                return (one if -d >= a else Fraction(-d, a)), zero
            return zero, (zero if e >= 0 else one if -e >= c else Fraction(-e, c))
        if s < 0:  # region 3
            return zero, (zero if e >= 0 else one if -e >= c else Fraction(-e, c))
        if t < 0:  # region 5
            return (zero if d >= 0 else one if -d >= a else Fraction(-d, a)), zero
        return Fraction(s, det), Fraction(t, det)  # region 0
    if s < 0:  # region 2
        tmp0, tmp1 = b + d, c + e
        if tmp1 > tmp0:
            numer, denom = tmp1 - tmp0, a - 2 * b + c
            s = one if numer >= denom else Fraction(numer, denom)
            return s, one - s
        return zero, (one if tmp1 <= 0 else zero if e >= 0 else Fraction(-e, c))
    if t < 0:  # region 6
        tmp0, tmp1 = b + e, a + d
        if tmp1 > tmp0:
            numer, denom = tmp1 - tmp0, a - 2 * b + c
            t = one if numer >= denom else Fraction(numer, denom)
            return one - t, t
        return (one if tmp1 <= 0 else zero if d >= 0 else Fraction(-d, a)), zero
    numer = (c + e) - (b + d)  # region 1
    if numer <= 0:
        s = zero
    else:
        denom = a - 2 * b + c
        s = one if numer >= denom else Fraction(numer, denom)
    return s, one - s


def _triangle(v, p):
    """Exact point-triangle query on Fraction vectors: ``(sqr_distance,
    closest, feature, barycentric)``, all exact; see :func:`triangle`."""
    e0, e1 = _sub(v[1], v[0]), _sub(v[2], v[0])
    a, b, c = _dot(e0, e0), _dot(e0, e1), _dot(e1, e1)
    dvec = _sub(v[0], p)
    d, e = _dot(e0, dvec), _dot(e1, dvec)
    if a * c - b * b > 0:
        s, t = _eberly_region(d, a, b, c, e)
        closest = [v[0][i] + s * e0[i] + t * e1[i] for i in range(3)]
    else:
        # Zero area: the triangle is the hull of its edges, a segment or a point.
        best = None
        for i, j in ((0, 1), (1, 2), (2, 0)):
            edge = _sub(v[j], v[i])
            ee = _dot(edge, edge)
            u = (
                min(max(Fraction(_dot(_sub(p, v[i]), edge), ee), Fraction(0)), Fraction(1))
                if ee
                else Fraction(0)
            )
            x = [v[i][k] + u * edge[k] for k in range(3)]
            dist2 = _dot(_sub(x, p), _sub(x, p))
            if best is None or dist2 < best[0]:
                best = (dist2, x)
        closest = best[1]
    sqr = _dot(_sub(closest, p), _sub(closest, p))

    # The feature whose relative interior holds the closest point, lowest code first.
    zero, one = Fraction(0), Fraction(1)
    if closest in v:
        k = v.index(closest)
        feature, bary = Feature.VERTEX0 + k, [one if i == k else zero for i in range(3)]
    else:
        feature, bary = Feature.FACE, None
        for code, (i, j) in ((Feature.EDGE01, (0, 1)), (Feature.EDGE12, (1, 2)), (Feature.EDGE20, (2, 0))):
            if _on_open_segment(closest, v[i], v[j]):
                edge = _sub(v[j], v[i])
                u = Fraction(_dot(_sub(closest, v[i]), edge), _dot(edge, edge))
                feature, bary = code, [zero] * 3
                bary[i], bary[j] = 1 - u, u
                break
        if bary is None:
            bary = [1 - s - t, s, t]
    return sqr, closest, Feature(feature), bary


def triangle(vertices, point):
    """Exact point-triangle query for 3D float inputs.

    Returns ``(distance, sqr_distance, x, y, z, feature, b0, b1, b2)`` with the
    distance faithfully rounded, the rest correctly rounded, and the feature
    the lowest-coded one whose relative interior holds the closest point.
    """
    (v, (p,)), unit = _grid(vertices, [point])
    sqr, closest, feature, bary = _triangle(v, p)
    sqr *= unit * unit
    return (
        faithful_sqrt(sqr),
        _float(sqr),
        *(_float(x * unit) for x in closest),
        int(feature),
        *(_float(w) for w in bary),
    )


def segment(vertices, point):
    """Exact point-segment query for 3D float inputs (``vertices`` ``(2, 3)``).

    Returns ``(distance, sqr_distance, x, y, z, feature, t)`` with the
    distance faithfully rounded, the rest correctly rounded, and the feature
    ``VERTEX0`` (``t = 0``, which a zero-length segment always gives: the
    lowest code of the tied endpoints), ``VERTEX1`` (``t = 1``) or
    ``EDGE01``.
    """
    v0, v1 = ([Fraction(float(c)) for c in row] for row in vertices)
    p = [Fraction(float(c)) for c in point]
    t, closest = _project(p, v0, v1)
    sqr = _dot(_sub(closest, p), _sub(closest, p))
    feature = Feature.VERTEX0 if t == 0 else (Feature.VERTEX1 if t == 1 else Feature.EDGE01)
    return faithful_sqrt(sqr), _float(sqr), *(_float(x) for x in closest), int(feature), _float(t)


def round_shape(is_disk, center, normal, radius, point, robust_point):
    """Exact point-circle or point-disk query for float inputs.

    ``robust_point`` supplies the closest point where it is not rational (a
    rim point), from the robust method.  Returns ``(distance, sqr_distance, x,
    y, z, feature, equidistant, height, radial)``.
    """
    c = [Fraction(float(x)) for x in center]
    n = [Fraction(float(x)) for x in normal]
    r = Fraction(float(radius))
    dvec = _sub([Fraction(float(x)) for x in point], c)
    nn = _dot(n, n)
    nd = _dot(n, dvec)
    h2 = nd * nd / nn
    q2 = _dot(dvec, dvec) - h2
    face = is_disk and q2 <= r * r
    height = -faithful_sqrt(h2) if nd < 0 else faithful_sqrt(h2)
    radial = faithful_sqrt(q2)
    if face:
        dist, sqr = faithful_sqrt(h2), _float(h2)
        closest = [c[i] + dvec[i] - nd * n[i] / nn for i in range(3)]
        x, y, z = (_float(v) for v in closest)
        feature = Feature.FACE
    else:
        if h2 == 0 and q2 == r * r:
            dist, sqr = 0.0, 0.0
        else:
            # d^2 = h^2 + (q - R)^2 with q irrational: narrow q until d rounds one way.
            bits, dist = 64, None
            while dist is None:
                q_lo, q_hi = _sqrt_bounds(q2, bits) if q2 else (Fraction(0), Fraction(0))
                w = sorted([abs(q_lo - r), abs(q_hi - r)])
                lo2 = h2 + (0 if q_lo <= r <= q_hi else w[0]) ** 2
                hi2 = h2 + w[1] ** 2
                dist = faithful_sqrt(lo2, hi2)
                bits *= 2
            sqr = _float((lo2 + hi2) / 2)
        x, y, z = robust_point
        feature = Feature.RIM
    return dist, sqr, x, y, z, int(feature), (not is_disk) and q2 == 0, height, radial


def hull_sqr_distance(vertices, point):
    """The exact squared distance from ``point`` to the hull of one, two or
    three float ``vertices`` (a point, a segment, a triangle), a Fraction."""
    v = [[Fraction(float(c)) for c in row] for row in vertices]
    p = [Fraction(float(c)) for c in point]
    if len(v) == 3:
        return _triangle(v, p)[0]
    if len(v) == 2:
        closest = _project(p, v[0], v[1])[1]
    else:
        closest = v[0]
    return _dot(_sub(closest, p), _sub(closest, p))


def round_sqr_bounds(is_disk, center, normal, radius, point, bits):
    """``(lo2, hi2)``, Fractions bounding the squared distance from ``point`` to
    a disk or a circle, ``hi2 - lo2`` about ``2^-bits`` of it (equal where it
    is rational: the disk's face)."""
    c = [Fraction(float(x)) for x in center]
    n = [Fraction(float(x)) for x in normal]
    r = Fraction(float(radius))
    dvec = _sub([Fraction(float(x)) for x in point], c)
    nn = _dot(n, n)
    nd = _dot(n, dvec)
    h2 = nd * nd / nn
    q2 = _dot(dvec, dvec) - h2
    if is_disk and q2 <= r * r:
        return h2, h2
    if q2 == r * r:
        return h2, h2
    q_lo, q_hi = _sqrt_bounds(q2, bits) if q2 else (Fraction(0), Fraction(0))
    w = sorted([abs(q_lo - r), abs(q_hi - r)])
    return h2 + (0 if q_lo <= r <= q_hi else w[0]) ** 2, h2 + w[1] ** 2


def _perfect_square(x):
    """The exact square root of the Fraction ``x`` where it is rational, else None."""
    n, d = isqrt(x.numerator), isqrt(x.denominator)
    return Fraction(n, d) if n * n == x.numerator and d * d == x.denominator else None


def minus_radius(sqr_bounds, radius):
    """A float within one ulp of ``sqrt(s) - radius``, ``s`` the exact squared
    distance bounded by ``sqr_bounds(bits) -> (lo2, hi2)`` to ``2^-bits`` of it;
    ``radius`` a float, or a Fraction (the exact sum of two radii).

    The bounds are narrowed until one float is faithful for every value
    they allow; a rational ``sqrt(s)`` (an exact square) gives the value
    itself, correctly rounded.
    """
    r = radius if isinstance(radius, Fraction) else Fraction(float(radius))
    bits = 64
    while True:
        lo2, hi2 = sqr_bounds(bits)
        if lo2 == hi2:
            root = _perfect_square(lo2)
            if root is not None:
                return _float(root - r)
        lo = _sqrt_bounds(lo2, bits)[0] if lo2 > 0 else Fraction(0)
        hi = _sqrt_bounds(hi2, bits)[1]
        t_lo, t_hi = lo - r, hi - r
        f = _float((t_lo + t_hi) / 2)
        below, above = math.nextafter(f, -math.inf), math.nextafter(f, math.inf)
        if Fraction(below) < t_lo and t_hi < Fraction(above) or bits > 1 << 16:
            return f
        bits *= 2


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _axpy(s, x, y):
    """``y + s x``."""
    return [yk + s * xk for xk, yk in zip(x, y, strict=True)]


def _segment_segment(p0, p1, q0, q1):
    """Exact segment-segment query on Fraction vectors.

    The optimality conditions of the squared distance on the parameter
    square, in code order of the feature pairs (those of the certified
    method's filter, exactly): the first pair whose conditions hold holds a
    closest pair, and it is the lowest that does.  Returns ``(sqr_distance,
    point_a, point_b, feature_a, feature_b, s, t)``, all exact.
    """
    e, f = _sub(p1, p0), _sub(q1, q0)
    w = {(i, j): _sub(q, p) for i, p in enumerate((p0, p1)) for j, q in enumerate((q0, q1))}
    alpha = {ij: -_dot(w[ij], f) for ij in w}  # (A_i - B_j) . f
    beta = {(j, i): _dot(w[i, j], e) for i, j in w}  # (B_j - A_i) . e
    n = _cross(e, f)
    h = [-_dot(n, _cross(w[i, 0], f)) for i in (0, 1)]  # -s |n|^2 and (1 - s) |n|^2 on the lines
    k = [_dot(n, _cross(w[0, j], e)) for j in (0, 1)]  # t |n|^2 and -(1 - t) |n|^2
    vertex, edge = (Feature.VERTEX0, Feature.VERTEX1), Feature.EDGE01
    conditions = []
    for i in (0, 1):
        for j in (0, 1):
            s_ok = beta[j, 0] <= 0 if i == 0 else beta[j, 1] >= 0
            t_ok = alpha[i, 0] <= 0 if j == 0 else alpha[i, 1] >= 0
            conditions.append(((vertex[i], vertex[j]), s_ok and t_ok))
        on_b = alpha[i, 0] > 0 and alpha[i, 1] < 0
        conditions.append(((vertex[i], edge), on_b and (h[0] >= 0 if i == 0 else h[1] <= 0)))
    for j in (0, 1):
        on_a = beta[j, 0] > 0 and beta[j, 1] < 0
        conditions.append(((edge, vertex[j]), on_a and (k[0] <= 0 if j == 0 else k[1] >= 0)))
    # Parallel lines (n = 0) never reach this: a lower pair holds then.
    conditions.append(((edge, edge), h[0] < 0 < h[1] and k[1] < 0 < k[0]))
    (fa, fb) = next(pair for pair, holds in sorted(conditions) if holds)
    zero, one = Fraction(0), Fraction(1)
    if fa == edge and fb == edge:
        nn = _dot(n, n)
        s, t = Fraction(-h[0], nn), Fraction(k[0], nn)
    elif fb == edge:
        s = zero if fa == Feature.VERTEX0 else one
        t = Fraction(alpha[int(fa), 0], _dot(f, f))
    elif fa == edge:
        s, t = Fraction(beta[int(fb), 0], _dot(e, e)), zero if fb == Feature.VERTEX0 else one
    else:
        s, t = Fraction(int(fa)), Fraction(int(fb))
    pa, pb = _axpy(s, e, p0), _axpy(t, f, q0)
    return _dot(_sub(pa, pb), _sub(pa, pb)), pa, pb, fa, fb, s, t


def _grid(*arrays):
    """Float arrays (of rows) as integers times one power of two: ``(rows,
    unit)`` with every value ``rows[..] * unit``, exactly.

    The queries then multiply integers, and form a Fraction only where they
    divide, which makes the exact arithmetic several times faster.
    """
    values = [[[Fraction(float(c)) for c in row] for row in arr] for arr in arrays]
    shift = max(x.denominator.bit_length() - 1 for arr in values for row in arr for x in row)
    rows = [
        [[x.numerator << (shift - x.denominator.bit_length() + 1) for x in row] for row in arr]
        for arr in values
    ]
    return rows, Fraction(1, 1 << shift)


def segment_segment(a, b):
    """Exact segment-segment query for 3D float inputs, the certified method's fallback.

    Returns ``(distance, sqr_distance, pax, pay, paz, pbx, pby, pbz,
    feature_a, feature_b, s, t)`` with the distance faithfully rounded, the
    rest correctly rounded, and the lowest feature pair that holds a closest
    pair; a zero distance has one point as both witnesses.
    """
    ((p0, p1), (q0, q1)), unit = _grid(a, b)
    sqr, pa, pb, fa, fb, s, t = _segment_segment(p0, p1, q0, q1)
    sqr *= unit * unit
    return (
        faithful_sqrt(sqr),
        _float(sqr),
        *(_float(x * unit) for x in pa),
        *(_float(x * unit) for x in pb),
        int(fa),
        int(fb),
        _float(s),
        _float(t),
    )


_TRIANGLE_EDGES = ((Feature.EDGE01, 0, 1), (Feature.EDGE12, 1, 2), (Feature.EDGE20, 2, 0))


def _segment_triangle(p0, p1, v):
    """Exact segment-triangle query on Fraction vectors.

    The minimum over the document's sub-queries, each exact: each endpoint
    against the triangle, the segment against each edge, and the segment
    crossing the open face.  Every feature pair but a parallel edge-face
    pair (never the lowest that holds a closest pair) belongs to one of
    them, and each returns its lowest, so the lowest ``(sqr_distance,
    pair)`` over them is the answer.  Returns ``(sqr_distance, point_a,
    point_b, feature_a, feature_b, s, barycentric)``, all exact.
    """
    zero = Fraction(0)
    candidates = []
    for i, p in enumerate((p0, p1)):
        sqr, closest, feature, bary = _triangle(v, p)
        candidates.append((sqr, (Feature(i), feature), p, closest, Fraction(i), bary))
    for code, j, k in _TRIANGLE_EDGES:
        sqr, pa, pb, fa, fb, s, t = _segment_segment(p0, p1, v[j], v[k])
        bary = [zero] * 3
        bary[j], bary[k] = 1 - t, t
        feature = code if fb == Feature.EDGE01 else Feature(j if fb == Feature.VERTEX0 else k)
        candidates.append((sqr, (fa, feature), pa, pb, s, bary))
    e = _sub(p1, p0)
    n = _cross(_sub(v[1], v[0]), _sub(v[2], v[0]))
    nn = _dot(n, n)
    h0, h1 = _dot(n, _sub(p0, v[0])), _dot(n, _sub(p1, v[0]))
    if nn != 0 and h0 * h1 < 0:
        s = Fraction(h0, h0 - h1)
        x = _axpy(s, e, p0)
        bary = [
            Fraction(_dot(n, _cross(_sub(v[(k + 1) % 3], x), _sub(v[(k + 2) % 3], x))), nn) for k in range(3)
        ]
        if all(b > 0 for b in bary):
            candidates.append((zero, (Feature.EDGE01, Feature.FACE), x, x, s, bary))
    sqr, (fa, fb), pa, pb, s, bary = min(candidates, key=lambda c: (c[0], c[1]))
    return sqr, pa, pb, fa, fb, s, bary


def segment_triangle(segment, triangle):
    """Exact segment-triangle query for 3D float inputs, the certified method's fallback.

    Returns ``(distance, sqr_distance, pax, pay, paz, pbx, pby, pbz,
    feature_a, feature_b, s, b0, b1, b2)`` as :func:`segment_segment` does,
    with the triangle witness's barycentric coordinates.
    """
    ((p0, p1), v), unit = _grid(segment, triangle)
    sqr, pa, pb, fa, fb, s, bary = _segment_triangle(p0, p1, v)
    sqr *= unit * unit
    return (
        faithful_sqrt(sqr),
        _float(sqr),
        *(_float(x * unit) for x in pa),
        *(_float(x * unit) for x in pb),
        int(fa),
        int(fb),
        _float(s),
        *(_float(w) for w in bary),
    )


def _edge_weights(i, j, s):
    """Barycentric weights of the point at parameter ``s`` from vertex ``i`` to vertex ``j``."""
    weights = [Fraction(0)] * 3
    weights[i], weights[j] = 1 - s, s
    return weights


def _edge_feature(code, i, j, feature):
    """A triangle's feature for a segment feature of its edge ``code`` from vertex ``i`` to ``j``."""
    if feature == Feature.EDGE01:
        return code
    return Feature(i if feature == Feature.VERTEX0 else j)


def _triangle_triangle(a, b):
    """Exact triangle-triangle query on Fraction vectors.

    The least of the six exact segment-triangle queries of each edge of one
    triangle against the other: every feature pair but two faces (never the
    lowest that holds a closest pair) belongs to one of them, and each
    returns its lowest.  Returns ``(sqr_distance, point_a, point_b,
    feature_a, feature_b, barycentric_a, barycentric_b)``, all exact.
    """
    candidates = []
    for code, i, j in _TRIANGLE_EDGES:
        sqr, pa, pb, fa, fb, s, bary = _segment_triangle(a[i], a[j], b)
        pair = (_edge_feature(code, i, j, fa), fb)
        candidates.append((sqr, pair, pa, pb, _edge_weights(i, j, s), bary))
    for code, i, j in _TRIANGLE_EDGES:
        sqr, pb, pa, fb, fa, s, bary = _segment_triangle(b[i], b[j], a)
        pair = (fa, _edge_feature(code, i, j, fb))
        candidates.append((sqr, pair, pa, pb, bary, _edge_weights(i, j, s)))
    sqr, (fa, fb), pa, pb, bary_a, bary_b = min(candidates, key=lambda c: (c[0], c[1]))
    return sqr, pa, pb, fa, fb, bary_a, bary_b


def triangle_triangle(a, b):
    """Exact triangle-triangle query for 3D float inputs, the certified method's fallback.

    Returns ``(distance, sqr_distance, pax, pay, paz, pbx, pby, pbz,
    feature_a, feature_b, a0, a1, a2, b0, b1, b2)`` as :func:`segment_segment`
    does, with both witnesses' barycentric coordinates.
    """
    (va, vb), unit = _grid(a, b)
    sqr, pa, pb, fa, fb, bary_a, bary_b = _triangle_triangle(va, vb)
    sqr *= unit * unit
    return (
        faithful_sqrt(sqr),
        _float(sqr),
        *(_float(x * unit) for x in pa),
        *(_float(x * unit) for x in pb),
        int(fa),
        int(fb),
        *(_float(w) for w in bary_a),
        *(_float(w) for w in bary_b),
    )


def pair_sqr_distance(a, b):
    """The exact squared distance between two segments or triangles (float
    vertices ``(2 or 3, 3)`` each, a segment first), a Fraction."""
    (va, vb), unit = _grid(a, b)
    if len(va) == 2:
        sqr = _segment_segment(*va, *vb)[0] if len(vb) == 2 else _segment_triangle(*va, vb)[0]
    else:
        sqr = _triangle_triangle(va, vb)[0]
    return sqr * unit * unit
