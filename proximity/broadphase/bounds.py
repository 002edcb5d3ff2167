"""Bounds of primitives and nodes, and the pruning tests of the search.

A collection stores each primitive as a row of parameters (see
:mod:`proximity.primitives`); its *cull* row holds its box and one slab, and
a node's bounds its box and an oriented box (:mod:`.refit`).

Pruning, and why it never changes the answer
--------------------------------------------
The traversal visits the nearer child first and skips a node when a lower
bound on the distance from the point to what it holds exceeds ``best +
SLACK``.  A *slab* is a vector ``u`` no longer than 1 and the range
``[h_min, h_max]`` of ``u . X`` over everything it bounds: every such ``X``
is at least ``e = max(u . P - h_max, h_min - u . P, 0)`` from ``P``.  A
node has its box and an oriented box, three slabs on orthogonal axes
``u``, ``v``, ``w``, whose excesses add in squares (``|P - X|^2 >= e_u^2 +
e_v^2 + e_w^2``); the bound is the larger of the distances to the two
boxes.  A node's ``u`` is the mean normal of its primitives, so a flat
patch has an oriented box thin along its normal and tight across it, which
prunes where the axis-aligned box would not (a point far over a tilted
patch, or inside a sphere).  A primitive has its box and the slab of its
own normal: for a point over a face's interior the slab distance is the
distance itself, so faces that are merely near are skipped without calling
the method.

These tests never skip a primitive that brute force would pick.  In units
of ``M``, the largest coordinate magnitude of the point and of every box:

* the tests run on coordinates multiplied by a power of two ``s`` with
  ``M s`` in ``[0.5, 1)`` (exact), so squares neither overflow nor lose
  anything that matters to underflow, and their rounding is a few ``eps``;
  a slab's ``u`` and range carry a few ``eps`` more, and the axes of an
  oriented box, each shortened by ``2^-40``, are orthogonal far within
  that, so the sum of squares never exceeds ``|P - X|^2``;
* every primitive lies in its box and its slab, and each method's computed
  distance is at least the true distance to them minus a few tens of
  ``eps M``: ``robust`` is within ``8 eps S`` of the true distance, with
  ``S <= 2 sqrt(3) M`` for triangles and ``S <= 5 M`` for disks and
  circles; ``certified`` is within an ulp; ``eberly``'s closest point on a
  triangle or a disk lies in the plane and the box up to the rounding of
  its coordinates;
* before any primitive is asked, ``best`` is the distance to the closest
  point found for the previous point (points are visited in spatial order,
  so it is near): that point lies on its primitive up to the rounding of
  its coordinates, so the primitive's computed distance exceeds it by a few
  ``eps M`` at most;
* ``SLACK`` is ``256 eps M``, several times the sum: a skipped primitive's
  computed distance exceeds ``best``, so even ties are visited, and the
  lowest index wins in both.

The tree keeps its primitives' cull rows in float32 (:func:`stored_cull`),
half the memory: boxes rounded outwards, slab axes towards zero (no
longer than before) with their ranges widened by what the rounding of the
axis can move ``u . X`` over the box, then rounded outwards.  Each row
still holds its primitive, so the argument above is unchanged; a
coordinate beyond float32's range leaves its side of the box unbounded.
A tree of a mesh's faces keeps none: the robust search answers a leaf's
faces side by side without them (:mod:`.traverse`), and the other
searches have them computed from the vertices at their first use
(:meth:`.tree.Tree.culling`).

``eberly``'s circle is the exception: near the axis it takes the rim
direction from rounding noise, so its closest point can leave the plane by
up to ``R``.  For that method circles are bounded by the cube ``C +- R``
and have no slab; the tree keeps a second set of boxes for it, and no
previous closest point bounds the search.
"""

import math

import numpy as np

from .. import primitives
from ..numerics.fp import EPS
from ..runtime import threads
from ..runtime.jit import inline, kernel, spliced
from ._alloc import empty, readonly

SLACK = 256.0 * EPS  # pruning slack, in units of the query's magnitude M (see the module docstring)

#: Columns of a primitive's cull row: its box ``(lo, hi)``, then one slab ``(u, h_min, h_max)``.
CULL_COLUMNS = 11

#: Columns of the rows of a tree of faces alone (hulls of three points):
#: their nine coordinates, without the padding of a collection of several
#: kinds to :data:`~proximity.primitives.N_PARAMS`.
FACE_COLUMNS = 9

_FLOAT32_MAX = float(np.finfo(np.float32).max)


@inline
def _box_sqr(bounds, node, s, qx, qy, qz):
    # Squared distance from the scaled point to the scaled box: 0 inside.
    dx = max(max(bounds[node, 0] * s - qx, qx - bounds[node, 3] * s), 0.0)
    dy = max(max(bounds[node, 1] * s - qy, qy - bounds[node, 4] * s), 0.0)
    dz = max(max(bounds[node, 2] * s - qz, qz - bounds[node, 5] * s), 0.0)
    return dx * dx + dy * dy + dz * dz


@inline
def _excess(boxes, k, c, s, qx, qy, qz):
    """How far the scaled point lies outside the slab ``(u, h_min, h_max)`` at
    ``boxes[k, c:c + 5]``: 0 within it."""
    t = boxes[k, c] * qx + boxes[k, c + 1] * qy + boxes[k, c + 2] * qz
    return max(max(t - boxes[k, c + 4] * s, boxes[k, c + 3] * s - t), 0.0)


@inline
def _bound_sqr(boxes, k, s, qx, qy, qz):
    """Squared lower bound on the distance from the scaled point to what node ``k`` holds.

    ``boxes[k]`` is ``(lo, hi)`` and three slabs ``(u, h_min, h_max)``
    across orthogonal axes; see the module docstring.
    """
    return max(_box_sqr(boxes, k, s, qx, qy, qz), _slabs_sqr(boxes, k, s, qx, qy, qz))


@inline
def _slabs_sqr(boxes, k, s, qx, qy, qz):
    """Squared distance from the scaled point to node ``k``'s oriented box
    (its three slabs), a lower bound as :func:`_bound_sqr`'s."""
    # A loop rather than three calls with the constants 6, 11 and 16, which
    # would compile a variant of _excess for each; the sum starts at -0.0,
    # which adds nothing (to any float, -0.0 and NaN included), and is left out.
    total = -0.0
    for c in range(6, 21, 5):
        h = _excess(boxes, k, c, s, qx, qy, qz)
        total += h * h
    return total


@inline
def _culled(cull, k, s, qx, qy, qz, reach):
    """Whether stored primitive ``k`` is farther than ``reach`` (scaled) by its box or its slab.

    ``cull[k]`` is ``(lo, hi, u, h_min, h_max)``; see the module docstring.
    """
    if _box_sqr(cull, k, s, qx, qy, qz) > reach * reach:
        return True
    return _excess(cull, k, 6, s, qx, qy, qz) > reach


@inline
def _scale(px, py, pz, magnitude):
    """The power of two ``s`` that brings ``M`` (point and boxes) into ``[0.5, 1)``."""
    m = max(max(abs(px), abs(py)), max(abs(pz), magnitude))
    return math.ldexp(1.0, -max(math.frexp(m)[1], -1000))


@inline
def plane_row(cull, k, x0, y0, z0, x1, y1, z1, x2, y2, z2):
    """Row ``k`` of :func:`primitive_cull` for the hull of three points (a
    triangle): their box, and the slab of their plane's normal, shortened as
    :func:`proximity.point.disk.shorter_than_one` does (none where they are collinear)."""
    cull[k, 0], cull[k, 3] = min(min(x0, x1), x2), max(max(x0, x1), x2)
    cull[k, 1], cull[k, 4] = min(min(y0, y1), y2), max(max(y0, y1), y2)
    cull[k, 2], cull[k, 5] = min(min(z0, z1), z2), max(max(z0, z1), z2)
    ex, ey, ez = x1 - x0, y1 - y0, z1 - z0
    fx, fy, fz = x2 - x0, y2 - y0, z2 - z0
    nx, ny, nz = ey * fz - ez * fy, ez * fx - ex * fz, ex * fy - ey * fx
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    shrink = (1.0 - 2.0**-40) / length if length > 0.0 else 0.0
    ux, uy, uz = nx * shrink, ny * shrink, nz * shrink
    if not (math.isfinite(ux) and math.isfinite(uy) and math.isfinite(uz)):
        ux, uy, uz = 0.0, 0.0, 0.0
    h0 = ux * x0 + uy * y0 + uz * z0
    h1 = ux * x1 + uy * y1 + uz * z1
    h2 = ux * x2 + uy * y2 + uz * z2
    low = min(min(min(math.inf, h0), h1), h2)
    high = max(max(max(-math.inf, h0), h1), h2)
    if not (math.isfinite(low) and math.isfinite(high)):
        low, high = -math.inf, math.inf
    cull[k, 6], cull[k, 7], cull[k, 8] = ux, uy, uz
    cull[k, 9], cull[k, 10] = low, high


@inline
def _box_row(cull, k, q, j, n):
    """Row ``k`` of :func:`primitive_cull` for the hull of the ``n`` points at
    the start of row ``j`` of ``q``: their box, and no slab."""
    for a in range(3):
        low, high = math.inf, -math.inf
        for v in range(n):
            low, high = min(low, q[j, 3 * v + a]), max(high, q[j, 3 * v + a])
        cull[k, a], cull[k, 3 + a] = low, high
    for a in range(6, 9):
        cull[k, a] = 0.0
    cull[k, 9], cull[k, 10] = -math.inf, math.inf


@kernel()
def _hull_rows(params, rows, n, cull):
    """:func:`primitive_cull` of stored rows ``rows``, hulls of ``n`` points."""
    for j in range(rows.shape[0]):
        k = rows[j]
        if n == 3:
            p = params[k]
            plane_row(cull, k, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8])
        else:
            _box_row(cull, k, params, k, n)


def primitive_cull(kinds, params):
    """Box and slab of each primitive, ``(n, 11)``, and the loose ones for ``eberly``.

    A primitive that is the hull of points (its ``vertices``, see
    :class:`proximity.primitives.Primitive`) is bounded by their extremes
    (exact) and, for three points, by the slab of their plane; the others
    by their kernel module's ``cull``.  The loose data, for methods whose
    closest point may leave the tight bounds (``Method.loose``), are the
    same array unless a kernel module gives others.
    """
    n = len(kinds)
    cull = empty(n, CULL_COLUMNS)
    kinds = readonly(kinds, np.int8)
    params = readonly(params, np.float64)
    kinds_present = primitives.present(kinds)
    loose = {}
    for p in kinds_present:
        rows = np.arange(n) if len(kinds_present) == 1 else np.flatnonzero(kinds == p.code)
        if p.vertices:
            _hull_rows(params, readonly(rows, np.int64), p.vertices, cull)
        else:
            looser = p.kernels.cull(p.code, params, rows, cull)
            if looser is not None:
                loose[p.code] = (rows, looser)
    looser = cull
    if loose:
        looser = cull.copy()
        for rows, values in loose.values():
            looser[rows] = values
    if params.shape[1] > primitives.N_PARAMS:  # rounded primitives: their radius, around
        radius = params[:, primitives.N_PARAMS]
        for rows in (cull,) if looser is cull else (cull, looser):
            _widen(rows, radius)
    return cull, looser


@inline
def _down32(x):
    """A float32 at most ``x``: ``x`` moved down by a float32 spacing (``2^-23`` of
    it, and the least subnormal), then rounded to nearest, which moves it
    back up by half a spacing at most; the float64 rounding of the move is
    far inside the other half.  1e39 goes to the largest float32, -1e39 to
    -inf; infinities stay."""
    if not math.isfinite(x):
        return np.float32(x)
    return np.float32(min(x - abs(x) * 2.0**-23 - 2.0**-149, _FLOAT32_MAX))


@spliced
def _up32(x):
    """A float32 at least ``x`` (see :func:`_down32`)."""
    return -_down32(-x)


@spliced
def _stored_row(cull, k, out, j):
    """Row ``k`` of :func:`stored_cull`, into row ``j`` of ``out``."""
    for a in range(3):
        out[j, a] = _down32(cull[k, a])
        out[j, 3 + a] = _up32(cull[k, 3 + a])
    # The axis towards zero, so it stays no longer than 1; u' . X differs
    # from u . X by at most sum |u - u'| max(|lo|, |hi|) over the box
    # (each difference exact: u' is near u, on a grid as fine as u's), and
    # the widening is rounded up beyond the sum's rounding.
    widen = 0.0
    for a in range(3):
        u = cull[k, 6 + a]
        f = math.copysign(max(np.float64(_down32(abs(u))), 0.0), u)
        out[j, 6 + a] = np.float32(f)
        d = abs(u - f)
        if d > 0.0:
            widen += d * max(abs(cull[k, a]), abs(cull[k, 3 + a]))
    widen *= 1.0 + 2.0**-40
    out[j, 9] = _down32(cull[k, 9] - widen)
    out[j, 10] = _up32(cull[k, 10] + widen)


@kernel(nogil=True)
def _stored_rows(cull, out, lo, hi):
    """Rows ``lo .. hi - 1`` of :func:`stored_cull`: a serial kernel, run on
    the threads, which compiles in a fraction of a parallel loop's time."""
    for k in range(lo, hi):
        _stored_row(cull, k, out, k)


#: Rows per call of :func:`_stored_rows`.
_STORED_CHUNK = 1 << 16


def stored_cull(cull, empty=np.empty):
    """The cull rows ``(n, 11)`` as the tree keeps them: float32, each still
    holding its primitive (see the module docstring), in an array from
    ``empty(shape, dtype)``.

    Parameters
    ----------
    cull : ndarray of float64, shape ``(n, CULL_COLUMNS)``
        Rows of :func:`primitive_cull`.
    """
    out = empty(cull.shape, np.float32)
    cull = readonly(cull, np.float64)
    threads.spread(lambda lo, hi: _stored_rows(cull, out, lo, hi), len(cull), _STORED_CHUNK)
    return out


def _widen(cull, radius):
    """Cull rows of primitives rounded by ``radius``: boxes and slab ranges
    widened by it (outwards, beyond their rounding; infinite ranges stay)."""
    with np.errstate(over="ignore", invalid="ignore"):
        grow = radius * (1.0 + 2.0**-50)
        cull[:, 0:3] -= grow[:, None]
        cull[:, 3:6] += grow[:, None]
        cull[:, 9] -= grow
        cull[:, 10] += grow
