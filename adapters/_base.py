"""What every backend shares: failure codes, model descriptions, results and the translation.

A backend asks its library one question per query row and hands back the
library's raw answer (a distance, a nearest point, or a library-level failure
such as "no result" or a sentinel).  :meth:`Backend.closest_point` then turns
that into proximity's own result type, checking each answer against the
geometry with proximity's most accurate method, so that contradictions become
NaN with a reason instead of numbers that look like answers.

Every tolerance here is relative: a row's tolerance is the Hausdorff distance
between the shape and the model the library was given (zero for an exact
primitive) plus ``rtol * (S + M)``, where ``S`` is the scale proximity's own
bound uses (``max_i |P - V_i|`` for a triangle, ``|P - C| + R`` for a disk or
circle) and ``M`` the largest coordinate magnitude of the point and the shape,
since a library that returns absolute coordinates cannot round them to
better than ``eps * M``.
"""

from dataclasses import dataclass, fields

import numpy as np

import proximity
from proximity import Feature, TriangleMesh, primitives

from ._common import (
    CALLER,
    EPS,
    PAIR_FRAME,
    WORLD,
    BackendResult,
    Failure,
    Model,
    best_method,
    library_version,
    norm,
    sagitta,
    segments_for,
    unit,
)
from ._pairs import closest_points as _closest_points


@dataclass(frozen=True)
class Query:
    """A validated query, flattened to rows: what the library layer sees.

    Attributes
    ----------
    kind : {"triangle", "disk", "circle", "mesh"}
    index : ndarray of int64, shape ``(n,)``
        Which shape (in the flattened batch) each row asks about.
    points : ndarray of float64, shape ``(n, 3)``
        Finite query points only: rows with NaN or inf are never passed.
    vertices : ndarray, shape ``(m, 3, 3)``
        Triangles (2D ones embedded in ``z = 0``); for a mesh, its vertices
        ``(V, 3)``; None for round shapes.
    center, normal, radius : ndarray, shapes ``(m, 3)``, ``(m, 3)``, ``(m,)``
        Round shapes, with unit normals; None for triangles.
    segments : ndarray of int64, shape ``(m,)``
        ``K`` for each shape; 0 where the backend does not tessellate.
    faces : ndarray of int64, shape ``(F, 3)``
        A mesh's faces, indexing ``vertices``; None for other shapes.
    """

    kind: str
    index: np.ndarray
    points: np.ndarray
    vertices: object
    center: object
    normal: object
    radius: object
    segments: np.ndarray
    faces: object = None

    def groups(self):
        """``(shape index, row positions in this query)`` for each shape that has rows."""
        if len(self.index) == 0:
            return
        order = np.argsort(self.index, kind="stable")
        cuts = np.flatnonzero(np.diff(self.index[order])) + 1
        for chunk in np.split(order, cuts):
            yield int(self.index[chunk[0]]), chunk


@dataclass(frozen=True)
class Raw:
    """A library's answers for the rows of a :class:`Query`, before translation.

    ``distance`` and ``point`` are the library's numbers in the caller's
    coordinates (already converted from any rescaled frame); ``failure``
    holds the library-level codes (OK, NO_RESULT, SENTINEL, EXCEPTION);
    ``face`` the index of the nearest face of a mesh where the library
    reports it (None where it does not, -1 in rows without an answer).
    """

    distance: np.ndarray
    point: np.ndarray
    failure: np.ndarray
    margin: float = float("nan")
    face: object = None

    @classmethod
    def empty(cls, n):
        return cls(np.full(n, np.nan), np.full((n, 3), np.nan), np.full(n, Failure.OK, dtype=np.int8))


class Backend:
    """Base of the backends: one library behind proximity's query interface.

    Subclasses set the class attributes and implement ``_triangles``,
    ``_disks``, ``_circles`` and ``_meshes`` over a :class:`Query` and
    ``_pairs`` over a :class:`~proximity.adapters._pairs.PairQuery`; this
    class validates, broadcasts, translates and builds the result.
    Backends are context managers; :meth:`close` releases whatever the
    library holds.

    Parameters
    ----------
    rescale : bool, optional, keyword-only
        Ask the library in a frame of each query's own (default True): a
        pair centered on its shapes' boxes and scaled by a power of two to a
        size of about 1 (:func:`~proximity.adapters._pairs.scaled`), and, for
        the backends that do so, each point query's row or shape likewise,
        so that libraries with absolute tolerances answer as they do at a
        unit size.  With False the library is given the caller's
        coordinates, as it would be used directly, and the backend's name
        ends in ``[raw]``.  :attr:`frame` and :attr:`pair_frame` say where
        the library worked.
    """

    #: Registry name; an instance asked in the caller's coordinates adds ``[raw]``.
    name = ""
    #: Distribution on PyPI, for the version string.
    distribution = ""
    #: Relative accuracy documented for the library's arithmetic.
    rtol = 64 * EPS
    #: Native model of each kind of shape, for :class:`Model`.
    primitives = {}
    #: How the query point is given to the library.
    probe = ""
    #: Coordinates the library works in for point queries, by the value of ``rescale``.
    point_frames = {True: CALLER, False: CALLER}
    #: Kinds of shape the library models by tessellation.
    tessellated = ()

    def __init__(self, *, rescale=True):
        self.rescale = bool(rescale)
        if not self.rescale:
            self.name = f"{type(self).name}[raw]"

    @property
    def frame(self):
        """Coordinates the library works in for point queries."""
        return self.point_frames[self.rescale]

    @property
    def pair_frame(self):
        """Coordinates the library works in for pair queries."""
        return self.pair_frames[self.rescale]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        """Release what the library holds; the base backend holds nothing."""

    def __repr__(self):
        return f"<{type(self).__name__} {self.name!r}>"

    @property
    def library(self):
        """``"distribution version"`` of the wrapped library."""
        return library_version(self.distribution)

    def distance(self, shape, points, *, tol=None):
        """Distances from ``points`` to ``shape``, or between two shapes, as the library gives them.

        Parameters and broadcasting are those of :meth:`closest_point`; where
        ``points`` is a shape too, those of :meth:`closest_points` (``tol``
        is then not used), as :func:`proximity.distance` does.

        Returns
        -------
        ndarray of float64, shape ``batch``
            NaN where the row failed (0 for ``CONTACT``); a NumPy scalar for
            one point against one shape, or one pair.
        """
        if isinstance(points, proximity.Shape):
            return self.closest_points(shape, points).result.distance
        return self.closest_point(shape, points, tol=tol).result.distance

    #: Native model of each kind of side of a pair query, for :class:`Model`;
    #: the kinds the backend answers pairs of.
    pair_models = {}
    #: How a pair is given to the library.
    pair_probe = ""
    #: Coordinates the library works in for pairs, by the value of ``rescale``.
    pair_frames = {True: PAIR_FRAME, False: f"{WORLD}, each shape at its pose"}

    def pair_rtol(self, kind_a, kind_b):
        """Relative accuracy documented for the library on a pair of kinds; :attr:`rtol` by default."""
        return self.rtol

    def closest_points(self, a, b):
        """Ask the library for the closest points of two shapes.

        Parameters
        ----------
        a, b : Shape
            Each a point, segment or triangle batch, a :class:`proximity.Sphere`
            or :class:`proximity.Capsule` batch (points and segments inflated),
            or a :class:`proximity.TriangleMesh`; any of them posed
            (``shape.transformed(T)``: the pose is given to the library as
            the object's transform where it takes one).  Batches broadcast
            as in :func:`proximity.closest_points`.  Which kinds a backend
            takes is in its ``pair_models``.

        Returns
        -------
        BackendResult
            A :class:`proximity.PairResult` in ``.result`` (distance,
            witness points ``point_a`` and ``point_b``; ``face_a`` and
            ``face_b`` where the library reports them, the other fields
            listed in ``unknown``), a :class:`Failure` code and a tolerance
            per row, and the :class:`Model`.  Contact is distance 0 (with
            ``CONTACT`` where the library gives no common point), as
            :func:`proximity.distance` gives it: no library's depth is kept.
            The tolerance is ``rtol (S + L) + 8 eps M``: ``S`` the pair's
            size (the largest coordinate difference between the vertices of
            both shapes, plus both radii), ``L`` the coordinate magnitude in
            the library's frame (with ``rescale``, a frame of the pair's
            own: about ``S``) and ``M`` in the world, ``rtol`` the backend's
            :meth:`pair_rtol`; without ``rescale``, ``L = M`` and the
            ``8 eps M`` of the moves into the frame and back is not added.

        Raises
        ------
        ValueError
            Where proximity refuses the pair (different dimensions, batches
            that do not broadcast), naming both arguments.
        NotImplementedError
            For a kind of shape, or a pair of kinds, the backend cannot
            give its library (2D shapes among them), naming the argument or
            both.

        Examples
        --------
        >>> import proximity, proximity.adapters as adapters
        >>> a = proximity.Capsule([[0, 0, -1], [0, 0, 1]], radius=0.5)
        >>> b = proximity.Capsule([[3, -1, 0], [3, 1, 0]], radius=0.5)
        >>> with adapters.get("fcl") as fcl:
        ...     r = fcl.closest_points(a, b)
        >>> float(r.distance), r.point_a.tolist(), r.point_b.tolist(), r.failure.name
        (2.0, [0.5, 0.0, 0.0], [2.5, 0.0, 0.0], 'OK')
        """
        return _closest_points(self, a, b)

    def _pairs(self, query):
        raise NotImplementedError

    def closest_point(self, shape, points, *, tol=None):
        """Ask the library for the closest point on ``shape`` to each of ``points``.

        Parameters
        ----------
        shape : proximity.Triangle, proximity.Disk, proximity.Circle or proximity.TriangleMesh
            One shape or a batch (a mesh is one shape).
        points : array_like, shape ``(..., D)``
            Query points, broadcast against the shape's batch like
            :func:`proximity.closest_point`.
        tol : float, optional
            Modelling tolerance, in the caller's length unit, for shapes the
            library has no primitive for: they are cut into the fewest
            segments whose sagitta is at most ``tol``.  Default ``1e-3 R``.

        Returns
        -------
        BackendResult
            proximity's result type in ``.result``, with a failure code,
            a documented tolerance per row and a description of the model.

        Raises
        ------
        TypeError
            If ``shape`` is not a proximity shape.
        ValueError
            Where proximity refuses the points (naming ``points``).
        NotImplementedError
            For a proximity shape the backend cannot give its library
            (rounded or posed shapes, scenes, and kinds not in its
            ``primitives``), naming it.
        """
        if not isinstance(shape, proximity.Shape):
            raise TypeError(f"shape must be a proximity shape; got {type(shape).__name__}")
        method = best_method(shape)
        # proximity validates the points (and names the argument) and gives
        # the geometry every answer is checked against.
        reference = np.asarray(shape.distance(points, method=method), dtype=np.float64)
        out_shape = reference.shape
        kind, data, check_shape = _flatten_shape(shape)
        if kind not in self.primitives:
            kinds = ", ".join(self.primitives)
            raise NotImplementedError(f"the {self.name} backend has no model of a {kind}; it has {kinds}")
        points3 = _to_3d(np.asarray(points, dtype=np.float64))
        all_points = np.broadcast_to(points3, out_shape + (3,)).reshape(-1, 3)
        n = all_points.shape[0]
        count = int(np.prod(shape.batch_shape, dtype=np.int64))
        index = np.broadcast_to(np.arange(count).reshape(shape.batch_shape), out_shape).reshape(-1)
        finite = np.isfinite(all_points).all(axis=1)

        if kind in self.tessellated:
            segments = segments_for(data["radius"], tol)
            bound = sagitta(data["radius"], segments)
        else:
            segments = np.zeros(count, dtype=np.int64)
            bound = np.zeros(count)
        rows = np.flatnonzero(finite)
        query = Query(
            kind=kind,
            index=index[rows],
            points=all_points[rows],
            segments=segments,
            vertices=data.get("vertices"),
            center=data.get("center"),
            normal=data.get("normal"),
            radius=data.get("radius"),
            faces=data.get("faces"),
        )
        raw = getattr(self, "_meshes" if kind == "mesh" else f"_{kind}s")(query)

        distance = np.full(n, np.nan)
        point = np.full((n, 3), np.nan)
        failure = np.full(n, Failure.NAN_INPUT, dtype=np.int8)
        distance[rows] = raw.distance
        point[rows] = raw.point
        failure[rows] = raw.failure
        face = None
        if raw.face is not None:
            face = np.full(n, -1, dtype=np.int64)
            face[rows] = raw.face

        scale, magnitude = _scales(kind, data, index, all_points)
        tolerance = bound[index] + self.rtol * (scale + magnitude)
        tolerance[~finite] = np.nan
        _translate(
            distance,
            point,
            failure,
            all_points,
            tolerance,
            reference.reshape(-1),
            check_shape,
            out_shape,
        )

        bad = failure != Failure.OK
        distance[bad] = np.nan
        point[bad] = np.nan
        if face is not None:
            face[bad] = -1
        model = Model(
            library=self.library,
            primitive=self.primitives[kind],
            probe=self.probe,
            segments=segments.reshape(shape.batch_shape),
            bound=bound.reshape(shape.batch_shape),
            margin=float(raw.margin),
            rtol=self.rtol,
            frame=self.frame,
        )
        result, unknown = _result(shape.result_type, shape.dim, out_shape, distance, point, face)
        return BackendResult(
            result=result,
            failure=failure.reshape(out_shape),
            tolerance=tolerance.reshape(out_shape),
            model=model,
            unknown=unknown,
            backend=self.name,
        )

    def _triangles(self, query):
        raise NotImplementedError

    def _disks(self, query):
        raise NotImplementedError

    def _circles(self, query):
        raise NotImplementedError

    def _meshes(self, query):
        raise NotImplementedError


def _to_3d(array):
    if array.shape[-1] == 3:
        return array
    return np.concatenate([array, np.zeros(array.shape[:-1] + (1,))], axis=-1)


def _flatten_shape(shape):
    """``(kind, flattened data, the shape in 3D for the geometric checks)``.

    A primitive batch's data are its constructor's arrays (broadcast over
    the batch, one row per member, coordinates in 3D, normals of unit
    length), under their names; its kind is its primitive's name.  A 2D
    shape is checked as its embedding in ``z = 0``, so that a returned point
    off that plane counts as off the shape.
    """
    batch = shape.batch_shape
    if isinstance(shape, TriangleMesh):
        return "mesh", {"vertices": shape.vertices, "faces": shape.faces}, shape
    primitive = getattr(shape, "_primitive", None)
    if primitive is None:
        # A proximity shape all the same (rounded, posed, a scene): the libraries have no model of it.
        raise NotImplementedError(
            f"shape is a {type(shape).__name__}: the backends' point queries take triangles, disks, "
            "circles and meshes"
        )
    data, embedded = {}, []
    for name, core in shape._fields:
        array = np.asarray(getattr(shape, name))
        array = np.broadcast_to(array, batch + array.shape[array.ndim - core :])
        if core and array.shape[-1] == shape.dim:  # coordinates
            array = _to_3d(array)
        embedded.append(array)
        data[name] = array.reshape((-1,) + array.shape[len(batch) :]).astype(np.float64)
    if "normal" in data:
        data["normal"] = unit(data["normal"])
    if "position" in data:
        data["vertices"] = data.pop("position")[:, None, :]
    check = shape if shape.dim == 3 else type(shape)(*embedded)
    return primitive.name, data, check


def error_scale(shape, points):
    """proximity's error scale ``S`` of each query row, of the broadcast shape.

    ``S = max_i |P - V_i|`` for a triangle, ``|P - C| + R`` for a disk or
    circle: proximity's ``robust`` method is accurate to ``8 eps S``.  For a
    mesh, ``|P - C| + R`` for the sphere ``(C, R)`` around the vertices'
    bounding box, which bounds ``S`` of every face.
    """
    points = np.asarray(points, dtype=np.float64)
    out_shape = np.broadcast_shapes(points.shape[:-1], shape.batch_shape)
    kind, data, _ = _flatten_shape(shape)
    count = int(np.prod(shape.batch_shape, dtype=np.int64))
    index = np.broadcast_to(np.arange(count).reshape(shape.batch_shape), out_shape).reshape(-1)
    rows = np.broadcast_to(_to_3d(points), out_shape + (3,)).reshape(-1, 3)
    return _scales(kind, data, index, rows)[0].reshape(out_shape)


def _scales(kind, data, index, points):
    """Per row: proximity's error scale ``S`` and the coordinate magnitude ``M``."""
    magnitude = np.max(np.abs(points), axis=1, initial=0.0)
    if kind != "mesh" and "vertices" in data:  # the hull of its vertices
        v = data["vertices"][index]
        scale = np.max(norm(v - points[:, None, :]), axis=1, initial=0.0)
        magnitude = np.maximum(magnitude, np.max(np.abs(v), axis=(1, 2), initial=0.0))
    elif kind == "mesh":
        v = data["vertices"]
        low, high = v.min(axis=0), v.max(axis=0)
        center = low * 0.5 + high * 0.5
        scale = norm(points - center) + float(norm(high - center))
        magnitude = np.maximum(magnitude, float(np.max(np.abs(v))))
    else:
        c = data["center"][index]
        scale = norm(points - c) + data["radius"][index]
        magnitude = np.maximum(magnitude, np.max(np.abs(c), axis=1, initial=0.0))
    return scale, magnitude


def _translate(distance, point, failure, points, tolerance, reference, check_shape, out_shape):
    """Mark answers that contradict the geometry; arrays are flat and changed in place."""
    ok = failure == Failure.OK
    # No shape here has volume, so a negative distance is either rounding
    # around contact (reported as 0) or not a distance at all.
    negative = ok & (distance < -tolerance)
    failure[negative] = Failure.SENTINEL
    ok &= ~negative
    # "Touching" is a distance within the tolerance of 0; it contradicts the
    # geometry when proximity puts the shape more than twice that far, so
    # that the disagreement exceeds the tolerance whatever the rounding.
    touching = ok & (np.abs(distance) <= tolerance) & (reference > 2.0 * tolerance)
    failure[touching] = Failure.FALSE_TOUCHING
    ok &= ~touching
    distance[ok & (distance < 0)] = 0.0
    if not ok.any():
        return
    # Distance from each returned point to the shape, by proximity: a point
    # farther than the tolerance is not on the shape (or on its model).
    safe = np.where(ok[:, None] & np.isfinite(point), point, 0.0)
    off = np.asarray(check_shape.distance(safe.reshape(out_shape + (3,))), dtype=np.float64).reshape(-1)
    not_on = ok & (~np.isfinite(point).all(axis=1) | ~(off <= tolerance))
    failure[not_on] = Failure.POINT_OFF_SHAPE
    ok &= ~not_on
    gap = norm(np.where(ok[:, None], point - points, 0.0))
    inconsistent = ok & ~(np.abs(gap - distance) <= tolerance)
    failure[inconsistent] = Failure.INCONSISTENT


def _result(result_type, dim, out_shape, distance, point, face=None):
    """proximity's result type, with the fields no library gives set to
    'unknown' (NaN, False, or face -1), and their names."""
    feature = np.full(out_shape, Feature.NONE, dtype=np.int8)
    with np.errstate(over="ignore", under="ignore"):
        # As in proximity, the square may leave the float64 range; the distance does not.
        sqr_distance = distance * distance
    values = dict(
        distance=distance.reshape(out_shape),
        sqr_distance=sqr_distance.reshape(out_shape),
        point=point.reshape(out_shape + (3,))[..., :dim].copy(),
        feature=feature,
    )
    unknown = ["feature"]
    widths = {name: width for p in primitives.BY_CODE for name, width in p.extra}
    for field in fields(result_type):
        name = field.name
        if name in values:
            continue
        if name == "face" and face is not None:
            values[name] = face.reshape(out_shape)
            continue
        unknown.append(name)
        if name == "face":
            values[name] = np.full(out_shape, -1, dtype=np.int64)
        elif widths.get(name) == 0:
            values[name] = np.zeros(out_shape, dtype=bool)
        else:
            width = widths.get(name, 1)
            values[name] = np.full(out_shape + ((width,) if width > 1 else ()), np.nan)
    return result_type(**values), tuple(unknown)
