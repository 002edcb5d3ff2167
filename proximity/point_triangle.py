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
    * Otherwise the minimum is over the three edges, each a clamped
      projection that never divides by zero: a degenerate triangle (collinear,
      or with coincident vertices) is handled as the segments or the point
      it is, with no special case.

    The result satisfies ``|d - d*| <= 8 eps S`` with ``S = max_i |P - V_i|``
    for every finite input; ``tests/`` checks this against exact rational
    arithmetic on adversarial families.

Both methods are dimension-free in the document; here 2D triangles are
embedded in the ``z = 0`` plane, which changes no distance.
"""

import math

import numpy as np
from numba import njit, prange
from numba.core import types

from ._fp import SAFE_MAX, SAFE_MIN, cross_accurate, dot3_accurate, pow2_scale
from ._loops import A_IN3, A_IN4, OUT1, OUT2, OUT_FEATURE, loop_views
from .results import Feature

NONE = int(Feature.NONE)
VERTEX0 = int(Feature.VERTEX0)
VERTEX1 = int(Feature.VERTEX1)
VERTEX2 = int(Feature.VERTEX2)
EDGE01 = int(Feature.EDGE01)
EDGE12 = int(Feature.EDGE12)
EDGE20 = int(Feature.EDGE20)
FACE = int(Feature.FACE)

EBERLY = 0
ROBUST = 1
METHODS = {"eberly": EBERLY, "robust": ROBUST}


@njit(cache=True)
def eberly(bx, by, bz, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz):
    """Listings 1-8 of the seed, for ``T(s, t) = B + s E0 + t E1``.

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


@njit(inline="always")
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


@njit(inline="always")
def _segment(ax, ay, az, ex, ey, ez, bx, by, bz):
    """Closest point to the origin on the segment from ``a`` to ``b = a + e``.

    Returns ``(sqr_distance, x, y, z, t)``.  The parameter is clamped before
    any division, so a zero-length segment is its point.  The closest point is
    formed from the nearer endpoint, which halves its rounding.
    """
    numer = -(ax * ex + ay * ey + az * ez)
    denom = ex * ex + ey * ey + ez * ez
    if numer <= 0.0:
        t = 0.0
        x, y, z = ax, ay, az
    elif numer >= denom:
        t = 1.0
        x, y, z = bx, by, bz
    else:
        t = numer / denom
        if t <= 0.5:
            x, y, z = ax + t * ex, ay + t * ey, az + t * ez
        else:
            u = t - 1.0
            x, y, z = bx + u * ex, by + u * ey, bz + u * ez
    return x * x + y * y + z * z, x, y, z, t


@njit(inline="always")
def _edge_function(nx, ny, nz, vx, vy, vz, ex, ey, ez):
    # n . (v x e): twice the signed area of (projection of P, v, v + e), times |n|.
    return (
        nx * (vy * ez - vz * ey)
        + ny * (vz * ex - vx * ez)
        + nz * (vx * ey - vy * ex)
    )


@njit(cache=True)
def robust(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz):
    """Robust point-triangle query; see the module docstring.

    Returns ``(distance, sqr_distance, x, y, z, feature, b0, b1, b2)`` where
    ``(x, y, z)`` is the closest point and ``b*`` are its barycentric
    coordinates.
    """
    ax = v0x - px
    ay = v0y - py
    az = v0z - pz
    bx = v1x - px
    by = v1y - py
    bz = v1z - pz
    cx = v2x - px
    cy = v2y - py
    cz = v2z - pz
    m = max(abs(ax), abs(ay), abs(az), abs(bx), abs(by), abs(bz), abs(cx), abs(cy), abs(cz))
    g = 1.0  # undoes the scaling of the differences
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: halve twice first.
        q = 0.25
        ax, ay, az = v0x * q - px * q, v0y * q - py * q, v0z * q - pz * q
        bx, by, bz = v1x * q - px * q, v1y * q - py * q, v1z * q - pz * q
        cx, cy, cz = v2x * q - px * q, v2y * q - py * q, v2z * q - pz * q
        m = max(abs(ax), abs(ay), abs(az), abs(bx), abs(by), abs(bz), abs(cx), abs(cy), abs(cz))
        g = 4.0
    if m == 0.0:
        return 0.0, 0.0, v0x, v0y, v0z, VERTEX0, 1.0, 0.0, 0.0
    g1 = 1.0
    g2 = 1.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        ax, ay, az = ax * f1 * f2, ay * f1 * f2, az * f1 * f2
        bx, by, bz = bx * f1 * f2, by * f1 * f2, bz * f1 * f2
        cx, cy, cz = cx * f1 * f2, cy * f1 * f2, cz * f1 * f2
        g1 = 1.0 / f1
        g2 = 1.0 / f2
    g1 *= g

    e0x, e0y, e0z = bx - ax, by - ay, bz - az
    e1x, e1y, e1z = cx - ax, cy - ay, cz - az
    e2x, e2y, e2z = cx - bx, cy - by, cz - bz

    nx, ny, nz = cross_accurate(e0x, e0y, e0z, e1x, e1y, e1z)
    nn = nx * nx + ny * ny + nz * nz
    if nn > 0.0:
        wc = _edge_function(nx, ny, nz, ax, ay, az, e0x, e0y, e0z)
        wa = _edge_function(nx, ny, nz, bx, by, bz, e2x, e2y, e2z)
        wb = -_edge_function(nx, ny, nz, cx, cy, cz, e1x, e1y, e1z)
        if wa > 0.0 and wb > 0.0 and wc > 0.0:
            na = dot3_accurate(nx, ny, nz, ax, ay, az)
            k = na / nn
            dist = abs(na) / math.sqrt(nn)
            w = wa + wb + wc
            return (
                dist * g1 * g2,
                dist * dist * g1 * g1 * g2 * g2,
                px + k * nx * g1 * g2,
                py + k * ny * g1 * g2,
                pz + k * nz * g1 * g2,
                FACE,
                wa / w,
                wb / w,
                wc / w,
            )

    best, x, y, z, t = _segment(ax, ay, az, e0x, e0y, e0z, bx, by, bz)
    feature = EDGE01
    b0 = 1.0 - t
    b1 = t
    b2 = 0.0
    if t == 0.0:
        feature = VERTEX0
    elif t == 1.0:
        feature = VERTEX1
    d2, x2, y2, z2, t2 = _segment(bx, by, bz, e2x, e2y, e2z, cx, cy, cz)
    if d2 < best:
        best, x, y, z = d2, x2, y2, z2
        feature = EDGE12
        b0 = 0.0
        b1 = 1.0 - t2
        b2 = t2
        if t2 == 0.0:
            feature = VERTEX1
        elif t2 == 1.0:
            feature = VERTEX2
    d2, x2, y2, z2, t2 = _segment(cx, cy, cz, -e1x, -e1y, -e1z, ax, ay, az)
    if d2 < best:
        best, x, y, z = d2, x2, y2, z2
        feature = EDGE20
        b0 = t2
        b1 = 0.0
        b2 = 1.0 - t2
        if t2 == 0.0:
            feature = VERTEX2
        elif t2 == 1.0:
            feature = VERTEX0
    # A vertex is reported exactly; other points relative to P.
    if feature == VERTEX0:
        x, y, z = v0x, v0y, v0z
    elif feature == VERTEX1:
        x, y, z = v1x, v1y, v1z
    elif feature == VERTEX2:
        x, y, z = v2x, v2y, v2z
    else:
        x, y, z = px + x * g1 * g2, py + y * g1 * g2, pz + z * g1 * g2
    return (
        math.sqrt(best) * g1 * g2,
        best * g1 * g1 * g2 * g2,
        x,
        y,
        z,
        feature,
        b0,
        b1,
        b2,
    )


@njit(inline="always")
def _query(method, V, P, i, j):
    """One query of the batch; returns the same tuple as :func:`robust`."""
    px, py, pz = P[i, j, 0], P[i, j, 1], P[i, j, 2]
    if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
        nan = math.nan
        return nan, nan, nan, nan, nan, NONE, nan, nan, nan
    v0x, v0y, v0z = V[i, j, 0, 0], V[i, j, 0, 1], V[i, j, 0, 2]
    v1x, v1y, v1z = V[i, j, 1, 0], V[i, j, 1, 1], V[i, j, 1, 2]
    v2x, v2y, v2z = V[i, j, 2, 0], V[i, j, 2, 1], V[i, j, 2, 2]
    if method == EBERLY:
        e0x, e0y, e0z = v1x - v0x, v1y - v0y, v1z - v0z
        e1x, e1y, e1z = v2x - v0x, v2y - v0y, v2z - v0z
        s, t, feature = eberly(v0x, v0y, v0z, e0x, e0y, e0z, e1x, e1y, e1z, px, py, pz)
        # The closest point and the distance as the seed's source forms them.
        x = v0x + s * e0x + t * e1x
        y = v0y + s * e0y + t * e1y
        z = v0z + s * e0z + t * e1z
        sqr = (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2
        return math.sqrt(sqr), sqr, x, y, z, feature, 1.0 - s - t, s, t
    return robust(v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, px, py, pz)


_SIGNATURE = types.void(
    types.int64, A_IN4, A_IN3, types.int64, OUT1, OUT1, OUT2, OUT_FEATURE, OUT2, types.boolean
)


@njit(_SIGNATURE, parallel=True, cache=True)
def _batch(method, V, P, n_j, dist, sqr, point, feature, bary, full):
    """Fill the flat outputs for an ``(I, J)`` loop over broadcast inputs.

    ``V`` is ``(I, J, 3, 3)`` and ``P`` is ``(I, J, 3)`` with any strides
    (zero along broadcast dimensions); output row ``k`` is loop index
    ``(k // J, k % J)``.  With ``full=False`` only ``dist`` is written and the
    other outputs may be empty.
    """
    for k in prange(dist.shape[0]):
        i = k // n_j
        j = k - i * n_j
        r = _query(method, V, P, i, j)
        dist[k] = r[0]
        if full:
            sqr[k] = r[1]
            point[k, 0] = r[2]
            point[k, 1] = r[3]
            point[k, 2] = r[4]
            feature[k] = r[5]
            bary[k, 0] = r[6]
            bary[k, 1] = r[7]
            bary[k, 2] = r[8]


def query(method, vertices, points, out_shape, full):
    """Run the batch kernel; inputs are validated float64 3D arrays."""
    (V, P), n_j = loop_views(out_shape, [(vertices, 2), (points, 1)])
    n = V.shape[0] * V.shape[1]
    m = n if full else 0
    out = dict(
        distance=np.empty(n),
        sqr_distance=np.empty(m),
        point=np.empty((m, 3)),
        feature=np.empty(m, np.int8),
        barycentric=np.empty((m, 3)),
    )
    _batch(METHODS[method], V, P, n_j, *out.values(), full)
    return out
