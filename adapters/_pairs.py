"""What the backends share for queries between two shapes: the sides taken apart, and the translation.

A pair query gives the library two shapes and reads back a distance and a
witness point on each.  :func:`closest_points` validates and broadcasts the
pair with proximity itself (which names both arguments in its errors),
takes each side apart into the kind of model a library can be given
(:class:`Side`), asks the backend's ``_pairs`` for the raw answers of every
row, and translates them (:func:`_translate`) into proximity's
:class:`proximity.PairResult` with a :class:`Failure` code per row.

Conventions translated
----------------------
Contact
    Libraries answer overlapping shapes in their own ways: fcl returns -1,
    or 0 with witness points that are not a common point, or a negative
    value for capsules; trimesh a negative value that is not a depth;
    pybullet the negative depth between the surfaces.  Every answer within
    the row's tolerance of 0, or below it, is contact.  Where proximity puts
    the shapes farther apart than twice the tolerance, the row is
    ``FALSE_TOUCHING``.  Otherwise the distance is 0 (as proximity's
    :func:`~proximity.distance` gives it) and the witness points are kept
    only if they are one common point of both shapes; if not, the row is
    ``CONTACT``: distance 0, witness points NaN.
Witness points
    Away from contact, each witness must be on its shape (a rounded shape's
    surface) within the tolerance, else ``POINT_OFF_SHAPE`` (or
    ``CONVEX_HULL`` where the library was given that side's convex hull),
    and the two must be the reported distance apart, else ``INCONSISTENT``.

Frame
    A backend made with ``rescale=True`` (the default) is given each pair in
    a frame of its own (:func:`scaled`: centered on it and scaled by a power
    of two to a size of about 1), and its answers are moved back
    (:func:`unscaled`); with ``rescale=False``, in the caller's coordinates.
    The choice is made here, for every backend: a backend's ``_pairs``
    answers the query it is given.

Tolerance of a row: ``rtol * (S + L)``, with ``S`` the pair's size (the
largest coordinate difference between the vertices of both shapes, in the
world, plus both radii; a mesh counts by its bounding box), ``L`` the
largest coordinate magnitude the library worked with, and ``rtol`` the
backend's for the pair of kinds (:meth:`Backend.pair_rtol`).  In the frame
of :func:`scaled`, ``L`` is about ``S`` and ``8 eps M`` is added for the
moves into the frame and back, ``M`` the largest coordinate magnitude in
the world; in the caller's coordinates ``L = M``.
"""

from dataclasses import dataclass, field, replace

import numpy as np

import proximity
from proximity import Feature, TriangleMesh
from proximity.results import PairResult
from proximity.shapes.base import Point, Segment, Triangle
from proximity.shapes.posed import Posed
from proximity.shapes.rounded import Inflated

from ._common import EPS, Failure, Model, best_method, norm, pow2_scale

#: Kind of each core type, and of its rounded form.
_KINDS = {Point: ("point", "sphere"), Segment: ("segment", "capsule"), Triangle: ("triangle", None)}


@dataclass(frozen=True)
class Side:
    """One argument of a pair query, as a library can be given it.

    Attributes
    ----------
    name : {"a", "b"}
    kind : {"point", "sphere", "segment", "capsule", "triangle", "mesh"}
    vertices : ndarray of float64
        A primitive batch's vertices in the shape's own frame, one row per
        member of the side's batch, ``(count, k, 3)`` (``k`` = 1, 2 or 3);
        a mesh's vertices ``(V, 3)``.
    faces : ndarray of int64, shape ``(F, 3)``, or None
        A mesh's faces.
    radius : ndarray of float64, shape ``(count,)``
        Each member's radius (0 for unrounded kinds).
    rotation, translation : ndarray, shapes ``(3, 3)`` and ``(3,)``
        The pose of the frame of :attr:`vertices` in the world (identity
        where the shape is not posed).
    posed : bool
        Whether the shape was a posed view.
    index : ndarray of int64, shape ``(n,)``
        The member answering each row of the broadcast pair.
    shape : Shape
        The argument itself, for the checks.
    """

    name: str
    kind: str
    vertices: np.ndarray
    faces: object
    radius: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    posed: bool
    index: np.ndarray
    shape: object

    @property
    def rounded(self):
        return self.kind in ("sphere", "capsule")

    def world(self, vertices):
        """``vertices`` (any shape ``(..., 3)``) of this side's frame, in the world."""
        return vertices @ self.rotation.T + self.translation

    def transform(self):
        """The 4x4 matrix of the pose."""
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = self.rotation, self.translation
        return m

    def extent(self):
        """Per member, ``(low, high)`` corners of its vertices' box in the world, ``(count, 3)`` each."""
        if self.kind == "mesh":
            w = self.world(self.vertices)
            return w.min(axis=0)[None], w.max(axis=0)[None]
        w = self.world(self.vertices)
        return w.min(axis=1), w.max(axis=1)


@dataclass(frozen=True)
class PairQuery:
    """The validated pair, flattened to rows: what a backend's ``_pairs`` sees."""

    a: Side
    b: Side
    n: int


@dataclass(frozen=True)
class PairRaw:
    """A library's answers for the rows of a :class:`PairQuery`, before translation.

    ``distance`` is the library's own number (negative in contact, where
    the library says so); ``point_a`` and ``point_b`` its witnesses in the
    world; ``failure`` the library-level codes (OK, NO_RESULT, SENTINEL,
    EXCEPTION); ``face_a``, ``face_b`` the faces of mesh sides where the
    library reports them; ``hull`` the names of the mesh sides the library
    was given as their convex hull; ``models`` the description of a side's
    model where it is not the backend's ``pair_models`` entry; ``margin``
    the collision margin read back; ``origin`` the origin of the frame of
    :func:`scaled` where the library was asked in it (set by :func:`unscaled`).
    """

    distance: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    failure: np.ndarray
    face_a: object = None
    face_b: object = None
    hull: tuple = ()
    models: dict = field(default_factory=dict)
    origin: object = None
    margin: float = float("nan")

    @classmethod
    def empty(cls, n, **options):
        return cls(
            np.full(n, np.nan),
            np.full((n, 3), np.nan),
            np.full((n, 3), np.nan),
            np.full(n, Failure.OK, dtype=np.int8),
            **options,
        )


def _unwrap(shape, name):
    """``(core, radius or None, rotation, translation, posed)`` of an argument."""
    rotation, translation, radius, posed = np.eye(3), np.zeros(3), None, False
    core = shape
    while isinstance(core, (Posed, Inflated)):
        if isinstance(core, Posed):
            # An outer pose applied to the inner one: X -> R_out (R_in X + t_in) + t_out.
            translation = rotation @ core.translation + translation
            rotation = rotation @ core.rotation
            posed = True
            core = core.shape
        else:
            radius = core.radius if radius is None else radius + core.radius
            core = core.core
    if not isinstance(core, proximity.Shape):
        raise TypeError(f"{name} must be a proximity shape; got {type(shape).__name__}")
    if core.dim != 3:
        # proximity answers 2D pairs; the libraries are 3D only.
        raise NotImplementedError(
            f"{name} is a {core.dim}D shape: the backends' pair queries take 3D shapes only"
        )
    return core, radius, rotation, translation, posed


def side(shape, name, out_shape):
    """The :class:`Side` of argument ``name``, its rows broadcast to ``out_shape``.

    Raises
    ------
    NotImplementedError
        For a shape no backend can be given in a pair query (disks, circles,
        scenes, rounded triangles and meshes), naming the argument.
    """
    core, radius, rotation, translation, posed = _unwrap(shape, name)
    batch = shape.batch_shape
    count = int(np.prod(batch, dtype=np.int64))
    index = np.broadcast_to(np.arange(count).reshape(batch), out_shape).reshape(-1)
    r = np.zeros(count) if radius is None else np.broadcast_to(radius, batch).reshape(-1).astype(np.float64)
    if isinstance(core, TriangleMesh) and radius is None:
        kind, faces = "mesh", np.asarray(core.faces, np.int64)
        vertices = np.asarray(core.vertices, np.float64)
    elif type(core) in _KINDS and _KINDS[type(core)][radius is not None] is not None:
        kind, faces = _KINDS[type(core)][radius is not None], None
        v = np.asarray(core.position if type(core) is Point else core.vertices, np.float64)
        if type(core) is Point:
            v = v[..., None, :]
        vertices = np.broadcast_to(v, batch + v.shape[-2:]).reshape((count,) + v.shape[-2:])
    else:
        what = type(core).__name__ if radius is None else f"rounded {type(core).__name__}"
        raise NotImplementedError(
            f"{name} is a {what}: the backends' pair queries take points, spheres, segments, capsules, "
            "triangles and meshes (posed or not)"
        )
    return Side(name, kind, vertices, faces, r, rotation, translation, posed, index, shape)


def _on_shape(s, points, out_shape):
    """Distance of each row's point to side ``s`` (to a rounded side's surface), by proximity."""
    shape = s.shape
    p = points.reshape(out_shape + (3,))
    method = best_method(shape)
    if s.rounded:
        d = np.abs(np.asarray(shape.signed_distance(p, method=method), np.float64))
    else:
        d = np.asarray(shape.distance(p, method=method), np.float64)
    return np.broadcast_to(d, out_shape).reshape(-1)


def _scales(a, b, origin=None):
    """Per row: the pair's size ``S`` (both radii included), and the largest coordinate
    magnitude ``L`` the library worked with (in the caller's unit): of the world
    coordinates, or where the library was given the frame of :func:`scaled` at ``origin``,
    of the coordinates relative to it (a posed side's: its own vertices', plus its
    translation's)."""
    low_a, high_a = a.extent()
    low_b, high_b = b.extent()
    low = np.minimum(low_a[a.index], low_b[b.index])
    high = np.maximum(high_a[a.index], high_b[b.index])
    size = np.max(high - low, axis=1) + a.radius[a.index] + b.radius[b.index]
    if origin is None:
        return size, np.maximum(np.max(np.abs(low), axis=1), np.max(np.abs(high), axis=1))
    magnitude = np.zeros(len(size))
    for s in (a, b):  # per member of the side (a mesh is one), then per row
        if s.posed:
            v = np.abs(s.vertices)
            member = np.array([v.max(initial=0.0)]) if s.kind == "mesh" else v.max(axis=(1, 2), initial=0.0)
            member = member + np.max(np.abs(s.translation - origin))
        else:
            lo, hi = s.extent()
            member = np.maximum(np.abs(lo - origin), np.abs(hi - origin)).max(axis=1)
        magnitude = np.maximum(magnitude, member[s.index])
    return size, magnitude


def _world_magnitude(a, b):
    """Per row: the largest coordinate magnitude of the pair's vertices in the world."""
    return _scales(a, b)[1]


def _translate(raw, a, b, tolerance, reference, out_shape):
    """The library's answers translated (see the module docstring): new arrays
    ``(distance, point_a, point_b, failure)``, flat."""
    distance = raw.distance.copy()
    pa, pb = raw.point_a.copy(), raw.point_b.copy()
    failure = raw.failure.copy()
    ok = failure == Failure.OK
    contact = ok & ~(distance > tolerance)
    false = contact & (reference > 2.0 * tolerance)
    # Contact with a convex hull where the shapes are apart is the hull's doing.
    failure[false] = Failure.CONVEX_HULL if raw.hull else Failure.FALSE_TOUCHING
    contact &= ~false
    ok &= ~false
    distance[contact] = 0.0
    if ok.any():
        safe_a = np.where(ok[:, None] & np.isfinite(pa), pa, 0.0)
        safe_b = np.where(ok[:, None] & np.isfinite(pb), pb, 0.0)
        off_a = _on_shape(a, safe_a, out_shape)
        off_b = _on_shape(b, safe_b, out_shape)
        finite = np.isfinite(pa).all(axis=1) & np.isfinite(pb).all(axis=1)
        on = finite & (off_a <= tolerance) & (off_b <= tolerance)
        gap = norm(safe_b - safe_a)
        # In contact the witnesses are kept only as a common point of both shapes.
        common = contact & on & (gap <= tolerance)
        failure[contact & ~common] = Failure.CONTACT
        far = ok & ~contact
        off = far & ~on
        hull = (off_b > tolerance) & ("b" in raw.hull) | (off_a > tolerance) & ("a" in raw.hull)
        failure[off & finite & hull] = Failure.CONVEX_HULL
        failure[off & ~(finite & hull)] = Failure.POINT_OFF_SHAPE
        inconsistent = far & on & ~(np.abs(gap - distance) <= tolerance)
        failure[inconsistent] = Failure.INCONSISTENT
    kept = failure == Failure.OK
    distance[~kept & (failure != Failure.CONTACT)] = np.nan
    pa[~kept] = np.nan
    pb[~kept] = np.nan
    return distance, pa, pb, failure


#: The result fields each kind of side has in proximity's answer.
_SIDE_FIELDS = {
    "point": (),
    "sphere": (),
    "segment": ("parameter",),
    "capsule": ("parameter",),
    "triangle": ("barycentric",),
    "mesh": ("barycentric", "face"),
}


def closest_points(backend, a, b):
    """:meth:`Backend.closest_points`: validate, ask the backend's ``_pairs``, translate."""
    from ._common import BackendResult

    for name, value in (("a", a), ("b", b)):
        if not isinstance(value, proximity.Shape):
            raise TypeError(f"{name} must be a proximity shape; got {type(value).__name__}")
    # proximity validates the pair (dimensions, broadcasting, supported kinds), naming
    # both arguments, and gives the distance every answer is checked against.
    method = "certified" if "certified" in a.methods and "certified" in b.methods else "robust"
    reference = np.asarray(proximity.distance(a, b, method=method), np.float64)
    out_shape = reference.shape
    sa, sb = side(a, "a", out_shape), side(b, "b", out_shape)
    kinds = backend.pair_models
    if sa.kind not in kinds or sb.kind not in kinds:
        raise NotImplementedError(
            f"the {backend.name} backend has no pair query for a {sa.kind} (a) and a {sb.kind} (b); "
            f"it takes {', '.join(kinds)}"
        )
    query = PairQuery(sa, sb, int(reference.size))
    if not query.n:
        raw = PairRaw.empty(0)
    elif backend.rescale:
        framed, origin, factor = scaled(query)
        raw = unscaled(backend._pairs(framed), origin, factor)
    else:
        raw = backend._pairs(query)
    size, magnitude = _scales(sa, sb, raw.origin)
    rtol = backend.pair_rtol(sa.kind, sb.kind)
    tolerance = rtol * (size + magnitude)
    if raw.origin is not None:
        # Moving the pair into the library's frame and its answer back rounds each
        # coordinate once or twice, by eps of the world's magnitude.
        tolerance += 8 * EPS * _world_magnitude(sa, sb)
    distance, pa, pb, failure = _translate(raw, sa, sb, tolerance, reference.reshape(-1), out_shape)

    values, unknown = {}, ["feature_a", "feature_b"]
    with np.errstate(over="ignore", under="ignore"):
        values.update(distance=distance, sqr_distance=distance * distance, point_a=pa, point_b=pb)
    values["feature_a"] = values["feature_b"] = np.full(query.n, Feature.NONE, np.int8)
    for s, face in ((sa, raw.face_a), (sb, raw.face_b)):
        key = s.name
        fields = _SIDE_FIELDS[s.kind]
        values[f"parameter_{key}"] = np.full(query.n, np.nan)
        values[f"barycentric_{key}"] = np.full((query.n, 3), np.nan)
        given = np.full(query.n, -1, np.int64)
        if s.kind == "mesh" and face is not None:
            given = np.where(failure == Failure.OK, np.asarray(face, np.int64), -1)
        values[f"face_{key}"] = given
        for name in ("primitive", "source"):
            values[f"{name}_{key}"] = np.full(query.n, -1, np.int64)
        unknown += [f"{f}_{key}" for f in fields if f != "face" or face is None]
    result = PairResult(
        **{name: np.asarray(v).reshape(out_shape + np.shape(v)[1:]) for name, v in values.items()}
    )
    model = Model(
        library=backend.library,
        primitive="; ".join(f"{s.name}: {raw.models.get(s.name, kinds[s.kind])}" for s in (sa, sb)),
        probe=backend.pair_probe,
        segments=np.zeros(out_shape, np.int64),
        bound=np.zeros(out_shape),
        margin=float(raw.margin),
        rtol=rtol,
        frame=backend.pair_frame,
    )
    return BackendResult(
        result=result,
        failure=failure.reshape(out_shape),
        tolerance=tolerance.reshape(out_shape),
        model=model,
        unknown=tuple(unknown),
        backend=backend.name,
    )


def extent(query):
    """``(low, high)``: the corners of the box around both sides of ``query``, every member."""
    lows, highs = zip(*(s.extent() for s in (query.a, query.b)), strict=True)
    return np.min([x.min(axis=0) for x in lows], axis=0), np.max([x.max(axis=0) for x in highs], axis=0)


def scaled(query):
    """``(query, origin, factor)``: the pair in one frame for all its rows, where the
    libraries' absolute tolerances act relative to the pair.

    The frame's origin is the center of both sides' boxes, and ``factor`` the power of two
    that brings their extent (and radii) into ``[0.5, 1)``.  An unposed side's vertices
    become ``(V - origin) factor``; a posed side's are only scaled (exactly), its pose
    keeps its rotation and its translation becomes ``(t - origin) factor``.
    """
    a, b = query.a, query.b
    low, high = extent(query)
    origin = low * 0.5 + high * 0.5
    radius = max(float(a.radius.max(initial=0.0)), float(b.radius.max(initial=0.0)))
    factor = float(pow2_scale(max(float(np.max(high - low)), radius)))

    def move(s):
        if not s.posed:  # moved with its vertices, so that the library sees small coordinates
            return replace(s, vertices=(s.vertices - origin) * factor, radius=s.radius * factor)
        translation = (s.translation - origin) * factor
        return replace(s, vertices=s.vertices * factor, radius=s.radius * factor, translation=translation)

    return PairQuery(move(a), move(b), query.n), origin, factor


def unscaled(raw, origin, factor):
    """``raw``, answered in the frame of :func:`scaled`, in the caller's coordinates."""
    return replace(
        raw,
        distance=raw.distance / factor,
        point_a=raw.point_a / factor + origin,
        point_b=raw.point_b / factor + origin,
        margin=raw.margin / factor,
        origin=origin,
    )


def pair_scale(a, b):
    """The pair's size ``S`` per row of the broadcast pair (both radii included)."""
    out_shape = np.broadcast_shapes(a.batch_shape, b.batch_shape)
    return _scales(side(a, "a", out_shape), side(b, "b", out_shape))[0].reshape(out_shape)


def local_frame(direction):
    """Rotations ``(n, 3, 3)`` whose third column is each unit ``direction`` (rows)."""
    from ._common import plane_frame

    u, v = plane_frame(direction)
    return np.stack([u, v, direction], axis=-1)


def segment_frames(vertices):
    """Of segments ``(n, 2, 3)``: rotations ``(n, 3, 3)`` taking z along each, midpoints
    ``(n, 3)`` and lengths ``(n,)``.

    A segment of length 0 is a point: any axis will do.
    """
    axis = vertices[:, 1] - vertices[:, 0]
    length = norm(axis)
    safe = np.where(length > 0, length, 1.0)[:, None]
    direction = np.where(length[:, None] > 0, axis / safe, [0.0, 0.0, 1.0])
    # Normalise again: the division rounds, and the frame must be orthonormal.
    direction = direction / np.linalg.norm(direction, axis=1, keepdims=True)
    return local_frame(direction), vertices.mean(axis=1), length


def quaternion(rotation):
    """``(x, y, z, w)`` of a rotation matrix (Shepperd's method: the largest of the four first)."""
    m = np.asarray(rotation, np.float64)
    trace = np.trace(m)
    diag = np.diag(m)
    k = int(np.argmax([trace, *diag]))
    if k == 0:
        w = np.sqrt(1.0 + trace) / 2.0
        q = [(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w), (m[1, 0] - m[0, 1]) / (4 * w), w]
    else:
        i = k - 1
        j, h = (i + 1) % 3, (i + 2) % 3
        s = np.sqrt(1.0 + m[i, i] - m[j, j] - m[h, h]) / 2.0
        q = [0.0, 0.0, 0.0, (m[h, j] - m[j, h]) / (4 * s)]
        q[i] = s
        q[j] = (m[j, i] + m[i, j]) / (4 * s)
        q[h] = (m[h, i] + m[i, h]) / (4 * s)
    q = np.asarray(q)
    return q / np.linalg.norm(q)
