"""Distance between a point and a disk in 3D.

Implements Section 2 of D. Eberly, *Distance Between Point and Circle or Disk
in 3D*: if the projection ``Q`` of ``P`` onto the disk's plane lies in the
disk it is the closest point, otherwise the closest point is on the rim, a
circle.  Both methods reuse those of :mod:`.circle`, so the same error
bound holds for ``robust``; a point whose radial distance is within rounding
of ``R`` can be classified either way at a cost below that bound.

The batch kernel here serves circles too: a circle query is a disk query that
always takes the rim branch.
"""

import functools
import math
import sys

import numpy as np
from numba import prange

from .. import methods
from ..features import Feature
from ..methods import CERTIFIED
from ..numerics import certified, dd
from ..numerics import exact as _exact
from ..numerics.fp import EPS, SAFE_MAX, SAFE_MIN, UNSCALED, pow2_scale, unscale
from ..primitives import CIRCLE, DISK
from ..runtime.batch import Layout, run
from ..runtime.jit import inline, kernel, part, specialize
from ..runtime.loops import (
    BLOCK,
    ROUND_C,
    ROUND_P,
    ROUND_R,
    ROUND_ROWS,
    ROUND_U,
    block_scalars,
    block_vectors,
    borrowed,
    drain_round,
    put_round,
    round_sinks,
    scratch,
    single_entry,
)
from .circle import (
    Q_MIN,
    circle,
    decompose,
    decompose_local,
    eberly_circle,
    eberly_projection,
    rim,
    rim_direction,
    short_radial,
    window,
)

NONE = int(Feature.NONE)
FACE = int(Feature.FACE)
RIM = int(Feature.RIM)


@inline
def _disk_from(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, on_axis, r, g):
    """Face or rim, from a decomposition; the query's full return tuple."""
    d, sqr, x, y, z = rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, on_axis, r, g)
    if q <= r:
        x, y, z = cx + unscale(qx, g), cy + unscale(qy, g), cz + unscale(qz, g)
        return (
            unscale(abs(h), g),
            unscale(unscale(h * h, g), g),
            x,
            y,
            z,
            FACE,
            False,
            unscale(h, g),
            unscale(q, g),
        )
    return d, sqr, x, y, z, RIM, False, unscale(h, g), unscale(q, g)


@inline
def disk(cx, cy, cz, ux, uy, uz, radius, px, py, pz):
    """Robust point-disk query for any finite input.

    Returns ``(distance, sqr_distance, x, y, z, feature, equidistant, height,
    radial)``, with ``equidistant`` always False.
    """
    h, qx, qy, qz, q, on_axis, r, g = decompose(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
    return _disk_from(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, on_axis, r, g)


@inline
def eberly_disk(cx, cy, cz, nx, ny, nz, radius, px, py, pz):
    """Section 2 as written; same return as :func:`disk`."""
    nx, ny, nz, h, qx, qy, qz, q = eberly_projection(cx, cy, cz, nx, ny, nz, px, py, pz)
    if q <= radius:
        x, y, z = cx + qx, cy + qy, cz + qz
        sqr = (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2
        return math.sqrt(sqr), sqr, x, y, z, FACE, False, h, q
    d, sqr, x, y, z, _, h, q = eberly_circle(cx, cy, cz, nx, ny, nz, radius, px, py, pz)
    return d, sqr, x, y, z, RIM, False, h, q


_NAN = math.nan
_NAN_ROW = (certified.CERTAIN, _NAN, _NAN, _NAN, _NAN, _NAN, NONE, False, _NAN, _NAN)


@inline
def _finite(px, py, pz):
    return math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)


@inline
def robust_query(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz):
    """The robust query on the scalar path:
    ``(status, d, sqr, x, y, z, feature, equidistant, h, q)``, status always certain."""
    if not _finite(px, py, pz):
        return _NAN_ROW
    if is_disk:
        d, sqr, x, y, z, f, e, h, q = disk(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
        return certified.CERTAIN, d, sqr, x, y, z, f, e, h, q
    d, sqr, x, y, z, e, h, q = circle(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
    return certified.CERTAIN, d, sqr, x, y, z, RIM, e, h, q


@inline
def eberly_query(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz):
    """Eberly's formula as written in his document, as :func:`robust_query`."""
    if not _finite(px, py, pz):
        return _NAN_ROW
    if is_disk:
        d, sqr, x, y, z, f, e, h, q = eberly_disk(cx, cy, cz, nx, ny, nz, radius, px, py, pz)
        return certified.CERTAIN, d, sqr, x, y, z, f, e, h, q
    d, sqr, x, y, z, e, h, q = eberly_circle(cx, cy, cz, nx, ny, nz, radius, px, py, pz)
    return certified.CERTAIN, d, sqr, x, y, z, RIM, e, h, q


@part
def certified_round(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz):
    """Certified point-circle or point-disk query, or a request for the fallback.

    ``u`` is the unit normal (for the closest point) and ``n`` the normal as
    given (for the exact terms).  Returns ``(status, distance, sqr_distance,
    x, y, z, feature, equidistant, height, radial)``.
    """
    nan = math.nan
    fail = (certified.EXACT, nan, nan, nan, nan, nan, NONE, False, nan, nan)
    dxh, dxl = dd.diff(px, cx)
    dyh, dyl = dd.diff(py, cy)
    dzh, dzl = dd.diff(pz, cz)
    r = radius
    m = max(max(abs(dxh), abs(dyh)), max(abs(dzh), r))
    if not m < np.inf:
        return fail
    g1 = 1.0
    g2 = 1.0
    if m == 0.0:
        return certified.CERTAIN, 0.0, 0.0, cx, cy, cz, FACE if is_disk else RIM, not is_disk, 0.0, 0.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        (dxh, dxl, dyh, dyl, dzh, dzl), o1 = certified.scale_vec((dxh, dxl, dyh, dyl, dzh, dzl), f1, f2)
        r, o2 = certified.scale_exact(r, f1, f2)
        if not (o1 and o2):
            return fail
        g1 = 1.0 / f1
        g2 = 1.0 / f2
    # The normal as given, scaled by a power of two (only its direction counts).
    k1, k2 = pow2_scale(max(max(abs(nx), abs(ny)), abs(nz)))
    nx, o1 = certified.scale_exact(nx, k1, k2)
    ny, o2 = certified.scale_exact(ny, k1, k2)
    nz, o3 = certified.scale_exact(nz, k1, k2)
    if not (o1 and o2 and o3):
        return fail

    # |n|^2 h^2 = (n . D)^2 and |n|^2 q^2 = |n x D|^2, in double-double.
    t1h, t1l = dd.mul(nx, 0.0, dxh, dxl)
    t2h, t2l = dd.mul(ny, 0.0, dyh, dyl)
    t3h, t3l = dd.mul(nz, 0.0, dzh, dzl)
    hh, hl = dd.add(t1h, t1l, t2h, t2l)
    hh, hl = dd.add(hh, hl, t3h, t3l)
    dh = 16.0 * certified.U * certified.U * (abs(t1h) + abs(t2h) + abs(t3h))
    vxh, vxl, vyh, vyl, vzh, vzl, ex, ey, ez = certified.cross3(
        nx, 0.0, ny, 0.0, nz, 0.0, dxh, dxl, dyh, dyl, dzh, dzl
    )
    xh, xl, dx2 = certified.norm2_bounded(vxh, vxl, vyh, vyl, vzh, vzl, ex, ey, ez)
    mh, ml, dm = certified.sum_sq(nx, 0.0, ny, 0.0, nz, 0.0)

    # On the axis only when n x D is exactly zero; within rounding of zero
    # (or underflowed), only exact arithmetic decides.
    on_axis = vxh == 0.0 and vyh == 0.0 and vzh == 0.0 and ex == 0.0 and ey == 0.0 and ez == 0.0
    if not on_axis and xh <= dx2 * (1.0 + 1e-12) + certified.SLACK:
        return fail
    # q^2 <= R^2 decides a disk's feature: compare |n x D|^2 with R^2 |n|^2.
    r2h, r2l = dd.sqr(r, 0.0)
    rrh, rrl = dd.mul(r2h, r2l, mh, ml)
    face = False
    if is_disk:
        gh, _ = dd.sub(rrh, rrl, xh, xl)
        bound = dx2 + 32.0 * certified.U * certified.U * abs(rrh)
        if abs(gh) <= bound * (1.0 + 1e-12) + certified.SLACK:
            return fail
        face = gh > 0.0
    h2h, h2l = dd.sqr(hh, hl)
    if h2h == 0.0 and hh != 0.0:
        return fail  # the height's square underflowed
    dh2 = 2.0 * abs(hh) * dh + dh * dh + 8.0 * certified.U * certified.U * abs(h2h)
    if h2h != 0.0:
        s1h, s1l, d1 = certified.ratio(h2h, h2l, dh2, mh, ml, dm)
    else:
        s1h, s1l, d1 = 0.0, 0.0, 2.0 * dh2 / mh
    if face:
        sh, sl, delta = s1h, s1l, d1
    else:
        q2h, q2l, dq2 = certified.ratio(xh, xl, dx2, mh, ml, dm) if xh != 0.0 else (0.0, 0.0, 0.0)
        qh, ql = dd.sqrt(q2h, q2l)
        dq = (0.5 * dq2 / q2h + 8.0 * certified.U * certified.U) * qh if q2h != 0.0 else 0.0
        wh, wl = dd.sub(qh, ql, r, 0.0)
        dw = dq + 4.0 * certified.U * certified.U * abs(wh)
        w2h, w2l = dd.sqr(wh, wl)
        dw2 = 2.0 * abs(wh) * dw + dw * dw + 8.0 * certified.U * certified.U * abs(w2h)
        sh, sl = dd.add(s1h, s1l, w2h, w2l)
        delta = d1 + dw2 + 4.0 * certified.U * certified.U * abs(sh)
    ok, dist, s = certified.faithful_sqrt(sh, sl, delta)
    dist = dist * g1 * g2
    if not ok or (dist < 2.2250738585072014e-308 and dist != 0.0) or not dist < np.inf:
        return fail

    # The closest point, height and radial distance in float, as the robust method.
    h, qx, qy, qz, q, _, _, g = decompose(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
    if face:
        x, y, z, feature = cx + unscale(qx, g), cy + unscale(qy, g), cz + unscale(qz, g), FACE
    else:
        wx, wy, wz = rim_direction(ux, uy, uz, qx, qy, qz, q, on_axis)
        x, y, z, feature = cx + radius * wx, cy + radius * wy, cz + radius * wz, RIM
    sqr = s * g1 * g1 * g2 * g2
    return certified.CERTAIN, dist, sqr, x, y, z, feature, on_axis, unscale(h, g), unscale(q, g)


@inline
def certified_query(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz):
    """The certified filter, as :func:`robust_query`; status ``EXACT`` where
    the query needs the exact fallback."""
    if not _finite(px, py, pz):
        return _NAN_ROW
    return certified_round(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz)


# Blocks per call of a block function (see :attr:`proximity.runtime.batch.Layout.span`).
# A distance to one disk costs a few nanoseconds, and a call of the block
# function about as much as ten of them; eight blocks a call make that a
# percent or two.
SPAN = 8

# Bound per method by :func:`proximity.runtime.jit.specialize`: the query of one
# point, whether the block function runs the robust method's SIMD loop
# first, and whether the method has an exact fallback.
QUERY = None
SIMD = EXACT_FALLBACK = False


def _single(out, s, p):
    """One query, written to ``out[:9]``: the fast path for one point and one shape.

    ``s`` holds ``(is_disk, center, unit normal, normal, radius)`` flattened;
    ``out[9]`` is the status, non-zero where the certified method needs its
    exact fallback.
    """
    out[9], out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8] = QUERY(
        s[0] != 0.0, s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8], s[9], s[10], p[0], p[1], p[2]
    )


def _exact_query(is_disk, center, unit_normal, normal, radius, point):
    """The certified method's exact fallback for one query."""
    row = np.empty(10)
    args = np.concatenate([[float(is_disk)], center, unit_normal, normal, [radius]])
    single_entry(single_kernel(methods.ROBUST))(row, args, np.ascontiguousarray(point))
    return _exact.round_shape(is_disk, center, normal, radius, point, row[2:5])


def exact_row(row, args, point):
    """Redo a fast-path row with the certified method's exact fallback."""
    row[:9] = _exact_query(args[0] != 0.0, args[1:4], args[4:7], args[7:10], args[10], point)
    row[9] = 0.0


@inline
def _robust_row(is_disk, lean, cx, cy, cz, ux, uy, uz, radius, px, py, pz):
    """One query of the compiled loops' robust path, without branches:
    its nine results, and whether they hold: in the safe window, with a
    radial part whose length has all its bits (else the scalar path
    measures it again).

    ``lean`` (a constant) asks for less: a radial part of at least
    :data:`~.point_circle.Q_MIN` whether or not on the axis, and, where
    ``lean == 2``, a query off the axis.  A lean loop that keeps the
    distance alone then compiles without the test of the axis (a square
    root) and without the rim point (three divisions); one that keeps the
    closest points of many shapes, without the rim direction on the axis,
    which depends on each shape's normal (a square root and three more
    divisions per query).  The queries a lean loop leaves are few but for
    points on or next to the axis; a complete loop (``lean == 0``) answers
    those of them that it can, with the same bits.
    """
    dx, dy, dz = px - cx, py - cy, pz - cz
    _, ok = window(dx, dy, dz, radius)
    h, qx, qy, qz, qq, on_axis = decompose_local(dx, dy, dz, ux, uy, uz)
    if lean:
        ok = ok & (qq >= Q_MIN)
    else:
        ok = ok & (not short_radial(qq, on_axis))
    if lean == 2:
        ok = ok & (not on_axis)
        on_axis = False
    res = _disk_from(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, qq, on_axis, radius, UNSCALED)
    d, s, x, y, z = rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, qq, on_axis, radius, UNSCALED)
    if not is_disk:
        res = (d, s, x, y, z, RIM, on_axis, h, qq)
    return res, ok


@inline
def _keep(sinks, oks, q, res, ok, full, lean):
    """Query ``q``'s results into ``sinks`` (the distance alone unless
    ``full``) and, after a complete pass (not ``lean``), whether they hold
    into ``oks``; 1 where they do not.

    A lean pass that leaves a query is followed by a complete pass over the
    whole block, which writes every flag again, so the lean pass keeps only
    the count.
    """
    put_round(sinks, q, res, full)
    if not lean:
        oks[q] = ok
    return not ok


@inline
def _pairs_loop(sinks, oks, c, u, p, r, is_disk, full, lean):
    """The SIMD loop of :func:`_block` over the runs of centers ``c``, unit
    normals ``u``, points ``p`` (``x0, y0, z0, x1, ...``) and radii ``r``;
    returns how many queries it left to the scalar path."""
    left = 0
    for q in range(BLOCK):
        cx, cy, cz, ux, uy, uz = c[3 * q], c[3 * q + 1], c[3 * q + 2], u[3 * q], u[3 * q + 1], u[3 * q + 2]
        px, py, pz = p[3 * q], p[3 * q + 1], p[3 * q + 2]
        res, ok = _robust_row(is_disk, lean, cx, cy, cz, ux, uy, uz, r[q], px, py, pz)
        left += _keep(sinks, oks, q, res, ok, full, lean)
    return left


@inline
def _pairs_pass(sinks, oks, c, u, p, r, is_disk, full, lean):
    """:func:`_pairs_loop`, lean or complete (see :func:`_robust_row`),
    compiled for each kind of output so that the distance alone compiles
    without the closest point's terms."""
    if full:
        return _pairs_loop(sinks, oks, c, u, p, r, is_disk, True, 2 if lean else 0)
    return _pairs_loop(sinks, oks, c, u, p, r, is_disk, False, 1 if lean else 0)


def _block(shape, P, n_j, k0, nb, out, exact, full):
    """Queries ``k0 .. k0 + nb`` of a batch (see :mod:`proximity.runtime.batch`),
    a block of :data:`~proximity.runtime.loops.BLOCK` at a time (the loop gives
    :data:`SPAN` blocks per call).

    The shapes' arrays and the points are read in place where they can be
    (see :func:`~proximity.runtime.loops.block_vectors`), and the results written
    in place (:func:`~proximity.runtime.loops.round_sinks`).  For ``robust``, a
    loop that compiles to SIMD code answers every query it can (``oks``
    says which); every other query is done one by one on the scalar path,
    which is the only path of the other methods.
    """
    shape, P, out, exact = borrowed(shape), borrowed(P), borrowed(out), borrowed(exact)
    is_disk, C, U, N, R = shape
    copies, results = scratch(ROUND_ROWS, np.float64), scratch(8, np.float64)
    codes, flags = scratch(1, np.int8), scratch(1, np.bool_)
    oks = results[7]
    for b0 in range(k0, k0 + nb, BLOCK):
        bn = min(BLOCK, k0 + nb - b0)
        c = block_vectors(copies, ROUND_C, C, n_j, b0, bn)
        u = block_vectors(copies, ROUND_U, U, n_j, b0, bn)
        p = block_vectors(copies, ROUND_P, P, n_j, b0, bn)
        r = block_scalars(copies, ROUND_R, R, n_j, b0, bn)
        sinks = round_sinks(out, b0, bn, full, results, codes, flags)
        left = bn
        if SIMD:
            left = _pairs_pass(sinks, oks, c, u, p, r, is_disk, full, True)
            if left:
                left = _pairs_pass(sinks, oks, c, u, p, r, is_disk, full, False)
        else:
            for q in range(bn):
                oks[q] = 0.0
        if left:
            for q in range(bn):
                if oks[q] != 0.0:
                    continue
                k = b0 + q
                i = k // n_j
                j = k - i * n_j
                cx, cy, cz = c[3 * q], c[3 * q + 1], c[3 * q + 2]
                ux, uy, uz = u[3 * q], u[3 * q + 1], u[3 * q + 2]
                px, py, pz = p[3 * q], p[3 * q + 1], p[3 * q + 2]
                nx, ny, nz = N[i, j, 0], N[i, j, 1], N[i, j, 2]
                cert = QUERY(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, r[q], px, py, pz)
                if EXACT_FALLBACK:
                    exact[k] = cert[0] != certified.CERTAIN
                put_round(sinks, q, cert[1:], full)
        drain_round(sinks, out, b0, bn, full)


@inline
def _one_loop(sinks, oks, p, is_disk, full, lean, cx, cy, cz, ux, uy, uz, radius):
    """The SIMD loop of :func:`_robust_block_one` over the points ``p``
    (``x0, y0, z0, x1, ...``); returns how many queries it left to the
    scalar path."""
    left = 0
    for q in range(BLOCK):
        px, py, pz = p[3 * q], p[3 * q + 1], p[3 * q + 2]
        res, ok = _robust_row(is_disk, lean, cx, cy, cz, ux, uy, uz, radius, px, py, pz)
        left += _keep(sinks, oks, q, res, ok, full, lean)
    return left


@inline
def _one_pass(sinks, oks, p, is_disk, full, lean, cx, cy, cz, ux, uy, uz, radius):
    """:func:`_one_loop`, lean or complete (see :func:`_robust_row`; the
    rim direction on the axis is a constant of the block here): one loop
    for the distance alone (the kinds differ there by a select), and one for
    each kind's full answer, so that each compiles to the work it keeps
    only."""
    lean = 1 if lean else 0
    if not full:
        return _one_loop(sinks, oks, p, is_disk, False, lean, cx, cy, cz, ux, uy, uz, radius)
    if is_disk:
        return _one_loop(sinks, oks, p, True, True, lean, cx, cy, cz, ux, uy, uz, radius)
    return _one_loop(sinks, oks, p, False, True, lean, cx, cy, cz, ux, uy, uz, radius)


@part
def _robust_block_one(shape, P, n_j, k0, nb, out, exact, full):
    """:func:`_block` for the robust method and a batch against one shape,
    ``C[0, 0]``, ``U[0, 0]``, ``R[0, 0]``.

    Only the points are read.  The loop reads the shape as scalars, so the
    compiler computes its own terms (such as the rim direction used on the
    axis) once per call instead of once per query.
    """
    shape, P, out = borrowed(shape), borrowed(P), borrowed(out)
    is_disk, C, U, _, R = shape
    cx, cy, cz, ux, uy, uz = C[0, 0, 0], C[0, 0, 1], C[0, 0, 2], U[0, 0, 0], U[0, 0, 1], U[0, 0, 2]
    radius = R[0, 0]
    copies, results = scratch(3, np.float64), scratch(8, np.float64)
    codes, flags = scratch(1, np.int8), scratch(1, np.bool_)
    oks = results[7]
    for b0 in range(k0, k0 + nb, BLOCK):
        bn = min(BLOCK, k0 + nb - b0)
        p = block_vectors(copies, 0, P, n_j, b0, bn)
        sinks = round_sinks(out, b0, bn, full, results, codes, flags)
        left = _one_pass(sinks, oks, p, is_disk, full, True, cx, cy, cz, ux, uy, uz, radius)
        if left:
            left = _one_pass(sinks, oks, p, is_disk, full, False, cx, cy, cz, ux, uy, uz, radius)
        if left:
            for q in range(bn):
                if oks[q] == 0.0:
                    px, py, pz = p[3 * q], p[3 * q + 1], p[3 * q + 2]
                    # The robust method reads the unit normal only; it stands in for the normal as given.
                    res = robust_query(is_disk, cx, cy, cz, ux, uy, uz, ux, uy, uz, radius, px, py, pz)
                    put_round(sinks, q, res[1:], full)
        drain_round(sinks, out, b0, bn, full)


# Per method: the query of one point, whether it has a SIMD loop (robust),
# whether it has an exact fallback, and a block function for many points
# against one shape (or None: the general one).
KERNELS = {
    "robust": (robust_query, True, False, _robust_block_one),
    "certified": (certified_query, False, True, None),
    "eberly": (eberly_query, False, False, None),
}


def single_kernel(method):
    """The one-query kernel of ``method`` (a :class:`~proximity.methods.Method`), compiled
    for :data:`~proximity.runtime.loops.SINGLE_ARGS` by :func:`~proximity.runtime.loops.single_entry`."""
    return specialize(_single, method.name, QUERY=KERNELS[method.name][0])


#: The arrays of a batch query: whether the shapes are disks (else circles),
#: center, unit normal, normal as given and radius, and the answers' extra fields.
LAYOUT = Layout(
    "round",
    flags=("is_disk",),
    arrays=(("center", 1), ("unit_normal", 1), ("normal", 1), ("radius", 0)),
    extra=(("equidistant", np.bool_, 1), ("height", np.float64, 1), ("radial", np.float64, 1)),
    span=SPAN,
)


@functools.cache
def block(method, one):
    """The block function of ``method``, called by the batch loop; ``one``:
    every query is against one shape."""
    query_, simd, exact_fallback, block_one = KERNELS[method.name]
    if one and block_one is not None:
        func = block_one.py_func
        return specialize(func, func.__name__, LAYOUT.block_signature, role="pointer")
    bindings = dict(QUERY=query_, SIMD=simd, EXACT_FALLBACK=exact_fallback)
    return specialize(_block, method.name, LAYOUT.block_signature, role="pointer", **bindings)


def exact(is_disk, center, unit_normal, normal, radius, point):
    """The certified method's exact answer to one query, as a flat tuple of the outputs."""
    return _exact_query(is_disk, center, unit_normal, normal, radius, point)


def query(method, is_disk, center, unit_normal, normal, radius, points, out_shape, full):
    """Run the batch kernel; inputs are validated float64 arrays."""
    arrays = (center, unit_normal, normal, radius)
    return run(LAYOUT, sys.modules[__name__], method, (is_disk,), arrays, points, out_shape, full)


# The query of a stored row of a collection (see :mod:`proximity.primitives`):
# bound per method, with the code of the disk kind.
ROW_QUERY = None
DISK_CODE = 1


def _row(kind, q, k, px, py, pz):
    """Stored row ``k`` of ``q``: center, unit normal, normal as given, radius."""
    st, d, sqr, x, y, z, f, e, h, r = ROW_QUERY(
        kind == DISK_CODE, q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5],
        q[k, 6], q[k, 7], q[k, 8], q[k, 9], px, py, pz,
    )  # fmt: skip
    return st, d, sqr, x, y, z, f, h, r, math.nan, e


def row_query(primitive, method):
    """The query of a stored disk or circle row by ``method`` (see :mod:`proximity.primitives`)."""
    query_ = KERNELS[method.name][0]
    return specialize(_row, method.name, role="inline", ROW_QUERY=query_, DISK_CODE=DISK.code)


def _interval(kind, q, k, px, py, pz):
    """Bounds ``(lo, hi)`` on the certified distance of stored row ``k``
    from the robust one: within ``8 eps S`` and one ulp of the exact one,
    with ``S`` at most ``1.75`` times the largest coordinate difference
    from the center (``sqrt(3)`` and rounding), plus ``R``."""
    d = robust_query(
        kind == DISK_CODE, q[k, 0], q[k, 1], q[k, 2], q[k, 3], q[k, 4], q[k, 5],
        q[k, 6], q[k, 7], q[k, 8], q[k, 9], px, py, pz,
    )[1]  # fmt: skip
    m = max(max(abs(q[k, 0] - px), abs(q[k, 1] - py)), abs(q[k, 2] - pz))
    w = 16.0 * EPS * (1.75 * m + q[k, 9]) + 5e-324  # the bound's absolute term, for subnormal distances
    return d - w, d + w


def row_interval(primitive):
    """:func:`_interval` with the code of the disk kind bound."""
    return specialize(_interval, "rows", role="inline", DISK_CODE=DISK.code)


def shorter_than_one(u):
    """The rows of ``u`` normalised and shortened by ``2^-40``, so that each is
    no longer than 1 despite rounding; zero where not finite."""
    # Any vector no longer than 1 gives a valid slab; shrink the rounded
    # unit vector by far more than its rounding so that it is one.
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        length = np.sqrt(np.sum(u * u, axis=1, keepdims=True))
        u = u / length * (1.0 - 2.0**-40)
    return np.where(np.isfinite(u).all(axis=1, keepdims=True), u, 0.0)


def slab(u, points):
    """``(h_min, h_max)`` of ``u . X`` over ``points (n, k, 3)``; unbounded where it overflows."""
    with np.errstate(invalid="ignore", over="ignore"):
        h = np.einsum("nkj,nj->nk", points, u)
    ok = np.isfinite(h).all(axis=1)
    return np.where(ok, h.min(axis=1), -np.inf), np.where(ok, h.max(axis=1), np.inf)


def cull(code, params, rows, out):
    """Box and slab of stored rows ``rows`` of ``params``, into ``out``; for
    circles, also their loose boxes (returned), else None.

    The box is the center plus or minus ``R sqrt(1 - u_a^2)`` on each axis
    ``a``, computed as ``R sqrt(u_b^2 + u_c^2) / |u|`` so that no
    cancellation enters (its rounding is a few ``eps`` of ``R``, inside the
    pruning slack), and the slab that of the plane.  Loose boxes bound a
    circle by the cube ``C +- R``, without a slab: the ``eberly`` method's
    closest point can leave the plane near the axis.
    """
    c = params[rows, 0:3]
    sq = params[rows, 3:6] ** 2
    r = params[rows, 9:10]
    # 1 - u_a^2 as the sum of the other two squares: subtracting from 1
    # would cancel, and the square root would magnify that to sqrt(eps).
    others = sq[:, [1, 2, 0]] + sq[:, [2, 0, 1]]
    with np.errstate(over="ignore"):
        extent = r * np.sqrt(others) / np.sqrt(sq.sum(axis=1, keepdims=True))
        out[rows, 0:3] = c - extent
        out[rows, 3:6] = c + extent
    u = shorter_than_one(params[rows, 3:6])
    out[rows, 6:9] = u
    out[rows, 9], out[rows, 10] = slab(u, c[:, None, :])
    if code != CIRCLE.code:
        return None
    loose = out[rows].copy()
    with np.errstate(over="ignore"):
        loose[:, 0:3] = c - r
        loose[:, 3:6] = c + r
    loose[:, 6:9] = 0.0
    loose[:, 9] = -np.inf
    loose[:, 10] = np.inf
    return loose


def resolve(code, params, point):
    """The certified answers of stored rows ``params`` to ``point``, exact
    fallback included: a dict of arrays, with ``extra`` and ``flag`` as a
    stored row's answer holds them."""
    r = query(CERTIFIED, code == DISK.code, params[:, 0:3], params[:, 3:6], params[:, 6:9], params[:, 9],
              point, (len(params),), True)  # fmt: skip
    extra = np.stack([r["height"], r["radial"], np.full(len(params), np.nan)], axis=1)
    flag = r["equidistant"] & (code == CIRCLE.code)
    return dict(r, extra=extra, flag=flag)


# |n| of a normal whose largest component lies in this range is computed
# without scaling: no square then overflows, and none that underflows could
# change the rounded sum, so the result has the bits of the scaled one.
_NO_SCALING = (2.0**-400, 2.0**400)
_LARGEST = np.finfo(np.float64).max


@kernel(parallel=True)
def round_frames(center, normal, radius, unit):
    """``unit[i] = normal[i] / |normal[i]|`` for an ``(n, 3)`` normal array,
    with the bits of ``shapes._unit``, and the number of rows with a problem:
    a non-finite entry, a zero normal or a negative radius.  ``center`` and
    ``radius`` are checked where they have ``n`` rows (else they have none).
    A row with a problem has a meaningless ``unit`` row."""
    bad = 0
    check_center, check_radius = center.shape[0] > 0, radius.shape[0] > 0
    for i in prange(normal.shape[0]):
        x, y, z = normal[i, 0], normal[i, 1], normal[i, 2]
        ax, ay, az = abs(x), abs(y), abs(z)
        big = max(ax, ay, az)
        ok = ax <= _LARGEST and ay <= _LARGEST and az <= _LARGEST and big > 0.0
        if check_center:
            ok = ok and abs(center[i, 0]) <= _LARGEST and abs(center[i, 1]) <= _LARGEST
            ok = ok and abs(center[i, 2]) <= _LARGEST
        if check_radius:
            ok = ok and 0.0 <= radius[i] <= _LARGEST
        if not ok:
            bad += 1
            big = 1.0
        if not _NO_SCALING[0] <= big <= _NO_SCALING[1]:
            e = -math.frexp(big)[1]
            x, y, z = math.ldexp(x, e), math.ldexp(y, e), math.ldexp(z, e)
        length = math.sqrt(x * x + y * y + z * z)
        unit[i, 0], unit[i, 1], unit[i, 2] = x / length, y / length, z / length
    return bad


def exact_sqr_bounds(code, params, point):
    """``bits -> (lo2, hi2)``: bounds on the exact squared distance of stored
    row ``params`` (center, unit normal, normal as given, radius), to
    ``2^-bits`` of it."""
    is_disk = code == DISK.code
    return lambda bits: _exact.round_sqr_bounds(is_disk, params[0:3], params[6:9], params[9], point, bits)
