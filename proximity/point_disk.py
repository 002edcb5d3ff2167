"""Distance between a point and a disk in 3D.

Implements Section 2 of D. Eberly, *Distance Between Point and Circle or Disk
in 3D*: if the projection ``Q`` of ``P`` onto the disk's plane lies in the
disk it is the closest point, otherwise the closest point is on the rim, a
circle.  Both methods reuse those of :mod:`.point_circle`, so the same error
bound holds for ``robust``; a point whose radial distance is within rounding
of ``R`` can be classified either way at a cost below that bound.

The batch kernel here serves circles too: a circle query is a disk query that
always takes the rim branch.
"""

import functools
import math

import numpy as np
from numba import prange
from numba.core import types

from . import _exact, _pool, certified, methods
from ._fp import UNSCALED, unscale
from ._jit import address, function_at, inline, kernel, part, specialize
from ._loops import (
    A_IN2,
    A_IN3,
    BLOCK,
    ONE_OK,
    ONE_OUT,
    ONE_P,
    ONE_ROWS,
    OUT1,
    OUT2,
    OUT_FEATURE,
    OUT_FLAG,
    ROUND_OK,
    ROUND_OUT,
    ROUND_ROWS,
    gather_points,
    gather_round,
    loop_views,
    point_at,
    round_at,
    scatter_round,
    single_entry,
    single_shape,
    store,
)
from .point_circle import (
    circle,
    decompose,
    decompose_local,
    rim,
    seed_circle,
    seed_projection,
    short_radial,
    window,
)
from .results import Feature

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
def seed_disk(cx, cy, cz, nx, ny, nz, radius, px, py, pz):
    """Section 2 as written; same return as :func:`disk`."""
    nx, ny, nz, h, qx, qy, qz, q = seed_projection(cx, cy, cz, nx, ny, nz, px, py, pz)
    if q <= radius:
        x, y, z = cx + qx, cy + qy, cz + qz
        sqr = (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2
        return math.sqrt(sqr), sqr, x, y, z, FACE, False, h, q
    d, sqr, x, y, z, _, h, q = seed_circle(cx, cy, cz, nx, ny, nz, radius, px, py, pz)
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
    """The seed's formula, as :func:`robust_query`."""
    if not _finite(px, py, pz):
        return _NAN_ROW
    if is_disk:
        d, sqr, x, y, z, f, e, h, q = seed_disk(cx, cy, cz, nx, ny, nz, radius, px, py, pz)
        return certified.CERTAIN, d, sqr, x, y, z, f, e, h, q
    d, sqr, x, y, z, e, h, q = seed_circle(cx, cy, cz, nx, ny, nz, radius, px, py, pz)
    return certified.CERTAIN, d, sqr, x, y, z, RIM, e, h, q


@inline
def certified_query(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz):
    """The certified filter, as :func:`robust_query`; status ``EXACT`` where
    the query needs the exact fallback."""
    if not _finite(px, py, pz):
        return _NAN_ROW
    return certified.round_shape(is_disk, cx, cy, cz, ux, uy, uz, nx, ny, nz, radius, px, py, pz)


# Bound per method by :func:`proximity._jit.specialize`: the query of one
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
def _robust_row(is_disk, cx, cy, cz, ux, uy, uz, radius, px, py, pz):
    """One query of the compiled loops' robust path, without branches:
    its nine results, and whether they hold: in the safe window, with a
    radial part whose length has all its bits (else the scalar path measures
    it again)."""
    dx, dy, dz = px - cx, py - cy, pz - cz
    _, ok = window(dx, dy, dz, radius)
    h, qx, qy, qz, qq, on_axis = decompose_local(dx, dy, dz, ux, uy, uz)
    ok = ok & (not short_radial(qq, on_axis))
    res = _disk_from(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, qq, on_axis, radius, UNSCALED)
    d, s, x, y, z = rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, qq, on_axis, radius, UNSCALED)
    if not is_disk:
        res = (d, s, x, y, z, RIM, on_axis, h, qq)
    return res, ok


def _block(
    is_disk,
    C,
    U,
    N,
    R,
    P,
    n_j,
    k0,
    nb,
    dist,
    sqr,
    point,
    feature,
    equidistant,
    height,
    radial,
    exact,
    full,
):
    """Queries ``k0 .. k0 + nb`` of :func:`_batch`.

    Gathered into local scratch (the rows of ``ROUND_*``); for ``robust``,
    computed by a loop that compiles to SIMD code (with, in row
    ``ROUND_OK``, whether the query was in its safe window); every other
    query is done one by one on the scalar path, which is the only path of
    the other methods.  Then scattered to the outputs.
    """
    z = np.empty((ROUND_ROWS, BLOCK))
    gather_round(z, C, U, P, R, n_j, k0, nb)
    if SIMD:
        for q in range(BLOCK):
            cx, cy, cz, ux, uy, uz, radius, px, py, pz = round_at(z, q)
            res, ok = _robust_row(is_disk, cx, cy, cz, ux, uy, uz, radius, px, py, pz)
            store(z, ROUND_OUT, q, res)
            z[ROUND_OK, q] = ok
    else:
        for q in range(nb):
            z[ROUND_OK, q] = 0.0
    for q in range(nb):
        if z[ROUND_OK, q] != 0.0:
            continue
        k = k0 + q
        i = k // n_j
        j = k - i * n_j
        cx, cy, cz, ux, uy, uz, radius, px, py, pz = round_at(z, q)
        cert = QUERY(is_disk, cx, cy, cz, ux, uy, uz, N[i, j, 0], N[i, j, 1], N[i, j, 2], radius, px, py, pz)
        if EXACT_FALLBACK:
            exact[k] = cert[0] != certified.CERTAIN
        store(z, ROUND_OUT, q, cert[1:])
    scatter_round(z, ROUND_OUT, k0, nb, dist, sqr, point, feature, equidistant, height, radial, full)


@part
def _robust_block_one(
    is_disk, C, U, N, R, P, n_j, k0, nb, dist, sqr, point, feature, equidistant, height, radial, exact, full
):
    """:func:`_block` for the robust method and a batch against one shape,
    ``C[0, 0]``, ``U[0, 0]``, ``R[0, 0]``.

    Only the points are gathered (the rows of ``ONE_*``).  The loop reads
    the shape as scalars, so the compiler computes its own terms (such as
    the rim direction used on the axis) once per block instead of once per
    query.
    """
    z = np.empty((ONE_ROWS, BLOCK))
    gather_points(z, ONE_P, P, n_j, k0, nb)
    cx, cy, cz, ux, uy, uz = C[0, 0, 0], C[0, 0, 1], C[0, 0, 2], U[0, 0, 0], U[0, 0, 1], U[0, 0, 2]
    radius = R[0, 0]
    # One loop for each kind, so that each compiles to the work of its kind only.
    if is_disk:
        for q in range(BLOCK):
            px, py, pz = point_at(z, ONE_P, q)
            res, ok = _robust_row(True, cx, cy, cz, ux, uy, uz, radius, px, py, pz)
            store(z, ONE_OUT, q, res)
            z[ONE_OK, q] = ok
    else:
        for q in range(BLOCK):
            px, py, pz = point_at(z, ONE_P, q)
            res, ok = _robust_row(False, cx, cy, cz, ux, uy, uz, radius, px, py, pz)
            store(z, ONE_OUT, q, res)
            z[ONE_OK, q] = ok
    for q in range(nb):
        if z[ONE_OK, q] == 0.0:
            px, py, pz = point_at(z, ONE_P, q)
            # The robust method reads the unit normal only; it stands in for the normal as given.
            res = robust_query(is_disk, cx, cy, cz, ux, uy, uz, ux, uy, uz, radius, px, py, pz)
            store(z, ONE_OUT, q, res[1:])
    scatter_round(z, ONE_OUT, k0, nb, dist, sqr, point, feature, equidistant, height, radial, full)


_BLOCK_SIGNATURE = types.void(
    types.boolean,
    A_IN3,
    A_IN3,
    A_IN3,
    A_IN2,
    A_IN3,
    types.int64,
    types.int64,
    types.int64,
    OUT1,
    OUT1,
    OUT2,
    OUT_FEATURE,
    OUT_FLAG,
    OUT1,
    OUT1,
    OUT_FLAG,
    types.boolean,
)
# The batch loop: the block's address, then the block's arguments but ``k0, nb``.
_BATCH_SIGNATURE = types.void(types.int64, *_BLOCK_SIGNATURE.args[:7], *_BLOCK_SIGNATURE.args[9:])
_block_at = function_at(_BLOCK_SIGNATURE)


def _batch(
    block_address,
    is_disk,
    C,
    U,
    N,
    R,
    P,
    n_j,
    dist,
    sqr,
    point,
    feature,
    equidistant,
    height,
    radial,
    exact,
    full,
):
    """Fill the flat outputs for an ``(I, J)`` loop over broadcast inputs.

    ``C``, ``U`` (unit normals), ``N`` (normals as given) and ``P`` are
    ``(I, J, 3)``, ``R`` is ``(I, J)``, any strides.  With ``full=False``
    only ``dist`` is written.  Blocks of queries go to the threads, each
    handled by the method's block function, called at ``block_address`` (as
    in :func:`proximity.point_triangle._batch`); the certified method flags
    in ``exact`` the rows its filter could not decide.
    """
    n = dist.shape[0]
    block_fn = _block_at(block_address)
    for block in prange((n + BLOCK - 1) // BLOCK):
        k0 = block * BLOCK
        nb = min(BLOCK, n - k0)
        block_fn(
            is_disk, C, U, N, R, P, n_j, k0, nb,
            dist, sqr, point, feature, equidistant, height, radial, exact, full,
        )  # fmt: skip


# Per method: the query of one point, whether it has a SIMD loop (robust),
# whether it has an exact fallback, and a block function for many points
# against one shape (or None: the general one).
KERNELS = {
    "robust": (robust_query, True, False, _robust_block_one),
    "certified": (certified_query, False, True, None),
    "eberly": (eberly_query, False, False, None),
}


def single_kernel(method):
    """The one-query kernel of ``method`` (a :class:`~proximity.methods.Method`),
    compiled for :data:`~proximity._loops.SINGLE_ARGS` by :func:`~proximity._loops.single_entry`."""
    return specialize(_single, method.name, QUERY=KERNELS[method.name][0])


def block_kernel(method, one):
    """The block function of ``method``, called by address; ``one``: for
    many points against one shape."""
    query_, simd, exact_fallback, block_one = KERNELS[method.name]
    if one and block_one is not None:
        func = block_one.py_func
        return specialize(func, func.__name__, _BLOCK_SIGNATURE, role="pointer")
    bindings = dict(QUERY=query_, SIMD=simd, EXACT_FALLBACK=exact_fallback)
    return specialize(_block, method.name, _BLOCK_SIGNATURE, role="pointer", **bindings)


@functools.cache
def batch_kernel(method, one):
    """The compiled batch loop of ``method``, a function of the batch
    arguments; ``one``: every query is against one shape."""
    loop = specialize(_batch, "blocks", _BATCH_SIGNATURE, parallel=True)
    return functools.partial(loop, address(block_kernel(method, one), _BLOCK_SIGNATURE))


def query(method, is_disk, center, unit_normal, normal, radius, points, out_shape, full):
    """Run the batch kernel; inputs are validated float64 arrays."""
    (C, U, N, R, P), n_j = loop_views(
        out_shape, [(center, 1), (unit_normal, 1), (normal, 1), (radius, 0), (points, 1)]
    )
    n = C.shape[0] * C.shape[1]
    m = n if full else 0
    out = dict(
        distance=_pool.empty(n),
        sqr_distance=_pool.empty(m),
        point=_pool.empty((m, 3)),
        feature=_pool.empty(m, np.int8),
        equidistant=_pool.empty(m, np.bool_),
        height=_pool.empty(m),
        radial=_pool.empty(m),
    )
    exact = np.zeros(n if method.exact_fallback else 0, np.bool_)
    one = all(single_shape(view) for view in (C, U, R))
    batch_kernel(method, one)(is_disk, C, U, N, R, P, n_j, *out.values(), exact, full)
    if method.exact_fallback:
        rows = np.flatnonzero(exact)
        for k in rows:
            i, j = divmod(int(k), n_j)
            res = _exact_query(is_disk, C[i, j], U[i, j], N[i, j], R[i, j], P[i, j])
            out["distance"][k] = res[0]
            if full:
                out["sqr_distance"][k], out["point"][k], out["feature"][k] = res[1], res[2:5], res[5]
                out["equidistant"][k], out["height"][k], out["radial"][k] = res[6:9]
        certified.count(n, len(rows))
    return out


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
