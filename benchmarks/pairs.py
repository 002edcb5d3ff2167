"""Mesh against mesh: the distance between two posed meshes, against python-fcl, coal, trimesh and pybullet.

    python -m benchmarks.pairs [--quick] [--out DIR] [--seed 0]

**The pairs.**  An icosphere (radius 1) against a torus (radii 1 and 0.35)
at two sizes, a table each: 5,120 faces each (``icosphere(4)``,
``torus(64, 40)``) and 20,480 each (``icosphere(5)``, ``torus(128, 80)``;
``--quick``: 320 and 1,280).  The torus is turned at random and moved along
a random direction until the two are about ``gap`` apart (by proximity's
own answer), for gaps 1, 1e-2 and 1e-4, and then moved 0.05 further in to
overlap; 5 poses per gap (``--quick``: 2), the same directions and turns at
both sizes.  Every library answers the same pairs of posed meshes, its
hierarchies built once outside the timing (but where said):

* proximity: ``proximity.distance(sphere, torus.transformed(T))``, the
  ``robust`` and the ``certified`` method, one thread (one query);
* python-fcl: ``fcl.distance`` of two ``CollisionObject`` over
  ``BVHModel`` (OBBRSS), the torus's moved by ``setTransform``;
* coal: ``coal.distance`` of two ``BVHModelOBBRSS`` with their
  ``Transform3s``;
* trimesh (python-fcl behind it), ``CollisionManager.min_distance_other``
  between two managers of one mesh each, the torus's moved by
  ``set_transform``.  trimesh makes a mesh it finds convex (the icosphere)
  an ``fcl.Convex`` and the torus a ``BVHModel``, and asks for signed
  distances: overlapping meshes give a negative number that is not the
  depth;
* trimesh, ``min_distance_single(torus, transform=T)`` against a manager
  holding the icosphere: it builds the torus's hierarchy again in every
  call, and the time includes that build;
* pybullet, ``getClosestPoints`` between two static bodies in a ``DIRECT``
  client, the torus's moved by ``resetBasePositionAndOrientation`` (its
  rotation as a quaternion).  pybullet 3.2 makes ``createCollisionShape(
  GEOM_MESH, vertices=..., indices=...)`` a BVH triangle mesh whatever the
  mass and flags, and ``vertices=...`` alone their convex hull; a pair of
  triangle meshes has no collision algorithm and reports no points at all.
  Three models, as its users choose: *both meshes* (no answer, shown as
  such), *sphere hull to mesh* (the icosphere's hull, which is the
  icosphere, against the torus's triangles: the right shapes; each call
  runs GJK between the hull and every triangle near the sphere's box, so
  its cost grows with the faces of both) and *both hulls* (fast, but the
  torus's hull fills its hole).  The threshold passed is ``1.1 gap +
  1e-3`` (overlapping: 1e-3), a distance the caller knew the answer to be
  within: pybullet's best case (a threshold of 2 took 3-9 times longer at
  20,480 faces).  As the point adapter ``adapters/pybullet_backend.py``,
  each body's collision margin is set to 0 (default 0.001), read back and
  added to the distance (pybullet reports the distance between the shapes
  grown by their margins; the nearest of its points is kept).

A peer that is not installed, or fails to import, is skipped.  Timing: each
pose's query is repeated (5 times, ``--quick``: 2) by each library in
turn, the least time kept; the table gives the median over the poses.  The
slow ones, ``min_distance_single`` and pybullet's sphere hull to mesh
(marked ``*``; 40-120 ms and 50-1,500 ms a call here), are timed on one
call per pose, whose answer is the one checked.

**Accuracy** against the exact minimum over all pairs of faces of the
torus posed in float64 (``torus.transformed(T)``'s vertices ``R V + t``
as :func:`proximity.numerics.rigid.to_world` rounds them): a face of one mesh can
hold a pair within ``D`` only where its centroid's distance to the other
mesh, less its circumradius, is at most ``D`` (``D`` an upper bound of the
minimum, with a margin far beyond the point queries' error); the pairs of
those faces are evaluated by the ``robust`` triangle pair, and those whose
answer could be the least (within twice its bound) in rational arithmetic
(:mod:`proximity.testing.exact`).  A negative answer of a peer (its
convention for "in collision") counts as 0.  The table gives the largest
absolute error over the poses, and how many poses had no answer.

**Hausdorff distance.**  The larger two meshes, the torus turned at random
and moved 0.5 along a random direction (3 poses, ``--quick``: 2):
``proximity.hausdorff_distance(sphere, torus.transformed(T))`` (``robust``,
``rtol=1e-6``), its certified bounds and the time of the call; beside it,
where trimesh is installed, the usual estimate by sampling: 10,000 points
(``--quick``: 2,000) drawn on each mesh (``trimesh.sample.sample_surface``,
seeded) and their greatest distance to the other mesh
(``trimesh.proximity.closest_point``), its meshes and trees built outside the
timing.  A sample's estimate is a lower bound: the table gives how far below
proximity's certified lower bound it falls.

**Primitive pairs.**  A million random pairs (``--quick``: 100,000) of
segments, of capsules (radius 0.05) and of triangles, answered by one
batched ``proximity.distance`` (all threads), against one call per pair
of python-fcl and coal (3,000 pairs, ``--quick``: 300; capsules by their
``Capsule`` primitives posed along the segments, segments as capsules of
radius 0, triangles as one-triangle hierarchies, which both need: neither
answers a ``TriangleP`` against another) and a vectorised NumPy
segment-segment baseline (the lines' closest points clamped to the
segments); the largest error against the exact distance on the first 200
pairs (``--quick``: 40).

``OUT/pairs.json`` holds the raw data; the project's targets (proximity at
least 2x faster than python-fcl and coal at a gap of 1e-2, batched
primitive pairs at least 20x coal's rate per call; the meshes of 20,480
faces, ``--quick``: 1,280) are checked apart in
``OUT/checks-pairs.txt``.
"""

import argparse
import os
import sys
import time

import mpmath
import numpy as np

import proximity
from adapters.pybullet_backend import load as load_pybullet
from benchmarks.moving import _installed, random_rotations
from benchmarks.saving import measure_and_save
from proximity.numerics.rigid import to_world
from proximity.testing import exact
from proximity.testing.exact import PREC
from proximity.testing.meshes import icosphere, torus

GAPS = (1.0, 1e-2, 1e-4, -0.05)
EPS = 2.0**-52


def meshes(quick):
    """The pairs ``((vertices, faces) of the icosphere, of the torus)``, the smaller first."""
    if quick:
        return [(icosphere(2), torus(16, 10)), (icosphere(3), torus(32, 20))]
    return [(icosphere(4), torus(64, 40)), (icosphere(5), torus(128, 80))]


def poses(sphere, ring, rng, gap, count):
    """``count`` poses of ``ring`` about ``gap`` from ``sphere`` (a negative gap: that much further in
    from about 1e-3)."""
    out = []
    for rotation in random_rotations(rng, count):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        t = 3.0 * u
        target = gap if gap > 0 else 1e-3
        for _ in range(60):
            pose = np.eye(4)
            pose[:3, :3], pose[:3, 3] = rotation, t
            d = float(proximity.distance(sphere, ring.transformed(pose)))
            if abs(d - target) <= 1e-3 * target:
                break
            t = t + (target - d) * u
        if gap < 0:
            pose[:3, 3] = t + gap * u
        out.append(pose)
    return out


def exact_distance(va, fa, vb, fb, upper):
    """The exact minimum distance over the face pairs of two meshes (an ``mpmath`` number), given
    ``upper``, a float at least the minimum; see the module docstring."""
    from proximity.testing import exact

    mesh_a, mesh_b = proximity.TriangleMesh(va, fa), proximity.TriangleMesh(vb, fb)
    margin = 1e-9 + 1e-9 * upper

    def near(tris, other):
        centroid = tris.mean(axis=1)
        radius = np.max(np.linalg.norm(tris - centroid[:, None], axis=-1), axis=1)
        return np.flatnonzero(other.distance(centroid) - radius <= upper + margin)

    ta, tb = va[fa], vb[fb]
    ia, ib = near(ta, mesh_b), near(tb, mesh_a)
    robust = proximity.distance(proximity.Triangle(ta[ia][:, None]), proximity.Triangle(tb[ib][None, :]))
    scale = float(np.max(np.ptp(np.concatenate([ta[ia].reshape(-1, 3), tb[ib].reshape(-1, 3)]), axis=0)))
    bound = 16 * EPS * scale + 2.0**-1070
    best = None
    for i, j in np.argwhere(robust <= robust.min() + 2 * bound):
        sqr = exact.triangle_triangle_closest(ta[ia[i]], tb[ib[j]]).sqr_distance
        best = sqr if best is None or sqr < best else best
        if best == 0:  # a common point: nothing is nearer
            break
    with mpmath.workprec(exact.PREC):
        return mpmath.sqrt(exact.to_mpf(best)), len(ia) * len(ib)


def _fcl(vertices, faces):
    import fcl

    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(np.ascontiguousarray(vertices), np.ascontiguousarray(faces))
    model.endModel()
    return model


def fcl_query(mesh_a, mesh_b, points=False):
    """A function of a pose: fcl's distance between the meshes, b posed (with its nearest points
    where ``points``)."""
    import fcl

    a = fcl.CollisionObject(_fcl(*mesh_a), fcl.Transform())
    b = fcl.CollisionObject(_fcl(*mesh_b), fcl.Transform())
    request = fcl.DistanceRequest(enable_nearest_points=points)

    def query(pose, reach):
        b.setTransform(fcl.Transform(pose[:3, :3], pose[:3, 3]))
        return fcl.distance(a, b, request, fcl.DistanceResult())

    return query


def _coal(vertices, faces):
    import coal

    model = coal.BVHModelOBBRSS()
    model.beginModel(len(faces), len(vertices))
    model.addVertices(np.ascontiguousarray(vertices))
    model.addTriangles(np.ascontiguousarray(faces, dtype=np.int64))
    model.endModel()
    return model


def coal_query(mesh_a, mesh_b):
    """A function of a pose: coal's distance between the meshes, b posed."""
    import coal

    a, b = _coal(*mesh_a), _coal(*mesh_b)
    identity = coal.Transform3s()
    request, result = coal.DistanceRequest(), coal.DistanceResult()

    def query(pose, reach):
        result.clear()
        return coal.distance(a, identity, b, coal.Transform3s(pose[:3, :3], pose[:3, 3]), request, result)

    return query


def proximity_query(mesh_a, mesh_b, method, points=False):
    """A function of a pose: proximity's distance between the meshes, b posed (its closest points
    too where ``points``, the witnesses read as a user reads them)."""
    a, b = proximity.TriangleMesh(*mesh_a), proximity.TriangleMesh(*mesh_b)

    def query(pose, reach):
        return float(proximity.distance(a, b.transformed(pose), method=method))

    def closest(pose, reach):
        r = proximity.closest_points(a, b.transformed(pose), method=method)
        _ = r.point_a, r.point_b
        return float(r.distance)

    return closest if points else query


def trimesh_other_query(mesh_a, mesh_b):
    """A function of a pose: ``CollisionManager.min_distance_other`` between two managers of one mesh
    each, b's moved by ``set_transform`` (its hierarchy built once)."""
    import trimesh

    a, b = trimesh.collision.CollisionManager(), trimesh.collision.CollisionManager()
    a.add_object("a", trimesh.Trimesh(*mesh_a, process=False))
    b.add_object("b", trimesh.Trimesh(*mesh_b, process=False))

    def query(pose, reach):
        b.set_transform("b", pose)
        return a.min_distance_other(b)

    return query


def trimesh_single_query(mesh_a, mesh_b):
    """A function of a pose: ``CollisionManager.min_distance_single`` of mesh b, posed, against a
    manager holding a; trimesh builds b's hierarchy again in every call."""
    import trimesh

    a = trimesh.collision.CollisionManager()
    a.add_object("a", trimesh.Trimesh(*mesh_a, process=False))
    b = trimesh.Trimesh(*mesh_b, process=False)

    def query(pose, reach):
        return a.min_distance_single(b, transform=pose)

    return query


def _pybullet_query(hull_a, hull_b):
    """A maker of functions of a pose: pybullet's ``getClosestPoints`` between two static bodies, each
    its mesh's convex hull (``hull_*``: vertices alone) or its triangles (vertices and indices: a BVH
    triangle mesh); ``None`` where it reports no points."""

    def make(mesh_a, mesh_b):
        from scipy.spatial.transform import Rotation

        pybullet = load_pybullet()
        client = pybullet.connect(pybullet.DIRECT)

        def body(vertices, faces, hull):
            triangles = {} if hull else {"indices": faces.ravel().tolist()}
            shape = pybullet.createCollisionShape(pybullet.GEOM_MESH, vertices=vertices.tolist(),
                                                  physicsClientId=client, **triangles)  # fmt: skip
            made = pybullet.createMultiBody(baseMass=0, baseCollisionShapeIndex=shape, physicsClientId=client)
            # As the point adapter: margin 0 (default 0.001), read back and added to every distance.
            pybullet.changeDynamics(made, -1, collisionMargin=0.0, physicsClientId=client)
            return made, pybullet.getDynamicsInfo(made, -1, physicsClientId=client)[-1]

        (a, margin_a), (b, margin_b) = body(*mesh_a, hull_a), body(*mesh_b, hull_b)

        def query(pose, reach):
            turn = Rotation.from_matrix(pose[:3, :3]).as_quat().tolist()
            pybullet.resetBasePositionAndOrientation(b, pose[:3, 3].tolist(), turn, physicsClientId=client)
            found = pybullet.getClosestPoints(a, b, reach, physicsClientId=client)
            # Distances between the shapes grown by their margins; negative in contact.
            return min(c[8] for c in found) + margin_a + margin_b if found else None

        query.close = lambda: pybullet.disconnect(physicsClientId=client)
        return query

    return make


#: ``(key, label, modules to import, maker, repeats)``: a maker takes the two meshes ``(vertices,
#: faces)`` and gives a function of the pose of b and a distance the answer is known to be within (the
#: threshold pybullet needs); repeats ``None``: the run's, else that many.
LIBRARIES = (
    ("robust", "proximity, robust", None, lambda a, b: proximity_query(a, b, "robust"), None),
    (
        "robust_points",
        "proximity, robust, closest points",
        None,
        lambda a, b: proximity_query(a, b, "robust", points=True),
        None,
    ),
    ("certified", "proximity, certified", None, lambda a, b: proximity_query(a, b, "certified"), None),
    ("fcl", "python-fcl", "fcl", fcl_query, None),
    ("fcl_points", "python-fcl, nearest points", "fcl", lambda a, b: fcl_query(a, b, points=True), None),
    ("coal", "coal", "coal", coal_query, None),
    ("trimesh", "trimesh, min_distance_other", "trimesh fcl", trimesh_other_query, None),
    ("trimesh_single", "trimesh, min_distance_single", "trimesh fcl", trimesh_single_query, 1),
    ("pybullet_meshes", "pybullet, both meshes", "pybullet", _pybullet_query(False, False), None),
    ("pybullet_hull_mesh", "pybullet, sphere hull to mesh", "pybullet", _pybullet_query(True, False), 1),
    ("pybullet_hulls", "pybullet, both hulls", "pybullet", _pybullet_query(True, True), None),
)


def _trimesh_sampled(mesh_a, mesh_b, samples, seed):
    """A function of nothing: trimesh's sampled Hausdorff estimate of two ``(vertices, faces)``."""
    import trimesh

    a = trimesh.Trimesh(*mesh_a, process=False)
    b = trimesh.Trimesh(*mesh_b, process=False)
    for m in (a, b):
        trimesh.proximity.closest_point(m, m.vertices[:1])  # builds its r-tree, outside the timing

    def query():
        pa = trimesh.sample.sample_surface(a, samples, seed=seed)[0]
        pb = trimesh.sample.sample_surface(b, samples, seed=seed + 1)[0]
        return max(float(trimesh.proximity.closest_point(b, pa)[1].max()),
                   float(trimesh.proximity.closest_point(a, pb)[1].max()))  # fmt: skip

    return query


def hausdorff(mesh_a, mesh_b, rng, quick, log=print):
    """The Hausdorff rows: proximity's certified bounds and trimesh's sampled estimate, per pose."""
    count, samples = (2, 2_000) if quick else (3, 10_000)
    sphere, ring = proximity.TriangleMesh(*mesh_a), proximity.TriangleMesh(*mesh_b)
    problem = _installed("trimesh") or _installed("rtree")
    rows = []
    for k, rotation in enumerate(random_rotations(rng, count)):
        u = rng.normal(size=3)
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = rotation, 0.5 * u / np.linalg.norm(u)
        start = time.perf_counter()
        r = proximity.hausdorff_distance(sphere, ring.transformed(pose), rtol=1e-6)
        row = {"time": time.perf_counter() - start, "lower": r.lower, "upper": r.upper,
               "converged": r.converged, "points": r.points_evaluated, "side": r.side}  # fmt: skip
        if not problem:
            posed = (to_world(mesh_b[0], pose[:3, :3], pose[:3, 3]), mesh_b[1])
            query = _trimesh_sampled(mesh_a, posed, samples, 1000 + k)
            start = time.perf_counter()
            estimate = query()
            row["trimesh"] = {"time": time.perf_counter() - start, "estimate": estimate, "samples": samples}
        rows.append(row)
        log(f"hausdorff pose {k}: [{r.lower:.12g}, {r.upper:.12g}] in {row['time'] * 1e3:.1f} ms"
            + (f"; trimesh {row['trimesh']['estimate']:.12g}" if "trimesh" in row else ""))  # fmt: skip
    return {"rows": rows, "skipped": {"trimesh": problem} if problem else {}, "samples": samples}


def _frame(vertices):
    """``(rotation, centre, length)`` of segments ``(n, 2, 3)``: the rotation takes z to each
    segment's direction (a capsule's axis in coal and python-fcl)."""
    centre = vertices.mean(axis=1)
    axis = vertices[:, 1] - vertices[:, 0]
    length = np.linalg.norm(axis, axis=1)
    z = axis / length[:, None]
    helper = np.where(np.abs(z[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=-1), centre, length


def _peer_call(name, kind, a, b, radius):
    """One call of python-fcl or coal for pair ``i`` of ``a``, ``b``, as a function of ``i`` that
    gives ``(distance, nearest points)``, the points read as their users read them (python-fcl's
    ``nearest_points`` with ``enable_nearest_points``, coal's ``getNearestPoint1`` and ``2``):
    capsules (radius 0: segments) by their primitives, triangles as one-triangle hierarchies
    (neither answers a triangle primitive against another)."""
    lib = __import__(name)
    if kind == "triangle":
        objects = [[_coal(t, [[0, 1, 2]]) if name == "coal" else _fcl(t, [[0, 1, 2]]) for t in side]
                   for side in (a, b)]  # fmt: skip
        poses = [[np.eye(4)] * len(a)] * 2
    else:
        objects, poses = [], []
        for side in (a, b):
            rotation, centre, length = _frame(side)
            objects.append([lib.Capsule(radius, float(h)) for h in length])
            pose = np.tile(np.eye(4), (len(side), 1, 1))
            pose[:, :3, :3], pose[:, :3, 3] = rotation, centre
            poses.append(pose)
    if name == "coal":
        request, result = lib.DistanceRequest(), lib.DistanceResult()
        transforms = [[lib.Transform3s(p[:3, :3], p[:3, 3]) for p in side] for side in poses]

        def one(i):
            result.clear()
            o, t = objects, transforms
            d = lib.distance(o[0][i], t[0][i], o[1][i], t[1][i], request, result)
            return d, (result.getNearestPoint1(), result.getNearestPoint2())

        return one
    request = lib.DistanceRequest(enable_nearest_points=True)
    pairs = [[lib.CollisionObject(o, lib.Transform(p[:3, :3], p[:3, 3])) for o, p in zip(objs, side,
              strict=True)] for objs, side in zip(objects, poses, strict=True)]  # fmt: skip

    def one(i):
        result = lib.DistanceResult()
        d = lib.distance(pairs[0][i], pairs[1][i], request, result)
        return d, result.nearest_points

    return one


def _peer_calls(name, kind, a, b, radius, calls):
    """``(seconds per call, distances)`` of ``calls`` pairs by python-fcl or coal, one call each
    (:func:`_peer_call`)."""
    one = _peer_call(name, kind, a[:calls], b[:calls], radius)
    one(0)
    start = time.perf_counter()
    out = [one(i)[0] for i in range(calls)]
    return (time.perf_counter() - start) / calls, np.array(out, dtype=np.float64)


#: The single calls timed: kinds of primitive pairs, and the radius of capsules.
SINGLE_KINDS = (("capsule", 0.25), ("segment", 0.0), ("triangle", 0.0))


def _single_calls(kind, a, b, radius):
    """``{library: function of a pair index}``: one warm call for one pair of shapes, proximity's
    witnesses read as its users read them (``point_a`` and ``point_b``), the peers' as
    :func:`_peer_call` reads them."""
    if radius:
        capsules = proximity.Capsule
        ours = [(capsules(x, radius), capsules(y, radius)) for x, y in zip(a, b, strict=True)]
    else:
        make = proximity.Triangle if kind == "triangle" else proximity.Segment
        ours = [(make(x), make(y)) for x, y in zip(a, b, strict=True)]

    def closest_points(i):
        r = proximity.closest_points(*ours[i])
        return r.distance, r.point_a, r.point_b

    def distance(i):
        return proximity.distance(*ours[i])

    calls = {"closest_points": closest_points, "distance": distance}
    for name in ("fcl", "coal"):
        if not _installed(name):
            calls[name] = _peer_call(name, kind, a, b, radius)
    return calls


def single_calls(rng, quick, log=print):
    """Warm single calls of one pair of primitives, proximity's ``closest_points`` and ``distance``
    against python-fcl's and coal's distance with nearest points: the least time per call over
    rounds in which each library takes its turn, on the same pairs."""
    pairs, rounds = (200, 3) if quick else (1000, 7)
    rows = []
    for kind, radius in SINGLE_KINDS:
        nv = 3 if kind == "triangle" else 2
        a = rng.uniform(-1.0, 1.0, (pairs, nv, 3))
        b = a.mean(axis=1, keepdims=True) + rng.normal(0.0, 0.5, (pairs, nv, 3))
        calls = _single_calls(kind, a, b, radius)
        best = {name: np.inf for name in calls}
        for one in calls.values():  # compiled and warm outside the timing
            one(0)
        for _ in range(rounds):
            for name, one in calls.items():
                start = time.perf_counter()
                for i in range(pairs):
                    one(i)
                best[name] = min(best[name], (time.perf_counter() - start) / pairs)
        rows.append({"kind": kind, "radius": radius, "pairs": pairs, "seconds": best})
        log(f"single {kind} pair: " + ", ".join(f"{k} {v * 1e6:.2f} us" for k, v in best.items()))
    return rows


def _numpy_segments(a, b):
    """Segment-segment distances in vectorised NumPy: the closest points of the two lines,
    clamped to the segments (the textbook method), as a baseline."""
    d1, d2, r = a[:, 1] - a[:, 0], b[:, 1] - b[:, 0], a[:, 0] - b[:, 0]
    aa, ee, f = (d1 * d1).sum(1), (d2 * d2).sum(1), (d2 * r).sum(1)
    c, bb = (d1 * r).sum(1), (d1 * d2).sum(1)
    denom = aa * ee - bb * bb
    with np.errstate(all="ignore"):
        s = np.where(denom > 0, np.clip((bb * f - c * ee) / denom, 0, 1), 0.0)
        t = (bb * s + f) / ee
        s = np.where(t < 0, np.clip(-c / aa, 0, 1), np.where(t > 1, np.clip((bb - c) / aa, 0, 1), s))
        t = np.clip(t, 0, 1)
    gap = a[:, 0] + d1 * s[:, None] - b[:, 0] - d2 * t[:, None]
    return np.sqrt((gap * gap).sum(1))


PRIMITIVE_KINDS = (("segment", 0.0), ("capsule", 0.05), ("triangle", 0.0))


def primitives(rng, quick, log=print, sizes=None):
    """Batched primitive pairs: proximity's rate against python-fcl's and coal's per call and a
    NumPy baseline, with the largest error against the exact distance on a sample; ``sizes``:
    ``(pairs, peer calls, exact sample)`` where not the defaults."""
    n, calls, sample = sizes or ((100_000, 300, 40) if quick else (1_000_000, 3_000, 200))
    rows = []
    for kind, radius in PRIMITIVE_KINDS:
        nv = 3 if kind == "triangle" else 2
        a = rng.uniform(-1.0, 1.0, (n, nv, 3))
        b = a.mean(axis=1, keepdims=True) + rng.normal(0.0, 0.5, (n, nv, 3))
        shape = proximity.Triangle if kind == "triangle" else proximity.Segment
        sa, sb = shape(a), shape(b)
        if radius:
            sa, sb = proximity.Capsule(a, radius), proximity.Capsule(b, radius)
        proximity.closest_points(shape(a[:10]), shape(b[:10]))  # compiled outside the timing
        proximity.distance(shape(a[:10]), shape(b[:10]))
        best = {"distance": np.inf, "closest_points": np.inf}
        for _ in range(3):
            for name in ("distance", "closest_points"):
                call = getattr(proximity, name)
                start = time.perf_counter()
                answer = call(sa, sb)
                best[name] = min(best[name], time.perf_counter() - start)
                if name == "distance":
                    ours = answer
            del answer
        row = {"kind": kind, "pairs": n, "radius": radius, "proximity": n / best["distance"],
               "proximity_points": n / best["closest_points"], "libraries": {}}  # fmt: skip
        reference = []
        for i in range(sample):
            if kind == "triangle":
                sqr = exact.triangle_triangle_closest(a[i], b[i]).sqr_distance
            else:
                sqr = exact.segment_segment_closest(a[i], b[i]).sqr_distance
            with mpmath.workprec(PREC):
                reference.append(mpmath.sqrt(exact.to_mpf(sqr)) - 2 * mpmath.mpf(radius))
        exact_d = [max(r, 0) for r in reference]

        def error(values, exact_d=exact_d):
            with mpmath.workprec(PREC):
                return max(float(abs(mpmath.mpf(float(max(x, 0.0))) - r))
                           for x, r in zip(values, exact_d, strict=False))  # fmt: skip

        row["error"] = error(ours[:sample])
        for name in ("fcl", "coal"):
            problem = _installed(name)
            if problem:
                row["libraries"][name] = {"skipped": problem}
                continue
            per_call, values = _peer_calls(name, kind, a, b, radius, calls)
            row["libraries"][name] = {"rate": 1.0 / per_call, "error": error(values[:sample])}
        if kind != "triangle":
            start = time.perf_counter()
            values = np.maximum(_numpy_segments(a, b) - 2 * radius, 0.0)
            row["libraries"]["numpy"] = {"rate": n / (time.perf_counter() - start), "error": error(values)}
        rows.append(row)
        log(f"primitive pairs, {kind}: proximity {row['proximity'] / 1e6:.1f} M pairs/s")
    return rows


def _missing(modules):
    """Why one of ``modules`` (names separated by spaces) cannot be imported, or ``None``."""
    for module in modules.split():
        if module == "pybullet":
            try:
                load_pybullet()  # without its build banner on the report's stdout
            except Exception as exc:  # noqa: BLE001 (as _installed)
                return f"{type(exc).__name__}: {exc}"
        problem = _installed(module)
        if problem:
            return problem
    return None


def mesh_pair(mesh_a, mesh_b, rng, count, repeats, log=print):
    """Every gap and library for one pair of meshes: ``(rows, gaps)``, the libraries and the raw data."""
    sphere, ring = proximity.TriangleMesh(*mesh_a), proximity.TriangleMesh(*mesh_b)
    queries, rows, times_of = {}, {}, {}
    for key, label, modules, make, own_repeats in LIBRARIES:
        problem = _missing(modules) if modules else None
        rows[key] = {"label": label}
        if problem:
            rows[key]["skipped"] = problem
            log(f"{label}: skipped ({problem})")
            continue
        queries[key] = make(mesh_a, mesh_b)
        queries[key](np.eye(4), 10.0)  # compiled, and the hierarchies built
        times_of[key] = own_repeats or repeats
        rows[key]["repeats"] = times_of[key]
    gaps = []
    for gap in GAPS:
        log(f"{len(mesh_a[1]):,} faces, gap {gap:g}: posing")
        pose_list = poses(sphere, ring, rng, gap, count)
        # pybullet's threshold: the poses are within 0.1% of the gap (overlapping: touching).
        reach = 1.1 * max(gap, 0.0) + 1e-3
        times = {key: [] for key in queries}
        answers = {key: [] for key in queries}
        references, exact_values, pairs_checked = [], [], []
        for pose in pose_list:
            best = {key: np.inf for key in queries}
            for key, query in queries.items():
                if times_of[key] > 1:
                    answers[key].append(query(pose, reach))
            for k in range(repeats):
                for key, query in queries.items():  # in turn, so that a busy machine slows all alike
                    if k >= times_of[key]:
                        continue
                    start = time.perf_counter()
                    answer = query(pose, reach)
                    best[key] = min(best[key], time.perf_counter() - start)
                    if times_of[key] == 1:  # a slow peer: its one timed call gives the answer
                        answers[key].append(answer)
            for key in queries:
                times[key].append(best[key])
            posed_b = to_world(mesh_b[0], pose[:3, :3], pose[:3, 3])
            upper = max(answers["robust"][-1], 0.0) + 1e-6 if "robust" in answers else 10.0
            d_exact, checked = exact_distance(mesh_a[0], mesh_a[1], posed_b, mesh_b[1], upper)
            references.append(float(d_exact))
            exact_values.append(d_exact)
            pairs_checked.append(checked)
        row = {"gap": gap, "exact": references, "face_pairs_checked": pairs_checked, "libraries": {}}
        for key in queries:
            errors = []
            # In mpmath: an error below the ulp of the distance is not lost to rounding.
            with mpmath.workprec(PREC):
                for x, r in zip(answers[key], exact_values, strict=True):
                    if x is not None:  # a negative answer (in contact) counts as 0
                        errors.append(float(abs(mpmath.mpf(max(float(x), 0.0)) - r)))
            row["libraries"][key] = {
                "time": float(np.median(times[key])),
                "times": times[key],
                "answers": [None if x is None else float(x) for x in answers[key]],
                "error": max(errors) if errors else None,
                "missing": sum(x is None for x in answers[key]),
            }
        gaps.append(row)
        timing = ", ".join(f"{k} {v['time'] * 1e3:.3f} ms" for k, v in row["libraries"].items())
        log(f"{len(mesh_a[1]):,} faces, gap {gap:g}: {timing}")
    for query in queries.values():
        getattr(query, "close", lambda: None)()
    return rows, gaps


def run(quick=False, seed=0, log=print):
    """Every size, gap and library; the raw data."""
    count, repeats = (2, 2) if quick else (5, 5)
    sizes = []
    for mesh_a, mesh_b in meshes(quick):
        # The same directions and turns for every size; the largest leaves rng where the rows after
        # it have always started.
        rng = np.random.default_rng(seed)
        rows, gaps = mesh_pair(mesh_a, mesh_b, rng, count, repeats, log)
        sizes.append({"faces": [len(mesh_a[1]), len(mesh_b[1])], "rows": rows, "gaps": gaps})
    distances = hausdorff(mesh_a, mesh_b, rng, quick, log)
    batches = primitives(rng, quick, log)
    single = single_calls(rng, quick, log)
    meta = {"cpus": os.cpu_count(), "quick": quick, "seed": seed, "poses": count, "repeats": repeats,
            "load_average": list(os.getloadavg()), "proximity": proximity.__version__}  # fmt: skip
    return {"meta": meta, "meshes": sizes, "hausdorff": distances, "primitives": batches, "single": single}


def checks(raw):
    """The project's target: ``(missed, lines)``."""
    lines, missed = [], 0
    for row in raw["meshes"][-1]["gaps"] if raw.get("meshes") else []:  # the largest meshes
        if row["gap"] != 1e-2:
            continue
        ours = row["libraries"]["robust"]["time"]
        for key in ("fcl", "coal"):
            if key not in row["libraries"]:
                lines.append(f"skipped  mesh-mesh at 1e-2 against {key}: not measured")
                continue
            ratio = row["libraries"][key]["time"] / ours
            met = ratio >= 2.0
            missed += not met
            lines.append(f"{'met   ' if met else 'MISSED'}  mesh-mesh at 1e-2 against {key}: {ratio:.1f}x "
                         "(target at least 2x)")  # fmt: skip
    for row in raw["meshes"][-1]["gaps"] if raw.get("meshes") else []:
        if row["gap"] != 1e-2 or "robust_points" not in row["libraries"]:
            continue
        libraries = row["libraries"]
        points = libraries["robust_points"]["time"]
        ratio = points / libraries["robust"]["time"]
        missed += not ratio <= 1.2
        lines.append(f"{_verdict(ratio <= 1.2)}  mesh-mesh at 1e-2, closest_points against distance: "
                     f"{ratio:.2f}x (target at most 1.2x)")  # fmt: skip
        if "fcl_points" in libraries and "time" in libraries["fcl_points"]:
            ratio = libraries["fcl_points"]["time"] / points
            missed += not ratio >= 1.5
            lines.append(f"{_verdict(ratio >= 1.5)}  mesh-mesh at 1e-2, closest_points against python-fcl "
                         f"with nearest points: {ratio:.1f}x (target at least 1.5x)")  # fmt: skip
    for row in raw.get("primitives", []):
        peer = row["libraries"].get("coal", {})
        if "rate" not in peer:
            lines.append(f"skipped  {row['kind']} pairs against coal: not measured")
            continue
        for key, what in (("proximity", "distance"), ("proximity_points", "closest_points")):
            if key not in row:
                continue
            ratio = row[key] / peer["rate"]
            missed += not ratio >= 20.0
            lines.append(f"{_verdict(ratio >= 20.0)}  batched {row['kind']} pairs, {what}, against coal per "
                         f"call: {ratio:.0f}x (target at least 20x)")  # fmt: skip
        if "proximity_points" in row:
            ratio = row["proximity"] / row["proximity_points"]
            missed += not ratio <= 1.5
            lines.append(f"{_verdict(ratio <= 1.5)}  batched {row['kind']} pairs, closest_points against "
                         f"distance: {ratio:.2f}x the time (target at most 1.5x)")  # fmt: skip
    for row in raw.get("single", []):
        if row["kind"] not in ("capsule", "segment"):
            continue
        ours = row["seconds"]["closest_points"]
        met = ours <= 2e-6
        missed += not met
        lines.append(f"{_verdict(met)}  single {row['kind']} pair, closest_points: {ours * 1e6:.2f} us "
                     "(target at most 2 us)")  # fmt: skip
        if "fcl" in row["seconds"]:
            fcl = row["seconds"]["fcl"]
            missed += not ours <= fcl
            text = f"python-fcl with nearest points: {ours * 1e6:.2f} against {fcl * 1e6:.2f} us"
            lines.append(f"{_verdict(ours <= fcl)}  single {row['kind']} pair, closest_points against {text}")
    return missed, lines


def _verdict(met):
    return "met   " if met else "MISSED"


def _cell(result):
    """One library at one gap: time per query and the largest error, or how many answers are missing."""
    text = f"{result['time'] * 1e3:>14.3f} ms  "
    if result["error"] is None:
        return text + f"{'no answer':>12s}"
    text += f"err {result['error']:8.1e}"
    return text + (f" ({result['missing']} none)" if result["missing"] else "")


def mesh_report(size, meta, columns=4):
    """One pair of meshes as text: a block of the gaps per ``columns`` libraries."""
    faces, rows = size["faces"], size["rows"]
    lines = [f"icosphere of {faces[0]:,} faces against a torus of {faces[1]:,}, {meta['poses']} poses per "
             f"gap; median ms per query (least of {meta['repeats']}), largest error against the exact "
             "distance"]  # fmt: skip
    keys = [k for k in rows if "skipped" not in rows[k]]
    for first in range(0, len(keys), columns):
        block = keys[first : first + columns]
        labels = [rows[k]["label"] + ("*" if rows[k]["repeats"] == 1 else "") for k in block]
        lines.append(f"  {'gap':>8s}" + "".join(f"{label:>34s}" for label in labels))
        for row in size["gaps"]:
            cells = "".join(f"{_cell(row['libraries'][k]):>34s}" for k in block)
            lines.append(f"  {'overlap' if row['gap'] < 0 else format(row['gap'], 'g'):>8s}{cells}")
    if any(rows[k]["repeats"] == 1 for k in keys):
        lines.append("  *: one timed call per pose, which gives the answer")
    for row in rows.values():
        if "skipped" in row:
            lines.append(f"  {row['label']}: skipped ({row['skipped']})")
    return lines


def report(raw):
    """The run as text: time per query and largest error per size, gap and library."""
    meta = raw["meta"]
    lines = []
    for size in raw["meshes"]:
        lines += mesh_report(size, meta)
    if "hausdorff" in raw:
        lines += hausdorff_report(raw["hausdorff"])
    if "primitives" in raw:
        lines += primitives_report(raw["primitives"])
    if "single" in raw:
        lines += single_report(raw["single"])
    lines.append(f"load average during the run: {meta['load_average']}")
    return "\n".join(lines)


def hausdorff_report(distances):
    """The Hausdorff rows as text."""
    lines = ["Hausdorff distance, the torus moved 0.5 and turned: proximity (robust, rtol 1e-6) and "
             f"trimesh's estimate from {distances['samples']:,} samples per mesh"]  # fmt: skip
    for k, row in enumerate(distances["rows"]):
        text = (f"  pose {k}: proximity [{row['lower']:.10f}, {row['upper']:.10f}] in "
                f"{row['time'] * 1e3:8.1f} ms ({row['points']:,} points"
                f"{'' if row['converged'] else ', NOT converged'})")  # fmt: skip
        if "trimesh" in row:
            t = row["trimesh"]
            short = (row["lower"] - t["estimate"]) / row["lower"]
            text += f"; trimesh {t['estimate']:.10f} in {t['time'] * 1e3:8.1f} ms ({short:.1e} below lower)"
        lines.append(text)
    for name, why in distances["skipped"].items():
        lines.append(f"  {name}: skipped ({why})")
    return lines


def single_report(rows):
    """The warm single calls as text: microseconds per call."""
    lines = ["single calls, warm, one pair: proximity's closest_points and distance against "
             "python-fcl's and coal's distance with nearest points; microseconds per call"]  # fmt: skip
    for row in rows:
        cells = ", ".join(f"{name} {seconds * 1e6:.2f}" for name, seconds in row["seconds"].items())
        lines.append(f"  {row['kind']:>8s}: {cells}")
    return lines


def primitives_report(rows):
    """The batched primitive pairs as text: pairs per second, and the largest error."""
    lines = ["primitive pairs: proximity's batch (robust, all threads: distance, and closest_points) against "
             "one call per pair with nearest points (python-fcl, coal) and vectorised NumPy (distances); "
             "pairs per second (largest error)"]  # fmt: skip
    for row in rows:
        cells = [f"proximity {row['proximity']:,.0f} ({row['error']:.1e})"]
        if "proximity_points" in row:
            cells.append(f"closest_points {row['proximity_points']:,.0f}")
        for name, peer in row["libraries"].items():
            if "skipped" in peer:
                cells.append(f"{name} skipped")
            else:
                ratio = row["proximity"] / peer["rate"]
                cells.append(f"{name} {peer['rate']:,.0f} ({peer['error']:.1e}, {ratio:.0f}x)")
        lines.append(f"  {row['kind']:>8s} ({row['pairs']:,} pairs): " + ", ".join(cells))
    return lines


def main(argv=None):
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.pairs", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small meshes and fewer poses, a smoke run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="bench-results", help="directory for pairs.json")
    args = parser.parse_args(argv)
    measure_and_save(args, "pairs", run, report, checks)
    return 0


if __name__ == "__main__":
    sys.exit(main())
