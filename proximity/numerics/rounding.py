"""Rounded primitives: ``d - r`` certified, and the nearest point of the rounded surface.

What the rounded shapes (:mod:`proximity.shapes.rounded`) and a collection of
rounded primitives (:mod:`proximity.broadphase`) share.
"""

import math
from fractions import Fraction

import numpy as np

from ..runtime.jit import kernel
from .normals import planar, plane_sides, surface_directions


def total_radius(radii):
    """The radius of a shape rounded by each of ``radii`` in turn (the outermost
    first, as a chain of rounded and posed views holds them), or None for none:
    the sum, inner first, as rounding a rounded shape adds the radii
    (:class:`proximity.Inflated`).  Rounding and posing commute, so a pose
    between two roundings changes nothing."""
    total = None
    for r in reversed(radii):
        total = r if total is None else added_radii(total, r)
    return total


def added_radii(inner, outer):
    """``inner + outer``, the radius of a rounded shape rounded again; a ValueError naming the
    radius where the sum overflows to infinity (each radius is finite)."""
    with np.errstate(over="ignore"):
        total = np.add(inner, outer)
    if not np.isfinite(total).all():
        inner, outer, total = np.broadcast_arrays(inner, outer, total)
        index = tuple(int(i) for i in np.argwhere(~np.isfinite(total))[0])
        raise ValueError(
            f"radius must be finite: rounding a shape of radius {inner[index]} by {outer[index]} gives "
            f"{total[index]} at index {index}"
        )
    return total


def certify_difference(e, d, r, exact_rows):
    """``e = d - r`` where it is faithful for the exact ``d* - r`` (``d``
    faithful), else the exact fallback's value; ``exact_rows(flat rows)``
    gives ``(primitive, params, point)`` for each of those rows (the
    nearest primitive's kind and stored row, and the query point).

    ``d*`` is within ``spacing(d)`` of ``d`` (0 exactly where ``d`` is 0:
    the certified method gives 0 only on the shape), and ``d - r`` is ``e``
    plus the subtraction's error, exactly (Knuth's TwoSum), so ``d* - r``
    is within ``|err| + spacing(d)`` of ``e``: ``e`` is faithful where that
    is less than half the spacing at ``e``, the nearer neighbour's distance
    at most.
    """
    bad = unfaithful(e, d, r)
    if len(bad) == 0:
        return e
    from . import exact  # in Python: no compiled code

    e = np.array(e, dtype=np.float64, copy=True)
    flat = e.reshape(-1)
    radii = np.broadcast_to(r, e.shape).reshape(-1)
    for k, (primitive, params, point) in zip(bad, exact_rows(bad), strict=True):
        bounds = primitive.kernels.exact_sqr_bounds(primitive.code, params, point)
        flat[k] = exact.minus_radius(bounds, Fraction(float(radii[k])))
    return e


def unfaithful(e, d, r):
    """The flat rows where ``e = d - r`` is not known to be faithful for
    ``d* - r`` (see :func:`certify_difference`)."""
    with np.errstate(invalid="ignore", over="ignore"):
        back = e - d
        err = (d - (e - back)) + (-r - back)
        u = np.where(d == 0, 0.0, np.spacing(d))
        gap = np.where(e == 0, 2.0**-1074, np.spacing(np.abs(e)) * 0.5)
        ok = (np.abs(err) + u) * (1.0 + 2.0**-50) < gap
    return np.flatnonzero(~ok.reshape(-1) & np.isfinite(e).reshape(-1))


def surface_points(p, c, d, r, rows_of):
    """The nearest point of the rounded surface to each query point ``p``:
    from the core's closest point ``c`` (at distance ``d``) towards ``p`` by
    ``r``; or, where ``p`` is so near the core that the direction of ``p -
    c`` is lost in the rounding of ``c`` (``d^2 < 64 r eps M``, ``M`` the
    coordinates' magnitude), along the core's normal on ``p``'s side
    (``rows_of(flat rows) -> (kinds, params)`` gives the primitives there).
    That point is on the surface, and within ``2 d`` of the nearest one."""
    dim = p.shape[-1]
    if dim == 3:
        shape = np.broadcast_shapes(p.shape, c.shape, d.shape + (3,), np.shape(r) + (3,))
        point, lost = np.empty(shape), np.empty(shape[:-1], np.bool_)
        rows3 = lambda x: np.ascontiguousarray(np.broadcast_to(x, shape), np.float64).reshape(-1, 3)  # noqa: E731
        rows1 = lambda x: np.ascontiguousarray(np.broadcast_to(x, shape[:-1]), np.float64).reshape(-1)  # noqa: E731
        surface_rows(rows3(p), rows3(c), rows1(d), rows1(r), point.reshape(-1, 3), lost.reshape(-1))
    else:
        point, lost = surface_numpy(p, c, d, r)
    return _lost_rows(point, lost, p, c, d, r, rows_of, dim)


def surface_numpy(p, c, d, r):
    """``(point, lost)`` of :func:`surface_points` before its lost rows are placed, in NumPy
    (any dimension; :func:`surface_rows` gives the same bits for 3D rows)."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # Along P - c normalised by its own length, not by d: an error of c
        # across the surface then moves the point by as much, where r / d
        # times as much would if the two lengths differed by it.
        v = p - c
        v = v / np.max(np.abs(v), axis=-1, keepdims=True)
        v = v / np.linalg.norm(v, axis=-1, keepdims=True)
        # Where P - c rounds to 0 (P on the core but for rounding), no direction.
        point = np.where((r == 0)[..., None] | (p == c).all(axis=-1)[..., None], c, c + v * r[..., None])
        m = np.maximum(np.maximum(np.max(np.abs(c), axis=-1), np.max(np.abs(p), axis=-1)), r)
        lost = (d < r) & ((d / m) ** 2 < 64.0 * 2.0**-52 * (r / m))
    return point, lost


@kernel()
def surface_rows(p, c, d, r, point, lost):
    """:func:`surface_points` of 3D rows, the same operations in the same order (so the same
    bits) as its NumPy form, row by row; ``lost`` marks the rows it leaves to the core's normal."""
    for i in range(p.shape[0]):
        c0, c1, c2 = c[i, 0], c[i, 1], c[i, 2]
        p0, p1, p2 = p[i, 0], p[i, 1], p[i, 2]
        radius, di = r[i], d[i]
        m = max(max(max(abs(c0), abs(c1)), abs(c2)), max(max(abs(p0), abs(p1)), abs(p2)))
        m = max(m, radius)
        if c0 != c0 or c1 != c1 or c2 != c2 or p0 != p0 or p1 != p1 or p2 != p2 or radius != radius:
            m = np.nan  # as NumPy's maximum, which a NaN wins
        lost[i] = di < radius and (di / m) * (di / m) < 64.0 * 2.0**-52 * (radius / m)
        if radius == 0.0 or (p0 == c0 and p1 == c1 and p2 == c2):
            point[i, 0], point[i, 1], point[i, 2] = c0, c1, c2
            continue
        v0, v1, v2 = p0 - c0, p1 - c1, p2 - c2
        top = max(max(abs(v0), abs(v1)), abs(v2))
        if v0 != v0 or v1 != v1 or v2 != v2:
            top = np.nan  # as NumPy's max, which a NaN wins
        v0, v1, v2 = v0 / top, v1 / top, v2 / top
        length = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        v0, v1, v2 = v0 / length, v1 / length, v2 / length
        point[i, 0], point[i, 1], point[i, 2] = c0 + v0 * radius, c1 + v1 * radius, c2 + v2 * radius


def _lost_rows(point, lost, p, c, d, r, rows_of, dim):
    """``point`` with the ``lost`` rows put along the core's normal on ``p``'s side."""
    rows = np.flatnonzero(lost.reshape(-1))
    if len(rows):
        flat_p, flat_c = p.reshape(-1, dim)[rows], c.reshape(-1, dim)[rows]
        kinds, params = rows_of(rows)
        u = surface_directions(kinds, params)[:, :dim]
        # A plane's side exactly (as the core's normal takes it: the two agree), the
        # side of u that P - c rounds to for the rest.
        side = plane_sides(kinds, params, _to_3d(flat_p)).astype(np.float64)
        loose = ~planar(kinds)
        side[loose] = np.where(np.einsum("ij,ij->i", flat_p[loose] - flat_c[loose], u[loose]) < 0, -1.0, 1.0)
        side[side == 0] = 1.0
        point = np.array(point, copy=True)
        radius = np.broadcast_to(r, d.shape).reshape(-1)[rows]
        point.reshape(-1, dim)[rows] = flat_c + (radius * side)[:, None] * u
    return point


def spindle_points(point, normal, d, r, circle, result):
    """``(point, normal)`` with the rows fixed where a circle of radius ``R``
    rounded by ``r > R`` (a spindle torus) has its nearest surface point on
    the axis.

    In the circle's meridian plane the point is at ``(radial, height)`` and
    its nearest circle point at ``(R, 0)``; the surface point ``r`` from it
    towards the point is at radial ``R + r (radial - R) / d``.  Where that is
    negative, the ray has crossed the axis (the circle's medial axis) into
    the balls of the circle's other side, and the nearest point of the
    surface is the cusp where it meets the axis: ``center + sign(height)
    sqrt(r^2 - R^2) u`` (``u`` the unit axis), outward normal ``sign(height)
    u``.  ``circle`` is the core (a :class:`proximity.Circle` batch) and
    ``result`` its answer.
    """
    shape = d.shape
    big_r = np.broadcast_to(circle.radius, shape)
    radial = np.broadcast_to(np.asarray(result.radial), shape)
    height = np.broadcast_to(np.asarray(result.height), shape)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # r > R holds wherever the rest does, but for the rounding of R - radial.
        crossed = (r > big_r) & (radial < big_r) & ((r / d) * (big_r - radial) > big_r)
    if not crossed.any():
        return point, normal
    rows = crossed
    axis = np.broadcast_to(circle.normal, shape + (3,))[rows]
    axis = axis / np.max(np.abs(axis), axis=-1, keepdims=True)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    side = np.where(height[rows] < 0, -1.0, 1.0)[:, None]
    ratio = big_r[rows] / r[rows]
    # sqrt(r^2 - R^2) without squaring r, which underflows or overflows at extreme scales.
    z = r[rows] * np.sqrt((1.0 - ratio) * (1.0 + ratio))
    point, normal = np.array(point, copy=True), np.array(normal, copy=True)
    point[rows] = np.broadcast_to(circle.center, shape + (3,))[rows] + side * z[:, None] * axis
    normal[rows] = side * axis
    return point, normal


def outward(surface, core, radius, fallback, face):
    """The outward unit normal of a rounded surface at ``surface``, a point
    ``radius`` from its core's closest point ``core``: ``(surface - core) / r``,
    normalised; ``fallback`` (the core's normals) where the radius is 0 and
    where the core's closest point is on a face (``face``, boolean): there
    the surface is the face's plane moved by ``r``, whose normal is the
    face's, towards the point (the core's normal, as the point query gives
    it), and ``surface - core`` holds the rounding of ``core`` besides."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        v = surface - core
        scale = np.max(np.abs(v), axis=-1, keepdims=True)
        v = v / np.where(scale > 0, scale, 1.0)
        n = v / np.linalg.norm(v, axis=-1, keepdims=True)
    r = np.broadcast_to(radius, n.shape[:-1])
    keep = (r == 0) | np.broadcast_to(face, n.shape[:-1])
    return np.where(keep[..., None], fallback, n)


def _to_3d(points):
    if points.shape[-1] == 3:
        return points
    return np.concatenate([points, np.zeros(points.shape[:-1] + (3 - points.shape[-1],))], axis=-1)
