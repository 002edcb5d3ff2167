"""Distance between a point and a triangle.

Implements D. Eberly, *Distance Between Point and Triangle in 3D* (Geometric
Tools, 1999, rev. 2017), in the document's notation: the triangle is
``T(s, t) = B + s E0 + t E1`` over ``s, t >= 0, s + t <= 1``, and the squared
distance is ``Q(s, t) = a s^2 + 2 b s t + c t^2 + 2 d s + 2 e t + f``.

Two methods:

``eberly``
    Section 3 as written: the region classification of Listing 1 and the
    region blocks of Listings 2-8, with the division deferred and performed at
    most once.  It is the baseline.  Its failures are kept, not patched: it
    returns NaN for every zero-area triangle (``det == 0`` in region 0 divides
    zero by zero), and near slivers ``det = ac - b^2`` cancels, so regions are
    misclassified and ``s, t`` can be off by the whole triangle.

``robust``
    The same minimisation, organised so that every quantity that decides the
    answer is computed from local difference vectors with a known error:

    * Vertices are taken relative to the query point (``a = V0 - P`` ...), so
      the distance never comes from subtracting two large absolute points.
      The rounding of these differences moves each vertex by at most
      ``eps/2 * S``, and distance to a triangle is 1-Lipschitz in its
      vertices, so it costs at most ``eps/2 * S`` in the distance.
    * When the largest difference lies outside ``[2^-64, 2^64]`` all
      differences are scaled by a power of two, so squared and fourth-power
      terms neither overflow nor underflow (coordinates from 1e-300 to 1e300).
    * The normal ``n = E0 x E1`` is computed with Kahan's difference of
      products, so it is accurate to about one ulp per component even for a
      sliver, where the naive cross product has no correct digits.  An exactly
      collinear triangle gives ``n == 0`` exactly.
    * The face is a candidate when the projection of ``P`` lies strictly
      inside all three edges.  Each edge test ``n . (V x E)`` is evaluated
      from a vertex of that edge, so its error, measured as a distance in the
      plane, is a few ``eps * S`` however thin the triangle is; a wrong
      decision therefore costs at most that much.  The face distance is then
      ``|n . a| / |n|``, with ``n . a`` as a compensated dot product.
    * The scaling above bounds the differences ``a, b, c``, not the edges,
      and ``|n|^2`` is a fourth power of the edges: for a triangle about
      ``2^-250`` times its distance from ``P`` or smaller, or a sliver
      ``2^-500`` times as wide as that distance, it falls towards the
      subnormal range, where it and the edge tests lose bits.  The face is a
      candidate only where ``|n|^2 >= 2^-1000`` (:data:`NN_MIN`), so every
      product of the face test that matters is a normal float.  Below, the
      triangle is too thin for the face to matter: its inradius is at most
      ``sqrt(|n|)``, below ``2^-250``, while ``S >= 2^-64`` where the test
      runs, so the nearest edge is as near as the face within ``2^-186 S``.
    * Otherwise the minimum is over the three edges, each a clamped
      projection that never divides by zero (the segment's,
      :func:`.segment.project`): a degenerate triangle (collinear,
      or with coincident vertices) is handled as the segments or the point
      it is, with no special case.

    The result satisfies ``|d - d*| <= 8 eps S + 2^-1075`` with
    ``S = max_i |P - V_i|`` for every finite input (the absolute term is the
    rounding of a subnormal distance); ``tests/`` checks this against exact
    rational arithmetic on adversarial families and at both ends of the
    float range.

Both methods are dimension-free in the document; here 2D triangles are
embedded in the ``z = 0`` plane, which changes no distance.
"""

import functools
import math
import sys

import numpy as np

from ..features import EDGE01, EDGE12, EDGE20, FACE, NONE, VERTEX0, VERTEX1, VERTEX2
from ..methods import CERTIFIED
from ..numerics import certified
from ..numerics import exact as _exact
from ..numerics.fp import (
    EPS,
    SAFE_MAX,
    SAFE_MIN,
    TINY,
    UNSCALED,
    cross_accurate,
    dot3_accurate,
    edge_function,
    pow2_scale,
    unscale,
)
from ..primitives import LANES
from ..runtime.batch import Layout, run
from ..runtime.jit import inline, kernel, part, specialize
from ..runtime.loops import (
    BLOCK,
    ONE_OK,
    ONE_OUT,
    ONE_P,
    ONE_ROWS,
    PAIR_OK,
    PAIR_OUT,
    PAIR_P,
    PAIR_ROWS,
    PAIR_V,
    gather_points,
    gather_triangles,
    point_at,
    scatter_triangles,
    store,
    triangle_at,
)
from .segment import project

# The least square of the normal with which the face is a candidate (see the
# module docstring): above it no term of the face test that matters is
# subnormal; below it the triangle is thinner than its rounding.
NN_MIN = 2.0**-1000

# The feature codes as floats, for the SIMD loops, which keep them in float rows.
F_NONE, F_FACE = float(NONE), float(FACE)
F_VERTEX0, F_VERTEX1, F_VERTEX2 = float(VERTEX0), float(VERTEX1), float(VERTEX2)
F_EDGE01, F_EDGE12, F_EDGE20 = float(EDGE01), float(EDGE12), float(EDGE20)


@kernel()
def eberly(bx, by, bz, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz):
    """Listings 1-8 of Eberly's document, for ``T(s, t) = B + s E0 + t E1``.

    Returns ``(s, t, feature)``; the caller forms the closest point.
    """
    dx = bx - px
    dy = by - py
    dz = bz - pz
    a = e0x * e0x + e0y * e0y + e0z * e0z
    b = e0x * e1x + e0y * e1y + e0z * e1z
    c = e1x * e1x + e1y * e1y + e1z * e1z
    d = e0x * dx + e0y * dy + e0z * dz
    e = e1x * dx + e1y * dy + e1z * dz
    det = abs(a * c - b * b)
    s = b * e - c * d
    t = b * d - a * e

    if s + t <= det:
        if s < 0.0:
            if t < 0.0:
                # region 4 (Listing 8)
                if d < 0.0:
                    t = 0.0
                    if -d >= a:
                        s = 1.0
                    else:
                        s = -d / a
                else:
                    s = 0.0
                    if e >= 0.0:
                        t = 0.0
                    elif -e >= c:
                        t = 1.0
                    else:
                        t = -e / c
            else:
                # region 3 (Listing 4)
                s = 0.0
                if e >= 0.0:
                    t = 0.0
                elif -e >= c:
                    t = 1.0
                else:
                    t = -e / c
        elif t < 0.0:
            # region 5 (Listing 5)
            t = 0.0
            if d >= 0.0:
                s = 0.0
            elif -d >= a:
                s = 1.0
            else:
                s = -d / a
        else:
            # region 0 (Listing 2)
            s /= det
            t /= det
            return s, t, FACE
    else:
        if s < 0.0:
            # region 2 (Listing 6)
            tmp0 = b + d
            tmp1 = c + e
            if tmp1 > tmp0:
                numer = tmp1 - tmp0
                denom = a - 2.0 * b + c
                if numer >= denom:
                    s = 1.0
                else:
                    s = numer / denom
                t = 1.0 - s
            else:
                s = 0.0
                if tmp1 <= 0.0:
                    t = 1.0
                elif e >= 0.0:
                    t = 0.0
                else:
                    t = -e / c
        elif t < 0.0:
            # region 6 (Listing 7)
            tmp0 = b + e
            tmp1 = a + d
            if tmp1 > tmp0:
                numer = tmp1 - tmp0
                denom = a - 2.0 * b + c
                if numer >= denom:
                    t = 1.0
                else:
                    t = numer / denom
                s = 1.0 - t
            else:
                t = 0.0
                if tmp1 <= 0.0:
                    s = 1.0
                elif d >= 0.0:
                    s = 0.0
                else:
                    s = -d / a
        else:
            # region 1 (Listing 3)
            numer = (c + e) - (b + d)
            if numer <= 0.0:
                s = 0.0
            else:
                denom = a - 2.0 * b + c
                if numer >= denom:
                    s = 1.0
                else:
                    s = numer / denom
            t = 1.0 - s
    return s, t, _boundary_feature(s, t)


@inline
def eberly_select(bx, by, bz, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz):
    """:func:`eberly` with its branches turned into selects, for SIMD loops.

    Every listing's arithmetic is kept operation for operation: the same
    predicates pick the region and the clamps, and the value that a listing
    divides is divided here with the same operands.  Only the order of
    evaluation differs (each region's candidates are computed, one is kept),
    so the results are bit-identical to :func:`eberly`; ``tests/`` checks
    that.  The feature is returned as a float code (the
    :class:`~proximity.Feature` value).

    The choice is written as nested selects, each on one comparison, as the
    listings' nested ifs: region masks combined with ``&`` and ``|`` compile
    to a loop that spends much of its time converting comparison masks
    (``docs/performance.md``).

    It is :func:`eberly_terms` followed by :func:`eberly_choice`, which the
    loop over many triangles runs as separate passes.
    """
    a, b, c, d, e = eberly_terms(bx, by, bz, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz)
    return eberly_choice(a, b, c, d, e)


@inline
def eberly_terms(bx, by, bz, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz):
    """The quadratic's coefficients ``a, b, c, d, e`` (Listing 1)."""
    dx = bx - px
    dy = by - py
    dz = bz - pz
    a = e0x * e0x + e0y * e0y + e0z * e0z
    b = e0x * e1x + e0y * e1y + e0z * e1z
    c = e1x * e1x + e1y * e1y + e1z * e1z
    d = e0x * dx + e0y * dy + e0z * dz
    e = e1x * dx + e1y * dy + e1z * dz
    return a, b, c, d, e


@inline
def eberly_choice(a, b, c, d, e):
    """The region, the clamps and the feature of :func:`eberly_select`,
    from the coefficients: ``(s, t, feature code)``."""
    det = abs(a * c - b * b)
    s = b * e - c * d
    t = b * d - a * e

    # Listing 1's tests: the regions are
    #   inner: 0 (s, t >= 0), 3 (s < 0 <= t), 4 (s, t < 0), 5 (t < 0 <= s);
    #   outer: 2 (s < 0), 6 (t < 0 <= s), 1 (s, t >= 0).
    inner = s + t <= det
    s_neg = s < 0.0
    t_neg = t < 0.0
    # The tests inside the region blocks (Listings 3-8).
    s_side = c + e > b + d  # region 2: the minimum is on s + t = 1
    t_side = a + d > b + e  # region 6: the minimum is on s + t = 1
    d_neg = d < 0.0  # region 4: the minimum is on t = 0

    denom = a - 2.0 * b + c
    numer_s = (c + e) - (b + d)  # Listings 3 and 6: s on the edge s + t = 1
    numer_t = (a + d) - (b + e)  # Listing 7: t on the edge s + t = 1
    # The one division of the boundary cases, with the listing's operands:
    # -e / c on s = 0, -d / a on t = 0, numer_s or numer_t / denom on s + t = 1.
    if inner:
        if s_neg:
            numer = (-d if d_neg else -e) if t_neg else -e
            denom_q = (a if d_neg else c) if t_neg else c
        else:
            numer = -d
            denom_q = a
    elif s_neg:
        numer = numer_s if s_side else -e
        denom_q = denom if s_side else c
    elif t_neg:
        numer = numer_t if t_side else -d
        denom_q = denom if t_side else a
    else:
        numer = numer_s
        denom_q = denom
    quotient = numer / denom_q

    # Each region's clamped parameter, as its listing computes it.
    s_0 = s / det
    t_0 = t / det
    s_1 = 0.0 if numer_s <= 0.0 else (1.0 if numer_s >= denom else quotient)
    s_2 = 1.0 if numer_s >= denom else quotient  # region 2, s + t = 1
    t_2 = 1.0 if c + e <= 0.0 else (0.0 if e >= 0.0 else quotient)  # region 2, s = 0
    t_3 = 0.0 if e >= 0.0 else (1.0 if -e >= c else quotient)  # regions 3 and 4, s = 0
    s_4 = 1.0 if -d >= a else quotient  # region 4, t = 0
    s_5 = 0.0 if d >= 0.0 else (1.0 if -d >= a else quotient)
    t_6 = 1.0 if numer_t >= denom else quotient  # region 6, s + t = 1
    s_6 = 1.0 if a + d <= 0.0 else (0.0 if d >= 0.0 else quotient)  # region 6, t = 0
    if inner:
        if s_neg:
            s_out = (s_4 if d_neg else 0.0) if t_neg else 0.0
            t_out = (0.0 if d_neg else t_3) if t_neg else t_3
        else:
            s_out = s_5 if t_neg else s_0
            t_out = 0.0 if t_neg else t_0
    elif s_neg:
        s_out = s_2 if s_side else 0.0
        t_out = (1.0 - s_2) if s_side else t_2
    elif t_neg:
        s_out = (1.0 - t_6) if t_side else s_6
        t_out = t_6 if t_side else 0.0
    else:
        s_out = s_1
        t_out = 1.0 - s_1

    # The feature: the face in region 0, else the edge of the domain that
    # (s, t) ended on, or the vertex where the clamp put it.
    f = F_EDGE12
    f = (F_VERTEX1 if s_out == 1.0 else F_EDGE01) if t_out == 0.0 else f
    f = (F_VERTEX0 if t_out == 0.0 else (F_VERTEX2 if t_out == 1.0 else F_EDGE20)) if s_out == 0.0 else f
    f = F_NONE if (s_out != s_out) | (t_out != t_out) else f
    f = (f if (s_neg | t_neg) else F_FACE) if inner else f
    return s_out, t_out, f


@inline
def _boundary_feature(s, t):
    # The listings leave (s, t) on an edge of the domain; name that edge, or
    # the vertex where the clamp put it.
    if s != s or t != t:
        return NONE
    if s == 0.0:
        if t == 0.0:
            return VERTEX0
        if t == 1.0:
            return VERTEX2
        return EDGE20
    if t == 0.0:
        return VERTEX1 if s == 1.0 else EDGE01
    return EDGE12


@inline
def _robust_local(ax, ay, az, bx, by, bz, cx, cy, cz):
    """The robust minimisation on vertices relative to ``P``, in the safe window.

    Returns ``(distance, sqr_distance, x, y, z, feature, b0, b1, b2)`` with
    ``(x, y, z)`` relative to ``P``.  Every candidate (face and three edges)
    is evaluated and the answer selected without branches, so the loop that
    calls this compiles to SIMD code.
    """
    e0x, e0y, e0z = bx - ax, by - ay, bz - az
    e1x, e1y, e1z = cx - ax, cy - ay, cz - az
    e2x, e2y, e2z = cx - bx, cy - by, cz - bz

    # Face: the projection of P is inside when all three edge functions are
    # positive, which needs a normal whose square is not near underflow.
    nx, ny, nz = cross_accurate(e0x, e0y, e0z, e1x, e1y, e1z)
    nn = nx * nx + ny * ny + nz * nz
    wc = edge_function(nx, ny, nz, ax, ay, az, e0x, e0y, e0z)
    wa = edge_function(nx, ny, nz, bx, by, bz, e2x, e2y, e2z)
    wb = -edge_function(nx, ny, nz, cx, cy, cz, e1x, e1y, e1z)
    inside = (wa > 0.0) & (wb > 0.0) & (wc > 0.0) & (nn >= NN_MIN)
    na = dot3_accurate(nx, ny, nz, ax, ay, az)
    nn_safe = max(nn, TINY)
    k = na / nn_safe
    face_dist = abs(na) / math.sqrt(nn_safe)
    w = max(wa + wb + wc, TINY)

    # Edges V0V1, V1V2, V2V0; ties go to the earlier edge.
    d1, x1, y1, z1, t1 = project(ax, ay, az, e0x, e0y, e0z, bx, by, bz)
    d2, x2, y2, z2, t2 = project(bx, by, bz, e2x, e2y, e2z, cx, cy, cz)
    d3, x3, y3, z3, t3 = project(cx, cy, cz, -e1x, -e1y, -e1z, ax, ay, az)
    on2 = d2 < d1
    best = d2 if on2 else d1
    on3 = d3 < best
    best = d3 if on3 else best
    on1 = not (on2 | on3)
    on2 = on2 & (not on3)

    if inside:
        return face_dist, face_dist * face_dist, k * nx, k * ny, k * nz, FACE, wa / w, wb / w, wc / w
    t = t1 if on1 else (t2 if on2 else t3)
    feature = EDGE01 if on1 else (EDGE12 if on2 else EDGE20)
    start = VERTEX0 if on1 else (VERTEX1 if on2 else VERTEX2)
    end = VERTEX1 if on1 else (VERTEX2 if on2 else VERTEX0)
    feature = start if t == 0.0 else (end if t == 1.0 else feature)
    b0 = 1.0 - t1 if on1 else (0.0 if on2 else t3)
    b1 = t1 if on1 else (1.0 - t2 if on2 else 0.0)
    b2 = 0.0 if on1 else (t2 if on2 else 1.0 - t3)
    x = x1 if on1 else (x2 if on2 else x3)
    y = y1 if on1 else (y2 if on2 else y3)
    z = z1 if on1 else (z2 if on2 else z3)
    return math.sqrt(best), best, x, y, z, feature, b0, b1, b2


@inline
def _finish(r, g, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Undo the scaling ``g`` and make the closest point absolute.

    A vertex is reported exactly, not as ``P + (V - P)``.
    """
    dist, sqr, x, y, z, feature, b0, b1, b2 = r
    x = px + unscale(x, g)
    y = py + unscale(y, g)
    z = pz + unscale(z, g)
    if feature == VERTEX0:
        x, y, z = v0x, v0y, v0z
    if feature == VERTEX1:
        x, y, z = v1x, v1y, v1z
    if feature == VERTEX2:
        x, y, z = v2x, v2y, v2z
    return unscale(dist, g), unscale(unscale(sqr, g), g), x, y, z, feature, b0, b1, b2


@inline
def _window(ax, ay, az, bx, by, bz, cx, cy, cz):
    """Largest difference, and whether it is inside the safe window."""
    m = max(
        max(max(abs(ax), abs(ay)), max(abs(az), abs(bx))),
        max(max(abs(by), abs(bz)), max(max(abs(cx), abs(cy)), abs(cz))),
    )
    return m, (m >= SAFE_MIN) & (m <= SAFE_MAX)


@inline
def robust(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Robust point-triangle query for any finite input; see the module docstring.

    Inlined into every caller: compiled as a function of its own, a mesh
    search compiled after a batch query in the same process linked the
    batch's copy, which made it slower, and the disk cache kept it.

    Returns ``(distance, sqr_distance, x, y, z, feature, b0, b1, b2)`` where
    ``(x, y, z)`` is the closest point and ``b*`` are its barycentric
    coordinates.
    """
    ax, ay, az = v0x - px, v0y - py, v0z - pz
    bx, by, bz = v1x - px, v1y - py, v1z - pz
    cx, cy, cz = v2x - px, v2y - py, v2z - pz
    m, _ = _window(ax, ay, az, bx, by, bz, cx, cy, cz)
    g = UNSCALED  # undoes the scaling of the differences
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        q = 0.25
        ax, ay, az = v0x * q - px * q, v0y * q - py * q, v0z * q - pz * q
        bx, by, bz = v1x * q - px * q, v1y * q - py * q, v1z * q - pz * q
        cx, cy, cz = v2x * q - px * q, v2y * q - py * q, v2z * q - pz * q
        m, _ = _window(ax, ay, az, bx, by, bz, cx, cy, cz)
        g = (4.0, 4.0, 1.0)
    if m == 0.0:
        return 0.0, 0.0, v0x, v0y, v0z, VERTEX0, 1.0, 0.0, 0.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        ax, ay, az = ax * f1 * f2, ay * f1 * f2, az * f1 * f2
        bx, by, bz = bx * f1 * f2, by * f1 * f2, bz * f1 * f2
        cx, cy, cz = cx * f1 * f2, cy * f1 * f2, cz * f1 * f2
        g = (g[0] / f1 / f2, g[1] / f1, 1.0 / f2)
    r = _robust_local(ax, ay, az, bx, by, bz, cx, cy, cz)
    return _finish(r, g, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)


@inline
def _eberly_query(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Eberly's algorithm with the closest point and distance formed as in his document."""
    e0x, e0y, e0z = v1x - v0x, v1y - v0y, v1z - v0z
    e1x, e1y, e1z = v2x - v0x, v2y - v0y, v2z - v0z
    s, t, feature = eberly_select(v0x, v0y, v0z, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz)
    return _eberly_point(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz, s, t, feature)


@inline
def _eberly_point(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz, s, t, feature):
    """The result row of :func:`_eberly_query`, given the parameters ``s, t``."""
    e0x, e0y, e0z = v1x - v0x, v1y - v0y, v1z - v0z
    e1x, e1y, e1z = v2x - v0x, v2y - v0y, v2z - v0z
    x = v0x + s * e0x + t * e1x
    y = v0y + s * e0y + t * e1y
    z = v0z + s * e0z + t * e1z
    sqr = (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2
    return math.sqrt(sqr), sqr, x, y, z, feature, 1.0 - s - t, s, t


@inline
def robust_query(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """:func:`robust` with the leading status of the per-method queries (always certain)."""
    d, sqr, x, y, z, f, b0, b1, b2 = robust(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
    return certified.CERTAIN, d, sqr, x, y, z, f, b0, b1, b2


@inline
def eberly_query(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """:func:`_eberly_query` with the leading status of the per-method queries."""
    d, sqr, x, y, z, f, b0, b1, b2 = _eberly_query(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
    return certified.CERTAIN, d, sqr, x, y, z, int(f), b0, b1, b2


# Bound per method by :func:`proximity.runtime.jit.specialize`: the query of one point.
QUERY = None


def _single(out, v, p):
    """One query, written to ``out[:9]``: the fast path for one point and one shape.

    ``v`` holds the nine vertex coordinates and ``p`` the point; ``out[9]``
    is the status, non-zero where the certified method needs its exact
    fallback.
    """
    px, py, pz = p[0], p[1], p[2]
    if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
        out[:] = math.nan
        out[5] = NONE
        out[9] = 0.0
    else:
        out[9], out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8] = QUERY(
            v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], px, py, pz
        )


def exact_row(row, vertices, point):
    """Redo a fast-path row with the certified method's exact fallback."""
    row[:9] = _exact.triangle(vertices.reshape(3, 3), point)
    row[9] = 0.0


_NAN_ROW = (math.nan, math.nan, math.nan, math.nan, math.nan, NONE, math.nan, math.nan, math.nan)


@inline
def _robust_lanes(z, width, n):
    """Robust queries of columns ``0 .. width - 1`` of the scratch ``z`` (the
    rows of ``PAIR_*``), computed by a loop that compiles to SIMD code (with,
    in row ``PAIR_OK``, whether the query was in the safe window), then those
    of the first ``n`` that were not redone one by one on the scalar path."""
    for q in range(width):
        v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz = triangle_at(z, q)
        ax, ay, az = v0x - px, v0y - py, v0z - pz
        bx, by, bz = v1x - px, v1y - py, v1z - pz
        cx, cy, cz = v2x - px, v2y - py, v2z - pz
        _, ok = _window(ax, ay, az, bx, by, bz, cx, cy, cz)
        res = _finish(
            _robust_local(ax, ay, az, bx, by, bz, cx, cy, cz),
            UNSCALED, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz,
        )  # fmt: skip
        store(z, PAIR_OUT, q, res)
        z[PAIR_OK, q] = ok
    for q in range(n):
        if z[PAIR_OK, q] != 0.0:
            continue
        v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz = triangle_at(z, q)
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            res = robust(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
            store(z, PAIR_OUT, q, res)
        else:
            store(z, PAIR_OUT, q, _NAN_ROW)


@part
def _robust_block(shape, P, n_j, k0, nb, out, exact, full):
    """Robust queries ``k0 .. k0 + nb`` of :func:`_batch`: gathered into local
    scratch, answered by :func:`_robust_lanes`, and scattered to the outputs."""
    z = np.empty((PAIR_ROWS, BLOCK))
    gather_triangles(z, shape.vertices, P, n_j, k0, nb)
    _robust_lanes(z, BLOCK, nb)
    scatter_triangles(z, PAIR_OUT, k0, nb, out, full)


# Eberly's algorithm on pairs keeps the coefficients, then the choice of
# ``s, t`` and the feature, in the output rows until the results replace them.
_TERMS = PAIR_OUT
_CHOICE = PAIR_OUT + 5


@part
def _eberly_block(shape, P, n_j, k0, nb, out, exact, full):
    """:func:`_robust_block` for Eberly's algorithm: rows with a non-finite
    point are the only ones it leaves, and get NaN.

    The query runs in three passes over the block: the coefficients (rows
    ``_TERMS``), the choice of ``s, t`` and the feature (rows ``_CHOICE``),
    and the result row.  As one pass, the loop keeps more values live than
    there are registers; the passes do the same operations with fewer moves
    to the stack (``docs/performance.md``).
    """
    z = np.empty((PAIR_ROWS, BLOCK))
    gather_triangles(z, shape.vertices, P, n_j, k0, nb)
    for q in range(BLOCK):
        v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz = triangle_at(z, q)
        e0x, e0y, e0z = v1x - v0x, v1y - v0y, v1z - v0z
        e1x, e1y, e1z = v2x - v0x, v2y - v0y, v2z - v0z
        terms = eberly_terms(v0x, v0y, v0z, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz)
        z[_TERMS, q], z[_TERMS + 1, q], z[_TERMS + 2, q], z[_TERMS + 3, q], z[_TERMS + 4, q] = terms
    for q in range(BLOCK):
        a, b, c = z[_TERMS, q], z[_TERMS + 1, q], z[_TERMS + 2, q]
        z[_CHOICE, q], z[_CHOICE + 1, q], z[_CHOICE + 2, q] = eberly_choice(
            a, b, c, z[_TERMS + 3, q], z[_TERMS + 4, q]
        )
    for q in range(BLOCK):
        v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz = triangle_at(z, q)
        res = _eberly_point(
            v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz,
            z[_CHOICE, q], z[_CHOICE + 1, q], z[_CHOICE + 2, q],
        )  # fmt: skip
        store(z, PAIR_OUT, q, res)
        z[PAIR_OK, q] = math.isfinite(px) & math.isfinite(py) & math.isfinite(pz)
    for q in range(nb):
        if z[PAIR_OK, q] == 0.0:
            store(z, PAIR_OUT, q, _NAN_ROW)
    scatter_triangles(z, PAIR_OUT, k0, nb, out, full)


@part
def _eberly_block_one(shape, P, n_j, k0, nb, out, exact, full):
    """:func:`_eberly_block` for a batch against one triangle, ``V[0, 0]``.

    Only the points are gathered (the rows of ``ONE_*``).  The loop reads
    the vertices as scalars, so the compiler computes the triangle's own
    terms (its edges, ``a``, ``b``, ``c`` and ``det``) once per block instead
    of once per query.
    """
    z = np.empty((ONE_ROWS, BLOCK))
    gather_points(z, ONE_P, P, n_j, k0, nb)
    v = shape.vertices[0, 0]
    v0x, v0y, v0z, v1x, v1y, v1z = v[0, 0], v[0, 1], v[0, 2], v[1, 0], v[1, 1], v[1, 2]
    v2x, v2y, v2z = v[2, 0], v[2, 1], v[2, 2]
    for q in range(BLOCK):
        px, py, pz = point_at(z, ONE_P, q)
        res = _eberly_query(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)
        store(z, ONE_OUT, q, res)
        z[ONE_OK, q] = math.isfinite(px) & math.isfinite(py) & math.isfinite(pz)
    for q in range(nb):
        if z[ONE_OK, q] == 0.0:
            store(z, ONE_OUT, q, _NAN_ROW)
    scatter_triangles(z, ONE_OUT, k0, nb, out, full)


# Per method: the query of one point, and the block functions of the batch
# loop for pairs and for many points against one triangle.
KERNELS = {
    "robust": (robust_query, _robust_block, _robust_block),
    "certified": (certified.triangle, certified.triangle_block, certified.triangle_block),
    "eberly": (eberly_query, _eberly_block, _eberly_block_one),
}

#: The arrays of a batch query: the vertices, and the barycentrics of the answers.
LAYOUT = Layout("triangle", flags=(), arrays=(("vertices", 2),), extra=(("barycentric", np.float64, 3),))


def single_kernel(method):
    """The one-query kernel of ``method`` (a :class:`~proximity.methods.Method`), compiled
    for :data:`~proximity.runtime.loops.SINGLE_ARGS` by :func:`~proximity.runtime.loops.single_entry`."""
    return specialize(_single, method.name, QUERY=KERNELS[method.name][0])


# The query of a stored row of a collection (see :mod:`proximity.primitives`),
# bound per method, and how the row's vertices are read, bound per layout.
ROW_QUERY = CORNERS = None


@inline
def _row_corners(q, k):
    """The vertices V0, V1, V2 of stored row ``k`` of rows ``q``: its first nine columns."""
    return q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], q[k, 6], q[k, 7], q[k, 8]


@inline
def _indexed_corners(q, k):
    """The vertices V0, V1, V2 of stored face ``k`` of ``q = (vertices, faces)``:
    the rows ``faces[k]`` of ``vertices`` (a tree of faces, :class:`~.broadphase.tree.Tree`).
    The same coordinates as the face's row would hold, so the same answers."""
    vertices, faces = q
    i, j, m = faces[k, 0], faces[k, 1], faces[k, 2]
    return (
        vertices[i, 0], vertices[i, 1], vertices[i, 2], vertices[j, 0], vertices[j, 1], vertices[j, 2],
        vertices[m, 0], vertices[m, 1], vertices[m, 2],
    )  # fmt: skip


def _row(kind, q, k, px, py, pz):
    """Stored row ``k`` of ``q``: the vertices V0, V1, V2."""
    x0, y0, z0, x1, y1, z1, x2, y2, z2 = CORNERS(q, k)
    st, d, sqr, x, y, z, f, b0, b1, b2 = ROW_QUERY(x0, y0, z0, x1, y1, z1, x2, y2, z2, px, py, pz)
    return st, d, sqr, x, y, z, f, b0, b1, b2, False


def _robust_rows(q, ks, n, px, py, pz, z):
    """Stored rows ``ks[:n]`` of ``q`` and ``P`` by :func:`_robust_lanes` (the last
    row again beyond ``n``): ``row_batch``, see :mod:`proximity.primitives`."""
    for j in range(LANES):
        x0, y0, z0, x1, y1, z1, x2, y2, z2 = CORNERS(q, ks[min(j, n - 1)])
        v = PAIR_V
        z[v, j], z[v + 1, j], z[v + 2, j], z[v + 3, j], z[v + 4, j], z[v + 5, j] = x0, y0, z0, x1, y1, z1
        z[v + 6, j], z[v + 7, j], z[v + 8, j] = x2, y2, z2
        z[PAIR_P, j], z[PAIR_P + 1, j], z[PAIR_P + 2, j] = px, py, pz
    _robust_lanes(z, LANES, n)


def row_batch(primitive, method, indexed=False):
    """:func:`_robust_rows` for ``robust`` (None for the other methods)."""
    if method.name == "robust":
        tag = "indexed" if indexed else "rows"
        return specialize(_robust_rows, tag, role="inline", CORNERS=_corners(indexed))


def _corners(indexed):
    return _indexed_corners if indexed else _row_corners


def row_query(primitive, method, indexed=False):
    """The query of a stored triangle row by ``method`` (see :mod:`proximity.primitives`);
    ``indexed``: of a face of a tree that reads its faces through their vertices."""
    tag = method.name + ("_indexed" if indexed else "")
    return specialize(_row, tag, role="inline", ROW_QUERY=KERNELS[method.name][0], CORNERS=_corners(indexed))


def _interval(kind, q, k, px, py, pz):
    """Bounds ``(lo, hi)`` on the certified distance of stored row ``k``
    from the robust one: within ``8 eps S`` and one ulp of the exact one,
    below ``2 eps S``, with ``S`` at most ``1.75`` times the largest
    coordinate difference (``sqrt(3)`` and rounding)."""
    x0, y0, z0, x1, y1, z1, x2, y2, z2 = CORNERS(q, k)
    d = robust(x0, y0, z0, x1, y1, z1, x2, y2, z2, px, py, pz)[0]
    m = max(max(abs(x0 - px), abs(y0 - py)), abs(z0 - pz))
    m = max(m, max(max(abs(x1 - px), abs(y1 - py)), abs(z1 - pz)))
    m = max(m, max(max(abs(x2 - px), abs(y2 - py)), abs(z2 - pz)))
    w = 16.0 * EPS * (1.75 * m) + 5e-324  # the bound's absolute term, for subnormal distances
    return d - w, d + w


def row_interval(primitive, indexed=False):
    """:func:`_interval`, the bounds of a stored triangle row's certified distance."""
    tag = "indexed" if indexed else "rows"
    return specialize(_interval, tag, role="inline", CORNERS=_corners(indexed))


def resolve(code, params, point):
    """The certified answers of stored rows ``params`` to ``point``, exact
    fallback included: a dict of arrays, with ``extra`` and ``flag`` as a
    stored row's answer holds them."""
    r = query(CERTIFIED, params[:, :9].reshape(-1, 3, 3), point, (len(params),), True)
    return dict(r, extra=r["barycentric"], flag=np.zeros(len(params), np.bool_))


@functools.cache
def block(method, one):
    """The block function of ``method``, called by the batch loop; ``one``:
    every query is against one triangle."""
    func = KERNELS[method.name][2 if one else 1].py_func
    return specialize(func, func.__name__, LAYOUT.block_signature, role="pointer")


def exact(vertices, point):
    """The certified method's exact answer to one query, as a flat tuple of the outputs."""
    return _exact.triangle(vertices, point)


def query(method, vertices, points, out_shape, full):
    """Run the batch kernel of ``method``; inputs are validated float64 3D arrays."""
    return run(LAYOUT, sys.modules[__name__], method, (), (vertices,), points, out_shape, full)


def exact_sqr_bounds(code, params, point):
    """``bits -> (lo2, hi2)``: the exact squared distance of stored row ``params`` (exact: equal bounds)."""
    s = _exact.hull_sqr_distance(params[:9].reshape(3, 3), point)
    return lambda bits: (s, s)
