"""Distance between a point and a disk in 3D.

Implements Section 2 of D. Eberly, *Distance Between Point and Circle or Disk
in 3D*: if the projection ``Q`` of ``P`` onto the disk's plane lies in the
disk it is the closest point, otherwise the closest point is on the rim, a
circle.  It reuses the height/radial decomposition of :mod:`.point_circle`,
so the same error bound holds; a point whose radial distance is within
rounding of ``R`` can be classified either way at a cost below that bound.

The batch kernel here serves circles too: a circle query is a disk query that
always takes the rim branch.
"""

import math

import numpy as np
from numba import njit, prange
from numba.core import types

from ._loops import A_IN2, A_IN3, OUT1, OUT2, OUT_FEATURE, OUT_FLAG, loop_views
from .point_circle import circle, decompose, rim
from .results import Feature

NONE = int(Feature.NONE)
FACE = int(Feature.FACE)
RIM = int(Feature.RIM)


@njit(inline="always")
def disk(cx, cy, cz, ux, uy, uz, radius, px, py, pz):
    """Point-disk query.

    Returns ``(distance, sqr_distance, x, y, z, feature, height, radial)``.
    """
    h, qx, qy, qz, q, r, g, on_axis = decompose(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
    if q <= r:
        return abs(h) * g, h * h * g * g, cx + qx * g, cy + qy * g, cz + qz * g, FACE, h * g, q * g
    d, sqr, x, y, z = rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, r, g, on_axis)
    return d, sqr, x, y, z, RIM, h * g, q * g


_SIGNATURE = types.void(
    types.boolean, A_IN3, A_IN3, A_IN2, A_IN3, types.int64,
    OUT1, OUT1, OUT2, OUT_FEATURE, OUT_FLAG, OUT1, OUT1, types.boolean,
)


@njit(_SIGNATURE, parallel=True, cache=True)
def _batch(is_disk, C, U, R, P, n_j, dist, sqr, point, feature, equidistant, height, radial, full):
    """Fill the flat outputs for an ``(I, J)`` loop over broadcast inputs.

    ``C``, ``U`` (unit normals) and ``P`` are ``(I, J, 3)``, ``R`` is
    ``(I, J)``, any strides.  With ``full=False`` only ``dist`` is written.
    """
    for k in prange(dist.shape[0]):
        i = k // n_j
        j = k - i * n_j
        px, py, pz = P[i, j, 0], P[i, j, 1], P[i, j, 2]
        if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
            dist[k] = math.nan
            if full:
                sqr[k] = point[k, 0] = point[k, 1] = point[k, 2] = math.nan
                height[k] = radial[k] = math.nan
                feature[k] = NONE
                equidistant[k] = False
            continue
        cx, cy, cz = C[i, j, 0], C[i, j, 1], C[i, j, 2]
        ux, uy, uz = U[i, j, 0], U[i, j, 1], U[i, j, 2]
        if is_disk:
            d, s, x, y, z, f, h, q = disk(cx, cy, cz, ux, uy, uz, R[i, j], px, py, pz)
            e = False
        else:
            d, s, x, y, z, e, h, q = circle(cx, cy, cz, ux, uy, uz, R[i, j], px, py, pz)
            f = RIM
        dist[k] = d
        if full:
            sqr[k] = s
            point[k, 0] = x
            point[k, 1] = y
            point[k, 2] = z
            feature[k] = f
            equidistant[k] = e
            height[k] = h
            radial[k] = q


def query(is_disk, center, unit_normal, radius, points, out_shape, full):
    """Run the batch kernel; inputs are validated float64 arrays."""
    (C, U, R, P), n_j = loop_views(
        out_shape, [(center, 1), (unit_normal, 1), (radius, 0), (points, 1)]
    )
    n = C.shape[0] * C.shape[1]
    m = n if full else 0
    out = dict(
        distance=np.empty(n),
        sqr_distance=np.empty(m),
        point=np.empty((m, 3)),
        feature=np.empty(m, np.int8),
        equidistant=np.empty(m, np.bool_),
        height=np.empty(m),
        radial=np.empty(m),
    )
    _batch(is_disk, C, U, R, P, n_j, *out.values(), full)
    return out
