"""Distance between a point and a segment.

Implements D. Eberly, *Distance Between Point and Line, Ray, or Line Segment*
(Geometric Tools), for the segment, in the document's notation: the segment
is ``X(t) = V0 + t D`` with ``D = V1 - V0`` and ``0 <= t <= 1`` (the
document's ``P0``, ``P1``; the query point is ``P`` here, as for the
triangle), and the closest point has the parameter
``t = D . (P - V0) / D . D`` clamped to ``[0, 1]``.  The features are the
endpoints ``VERTEX0`` (``t = 0``) and ``VERTEX1`` (``t = 1``) and the open
segment ``EDGE01``.

Two methods:

``robust``
    The document's formula, organised as the triangle's edges are in
    :mod:`.triangle`:

    * The endpoints are taken relative to the query point (``A = V0 - P``,
      ``B = V1 - P``).  Their rounding moves each endpoint by at most
      ``eps/2 * S``, and the distance to a segment is 1-Lipschitz in its
      endpoints, so it costs at most ``eps/2 * S``.
    * When the largest difference lies outside ``[2^-64, 2^64]`` both are
      scaled by a power of two, so the squares neither overflow nor
      underflow (coordinates from 1e-300 to 1e300); differences of two
      finite coordinates that overflow are formed from quartered inputs.
    * ``t = -A . E / E . E`` with ``E = B - A``, clamped after a division
      that cannot produce NaN (:func:`project`).  The error of ``t`` times
      ``|E|`` is a few ``eps * S``, and ``|X(t)|^2`` grows only by
      ``|E|^2 dt^2`` away from its minimum, so the distance is off by at most
      that much.  The closest point is formed from the nearer endpoint, and
      is that endpoint exactly when ``t`` is 0 or 1.
    * A zero-length segment (``E == 0``) gives ``t = 0``: it is the point
      ``V0``, with no special case.  A segment shorter than ``2^-511`` of its
      distance (in the scaled frame, ``E . E`` underflows) may get any ``t``,
      but every point of it is then within ``|E| << eps * S`` of the closest:
      no product of more than two differences is formed, so there is no band
      of distances where precision is lost.

    The result satisfies ``|d - d*| <= 8 eps S + 2^-1075`` with
    ``S = max(|P - V0|, |P - V1|)`` (Euclidean norms, as
    :func:`proximity.testing.exact.segment_scale`) for every finite input;
    the absolute term is the rounding of a subnormal distance.

``certified``
    The filtered computation of :mod:`proximity.numerics.certified`: the feature from the signs
    of ``(P - V0) . D`` and ``(P - V1) . D``, each decided only when it
    exceeds its error bound; the squared distance in double-double, ``|A|^2``
    for an endpoint and ``|A x D|^2 / |D|^2`` for the open segment, from the
    exact differences; a faithful rounding check on its square root.  A
    point equal to an endpoint and a zero-length segment are decided
    exactly (``VERTEX0`` for both endpoints of a zero-length segment, the
    lowest code of the tied features).  Whatever the filter cannot decide
    returns :data:`~.certified.EXACT`, for :func:`proximity.numerics.exact.segment`.

Segments in 2D are embedded in the ``z = 0`` plane, which changes no
distance.
"""

import functools
import math
import sys

import numpy as np

from ..features import EDGE01, NONE, VERTEX0, VERTEX1
from ..methods import CERTIFIED
from ..numerics import exact as _exact
from ..numerics.certified import (
    CERTAIN,
    EXACT,
    dd_vec,
    dot_sign,
    edge_distance,
    scale_vec,
    settle,
    vertex_distance,
)
from ..numerics.fp import EPS, SAFE_MAX, SAFE_MIN, TINY, UNSCALED, pow2_scale, unscale
from ..runtime.batch import Layout, run
from ..runtime.jit import inline, part, specialize
from ..runtime.loops import BLOCK, scatter_common


@inline
def project(ax, ay, az, ex, ey, ez, bx, by, bz):
    """Closest point to the origin on the segment from ``a`` to ``b = a + e``.

    Returns ``(sqr_distance, x, y, z, t)``.  The parameter is clamped after a
    division that cannot produce NaN (a zero-length segment has a zero
    numerator), so a degenerate segment is its point.  The closest point is
    formed from the nearer endpoint, which halves its rounding and makes the
    endpoints exact.  Written with selects rather than branches: which case
    applies is unpredictable from one query to the next.
    """
    numer = -(ax * ex + ay * ey + az * ez)
    denom = ex * ex + ey * ey + ez * ez
    t = min(max(numer / max(denom, TINY), 0.0), 1.0)
    near_b = t > 0.5
    u = t - 1.0 if near_b else t
    x = (bx if near_b else ax) + u * ex
    y = (by if near_b else ay) + u * ey
    z = (bz if near_b else az) + u * ez
    return x * x + y * y + z * z, x, y, z, t


@inline
def window(ax, ay, az, bx, by, bz):
    """Largest difference, and whether it is inside the safe window."""
    m = max(max(max(abs(ax), abs(ay)), abs(az)), max(max(abs(bx), abs(by)), abs(bz)))
    return m, (m >= SAFE_MIN) & (m <= SAFE_MAX)


@inline
def robust_local(ax, ay, az, bx, by, bz):
    """The robust method on endpoints relative to ``P``, in the safe window.

    Returns ``(distance, sqr_distance, x, y, z, feature, t)`` with
    ``(x, y, z)`` relative to ``P``.  Branch-free, so that a loop over it
    compiles to SIMD code.
    """
    sqr, x, y, z, t = project(ax, ay, az, bx - ax, by - ay, bz - az, bx, by, bz)
    t = t + 0.0  # -0.0, from a projection exactly on V0, reads as 0
    feature = VERTEX0 if t == 0.0 else (VERTEX1 if t == 1.0 else EDGE01)
    return math.sqrt(sqr), sqr, x, y, z, feature, t


@inline
def finish(r, g, v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz):
    """Undo the scaling ``g`` of a :func:`robust_local` result and make its
    closest point absolute; an endpoint is reported exactly, not as
    ``P + (V - P)``."""
    dist, sqr, x, y, z, feature, t = r
    x = px + unscale(x, g)
    y = py + unscale(y, g)
    z = pz + unscale(z, g)
    x = v0x if feature == VERTEX0 else (v1x if feature == VERTEX1 else x)
    y = v0y if feature == VERTEX0 else (v1y if feature == VERTEX1 else y)
    z = v0z if feature == VERTEX0 else (v1z if feature == VERTEX1 else z)
    return unscale(dist, g), unscale(unscale(sqr, g), g), x, y, z, feature, t


@part
def robust(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz):
    """Robust point-segment query for any finite input; see the module docstring.

    Returns ``(distance, sqr_distance, x, y, z, feature, t)`` where
    ``(x, y, z)`` is the closest point, ``V0 + t (V1 - V0)`` (exactly ``V0``
    for ``t == 0`` and ``V1`` for ``t == 1``), and ``feature`` is
    ``VERTEX0``, ``VERTEX1`` or ``EDGE01``.
    """
    ax, ay, az = v0x - px, v0y - py, v0z - pz
    bx, by, bz = v1x - px, v1y - py, v1z - pz
    m, _ = window(ax, ay, az, bx, by, bz)
    g = UNSCALED  # undoes the scaling of the differences
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        q = 0.25
        ax, ay, az = v0x * q - px * q, v0y * q - py * q, v0z * q - pz * q
        bx, by, bz = v1x * q - px * q, v1y * q - py * q, v1z * q - pz * q
        m, _ = window(ax, ay, az, bx, by, bz)
        g = (4.0, 4.0, 1.0)
    if m == 0.0:
        return 0.0, 0.0, v0x, v0y, v0z, VERTEX0, 0.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        ax, ay, az = ax * f1 * f2, ay * f1 * f2, az * f1 * f2
        bx, by, bz = bx * f1 * f2, by * f1 * f2, bz * f1 * f2
        g = (g[0] / f1 / f2, g[1] / f1, 1.0 / f2)
    r = robust_local(ax, ay, az, bx, by, bz)
    return finish(r, g, v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)


@inline
def differences(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz):
    """The exact differences ``A = V0 - P``, ``B = V1 - P`` and ``D = V1 - V0``
    as double-double vectors, the largest ``|V - P|`` component, and whether
    it is in the safe window with ``D`` finite."""
    a = dd_vec(px, py, pz, v0x, v0y, v0z)
    b = dd_vec(px, py, pz, v1x, v1y, v1z)
    e = dd_vec(v0x, v0y, v0z, v1x, v1y, v1z)
    m, in_window = window(a[0], a[2], a[4], b[0], b[2], b[4])
    return a, b, e, m, in_window & (abs(e[0]) + abs(e[2]) + abs(e[4]) < np.inf)


@inline
def classify(a, b, e):
    """The exact closest feature from float predicates, or ``NONE`` if undecided.

    ``VERTEX0`` when ``(P - V0) . D < 0``, ``VERTEX1`` when
    ``(P - V1) . D > 0``, ``EDGE01`` when neither holds, each sign taken
    from the leading parts of the exact differences with
    :func:`~.certified.dot_sign`'s bound.  ``t == 0`` or ``1`` exactly (the
    projection on an endpoint) is left undecided, except where an exact
    zero decides it: ``P == V0`` or a zero-length segment (``VERTEX0``),
    ``P == V1`` (``VERTEX1``).
    """
    at_v0 = (a[0] == 0.0) & (a[2] == 0.0) & (a[4] == 0.0)
    at_v1 = (b[0] == 0.0) & (b[2] == 0.0) & (b[4] == 0.0)
    point = (e[0] == 0.0) & (e[2] == 0.0) & (e[4] == 0.0)
    # The signs of t and of 1 - t; t > 1 implies t > 0, so VERTEX1 needs only the second.
    above = dot_sign(-a[0], -a[2], -a[4], e[0], e[2], e[4])
    below = dot_sign(b[0], b[2], b[4], e[0], e[2], e[4])
    code = EDGE01 if (above == 1) & (below == 1) else NONE
    code = VERTEX1 if below == -1 else code
    code = VERTEX0 if above == -1 else code
    code = VERTEX1 if at_v1 else code
    return VERTEX0 if at_v0 | point else code


@part
def certified(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz):
    """Certified point-segment query for any finite input, or a request for
    the exact fallback.

    Returns ``(status, distance, sqr_distance, x, y, z, feature, t)`` with
    ``status`` :data:`~.certified.CERTAIN` (a faithfully rounded distance and
    the exact feature; a point on the segment gets exactly 0) or
    :data:`~.certified.EXACT` (the other values are then meaningless).  The
    closest point and ``t`` are computed in float, as the robust method's;
    the point is exactly ``V0`` where ``t == 0`` and ``V1`` where ``t == 1``.
    """
    nan = math.nan
    fail = (EXACT, nan, nan, nan, nan, nan, NONE, nan)
    a, b, e, m, _ = differences(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)
    if not (m < np.inf and abs(e[0]) + abs(e[2]) + abs(e[4]) < np.inf):
        return fail  # a difference of two finite coordinates overflowed
    if m == 0.0:
        return CERTAIN, 0.0, 0.0, v0x, v0y, v0z, VERTEX0, 0.0
    g = 1.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        a, o1 = scale_vec(a, f1, f2)
        b, o2 = scale_vec(b, f1, f2)
        e, o3 = scale_vec(e, f1, f2)
        if not (o1 & o2 & o3):
            return fail
        g = (1.0 / f1) * (1.0 / f2)
        if not g < np.inf:
            return fail
    code = classify(a, b, e)
    if code == NONE:
        return fail
    if code == EDGE01:
        ok, d, s, x, y, z, t = edge_distance(a, e)
    else:
        end = code == VERTEX1
        v = b if end else a
        ok, d, s = vertex_distance(v)
        x, y, z, t = v[0], v[2], v[4], 1.0 if end else 0.0
    status, d, s = settle(ok, d, s, g)
    if status != CERTAIN:
        return fail
    # An endpoint exactly, as the robust method; t is 0 or 1 on VERTEX0 and
    # VERTEX1, and may round to it on EDGE01.
    x, y, z = px + x * g, py + y * g, pz + z * g
    x = v0x if t == 0.0 else (v1x if t == 1.0 else x)
    y = v0y if t == 0.0 else (v1y if t == 1.0 else y)
    z = v0z if t == 0.0 else (v1z if t == 1.0 else z)
    return CERTAIN, d, s, x, y, z, float(code), t


# The per-method queries, with the leading status of the certified method.


@inline
def robust_query(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz):
    """:func:`robust` with the leading status of the per-method queries (always certain)."""
    d, sqr, x, y, z, f, t = robust(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)
    return CERTAIN, d, sqr, x, y, z, float(f), t


# Bound per method by :func:`proximity.runtime.jit.specialize`: the query of one point.
QUERY = None


def _single(out, v, p):
    """One query, written to ``out[:9]``: the fast path for one point and one segment.

    ``v`` holds the six endpoint coordinates and ``p`` the point; ``out[6]``
    is the parameter, ``out[9]`` the status, non-zero where the certified
    method needs its exact fallback.
    """
    px, py, pz = p[0], p[1], p[2]
    out[7] = math.nan
    out[8] = math.nan
    if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
        out[:] = math.nan
        out[5] = NONE
        out[9] = 0.0
    else:
        out[9], out[0], out[1], out[2], out[3], out[4], out[5], out[6] = QUERY(
            v[0], v[1], v[2], v[3], v[4], v[5], px, py, pz
        )


def exact_row(row, vertices, point):
    """Redo a fast-path row with the certified method's exact fallback."""
    row[:7] = _exact.segment(vertices.reshape(2, 3), point)
    row[9] = 0.0


# A block's scratch rows: the endpoints (six rows) and the point (three),
# the query's seven results, and whether it was in the safe window.
_V, _P, _OUT, _OK, _ROWS = 0, 6, 9, 16, 17
_NAN_ROW = (math.nan, math.nan, math.nan, math.nan, math.nan, float(NONE), math.nan)


@inline
def _gather(z, V, P, n_j, k0, nb):
    """Rows ``_V`` to ``_P + 2`` of ``z``: endpoints and point of queries
    ``k0 .. k0 + nb`` of an ``(I, J)`` loop, as
    :func:`proximity.runtime.loops.gather_triangles` does for triangles."""
    i = k0 // n_j
    j = k0 - i * n_j
    q = 0
    while q < nb:
        run = min(nb - q, n_j - j)
        Vi = V[i]
        Pi = P[i]
        for t in range(run):
            for c in range(3):
                z[_V + c, q + t] = Vi[j + t, 0, c]
                z[_V + 3 + c, q + t] = Vi[j + t, 1, c]
                z[_P + c, q + t] = Pi[j + t, c]
        q += run
        i += 1
        j = 0
    for row in range(_V, _P + 3):
        for q in range(nb, BLOCK):
            z[row, q] = 0.0


@inline
def _at(z, q):
    """Query ``q`` of a block: ``(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)``."""
    return (
        z[_V, q], z[_V + 1, q], z[_V + 2, q], z[_V + 3, q], z[_V + 4, q], z[_V + 5, q],
        z[_P, q], z[_P + 1, q], z[_P + 2, q],
    )  # fmt: skip


@inline
def _store(z, q, res):
    """Column ``q`` of the rows ``_OUT``: one query's seven results."""
    z[_OUT, q], z[_OUT + 1, q], z[_OUT + 2, q], z[_OUT + 3, q] = res[0], res[1], res[2], res[3]
    z[_OUT + 4, q], z[_OUT + 5, q], z[_OUT + 6, q] = res[4], res[5], res[6]


@inline
def _scatter(z, k0, nb, out, full):
    """:func:`proximity.runtime.loops.scatter_common`, and the parameters (``out[4]``)."""
    scatter_common(z, _OUT, k0, nb, out, full)
    if full:
        t = out[4][k0 : k0 + nb]
        for q in range(nb):
            t[q] = z[_OUT + 6, q]


@part
def _robust_block(shape, P, n_j, k0, nb, out, exact, full):
    """Robust queries ``k0 .. k0 + nb`` of a batch (see :mod:`proximity.runtime.batch`):
    a loop that compiles to SIMD code for the queries in the safe window,
    the scalar path for the others."""
    z = np.empty((_ROWS, BLOCK))
    _gather(z, shape.vertices, P, n_j, k0, nb)
    for q in range(BLOCK):
        v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz = _at(z, q)
        ax, ay, az = v0x - px, v0y - py, v0z - pz
        bx, by, bz = v1x - px, v1y - py, v1z - pz
        _, ok = window(ax, ay, az, bx, by, bz)
        res = finish(robust_local(ax, ay, az, bx, by, bz), UNSCALED, v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)
        _store(z, q, res)
        z[_OK, q] = ok
    for q in range(nb):
        if z[_OK, q] != 0.0:
            continue
        v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz = _at(z, q)
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            _store(z, q, robust(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz))
        else:
            _store(z, q, _NAN_ROW)
    _scatter(z, k0, nb, out, full)


@part
def _certified_block(shape, P, n_j, k0, nb, out, exact, full):
    """Certified queries ``k0 .. k0 + nb`` of a batch, one by one; ``exact``
    flags the rows left to the exact fallback."""
    z = np.empty((_ROWS, BLOCK))
    _gather(z, shape.vertices, P, n_j, k0, nb)
    for q in range(nb):
        v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz = _at(z, q)
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            res = certified(v0x, v0y, v0z, v1x, v1y, v1z, px, py, pz)
            exact[k0 + q] = res[0] != CERTAIN
            _store(z, q, res[1:])
        else:
            _store(z, q, _NAN_ROW)
    _scatter(z, k0, nb, out, full)


# Per method: the query of one point, and the block functions of the batch
# loop for pairs and for many points against one segment.
KERNELS = {
    "robust": (robust_query, _robust_block, _robust_block),
    "certified": (certified, _certified_block, _certified_block),
}

#: The arrays of a batch query: the endpoints, and the parameters of the answers.
LAYOUT = Layout("segment", flags=(), arrays=(("vertices", 2),), extra=(("parameter", np.float64, 1),))


def single_kernel(method):
    """The one-query kernel of ``method``, compiled for :data:`~proximity.runtime.loops.SINGLE_ARGS`."""
    return specialize(_single, method.name, QUERY=KERNELS[method.name][0])


@functools.cache
def block(method, one):
    """The block function of ``method``, called by the batch loop."""
    func = KERNELS[method.name][2 if one else 1].py_func
    return specialize(func, func.__name__, LAYOUT.block_signature, role="pointer")


def exact(vertices, point):
    """The certified method's exact answer to one query, as a flat tuple of the outputs."""
    return _exact.segment(vertices, point)


def query(method, vertices, points, out_shape, full):
    """Run the batch kernel of ``method``; inputs are validated float64 3D arrays."""
    return run(LAYOUT, sys.modules[__name__], method, (), (vertices,), points, out_shape, full)


# The query of a stored row of a collection (see :mod:`proximity.primitives`):
# bound per method.
ROW_QUERY = None


def _row(kind, q, k, px, py, pz):
    """Stored row ``k`` of ``q``: the endpoints V0, V1."""
    st, d, sqr, x, y, z, f, t = ROW_QUERY(q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], px, py, pz)
    return st, d, sqr, x, y, z, f, t, math.nan, math.nan, False


def row_query(primitive, method):
    """The query of a stored segment row by ``method`` (see :mod:`proximity.primitives`)."""
    return specialize(_row, method.name, role="inline", ROW_QUERY=KERNELS[method.name][0])


@inline
def _interval(kind, q, k, px, py, pz):
    """Bounds ``(lo, hi)`` on the certified distance of stored row ``k``, as
    :func:`proximity.point.triangle._interval` gives them."""
    d = robust(q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5], px, py, pz)[0]
    m = 0.0
    for v in range(2):
        m = max(m, max(max(abs(q[k, 3 * v] - px), abs(q[k, 3 * v + 1] - py)), abs(q[k, 3 * v + 2] - pz)))
    w = 16.0 * EPS * (1.75 * m) + 5e-324  # the bound's absolute term, for subnormal distances
    return d - w, d + w


def row_interval(primitive):
    """:func:`_interval`, the bounds of a stored segment row's certified distance."""
    return _interval


def resolve(code, params, point):
    """The certified answers of stored rows ``params`` to ``point``, exact
    fallback included: a dict of arrays, with ``extra`` and ``flag`` as a
    stored row's answer holds them."""
    r = query(CERTIFIED, params[:, :6].reshape(-1, 2, 3), point, (len(params),), True)
    nan = np.full(len(params), np.nan)
    extra = np.stack([r["parameter"], nan, nan], axis=1)
    return dict(r, extra=extra, flag=np.zeros(len(params), np.bool_))


def exact_sqr_bounds(code, params, point):
    """``bits -> (lo2, hi2)``: the exact squared distance of stored row ``params`` (exact: equal bounds)."""
    s = _exact.hull_sqr_distance(params[:6].reshape(2, 3), point)
    return lambda bits: (s, s)
