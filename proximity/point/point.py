"""Distance between two points: the core of a sphere.

The closest point of a point ``V`` is ``V`` itself (feature ``VERTEX0``), and
the distance is ``|P - V|``.  It is a primitive of its own so that a sphere
is a point inflated by its radius (:class:`proximity.Inflated`), as a
capsule is a segment.

``robust``
    ``A = V - P`` (rounding moves ``V`` by at most ``eps/2 |A|``), scaled by
    a power of two outside the safe window as the other kernels do, and
    ``|A|`` from the sum of squares: within ``3 eps S`` of the exact
    distance, ``S = |P - V|``, plus ``2^-1075`` for a subnormal one.
``certified``
    ``|A|^2`` of the exact difference in double-double, and a faithful
    rounding check on its square root (:func:`~.certified.vertex_distance`);
    what it cannot decide goes to :func:`proximity.numerics.exact.segment` (a
    segment of zero length).
"""

import functools
import math
import sys

import numpy as np

from ..features import NONE, VERTEX0
from ..methods import CERTIFIED
from ..numerics import exact as _exact
from ..numerics.certified import CERTAIN, EXACT, dd_vec, scale_vec, settle, vertex_distance
from ..numerics.fp import EPS, SAFE_MAX, SAFE_MIN, UNSCALED, pow2_scale, unscale
from ..runtime.batch import Layout, run
from ..runtime.jit import inline, part, specialize
from ..runtime.loops import BLOCK, scatter_common


@inline
def window(ax, ay, az):
    """Largest difference, and whether it is inside the safe window."""
    m = max(max(abs(ax), abs(ay)), abs(az))
    return m, (m >= SAFE_MIN) & (m <= SAFE_MAX)


@inline
def _local(ax, ay, az):
    sqr = ax * ax + ay * ay + az * az
    return math.sqrt(sqr), sqr


@part
def robust(vx, vy, vz, px, py, pz):
    """Robust point-point query for any finite input: ``(distance, sqr_distance, x, y, z, feature)``."""
    ax, ay, az = vx - px, vy - py, vz - pz
    m, ok = window(ax, ay, az)
    g = UNSCALED
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        q = 0.25
        ax, ay, az = vx * q - px * q, vy * q - py * q, vz * q - pz * q
        m, ok = window(ax, ay, az)
        g = (4.0, 4.0, 1.0)
    if m == 0.0:
        return 0.0, 0.0, vx, vy, vz, VERTEX0
    if not ok:
        f1, f2 = pow2_scale(m)
        ax, ay, az = ax * f1 * f2, ay * f1 * f2, az * f1 * f2
        g = (g[0] / f1 / f2, g[1] / f1, 1.0 / f2)
    d, sqr = _local(ax, ay, az)
    return unscale(d, g), unscale(unscale(sqr, g), g), vx, vy, vz, VERTEX0


@inline
def robust_query(vx, vy, vz, px, py, pz):
    """:func:`robust` with the leading status of the per-method queries (always certain)."""
    d, sqr, x, y, z, f = robust(vx, vy, vz, px, py, pz)
    return CERTAIN, d, sqr, x, y, z, float(f)


@part
def certified(vx, vy, vz, px, py, pz):
    """Certified point-point query: ``(status, distance, sqr_distance, x, y, z, feature)``."""
    nan = math.nan
    fail = (EXACT, nan, nan, nan, nan, nan, float(NONE))
    a = dd_vec(px, py, pz, vx, vy, vz)
    m = max(max(abs(a[0]), abs(a[2])), abs(a[4]))
    if not m < np.inf:
        return fail
    if m == 0.0:
        return CERTAIN, 0.0, 0.0, vx, vy, vz, float(VERTEX0)
    g = 1.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        a, ok = scale_vec(a, f1, f2)
        g = (1.0 / f1) * (1.0 / f2)
        if not (ok and g < np.inf):
            return fail
    ok, d, s = vertex_distance(a)
    status, d, s = settle(ok, d, s, g)
    if status != CERTAIN:
        return fail
    return CERTAIN, d, s, vx, vy, vz, float(VERTEX0)


# Bound per method by :func:`proximity.runtime.jit.specialize`: the query of one point.
QUERY = None


def _single(out, v, p):
    """One query, written to ``out[:6]``: the fast path; ``out[9]`` the status."""
    px, py, pz = p[0], p[1], p[2]
    out[6] = out[7] = out[8] = math.nan
    if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
        out[:] = math.nan
        out[5] = NONE
        out[9] = 0.0
    else:
        out[9], out[0], out[1], out[2], out[3], out[4], out[5] = QUERY(v[0], v[1], v[2], px, py, pz)


def exact(vertices, point):
    """The certified method's exact answer to one query, as a flat tuple of the outputs."""
    return _exact.segment(np.concatenate([vertices, vertices]), point)[:6]


def exact_row(row, vertices, point):
    """Redo a fast-path row with the certified method's exact fallback."""
    row[:6] = exact(vertices.reshape(1, 3), point)
    row[9] = 0.0


# A block's scratch rows: the point's vertex, the query point, six results, a flag.
_V, _P, _OUT, _OK, _ROWS = 0, 3, 6, 12, 13
_NAN_ROW = (math.nan, math.nan, math.nan, math.nan, math.nan, float(NONE))


@inline
def _gather(z, V, P, n_j, k0, nb):
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
                z[_P + c, q + t] = Pi[j + t, c]
        q += run
        i += 1
        j = 0
    for row in range(_V, _P + 3):
        for q in range(nb, BLOCK):
            z[row, q] = 0.0


@inline
def _store(z, q, res):
    z[_OUT, q], z[_OUT + 1, q], z[_OUT + 2, q] = res[0], res[1], res[2]
    z[_OUT + 3, q], z[_OUT + 4, q], z[_OUT + 5, q] = res[3], res[4], res[5]


@part
def _robust_block(shape, P, n_j, k0, nb, out, exact, full):
    """Robust queries ``k0 .. k0 + nb`` of a batch: SIMD in the safe window, scalar outside."""
    z = np.empty((_ROWS, BLOCK))
    _gather(z, shape.vertices, P, n_j, k0, nb)
    for q in range(BLOCK):
        vx, vy, vz, px, py, pz = z[_V, q], z[_V + 1, q], z[_V + 2, q], z[_P, q], z[_P + 1, q], z[_P + 2, q]
        _, ok = window(vx - px, vy - py, vz - pz)
        d, sqr = _local(vx - px, vy - py, vz - pz)
        _store(z, q, (d, sqr, vx, vy, vz, float(VERTEX0)))
        z[_OK, q] = ok
    for q in range(nb):
        if z[_OK, q] != 0.0:
            continue
        vx, vy, vz, px, py, pz = z[_V, q], z[_V + 1, q], z[_V + 2, q], z[_P, q], z[_P + 1, q], z[_P + 2, q]
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            d, sqr, x, y, zz, f = robust(vx, vy, vz, px, py, pz)
            _store(z, q, (d, sqr, x, y, zz, float(f)))
        else:
            _store(z, q, _NAN_ROW)
    scatter_common(z, _OUT, k0, nb, out, full)


@part
def _certified_block(shape, P, n_j, k0, nb, out, exact, full):
    """Certified queries ``k0 .. k0 + nb`` of a batch, one by one."""
    z = np.empty((_ROWS, BLOCK))
    _gather(z, shape.vertices, P, n_j, k0, nb)
    for q in range(nb):
        vx, vy, vz, px, py, pz = z[_V, q], z[_V + 1, q], z[_V + 2, q], z[_P, q], z[_P + 1, q], z[_P + 2, q]
        if math.isfinite(px) and math.isfinite(py) and math.isfinite(pz):
            res = certified(vx, vy, vz, px, py, pz)
            exact[k0 + q] = res[0] != CERTAIN
            _store(z, q, res[1:])
        else:
            _store(z, q, _NAN_ROW)
    scatter_common(z, _OUT, k0, nb, out, full)


KERNELS = {
    "robust": (robust_query, _robust_block, _robust_block),
    "certified": (certified, _certified_block, _certified_block),
}

#: The arrays of a batch query: the point (as a hull of one vertex); no extra outputs.
LAYOUT = Layout("point", flags=(), arrays=(("vertices", 2),), extra=())


def single_kernel(method):
    """The one-query kernel of ``method``, compiled for :data:`~proximity.runtime.loops.SINGLE_ARGS`."""
    return specialize(_single, method.name, QUERY=KERNELS[method.name][0])


@functools.cache
def block(method, one):
    """The block function of ``method``, called by the batch loop."""
    func = KERNELS[method.name][2 if one else 1].py_func
    return specialize(func, func.__name__, LAYOUT.block_signature, role="pointer")


def query(method, vertices, points, out_shape, full):
    """Run the batch kernel of ``method``; ``vertices`` is ``batch + (1, 3)``."""
    return run(LAYOUT, sys.modules[__name__], method, (), (vertices,), points, out_shape, full)


ROW_QUERY = None


def _row(kind, q, k, px, py, pz):
    """Stored row ``k`` of ``q``: the point."""
    st, d, sqr, x, y, z, f = ROW_QUERY(q[k, 0], q[k, 1], q[k, 2], px, py, pz)
    return st, d, sqr, x, y, z, f, math.nan, math.nan, math.nan, False


def row_query(primitive, method):
    """The query of a stored point row by ``method`` (see :mod:`proximity.primitives`)."""
    return specialize(_row, method.name, role="inline", ROW_QUERY=KERNELS[method.name][0])


@inline
def _interval(kind, q, k, px, py, pz):
    """Bounds ``(lo, hi)`` on the certified distance of stored row ``k``."""
    d = robust(q[k, 0], q[k, 1], q[k, 2], px, py, pz)[0]
    m = max(max(abs(q[k, 0] - px), abs(q[k, 1] - py)), abs(q[k, 2] - pz))
    w = 16.0 * EPS * (1.75 * m) + 5e-324
    return d - w, d + w


def row_interval(primitive):
    """:func:`_interval`, the bounds of a stored point row's certified distance."""
    return _interval


def resolve(code, params, point):
    """The certified answers of stored rows ``params`` to ``point``, as arrays."""
    r = query(CERTIFIED, params[:, :3].reshape(-1, 1, 3), point, (len(params),), True)
    return dict(r, extra=np.full((len(params), 3), np.nan), flag=np.zeros(len(params), np.bool_))


def exact_sqr_bounds(code, params, point):
    """``bits -> (lo2, hi2)``: the exact squared distance of stored row ``params`` (exact: equal bounds)."""
    s = _exact.hull_sqr_distance(params[:3].reshape(1, 3), point)
    return lambda bits: (s, s)
