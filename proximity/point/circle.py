"""Distance between a point and a circle in 3D.

Implements Section 1 of D. Eberly, *Distance Between Point and Circle or Disk
in 3D* (Geometric Tools, 1998, rev. 2008).  The circle has center ``C``, unit
normal ``N`` and radius ``R``; ``Q`` is the projection of ``P`` onto the
circle's plane.  The closest point is ``X = C + R (Q - C) / |Q - C|``, and
when ``Q == C`` every circle point is closest, at distance
``sqrt(R^2 + |P - C|^2)``.

Two methods:

``eberly``
    The section as written: ``Q``, then ``X``, then ``|P - X|``, with the
    normal normalised as ``N / |N|``.  It is the baseline.  It loses the
    distance to cancellation when ``P`` and ``X`` are large absolute points
    close together (offset circles), returns NaN where ``|N|^2`` or
    ``|Q - C|^2`` over- or underflows, and near the axis takes the direction
    of ``Q - C`` from rounding noise.

``robust``
    The distance is not taken as ``|P - X|`` but from the decomposition of
    ``D = P - C`` into a height ``h = N . D`` and a radial part
    ``Q - C = D - h N`` of length ``q``: ``d = sqrt(h^2 + (q - R)^2)``.  Each
    term has an absolute error of a few ``eps * (|D| + R)``, and ``d`` is
    1-Lipschitz in ``q``, so near the axis, where the direction of ``Q - C``
    is lost to rounding, the distance is still accurate.  Differences whose
    size lies outside ``[2^-64, 2^64]`` are scaled by a power of two first,
    so ``h^2`` and ``(q - R)^2`` neither overflow nor underflow.  That
    scaling is set by the larger of ``|D|`` and ``R``, and ``q`` can be far
    smaller: below ``2^-511`` in that frame (a point about
    ``2^-511 (|D| + R)`` from the axis, off it by more than rounding),
    ``q^2`` is subnormal, which costs the distance nothing but would make
    ``(Q - C) / q``, the direction of the rim point, longer or shorter than
    a unit vector; there ``q`` is measured again from ``Q - C`` scaled up by
    a power of two.  Normals of any length are normalised once, at
    construction, the same way.  The result satisfies
    ``|d - d*| <= 8 eps (|P - C| + R) + 2^-1075``; the
    absolute term is the rounding of a subnormal distance.
"""

import math

from ..numerics.fp import EPS, SAFE_MAX, SAFE_MIN, UNSCALED, pow2_scale, unscale
from ..runtime.jit import inline

# The radial part is the difference of two vectors of length up to |D|; below
# this multiple of eps * |D| its direction is rounding noise.
AXIS_TOLERANCE = 8.0 * EPS
# Below this length the radial part's square is subnormal and its length has
# lost bits, which would put the rim point off the circle: it is measured again
# from its components times LIFT.
Q_MIN = 2.0**-511
LIFT = 2.0**600


@inline
def window(dx, dy, dz, r):
    """Largest of the differences and the radius, and whether it is in the safe window."""
    m = max(max(abs(dx), abs(dy)), max(abs(dz), r))
    return m, (m >= SAFE_MIN) & (m <= SAFE_MAX)


@inline
def decompose_local(dx, dy, dz, ux, uy, uz):
    """Height and radial part of ``D = P - C``, for ``D`` in the safe window.

    Returns ``(h, qx, qy, qz, q, on_axis)`` where ``on_axis`` says whether
    ``q`` is within its rounding error of zero.
    """
    h = ux * dx + uy * dy + uz * dz
    qx, qy, qz = dx - h * ux, dy - h * uy, dz - h * uz
    # The subtraction leaves a component along N of up to eps * |h|; near the
    # axis that is a large part of Q - C and would tilt the rim direction out
    # of the plane, so remove it once more.
    c = ux * qx + uy * qy + uz * qz
    qx, qy, qz = qx - c * ux, qy - c * uy, qz - c * uz
    q = math.sqrt(qx * qx + qy * qy + qz * qz)
    on_axis = q <= AXIS_TOLERANCE * math.sqrt(dx * dx + dy * dy + dz * dz)
    return h, qx, qy, qz, q, on_axis


@inline
def decompose(cx, cy, cz, ux, uy, uz, r, px, py, pz):
    """:func:`decompose_local` for any finite input, in a scaled frame.

    Returns ``(h, qx, qy, qz, q, on_axis, r, g)``: lengths are multiplied by
    a power of two chosen so that no squared term over- or underflows, which
    :func:`~proximity.numerics.fp.unscale` with ``g`` undoes.
    """
    dx, dy, dz = px - cx, py - cy, pz - cz
    m, _ = window(dx, dy, dz, r)
    g = UNSCALED
    if m > 1.7e308:
        # A difference of two finite coordinates overflowed: quarter first.
        dx, dy, dz = px * 0.25 - cx * 0.25, py * 0.25 - cy * 0.25, pz * 0.25 - cz * 0.25
        r = r * 0.25
        m, _ = window(dx, dy, dz, r)
        g = (4.0, 4.0, 1.0)
    if m < SAFE_MIN or m > SAFE_MAX:
        f1, f2 = pow2_scale(m)
        dx, dy, dz, r = dx * f1 * f2, dy * f1 * f2, dz * f1 * f2, r * f1 * f2
        g = (g[0] / f1 / f2, g[1] / f1, 1.0 / f2)
    h, qx, qy, qz, q, on_axis = decompose_local(dx, dy, dz, ux, uy, uz)
    if short_radial(q, on_axis):
        q = remeasure(qx, qy, qz)
    return h, qx, qy, qz, q, on_axis, r, g


@inline
def short_radial(q, on_axis):
    """Whether the length ``q`` of the radial part lost bits to underflow:
    then :func:`rim_direction`'s ``Q - C`` over ``q`` is not a unit vector.
    On the axis the direction is not taken from ``Q - C``."""
    return (q < Q_MIN) & (not on_axis)


@inline
def remeasure(qx, qy, qz):
    """``|Q - C|`` from its components times :data:`LIFT`, for a radial part
    that :func:`short_radial` flags.

    The lift is exact and makes the squares normal floats.  Off the axis some
    component's square did not underflow to zero (else ``q`` would be zero
    and on the axis), so the length is at least ``2^-538`` and shortening it
    again is exact too.
    """
    qx, qy, qz = qx * LIFT, qy * LIFT, qz * LIFT
    return math.sqrt(qx * qx + qy * qy + qz * qz) / LIFT


@inline
def rim_direction(ux, uy, uz, qx, qy, qz, q, on_axis):
    """Unit vector from the center towards the closest rim point.

    On the axis any direction in the plane is closest; a fixed one is chosen,
    perpendicular to the normal's smallest component, so that the answer does
    not depend on rounding noise.
    """
    ax, ay, az = abs(ux), abs(uy), abs(uz)
    x_least = (ax <= ay) & (ax <= az)
    y_least = (not x_least) & (ay <= az)
    wx = 0.0 if x_least else (-uz if y_least else uy)
    wy = uz if x_least else (0.0 if y_least else -ux)
    wz = -uy if x_least else (ux if y_least else 0.0)
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    q = max(q, 5e-324)
    return (
        wx / w if on_axis else qx / q,
        wy / w if on_axis else qy / q,
        wz / w if on_axis else qz / q,
    )


@inline
def rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, on_axis, r, g):
    """Closest rim point from a decomposition: ``(distance, sqr, x, y, z)``."""
    wx, wy, wz = rim_direction(ux, uy, uz, qx, qy, qz, q, on_axis)
    dr = q - r
    sqr = h * h + dr * dr
    return (
        unscale(math.sqrt(sqr), g),
        unscale(unscale(sqr, g), g),
        cx + radius * wx,
        cy + radius * wy,
        cz + radius * wz,
    )


@inline
def circle(cx, cy, cz, ux, uy, uz, radius, px, py, pz):
    """Robust point-circle query for any finite input.

    Returns ``(distance, sqr_distance, x, y, z, equidistant, height, radial)``.
    """
    h, qx, qy, qz, q, on_axis, r, g = decompose(cx, cy, cz, ux, uy, uz, radius, px, py, pz)
    d, sqr, x, y, z = rim(cx, cy, cz, ux, uy, uz, radius, h, qx, qy, qz, q, on_axis, r, g)
    return d, sqr, x, y, z, on_axis, unscale(h, g), unscale(q, g)


@inline
def eberly_projection(cx, cy, cz, nx, ny, nz, px, py, pz):
    """Eberly's ``N`` (normalised as given) and ``Q - C``, as written in his document."""
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    nx, ny, nz = nx / length, ny / length, nz / length
    h = nx * (px - cx) + ny * (py - cy) + nz * (pz - cz)
    qx, qy, qz = px - h * nx - cx, py - h * ny - cy, pz - h * nz - cz
    return nx, ny, nz, h, qx, qy, qz, math.sqrt(qx * qx + qy * qy + qz * qz)


@inline
def eberly_circle(cx, cy, cz, nx, ny, nz, radius, px, py, pz):
    """Section 1 as written; same return as :func:`circle`."""
    nx, ny, nz, h, qx, qy, qz, q = eberly_projection(cx, cy, cz, nx, ny, nz, px, py, pz)
    on_axis = q == 0.0
    dx, dy, dz = px - cx, py - cy, pz - cz
    x = cx + radius * qx / q
    y = cy + radius * qy / q
    z = cz + radius * qz / q
    sqr = (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2
    if on_axis:
        sqr = radius * radius + dx * dx + dy * dy + dz * dz
    return math.sqrt(sqr), sqr, x, y, z, on_axis, h, q
