"""Certified distances: faithfully rounded, with the exact closest feature.

``method="certified"`` returns, for every finite input, a distance that is one
of the two float64 values bracketing the exact distance ``d*`` (so
``|d - d*| < ulp(d*)``), the exact closest feature, and exactly 0 for a point
on the shape.  It is a filtered computation:

1. **Predicates in float, with semi-static error bounds.**  Which feature is
   closest (a vertex, the interior of an edge, the face) is decided by the
   signs of six dot products and three edge functions (for a disk, by
   ``q^2 <= R^2``), each evaluated in float64 together with a rigorous bound
   on its rounding error: ``(k + n + margin) u F``, where ``F`` is the same
   expression evaluated on absolute values, ``k`` its degree in the inputs
   (the rounded coordinate differences) and ``n`` the depth of its
   evaluation.  A sign is taken only when the value exceeds its bound.
2. **The squared distance to that feature in double-double** (about 106
   bits, :mod:`.dd`), from the exact differences ``V - P`` (an error-free
   subtraction), by formulas without cancellation where possible: ``|X|^2``
   for a vertex, ``|A x B|^2 / |B - A|^2`` for an edge, ``(A . (B x C))^2 /
   |n|^2`` for the face, ``h^2 + (q - R)^2`` for a rim.  Each carries a bound
   ``delta`` built from the error bounds of the double-double operations.
3. **A rounding check.**  ``r``, the float nearest ``sqrt(s)``, is faithful
   when ``pred(r)^2 < s - delta`` and ``s + delta < succ(r)^2``, compared
   exactly with error-free products.

Where a sign is undecided (a point within rounding of a region boundary, a
degenerate triangle, a point on the shape), a term is too small for the
double-double bounds (below :data:`DD_MIN` in the scaled frame: a distance
under about ``2^-480`` of the query's size), or the rounding check fails, the
query falls back to exact rational arithmetic (:mod:`.exact`), refining a
square root's precision until the rounding is decided.  The fallback counts
are available from :func:`stats`.

Ties between features (possible only for degenerate triangles, where the
closest point lies inside several features) go to the lowest
:class:`~proximity.Feature` code, that is the lowest-dimensional feature and
then the lowest index.
"""

import math

import numpy as np
from numba import literal_unroll, uint64

from ..features import EDGE01, EDGE12, FACE, NONE, VERTEX0, VERTEX1, VERTEX2
from ..runtime.counts import count  # noqa: F401  (re-exported for the kernels' callers)
from ..runtime.jit import inline, part
from ..runtime.loops import (
    BLOCK,
    PAIR_OK,
    PAIR_OUT,
    PAIR_P,
    PAIR_ROWS,
    gather_triangles,
    scatter_triangles,
    store,
    triangle_at,
)
from . import dd
from .fp import SAFE_MAX, SAFE_MIN, cross_accurate, dot3_accurate, edge_function, fma, pow2_scale

U = 2.0**-53
SLACK = 2.0**-990  # absolute slack, in the scaled frame: covers underflowed terms
# Error bound factors, in units of u, for predicates of degree 2 and 4 in the
# coordinate differences (degree + evaluation depth + a margin).
PRED2 = 16.0 * U
PRED4 = 40.0 * U

CERTAIN = 0.0
EXACT = 1.0

# Below this, a double-double's low part is subnormal and the relative error
# bounds of the double-double operations fail (2^-969 and under, with room
# for the few operations that follow).
DD_MIN = 2.0**-960


@inline
def _sign(value, bound):
    """+1 or -1 when ``|value| > bound``, else 0 (undecided)."""
    bound = bound * (1.0 + 1e-12) + SLACK
    return 1 if value > bound else (-1 if value < -bound else 0)


@inline
def dot_sign(ax, ay, az, bx, by, bz):
    """The sign of ``a . b`` for vectors rounded once from exact values, or 0
    when it is undecided: the predicates of :func:`_classify` on their own.

    The bound covers that rounding and the evaluation, relative to ``|a| . |b|``.
    """
    value = ax * bx + ay * by + az * bz
    return _sign(value, PRED2 * (abs(ax) * abs(bx) + abs(ay) * abs(by) + abs(az) * abs(bz)))


@inline
def _both(s1, s2, want1, want2):
    """Three-valued AND of two signs: 1 true, 0 undecided, -1 false."""
    false = ((s1 != 0) & (s1 != want1)) | ((s2 != 0) & (s2 != want2))
    return -1 if false else (1 if (s1 == want1) & (s2 == want2) else 0)


@inline
def _cross_abs(ax, ay, az, bx, by, bz):
    return ay * bz + az * by, az * bx + ax * bz, ax * by + ay * bx


@inline
def faithful_sqrt(sh, sl, delta):
    """``(ok, r, s)``: ``r`` is ``sqrt(sh + sl)`` rounded to a float, ``ok``
    when ``r`` is faithful for every value within ``delta`` of ``sh + sl``;
    ``s`` is the square rounded to a float.

    One Newton step on the exact residual puts ``r`` within ``(1/2 + 2^-50)
    ulp`` of ``sqrt(sh + sl)``, and ``ulp(r) > 2^-53 r``, so ``r`` is
    faithful whenever ``delta < 2^-54 (sh + sl)``: the rest of the ulp then
    covers the error of ``s`` (half an ulp below a power of two included).
    """
    positive = sh > 0.0
    h = sh if positive else 1.0
    r = math.sqrt(h)
    r = r + ((fma(-r, r, h) + (sl if positive else 0.0)) / (2.0 * r))
    ok = positive & (delta * (1.0 + 1e-9) + SLACK < h * 2.0**-54)
    ok = ok | ((sh == 0.0) & (sl == 0.0) & (delta == 0.0))
    return ok, r if positive else 0.0, sh + sl if positive else 0.0


@inline
def sum_sq(xh, xl, yh, yl, zh, zl):
    """``x^2 + y^2 + z^2`` of double-doubles, with ``delta`` (no cancellation)."""
    s1h, s1l = dd.sqr(xh, xl)
    s2h, s2l = dd.sqr(yh, yl)
    s3h, s3l = dd.sqr(zh, zl)
    sh, sl = dd.add(s1h, s1l, s2h, s2l)
    sh, sl = dd.add(sh, sl, s3h, s3l)
    # Squares that underflowed to zero are not a certain zero.
    underflow = (sh == 0.0) & ((xh != 0.0) | (yh != 0.0) | (zh != 0.0))
    return sh, sl, math.inf if underflow else 16.0 * U * U * abs(sh)


@inline
def _cross_dd(ah, al, bh, bl, ch, cl, dh, dl):
    """``a * d - b * c`` of double-doubles, and a bound on its error."""
    p1h, p1l = dd.mul(ah, al, dh, dl)
    p2h, p2l = dd.mul(bh, bl, ch, cl)
    rh, rl = dd.sub(p1h, p1l, p2h, p2l)
    return rh, rl, 16.0 * U * U * (abs(p1h) + abs(p2h))


@inline
def cross3(xh, xl, yh, yl, zh, zl, ph, pl, qh, ql, rh, rl):
    """``(x, y, z) x (p, q, r)`` in double-double, with per-component bounds."""
    cxh, cxl, ex = _cross_dd(yh, yl, zh, zl, qh, ql, rh, rl)
    cyh, cyl, ey = _cross_dd(zh, zl, xh, xl, rh, rl, ph, pl)
    czh, czl, ez = _cross_dd(xh, xl, yh, yl, ph, pl, qh, ql)
    return cxh, cxl, cyh, cyl, czh, czl, ex, ey, ez


@inline
def norm2_bounded(xh, xl, yh, yl, zh, zl, ex, ey, ez):
    """``|c|^2`` of a double-double vector whose components err by ``e*``."""
    sh, sl, d = sum_sq(xh, xl, yh, yl, zh, zl)
    d += 2.0 * (abs(xh) * ex + abs(yh) * ey + abs(zh) * ez) + ex * ex + ey * ey + ez * ez
    return sh, sl, d


@inline
def ratio(nh, nl, dn, mh, ml, dm):
    """``n / m`` and its error bound, from the bounds of both.

    No bound (inf) where ``n`` or ``m`` is below :data:`DD_MIN`: their
    relative bounds do not hold there, and the quotient may have
    underflowed to a zero that would pass for an exact one.
    """
    qh, ql = dd.div(nh, nl, mh, ml)
    rel = dn / abs(nh) + dm / abs(mh) + 32.0 * U * U
    return qh, ql, 2.0 * rel * abs(qh) if (abs(nh) >= DD_MIN) & (abs(mh) >= DD_MIN) else math.inf


@inline
def _classify(ax, ay, az, bx, by, bz, cx, cy, cz, e0x, e0y, e0z, e1x, e1y, e1z, e2x, e2y, e2z):
    """The exact closest feature from float predicates, or NONE if undecided.

    ``a, b, c`` are the vertices relative to ``P`` and ``e0 = V1 - V0``,
    ``e1 = V2 - V0``, ``e2 = V2 - V1`` the edges, all rounded once from exact
    values; each bound covers that rounding as a relative perturbation of
    the inputs, so it scales with the triangle's edges, not with the
    distance to it.
    """
    Ax, Ay, Az = abs(ax), abs(ay), abs(az)
    Bx, By, Bz = abs(bx), abs(by), abs(bz)
    Cx, Cy, Cz = abs(cx), abs(cy), abs(cz)
    E0x, E0y, E0z = abs(e0x), abs(e0y), abs(e0z)
    E1x, E1y, E1z = abs(e1x), abs(e1y), abs(e1z)
    E2x, E2y, E2z = abs(e2x), abs(e2y), abs(e2z)
    # (P - X) . (Y - X) for each vertex X and each edge XY through it.
    ab_a = _sign(-(ax * e0x + ay * e0y + az * e0z), PRED2 * (Ax * E0x + Ay * E0y + Az * E0z))
    ab_b = _sign(bx * e0x + by * e0y + bz * e0z, PRED2 * (Bx * E0x + By * E0y + Bz * E0z))
    bc_b = _sign(-(bx * e2x + by * e2y + bz * e2z), PRED2 * (Bx * E2x + By * E2y + Bz * E2z))
    bc_c = _sign(cx * e2x + cy * e2y + cz * e2z, PRED2 * (Cx * E2x + Cy * E2y + Cz * E2z))
    ca_c = _sign(cx * e1x + cy * e1y + cz * e1z, PRED2 * (Cx * E1x + Cy * E1y + Cz * E1z))
    ca_a = _sign(-(ax * e1x + ay * e1y + az * e1z), PRED2 * (Ax * E1x + Ay * E1y + Az * E1z))
    # Edge functions n . (X x E), as in the robust method, with their bounds.
    nx, ny, nz = e0y * e1z - e0z * e1y, e0z * e1x - e0x * e1z, e0x * e1y - e0y * e1x
    Nx, Ny, Nz = _cross_abs(E0x, E0y, E0z, E1x, E1y, E1z)
    kx, ky, kz = ay * e0z - az * e0y, az * e0x - ax * e0z, ax * e0y - ay * e0x
    Kx, Ky, Kz = _cross_abs(Ax, Ay, Az, E0x, E0y, E0z)
    wc = _sign(nx * kx + ny * ky + nz * kz, PRED4 * (Nx * Kx + Ny * Ky + Nz * Kz))
    kx, ky, kz = by * e2z - bz * e2y, bz * e2x - bx * e2z, bx * e2y - by * e2x
    Kx, Ky, Kz = _cross_abs(Bx, By, Bz, E2x, E2y, E2z)
    wa = _sign(nx * kx + ny * ky + nz * kz, PRED4 * (Nx * Kx + Ny * Ky + Nz * Kz))
    kx, ky, kz = cy * e1z - cz * e1y, cz * e1x - cx * e1z, cx * e1y - cy * e1x
    Kx, Ky, Kz = _cross_abs(Cx, Cy, Cz, E1x, E1y, E1z)
    wb = -_sign(nx * kx + ny * ky + nz * kz, PRED4 * (Nx * Kx + Ny * Ky + Nz * Kz))
    # The regions, in feature-code order: the first that certainly holds is
    # the closest feature, and an undecided one before it leaves it open.
    # Selects rather than branches, so that a loop of queries vectorises.
    holds = (
        _both(ab_a, ca_a, -1, -1),
        _both(ab_b, bc_b, -1, -1),
        _both(bc_c, ca_c, -1, -1),
        min(_both(ab_a, ab_b, 1, 1), _both(wc, wc, -1, -1)),
        min(_both(bc_b, bc_c, 1, 1), _both(wa, wa, -1, -1)),
        min(_both(ca_c, ca_a, 1, 1), _both(wb, wb, -1, -1)),
        min(_both(wa, wb, 1, 1), _both(wc, wc, 1, 1)),
    )
    result = NONE
    still_open = True
    for feature in literal_unroll((0, 1, 2, 3, 4, 5, 6)):
        result = feature if still_open & (holds[feature] == 1) else result
        still_open = still_open & (holds[feature] == -1)
    return result


@inline
def scale_exact(x, f1, f2):
    """``x * f1 * f2`` and whether that was exact (no underflow)."""
    y = x * f1 * f2
    return y, (y / f2) / f1 == x


@inline
def dd_vec(x0, y0, z0, x1, y1, z1):
    """``(x1, y1, z1) - (x0, y0, z0)``, exactly, as three double-doubles."""
    xh, xl = dd.diff(x1, x0)
    yh, yl = dd.diff(y1, y0)
    zh, zl = dd.diff(z1, z0)
    return xh, xl, yh, yl, zh, zl


@inline
def scale_vec(v, f1, f2):
    """A double-double vector times ``f1 * f2``, and whether that was exact."""
    xh, o1 = scale_exact(v[0], f1, f2)
    xl, o2 = scale_exact(v[1], f1, f2)
    yh, o3 = scale_exact(v[2], f1, f2)
    yl, o4 = scale_exact(v[3], f1, f2)
    zh, o5 = scale_exact(v[4], f1, f2)
    zl, o6 = scale_exact(v[5], f1, f2)
    return (xh, xl, yh, yl, zh, zl), o1 & o2 & o3 & o4 & o5 & o6


@inline
def _dot_bounded(v, vh_err, w):
    """``v . w`` of double-double vectors where ``v`` errs by ``vh_err``; ``(h, l, delta)``."""
    t1h, t1l = dd.mul(v[0], v[1], w[0], w[1])
    t2h, t2l = dd.mul(v[2], v[3], w[2], w[3])
    t3h, t3l = dd.mul(v[4], v[5], w[4], w[5])
    th, tl = dd.add(t1h, t1l, t2h, t2l)
    th, tl = dd.add(th, tl, t3h, t3l)
    delta = abs(w[0]) * vh_err[0] + abs(w[2]) * vh_err[1] + abs(w[4]) * vh_err[2]
    return th, tl, delta + 16.0 * U * U * (abs(t1h) + abs(t2h) + abs(t3h))


@inline
def _sel(c, x, y):
    """Element-wise ``x if c else y`` of two double-double vectors."""
    return (
        x[0] if c else y[0],
        x[1] if c else y[1],
        x[2] if c else y[2],
        x[3] if c else y[3],
        x[4] if c else y[4],
        x[5] if c else y[5],
    )


@inline
def vertex_distance(x):
    """``(ok, distance, sqr_distance)`` of a vertex ``X`` relative to ``P``
    (a double-double vector): ``|X|^2``, which has no cancellation, and
    whether its square root is faithful (:func:`faithful_sqrt`)."""
    vh, vl, dv = sum_sq(x[0], x[1], x[2], x[3], x[4], x[5])
    return faithful_sqrt(vh, vl, dv)


@inline
def edge_distance(p, e):
    """The distance to a segment from ``X`` along ``E`` (double-double
    vectors, ``X`` relative to ``P``), known to be closest in its interior:
    ``|X x E|^2 / |E|^2``.

    Returns ``(ok, distance, sqr_distance, x, y, z, t)``: :func:`vertex_distance`'s
    three, then the closest point relative to ``P`` and its parameter along
    ``E``, clamped to ``[0, 1]`` and formed from the nearer end, in float.
    """
    k = cross3(p[0], p[1], p[2], p[3], p[4], p[5], e[0], e[1], e[2], e[3], e[4], e[5])
    nh, nl, dn = norm2_bounded(k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7], k[8])
    mh, ml, dm = sum_sq(e[0], e[1], e[2], e[3], e[4], e[5])
    eh, el, de = ratio(nh, nl, dn, mh, ml, dm)
    ok, r, s = faithful_sqrt(eh, el, de)
    t = -(p[0] * e[0] + p[2] * e[2] + p[4] * e[4]) / max(e[0] * e[0] + e[2] * e[2] + e[4] * e[4], 5e-324)
    t = min(max(t, 0.0), 1.0)
    near_end = t > 0.5
    u = t - 1.0 if near_end else t
    base = 1.0 if near_end else 0.0
    ex = p[0] + base * e[0] + u * e[0]
    ey = p[2] + base * e[2] + u * e[2]
    ez = p[4] + base * e[4] + u * e[4]
    return ok, r, s, ex, ey, ez, t


@inline
def _vertex(a, b, c, feature):
    """The squared distance to the closest vertex, ``|X|^2``.

    ``a, b, c`` are the vertices relative to ``P``, each a double-double
    vector.  Returns ``(ok, distance, sqr_distance, x, y, z, b0, b1, b2)``
    with ``(x, y, z)`` relative to ``P``.
    """
    x = _sel(feature == VERTEX0, a, _sel(feature == VERTEX1, b, c))
    ok, r, s = vertex_distance(x)
    b0 = 1.0 if feature == VERTEX0 else 0.0
    b1 = 1.0 if feature == VERTEX1 else 0.0
    b2 = 1.0 if feature == VERTEX2 else 0.0
    return ok, r, s, x[0], x[2], x[4], b0, b1, b2


@inline
def _edge(a, b, c, e0, e1, e2, feature):
    """:func:`_vertex` for the closest edge, from ``X`` along ``E``: ``|X x E|^2 / |E|^2``.

    ``e0, e1, e2`` are the edges ``V1 - V0``, ``V2 - V0``, ``V2 - V1``.
    """
    on01 = feature == EDGE01
    on12 = feature == EDGE12
    p = _sel(on01, a, _sel(on12, b, c))
    e = _sel(on01, e0, _sel(on12, e2, (-e1[0], -e1[1], -e1[2], -e1[3], -e1[4], -e1[5])))
    ok, r, s, ex, ey, ez, t = edge_distance(p, e)
    b0 = 1.0 - t if on01 else (0.0 if on12 else t)
    b1 = t if on01 else (1.0 - t if on12 else 0.0)
    b2 = 0.0 if on01 else (t if on12 else 1.0 - t)
    return ok, r, s, ex, ey, ez, b0, b1, b2


@inline
def _face(a, b, c, e0, e1, e2):
    """:func:`_vertex` for the face: ``d = |n . A| / |n|`` with ``n = E0 x E1``."""
    n = cross3(e0[0], e0[1], e0[2], e0[3], e0[4], e0[5], e1[0], e1[1], e1[2], e1[3], e1[4], e1[5])
    th, tl, dt = _dot_bounded(n, (n[6], n[7], n[8]), a)
    th2, tl2 = dd.sqr(th, tl)
    dt2 = 2.0 * abs(th) * dt + dt * dt + 8.0 * U * U * abs(th2)
    gh, gl, dg = norm2_bounded(n[0], n[1], n[2], n[3], n[4], n[5], n[6], n[7], n[8])
    fh, fl, df = ratio(th2, tl2, dt2, gh, gl, dg)
    ok, r, s = faithful_sqrt(fh, fl, df)
    fx, fy, fz = cross_accurate(e0[0], e0[2], e0[4], e1[0], e1[2], e1[4])
    q = dot3_accurate(fx, fy, fz, a[0], a[2], a[4]) / max(fx * fx + fy * fy + fz * fz, 5e-324)
    wc = max(edge_function(fx, fy, fz, a[0], a[2], a[4], e0[0], e0[2], e0[4]), 0.0)
    wa = max(edge_function(fx, fy, fz, b[0], b[2], b[4], e2[0], e2[2], e2[4]), 0.0)
    wb = max(-edge_function(fx, fy, fz, c[0], c[2], c[4], e1[0], e1[2], e1[4]), 0.0)
    w = max(wa + wb + wc, 5e-324)
    return ok, r, s, q * fx, q * fy, q * fz, wa / w, wb / w, wc / w


@inline
def _classify_local(a, b, c, e0, e1, e2):
    """:func:`_classify` on the leading parts of the exact differences."""
    return _classify(
        a[0], a[2], a[4], b[0], b[2], b[4], c[0], c[2], c[4],
        e0[0], e0[2], e0[4], e1[0], e1[2], e1[4], e2[0], e2[2], e2[4],
    )  # fmt: skip


@inline
def _kind(feature):
    """0 for a vertex, 1 for an edge, 2 for the face, 3 for NONE (undecided)."""
    if feature == NONE:
        return 3
    if feature <= VERTEX2:
        return 0
    return 2 if feature == FACE else 1


@inline
def differences(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Exact differences for :func:`_vertex`, :func:`_edge` and :func:`_face`, the largest ``|V - P|``,
    and whether all of them are in the safe window (and finite)."""
    a = dd_vec(px, py, pz, v0x, v0y, v0z)
    b = dd_vec(px, py, pz, v1x, v1y, v1z)
    c = dd_vec(px, py, pz, v2x, v2y, v2z)
    e0 = dd_vec(v0x, v0y, v0z, v1x, v1y, v1z)
    e1 = dd_vec(v0x, v0y, v0z, v2x, v2y, v2z)
    e2 = dd_vec(v1x, v1y, v1z, v2x, v2y, v2z)
    m = max(
        max(max(abs(a[0]), abs(a[2])), max(abs(a[4]), abs(b[0]))),
        max(max(abs(b[2]), abs(b[4])), max(max(abs(c[0]), abs(c[2])), abs(c[4]))),
    )
    edges = abs(e0[0]) + abs(e0[2]) + abs(e0[4]) + abs(e1[0]) + abs(e1[2]) + abs(e1[4])
    edges += abs(e2[0]) + abs(e2[2]) + abs(e2[4])
    in_window = (m >= SAFE_MIN) & (m <= SAFE_MAX) & (edges < np.inf)
    return a, b, c, e0, e1, e2, m, in_window


@inline
def settle(ok, d, s, g):
    """``(status, distance, sqr_distance)``: ``d`` and ``s`` unscaled by ``g``,
    and :data:`EXACT` where ``d`` was not faithful or became subnormal or
    infinite (its rounding is then no longer the one that was checked)."""
    d = d * g
    ok = ok & ((d >= 2.2250738585072014e-308) | (d == 0.0)) & (d < np.inf)
    return CERTAIN if ok else EXACT, d, s * g * g


@inline
def finish(r, g, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Unscale by ``g``, make the point absolute (vertices exactly), and
    refuse a distance that became subnormal or infinite."""
    ok, d, s, x, y, z, feature, b0, b1, b2 = r
    status, d, s = settle(ok, d, s, g)
    x, y, z = px + x * g, py + y * g, pz + z * g
    x = v0x if feature == VERTEX0 else (v1x if feature == VERTEX1 else (v2x if feature == VERTEX2 else x))
    y = v0y if feature == VERTEX0 else (v1y if feature == VERTEX1 else (v2y if feature == VERTEX2 else y))
    z = v0z if feature == VERTEX0 else (v1z if feature == VERTEX1 else (v2z if feature == VERTEX2 else z))
    return status, d, s, x, y, z, feature, b0, b1, b2


# The certified block keeps each query's classified feature in the first of
# the pairs' output rows until the results come back; its sorted copy ``w``
# holds the inputs, the feature, the nine results and the status.
Z_FEATURE = PAIR_OUT
W_FEATURE, W_OUT, W_STATUS, W_ROWS = PAIR_P + 3, PAIR_P + 4, PAIR_P + 13, PAIR_P + 14


@inline
def _local_at(w, m):
    """The exact differences of the query in column ``m`` of ``w`` (its rows
    of ``PAIR_V`` and ``PAIR_P``, as :func:`~._loops.gather_triangles`)."""
    a, b, c, e0, e1, e2, _, _ = differences(*triangle_at(w, m))
    return a, b, c, e0, e1, e2


@inline
def _store_at(w, m, part, feature):
    """A :func:`_vertex`-style result, finished, into the rows ``W_OUT`` of
    ``w`` and its status into row ``W_STATUS``."""
    ok, r, s, x, y, z, b0, b1, b2 = part
    res = finish((ok, r, s, x, y, z, feature, b0, b1, b2), 1.0, *triangle_at(w, m))
    store(w, W_OUT, m, res[1:])
    w[W_STATUS, m] = res[0]


@part
def triangle_block(shape, P, n_j, k0, nb, out, exact, full):
    """Certified queries ``k0 .. k0 + nb`` of a batch (see :mod:`proximity.runtime.batch`).

    As ``point_triangle._robust_block``: gathered into local scratch and
    classified by a loop that compiles to SIMD code.  The formula for the
    squared distance differs by feature (vertex, edge or face) and each is
    costly in double-double, so the queries are then sorted by kind, and
    each kind computed by its own SIMD loop rather than all three formulas
    for every query (``docs/performance.md``).  Queries
    that the filter could not certify (outside the safe window, or
    undecided) are redone one by one by :func:`triangle`; ``exact`` flags
    the rows that even it left to the exact fallback.
    """
    z = np.empty((PAIR_ROWS, BLOCK))
    gather_triangles(z, shape.vertices, P, n_j, k0, nb)
    kinds = np.empty(BLOCK)
    for q in range(BLOCK):
        a, b, c, e0, e1, e2, _, ok = differences(*triangle_at(z, q))
        f = _classify_local(a, b, c, e0, e1, e2)
        z[Z_FEATURE, q] = f
        kinds[q] = _kind(f) if ok else 3
    # Columns of w in kind order: vertices, edges, then faces.  The counts
    # are scalars: read from an array, the loops' bounds would be reloaded
    # after every store, and the loops would not compile to SIMD code.
    n_vertex = 0
    n_edge = 0
    n_face = 0
    for q in range(nb):
        z[PAIR_OK, q] = 0.0
        k = kinds[q]
        n_vertex += k == 0.0
        n_edge += k == 1.0
        n_face += k == 2.0
    order = np.empty(BLOCK, np.int64)
    i_vertex, i_edge, i_face = 0, n_vertex, n_vertex + n_edge
    for q in range(nb):
        k = kinds[q]
        if k == 0.0:
            order[i_vertex] = q
            i_vertex += 1
        elif k == 1.0:
            order[i_edge] = q
            i_edge += 1
        elif k == 2.0:
            order[i_face] = q
            i_face += 1
    n = n_vertex + n_edge + n_face
    w = np.empty((W_ROWS, BLOCK))
    for m in range(n):
        q = order[m]
        for row in range(PAIR_P + 3):
            w[row, m] = z[row, q]
        w[W_FEATURE, m] = z[Z_FEATURE, q]
    # Each kind's loop indexes with an unsigned column, which the compiler
    # knows to be non-negative: with a signed one offset by a run-time start,
    # the index's wrap-around test keeps the loop from compiling to SIMD code.
    for k in range(n_vertex):
        m = uint64(k)
        a, b, c, _, _, _ = _local_at(w, m)
        _store_at(w, m, _vertex(a, b, c, w[W_FEATURE, m]), w[W_FEATURE, m])
    for k in range(n_edge):
        m = uint64(n_vertex + k)
        a, b, c, e0, e1, e2 = _local_at(w, m)
        _store_at(w, m, _edge(a, b, c, e0, e1, e2, w[W_FEATURE, m]), w[W_FEATURE, m])
    for k in range(n_face):
        m = uint64(n_vertex + n_edge + k)
        a, b, c, e0, e1, e2 = _local_at(w, m)
        _store_at(w, m, _face(a, b, c, e0, e1, e2), w[W_FEATURE, m])
    for m in range(n):
        q = order[m]
        for row in range(9):
            z[PAIR_OUT + row, q] = w[W_OUT + row, m]
        z[PAIR_OK, q] = w[W_STATUS, m] == CERTAIN
    for q in range(nb):
        if z[PAIR_OK, q] != 0.0:
            continue
        v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz = triangle_at(z, q)
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            res = triangle(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
            exact[k0 + q] = res[0] != CERTAIN
            store(z, PAIR_OUT, q, res[1:])
        else:
            nan = math.nan
            store(z, PAIR_OUT, q, (nan, nan, nan, nan, nan, float(NONE), nan, nan, nan))
    scatter_triangles(z, PAIR_OUT, k0, nb, out, full)


@part
def triangle(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Certified point-triangle query for any finite input, or a request for
    the exact fallback.

    Returns ``(status, distance, sqr_distance, x, y, z, feature, b0, b1, b2)``
    with ``status`` :data:`CERTAIN` or :data:`EXACT` (the other values are then
    meaningless).
    """
    nan = math.nan
    fail = (EXACT, nan, nan, nan, nan, nan, NONE, nan, nan, nan)
    a, b, c, e0, e1, e2, m, _ = differences(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
    edges = abs(e0[0]) + abs(e0[2]) + abs(e0[4]) + abs(e1[0]) + abs(e1[2]) + abs(e1[4])
    if not (m < np.inf and edges + abs(e2[0]) + abs(e2[2]) + abs(e2[4]) < np.inf):
        return fail  # a difference of two finite coordinates overflowed
    if m == 0.0:
        return CERTAIN, 0.0, 0.0, v0x, v0y, v0z, VERTEX0, 1.0, 0.0, 0.0
    g = 1.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        a, o1 = scale_vec(a, f1, f2)
        b, o2 = scale_vec(b, f1, f2)
        c, o3 = scale_vec(c, f1, f2)
        e0, o4 = scale_vec(e0, f1, f2)
        e1, o5 = scale_vec(e1, f1, f2)
        e2, o6 = scale_vec(e2, f1, f2)
        if not (o1 & o2 & o3 & o4 & o5 & o6):
            return fail
        g = (1.0 / f1) * (1.0 / f2)
        if not g < np.inf:
            return fail
    code = _classify_local(a, b, c, e0, e1, e2)
    kind = _kind(code)
    if kind == 3:
        return fail
    # The feature as a float, as the block loops keep it: the helpers then
    # compile once for both.
    feature = float(code)
    if kind == 0:
        part = _vertex(a, b, c, feature)
    elif kind == 1:
        part = _edge(a, b, c, e0, e1, e2, feature)
    else:
        part = _face(a, b, c, e0, e1, e2)
    ok, d, s, x, y, z, b0, b1, b2 = part
    r = (ok, d, s, x, y, z, feature, b0, b1, b2)
    r = finish(r, g, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
    return r if r[0] == CERTAIN else fail
