"""The results of point queries, one type per kind of shape, and those of the one-point fast path."""

from dataclasses import dataclass

import numpy as np

from ..features import _FEATURES
from .base import Result


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
