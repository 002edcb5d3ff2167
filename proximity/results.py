"""Result types of the closest-point queries.

Results are frozen dataclasses of read-only arrays whose leading shape is the
broadcast shape of the query; one point against one shape gives NumPy
scalars.
"""

from dataclasses import dataclass, fields

import numpy as np

from ._validate import freeze_fields, freeze_result
from .features import _FEATURES, Feature

# Keys of a result's ``__dict__`` besides its fields: the query that made it
# (points, the batch member of each row or None, the shape), which its normals
# need, and the normals once computed.
_QUERY = "_query"
_NORMAL = "_normal"


def asdict(result):
    """The fields of a result, by name (its arrays, not copies)."""
    return {f.name: getattr(result, f.name) for f in fields(result)}


def attach(result, points, members, shape):
    """Keep with ``result`` the query that made it, for its :attr:`Result.normal`:
    ``points`` (broadcasting to the result's batch), the batch member of
    ``shape`` each row asked (None where the shape is not a batch), and
    ``shape``, whose ``_surface_normals(result, rows)`` gives the normals of
    rows on it."""
    result.__dict__[_QUERY] = (points, members, shape)
    return result


def _normals(result, points, members, shape):
    """``(P - point) / distance``, and the shape's normals where the distance is 0."""
    point = np.asarray(result.point)
    distance = np.asarray(result.distance)
    dim = point.shape[-1]
    points = np.broadcast_to(np.asarray(points, dtype=np.float64)[..., :dim], point.shape)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        normal = (points - point) / distance[..., None]
        # Where the difference's squares overflow or underflow, a scaled unit vector.
        length = np.linalg.norm(normal, axis=-1)
        off = np.isfinite(distance) & (distance > 0) & ~(np.abs(length - 1.0) < 1e-6)
        if off.any():
            v = (points - point)[off]
            v = v / np.max(np.abs(v), axis=-1, keepdims=True)
            normal[off] = v / np.linalg.norm(v, axis=-1, keepdims=True)
    on = np.flatnonzero((distance == 0).reshape(-1))
    if len(on):
        flat = normal.reshape(-1, dim)
        index = None if members is None else np.broadcast_to(members, distance.shape).reshape(-1)[on]
        flat[on] = shape._surface_normals(result, on, index)[:, :dim]
    return normal


def _frozen(value):
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return value[()]
        return freeze_result(value)
    return value


#: Print options of the reprs of shapes and results: big batches abbreviated.
REPR_OPTIONS = {"threshold": 24, "edgeitems": 2}


def format_repr(obj, names, **extra):
    """``Type(name=array(...), ...)``, the arrays as NumPy prints them, then ``extra``."""
    head = f"{type(obj).__name__}("
    with np.printoptions(**REPR_OPTIONS):
        parts = [(name, np.array_repr(np.asarray(getattr(obj, name)))) for name in names]
    parts += [(name, repr(value)) for name, value in extra.items()]
    flat = head + ", ".join(f"{name}={value}" for name, value in parts) + ")"
    if "\n" not in flat and len(flat) <= 100:
        return flat
    if len(parts) == 1:
        (name, value), pad = parts[0], len(head) + len(parts[0][0]) + 1
        text = f"{head}{name}={_indent(value, pad)})"
    else:
        lines = [f"    {name}={_indent(value, 5 + len(name))}," for name, value in parts]
        text = head + "\n" + "\n".join(lines) + "\n)"
    return "\n".join(line.rstrip() for line in text.split("\n"))


def _indent(text, width):
    return text.replace("\n", "\n" + " " * width)


@dataclass(frozen=True, repr=False)
class Result:
    """Fields every query returns.

    Attributes
    ----------
    distance : ndarray of float64, shape ``batch``
        Euclidean distance from each point to the shape.
    sqr_distance : ndarray of float64, shape ``batch``
        Squared distance (over- or underflows where the distance squared is
        outside the float64 range, even though ``distance`` does not).
    point : ndarray of float64, shape ``batch + (D,)``
        The closest point on the shape.
    feature : ndarray of int8, shape ``batch``
        :class:`Feature` code of the feature the closest point lies on.

    Examples
    --------
    One point against one shape gives NumPy scalars; ``feature_name`` names
    the :class:`Feature`:

    >>> import proximity
    >>> r = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).closest_point([0, 0, 2])
    >>> float(r.distance), float(r.sqr_distance), r.point.tolist(), str(r.feature_name)
    (2.0, 4.0, [0.0, 0.0, 0.0], 'VERTEX0')
    >>> isinstance(r, proximity.Result)
    True
    """

    distance: np.ndarray
    sqr_distance: np.ndarray
    point: np.ndarray
    feature: np.ndarray

    def __post_init__(self):
        for name, value in vars(self).items():
            value = _frozen(value)
            if name == "feature" and not isinstance(value, np.ndarray):
                value = np.int8(value)
            object.__setattr__(self, name, value)

    def __getstate__(self):
        # The fields, and the normals (computed now: the query they need stays here).
        state = asdict(self)
        if _QUERY in self.__dict__ or _NORMAL in self.__dict__:
            state[_NORMAL] = self.normal
        return state

    def __setstate__(self, state):
        # Arrays come back from a pickle writeable: make them read-only again.
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return format_repr(self, [f.name for f in fields(self)])

    @property
    def normal(self):
        """Unit vector from the closest point towards the query point, ``batch + (D,)``.

        ``(P - point) / distance`` where the distance is positive; on the
        shape, the shape's own normal there: a triangle's or a disk's face
        normal (as its vertices or its normal orient it), a mesh's
        angle-weighted pseudonormal of the closest face, edge or vertex
        (outwards on a closed, consistently oriented mesh), a circle's axis,
        a segment's perpendicular with the smallest component along the
        coordinate axis least aligned with it, a point's ``+z``; NaN where
        the row has no answer.  Computed at its first use and kept.

        Examples
        --------
        >>> import proximity
        >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> tri.closest_point([[0.2, 0.2, 3.0], [2, 0, 0], [0.2, 0.2, 0.0]]).normal.tolist()
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        """
        normal = self.__dict__.get(_NORMAL)
        if normal is None:
            query = self.__dict__.get(_QUERY)
            if query is None:
                raise AttributeError(f"this {type(self).__name__} was not made by a query: it has no normals")
            normal = freeze_result(np.asarray(_normals(self, *query)))
            self.__dict__[_NORMAL] = normal
        return normal[()] if normal.ndim == 1 and np.ndim(self.distance) == 0 else normal

    @property
    def feature_name(self):
        """The :class:`Feature` names of ``feature``: an array of str (a str for one point).

        Examples
        --------
        >>> import proximity
        >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> tri.closest_point([[2, 0, 0], [0.2, 0.2, 1]]).feature_name.tolist()
        ['VERTEX1', 'FACE']
        >>> str(tri.closest_point([0.2, 0.2, 1]).feature_name)
        'FACE'
        """
        return Feature.names(self.feature)

    def __getitem__(self, index):
        """The results of the queries at ``index`` of the batch.

        Examples
        --------
        >>> import proximity
        >>> r = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).closest_point([[2, 0, 0], [0, 0, 3]])
        >>> str(r[1].feature_name), float(r[1].distance)
        ('VERTEX0', 3.0)
        >>> r[1]
        TriangleResult(
            distance=array(3.),
            sqr_distance=array(9.),
            point=array([0., 0., 0.]),
            feature=array(0, dtype=int8),
            barycentric=array([ 1., -0.,  0.]),
        )
        """
        if np.ndim(self.distance) == 0:
            raise IndexError("a single query's result has no batch to index")
        result = type(self)(**{name: value[index] for name, value in asdict(self).items()})
        if _NORMAL in self.__dict__:
            result.__dict__[_NORMAL] = self.__dict__[_NORMAL][index]
        elif _QUERY in self.__dict__:
            points, members, shape = self.__dict__[_QUERY]
            batch = np.shape(self.distance)
            points = np.broadcast_to(points, batch + points.shape[-1:])[index]
            members = None if members is None else np.broadcast_to(members, batch)[index]
            result.__dict__[_QUERY] = (points, members, shape)
        return result


@dataclass(frozen=True, repr=False)
class TriangleResult(Result):
    """Closest point on a triangle.

    Attributes
    ----------
    barycentric : ndarray of float64, shape ``batch + (3,)``
        Weights ``(b0, b1, b2)`` of the vertices, summing to 1, with
        ``point = b0 V0 + b1 V1 + b2 V2`` (up to rounding).  In the notation
        of Eberly's *Distance Between Point and Triangle in 3D*,
        ``(s, t) = (b1, b2)``.  On the face of a sliver of height
        ``h`` they are determined only to about ``eps * S / h`` (points that
        close together have barycentrics that far apart); ``point`` and
        ``distance`` keep their accuracy there.

    Examples
    --------
    >>> import proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> r = tri.closest_point([[0.25, 0.25, 1.0], [1, 1, 0]])
    >>> r.barycentric.tolist()
    [[0.5, 0.25, 0.25], [0.0, 0.5, 0.5]]
    >>> r.point.tolist()
    [[0.25, 0.25, 0.0], [0.5, 0.5, 0.0]]
    """

    barycentric: np.ndarray


@dataclass(frozen=True, repr=False)
class PointResult(Result):
    """Closest point on a point: the point itself, feature ``VERTEX0``.

    Examples
    --------
    >>> import proximity
    >>> r = proximity.Point([1, 2, 3]).closest_point([1, 2, 5])
    >>> float(r.distance), r.point.tolist(), str(r.feature_name)
    (2.0, [1.0, 2.0, 3.0], 'VERTEX0')
    """


@dataclass(frozen=True, repr=False)
class SegmentResult(Result):
    """Closest point on a segment.

    Attributes
    ----------
    parameter : ndarray of float64, shape ``batch``
        ``t`` in ``[0, 1]`` with ``point = V0 + t (V1 - V0)`` (up to
        rounding): 0 on ``VERTEX0``, 1 on ``VERTEX1``.

    Examples
    --------
    >>> import proximity
    >>> r = proximity.Segment([[0, 0, 0], [4, 0, 0]]).closest_point([[1, 1, 0], [9, 0, 0]])
    >>> r.parameter.tolist(), r.point.tolist()
    ([0.25, 1.0], [[1.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    """

    parameter: np.ndarray


@dataclass(frozen=True, repr=False)
class DiskResult(Result):
    """Closest point on a disk.

    Attributes
    ----------
    height : ndarray of float64, shape ``batch``
        Signed distance of the point from the disk's plane, along the
        normal as given.
    radial : ndarray of float64, shape ``batch``
        Distance of the point from the disk's axis.

    Examples
    --------
    >>> import proximity
    >>> disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> r = disk.closest_point([[3, 0, -2], [0.5, 0, 2]])
    >>> r.height.tolist(), r.radial.tolist(), [proximity.Feature(f).name for f in r.feature]
    ([-2.0, 2.0], [3.0, 0.5], ['RIM', 'FACE'])
    >>> r.distance.round(6).tolist()
    [2.828427, 2.0]
    """

    height: np.ndarray
    radial: np.ndarray


@dataclass(frozen=True, repr=False)
class CircleResult(DiskResult):
    """Closest point on a circle.

    Attributes
    ----------
    equidistant : ndarray of bool, shape ``batch``
        True where the point lies on the circle's axis (to within the
        rounding of ``radial``): every point of the circle is then closest,
        and ``point`` is one of them, chosen deterministically.

    Examples
    --------
    >>> import proximity
    >>> ring = proximity.Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> r = ring.closest_point([[0, 0, 1], [2, 0, 0]])
    >>> r.equidistant.tolist(), r.distance.round(6).tolist()
    ([True, False], [1.414214, 1.0])
    >>> r.height.tolist(), r.radial.tolist()
    ([1.0, 0.0], [0.0, 2.0])
    """

    equidistant: np.ndarray


@dataclass(frozen=True, repr=False)
class MeshResult(TriangleResult):
    """Closest point on a triangle mesh.

    Attributes
    ----------
    face : ndarray of int64, shape ``batch``
        Index (into the mesh's ``faces``) of the face holding the closest
        point; ``barycentric`` and ``feature`` refer to that face.  Among
        faces at the same computed distance, the lowest index.  -1 where
        the row has no answer.

    Examples
    --------
    >>> import numpy as np, proximity
    >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    >>> r = square.closest_point([[0.75, 0.25, 1.0], [0.25, 0.75, 1.0], [np.nan, 0, 0]])
    >>> r.face.tolist(), r.distance.tolist()
    ([0, 1, -1], [1.0, 1.0, nan])
    >>> r.barycentric[0].tolist()    # of face 0's vertices 0, 1, 2
    [0.25, 0.5, 0.25]
    """

    face: np.ndarray


@dataclass(frozen=True, repr=False)
class SceneResult(Result):
    """Closest point on a scene of triangles, disks and circles.

    Attributes
    ----------
    primitive : ndarray of int64, shape ``batch``
        Index of the nearest primitive in the scene's flattened list (see
        :class:`proximity.Scene`); among primitives at the same computed
        distance, the lowest index.  -1 where the row has no answer.
    source : ndarray of int64, shape ``batch``
        Index, in the list the scene was built from, of the shape that
        primitive came from; -1 where the row has no answer.
    barycentric : ndarray of float64, shape ``batch + (3,)``
        As in :class:`TriangleResult` where the nearest primitive is a
        triangle; NaN otherwise.
    height, radial : ndarray of float64, shape ``batch``
        As in :class:`DiskResult` where the nearest primitive is a disk or
        a circle; NaN otherwise.
    parameter : ndarray of float64, shape ``batch``
        As in :class:`SegmentResult` where the nearest primitive is a
        segment; NaN otherwise.
    equidistant : ndarray of bool, shape ``batch``
        As in :class:`CircleResult` where the nearest primitive is a
        circle; False otherwise.

    Examples
    --------
    >>> import proximity
    >>> scene = proximity.Scene([
    ...     proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
    ...     proximity.Disk(center=[0, 0, 5], normal=[0, 0, 1], radius=1.0),
    ... ])
    >>> r = scene.closest_point([[0.2, 0.2, 1.0], [0.0, 0.0, 4.5]])
    >>> r.distance.tolist(), r.primitive.tolist(), r.source.tolist()
    ([1.0, 0.5], [0, 1], [0, 1])
    >>> r.height.tolist()    # NaN where the nearest primitive is a triangle
    [nan, -0.5]
    """

    primitive: np.ndarray
    source: np.ndarray
    barycentric: np.ndarray
    height: np.ndarray
    radial: np.ndarray
    equidistant: np.ndarray
    parameter: np.ndarray


# One query's result from the nine values the fast path's kernels write in a
# read-only row: ``(distance, sqr_distance, x, y, z, feature)`` and three
# shape-specific values.  The instance is filled in directly, without the
# per-field conversions of ``__init__``, which would cost more than the query
# itself; the fields are NumPy scalars and views of the row, as ``__init__``
# makes them.
_new = object.__new__
_POINT = slice(2, 5)
_LAST3 = slice(6, 9)


def triangle_from_row(row):
    """:class:`TriangleResult` of one fast-path query."""
    # Written out, not built on _round_from_row's common fields: this is the
    # one-point call made from Python loops, where one more call frame shows.
    result = _new(TriangleResult)
    fields = result.__dict__
    fields["distance"] = row[0]
    fields["sqr_distance"] = row[1]
    fields["point"] = row[_POINT]
    fields["feature"] = _FEATURES[row.item(5)]
    fields["barycentric"] = row[_LAST3]
    return result


def point_from_row(row):
    """:class:`PointResult` of one fast-path query."""
    result = _new(PointResult)
    fields = result.__dict__
    fields["distance"] = row[0]
    fields["sqr_distance"] = row[1]
    fields["point"] = row[_POINT]
    fields["feature"] = _FEATURES[row.item(5)]
    return result


def segment_from_row(row):
    """:class:`SegmentResult` of one fast-path query."""
    result = _new(SegmentResult)
    fields = result.__dict__
    fields["distance"] = row[0]
    fields["sqr_distance"] = row[1]
    fields["point"] = row[_POINT]
    fields["feature"] = _FEATURES[row.item(5)]
    fields["parameter"] = row[6]
    return result


def _round_from_row(cls, row):
    result = _new(cls)
    fields = result.__dict__
    fields["distance"] = row[0]
    fields["sqr_distance"] = row[1]
    fields["point"] = row[_POINT]
    fields["feature"] = _FEATURES[row.item(5)]
    fields["height"] = row[7]
    fields["radial"] = row[8]
    return result, fields


def disk_from_row(row):
    """:class:`DiskResult` of one fast-path query."""
    return _round_from_row(DiskResult, row)[0]


def circle_from_row(row):
    """:class:`CircleResult` of one fast-path query."""
    result, fields = _round_from_row(CircleResult, row)
    fields["equidistant"] = row[6] != 0.0
    return result


@dataclass(frozen=True, repr=False)
class PairResult:
    """Closest points of two shapes: :func:`proximity.closest_points`.

    Every field has the broadcast batch shape of the two shapes (NumPy
    scalars for two single shapes); a field that does not apply to a side
    is NaN (or -1 for indices).

    Attributes
    ----------
    distance : ndarray of float64, shape ``batch``
        Distance between the shapes (0 where they touch or overlap).
    sqr_distance : ndarray of float64, shape ``batch``
        Its square.
    point_a, point_b : ndarray of float64, shape ``batch + (D,)``
        A closest point on each shape, ``distance`` apart; one common point
        where the shapes touch or overlap.  On rounded shapes, the points
        of their surfaces along the cores' witness direction.
    feature_a, feature_b : ndarray of int8, shape ``batch``
        :class:`Feature` codes of the features holding them (the cores' for
        rounded shapes; of the face or primitive for meshes and scenes).
    parameter_a, parameter_b : ndarray of float64, shape ``batch``
        Where a side is a segment: ``t`` with ``point = V0 + t (V1 - V0)``.
    barycentric_a, barycentric_b : ndarray of float64, shape ``batch + (3,)``
        Where a side is a triangle or a mesh: the witness's weights over the
        vertices of its triangle (face).
    face_a, face_b : ndarray of int64, shape ``batch``
        Where a side is a mesh: the index of the face holding the witness.
    primitive_a, primitive_b, source_a, source_b : ndarray of int64, shape ``batch``
        Where a side is a scene: the index of the primitive holding the
        witness, and of the shape it came from (see :class:`proximity.SceneResult`).

    Examples
    --------
    >>> import proximity
    >>> a = proximity.Segment([[0, 0, 0], [4, 0, 0]])
    >>> b = proximity.Segment([[1, -1, 2], [1, 1, 2]])
    >>> r = proximity.closest_points(a, b)
    >>> float(r.distance), r.point_a.tolist(), r.point_b.tolist()
    (2.0, [1.0, 0.0, 0.0], [1.0, 0.0, 2.0])
    >>> str(r.feature_name_a), float(r.parameter_a), float(r.parameter_b)
    ('EDGE01', 0.25, 0.5)
    """

    distance: np.ndarray
    sqr_distance: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    feature_a: np.ndarray
    feature_b: np.ndarray
    parameter_a: np.ndarray
    parameter_b: np.ndarray
    barycentric_a: np.ndarray
    barycentric_b: np.ndarray
    face_a: np.ndarray
    face_b: np.ndarray
    primitive_a: np.ndarray
    primitive_b: np.ndarray
    source_a: np.ndarray
    source_b: np.ndarray

    def __post_init__(self):
        for name, value in vars(self).items():
            value = _frozen(value)
            if name.startswith("feature") and not isinstance(value, np.ndarray):
                value = np.int8(value)
            object.__setattr__(self, name, value)

    def __setstate__(self, state):
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return format_repr(self, [f.name for f in fields(self)])

    @property
    def feature_name_a(self):
        """The :class:`Feature` names of ``feature_a`` (a str for one pair)."""
        return Feature.names(self.feature_a)

    @property
    def feature_name_b(self):
        """The :class:`Feature` names of ``feature_b`` (a str for one pair)."""
        return Feature.names(self.feature_b)

    def swapped(self):
        """The same answer with the sides exchanged: ``a`` becomes ``b``.

        Examples
        --------
        >>> import proximity
        >>> r = proximity.closest_points(proximity.Point([0, 0, 1]), proximity.Point([0, 0, 3]))
        >>> r.swapped().point_a.tolist()
        [0.0, 0.0, 3.0]
        """
        values = {}
        for name, value in vars(self).items():
            if name.endswith("_a"):
                name = name[:-2] + "_b"
            elif name.endswith("_b"):
                name = name[:-2] + "_a"
            values[name] = value
        return _new_pair(values)

    def __getitem__(self, index):
        """The results of the pairs at ``index`` of the batch."""
        if np.ndim(self.distance) == 0:
            raise IndexError("a single pair's result has no batch to index")
        return PairResult(**{name: value[index] for name, value in vars(self).items()})


def _new_pair(values):
    """A :class:`PairResult` of fields already frozen (no conversions)."""
    result = _new(PairResult)
    result.__dict__.update(values)
    return result


def pair_result(values, out_shape):
    """The :class:`PairResult` of flat fields ``values`` (a row per pair), shaped ``out_shape``."""
    fields = {}
    for name, value in values.items():
        value = np.asarray(value).reshape(out_shape + np.shape(value)[1:])
        fields[name] = value[()] if value.ndim == 0 else freeze_result(np.array(value))
        if name.startswith("feature") and value.ndim == 0:
            fields[name] = np.int8(value)
    return _new_pair(fields)


def beyond(answer, limit):
    """``answer`` (a result, or an array of distances) with the rows farther
    than ``limit`` set as a cutoff sets them: distance and squared distance
    ``inf``, NaN points and parameters, feature ``NONE``, False flags, -1
    indices.  The other rows, and an answer with none beyond, are returned
    as they are."""
    if not isinstance(answer, Result):
        far = np.asarray(answer) > limit
        return np.where(far, np.inf, answer)[()] if far.any() else answer
    far = np.asarray(answer.distance) > limit
    if not far.any():
        return answer
    values = {}
    for name, value in asdict(answer).items():
        value = np.array(value)
        mask = far.reshape(far.shape + (1,) * (value.ndim - far.ndim))
        if name in ("distance", "sqr_distance"):
            fill = np.inf
        elif value.dtype == np.bool_:
            fill = False
        elif value.dtype.kind == "i":
            fill = -1
        else:
            fill = np.nan
        values[name] = np.where(mask, fill, value).astype(value.dtype)
    result = type(answer)(**values)
    if _QUERY in answer.__dict__:
        result.__dict__[_QUERY] = answer.__dict__[_QUERY]
    return result


@dataclass(frozen=True, repr=False)
class HausdorffResult:
    """The Hausdorff distance between two meshes: :func:`proximity.hausdorff_distance`.

    Attributes
    ----------
    distance : float
        The distance from the witness (``point_a`` where ``side == "a"``,
        ``point_b`` where ``"b"``) to the other mesh, as the method computes
        it, clamped to ``[lower, upper]``.
    lower, upper : float
        Certified bounds: ``lower <= H <= upper`` for the exact Hausdorff
        distance ``H`` (the directed one with ``directed=True``).
    point_a, point_b : ndarray of float64, shape ``(3,)``
        The witness pair: where ``side == "a"``, ``point_a`` is the point of
        ``a`` found farthest from ``b`` (it gives ``lower``) and ``point_b``
        its closest point on ``b``; where ``side == "b"``, the other way
        round.
    side : str
        ``"a"`` or ``"b"``: the mesh holding the farthest point.
    directed : bool
        Whether this is ``h(a, b)`` alone.
    converged : bool
        False where the search stopped at ``max_points`` or at the depth
        limit before ``upper - lower`` reached ``rtol`` (with a warning).
    points_evaluated : int
        How many points the search measured against the other mesh.

    Examples
    --------
    >>> import numpy as np, proximity
    >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                                 [[0, 1, 2], [0, 2, 3]])
    >>> T = np.eye(4); T[:3, 3] = [0, 0, 0.5]
    >>> r = proximity.hausdorff_distance(square, square.transformed(T))
    >>> r.lower <= 0.5 <= r.upper, r.converged
    (True, True)
    """

    distance: float
    lower: float
    upper: float
    point_a: np.ndarray
    point_b: np.ndarray
    side: str
    directed: bool
    converged: bool
    points_evaluated: int

    def __post_init__(self):
        for name in ("point_a", "point_b"):
            object.__setattr__(self, name, freeze_result(np.array(getattr(self, name), np.float64)))

    def __setstate__(self, state):
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return (
            f"HausdorffResult(distance={self.distance!r}, lower={self.lower!r}, upper={self.upper!r}, "
            f"point_a={self.point_a.tolist()}, point_b={self.point_b.tolist()}, side={self.side!r}, "
            f"directed={self.directed}, converged={self.converged}, points_evaluated={self.points_evaluated})"
        )
