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

Pair queries
------------
One ``fcl.distance`` call per pair of ``CollisionObject`` s, nearest points
requested.  A point is ``Sphere(0)``, a sphere ``Sphere(R)``, a segment
``Capsule(0, L)``, a capsule ``Capsule(R, L)`` (rotated so that its axis is
the segment), a triangle a one-triangle ``BVHModel`` (``TriangleP`` pairs
have no distance: 1.797e308 with a warning) and a mesh one ``BVHModel``; a
posed shape's pose is its object's ``Transform`` (composed with a capsule's
own frame).  By default (``rescale=True``) every pair of a call is given in
one frame: centered on the shapes' boxes (an unposed shape's vertices
moved, a posed shape's translation) and scaled by a power of two to a size
of about 1, since fcl's segment-triangle and triangle-triangle tests have
absolute tolerances: in the caller's coordinates, at a size of ``1e-4``,
segment-triangle distances were off by up to 2% of the pair's size, and by
84% at ``1e-6``; of 262 random triangle pairs apart, at ``1e-4``, fcl called
4 "touching" (distance 0) and was off on 9 more by up to 2.2% of their
size.  ``rescale=False`` (named ``fcl[raw]``) gives fcl the caller's
coordinates, as it would be used directly.  Point queries are always in
the caller's coordinates.  fcl reports the faces of both sides' BVH models
(``DistanceResult.b1``, ``b2``), kept as ``face_a`` and ``face_b``.

* A shape against a BVH model: fcl returns the BVH model's nearest point
  first whatever the order asked, so BVH models are asked first; and a
  sphere against a BVH model returns each nearest point in its own
  object's frame, moved to the world by the backend.
* In contact fcl returns -1, or 0 with nearest points that are not a
  common point, or (capsules, spheres) the negative depth with a point on
  each surface: distance 0 and ``CONTACT``.
* A sphere against a degenerate triangle is "touching", as for points:
  ``FALSE_TOUCHING``.
* A capsule of radius > 0 against a BVH model is answered by GJK: on 3200
  random capsule-triangle pairs distances were off by ``6e-8`` of the
  pair's size at the median, ``4e-5`` at the 99th percentile and
  ``1.4e-3`` at worst; the documented relative tolerance of those pairs is
  ``1e-2`` (``64 eps`` for the others, met by every pair measured).
"""

import numpy as np

from ._base import Backend, Raw
from ._common import PAIR_FRAME, WORLD, Failure, import_library, norm, plane_frame, polygon
from ._pairs import PairRaw, segment_frames

#: fcl's answer for a pair it has no distance function for is DBL_MAX.
UNSUPPORTED = 1.7e308

#: fcl's answer for shapes in contact, when it does not compute a depth.
CONTACT = -1.0

#: Relative accuracy of fcl's GJK (a capsule of radius > 0 against a BVH
#: model): on 3200 random capsule-triangle pairs of sizes 1e-6 to 1e3 (in the
#: pair's frame), distances were off by 6e-8 of the pair's size at the median,
#: 4e-5 at the 99th percentile and 1.4e-3 at worst.
GJK_RTOL = 1e-2

#: Kinds of pair side fcl is given as a BVHModel.
BVH_KINDS = ("triangle", "mesh")


def load():
    """Import python-fcl, or raise an ImportError naming the extra to install."""
    return import_library("fcl", "python-fcl")


class FclBackend(Backend):
    """Closest points by python-fcl.

    Parameters
    ----------
    rescale : bool, optional, keyword-only
        Give fcl each pair query in a frame of the pair's own (default
        True); see the module docstring.  Point queries are always in the
        caller's coordinates.

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

    def __init__(self, *, rescale=True):
        super().__init__(rescale=rescale)
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

    pair_models = {
        "point": "Sphere(0)",
        "sphere": "Sphere(R)",
        "segment": "Capsule(0, L)",
        "capsule": "Capsule(R, L)",
        "triangle": "BVHModel(1 triangle)",
        "mesh": "BVHModel(F triangles)",
    }
    pair_probe = "fcl.distance(a, b), nearest points requested; BVH models first"
    pair_frames = {
        rescale: f"{frame}; a posed shape's pose is its CollisionObject's Transform"
        for rescale, frame in ((True, PAIR_FRAME), (False, WORLD))
    }

    def _pairs(self, query):
        fcl = self._fcl
        a, b = query.a, query.b
        objects = {"a": _pair_objects(fcl, a), "b": _pair_objects(fcl, b)}
        # fcl answers a shape against a BVH model with the nearest points of
        # the BVH model's side first whatever the order asked: BVH models are
        # asked first.
        first, second = (b, a) if b.kind in BVH_KINDS and a.kind not in BVH_KINDS else (a, b)
        # A sphere against a BVH model has its own routine, which returns each
        # nearest point in its object's frame: moved to the world here.
        local = first.kind in BVH_KINDS and second.kind in ("point", "sphere")
        raw = PairRaw.empty(query.n, face_a=np.full(query.n, -1), face_b=np.full(query.n, -1))
        faces = {"a": raw.face_a, "b": raw.face_b}
        for i in range(query.n):
            result = fcl.DistanceResult()
            one, other = objects[first.name][first.index[i]], objects[second.name][second.index[i]]
            d = fcl.distance(one, other, self._request, result)
            if not (d < UNSUPPORTED):  # unsupported, or NaN
                raw.failure[i] = Failure.SENTINEL
                continue
            raw.distance[i] = d
            points = {first.name: result.nearest_points[0], second.name: result.nearest_points[1]}
            if local:
                center = second.vertices[second.index[i], 0]
                points[first.name] = first.world(points[first.name])
                points[second.name] = second.world(center + points[second.name] @ np.eye(3))
            raw.point_a[i], raw.point_b[i] = points["a"], points["b"]
            faces[first.name][i], faces[second.name][i] = result.b1, result.b2
        return raw

    def pair_rtol(self, kind_a, kind_b):
        """``64 eps``; ``1e-2`` for a capsule against a BVH model, which fcl answers by GJK."""
        kinds = {kind_a, kind_b}
        if "capsule" in kinds and kinds & set(BVH_KINDS):
            return GJK_RTOL
        return self.rtol

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


# -- pair queries ---------------------------------------------------------------------------


def _pair_objects(fcl, s):
    """One ``CollisionObject`` per member of side ``s``, at its pose in the world."""
    r, t = s.rotation, s.translation
    if s.kind == "mesh":
        model = fcl.BVHModel()
        model.beginModel(len(s.vertices), len(s.faces))
        model.addSubModel(np.ascontiguousarray(s.vertices), np.ascontiguousarray(s.faces))
        model.endModel()
        return [fcl.CollisionObject(model, fcl.Transform(r, t))]
    objects = []
    if s.kind in ("segment", "capsule"):
        frames, middle, length = segment_frames(s.vertices)
        for k in range(len(s.vertices)):
            geometry = fcl.Capsule(float(s.radius[k]), float(length[k]))
            objects.append(fcl.CollisionObject(geometry, fcl.Transform(r @ frames[k], r @ middle[k] + t)))
    elif s.kind in ("point", "sphere"):
        for k in range(len(s.vertices)):
            geometry = fcl.Sphere(float(s.radius[k]))
            objects.append(fcl.CollisionObject(geometry, fcl.Transform(r, r @ s.vertices[k, 0] + t)))
    else:  # triangle: a one-triangle BVHModel, since TriangleP pairs have no distance
        faces = np.array([[0, 1, 2]])
        for k in range(len(s.vertices)):
            model = fcl.BVHModel()
            model.beginModel(3, 1)
            model.addSubModel(np.ascontiguousarray(s.vertices[k]), faces)
            model.endModel()
            objects.append(fcl.CollisionObject(model, fcl.Transform(r, t)))
    return objects
