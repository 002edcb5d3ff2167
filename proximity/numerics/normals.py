"""The normals of the answers: ``Result.normal`` and ``PairResult.normal``.

A normal is ``(P - point) / distance`` where that has a direction.  Where
the distance is within the rounding of the coordinates it has none, and the
normal comes from the feature the closest point is on: a face's normal, on
the query point's side of the face's plane decided exactly (the orientation
predicates of :mod:`proximity.numerics.orient`), and the shape's own normal on an
edge or a vertex (a mesh's pseudonormal).  A face's normal is taken at every
distance, as the closest point's difference from the query point is along
it.  ``docs/accuracy.md`` states the definition for every shape.
"""

from fractions import Fraction

import numpy as np

from .. import primitives
from ..features import FACE
from ..runtime import lazy
from .rigid import rotate, to_local, to_world

#: Below this many ``eps`` times the magnitude of the coordinates, a distance
#: is taken for rounding, and ``P - point`` for no direction.  The ``robust``
#: contract puts the closest point within ``8 eps S`` of the shape (and
#: ``|P - point|`` within as much of the distance), plus ``eps |point|`` of
#: its own rounding; ``S`` (``max |P - V|`` for a hull, ``|P - C| + R`` for a
#: circle or a disk) is at most ``4 sqrt(3) M`` for ``M`` the largest
#: coordinate magnitude of the point and of the nearest primitive's points
#: (vertices; center and radius), so the point's error is below ``57 eps M``.
#: Below 64 of it, ``P - point`` may be that error alone; above, the error of
#: its direction falls as the distance grows.
ROUNDING = 64.0
_EPS = 2.0**-52


def surface_directions(kinds, params):
    """A unit vector normal to each primitive at every point of it, ``(n, 3)``:
    along which a point on the primitive reaches the rounded surface.

    A triangle's plane normal, ``(V1 - V0) x (V2 - V0)``; a segment's (or a
    zero-area triangle's longest edge's) perpendicular with the smallest
    component along the coordinate axis least aligned with it; a point's
    ``+z``; a disk's and a circle's axis (along its normal as given).
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


def query_normals(result, points, members, shape, floor=None):
    """The normals of a query's rows (see :attr:`proximity.Result.normal`); ``floor``
    (broadcasting to the batch), a magnitude below which the rounding of the
    coordinates is not taken."""
    point = np.asarray(result.point)
    dim = point.shape[-1]
    batch = point.shape[:-1]
    points = np.broadcast_to(np.asarray(points, dtype=np.float64)[..., :dim], point.shape).reshape(-1, dim)
    distance = np.broadcast_to(np.asarray(result.distance), batch).reshape(-1)
    feature = np.broadcast_to(np.asarray(result.feature), batch).reshape(-1)
    index = np.broadcast_to(shape._elements(result, members), batch).reshape(-1)
    if floor is not None:
        floor = np.broadcast_to(floor, batch).reshape(-1)
    normal = normals_at(points, point.reshape(-1, dim), distance, feature, index, shape, floor)
    return normal.reshape(point.shape)


def frame_normals(query, core, rotation, points, translation):
    """A posed view's normals: the shape's, from its result ``core`` (and its
    ``query``, or None where ``core`` has its normals already), the rounding
    taken at the magnitude of the world's ``points`` and the pose's
    ``translation`` (the move to the shape's frame rounds by as much), turned
    by ``rotation``."""
    if query is None:
        return rotate(np.asarray(core.normal), rotation)
    batch = np.shape(core.distance)
    world = np.max(np.abs(np.broadcast_to(points, batch + (3,))), axis=-1)
    floor = np.maximum(world, np.max(np.abs(translation)))
    return rotate(query_normals(core, *query, floor=floor), rotation)


def normals_at(points, point, distance, feature, index, shape, floor=None):
    """The normals of flat rows ``(n, D)``: ``(P - point) / distance`` off the
    shape, and the shape's normal on its ``feature`` of element ``index`` at a
    face and within rounding of the rest (the coordinates' magnitude taken as
    at least ``floor``, ``(n,)``, where given).

    ``shape`` gives the elements of a result's rows (``_elements(result,
    members)``: batch members, faces or primitives), their primitives' rows
    (``_feature_rows(index)``) and its normals on them
    (``_feature_normals(index, feature, points)``: at a face, towards the
    point's side, the face's own orientation where the point is NaN).
    """
    dim = point.shape[-1]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        normal = (points - point) / distance[:, None]
        # Where the difference's squares overflow or underflow, a scaled unit vector.
        length = np.linalg.norm(normal, axis=-1)
        off = np.isfinite(distance) & (distance > 0) & ~(np.abs(length - 1.0) < 1e-6)
        if off.any():
            v = (points - point)[off]
            v = v / np.max(np.abs(v), axis=-1, keepdims=True)
            normal[off] = v / np.linalg.norm(v, axis=-1, keepdims=True)
    finite = np.isfinite(distance)
    face = finite & (feature == FACE)
    rest = np.flatnonzero(finite & ~face)
    if len(rest):
        m = np.maximum(np.max(np.abs(points[rest]), axis=1), np.max(np.abs(point[rest]), axis=1))
        m = np.maximum(m, row_magnitudes(*shape._feature_rows(index[rest])))
        if floor is not None:
            m = np.maximum(m, floor[rest])
        with np.errstate(invalid="ignore", over="ignore"):
            near = (distance[rest] <= ROUNDING * _EPS * m) | ~np.isfinite(normal[rest]).all(axis=1)
        rest = rest[near]
    asked = np.union1d(np.flatnonzero(face), rest)
    if len(asked):
        p3 = points[asked]
        if dim < 3:
            p3 = np.concatenate([p3, np.zeros((len(asked), 3 - dim))], axis=1)
        # On the shape, no side: NaN points take the face's own orientation.
        p3 = np.where((distance[asked] == 0)[:, None], np.nan, p3)
        normal[asked] = shape._feature_normals(index[asked], feature[asked], p3)[:, :dim]
    return normal


def feature_normals(kinds, params, feature, points):
    """Each primitive's unit normal at a closest point on its ``feature``
    to ``points`` (``(n, 3)``), in the primitive's frame: on a face (a
    triangle's, a disk's), the face's normal (:func:`surface_directions`)
    towards the point's side of its plane, decided exactly, and as the
    face's own orientation where the point lies on the plane or is NaN;
    elsewhere :func:`surface_directions`."""
    normal = surface_directions(kinds, params)
    face = np.flatnonzero(np.asarray(feature) == FACE)
    if len(face):
        side = plane_sides(kinds[face], params[face], points[face])
        flip = face[side < 0]
        normal[flip] = 0.0 - normal[flip]  # not -n: 0.0 - 0.0 is 0.0, where -0.0 would show
    return normal


def row_magnitudes(kinds, params):
    """The largest coordinate magnitude of each primitive's points (its
    vertices, a disk's or a circle's center, with its radius): ``(n,)``."""
    out = np.zeros(len(kinds))
    for p in primitives.present(kinds):
        rows = kinds == p.code
        columns = [params[rows, c : c + 3] for c in p.points]
        m = np.max(np.abs(np.concatenate(columns, axis=1)), axis=1)
        if p.axis is not None:
            m = np.maximum(m, np.abs(params[rows, p.width - 1]))  # the radius, last
        out[rows] = m
    return out


def row_centers(kinds, params):
    """A point of each primitive, inside it: the mean of its vertices, a disk's or a circle's
    center: ``(n, 3)``."""
    out = np.zeros((len(kinds), 3))
    for p in primitives.present(kinds):
        rows = kinds == p.code
        out[rows] = np.mean([params[rows, c : c + 3] for c in p.points], axis=0)
    return out


# Nonzero coordinates below this, in a frame scaled so that the largest is about 1, may
# underflow in the expansions of the exact predicates' products (of up to three
# differences); rows holding one are decided in rational arithmetic instead.
_SMALL = 2.0**-200


def planar(kinds):
    """Which rows are of a primitive with a plane: a triangle, a disk, a circle."""
    codes = (primitives.TRIANGLE.code, primitives.DISK.code, primitives.CIRCLE.code)
    return np.isin(kinds, codes)


def plane_sides(kinds, params, points):
    """The side of each point (``(n, 3)``) of its primitive's plane, exactly:
    ``int8`` 1 on the side its normal points to (:func:`surface_directions`),
    -1 on the other, 0 on the plane, for primitives without one (segments,
    points) and for points that are not finite.

    The sign of ``(P - V0) . ((V1 - V0) x (V2 - V0))`` for a triangle, of
    ``(P - C) . N`` (``N`` the normal as given) for a disk or a circle: a
    float filter (the predicates' static error bounds, J. R. Shewchuk,
    *Adaptive precision floating-point arithmetic and fast robust geometric
    predicates*, 1997), then, for the rows it leaves undecided (points
    within rounding of the plane), the exact predicates of
    :mod:`proximity.numerics.orient` on the rows scaled by a power of two (exactly)
    so that their largest coordinate is about 1, and rational arithmetic for
    rows whose coordinates that leaves too small for them.
    """
    out = np.zeros(len(kinds), np.int8)
    kinds = np.asarray(kinds)
    finite = np.isfinite(points).all(axis=1)
    tri = np.flatnonzero((kinds == primitives.TRIANGLE.code) & finite)
    axis = np.flatnonzero(((kinds == primitives.DISK.code) | (kinds == primitives.CIRCLE.code)) & finite)
    with np.errstate(invalid="ignore", over="ignore", under="ignore"):
        if len(tri):
            v = params[tri, :9].reshape(-1, 3, 3)
            a, b, c = v[:, 0] - points[tri], v[:, 1] - points[tri], v[:, 2] - points[tri]
            p1, p2 = b[:, 1] * c[:, 2], b[:, 2] * c[:, 1]
            q1, q2 = c[:, 1] * a[:, 2], c[:, 2] * a[:, 1]
            r1, r2 = a[:, 1] * b[:, 2], a[:, 2] * b[:, 1]
            det = a[:, 0] * (p1 - p2) + b[:, 0] * (q1 - q2) + c[:, 0] * (r1 - r2)
            perm = (np.abs(a[:, 0]) * (np.abs(p1) + np.abs(p2)) + np.abs(b[:, 0]) * (np.abs(q1) + np.abs(q2))
                    + np.abs(c[:, 0]) * (np.abs(r1) + np.abs(r2)))  # fmt: skip
            sure = (np.abs(det) > _ERR3 * perm) & (perm > _NORMAL_SUM)
            # orient3d(V0, V1, V2, P) is the sign of (V0 - P) . ((V1 - P) x (V2 - P)): the opposite.
            out[tri[sure]] = np.where(det[sure] > 0, -1, 1)
            tri = tri[~sure]
        if len(axis):
            t = (points[axis] - params[axis, 0:3]) * params[axis, 6:9]
            det = t[:, 0] + t[:, 1] + t[:, 2]
            perm = np.abs(t[:, 0]) + np.abs(t[:, 1]) + np.abs(t[:, 2])
            sure = (np.abs(det) > _ERR_DOT * perm) & (perm > _NORMAL_SUM)
            out[axis[sure]] = np.where(det[sure] > 0, 1, -1)
            axis = axis[~sure]
    if len(tri) or len(axis):
        _exact_sides(out, tri, axis, params, points)
    return out


# The float filters' bounds, as :mod:`proximity.numerics.orient` states them (not imported: that
# module loads the compiler, which a decided row does not need).  They hold where no
# product is subnormal; where some are, their absolute errors (2^-1074 each) are far below
# the bound when the magnitudes' sum is above _NORMAL_SUM, and the rest go to the exact path.
_ERR3 = 8.0e-16
_ERR_DOT = 4.5e-16
_NORMAL_SUM = 2.0**-900


def _exact_sides(out, tri, axis, params, points):
    """:func:`plane_sides` of the rows ``tri`` (triangles) and ``axis`` (disks, circles) the
    float filter left undecided, into ``out``."""
    rows = np.zeros((len(tri) + len(axis), 12))
    rows[: len(tri), :9] = params[tri, :9]
    rows[: len(tri), 9:] = points[tri]
    # C, N, P: the point and the center share a scale, the normal has its own.
    rows[len(tri) :, 0:3] = params[axis, 0:3]
    rows[len(tri) :, 3:6] = params[axis, 6:9]
    rows[len(tri) :, 6:9] = points[axis]
    kind = np.concatenate([np.zeros(len(tri), np.int8), np.ones(len(axis), np.int8)])
    which = np.concatenate([tri, axis])
    original = rows.copy()
    # Scaled by powers of two, exactly (but where a coordinate falls below _SMALL, which
    # goes to rational arithmetic): a triangle's four points together; a disk's point and
    # center together, its normal alone (which scales the product, not its sign).
    t, d = slice(0, len(tri)), slice(len(tri), None)
    rows[t] = _unit_scaled(rows[t])
    rows[d, 3:6] = _unit_scaled(rows[d, 3:6])
    both = _unit_scaled(np.concatenate([rows[d, 0:3], rows[d, 6:9]], axis=1))
    rows[d, 0:3], rows[d, 6:9] = both[:, :3], both[:, 3:]
    small = np.any((rows != 0) & (np.abs(rows) < _SMALL), axis=1)
    sides = np.full(len(rows), 2, np.int8)  # DOUBT
    fast = np.flatnonzero(~small)
    if len(fast):
        orient = lazy.load("proximity.numerics.orient")
        orient.warm()
        got = np.empty(len(fast), np.int64)
        orient.plane_sides(np.ascontiguousarray(kind[fast]), np.ascontiguousarray(rows[fast]), got)
        sides[fast] = got
    for k in np.flatnonzero(sides == 2):
        sides[k] = _fraction_side(kind[k], original[k])
    out[which] = sides


def _unit_scaled(block):
    """Each row of ``block`` times the power of two that brings its largest magnitude into [0.5, 1)."""
    m = np.max(np.abs(block), axis=1, keepdims=True) if block.size else np.ones((len(block), 1))
    _, e = np.frexp(np.where(np.isfinite(m) & (m > 0), m, 1.0))
    return np.ldexp(block, -e)


def _fraction_side(kind, row):
    """:func:`plane_sides` of one row (``kind`` 0 a triangle's, 1 a disk's), in rational arithmetic."""
    x = [Fraction(float(value)) for value in row]
    if kind == 0:
        a, b, c, p = x[0:3], x[3:6], x[6:9], x[9:12]
        e0 = [b[i] - a[i] for i in range(3)]
        e1 = [c[i] - a[i] for i in range(3)]
        n = [e0[1] * e1[2] - e0[2] * e1[1], e0[2] * e1[0] - e0[0] * e1[2], e0[0] * e1[1] - e0[1] * e1[0]]
        value = sum((p[i] - a[i]) * n[i] for i in range(3))
    else:
        value = sum((x[6 + i] - x[i]) * x[3 + i] for i in range(3))
    return (value > 0) - (value < 0)


class PairNormals:
    """What a pair's :attr:`~proximity.results.PairResult.normal` needs, kept until it is asked.

    ``a`` and ``b`` are the sides' cores (meshes, scenes, batches of primitives);
    ``ca``, ``cb`` their witnesses (``batch + (3,)``, in ``a``'s frame), ``d`` the cores'
    distance (NaN where the pair has no answer), ``fa``, ``fb`` the witnesses' features and
    ``ia``, ``ib`` their elements (batch member, face or primitive, as ``_feature_rows``
    numbers them).  ``pose`` is ``(R, t)`` taking ``b``'s frame to ``a``'s, or None; ``back``
    ``(R, t)`` taking ``a``'s frame to the world, or None; ``sign`` -1 where the answer's
    sides were exchanged; ``dim`` the sides' dimension.
    """

    __slots__ = ("a", "b", "ca", "cb", "d", "fa", "fb", "ia", "ib", "pose", "back", "sign", "dim")
    _ROWS = ("ca", "cb", "d", "fa", "fb", "ia", "ib")  # the per-row values, the others' constants

    def __init__(self, a, b, ca, cb, d, fa, fb, ia, ib, pose=None, back=None, sign=1.0, dim=3):
        self.a, self.b, self.ca, self.cb, self.d = a, b, ca, cb, d
        self.fa, self.fb, self.ia, self.ib = fa, fb, ia, ib
        self.pose, self.back, self.sign, self.dim = pose, back, sign, dim

    def _with(self, **values):
        out = object.__new__(PairNormals)
        for name in self.__slots__:
            setattr(out, name, values.get(name, getattr(self, name)))
        return out

    def _rows(self):
        """The per-row values, flat (``(n, 3)`` witnesses, ``(n,)`` the others)."""
        batch = np.shape(self.d)
        rows = []
        for name in self._ROWS:
            value = np.asarray(getattr(self, name))
            tail = (3,) if name in ("ca", "cb") else ()
            rows.append(np.broadcast_to(value, batch + tail).reshape((-1,) + tail))
        return rows

    def take(self, index):
        """The normals of the pairs at ``index`` of the batch (whose shape every per-row value has)."""
        return self._with(**{name: np.asarray(getattr(self, name))[index] for name in self._ROWS})

    def negated(self):
        """The normals of the same answer with its sides exchanged."""
        return self._with(sign=-self.sign)

    def normal(self):
        """The normals, ``batch + (D,)`` (see :attr:`~proximity.results.PairResult.normal`)."""
        batch = np.shape(self.d)
        ca, cb, d, fa, fb, ia, ib = self._rows()
        normal = np.full((len(d), 3), np.nan)
        found = np.flatnonzero(np.isfinite(d) & np.isfinite(ca).all(axis=1) & np.isfinite(cb).all(axis=1))
        if len(found):
            rows = [value[found] for value in (ca, cb, d, fa, fb, ia, ib)]
            ca, cb, d = rows[:3]
            ends = self.a._feature_rows(rows[5]), self.b._feature_rows(rows[6])
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                v = cb - ca
                v = v / np.max(np.abs(v), axis=1, keepdims=True)
                away = v / np.linalg.norm(v, axis=1, keepdims=True)
                m = np.maximum(np.max(np.abs(ca), axis=1), np.max(np.abs(cb), axis=1))
                m = np.maximum(m, np.maximum(row_magnitudes(*ends[0]), row_magnitudes(*ends[1])))
                if self.pose is not None:
                    m = m + np.max(np.abs(self.pose[1]))  # b's rows are posed by it
                near = (d <= ROUNDING * _EPS * m) | ~np.isfinite(away).all(axis=1)
            out = np.where(near[:, None], np.nan, away)
            if self.dim == 3:
                self._features(out, near, rows, ends)
            normal[found] = out
        if self.back is not None:
            normal = normal @ self.back[0].T
        normal = normal * self.sign + 0.0
        return normal.reshape(batch + (3,))[..., : self.dim]

    def _features(self, out, near, rows, ends):
        """Into ``out``: the rows with a witness on a face, and the others within rounding,
        from the features (``rows`` the per-row values, ``ends`` each side's primitives)."""

        ca, cb, _, fa, fb, ia, ib = rows
        r, t = self.pose if self.pose is not None else (np.eye(3), np.zeros(3))
        ref_a = row_centers(*ends[0])
        ref_b = to_world(row_centers(*ends[1]), r, t)
        # The other side as a face sees it: its witness where apart, its primitive where not.
        seen_by_a = np.where(near[:, None], ref_b, cb)
        seen_by_b = to_local(np.where(near[:, None], ref_a, ca), r, t)
        face_a = np.flatnonzero(fa == FACE)
        if len(face_a):
            out[face_a] = self.a._feature_normals(ia[face_a], fa[face_a], seen_by_a[face_a])
        face_b = np.flatnonzero((fb == FACE) & (fa != FACE))
        if len(face_b):
            out[face_b] = 0.0 - self.b._feature_normals(ib[face_b], fb[face_b], seen_by_b[face_b]) @ r.T
        # Touching or crossing on edges and vertices: a side's own normal there, if it has one.
        rest = near & (fa != FACE) & (fb != FACE)
        planes = (primitives.TRIANGLE.code, primitives.DISK.code)
        with_a = np.isin(ends[0][0], planes)
        on_a = np.flatnonzero(rest & with_a)
        if len(on_a):
            n = self.a._feature_normals(ia[on_a], fa[on_a], ref_b[on_a])
            out[on_a] = _towards(n, ref_b[on_a] - ca[on_a])
        on_b = np.flatnonzero(rest & ~with_a & np.isin(ends[1][0], planes))
        if len(on_b):
            n = self.b._feature_normals(ib[on_b], fb[on_b], seen_by_b[on_b]) @ r.T
            out[on_b] = 0.0 - _towards(n, ref_a[on_b] - cb[on_b])


def _towards(n, v):
    """``n`` turned to the side of ``v``; NaN where ``v`` is normal to it."""
    dot = np.einsum("ij,ij->i", n, v)
    return np.where((dot > 0)[:, None], n, np.where((dot < 0)[:, None], 0.0 - n, np.nan))
