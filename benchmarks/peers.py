"""The libraries people pick for point-to-mesh distance, behind one interface, for :mod:`benchmarks.meshes`.

Each peer builds its structure for a mesh once and answers a batch of
points with the unsigned distance and, where it has one, the signed
distance (converted to negative inside).  Each runs in a process of its own
(``python -m benchmarks.peers``, started by :mod:`benchmarks.meshes`), so
that the thread settings a library reads once at start-up (libigl's
``IGL_NUM_THREADS``, OpenMP's ``OMP_NUM_THREADS``) are set for it alone, and
so that libraries that bundle their own TBB or OpenMP never share a process.

==========  ==========================================================  =========  ===========================
peer        unsigned; signed                                            precision  threads
==========  ==========================================================  =========  ===========================
proximity   ``TriangleMesh.distance``; ``signed_distance``              float64    ``proximity.threads(n)``
open3d      ``RaycastingScene.compute_distance``;                       float32    ``nthreads=n``
            ``compute_signed_distance`` (a ray's crossings)
libigl      ``AABB.squared_distance``; ``igl.signed_distance``          float64    ``IGL_NUM_THREADS``
            (pseudonormal; builds its tree in every call)
warp        ``mesh_query_point_no_sign``;                               float32    one: Warp runs CPU kernels
            ``mesh_query_point_sign_normal``, in a kernel on the CPU               on one thread
fcpw        ``scene_3D.find_closest_points`` on a                       float32    the process held to n
            ``bvh_surface_area`` BVH; ``Interaction.signed_distance``              cores (its own threads,
            of each answer (the nearest face's normal), in a Python                one per core of the
            loop                                                                   machine, per call)
meshlib     ``findSignedDistances`` (absolute value for the unsigned);  float32    the process held to n
            the same (pseudonormal)                                                cores (TBB)
coal        ``coal.distance`` of an OBBRSS ``BVHModel`` and a           float64    one (a Python loop)
            ``Sphere(0)`` moved to each point; none
fcl         the same with python-fcl; none                              float64    one (a Python loop)
pcu         ``closest_points_on_mesh``; ``signed_distance_to_mesh``     float64    ``OMP_NUM_THREADS``
            (fast winding number); both build a tree in every call
trimesh     ``proximity.closest_point``; ``proximity.signed_distance``  float64    one
==========  ==========================================================  =========  ===========================

FCPW: the fastest closest-point set-up its wheel (1.2) offers.  The wheel is
built without Enoki (``FCPW_USE_ENOKI=OFF`` in its ``pyproject.toml``), so
``build(..., vectorize=True)`` gives the same binary BVH with leaves of 4
triangles as ``vectorize=False`` (the same statistics with
``print_stats=True``); its SIMD wide-node tree (``mbvh``) needs a build from
source.  The batch calls start ``std::thread::hardware_concurrency()``
threads each, whatever the affinity, so on one core those threads share it.
The unsigned query's answers come back as a list of ``Interaction``
objects; reading their distances in a Python loop (about 70 ns a point) is
left out of its time.  The signed distance is that loop calling each
answer's ``signed_distance`` (the sign of the offset along the nearest
face's normal), which is timed: it is where the sign is computed.
MeshLib: its Python API has no batch unsigned query that returns an array
(``PointsToMeshProjector.findProjections`` returns a list of objects that
takes longer to read than the query takes), so the unsigned distance is the
absolute value of the signed one, sign included in its time.  FCPW's
``scene_3D.contains`` would sign a batch, but its NumPy result is not
written back by the wheel's binding.

Memory: each child measures its build in its own process, with the mesh's
arrays already loaded and the library loaded and warmed on a small mesh:
*kept* is the growth of ``VmRSS`` over the build (after ``malloc_trim(0)``,
so that memory the C allocator keeps but no longer uses is not counted),
*peak* the growth of ``VmHWM``, reset through ``/proc/self/clear_refs``
just before.  The library's own copies of the mesh (float32 vertices, 32-bit
faces, half-edges) count as its memory; where a call builds the tree
(``rebuilds``), the build keeps nothing.

The child's command line: ``python -m benchmarks.peers NAME DATA.npz THREADS
OUT.npz``: ``DATA.npz`` holds ``vertices``, ``faces`` and one array of
points per set; the child writes the answers to ``OUT.npz`` and prints one
line of JSON: ``{"build": s, "sets": {set: {"unsigned": timing, "signed":
timing}}, "memory": {"faces", "before_kib", "kept_kib", "peak_kib"}}`` (``memory``
None where ``/proc`` cannot reset the peak) or ``{"skipped": reason}``.
"""

import ctypes
import ctypes.util
import gc
import json
import os
import re
import sys
import time
from pathlib import Path

import numpy as np


class Peer:
    """A library: ``build(vertices, faces)`` and the queries on what it built."""

    name = ""
    label = ""
    module = ""
    precision = "float64"
    #: "parameter" (set per call), "environment" (read at start-up), "affinity" (the
    #: child process held to that many cores) or "one".
    threads = "one"
    has_signed = True
    #: The queries ("unsigned", "signed") that build the library's tree in
    #: every call: timed on every point at once, as they would be used.
    rebuilds = ()

    def available(self):
        """None, or why the library cannot be used here."""
        try:
            __import__(self.module)
        except Exception as exc:  # an ImportError, or a library that fails as it loads
            return f"{self.module} does not import: {type(exc).__name__}: {exc}"
        return None

    def warm(self):
        """Load what the library compiles or loads on first use, before anything is timed."""

    def build(self, vertices, faces):
        raise NotImplementedError

    def distance(self, built, points, threads):
        raise NotImplementedError

    def answers(self, result):
        """The distances, from what :meth:`distance` returned (outside the time)."""
        return result

    def signed(self, built, points, threads):
        raise NotImplementedError


class Proximity(Peer):
    name = "proximity"
    label = "proximity (robust)"
    module = "proximity"
    threads = "parameter"

    def warm(self):
        import proximity
        from proximity.testing.meshes import icosphere

        mesh = proximity.TriangleMesh(*icosphere(1))
        mesh.distance(np.zeros((2, 3)))
        mesh.signed_distance(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0]]))

    def build(self, vertices, faces):
        import proximity

        return proximity.TriangleMesh(vertices, faces)

    def prepare_signed(self, built, points):
        """The pseudonormals, which the first signed query computes: timed apart."""
        built.signed_distance(points[:1])

    def distance(self, built, points, threads):
        import proximity

        with proximity.threads(threads):
            return np.asarray(built.distance(points))

    def signed(self, built, points, threads):
        import proximity

        with proximity.threads(threads):
            return np.asarray(built.signed_distance(points))


class Open3D(Peer):
    name = "open3d"
    label = "Open3D RaycastingScene"
    module = "open3d"
    precision = "float32"
    threads = "parameter"

    def build(self, vertices, faces):
        import open3d as o3d

        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(
            o3d.core.Tensor(vertices.astype(np.float32)), o3d.core.Tensor(faces.astype(np.uint32))
        )
        scene.compute_distance(o3d.core.Tensor(vertices[:1].astype(np.float32)))  # builds the tree
        return scene

    def distance(self, scene, points, threads):
        import open3d as o3d

        query = o3d.core.Tensor(points.astype(np.float32))
        return scene.compute_distance(query, nthreads=threads).numpy().astype(np.float64)

    def signed(self, scene, points, threads):
        import open3d as o3d

        query = o3d.core.Tensor(points.astype(np.float32))
        return scene.compute_signed_distance(query, nthreads=threads).numpy().astype(np.float64)


class Libigl(Peer):
    name = "libigl"
    label = "libigl AABB; signed_distance"
    module = "igl"
    threads = "environment"
    rebuilds = ("signed",)

    def build(self, vertices, faces):
        import igl

        tree = igl.AABB()
        tree.init(vertices, faces)
        return tree, vertices, faces

    def distance(self, built, points, threads):
        tree, vertices, faces = built
        sqr_distance, _, _ = tree.squared_distance(vertices, faces, points)
        return np.sqrt(sqr_distance)

    def signed(self, built, points, threads):
        import igl

        _, vertices, faces = built
        signed, _, _, _ = igl.signed_distance(
            points, vertices, faces, sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL
        )
        return signed


def _warp_kernels():
    import warp as wp

    @wp.kernel
    def unsigned(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
        i = wp.tid()
        q = wp.mesh_query_point_no_sign(mesh, points[i], 1.0e30)
        if q.result:
            out[i] = wp.length(points[i] - wp.mesh_eval_position(mesh, q.face, q.u, q.v))
        else:
            out[i] = wp.nan

    @wp.kernel
    def signed(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
        i = wp.tid()
        q = wp.mesh_query_point_sign_normal(mesh, points[i], 1.0e30)
        if q.result:
            out[i] = q.sign * wp.length(points[i] - wp.mesh_eval_position(mesh, q.face, q.u, q.v))
        else:
            out[i] = wp.nan

    return unsigned, signed


class Warp(Peer):
    name = "warp"
    label = "Warp (CPU)"
    module = "warp"
    precision = "float32"

    def warm(self):
        import warp as wp

        wp.config.quiet = True
        wp.init()
        self.kernels = _warp_kernels()
        built = self.build(np.eye(3), np.array([[0, 1, 2]]))
        self.distance(built, np.zeros((1, 3)), 1)
        self.signed(built, np.zeros((1, 3)), 1)

    def build(self, vertices, faces):
        import warp as wp

        return wp.Mesh(
            points=wp.array(vertices.astype(np.float32), dtype=wp.vec3, device="cpu"),
            indices=wp.array(faces.astype(np.int32).reshape(-1), dtype=wp.int32, device="cpu"),
        )

    def _run(self, kernel, mesh, points):
        import warp as wp

        query = wp.array(points.astype(np.float32), dtype=wp.vec3, device="cpu")
        out = wp.empty(len(points), dtype=float, device="cpu")
        wp.launch(kernel, dim=len(points), inputs=[mesh.id, query, out], device="cpu")
        wp.synchronize_device("cpu")
        return out.numpy().astype(np.float64)

    def distance(self, mesh, points, threads):
        return self._run(self.kernels[0], mesh, points)

    def signed(self, mesh, points, threads):
        return self._run(self.kernels[1], mesh, points)


def _grid(n=64):
    """A square of ``2 n**2`` triangles: a mesh big enough that a library warmed on it starts its
    thread pool, small enough to take no time."""
    x, y = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    corner = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    faces = np.concatenate([np.stack([corner, corner + n + 1, corner + 1], axis=1),
                            np.stack([corner + 1, corner + n + 1, corner + n + 2], axis=1)])  # fmt: skip
    return vertices, faces


class FCPW(Peer):
    name = "fcpw"
    label = "FCPW (wheel)"
    module = "fcpw"
    precision = "float32"
    threads = "affinity"

    def warm(self):
        built = self.build(*_grid())
        self.distance(built, np.ones((1000, 3)), 1)
        self.signed(built, np.ones((1000, 3)), 1)

    def build(self, vertices, faces):
        import fcpw

        scene = fcpw.scene_3D()
        scene.set_object_count(1)
        scene.set_object_vertices(np.asfortranarray(vertices, dtype=np.float32), 0)
        scene.set_object_triangles(np.asfortranarray(faces, dtype=np.int32), 0)
        # vectorize=True asks for the wide-node tree; the wheel, built without Enoki, builds the binary one.
        scene.build(fcpw.aggregate_type.bvh_surface_area, True)
        return scene

    def _closest(self, scene, points, record_normal):
        import fcpw

        query = np.asfortranarray(points, dtype=np.float32)
        found = fcpw.interaction_3D_list()
        radii = np.full(len(points), np.inf, dtype=np.float32)  # no bound on the search
        scene.find_closest_points(query, radii, found, record_normal)
        return query, found

    def distance(self, scene, points, threads):
        return self._closest(scene, points, False)[1]

    def answers(self, found):
        # A Python loop over the wheel's list of answers (about 70 ns a point): left out of the time.
        return np.array([hit.d for hit in found], dtype=np.float64)

    def signed(self, scene, points, threads):
        query, found = self._closest(scene, points, True)
        return np.array([hit.signed_distance(x) for hit, x in zip(found, query, strict=True)])


class MeshLib(Peer):
    name = "meshlib"
    label = "MeshLib findSignedDistances"
    module = "meshlib.mrmeshpy"
    precision = "float32"
    threads = "affinity"

    def warm(self):
        built = self.build(*_grid())
        self.signed(built, np.ones((1000, 3)), 1)

    def build(self, vertices, faces):
        from meshlib import mrmeshnumpy

        mesh = mrmeshnumpy.meshFromFacesVerts(
            np.ascontiguousarray(faces, dtype=np.int32), np.ascontiguousarray(vertices, dtype=np.float32)
        )
        mesh.getAABBTree()  # built on first use otherwise
        return mesh

    def distance(self, mesh, points, threads):
        return np.abs(self.signed(mesh, points, threads))

    def signed(self, mesh, points, threads):
        from meshlib import mrmeshnumpy, mrmeshpy

        query = np.ascontiguousarray(points, dtype=np.float32)
        query = mrmeshpy.VertCoords(mrmeshnumpy.fromNumpyArray(query))
        return np.array(mrmeshpy.findSignedDistances(mesh, query).vec, dtype=np.float64)


class Coal(Peer):
    name = "coal"
    label = "coal, per point"
    module = "coal"
    has_signed = False

    def build(self, vertices, faces):
        import coal

        model = coal.BVHModelOBBRSS()
        model.beginModel(len(faces), len(vertices))
        model.addVertices(np.ascontiguousarray(vertices))
        model.addTriangles(np.ascontiguousarray(faces, dtype=np.int64))
        model.endModel()
        return model

    def distance(self, model, points, threads):
        import coal

        probe, identity, moved = coal.Sphere(0.0), coal.Transform3s(), coal.Transform3s()
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        out = np.empty(len(points))
        for k, p in enumerate(points):
            moved.setTranslation(p)
            result.clear()
            out[k] = coal.distance(model, identity, probe, moved, request, result)
        return out


class FCL(Peer):
    name = "fcl"
    label = "python-fcl, per point"
    module = "fcl"
    has_signed = False

    def build(self, vertices, faces):
        import fcl

        model = fcl.BVHModel()
        model.beginModel(len(vertices), len(faces))
        model.addSubModel(np.ascontiguousarray(vertices), np.ascontiguousarray(faces))
        model.endModel()
        return fcl.CollisionObject(model, fcl.Transform())

    def distance(self, mesh, points, threads):
        import fcl

        probe = fcl.CollisionObject(fcl.Sphere(0.0), fcl.Transform())
        request = fcl.DistanceRequest()
        out = np.empty(len(points))
        for k, p in enumerate(points):
            probe.setTranslation(p)
            out[k] = fcl.distance(mesh, probe, request, fcl.DistanceResult())
        return out


class PointCloudUtils(Peer):
    name = "pcu"
    label = "point-cloud-utils"
    module = "point_cloud_utils"
    threads = "environment"
    rebuilds = ("unsigned", "signed")

    def build(self, vertices, faces):
        return vertices, faces  # every call builds its own tree

    def distance(self, built, points, threads):
        import point_cloud_utils as pcu

        distance, _, _ = pcu.closest_points_on_mesh(points, *built)
        return np.asarray(distance, dtype=np.float64)

    def signed(self, built, points, threads):
        import point_cloud_utils as pcu

        signed, _, _ = pcu.signed_distance_to_mesh(points, *built)
        return np.asarray(signed, dtype=np.float64)


class Trimesh(Peer):
    name = "trimesh"
    label = "trimesh.proximity"
    module = "trimesh"

    def available(self):
        for module in ("trimesh", "rtree", "scipy"):
            try:
                __import__(module)
            except ImportError as exc:
                return f"trimesh's mesh query needs {module}: {exc}"
        return None

    def build(self, vertices, faces):
        import trimesh

        mesh = trimesh.Trimesh(vertices, faces, process=False)
        trimesh.proximity.closest_point(mesh, vertices[:1])  # builds its r-tree
        return mesh

    def distance(self, mesh, points, threads):
        import trimesh

        return trimesh.proximity.closest_point(mesh, points)[1]

    def signed(self, mesh, points, threads):
        import trimesh

        return -trimesh.proximity.signed_distance(mesh, points)  # trimesh's is positive inside


PEERS = {
    peer.name: peer
    for peer in (
        Proximity(),
        Open3D(),
        Libigl(),
        Warp(),
        FCPW(),
        MeshLib(),
        Coal(),
        FCL(),
        PointCloudUtils(),
        Trimesh(),
    )  # fmt: skip
}


# -- memory (Linux: /proc/self) ------------------------------------------------------------


def _status_kib(field):
    text = Path("/proc/self/status").read_text()
    return int(re.search(rf"{field}:\s+(\d+)", text).group(1))


def rss_kib():
    """The process's resident set now (``VmRSS``), KiB."""
    return _status_kib("VmRSS")


def peak_kib():
    """The largest resident set since the start or the last :func:`reset_peak` (``VmHWM``), KiB."""
    return _status_kib("VmHWM")


def reset_peak():
    """Set ``VmHWM`` to the resident set now."""
    Path("/proc/self/clear_refs").write_text("5")


def can_reset_peak():
    return Path("/proc/self/clear_refs").exists()


def _release_free_heap():
    """Return the C heap's free pages to the system (glibc's ``malloc_trim``; elsewhere nothing), so
    that ``VmRSS`` counts what is in use, not what the allocator keeps for later."""
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name)
    except OSError:
        return
    if hasattr(libc, "malloc_trim"):
        libc.malloc_trim(0)


def measure_build(build):
    """``(built, seconds, memory)`` of ``build()``: the growth of ``VmRSS`` over it (kept) and of
    ``VmHWM`` (peak), in KiB; ``memory`` is None where ``/proc`` cannot reset the peak."""
    measured = can_reset_peak()
    if measured:
        gc.collect()
        _release_free_heap()
        reset_peak()
        before = rss_kib()
    start = time.perf_counter()
    built = build()
    seconds = time.perf_counter() - start
    if not measured:
        return built, seconds, None
    peak = peak_kib()
    gc.collect()
    _release_free_heap()
    memory = {"before_kib": before, "kept_kib": rss_kib() - before, "peak_kib": peak - before}
    return built, seconds, memory


# -- the child process ----------------------------------------------------------------------


def measure(call, points, target=1.0, repeats=3, whole=False, finish=None):
    """Time ``call`` on a prefix of ``points`` that takes about ``target`` seconds (all of them if faster).

    The prefix grows from 200 points until one call takes ``target``
    seconds or covers every point; the last size is then timed up to
    ``repeats`` times in all, while the calls add up to ``3 target``.
    ``whole``: every point from the start.  Returns ``(timing, answers)``
    with ``timing = {"n", "seconds", "qps"}`` (the median); ``finish``, if
    given, turns the last call's result into the answers, untimed.
    """
    n = len(points) if whole else min(len(points), 200)
    while True:
        start = time.perf_counter()
        answers = call(points[:n])
        seconds = time.perf_counter() - start
        if n == len(points) or seconds >= target:
            break
        n = min(len(points), max(2 * n, int(1.5 * n * target / max(seconds, 1e-4))))
    times = [seconds]
    while len(times) < repeats and sum(times) < 3 * target:
        start = time.perf_counter()
        call(points[:n])
        times.append(time.perf_counter() - start)
    median = float(np.median(times))
    return {"n": int(n), "seconds": times, "qps": n / median}, answers if finish is None else finish(answers)


def child(name, data_path, threads, out_path):
    """Build the mesh with peer ``name``, time its queries on every point set, save the answers."""
    peer = PEERS[name]
    if peer.threads == "affinity":
        if not hasattr(os, "sched_setaffinity"):
            return {"skipped": f"{peer.label}'s threads follow the cores the process may use: no "
                    "os.sched_setaffinity here to set them"}  # fmt: skip
        # Before the library loads: TBB sizes its pool from the affinity it finds then.
        os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:threads])
    reason = peer.available()
    if reason is not None:
        return {"skipped": reason}
    data = np.load(data_path)
    vertices, faces = data["vertices"], data["faces"]
    sets = [key for key in data.files if key not in ("vertices", "faces")]
    peer.warm()
    built, seconds, memory = measure_build(lambda: peer.build(vertices, faces))
    if memory is not None:
        memory["faces"] = int(len(faces))
    record = {"build": seconds, "memory": memory, "sets": {}}
    if peer.has_signed and hasattr(peer, "prepare_signed"):
        start = time.perf_counter()
        peer.prepare_signed(built, data[sets[0]])
        record["prepare_signed"] = time.perf_counter() - start
    answers = {}
    for label in sets:
        points = data[label]
        timing, answers[f"{label}.unsigned"] = measure(
            lambda p: peer.distance(built, p, threads),
            points,
            whole="unsigned" in peer.rebuilds,
            finish=peer.answers,
        )
        record["sets"][label] = {"unsigned": timing}
        if peer.has_signed:
            timing, answers[f"{label}.signed"] = measure(
                lambda p: peer.signed(built, p, threads), points, whole="signed" in peer.rebuilds
            )
            record["sets"][label]["signed"] = timing
    np.savez(out_path, **answers)
    return record


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 4:
        print(__doc__.split("\n\n")[-1], file=sys.stderr)
        return 2
    name, data_path, threads, out_path = argv
    print(json.dumps(child(name, data_path, int(threads), out_path)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
