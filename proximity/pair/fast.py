"""The fast paths of pair queries: routes resolved once per pair of shape types.

:func:`proximity.closest_points`, :func:`proximity.distance` and
:func:`proximity.signed_distance` look here first, by the types of their two
arguments and the method, and fall to the general path
(:mod:`proximity.pair.queries`) where a route cannot answer:

* one segment or triangle against another (3D): the pair kernel's entry
  point (:func:`proximity.pair.kernels.single`) on the shapes' own rows, and
  a :class:`~proximity.PairResult` that reads its fields from the kernel's
  row when they are first asked (:class:`_Fast`);
* the same rounded (capsules, rounded triangles; ``robust``): the kernel
  also subtracts the radii and moves the witnesses onto the surfaces, with
  the general path's operations (:class:`_RoundedFast`);
* a mesh against a mesh or a posed mesh (:func:`distance`): the compiled
  descent and its constant arguments, prepared once per pair of
  hierarchies (:class:`_MeshPair`).

Each route gives the bits of the general path (``tests/test_pairs_api.py``).
"""

import weakref

import numpy as np

from .. import primitives
from ..features import _FEATURES
from ..methods import resolve
from ..numerics.normals import PairNormals
from ..numerics.rigid import pose_matrix
from ..results import PairResult
from ..results.base import _LAZY, _PAIR
from ..runtime import counts, lazy, threads
from ..shapes.base import Point, Segment, Triangle
from ..shapes.mesh import TriangleMesh
from ..shapes.posed import Posed
from ..shapes.rounded import Capsule, Inflated, Sphere
from . import table

__all__ = ["closest_route", "fast_for", "mesh_pair", "single_row"]


def _pad(values):
    values = list(values)
    return np.array(values + [np.nan] * (3 - len(values)), dtype=np.float64)


_fast = {}  # (type of a, type of b, method name) -> _Fast, or False where there is none
_empty = np.empty
_new = object.__new__
_NAN = np.float64(np.nan)
_NAN3 = np.full(3, np.nan)
_NAN3.flags.writeable = False
_MINUS1 = np.int64(-1)
_ROUNDED = (Inflated, Capsule, Sphere)
_HULLS = (Segment, Triangle)
_CORES = {Capsule: Segment, Sphere: Point}  # the type of the core of each named rounded shape


def single_row(pair, method, a, b, entry=None):
    """The row of :func:`proximity.pair.kernels.single` for rows ``a``, ``b`` of ``pair``
    (unswapped; C-contiguous float64), unrounded, the exact fallback's answer written over
    the kernel's where its status asks for it (counted for :func:`proximity.certified_stats`)."""
    pk = lazy.load("proximity.pair.kernels")
    row = _empty(pk.SINGLE_WIDTH)
    (entry or pk.single(pair, method))(row, a, b, 0.0, 0.0)
    if row[0] != 0.0:
        exact = pk.exact(pair, a, b)
        row[1:11] = exact[:10]
        ea = pair.extras[0]
        row[11:17] = np.concatenate([_pad(exact[10 : 10 + ea]), _pad(exact[10 + ea :])])
    if method.exact_fallback:
        counts.count(1, int(row[0] != 0.0))
    return row


class _Fast:
    """The fast path of a pair of single shape types: the kernel's entry point, and where
    each field of the result sits in its output row (see :func:`proximity.pair.kernels.single`)."""

    def __init__(self, pair, method):
        pk = lazy.load("proximity.pair.kernels")
        self.swapped = pair.swapped
        inner = pair.unswapped
        self.inner, self.method = inner, method
        self.entry = pk.single(inner, method)
        self.width = pk.SINGLE_WIDTH
        self.at_distance = self.at_signed = 1  # where the row holds them
        self.exact_fallback = method.exact_fallback
        first, second = (11, 14) if not pair.swapped else (14, 11)
        points = (slice(3, 6), slice(6, 9)) if not pair.swapped else (slice(6, 9), slice(3, 6))
        features = (9, 10) if not pair.swapped else (10, 9)
        self.sides = [
            (points[k], features[k], kind is primitives.SEGMENT, slice(start, start + 3))
            for k, (kind, start) in enumerate(((pair.a, first), (pair.b, second)))
        ]
        self.at_a, self.at_b = points

    def run(self, a, b):
        """The kernel's row of ``a`` and ``b`` (read-only), its exact fallback run where asked."""
        first, second = (b, a) if self.swapped else (a, b)
        row = single_row(self.inner, self.method, first._args, second._args, self.entry)
        row.setflags(False)
        return row

    def closest_points(self, a, b):
        """The :class:`PairResult` of ``a`` and ``b``, its fields read from the answer's row at
        their first use (:meth:`fields`), its normal computed when asked (:meth:`normals`)."""
        row = self.run(a, b)
        result = _new(PairResult)
        fields = result.__dict__
        fields["distance"], fields["point_a"], fields["point_b"] = row[1], row[self.at_a], row[self.at_b]
        fields[_LAZY] = fields[_PAIR] = (self, row, a, b)
        return result

    def closer(self):
        """``closest(a, b)``: :meth:`closest_points` with its constants bound, None where a side
        is not one 3D primitive; the robust kernel's row read as it is where its status is 0."""
        if self.exact_fallback:

            def closest(a, b):
                return None if a._args is None or b._args is None else self.closest_points(a, b)

            return closest
        entry, width, swapped, reader = self.entry, self.width, self.swapped, self
        at_a, at_b = self.at_a, self.at_b

        def closest(a, b):
            first, second = (b, a) if swapped else (a, b)
            args_a, args_b = first._args, second._args
            if args_a is None or args_b is None:
                return None
            row = _empty(width)
            entry(row, args_a, args_b, 0.0, 0.0)
            if row.item(0):
                return reader.closest_points(a, b)
            row.setflags(False)
            result = _new(PairResult)
            fields = result.__dict__
            fields["distance"], fields["point_a"], fields["point_b"] = row[1], row[at_a], row[at_b]
            fields[_LAZY] = fields[_PAIR] = (reader, row, a, b)
            return result

        return closest

    def fields(self, row):
        """The fields of a :class:`PairResult` of the answer ``row`` besides ``distance`` and
        the witnesses (which :meth:`closest_points` sets), by name."""
        fields = {"sqr_distance": row[2]}
        (_, feature_a, segment_a, extra_a), (_, feature_b, segment_b, extra_b) = self.sides
        fields["feature_a"] = _FEATURES[row.item(feature_a)]
        fields["feature_b"] = _FEATURES[row.item(feature_b)]
        fields["parameter_a"] = row[extra_a.start] if segment_a else _NAN
        fields["parameter_b"] = row[extra_b.start] if segment_b else _NAN
        fields["barycentric_a"] = _NAN3 if segment_a else row[extra_a]
        fields["barycentric_b"] = _NAN3 if segment_b else row[extra_b]
        fields["face_a"] = fields["face_b"] = fields["primitive_a"] = fields["primitive_b"] = _MINUS1
        fields["source_a"] = fields["source_b"] = _MINUS1
        return fields

    def normals(self, row, a, b):
        """The :class:`PairNormals` of the answer ``row`` of ``a`` and ``b``."""
        (point_a, feature_a, _, _), (point_b, feature_b, _, _) = self.sides
        return PairNormals(a, b, row[point_a], row[point_b], row[1], row[feature_a], row[feature_b], 0, 0)


class _RoundedFast:
    """The fast path of a pair of single rounded segments or triangles (``robust``): the
    cores' kernel, which also rounds its answer as :func:`closest_points` does (see
    :func:`proximity.pair.kernels.single`); None where a witness direction is lost in
    rounding, or the kernel asks its exact fallback: the general path answers those."""

    at_distance, at_signed = 18, 17  # where the row holds them

    def __init__(self, fast):
        self.fast = fast
        # The surface points' slices: the kernel's first side at 20, its second at 23.
        first, second = slice(20, 23), slice(23, 26)
        self.at_a, self.at_b = (second, first) if fast.swapped else (first, second)

    def run(self, a, b):
        fast = self.fast
        row = _empty(fast.width)
        first, second = (b, a) if fast.swapped else (a, b)
        fast.entry(row, first.core._args, second.core._args, first.radius, second.radius)
        if row.item(26):  # lost in rounding, or the exact fallback asked
            return None
        row.setflags(False)
        return row

    def closer(self):
        """``closest(a, b)``: the :class:`PairResult` of ``a`` and ``b``, or None where
        :meth:`run` gives none; :meth:`run` and the result's assembly written out with their
        constants bound (one call less on a path of about 2 us)."""
        fast = self.fast
        entry, width, swapped, reader = fast.entry, fast.width, fast.swapped, self
        at_a, at_b = self.at_a, self.at_b

        def closest(a, b):
            if a.batch_shape or b.batch_shape:
                return None
            first, second = (b, a) if swapped else (a, b)
            args_a, args_b = first.core._args, second.core._args
            if args_a is None or args_b is None:
                return None
            row = _empty(width)
            entry(row, args_a, args_b, first.radius, second.radius)
            if row.item(26):
                return None
            row.setflags(False)
            result = _new(PairResult)
            fields = result.__dict__
            fields["distance"], fields["point_a"], fields["point_b"] = row[18], row[at_a], row[at_b]
            fields[_LAZY] = fields[_PAIR] = (reader, row, a, b)
            return result

        return closest

    def fields(self, row):
        """As :meth:`_Fast.fields`, the square of the rounded pair's distance."""
        fields = self.fast.fields(row)
        fields["sqr_distance"] = row[19]
        return fields

    def normals(self, row, a, b):
        """The normals of the cores' answer, from ``a``'s core towards ``b``'s."""
        return self.fast.normals(row, a.core, b.core)


def _hull_fast(type_a, type_b, method):
    """The :class:`_Fast` path of single shapes of two hull types (segments, triangles) by
    ``method``, made once; None where these types have none."""
    key = (type_a, type_b, method)
    fast = _fast.get(key)
    if fast is None:
        fast = False
        if type_a in _HULLS and type_b in _HULLS and method in ("robust", "certified"):
            fast = _Fast(table.lookup(type_a._primitive, type_b._primitive), resolve(method))
            fast.rounded = _RoundedFast(fast)
        _fast[key] = fast
    return fast or None


def fast_for(a, b, method):
    """The fast path of :func:`distance` and :func:`signed_distance` for ``a`` and ``b``
    (:class:`_Fast`, or :class:`_RoundedFast` for rounded shapes), or None where there is none."""
    if type(method) is not str:
        return None
    type_a, type_b = type(a), type(b)
    if type_a in _ROUNDED:
        if type_b not in _ROUNDED or method != "robust" or a.batch_shape or b.batch_shape:
            return None
        a, b = a.core, b.core
        fast = _hull_fast(type(a), type(b), method)
        fast = None if fast is None else fast.rounded
    else:
        fast = _hull_fast(type_a, type_b, method)
    return fast if fast is not None and a._args is not None and b._args is not None else None


_closest = {}  # (type of a, type of b, method name) -> closest(a, b) (see closest_route), or False


def closest_route(a, b, method):
    """``closest(a, b) -> PairResult or None``: the fast path of :func:`closest_points` for
    shapes of the types of ``a`` and ``b`` (resolved once per pair of types and method), or
    None where there is none; ``closest`` returns None where it cannot answer these two
    (batches, 2D shapes; rounded shapes whose witness direction is lost in rounding)."""
    if type(method) is not str:
        return None
    key = (type(a), type(b), method)
    route = _closest.get(key)
    if route is None:
        route = _closest[key] = _closest_route(*key)
    return route or None


def _closest_route(type_a, type_b, method):
    if type_a in _CORES and type_b in _CORES and method == "robust":  # their cores' types are known
        fast = _hull_fast(_CORES[type_a], _CORES[type_b], method)
        return False if fast is None else fast.rounded.closer()
    if type_a in _ROUNDED and type_b in _ROUNDED and method == "robust":
        cores = {}  # (type of a's core, type of b's core) -> closest(a, b), or False

        def pick(a, b):
            key = (type(a.core), type(b.core))
            closest = cores.get(key)
            if closest is None:
                fast = _hull_fast(*key, method)
                closest = cores[key] = False if fast is None else fast.rounded.closer()
            return None if closest is False else closest(a, b)

        return pick
    fast = _hull_fast(type_a, type_b, method)
    return False if fast is None else fast.closer()


class _MeshPair:
    """The fast path of :func:`distance` between a mesh and a mesh or a posed mesh: the sides,
    the compiled descent and its constant arguments, prepared once per pair of trees; a
    call poses, runs the descent on one query and reads its answer, the same bits as the
    general path (:func:`_collection_answer`), which finishes what it leaves undecided."""

    def __init__(self, mesh_a, mesh_b, method, posed):
        pc = lazy.load("proximity.pair.composite")
        bp = pc._broadphase()
        self.a, depth_a, kinds_a, self.m_a = pc.side_of(mesh_a)
        self.b, depth_b, kinds_b, self.m_b = pc.side_of(mesh_b)
        self.depth = int(depth_a + depth_b)
        present = bp.present_pairs(kinds_a, kinds_b, ("a", "b"))
        self.descend = bp.descent_kernel(method, present, posed, -1, -1)  # faces have no radii
        zero, none = np.zeros(1, np.int64), np.empty(0)
        self.queries = bp.Queries(zero, zero, np.zeros(1), np.zeros(1), np.full(1, np.inf))
        # The outputs a distance does not write, between signed, distance and undecided.
        self.unused = (none, np.empty((0, 3)), np.empty((0, 3)), np.empty(0, np.int8), np.empty(0, np.int8),
                       np.empty((0, 3)), np.empty((0, 3)), np.empty(0, np.int64), np.empty(0, np.int64),
                       np.empty(0, np.int64), np.empty(0, np.int64), none, none)  # fmt: skip
        self.outputs, self.magnitude = bp.Outputs, bp.magnitude
        self.unposed = np.zeros((3, 4))

    def run(self, pose):
        """The distance, or None where the descent left it undecided."""
        magnitude = float(self.magnitude(self.m_a, self.m_b, pose, 0.0))
        pose_array = self.unposed if pose is None else pose
        out = self.outputs(np.empty(1), np.empty(1), *self.unused, np.empty(1))
        with threads.kernel():
            self.descend(0, 1, self.a, self.b, pose_array, self.depth, magnitude, self.queries, out, False)
        if out.undecided[0] == out.undecided[0]:
            return None
        # As the general path's np.maximum(signed, 0.0) + 0.0 (the sum turns -0.0 into 0.0).
        return np.float64(max(float(out.signed[0]), 0.0) + 0.0)

    def closest_points(self, pose, mesh_a, mesh_b):
        """The :class:`~proximity.PairResult` of ``mesh_a`` and ``mesh_b`` posed by ``pose``
        (3 x 4, or None), or None where the descent left it undecided: the general path's
        fields (:func:`proximity.pair.queries.closest_points`), made from one query's outputs."""
        magnitude = float(self.magnitude(self.m_a, self.m_b, pose, 0.0))
        pose_array = self.unposed if pose is None else pose
        e = np.empty
        out = self.outputs(e(1), e(1), e(1), e((1, 3)), e((1, 3)), e(1, np.int8), e(1, np.int8), e((1, 3)),
                           e((1, 3)), e(1, np.int64), e(1, np.int64), e(1, np.int64), e(1, np.int64), e(1),
                           e(1), e(1))  # fmt: skip
        with threads.kernel():
            self.descend(0, 1, self.a, self.b, pose_array, self.depth, magnitude, self.queries, out, True)
        if out.undecided[0] == out.undecided[0]:
            return None
        signed = out.signed[0]
        if not np.isfinite(signed):  # no pair answered (as the general path's rows without one)
            return None
        point_a, point_b = out.point_a[0], out.point_b[0]
        extra_a, extra_b = out.extra_a[0], out.extra_b[0]
        for array in (point_a, point_b, extra_a, extra_b):
            array.flags.writeable = False
        fields = {
            "distance": np.float64(max(float(signed), 0.0) + 0.0),
            "sqr_distance": out.sqr_distance[0],
            "point_a": point_a,
            "point_b": point_b,
            "feature_a": out.feature_a[0],
            "feature_b": out.feature_b[0],
            "parameter_a": _NAN,
            "parameter_b": _NAN,
            "barycentric_a": extra_a,
            "barycentric_b": extra_b,
            "face_a": out.index_a[0],
            "face_b": out.index_b[0],
            "primitive_a": _MINUS1,
            "primitive_b": _MINUS1,
            "source_a": _MINUS1,
            "source_b": _MINUS1,
        }
        turn = None if pose is None else (pose[:, :3], pose[:, 3])
        rows = (out.point_a.reshape(3), out.point_b.reshape(3), out.distance.reshape(()),
                out.feature_a.reshape(()), out.feature_b.reshape(()), out.index_a.reshape(()),
                out.index_b.reshape(()))  # fmt: skip
        result = _new(PairResult)
        result.__dict__.update(fields)
        result.__dict__[_PAIR] = PairNormals(mesh_a, mesh_b, *rows, pose=turn, back=None, dim=3)
        return result


_mesh_pairs = weakref.WeakKeyDictionary()  # tree of a -> {tree of b: {(method, posed): _MeshPair}}
_last = (lambda: None, lambda: None, None, None)  # the last pair asked: (weak a, weak b, key, _MeshPair)


def mesh_pair(a, b, method):
    """``(prepared fast path, 3 x 4 pose or None)`` of ``distance(a, b, method=method)``, or None
    where ``a`` is not a :class:`~proximity.TriangleMesh` and ``b`` one or a posed one."""
    if type(a) is not TriangleMesh or method not in ("robust", "certified"):
        return None
    pose = None
    if type(b) is Posed:
        pose, b = pose_matrix(b.rotation, b.translation)[:3], b.shape  # as _poses and _pose_array give it
    if type(b) is not TriangleMesh:
        return None
    global _last
    tree_a, tree_b, key = a._tree, b._tree, (method, pose is not None)
    ref_a, ref_b, last_key, fast = _last
    if ref_a() is tree_a and ref_b() is tree_b and last_key == key:
        return fast, pose
    prepared = _mesh_pairs.get(tree_a)
    if prepared is None:
        prepared = _mesh_pairs[tree_a] = weakref.WeakKeyDictionary()
    prepared = prepared.setdefault(tree_b, {})
    fast = prepared.get(key)
    if fast is None:
        fast = prepared[key] = _MeshPair(a, b, resolve(method), pose is not None)
    _last = (weakref.ref(tree_a), weakref.ref(tree_b), key, fast)
    return fast, pose
