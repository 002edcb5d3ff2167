"""What every result shares: the :class:`Result` base, its normals, its repr, cutoffs.

Results are frozen dataclasses of read-only arrays whose leading shape is the
broadcast shape of the query; one point against one shape gives NumPy
scalars.
"""

from dataclasses import dataclass, fields

import numpy as np

from .._validate import freeze_fields, freeze_result
from ..features import Feature
from ..numerics.normals import frame_normals, query_normals

# Keys of a result's ``__dict__`` besides its fields: the query that made it
# (points, the batch member of each row or None, the shape), which its normals
# need; or, for a posed view's, the shape's own result, the rotation that turns
# its normals to the world and what bounds the move's rounding; and the
# normals once computed.
_QUERY = "_query"
_FRAME = "_frame"
_NORMAL = "_normal"
# A pair's: what its normals need (see proximity.numerics.normals.PairNormals).
_PAIR = "_pair"
# A pair's fields not yet read from its answer: ``(reader, answer)``, where
# ``reader.fields(answer)`` gives them by name (the fast path's, see
# proximity.pair.queries: all but the distance and the witnesses), read at the
# first access of any.
_LAZY = "_lazy"


def asdict(result):
    """The fields of a result, by name (its arrays, not copies)."""
    return {f.name: getattr(result, f.name) for f in fields(result)}


def attach(result, points, members, shape):
    """Keep with ``result`` the query that made it, for its :attr:`Result.normal`:
    ``points`` (broadcasting to the result's batch), the batch member of
    ``shape`` each row asked (None where the shape is not a batch), and
    ``shape`` (see :func:`proximity.numerics.normals.normals_at` for what it gives)."""
    result.__dict__[_QUERY] = (points, members, shape)
    return result


def attach_frame(result, normals):
    """Keep with ``result`` (a posed view's) ``normals()``, which gives its normals
    (:func:`posed_normals` of the shape's own result, or a posed view's parts')."""
    result.__dict__[_FRAME] = normals
    return result


def posed_normals(core, rotation, points, translation):
    """The normals of a posed view's result: those of the shape's own result ``core``,
    turned by ``rotation``; ``points`` are the world's query points (broadcasting to the
    batch) and ``translation`` the pose's: their magnitudes bound the rounding that the
    move to the shape's frame added to its points."""
    query = None if _NORMAL in core.__dict__ else core.__dict__.get(_QUERY)
    return frame_normals(query, core, rotation, points, translation)


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
        if _QUERY in self.__dict__ or _FRAME in self.__dict__ or _NORMAL in self.__dict__:
            state[_NORMAL] = self.normal
        return state

    def __setstate__(self, state):
        # Arrays come back from a pickle writeable: make them read-only again.
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return format_repr(self, [f.name for f in fields(self)])

    @property
    def normal(self):
        """Unit normal at the closest point, towards the query point, ``batch + (D,)``.

        * On a face (``feature`` ``FACE``: a triangle's, a mesh's, a
          disk's), the face's normal at every distance, towards the query
          point's side of its plane (decided exactly); as the face is
          oriented (by its vertices' order, the disk's normal) where the
          point is on the plane or the distance is 0.
        * Elsewhere (an edge, a vertex, a rim), ``(P - point) / distance``
          above the rounding of the coordinates; below ``64 eps M`` (``M``
          the largest coordinate magnitude of the point and of the nearest
          primitive), where ``P - point`` has no direction, the shape's own
          normal there, as at distance 0: a mesh's angle-weighted
          pseudonormal (outwards on a closed, consistently oriented mesh;
          the face's normal on one that is not), a triangle's face normal,
          a disk's or a circle's axis, a segment's perpendicular with the
          smallest component along the coordinate axis least aligned with
          it, a point's ``+z``.
        * A posed view's: its shape's, computed in the shape's frame (the
          rounding taken at the world coordinates' magnitude) and turned. A
          rounded shape's: its surface's outward normal at ``point`` (the
          core's where the core's closest point is on a face).
        * In 2D, in the plane: within rounding, a segment's perpendicular,
          a triangle's outward edge normal (at a vertex, the sum of its
          edges'); NaN inside a triangle, on a point, and where the row has
          no answer.  See ``docs/accuracy.md``, *Normals*.

        Computed at its first use and kept.

        Examples
        --------
        >>> import proximity
        >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> points = [[0.2, 0.2, 3.0], [2, 0, 0], [0.2, 0.2, 0.0], [0.2, 0.2, -1e-300]]
        >>> tri.closest_point(points).normal.tolist()
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
        """
        normal = self.__dict__.get(_NORMAL)
        if normal is None:
            frame = self.__dict__.get(_FRAME)
            if frame is not None:
                normal = frame()
            else:
                query = self.__dict__.get(_QUERY)
                if query is None:
                    name = type(self).__name__
                    raise AttributeError(f"this {name} was not made by a query: it has no normals")
                normal = query_normals(self, *query)
            normal = freeze_result(np.asarray(normal))
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
        elif _FRAME in self.__dict__:
            # The whole batch's normals, computed once and kept here, then indexed.
            result.__dict__[_FRAME] = lambda: self.normal[index]
        elif _QUERY in self.__dict__:
            points, members, shape = self.__dict__[_QUERY]
            batch = np.shape(self.distance)
            points = np.broadcast_to(points, batch + points.shape[-1:])[index]
            members = None if members is None else np.broadcast_to(members, batch)[index]
            result.__dict__[_QUERY] = (points, members, shape)
        return result


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
    elif _FRAME in answer.__dict__:
        normals = answer.__dict__[_FRAME]
        result.__dict__[_FRAME] = lambda: np.where(far[..., None], np.nan, normals())
    return result
