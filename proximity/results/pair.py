"""The results of queries between two shapes: closest points, and bounds on the Hausdorff distance."""

from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np

from .._validate import freeze_fields, freeze_result
from ..features import Feature
from .base import _LAZY, _NORMAL, _PAIR, _frozen, asdict, format_repr


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
    >>> r.normal.tolist()
    [0.0, 0.0, 1.0]
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

    def __getattr__(self, name):
        # Called only for a name not in the instance: a fast path's fields, read from its
        # answer at the first access of any (see proximity.results.base._LAZY).
        lazy = self.__dict__.get(_LAZY)
        if lazy is None or name.startswith("__"):
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        self.__dict__.update(lazy[0].fields(lazy[1]))
        del self.__dict__[_LAZY]
        return object.__getattribute__(self, name)

    def __getstate__(self):
        # The fields, and the normals (computed now: what they need stays here).
        state = asdict(self)
        if _PAIR in self.__dict__ or _NORMAL in self.__dict__:
            state[_NORMAL] = self.normal
        return state

    def __setstate__(self, state):
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return format_repr(self, [f.name for f in fields(self)])

    @property
    def normal(self):
        """Unit vector from ``a`` towards ``b``, ``batch + (D,)``: the direction of separation.

        * Where a witness is on a face (``feature_a`` or ``feature_b``
          ``FACE``, ``a``'s first), that face's normal at every distance,
          away from ``a``'s face or into ``b``'s: on the side of the other
          witness where they are apart, else of the other side's primitive
          (the mean of its vertices), decided exactly; the face's own
          orientation where that lies on the plane.
        * Elsewhere, ``(point_b - point_a) / distance`` above the rounding
          of the coordinates (``64 eps M``, ``M`` the largest coordinate
          magnitude of the witnesses and their primitives); for rounded
          shapes, from ``a``'s core towards ``b``'s, overlapping too.
        * Within that rounding (touching or crossing) on edges or
          vertices, the normal there of a side with a surface (a triangle,
          a mesh's pseudonormal, a disk; ``a``'s first), turned towards the
          other side's primitive; NaN where neither has one (segments,
          points, circles: crossing segments have no direction of
          separation), where that primitive is in the tangent plane, where
          2D shapes touch, and where the pair has no answer.

        Computed at its first use and kept; in world coordinates for posed
        sides.

        Examples
        --------
        >>> import proximity
        >>> floor = proximity.Triangle([[0, 0, 0], [4, 0, 0], [0, 4, 0]])
        >>> rod = proximity.Segment([[1, 1, 0], [1, 1, -3]])        # touching from below
        >>> proximity.closest_points(floor, rod).normal.tolist()
        [0.0, 0.0, -1.0]
        """
        normal = self.__dict__.get(_NORMAL)
        if normal is None:
            source = self.__dict__.get(_PAIR)
            if source is None:
                raise AttributeError("this PairResult was not made by a query: it has no normals")
            if type(source) is tuple:  # the fast path's (answer, row, a, b), kept as it is
                source = source[0].normals(*source[1:])
            normal = freeze_result(np.asarray(source.normal()))
            self.__dict__[_NORMAL] = normal
        return normal[()] if normal.ndim == 1 and np.ndim(self.distance) == 0 else normal

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
        for name, value in asdict(self).items():
            if name.endswith("_a"):
                name = name[:-2] + "_b"
            elif name.endswith("_b"):
                name = name[:-2] + "_a"
            values[name] = value
        result = _new_pair(values)
        if _NORMAL in self.__dict__:
            result.__dict__[_NORMAL] = freeze_result(0.0 - self.__dict__[_NORMAL])
        elif _PAIR in self.__dict__:
            source = self.__dict__[_PAIR]
            if type(source) is tuple:
                source = source[0].normals(*source[1:])
            result.__dict__[_PAIR] = source.negated()
        return result

    def __getitem__(self, index):
        """The results of the pairs at ``index`` of the batch."""
        if np.ndim(self.distance) == 0:
            raise IndexError("a single pair's result has no batch to index")
        result = PairResult(**{name: value[index] for name, value in asdict(self).items()})
        if _NORMAL in self.__dict__:
            result.__dict__[_NORMAL] = self.__dict__[_NORMAL][index]
        elif _PAIR in self.__dict__:
            result.__dict__[_PAIR] = self.__dict__[_PAIR].take(index)
        return result


_new = object.__new__


def _new_pair(values, normals=None):
    """A :class:`PairResult` of fields already frozen (no conversions), its
    normals from ``normals`` (see :attr:`PairResult.normal`) where given."""
    result = _new(PairResult)
    result.__dict__.update(values)
    if normals is not None:
        result.__dict__[_PAIR] = normals
    return result


class Fill(NamedTuple):
    """A field of a :func:`pair_result` with one value in every row: ``value`` of ``dtype``,
    each row's of shape ``trailing`` (a read-only broadcast of it, no memory per row)."""

    value: object
    dtype: type
    trailing: tuple = ()


def pair_result(values, out_shape, normals=None):
    """The :class:`PairResult` of flat fields ``values`` (a row per pair, or a :class:`Fill`),
    shaped ``out_shape``, its normals from ``normals`` (see :attr:`PairResult.normal`) where
    given.  A writeable array is taken as the caller's to give (made read-only, not copied); a
    read-only one, which may view a shape's data, is copied."""
    fields = {}
    for name, value in values.items():
        if type(value) is Fill:
            value = np.broadcast_to(np.array(value.value, value.dtype), out_shape + value.trailing)
            fields[name] = value[()] if value.ndim == 0 else value
            continue
        value = np.asarray(value).reshape(out_shape + np.shape(value)[1:])
        if value.ndim == 0:
            fields[name] = value[()]
        else:
            fields[name] = freeze_result(value if value.flags.writeable else np.array(value))
        if name.startswith("feature") and value.ndim == 0:
            fields[name] = np.int8(value)
    return _new_pair(fields, normals)


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
