"""Rounded primitives: ``d - r`` certified, and the nearest point of the rounded surface.

What the rounded shapes (:mod:`proximity.shapes.rounded`) and a collection of
rounded primitives (:mod:`proximity.broadphase`) share.
"""

from fractions import Fraction

import numpy as np

from .. import primitives


def total_radius(radii):
    """The radius of a shape rounded by each of ``radii`` in turn (the outermost
    first, as a chain of rounded and posed views holds them), or None for none:
    the sum, inner first, as rounding a rounded shape adds the radii
    (:class:`proximity.Inflated`).  Rounding and posing commute, so a pose
    between two roundings changes nothing."""
    total = None
    for r in reversed(radii):
        total = r if total is None else total + r
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
    rows = np.flatnonzero(lost.reshape(-1))
    if len(rows):
        flat_p, flat_c = p.reshape(-1, dim)[rows], c.reshape(-1, dim)[rows]
        u = surface_directions(*rows_of(rows))[:, :dim]
        side = np.where(np.einsum("ij,ij->i", flat_p - flat_c, u) < 0, -1.0, 1.0)
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


def surface_directions(kinds, params):
    """A unit vector normal to each primitive at every point of it, ``(n, 3)``:
    along which a point on the primitive reaches the rounded surface.

    A triangle's plane normal; a segment's (or a zero-area triangle's
    longest edge's) perpendicular with the smallest component along the
    coordinate axis least aligned with it; a point's ``+z``; a disk's and a
    circle's axis.
    """
    out = np.zeros((len(kinds), 3))
    out[:, 2] = 1.0
    for p in primitives.BY_CODE:
        rows = np.flatnonzero(kinds == p.code)
        if len(rows) == 0:
            continue
        q = params[rows]
        if p.axis is not None:
            n = q[:, p.axis : p.axis + 3]
        elif p.vertices >= 2:
            v = q[:, : 3 * p.vertices].reshape(-1, p.vertices, 3)
            # Differences in units of their largest (so that no product underflows or overflows).
            v = v - v[:, :1]
            size = np.max(np.abs(v), axis=(1, 2), keepdims=True)
            v = v / np.where(size > 0, size, 1.0)
            edges = v - np.roll(v, 1, axis=1)
            longest = edges[np.arange(len(v)), np.argmax(np.linalg.norm(edges, axis=2), axis=1)]
            n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]) if p.vertices == 3 else np.zeros_like(longest)
            flat = np.linalg.norm(n, axis=1) == 0
            axis = np.eye(3)[np.argmin(np.abs(longest), axis=1)]
            n = np.where(flat[:, None], np.cross(longest, axis), n)
        else:
            continue
        length = np.linalg.norm(n, axis=1, keepdims=True)
        good = (length[:, 0] > 0) & np.isfinite(length[:, 0])
        out[rows[good]] = n[good] / length[good]
    return out



def outward(surface, core, radius, fallback):
    """The outward unit normal of a rounded surface at ``surface``, a point
    ``radius`` from its core's closest point ``core``: ``(surface - core) / r``,
    normalised; ``fallback`` (the core's normals) where the radius is 0."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        v = surface - core
        scale = np.max(np.abs(v), axis=-1, keepdims=True)
        v = v / np.where(scale > 0, scale, 1.0)
        n = v / np.linalg.norm(v, axis=-1, keepdims=True)
    r = np.broadcast_to(radius, n.shape[:-1])[..., None]
    return np.where(r > 0, n, fallback)
