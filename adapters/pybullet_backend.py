"""pybullet backend: ``getClosestPoints`` between the shape's body and a probe body.

Model
-----
Each backend owns one ``DIRECT`` physics client, disconnected by
:meth:`PybulletBackend.close` (or when the backend is garbage collected or
the interpreter exits).  Its world holds at most two bodies: a probe, moved
to each query point with ``resetBasePositionAndOrientation``, and the body of
the shape being asked about, removed once its rows are answered.
Collision shapes are freed only by ``resetSimulation``, which is run after
every :data:`RESET_EVERY` shapes.

By default (``rescale=True``) each shape is given in its own frame:
translated to its first vertex (or center) and scaled by a power of two so
that its size is in ``[0.5, 1)``.  pybullet's accuracy depends on the size
of the probe relative to the shape (it refuses a probe of radius 0); in the
shape's frame the probe is always the same small fraction of it.
``rescale=False`` (named ``pybullet[raw]``) gives pybullet the caller's
coordinates, the probe's radius 1e-9 in the caller's unit, as it would be
used directly: on 400 random shapes of each size, triangles were within
``6e-16 S`` down to a size of 1e-6, but of disks of a radius of about 1e-5,
47 nearest points were off the disk and 205 distances beyond the tolerance
(up to ``0.5% S``), and at 1e-6, 174 and 175 (up to ``49% S``).

Probe
    ``GEOM_SPHERE`` of radius 1e-9 (of the shape's size, or of the caller's
    unit without ``rescale``): pybullet refuses radius 0.  The radius is
    added back to every distance.
Triangle
    ``GEOM_MESH`` of the three vertices (a one-triangle convex hull).
Disk
    ``GEOM_CYLINDER`` of height 0, rotated so its axis is the normal.
Circle
    pybullet has no circle: the inscribed polygon of ``K`` segments, with
    the fewest ``K`` whose sagitta ``R (1 - cos(pi/K))`` meets the
    tolerance.  Its segments all have the same length, so one
    ``GEOM_CAPSULE`` of radius 1e-9 (pybullet refuses 0) is moved to each
    segment in turn and the nearest answer is kept; the capsule radius is
    added back.  A compound of ``K`` capsules would be one body, but
    ``getClosestPoints`` reports at most 16 points per pair of bodies, so a
    compound of more children can miss its nearest one; and creating a
    body costs far more than moving one.
TriangleMesh
    ``GEOM_MESH`` with ``GEOM_FORCE_CONCAVE_TRIMESH`` (a static concave
    mesh, not its convex hull), in the frame of its bounding box's center.
    ``getClosestPoints`` reports one point per face within the distance
    threshold, so each query costs time in proportion to the faces that
    threshold reaches, which here is the whole mesh; it does not report
    which face is nearest.

Every body's collision margin is set to 0 with ``changeDynamics`` (the
default is 0.001) and read back into :attr:`Model.margin`.

Known biases, translated
------------------------
* Degenerate triangles (collinear or coincident vertices) give no result:
  ``NO_RESULT``.
* Distances are signed: in contact, pybullet reports a distance between
  ``-r`` and 0 for the probe of radius ``r``.  After ``r`` is added back,
  negative distances are reported as 0, and points in contact can come out
  at up to ``r`` (1e-9 of the shape's size).  Rows reported touching where
  proximity finds the shape farther than the tolerance become
  ``FALSE_TOUCHING``.
* With the default margin of 0.001, a cylinder of height 0 is a disk whose
  rim is squared off: distances in directions 45 degrees off the rim's
  plane are too long by ``(sqrt(2) - 1) * 0.001``, whatever the radius
  (0.04% of a unit radius, 0.4% of a radius of 0.1).  With margin 0 this
  bias is gone.
* Near contact, GJK stops early: for points within about ``1e-6`` of the
  shape's size from it, distances are off by up to ``2e-6`` of the size
  (measured at a disk's rim), and points ``1e-7`` from a triangle can be
  reported touching.  Elsewhere distances agree with proximity to about
  ``1e-12`` of the size.  The documented relative tolerance is ``1e-5``.
Pair queries
------------
``getClosestPoints`` between a body of each side (one per member of a
batch), by default (``rescale=True``) all built in one frame per call: the
center of both shapes' boxes as origin, scaled by a power of two so that
they fit in a box of size below 1; without ``rescale``, in the caller's
coordinates.  A point is a ``GEOM_SPHERE`` of radius 1e-9 and a segment a
``GEOM_CAPSULE`` of that radius (pybullet refuses 0), added back; spheres
and capsules are ``GEOM_SPHERE(R)`` and ``GEOM_CAPSULE(R, L)``; a triangle
is a ``GEOM_MESH`` given its indices and a mesh a
``GEOM_FORCE_CONCAVE_TRIMESH``: both are triangle meshes.  A posed shape's
pose is its body's position and orientation.  Margins are set to 0.

* pybullet pairs a triangle mesh with convex shapes only: two of them give
  no points at all.  Where both sides are triangles or meshes, one is given
  as the convex hull of its vertices (pybullet's model of a mesh on a body
  that moves): a triangle against a mesh (a triangle's hull is the
  triangle), else b.  The answer is to that hull: a witness off the mesh,
  or contact where the meshes are apart, becomes ``CONVEX_HULL``.
  ``PybulletBackend(hull=False)`` gives both as triangle meshes, as
  pybullet pairs two static meshes: ``NO_RESULT``.
* In overlap pybullet reports the negative depth, with a point of each
  surface: distance 0 and ``CONTACT``.
* Answers are GJK's, documented to the same ``1e-5`` relative tolerance,
  but between a triangle mesh and a convex hull (two triangles, two
  meshes): ``1e-3``.  On 3200 random triangle pairs of sizes 1e-6 to 1e3,
  pybullet's distances were off by ``6e-6`` of the pair's size at the
  median, ``5.3e-5`` at the 99th percentile and ``9e-5`` at worst.
"""

import dataclasses
import typing
import weakref

import numpy as np

from ._base import Backend, Raw
from ._common import CALLER, Failure, import_library, norm, plane_frame, polygon, pow2_scale
from ._pairs import PairRaw, extent, quaternion, segment_frames

#: Radius of the probe sphere and of the circle's capsules, relative to the
#: shape's size; pybullet refuses 0.  Added back to every distance.
PROBE_RADIUS = 1e-9

IDENTITY = [0.0, 0.0, 0.0, 1.0]
ORIGIN = [0.0, 0.0, 0.0]

#: Kinds of pair side pybullet is given as a triangle mesh.
CONCAVE_KINDS = ("triangle", "mesh")

#: Relative accuracy of a triangle mesh against a convex hull (two triangles,
#: two meshes): on 3200 random triangle pairs of sizes 1e-6 to 1e3, pybullet's
#: distances were off by 6e-6 of the pair's size at the median, 5.3e-5 at the
#: 99th percentile and 9e-5 at worst.
HULL_RTOL = 1e-3

#: ``getClosestPoints``' distance threshold for pairs, relative to the
#: diagonal of the box around both shapes, beyond which they cannot be.
PAIR_REACH = 2.0

#: Collision shapes created between two ``resetSimulation`` calls: removing a
#: body does not free its collision shape.
RESET_EVERY = 1000


def load():
    """Import pybullet, or raise an ImportError naming the extra to install."""
    return import_library("pybullet", "pybullet", quiet=True)  # without its build banner


def _disconnect(pybullet, client):
    # A finalizer must not raise: at interpreter exit the server may already be gone.
    try:
        pybullet.disconnect(physicsClientId=client)
    except pybullet.error:
        pass


class _Body(typing.NamedTuple):
    """How the body of one shape of a point query is built, for :meth:`PybulletBackend._run`."""

    #: Creates the collision shape, in the frame of ``origin`` and ``factor``.
    create: typing.Callable
    #: ``(position, orientation)`` of each placement of the body, in that frame.
    placements: list
    #: The frame: ``local = (world - origin) * factor``.
    origin: np.ndarray
    factor: float
    #: Radius to add back to distances (a capsule standing in for a segment).
    added: float
    #: A ball around the shape, in the frame: center and radius.
    center: np.ndarray
    radius: float


def _quaternion_z_to(direction):
    """``(x, y, z, w)`` turning +z onto ``direction`` (unit rows); the sign of ``direction`` is free."""
    d = np.where(direction[..., 2:3] < 0, -direction, direction)
    q = np.stack([-d[..., 1], d[..., 0], np.zeros(d.shape[:-1]), 1.0 + d[..., 2]], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


class PybulletBackend(Backend):
    """Closest points by pybullet, in a ``DIRECT`` client owned by the backend.

    Parameters
    ----------
    hull : bool, optional
        In a pair query between two triangles or meshes, give one of them
        (a triangle against a mesh, else b) as the convex hull of its
        vertices (default True), without which pybullet gives no answer;
        see the module docstring.
    rescale : bool, optional, keyword-only
        Give pybullet each shape of a point query, and each pair, in a
        frame of its own (default True); with False (named
        ``pybullet[raw]``), the caller's coordinates.  See the module
        docstring.

    Examples
    --------
    >>> import proximity, proximity.adapters as adapters
    >>> disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> with adapters.get("pybullet") as pb:
    ...     r = pb.closest_point(disk, [[2.0, 0.0, 1.0]])
    >>> round(float(r.distance[0]), 9), r.model.margin
    (1.414213562, 0.0)
    """

    name = "pybullet"
    distribution = "pybullet"
    rtol = 1e-5
    primitives = {
        "triangle": "GEOM_MESH(1 triangle)",
        "disk": "GEOM_CYLINDER(R, height 0)",
        "circle": "GEOM_CAPSULE(1e-9, L) moved to K segments",
        "mesh": "GEOM_MESH(GEOM_FORCE_CONCAVE_TRIMESH)",
    }
    probe = f"GEOM_SPHERE(radius {PROBE_RADIUS:g} in the frame the shape is given in), added back"
    point_frames = {
        True: "per shape: origin at a vertex or the center, scaled by a power of two",
        False: CALLER,
    }
    tessellated = ("circle",)

    pair_models = {
        "point": f"GEOM_SPHERE({PROBE_RADIUS:g}), added back",
        "sphere": "GEOM_SPHERE(R)",
        "segment": f"GEOM_CAPSULE({PROBE_RADIUS:g}, L), added back",
        "capsule": "GEOM_CAPSULE(R, L)",
        "triangle": "GEOM_MESH(1 triangle)",
        "mesh": "GEOM_MESH(GEOM_FORCE_CONCAVE_TRIMESH)",
    }
    pair_hull = "GEOM_MESH(vertices alone: their convex hull)"
    pair_probe = "getClosestPoints(body a, body b), the nearest of the points reported"

    def pair_rtol(self, kind_a, kind_b):
        """``1e-5``; ``1e-3`` between two triangles or meshes (b given as its convex hull)."""
        if kind_a in CONCAVE_KINDS and kind_b in CONCAVE_KINDS:
            return HULL_RTOL
        return self.rtol

    def __init__(self, *, hull=True, rescale=True):
        super().__init__(rescale=rescale)
        self.hull = bool(hull)
        self._p = load()
        self._client = self._p.connect(self._p.DIRECT)
        if self._client < 0:
            raise RuntimeError("pybullet could not start a DIRECT physics client")
        self._finalizer = weakref.finalize(self, _disconnect, self._p, self._client)
        self._created = 0
        self._probe = self._new_probe()

    @property
    def client(self):
        """The physics client id this backend owns."""
        return self._client

    @property
    def closed(self):
        """Whether :meth:`close` has run."""
        return not self._finalizer.alive

    def close(self):
        """Disconnect the physics client; further queries raise RuntimeError."""
        self._finalizer()

    def num_bodies(self):
        """Bodies in this backend's world (the probe, and the shape being asked about)."""
        return self._p.getNumBodies(physicsClientId=self._client)

    def _call(self, name, *args, **kwargs):
        return getattr(self._p, name)(*args, physicsClientId=self._client, **kwargs)

    def _new_probe(self):
        sphere = self._call("createCollisionShape", self._p.GEOM_SPHERE, radius=PROBE_RADIUS)
        self._created += 1
        return self._call("createMultiBody", baseMass=0, baseCollisionShapeIndex=sphere)

    def _fresh_world(self):
        # Bodies are removed after each shape, but their collision shapes stay
        # in the server until the simulation is reset.
        if self._created >= RESET_EVERY:
            self._call("resetSimulation")
            self._created = 0
            self._probe = self._new_probe()

    def _frame(self, origin, size):
        """``(origin, factor)`` of the frame a shape is given in: with ``rescale``, its own
        (``origin``, and the power of two that brings ``size`` into ``[0.5, 1)``), else the
        caller's coordinates."""
        if self.rescale:
            return np.asarray(origin, dtype=np.float64), float(pow2_scale(size))
        return np.zeros(3), 1.0

    def _run(self, query, describe):
        """Answer every group of rows.

        ``describe(k)`` gives the :class:`_Body` of shape ``k``, in the
        frame of :meth:`_frame`.  The body is asked at each placement in
        turn (the segments of a circle) and each row keeps its nearest
        answer.
        """
        if self.closed:
            raise RuntimeError("this pybullet backend is closed")
        raw = Raw.empty(len(query.index))
        margins = [0.0]
        for k, chunk in query.groups():
            create, placements, origin, factor, added, center, radius = describe(k)
            self._fresh_world()
            try:
                shape = create()
                self._created += 1
                position, orientation = placements[0]
                body = self._call(
                    "createMultiBody",
                    baseMass=0,
                    baseCollisionShapeIndex=shape,
                    basePosition=position,
                    baseOrientation=orientation,
                )
            except self._p.error:
                raw.failure[chunk] = Failure.EXCEPTION
                continue
            local = (query.points[chunk] - origin) * factor
            # Beyond the farthest point of the shape from each point, nothing is missed.
            reach = 2.0 * (norm(local - center) + radius)
            distance = np.full(len(chunk), np.inf)
            nearest = np.full((len(chunk), 3), np.nan)
            failure = np.full(len(chunk), Failure.OK, dtype=np.int8)
            try:
                self._call("changeDynamics", body, -1, collisionMargin=0.0)
                margins.append(self._call("getDynamicsInfo", body, -1)[-1] / factor)
                for position, orientation in placements:
                    self._call("resetBasePositionAndOrientation", body, position, orientation)
                    d, x, f = self._ask(body, local, added, reach)
                    closer = (f == Failure.OK) & (d < distance)
                    distance[closer] = d[closer]
                    nearest[closer] = x[closer]
                    failure = np.maximum(failure, f)
            finally:
                self._call("removeBody", body)
            distance[failure != Failure.OK] = np.nan
            raw.distance[chunk] = distance / factor
            raw.point[chunk] = nearest / factor + origin
            raw.failure[chunk] = failure
        return Raw(raw.distance, raw.point, raw.failure, margin=max(margins))

    def _ask(self, body, local, added, reach):
        n = len(local)
        distance = np.full(n, np.nan)
        nearest = np.full((n, 3), np.nan)
        failure = np.full(n, Failure.OK, dtype=np.int8)
        for i, p in enumerate(local.tolist()):
            self._call("resetBasePositionAndOrientation", self._probe, p, IDENTITY)
            contacts = self._call("getClosestPoints", body, self._probe, float(reach[i]))
            if not contacts:
                failure[i] = Failure.NO_RESULT
                continue
            best = min(contacts, key=lambda c: c[8])
            # Signed distance between the inflated shapes, with the probe's and
            # the capsule's radii added back; small negatives mean contact.
            distance[i] = best[8] + PROBE_RADIUS + added
            nearest[i] = best[5]
        return distance, nearest, failure

    def _pair_bodies(self, s, hull, made):
        """``(bodies, added, margins)``: one body per member of side ``s`` (in the frame of
        :func:`scaled`), each also appended to ``made``; the radius to add back to its
        distances (the probe radius standing in for 0); and the margins of mesh bodies.
        ``hull``: a triangle or mesh is given as the convex hull of its vertices."""
        p = self._p
        rotation, position = s.rotation, s.translation
        if s.kind == "mesh":
            members = [(s.vertices, s.faces, rotation, position)]
        elif s.kind == "triangle":
            members = [(v, None, rotation, position) for v in s.vertices]
        elif s.kind in ("segment", "capsule"):
            frames, middle, length = segment_frames(s.vertices)
            members = [
                (length[k], None, rotation @ frames[k], rotation @ middle[k] + position)
                for k in range(len(s.vertices))
            ]
        else:
            members = [(None, None, rotation, rotation @ v[0] + position) for v in s.vertices]
        bodies, added, margins = [], np.zeros(len(members)), []
        for k, (geometry, faces, r, t) in enumerate(members):
            radius = float(s.radius[k])
            given = max(radius, PROBE_RADIUS)
            added[k] = given - radius
            if s.kind in ("point", "sphere"):
                shape = self._call("createCollisionShape", p.GEOM_SPHERE, radius=given)
            elif s.kind in ("segment", "capsule"):
                height = float(geometry)
                shape = self._call("createCollisionShape", p.GEOM_CAPSULE, radius=given, height=height)
            else:
                # With indices, pybullet builds a concave triangle mesh, which it pairs
                # with convex shapes only; vertices alone are their convex hull.
                if hull:
                    options = {}
                elif faces is None:
                    options = dict(indices=[0, 1, 2])
                else:
                    options = dict(indices=faces.ravel().tolist(), flags=p.GEOM_FORCE_CONCAVE_TRIMESH)
                shape = self._call("createCollisionShape", p.GEOM_MESH, vertices=geometry.tolist(), **options)
            self._created += 1
            body = self._call(
                "createMultiBody",
                baseMass=0,
                baseCollisionShapeIndex=shape,
                basePosition=t.tolist(),
                baseOrientation=quaternion(r).tolist(),
            )
            bodies.append(body)
            made.append(body)
            self._call("changeDynamics", body, -1, collisionMargin=0.0)
            if s.kind in ("triangle", "mesh"):  # spheres and capsules report their radius
                margins.append(self._call("getDynamicsInfo", body, -1)[-1])
        return bodies, added, margins

    def _pairs(self, query):
        if self.closed:
            raise RuntimeError("this pybullet backend is closed")
        a, b = query.a, query.b
        low, high = extent(query)
        reach = PAIR_REACH * float(norm(high - low) + a.radius.max(initial=0.0) + b.radius.max(initial=0.0))
        # pybullet pairs a concave triangle mesh (a triangle or mesh given with its
        # indices) with convex shapes only: where both sides are triangles or meshes,
        # one is given as the convex hull of its vertices: a triangle (whose hull is
        # itself) against a mesh, else b.
        hull = None
        if self.hull and a.kind in CONCAVE_KINDS and b.kind in CONCAVE_KINDS:
            hull = a if (a.kind, b.kind) == ("triangle", "mesh") else b
        raw = PairRaw.empty(
            query.n,
            hull=(hull.name,) if hull is not None and hull.kind == "mesh" else (),
            models={hull.name: self.pair_hull} if hull is not None else {},
        )
        self._fresh_world()
        made, margins, more = [], [], []
        try:
            bodies_a, added_a, margins = self._pair_bodies(a, hull is a, made)
            bodies_b, added_b, more = self._pair_bodies(b, hull is b, made)
            for i in range(query.n):
                ka, kb = a.index[i], b.index[i]
                contacts = self._call("getClosestPoints", bodies_a[ka], bodies_b[kb], reach)
                if not contacts:
                    raw.failure[i] = Failure.NO_RESULT
                    continue
                best = min(contacts, key=lambda c: c[8])
                raw.distance[i] = best[8] + added_a[ka] + added_b[kb]
                raw.point_a[i], raw.point_b[i] = best[5], best[6]
        except self._p.error:
            raw.failure[:] = Failure.EXCEPTION
            raw.distance[:] = np.nan
        finally:
            for body in made:
                self._call("removeBody", body)
        # Spheres and capsules report their radius as their margin: only meshes' are read.
        return dataclasses.replace(raw, margin=max(margins + more, default=0.0))

    def _triangles(self, query):
        def describe(k):
            v = query.vertices[k]
            origin, factor = self._frame(v[0], np.max(np.abs(v - v[0])))
            local = (v - origin) * factor

            def create():
                return self._call(
                    "createCollisionShape", self._p.GEOM_MESH, vertices=local.tolist(), indices=[0, 1, 2]
                )

            radius = float(np.max(norm(local - local[0])))
            return _Body(create, [(ORIGIN, IDENTITY)], origin, factor, 0.0, local[0], radius)

        return self._run(query, describe)

    def _disks(self, query):
        def describe(k):
            origin, factor = self._frame(query.center[k], query.radius[k])
            radius = float(query.radius[k] * factor)
            center = (query.center[k] - origin) * factor

            def create():
                return self._call("createCollisionShape", self._p.GEOM_CYLINDER, radius=radius, height=0.0)

            # The cylinder's axis is set by the body's orientation: a frame
            # orientation on the shape would wrap it in a compound, whose
            # margin is not the cylinder's.
            placement = (center.tolist(), _quaternion_z_to(query.normal[k]).tolist())
            return _Body(create, [placement], origin, factor, 0.0, center, radius)

        return self._run(query, describe)

    def _circles(self, query):
        u, v = plane_frame(query.normal)

        def describe(k):
            origin, factor = self._frame(query.center[k], query.radius[k])
            center = (query.center[k] - origin) * factor
            radius = float(query.radius[k] * factor)
            corners = polygon(center, u[k], v[k], radius, int(query.segments[k]))
            axis = corners[1:] - corners[:-1]
            # All segments of the inscribed polygon have the same length, so
            # one capsule serves them all, moved from segment to segment.
            length = float(np.linalg.norm(axis[0]))
            direction = axis / max(length, np.finfo(np.float64).tiny)
            placements = list(
                zip(
                    ((corners[1:] + corners[:-1]) / 2).tolist(),
                    _quaternion_z_to(direction).tolist(),
                    strict=True,
                )
            )

            def create():
                return self._call(
                    "createCollisionShape", self._p.GEOM_CAPSULE, radius=PROBE_RADIUS, height=length
                )

            return _Body(create, placements, origin, factor, PROBE_RADIUS, center, radius)

        return self._run(query, describe)

    def _meshes(self, query):
        def describe(k):
            v = query.vertices
            middle = v.min(axis=0) * 0.5 + v.max(axis=0) * 0.5
            origin, factor = self._frame(middle, np.max(np.abs(v - middle)))
            local = ((v - origin) * factor).tolist()
            indices = query.faces.ravel().tolist()
            center = (middle - origin) * factor
            radius = float(norm(v.max(axis=0) - middle)) * factor

            def create():
                return self._call(
                    "createCollisionShape",
                    self._p.GEOM_MESH,
                    vertices=local,
                    indices=indices,
                    flags=self._p.GEOM_FORCE_CONCAVE_TRIMESH,
                )

            return _Body(create, [(ORIGIN, IDENTITY)], origin, factor, 0.0, center, radius)

        return self._run(query, describe)
