"""Queries between two shapes: :func:`closest_points`, and the distance of one shape to another.

A pair of shapes is answered by the kinds of their primitives, through the
pair registry (:mod:`proximity.pair.table`):

* two batches of primitives broadcast against each other like points
  against a shape; a pair kernel runs the pair batch pipeline
  (:mod:`proximity.pair.kernels`), one pair of single shapes its fast
  path, and a point against anything is that shape's point query;
* a mesh or a scene on either side is searched by a simultaneous descent
  of both hierarchies (:mod:`proximity.pair.descent`), a batch of
  primitives on the other side being a forest of one-primitive leaves;
* a rounded shape (:class:`proximity.Inflated`) is its core with a
  radius: the cores' pair with ``d - r_a - r_b`` (certified where that
  subtraction cancels, as :mod:`proximity.shapes.rounded` does), negative when
  the solids overlap, and the witnesses moved onto the surfaces;
* a posed view (:class:`proximity.Posed`) of a mesh or a scene is searched
  in place, its pose applied on the fly by the descent (side b's): a posed
  side a is swapped to b, and where both sides are posed, b is posed
  relative to a, ``[R_a^T R_b | R_a^T (t_b - t_a)]`` rounded, and the
  witnesses moved back by a's pose, each rounding within a few ``eps``
  of the coordinates' magnitude (as :mod:`proximity.shapes.posed` bounds a posed
  point query).  A posed batch of segments, triangles or points is the
  batch of its posed vertices.
"""

import numpy as np

from .. import primitives
from .._validate import as_float64, broadcast_batch, freeze_result
from .._validate import cutoff as _cutoff
from ..features import NONE, VERTEX0
from ..methods import resolve
from ..numerics.normals import PairNormals
from ..numerics.rigid import pose_matrix, to_world
from ..numerics.rounding import surface_points, total_radius
from ..results import Fill, pair_result
from ..runtime import lazy, threads
from ..shapes.base import Point, Segment, Triangle
from ..shapes.posed import Posed
from ..shapes.rounded import Inflated
from ..shapes.scene import Scene
from . import table
from .fast import closest_route, fast_for, mesh_pair, single_row

_ZERO = np.zeros(())
_ZERO.flags.writeable = False


class _Side:
    """One argument of a pair query, taken apart: its core, outer radius and kind."""

    def __init__(self, shape, name):
        if not hasattr(shape, "_rows") or not hasattr(shape, "closest_point"):
            raise TypeError(f"{name} must be a proximity shape; got {type(shape).__name__}")
        self.shape, self.name = shape, name
        self.radius = _ZERO
        core = shape
        if isinstance(shape, Inflated):
            core, self.radius = shape.core, shape.radius
        self.core = core
        self.collection = hasattr(core, "_tree")
        if getattr(core, "_instanced", None) is not None:
            raise TypeError(f"{name}: a scene of instances is searched part by part (see _pair_instances)")
        self.primitive = getattr(core, "_primitive", None)
        if not self.collection and self.primitive is None:
            raise TypeError(f"{name} must be a proximity shape; got {type(shape).__name__}")
        self.batch = shape.batch_shape
        self.dim = shape.dim
        r = self.radius
        self.rounded = (r.item() != 0.0) if r.size == 1 else bool(np.any(r))

    def rows(self):
        """The batch's stored rows ``(count, N_PARAMS)``, in C order, and its kinds."""
        kinds, params = self.core._rows()[:2]
        return kinds, params

    def hull_rows(self):
        """The core's vertices as rows ``batch + (3 * vertices,)`` (hull kinds)."""
        v = self.core._vertices3
        return v.reshape(v.shape[:-2] + (3 * v.shape[-2],))


def _unposed(shape, name):
    """``(shape, rotation, translation)``: ``shape`` without its pose, or with it where it is
    a batch of hull primitives (their vertices posed); ``rotation`` None where unposed.

    Rounding and posing commute (a rigid motion keeps distances), so any nesting of
    posed and rounded views is the core rounded by the sum of the radii, posed."""
    rotation = translation = None
    radii = []
    core = shape
    while isinstance(core, (Posed, Inflated)):
        if isinstance(core, Posed):
            if rotation is None:
                rotation, translation = core.rotation, core.translation
            else:  # an outer pose applied to an inner one
                rotation, translation = rotation @ core.rotation, rotation @ core.translation + translation
            core = core.shape
        else:
            radii.append(core.radius)
            core = core.core
    if rotation is None:
        return shape, None, None
    radius = total_radius(radii)
    if type(core) is Scene and core._instanced is not None:
        raise TypeError(f"{name}: a scene of instances is searched part by part (see _pair_instances)")
    if type(core) in (Triangle, Segment):
        core = type(core)(to_world(core.vertices, rotation, translation))
        rotation = translation = None
    elif type(core) is Point:
        core = Point(to_world(core.position, rotation, translation))
        rotation = translation = None
    elif not hasattr(core, "_tree"):
        raise NotImplementedError(
            f"{name} is a posed {type(core).__name__}: pair queries take posed meshes, scenes, segments, "
            "triangles and points"
        )
    return (core if radius is None else Inflated(core, radius)), rotation, translation


def _poses(a, b, pose_b, names=("a", "b")):
    """The pair without its posed views: ``(a, b, pose_b, swap, back)``.  ``swap``: the sides
    were exchanged (a posed side a becomes side b); ``back``: ``(R, t)`` that moves the
    answer's points to the world, or None."""
    if pose_b is not None:
        return a, b, pose_b, False, None
    a, ra, ta = _unposed(a, names[0])
    b, rb, tb = _unposed(b, names[1])
    if ra is None and rb is None:
        return a, b, None, False, None
    if ra is None:
        return a, b, pose_matrix(rb, tb), False, None
    if rb is None:
        return b, a, pose_matrix(ra, ta), True, None
    # Both posed: b in a's frame, R_a^T (R_b x + t_b - t_a).
    return a, b, pose_matrix(ra.T @ rb, ra.T @ (tb - ta)), False, (ra, ta)


def _same_dimension(a, b, names):
    if a.dim != b.dim:
        raise ValueError(
            f"{names[0]} and {names[1]} must live in the same dimension; got {a.dim}D "
            f"({type(a).__name__}) and {b.dim}D ({type(b).__name__})"
        )


def _prepare(a, b, method, names=("a", "b")):
    side_a, side_b = _Side(a, names[0]), _Side(b, names[1])
    _same_dimension(a, b, names)
    out_shape = broadcast_batch(
        [(names[0], side_a.batch), (names[1], side_b.batch)],
        f"the batch dimensions of {names[0]} and {names[1]}",
    )
    method = resolve(method)
    return side_a, side_b, out_shape, method


# -- answers: flat arrays of the cores' pair ---------------------------------------------


def _primitive_answer(side_a, side_b, out_shape, method, full):
    """Two batches of primitives: the cores' answer, flat, with each row's primitive rows."""
    pair = table.lookup(side_a.primitive, side_b.primitive, (side_a.name, side_b.name))
    if method.name not in pair.methods:
        raise ValueError(f"method must be one of {pair.methods} for a {pair.a.name} and a {pair.b.name}; "
                         f"got {method.name!r}")  # fmt: skip
    if pair.point:
        out = _point_answer(side_a, side_b, pair, out_shape, method, full)
    else:
        out = _kernel_answer(side_a, side_b, pair, out_shape, method, full)
    out["pair"] = pair
    return out


def _point_answer(side_a, side_b, pair, out_shape, method, full):
    """A point against a primitive batch: that shape's point query."""
    point, other = (side_b, side_a) if pair.swapped else (side_a, side_b)
    core_shape = np.broadcast_shapes(point.core.batch_shape, other.core.batch_shape)
    position = point.core._vertices3[..., 0, :]
    if full:
        r = other.core.closest_point(point.core.position, method=method.name)
        d = np.broadcast_to(r.distance, out_shape).reshape(-1)
    else:
        d = np.broadcast_to(other.core.distance(point.core.position, method=method.name), out_shape).reshape(
            -1
        )
    out = {"distance": d}
    if full:
        n = d.size
        ex = np.full((n, 3), np.nan)
        for name, _ in other.primitive.extra:
            if name == "barycentric":
                ex = np.broadcast_to(r.barycentric, out_shape + (3,)).reshape(-1, 3)
            elif name == "parameter":
                ex = np.full((n, 3), np.nan)
                ex[:, 0] = np.broadcast_to(r.parameter, out_shape).reshape(-1)
        p = np.broadcast_to(r.point, core_shape + (point.dim,))
        p3 = np.concatenate([p, np.zeros(p.shape[:-1] + (3 - point.dim,))], axis=-1) if point.dim < 3 else p
        out.update(
            sqr_distance=np.broadcast_to(r.sqr_distance, out_shape).reshape(-1),
            point=np.broadcast_to(position, out_shape + (3,)).reshape(-1, 3),
            feature=np.full(n, VERTEX0, np.int8),
            point_b=np.broadcast_to(p3, out_shape + (3,)).reshape(-1, 3),
            feature_b=np.broadcast_to(r.feature, out_shape).reshape(-1),
            extra_a=np.full((n, 3), np.nan),
            extra_b=ex,
        )
    return _swapped(out) if pair.swapped else out


def _kernel_answer(side_a, side_b, pair, out_shape, method, full):
    """Two batches of segments or triangles: the pair kernel, the fast path for one pair."""
    pk = lazy.load("proximity.pair.kernels")
    inner = pair.unswapped
    first, second = (side_b, side_a) if pair.swapped else (side_a, side_b)
    a, b = first.hull_rows(), second.hull_rows()
    if a.ndim == 1 and b.ndim == 1:
        row = single_row(inner, method, np.ascontiguousarray(a), np.ascontiguousarray(b))
        out = {"distance": row[1:2]}
        if full:
            out.update(sqr_distance=row[2:3], point=row[None, 3:6], feature=row[9:10].astype(np.int8),
                       point_b=row[None, 6:9], feature_b=row[10:11].astype(np.int8), extra_a=row[None, 11:14],
                       extra_b=row[None, 14:17])  # fmt: skip
    else:
        with threads.kernel():
            out = pk.query(inner, method, a, b, out_shape, full)
    return _swapped(out) if pair.swapped else out


def _swapped(out):
    swapped = dict(out)
    for x, y in (("point", "point_b"), ("feature", "feature_b"), ("extra_a", "extra_b")):
        if x in out:
            swapped[x], swapped[y] = out[y], out[x]
    return swapped


def _pose_array(pose):
    if pose is None:
        return None

    t = as_float64(pose, "pose_b", "(4, 4)")
    if t.shape != (4, 4) or not np.isfinite(t).all() or t[3].tolist() != [0.0, 0.0, 0.0, 1.0]:
        raise ValueError(f"pose_b must be a finite 4 x 4 affine matrix with last row [0, 0, 0, 1]; got {t!r}")
    return np.ascontiguousarray(t[:3])


def _collection_answer(side_a, side_b, out_shape, method, full, cutoff, pose_b):
    """A mesh or a scene on a side: the descent, one query per member of the broadcast batch."""
    pc = lazy.load("proximity.pair.composite")
    names = (side_a.name, side_b.name)
    count = int(np.prod(out_shape, dtype=np.int64))
    sides, starts = [], []
    for side in (side_a, side_b):
        if side.collection:
            sides.append(pc.side_of(side.core))
            starts.append(np.zeros(count, np.int64))
        else:
            kinds, params = side.rows()
            sides.append(pc.side_of(kinds=kinds, params=params))
            members = np.arange(int(np.prod(side.core.batch_shape, dtype=np.int64)))
            starts.append(np.broadcast_to(members.reshape(side.core.batch_shape), out_shape).reshape(-1))
    if count == 1:
        radii = [np.array([float(s.radius.reshape(-1)[0])]) for s in (side_a, side_b)]
    else:
        radii = [np.broadcast_to(s.radius, out_shape).reshape(-1) for s in (side_a, side_b)]
    with threads.kernel():
        out = pc.closest(sides, method, starts, radii, np.full(count, cutoff), pose_b, full, names)
    out["sides"] = [side[0] for side in sides]
    return out


def _answer(a, b, method, max_distance, full, names=("a", "b"), pose_b=None):
    """``(out_shape, sides, flat answer)`` of the pair ``a``, ``b``: ``signed`` (``d - r_a - r_b``)
    and, with ``full``, the rest, witnesses on the surfaces."""
    side_a, side_b, out_shape, method = _prepare(a, b, method, names)
    cutoff = _cutoff(max_distance)
    pose = _pose_array(pose_b)
    if side_a.collection or side_b.collection or pose is not None:
        out = _collection_answer(side_a, side_b, out_shape, method, full, cutoff, pose)
    else:
        out = _primitive_answer(side_a, side_b, out_shape, method, full)
        out = _round_primitives(side_a, side_b, out_shape, out, method, full)
        if cutoff < np.inf:
            beyond = ~(out["signed"] <= cutoff)
            out["signed"] = np.where(beyond, np.inf, out["signed"])
            out["beyond"] = beyond
    return out_shape, side_a, side_b, out


def _round_primitives(side_a, side_b, out_shape, out, method, full):
    """Primitive batches: ``signed = d - r_a - r_b``, certified where the method is, and
    the names of the descent's outputs."""
    d = np.asarray(out["distance"], np.float64)
    n = d.size
    ra = np.broadcast_to(side_a.radius, out_shape).reshape(-1)
    rb = np.broadcast_to(side_b.radius, out_shape).reshape(-1)
    pair = out.pop("pair")
    if side_a.rounded or side_b.rounded:
        with np.errstate(invalid="ignore"):
            signed = d - (ra + rb)
        if method.exact_fallback:
            pc = lazy.load("proximity.pair.composite")
            rows_a = _member_rows(side_a, out_shape)
            rows_b = _member_rows(side_b, out_shape)
            signed = pc.minus_radii(d, ra, rb, pair, rows_a, rows_b)
    else:
        signed = d
    result = {"signed": signed, "distance": d}
    if full:
        for name, key in (("sqr_distance", "sqr_distance"), ("point_a", "point"), ("point_b", "point_b"),
                          ("feature_a", "feature"), ("feature_b", "feature_b"), ("extra_a", "extra_a"),
                          ("extra_b", "extra_b")):  # fmt: skip
            result[name] = out[key]
        result.update(index_a=np.full(n, -1, np.int64), index_b=np.full(n, -1, np.int64))
        result.update(radius_a=np.array(ra, np.float64), radius_b=np.array(rb, np.float64))
    return result


class _LazyRows:
    """Per flat row of a broadcast batch: the stored row of its member, built on demand."""

    def __init__(self, side, out_shape):
        self.params = side.rows()[1]
        self.index = np.broadcast_to(
            np.arange(len(self.params)).reshape(side.core.batch_shape), out_shape
        ).reshape(-1)

    def __getitem__(self, k):
        return self.params[self.index[k]]


def _member_rows(side, out_shape):
    return _LazyRows(side, out_shape)


# -- results ------------------------------------------------------------------------------


def _side_fields(side, index, extra, kinds):
    """``parameter``, ``barycentric``, ``face``, ``primitive`` and ``source`` of one side: flat
    arrays, or a :class:`~proximity.results.Fill` where the field holds one value in every row
    (a triangle's parameter, a batch's face)."""
    n = len(extra)
    nan, none = Fill(np.nan, np.float64), Fill(-1, np.int64)
    nan3 = Fill(np.nan, np.float64, (3,))
    if kinds is None:  # one kind in every row
        code = side.primitive.code if side.primitive is not None else -1
        parameter = extra[:, 0] if code == primitives.SEGMENT.code else nan
        barycentric = extra if code == primitives.TRIANGLE.code else nan3
    else:
        parameter = np.full(n, np.nan)
        barycentric = np.full((n, 3), np.nan)
        seg = kinds == primitives.SEGMENT.code
        tri = kinds == primitives.TRIANGLE.code
        parameter[seg] = extra[seg, 0]
        barycentric[tri] = extra[tri]
    face = primitive = source = none
    core = side.core
    if side.collection and index is not None:
        if hasattr(core, "faces"):
            face = np.array(index, np.int64)
        else:
            primitive = np.array(index, np.int64)
            found = primitive >= 0
            source = np.where(found, np.searchsorted(core.offsets, primitive, side="right") - 1, -1)
    return parameter, barycentric, face, primitive, source


def _winner_kinds(out, key):
    """The kind code of the primitive holding each row's witness on ``side``."""
    if "sides" in out:
        tree = out["sides"][0 if key == "a" else 1]
        rows = out[f"row_{key}"]
        return np.where(rows >= 0, tree.kinds[np.maximum(rows, 0)], -1)
    return None


def _surface(side, other_point, out, key, out_shape, pose_b):
    """Witness points of ``side`` moved onto its rounded surface (radius ``radius_key``)."""
    pc = lazy.load("proximity.pair.composite")
    c = out[f"point_{key}"]
    r = out[f"radius_{key}"]
    if not np.any(r > 0):
        return c
    d = np.asarray(out["distance"], np.float64)
    rows_key = f"row_{key}"

    def rows_of(rows):
        if "sides" in out:
            tree = out["sides"][0 if key == "a" else 1]
            k = np.maximum(out[rows_key][rows], 0)
            params = tree.params[k][:, : primitives.N_PARAMS]
            if key == "b" and pose_b is not None:
                params = pc.posed_rows(params, tree.kinds[k], pose_b)
            return tree.kinds[k], params
        kinds, params = side.rows()
        index = np.broadcast_to(np.arange(len(kinds)).reshape(side.core.batch_shape), out_shape).reshape(-1)
        return kinds[index[rows]], params[index[rows]]

    with np.errstate(invalid="ignore"):
        return surface_points(other_point, c, d, r, rows_of)


# -- normals ----------------------------------------------------------------------------


def _elements(side, out, key, out_shape):
    """Each row's element of ``side``: its face or primitive, or its member of the batch."""
    if side.collection:
        return np.asarray(out[f"index_{key}"])
    count = int(np.prod(side.core.batch_shape, dtype=np.int64))
    return np.broadcast_to(np.arange(count).reshape(side.core.batch_shape), out_shape).reshape(-1)


def _instances(query, a, b, method, max_distance, pose_b, signed):
    """The pair where a side is a scene of instances, part by part
    (:mod:`proximity.pair.instances`); None where neither side is one."""
    pi = lazy.load("proximity.pair.instances")
    key = "a" if pi.unwrapped(a) is not None else "b" if pi.unwrapped(b) is not None else None
    if key is None:
        return None
    for name, shape in (("a", a), ("b", b)):
        if not hasattr(shape, "_rows") or not hasattr(shape, "closest_point"):
            raise TypeError(f"{name} must be a proximity shape; got {type(shape).__name__}")
    # Checked here, on the arguments: the parts below are posed meshes and scenes, and may swap sides.
    _same_dimension(a, b, ("a", "b"))
    if pose_b is not None:
        b, pose_b = b.transformed(pose_b), None
    cutoff = None if max_distance is None else _cutoff(max_distance)
    # One pair (a radius array rounding the scene makes a batch): each part prunes with the best so far.
    single = getattr(a, "batch_shape", None) == () and getattr(b, "batch_shape", None) == ()

    def one(x, y, max_distance):
        return query(x, y, method=method, max_distance=max_distance)

    return pi.least(one, a, b, key, single, cutoff, signed)


def closest_points(a, b, *args, method="robust", max_distance=None, pose_b=None):
    """Closest points of two shapes; see :func:`proximity.closest_points`."""
    if args:
        raise TypeError(
            "closest_points() takes two positional arguments, a and b; method is keyword-only: "
            f"closest_points(a, b, method={args[0]!r})"
        )
    if max_distance is None and pose_b is None:
        closest = closest_route(a, b, method)
        if closest is not None:
            result = closest(a, b)
            if result is not None:
                return result
        meshes = mesh_pair(a, b, method)
        if meshes is not None:
            found = meshes[0].closest_points(meshes[1], a, b.shape if type(b) is Posed else b)
            if found is not None:
                return found
    found = _instances(closest_points, a, b, method, max_distance, pose_b, False)
    if found is not None:
        return found
    a, b, pose_b, swap, back = _poses(a, b, pose_b)
    names = ("b", "a") if swap else ("a", "b")
    out_shape, side_a, side_b, out = _answer(a, b, method, max_distance, True, names, pose_b)
    signed = np.asarray(out["signed"], np.float64)
    found = np.isfinite(signed)
    pa, pb = out["point_a"], out["point_b"]
    rounded = side_a.rounded or side_b.rounded or _rounded_rows(out)
    if rounded:
        pa = _surface(side_a, out["point_b"], out, "a", out_shape, None)
        pb = _surface(side_b, out["point_a"], out, "b", out_shape, _pose_array(pose_b))
    with np.errstate(invalid="ignore", over="ignore"):
        distance = np.maximum(signed, 0.0) + 0.0
        sqr = distance * distance if rounded else np.asarray(out["sqr_distance"], np.float64)
    # Rows without an answer (beyond the cutoff, not finite): inf, NaN, NONE and -1.
    every = bool(found.all())
    values = {
        "distance": distance,
        "sqr_distance": sqr if every else np.where(found, sqr, np.inf),
        "point_a": (pa if every else np.where(found[:, None], pa, np.nan))[:, : side_a.dim],
        "point_b": (pb if every else np.where(found[:, None], pb, np.nan))[:, : side_a.dim],
    }
    for key in ("feature_a", "feature_b"):
        feature = np.asarray(out[key])
        values[key] = (feature if every else np.where(found, feature, NONE)).astype(np.int8, copy=False)
    for key, side in (("a", side_a), ("b", side_b)):
        kinds = _winner_kinds(out, key)
        fields = _side_fields(side, out[f"index_{key}"], np.asarray(out[f"extra_{key}"]), kinds)
        for name, value in zip(
            ("parameter", "barycentric", "face", "primitive", "source"), fields, strict=True
        ):
            if every or type(value) is Fill:
                pass
            elif value.dtype.kind == "f":
                value = np.where(found[:, None] if value.ndim == 2 else found, value, np.nan)
            else:
                value = np.where(found, value, -1)
            values[f"{name}_{key}"] = value
    if back is not None:
        for key in ("point_a", "point_b"):
            values[key] = to_world(values[key], *back)
    pose = _pose_array(pose_b)
    rows = [
        out["point_a"],
        out["point_b"],
        np.where(found, out["distance"], np.nan),
        out["feature_a"],
        out["feature_b"],
        _elements(side_a, out, "a", out_shape),
        _elements(side_b, out, "b", out_shape),
    ]
    rows = [np.asarray(value).reshape(out_shape + np.shape(value)[1:]) for value in rows]
    pose = None if pose is None else (pose[:, :3], pose[:, 3])
    normals = PairNormals(side_a.core, side_b.core, *rows, pose=pose, back=back, dim=side_a.dim)
    result = pair_result(values, out_shape, normals)
    return result.swapped() if swap else result


def _rounded_rows(out):
    return "sides" in out and any(t.params.shape[1] > primitives.N_PARAMS for t in out["sides"])


def distance(a, b, *, method="robust", max_distance=None, pose_b=None):
    """The distance between two shapes; see :func:`proximity.distance`."""
    if max_distance is None and pose_b is None:
        fast = fast_for(a, b, method)
        if fast is not None:
            row = fast.run(a, b)
            if row is not None:
                return row[fast.at_distance]
        meshes = mesh_pair(a, b, method)
        if meshes is not None:
            d = meshes[0].run(meshes[1])
            if d is not None:
                return d
    found = _instances(distance, a, b, method, max_distance, pose_b, True)
    if found is not None:
        return found
    a, b, pose_b, swap, _ = _poses(a, b, pose_b)
    names = ("b", "a") if swap else ("a", "b")
    out_shape, _, _, out = _answer(a, b, method, max_distance, False, names, pose_b)
    signed = np.asarray(out["signed"], np.float64)
    with np.errstate(invalid="ignore"):
        d = np.maximum(signed, 0.0) + 0.0
    return freeze_result(np.array(d.reshape(out_shape)))[()]


def signed_distance(a, b, *, method="robust", max_distance=None, pose_b=None):
    """``d - r_a - r_b``: negative where two rounded shapes overlap; see :func:`proximity.signed_distance`."""
    if max_distance is None and pose_b is None:
        fast = fast_for(a, b, method)
        if fast is not None:
            row = fast.run(a, b)
            if row is not None:
                return row[fast.at_signed] + 0.0
    found = _instances(signed_distance, a, b, method, max_distance, pose_b, True)
    if found is not None:
        return found
    a, b, pose_b, swap, _ = _poses(a, b, pose_b)
    names = ("b", "a") if swap else ("a", "b")
    out_shape, _, _, out = _answer(a, b, method, max_distance, False, names, pose_b)
    signed = np.asarray(out["signed"], np.float64) + 0.0
    return freeze_result(np.array(signed.reshape(out_shape)))[()]


__all__ = ["closest_points", "distance", "signed_distance"]
