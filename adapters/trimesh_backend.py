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
TriangleMesh
    ``trimesh.Trimesh(vertices, faces, process=False)`` asked with
    ``trimesh.proximity.closest_point``, which needs ``rtree`` and ``scipy``;
    it reports the nearest face, kept as ``face``.

trimesh returns points only; the distance is ``|P - X|`` (for a mesh,
trimesh's own).  It reports no feature or parameters.

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
accurate to a few ``eps`` of ``S`` on every scale.  A mesh is moved and
scaled as a whole instead (its bounding box centered on the origin, its
half-diagonal in ``[0.5, 1)``), which makes the tolerance relative to the
mesh, not to its faces.  ``rescale=False`` gives trimesh the caller's
coordinates, as it would be used directly.

On a mesh, where the two nearest faces' squared distances differ by less
than ``tol.merge = 1e-8`` (absolute, in trimesh's frame), trimesh keeps the
face whose normal points most towards the query point, nearer or not: the
distance can be too long by up to about ``1e-8 / (2 d)`` (5.5e-8 on a torus
of 20,000 faces, for 2 of 200 points near its surface).  The answer is a
point of the mesh at the distance reported, so the row stays ``OK``;
:func:`proximity.adapters.cross_check` shows it as a disagreement beyond tolerance.
Pair queries
------------
``CollisionManager.min_distance_other`` (which needs python-fcl) between
one manager per side, each holding one ``Trimesh``: a triangle as a mesh
of one face, a mesh as itself, a posed shape with its pose as the object's
transform; by default (``rescale=True``) in the frame of the pair that the
fcl backend uses, since fcl's triangle tests have absolute tolerances (at
a size of ``1e-4``, triangle pairs were off by up to 0.7% of their size
in the caller's coordinates).  trimesh has no segment, sphere or capsule without tessellating
it (and a segment as the degenerate triangle ``(A, B, B)`` would be
"touching" everything in fcl): those raise ``NotImplementedError``.
trimesh asks fcl for signed distances: overlapping shapes come back
negative (not in general the depth) with points that are not a point of
contact: distance 0 and ``CONTACT``.  Signed distances are less accurate
than fcl's own: on a torus against 20 posed icospheres, distances were off
by up to ``1.1e-8`` of the pair's size, and on 400 random triangle pairs,
one of them rotated, by up to ``1.8e-8``, so the documented relative
tolerance of pairs is ``1e-6`` (unrotated triangle pairs were within
``64 eps``).  Its
``DistanceData`` names the face of the first object of fcl's broad phase
only, either side: no face is reported.
"""

import numpy as np

from ._base import Backend, Raw
from ._common import CALLER, PAIR_FRAME, WORLD, Failure, import_library, norm, plane_frame, pow2_scale
from ._pairs import PairRaw

#: Relative accuracy of ``min_distance_other``, which asks fcl for signed
#: distances: in the pair's frame, distances were off by up to 1.1e-8 of the
#: pair's size on a torus against 20 posed icospheres, and 1.8e-8 on 400
#: random triangle pairs, one of them rotated (unrotated triangle pairs were
#: within 64 eps).
PAIR_RTOL = 1e-6

#: Triangles built and sent to trimesh at once, to bound memory for large K.
CHUNK = 1 << 16


def load():
    """Import trimesh, or raise an ImportError naming the extra to install."""
    return import_library("trimesh", "trimesh")


class TrimeshBackend(Backend):
    """Closest points by ``trimesh.triangles.closest_point``.

    Parameters
    ----------
    rescale : bool, optional, keyword-only
        Translate each row to the query point and scale it by a power of two
        before calling trimesh, and give it each pair in a frame of the
        pair's own (default True); see the module docstring.  With False
        (named ``trimesh[raw]``), the caller's coordinates.

    Examples
    --------
    >>> import numpy as np, proximity, proximity.adapters as adapters
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
        "mesh": "Trimesh, by trimesh.proximity.closest_point",
    }
    probe = "the point"
    tessellated = ("disk", "circle")

    pair_models = {
        "triangle": "Trimesh(1 face)",
        "mesh": "Trimesh(F faces)",
    }
    pair_probe = "CollisionManager.min_distance_other, one manager per side"
    point_frames = {True: "per row: origin at the point, scaled by a power of two", False: CALLER}
    pair_frames = {
        rescale: f"{frame}; a posed shape's pose is its transform in the CollisionManager"
        for rescale, frame in ((True, PAIR_FRAME), (False, WORLD))
    }

    def pair_rtol(self, kind_a, kind_b):
        """``1e-6`` (see the module docstring)."""
        return PAIR_RTOL

    def _pairs(self, query):
        collision = self._trimesh.collision
        a, b = query.a, query.b
        managers = {}
        for s in (a, b):
            built = []
            for k in range(1 if s.kind == "mesh" else len(s.vertices)):
                if s.kind == "mesh":
                    mesh = self._trimesh.Trimesh(s.vertices, s.faces, process=False)
                else:
                    mesh = self._trimesh.Trimesh(s.vertices[k], [[0, 1, 2]], process=False)
                manager = collision.CollisionManager()
                manager.add_object(s.name, mesh, transform=s.transform())
                built.append(manager)
            managers[s.name] = built
        # trimesh's DistanceData names the face of one object only, the first one of fcl's
        # broad phase (-1 for the other, whichever side): no face is reported.
        raw = PairRaw.empty(query.n)
        for i in range(query.n):
            other = managers["b"][b.index[i]]
            d, data = managers["a"][a.index[i]].min_distance_other(other, return_data=True)
            raw.distance[i] = d
            raw.point_a[i], raw.point_b[i] = data.point("a"), data.point("b")
        bad = ~np.isfinite(raw.distance)
        raw.failure[bad] = Failure.NO_RESULT
        return raw

    def __init__(self, *, rescale=True):
        super().__init__(rescale=rescale)
        self._trimesh = load()
        self._closest = self._trimesh.triangles.closest_point

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

    def _meshes(self, query):
        # trimesh's mesh query imports these itself, and fails late without them.
        import_library("rtree", "rtree")
        import_library("scipy", "scipy")
        vertices, points = query.vertices, query.points
        origin, factor = np.zeros(3), 1.0
        if self.rescale:
            low, high = vertices.min(axis=0), vertices.max(axis=0)
            origin = low * 0.5 + high * 0.5
            factor = float(pow2_scale(norm(high - origin)))
            vertices, points = (vertices - origin) * factor, (points - origin) * factor
        mesh = self._trimesh.Trimesh(vertices, query.faces, process=False)
        raw = Raw.empty(len(points))
        if len(points) == 0:
            return Raw(raw.distance, raw.point, raw.failure, face=np.zeros(0, dtype=np.int64))
        closest, distance, face = self._trimesh.proximity.closest_point(mesh, points)
        raw.distance[:] = distance / factor
        raw.point[:] = closest / factor + origin
        bad = ~np.isfinite(raw.distance) | ~np.isfinite(raw.point).all(axis=1)
        raw.failure[bad] = Failure.NO_RESULT
        return Raw(raw.distance, raw.point, raw.failure, face=np.asarray(face, dtype=np.int64))
