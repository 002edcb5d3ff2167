"""Distance between a point and a circle in 3D.

Implements Section 1 of D. Eberly, *Distance Between Point and Circle or Disk
in 3D* (Geometric Tools, 1998, rev. 2008).  The circle has center ``C``, unit
normal ``N`` and radius ``R``; ``Q`` is the projection of ``P`` onto the
circle's plane.  The closest point is ``X = C + R (Q - C) / |Q - C|``, and
when ``Q == C`` every circle point is closest, at distance
``sqrt(R^2 + |P - C|^2)``.

Robustness
----------
The distance is not taken as ``|P - X|``, which subtracts two absolute
points, but from the decomposition of ``D = P - C`` into a height
``h = N . D`` and a radial part ``Q - C = D - h N`` of length ``q``:
``d = sqrt(h^2 + (q - R)^2)``.  Each term has an absolute error of a few
``eps * (|D| + R)``, and ``d`` is 1-Lipschitz in ``q``, so near the axis,
where the direction of ``Q - C`` is lost to rounding, the distance is still
accurate.  Differences whose size lies outside ``[2^-64, 2^64]`` are scaled
by a power of two first, so ``h^2`` and ``(q - R)^2`` neither overflow nor
underflow.  Normals of any length are normalised once, at construction.
"""

import math

from numba import njit

from ._fp import EPS, SAFE_MAX, SAFE_MIN, pow2_scale

# The radial part is the difference of two vectors of length up to |D|; below
# this multiple of eps * |D| its direction is rounding noise.
AXIS_TOLERANCE = 8.0 * EPS


@njit(inline="always")
def decompose(cx, cy, cz, ux, uy, uz, r, px, py, pz):
    """Height and radial part of ``P - C`` in a scaled frame.

    Returns ``(h, qx, qy, qz, q, r, g, on_axis)``: everything but ``g`` is
    multiplied by a power of two ``1 / g`` chosen so that no squared term
    over- or underflows, and ``on_axis`` says whether ``q`` is within its
    rounding error of zero.
    """
    dx, dy, dz = px - cx, py - cy, pz - cz
    m = max(abs(dx), abs(dy), abs(dz), r)
    g = 1.0
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        dx, dy, dz = px * 0.25 - cx * 0.25, py * 0.25 - cy * 0.25, pz * 0.25 - cz * 0.25
        r = r * 0.25
        m = max(abs(dx), abs(dy), abs(dz), r)
        g = 4.0
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        dx, dy, dz, r = dx * f1 * f2, dy * f1 * f2, dz * f1 * f2, r * f1 * f2
        g = g / f1 / f2
    h = ux * dx + uy * dy + uz * dz
    qx, qy, qz = dx - h * ux, dy - h * uy, dz - h * uz
    q = math.sqrt(qx * qx + qy * qy + qz * qz)
    on_axis = q <= AXIS_TOLERANCE * math.sqrt(dx * dx + dy * dy + dz * dz)
    return h, qx, qy, qz, q, r, g, on_axis


@njit(inline="always")
def rim_direction(ux, uy, uz, qx, qy, qz, q, on_axis):
    """Unit vector from the center towards the closest rim point.

    On the axis any direction in the plane is closest; a fixed one is chosen,
    perpendicular to the normal's smallest component, so that the answer does
    not depend on rounding noise.
    """
    if not on_axis:
        return qx / q, qy / q, qz / q
    ax, ay, az = abs(ux), abs(uy), abs(uz)
    if ax <= ay and ax <= az:
        wx, wy, wz = 0.0, uz, -uy
    elif ay <= az:
        wx, wy, wz = -uz, 0.0, ux
    else:
        wx, wy, wz = uy, -ux, 0.0
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    return wx / w, wy / w, wz / w


@njit(inline="always")
def rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, r, g, on_axis):
    """Closest rim point from a decomposition; ``(distance, sqr, x, y, z)``."""
    wx, wy, wz = rim_direction(ux, uy, uz, qx, qy, qz, q, on_axis)
    dr = q - r
    sqr = h * h + dr * dr
    return math.sqrt(sqr) * g, sqr * g * g, cx + radius * wx, cy + radius * wy, cz + radius * wz


@njit(inline="always")
def circle(cx, cy, cz, ux, uy, uz, radius, px, py, pz):
    """Point-circle query.

    Returns ``(distance, sqr_distance, x, y, z, equidistant, height, radial)``.
    """
    h, qx, qy, qz, q, r, g, on_axis = decompose(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
    d, sqr, x, y, z = rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, r, g, on_axis)
    return d, sqr, x, y, z, on_axis, h * g, q * g
