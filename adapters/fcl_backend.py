"""python-fcl backend: one fcl distance query per row, against a point-sized sphere.

Model
-----
The query point is ``fcl.Sphere(0)``, placed at the point: an exact point.

Triangle
    A ``BVHModel`` holding the one triangle, in the caller's coordinates.
    fcl's own triangle primitive, ``TriangleP``, has no distance function
    against a sphere: fcl prints a warning and returns 1.797e308.
Disk
    ``Cylinder(R, 0)``, rotated so its axis is the disk's normal: an exact
    disk.
Circle
    fcl has no circle.  The inscribed polygon of ``K`` segments, each a
    ``Capsule(0, L)`` (a capsule of radius 0 is exactly a segment), with the
    fewest ``K`` whose sagitta ``R (1 - cos(pi/K))`` meets the tolerance.
    The row's answer is the nearest of the ``K`` capsules.
TriangleMesh
    One ``BVHModel`` of all the faces, built once per call, in the caller's
    coordinates; fcl's own hierarchy finds the nearest face, whose index it
    reports (``DistanceResult.b1``) and the result keeps as ``face``.

Known biases, translated
------------------------
* A degenerate triangle (collinear or coincident vertices) is "touching"
  every point: fcl returns distance 0 with uninitialised nearest points.
  Such rows become ``FALSE_TOUCHING`` when proximity finds the triangle
  farther than the row's tolerance.  In a mesh, the same happens whenever
  fcl's traversal reaches a degenerate face.
* In contact (distance 0), the nearest points are not computed: whatever is
  in memory is returned (values such as ``(0, 6.9e-310, 0.707)``).  Those
  rows become ``POINT_OFF_SHAPE`` or ``INCONSISTENT``.
* ``Cylinder(R, 0)`` and ``Capsule(0, L)`` return the sentinel -1 when the
  point is on them (a point in the disk's plane inside or on the rim, a
  point on a polygon segment).  Those rows become ``SENTINEL``.

Away from these cases fcl agrees with proximity to a few ``eps`` of the
coordinates; the documented relative tolerance is ``64 eps``.
"""

import numpy as np

from ._base import Backend, Failure, Raw, import_library, norm, plane_frame, polygon

#: fcl's answer for a pair it has no distance function for is DBL_MAX.
UNSUPPORTED = 1.7e308

#: fcl's answer for shapes in contact, when it does not compute a depth.
CONTACT = -1.0


def load():
    """Import python-fcl, or raise an ImportError naming the extra to install."""
    return import_library("fcl", "python-fcl")


class FclBackend(Backend):
    """Closest points by python-fcl.

    Examples
    --------
    >>> import proximity, proximity.adapters as adapters
    >>> good = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    >>> collinear = [[0, 0, 0], [1, 0, 0], [3, 0, 0]]
    >>> with adapters.get("fcl") as fcl:
    ...     r = fcl.closest_point(proximity.Triangle([good, collinear]), [0.25, 0.25, 2.0])
    >>> r.distance.tolist(), [adapters.Failure(f).name for f in r.failure]
    ([2.0, nan], ['OK', 'FALSE_TOUCHING'])
    """

    name = "fcl"
    distribution = "python-fcl"
    primitives = {
        "triangle": "BVHModel(1 triangle)",
        "disk": "Cylinder(R, 0)",
        "circle": "K x Capsule(0, L)",
        "mesh": "BVHModel(F triangles)",
    }
    probe = "Sphere(0) at the point"
    tessellated = ("circle",)

    def __init__(self):
        self._fcl = load()
        self._request = self._fcl.DistanceRequest(enable_nearest_points=True)

    def _ask(self, objects, probe, points):
        """Nearest of ``objects`` to each point: ``(distance, point, failure)`` arrays."""
        fcl = self._fcl
        n = len(points)
        distance = np.full(n, np.nan)
        nearest = np.full((n, 3), np.nan)
        failure = np.full(n, Failure.OK, dtype=np.int8)
        for i, p in enumerate(points):
            probe.setTranslation(p)
            best = np.inf
            for obj in objects:
                result = fcl.DistanceResult()
                d = fcl.distance(obj, probe, self._request, result)
                if d == CONTACT or not (d < UNSUPPORTED):
                    # Not a distance: in contact, unsupported, or NaN.  Other
                    # small negatives are rounding around contact, left to
                    # the translation.
                    failure[i] = Failure.SENTINEL
                    break
                if d < best:
                    best = d
                    nearest[i] = result.nearest_points[0]
            if failure[i] == Failure.OK:
                distance[i] = best
            else:
                nearest[i] = np.nan
        return distance, nearest, failure

    def _probe(self):
        return self._fcl.CollisionObject(self._fcl.Sphere(0.0), self._fcl.Transform())

    def _run(self, query, build):
        raw = Raw.empty(len(query.index))
        probe = self._probe()
        for k, chunk in query.groups():
            d, x, f = self._ask(build(k), probe, query.points[chunk])
            raw.distance[chunk], raw.point[chunk], raw.failure[chunk] = d, x, f
        return raw

    def _triangles(self, query):
        fcl = self._fcl
        faces = np.array([[0, 1, 2]])

        def build(k):
            model = fcl.BVHModel()
            model.beginModel(3, 1)
            model.addSubModel(np.ascontiguousarray(query.vertices[k]), faces)
            model.endModel()
            return [fcl.CollisionObject(model, fcl.Transform())]

        return self._run(query, build)

    def _disks(self, query):
        fcl = self._fcl
        u, v = plane_frame(query.normal)

        def build(k):
            rotation = np.column_stack([u[k], v[k], query.normal[k]])
            return [
                fcl.CollisionObject(
                    fcl.Cylinder(float(query.radius[k]), 0.0), fcl.Transform(rotation, query.center[k])
                )
            ]

        return self._run(query, build)

    def _circles(self, query):
        fcl = self._fcl
        u, v = plane_frame(query.normal)

        def build(k):
            corners = polygon(query.center[k], u[k], v[k], query.radius[k], int(query.segments[k]))
            axis = corners[1:] - corners[:-1]
            length = norm(axis)
            # A zero-length segment (radius 0) is a point: any axis will do.
            direction = np.where(
                length[:, None] > 0, axis / np.where(length > 0, length, 1.0)[:, None], query.normal[k]
            )
            su, sv = plane_frame(direction)
            middle = (corners[1:] + corners[:-1]) / 2
            return [
                fcl.CollisionObject(
                    fcl.Capsule(0.0, float(length[i])),
                    fcl.Transform(np.column_stack([su[i], sv[i], direction[i]]), middle[i]),
                )
                for i in range(len(length))
            ]

        return self._run(query, build)

    def _meshes(self, query):
        fcl = self._fcl
        model = fcl.BVHModel()
        model.beginModel(len(query.vertices), len(query.faces))
        model.addSubModel(np.ascontiguousarray(query.vertices), np.ascontiguousarray(query.faces))
        model.endModel()
        mesh = fcl.CollisionObject(model, fcl.Transform())
        probe = self._probe()
        raw = Raw.empty(len(query.points))
        face = np.full(len(query.points), -1, dtype=np.int64)
        for i, p in enumerate(query.points):
            probe.setTranslation(p)
            result = fcl.DistanceResult()
            d = fcl.distance(mesh, probe, self._request, result)
            if d == CONTACT or not (d < UNSUPPORTED):
                raw.failure[i] = Failure.SENTINEL
                continue
            raw.distance[i] = d
            raw.point[i] = result.nearest_points[0]
            face[i] = result.b1
        return Raw(raw.distance, raw.point, raw.failure, face=face)
