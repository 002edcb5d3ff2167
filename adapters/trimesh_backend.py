"""trimesh backend: ``trimesh.triangles.closest_point`` on triangles, vectorised.

Model
-----
trimesh answers one question, the closest point on a triangle, for arrays of
(triangle, point) pairs; every shape is given to it as triangles.

Triangle
    The triangle itself.
Disk
    trimesh has no disk: a fan of ``K`` triangles from the center to the
    inscribed polygon, with the fewest ``K`` whose sagitta
    ``R (1 - cos(pi/K))`` meets the tolerance.  The answer is the nearest of
    the ``K`` triangles.
Circle
    trimesh has no circle or segment primitive: the inscribed polygon of
    ``K`` segments, each given as the degenerate triangle ``(A, B, B)``,
    which trimesh's region tests answer as the segment ``AB``.

trimesh returns points only; the distance is ``|P - X|``.  It reports no
feature or parameters.

Known bias, translated
----------------------
trimesh decides the Voronoi region of the point with an absolute tolerance
``tol.zero = 1e-13`` on products of coordinate differences, which have the
units of length squared (and up to the fourth power).  On triangles of a
millimetre or less (in a unit of a metre) whole regions are misclassified,
and the returned point, though on the triangle, is not the closest one: the
distance is then wrong by up to the size of the triangle.  By default
(``rescale=True``) each row is moved so that the query point is the origin
and scaled by a power of two so that the triangle's farthest vertex is at a
distance in ``[0.5, 1)``: the tolerance is then relative, and trimesh is
accurate to a few ``eps`` of ``S`` on every scale.  ``rescale=False`` gives
trimesh the caller's coordinates, as it would be used directly.
"""

import numpy as np

from ._base import Backend, Failure, Raw, import_library, norm, plane_frame, pow2_scale

#: Triangles built and sent to trimesh at once, to bound memory for large K.
CHUNK = 1 << 16


def load():
    """Import trimesh, or raise an ImportError naming the extra to install."""
    return import_library("trimesh", "trimesh")


class TrimeshBackend(Backend):
    """Closest points by ``trimesh.triangles.closest_point``.

    Parameters
    ----------
    rescale : bool, optional
        Translate each row to the query point and scale it by a power of two
        before calling trimesh (default True); see the module docstring.

    Examples
    --------
    >>> import numpy as np, proximity, adapters
    >>> tiny = proximity.Triangle(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]) * 1e-4)
    >>> p = [3e-5, 3e-5, 1e-4]  # above the face, at a height of 1e-4
    >>> with adapters.get("trimesh") as tm, adapters.get("trimesh", rescale=False) as raw:
    ...     print(f"{float(tm.distance(tiny, p)):.6g} {float(raw.distance(tiny, p)):.6g}")
    0.0001 0.000104403
    """

    name = "trimesh"
    distribution = "trimesh"
    primitives = {
        "triangle": "triangle",
        "disk": "fan of K triangles",
        "circle": "K segments as (A, B, B) triangles",
    }
    probe = "the point"
    tessellated = ("disk", "circle")

    def __init__(self, *, rescale=True):
        self._closest = load().triangles.closest_point
        self.rescale = bool(rescale)
        if not self.rescale:
            self.name = "trimesh[raw]"
            self.frame = "caller's coordinates"
        else:
            self.frame = "per row: origin at the point, scaled by a power of two"

    def _nearest(self, triangles, points, rows, n):
        """Nearest of several triangles per row: ``triangles[j]`` belongs to row ``rows[j]``."""
        raw = Raw.empty(n)
        if len(triangles) == 0:
            return raw
        if self.rescale:
            rel = triangles - points[rows][:, None, :]
            size = np.zeros(n)
            np.maximum.at(size, rows, np.max(np.abs(rel), axis=(1, 2)))
            factor = pow2_scale(size)
            rel = rel * factor[rows][:, None, None]
            target = np.zeros((len(rel), 3))
        else:
            rel, target = triangles, points[rows]
        found = self._closest(rel, target)
        gap = norm(found - target)
        # The nearest candidate of each row; rows are contiguous and sorted.
        starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
        best = np.minimum.reduceat(gap, starts)
        choice = np.flatnonzero(gap == np.repeat(best, np.diff(np.r_[starts, len(rows)])))
        first = choice[np.r_[True, rows[choice][1:] != rows[choice][:-1]]]
        row = rows[first]
        if self.rescale:
            raw.distance[row] = gap[first] / factor[row]
            raw.point[row] = found[first] / factor[row][:, None] + points[row]
        else:
            raw.distance[row] = gap[first]
            raw.point[row] = found[first]
        # A row whose answer is not finite has no result from trimesh.
        bad = ~np.isfinite(raw.distance) | ~np.isfinite(raw.point).all(axis=1)
        raw.failure[bad] = Failure.NO_RESULT
        return raw

    def _triangles(self, query):
        n = len(query.index)
        return self._nearest(query.vertices[query.index], query.points, np.arange(n), n)

    def _round(self, query, fan):
        n = len(query.index)
        raw = Raw.empty(n)
        u, v = plane_frame(query.normal)
        segments = query.segments[query.index]
        ends = np.cumsum(segments)
        start = 0
        # Rows in blocks of about CHUNK triangles, so that memory stays bounded for large K.
        while start < n:
            done = ends[start - 1] if start else 0
            stop = max(start + 1, int(np.searchsorted(ends, done + CHUNK, side="right")))
            block = self._round_block(query, fan, u, v, slice(start, stop))
            raw.distance[start:stop] = block.distance
            raw.point[start:stop] = block.point
            raw.failure[start:stop] = block.failure
            start = stop
        return raw

    def _round_block(self, query, fan, u, v, rows_slice):
        index = query.index[rows_slice]
        points = query.points[rows_slice]
        n = len(index)
        k = query.segments[index]
        rows = np.repeat(np.arange(n), k)
        # Segment j of its row, between the polygon corners j and j + 1 (mod K).
        j = np.arange(len(rows)) - np.repeat(np.cumsum(k) - k, k)
        kk = k[rows].astype(np.float64)
        shape = index[rows]
        radius = query.radius[shape][:, None]

        def corner(i):
            theta = 2.0 * np.pi * np.where(i == k[rows], 0, i) / kk
            return query.center[shape] + radius * (
                np.cos(theta)[:, None] * u[shape] + np.sin(theta)[:, None] * v[shape]
            )

        a, b = corner(j), corner(j + 1)
        triangles = np.stack([a, b, query.center[shape] if fan else b], axis=1)
        return self._nearest(triangles, points, rows, n)

    def _disks(self, query):
        return self._round(query, fan=True)

    def _circles(self, query):
        return self._round(query, fan=False)
