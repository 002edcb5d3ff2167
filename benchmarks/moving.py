"""Moving objects: frames of posed instances, and refits, against rebuilding and against the peers.

    python -m benchmarks.moving [--quick] [--out DIR] [--seed 0] [--write docs/performance.md]

**The moving scene.**  50 posed copies of one icosphere of 5,120 faces
(radius 1), scattered in a cube of side 12 with random rotations; each
frame moves and turns every copy a little and asks for the closest point
of 10,000 new points uniform in the scene's bounding box (``--quick``: the
same sizes, 2 frames instead of 5).  Each library's frame is split into
the *pose update* (whatever it needs before its queries) and the
*queries*; the table gives the median over the frames.

* proximity, instanced: ``scene.with_poses(poses)`` then
  ``scene.closest_point(points)`` (``robust``), on all threads and on one;
* proximity, rebuilt: 50 ``TriangleMesh`` built from the posed vertices
  and a ``Scene`` of them, every frame;
* python-fcl and coal: a ``CollisionObject`` per copy over one shared
  ``BVHModel`` in a ``DynamicAABBTreeCollisionManager``, moved with
  ``setTransform`` (and coal's ``computeAABB``) and ``update()``; then a
  ``Sphere(0)`` object moved to each point and ``manager.distance`` in a
  Python loop, on the first 2,000 points of each frame (scaled to the
  frame's 10,000);
* Warp on the CPU: one merged mesh of the 50 copies (float32), its
  vertices posed by a Warp kernel and ``Mesh.refit()``, then
  ``mesh_query_point_no_sign`` for every point.

Accuracy: the first 200 points of the first frame (``--quick``: 50) against
the exact distance (rational arithmetic) to the copies' vertices posed in
float64, as the largest error relative to the scene's size (the diagonal
of its bounding box).  Proximity's instanced answers are also compared
with its rebuilt ones on every point of every frame.

**Refit.**  An icosphere of 20,480 and one of 1,310,720 faces (``--quick``:
1,280 and 20,480), their vertices moved by a smooth wobble of 5% of the
radius: the ``TriangleMesh`` constructor against ``mesh.with_vertices``
(whose answers on 10,000 points are compared bit for bit with the fresh
build's), and Warp's ``Mesh`` constructor against its ``refit()``.  Then
what a refit loses: the query time of 100,000 points in the bounding box on
the refitted tree against a fresh build, for the wobble and for a twist of
the sphere by half a turn from pole to pole.

**A distance cutoff.**  The icosphere of 20,480 faces and 100,000 points
uniform in a cube of side 8 around it (``--quick``: 10,000), most of them
far: ``mesh.distance(points)`` against ``mesh.distance(points,
max_distance=0.02)`` (1% of the sphere's diameter), the least of 5 calls
each, alternating; the rows within the cutoff are compared bit for bit and
the rows beyond must be ``inf``.

The project's targets are checked apart (``OUT/checks-moving.txt``);
``OUT/moving.json`` holds the raw data.  ``--write`` rewrites the
``moving-bench`` section of the page.
"""

import argparse
import os
import sys
import time

import numpy as np

import proximity
from benchmarks.meshes import write_section
from benchmarks.saving import measure_and_save
from proximity.numerics.rigid import to_world
from proximity.testing.meshes import icosphere, peer_mesh, reference

INSTANCES = 50
SUBDIVISIONS = 4  # 5,120 faces
POINTS = 10_000
PEER_POINTS = 2_000
SIDE = 12.0


def random_rotations(rng, n):
    """``n`` rotation matrices, uniform (from unit quaternions)."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def small_rotations(rng, n, angle):
    """``n`` rotations by ``angle`` radians about random axes (Rodrigues)."""
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    k = np.zeros((n, 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    k -= k.transpose(0, 2, 1)
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def frames(rng, n_frames):
    """Poses ``(n_frames, INSTANCES, 4, 4)`` of copies drifting and turning, and the frames' points."""
    rotation = random_rotations(rng, INSTANCES)
    translation = rng.uniform(0.0, SIDE, (INSTANCES, 3))
    velocity = rng.normal(0.0, 0.05, (INSTANCES, 3))
    poses, points = [], []
    for _ in range(n_frames):
        pose = np.tile(np.eye(4), (INSTANCES, 1, 1))
        pose[:, :3, :3], pose[:, :3, 3] = rotation, translation
        poses.append(pose)
        points.append(rng.uniform(-1.0, SIDE + 1.0, (POINTS, 3)))
        rotation = small_rotations(rng, INSTANCES, 0.02) @ rotation
        translation = translation + velocity
    return np.array(poses), np.array(points)


def posed_vertices(vertices, poses):
    """The copies' vertices, ``(INSTANCES, V, 3)``, posed in float64 (in the order proximity sums)."""
    return np.stack([to_world(vertices, pose[:3, :3], pose[:3, 3]) for pose in poses])


def _split(update, query):
    return {"update": update, "query": query, "frame": update + query}


# -- the libraries' frames ---------------------------------------------------------------------
def proximity_instanced(vertices, faces, poses, points, threads=None):
    mesh = proximity.TriangleMesh(vertices, faces)
    scene = proximity.Scene([mesh.transformed(pose) for pose in poses[0]])
    scene.closest_point(points[0][:100])  # compiles before the clock starts
    times, answers = [], []
    with proximity.threads(threads):
        for pose, frame_points in zip(poses, points, strict=True):
            start = time.perf_counter()
            scene = scene.with_poses(pose)
            posed = time.perf_counter()
            result = scene.closest_point(frame_points)
            times.append(_split(posed - start, time.perf_counter() - posed))
            answers.append(np.asarray(result.distance))
    return times, answers


def proximity_rebuilt(vertices, faces, poses, points):
    times, answers = [], []
    for pose, frame_points in zip(poses, points, strict=True):
        start = time.perf_counter()
        scene = proximity.Scene([proximity.TriangleMesh(v, faces) for v in posed_vertices(vertices, pose)])
        built = time.perf_counter()
        result = scene.closest_point(frame_points)
        times.append(_split(built - start, time.perf_counter() - built))
        answers.append(np.asarray(result.distance))
    return times, answers


def fcl_frames(vertices, faces, poses, points):
    import fcl

    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(vertices, faces)
    model.endModel()
    objects = [fcl.CollisionObject(model, fcl.Transform()) for _ in range(INSTANCES)]
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(objects)
    manager.setup()
    probe = fcl.CollisionObject(fcl.Sphere(0.0), fcl.Transform())
    times, answers = [], []
    for pose, frame_points in zip(poses, points, strict=True):
        start = time.perf_counter()
        for obj, p in zip(objects, pose, strict=True):
            obj.setTransform(fcl.Transform(p[:3, :3], p[:3, 3]))
        manager.update()
        posed = time.perf_counter()
        out = np.empty(PEER_POINTS)
        for k, p in enumerate(frame_points[:PEER_POINTS]):
            probe.setTranslation(p)
            data = fcl.DistanceData(fcl.DistanceRequest(), fcl.DistanceResult())
            manager.distance(probe, data, fcl.defaultDistanceCallback)
            out[k] = data.result.min_distance
        query = (time.perf_counter() - posed) * POINTS / PEER_POINTS
        times.append(_split(posed - start, query))
        answers.append(out)
    return times, answers


def coal_frames(vertices, faces, poses, points):
    import coal

    model = coal.BVHModelOBBRSS()
    model.beginModel(len(faces), len(vertices))
    model.addVertices(vertices)
    model.addTriangles(faces.astype(np.int64))
    model.endModel()
    objects = [coal.CollisionObject(model, coal.Transform3s()) for _ in range(INSTANCES)]
    manager = coal.DynamicAABBTreeCollisionManager()
    for obj in objects:
        manager.registerObject(obj)
    manager.setup()
    probe = coal.CollisionObject(coal.Sphere(0.0), coal.Transform3s())
    times, answers = [], []
    for pose, frame_points in zip(poses, points, strict=True):
        start = time.perf_counter()
        for obj, p in zip(objects, pose, strict=True):
            obj.setTransform(coal.Transform3s(p[:3, :3], p[:3, 3]))
            obj.computeAABB()
        manager.update()
        posed = time.perf_counter()
        out = np.empty(PEER_POINTS)
        for k, p in enumerate(frame_points[:PEER_POINTS]):
            probe.setTranslation(p)
            probe.computeAABB()  # the manager prunes with the probe's box, not its transform
            callback = coal.DistanceCallBackDefault()
            manager.distance(probe, callback)
            out[k] = callback.data.result.min_distance
        query = (time.perf_counter() - posed) * POINTS / PEER_POINTS
        times.append(_split(posed - start, query))
        answers.append(out)
    return times, answers


def _warp_kernels():
    import warp as wp

    @wp.kernel
    def pose(
        local: wp.array(dtype=wp.vec3), transforms: wp.array(dtype=wp.mat44), out: wp.array(dtype=wp.vec3)
    ):
        i = wp.tid()
        n = local.shape[0]
        out[i] = wp.transform_point(transforms[i // n], local[i % n])

    @wp.kernel
    def query(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
        i = wp.tid()
        q = wp.mesh_query_point_no_sign(mesh, points[i], 1.0e30)
        if q.result:
            out[i] = wp.length(points[i] - wp.mesh_eval_position(mesh, q.face, q.u, q.v))
        else:
            out[i] = wp.nan

    return pose, query


def warp_frames(vertices, faces, poses, points):
    import warp as wp

    wp.config.quiet = True
    wp.init()
    pose_kernel, query_kernel = _warp_kernels()
    device = "cpu"
    local = wp.array(vertices.astype(np.float32), dtype=wp.vec3, device=device)
    merged = (faces[None] + len(vertices) * np.arange(INSTANCES)[:, None, None]).reshape(-1)
    world = posed_vertices(vertices, poses[0]).reshape(-1, 3).astype(np.float32)
    mesh = wp.Mesh(
        points=wp.array(world, dtype=wp.vec3, device=device),
        indices=wp.array(merged.astype(np.int32), dtype=wp.int32, device=device),
    )
    out = wp.empty(POINTS, dtype=float, device=device)

    def frame(pose, frame_points):
        start = time.perf_counter()
        transforms = wp.array(pose.astype(np.float32), dtype=wp.mat44, device=device)
        wp.launch(pose_kernel, dim=len(world), inputs=[local, transforms, mesh.points], device=device)
        mesh.refit()
        wp.synchronize_device(device)
        posed = time.perf_counter()
        query = wp.array(frame_points.astype(np.float32), dtype=wp.vec3, device=device)
        wp.launch(query_kernel, dim=POINTS, inputs=[mesh.id, query, out], device=device)
        wp.synchronize_device(device)
        answer = out.numpy().astype(np.float64)
        return _split(posed - start, time.perf_counter() - posed), answer

    frame(poses[0], points[0])  # compiles the kernels
    times, answers = [], []
    for pose, frame_points in zip(poses, points, strict=True):
        t, answer = frame(pose, frame_points)
        times.append(t)
        answers.append(answer)
    return times, answers


PEERS = (("fcl", "python-fcl, per point", fcl_frames), ("coal", "coal, per point", coal_frames),
         ("warp", "Warp (CPU), merged mesh refit", warp_frames))  # fmt: skip


def _installed(module):
    try:
        __import__(module)
    except Exception as exc:  # noqa: BLE001 (an installed peer may fail to import in many ways)
        return f"{type(exc).__name__}: {exc}"
    return None


def moving_scene(quick, seed, log):
    rng = np.random.default_rng(seed)
    vertices, faces = icosphere(SUBDIVISIONS)
    poses, points = frames(rng, 2 if quick else 5)
    world = posed_vertices(vertices, poses[0])
    size = float(np.linalg.norm(np.ptp(np.concatenate([world.reshape(-1, 3), points[0]]), axis=0)))
    n_exact = 50 if quick else 200
    log(f"moving scene: exact distances of {n_exact} points to {INSTANCES * len(faces):,} faces")
    merged = (faces[None] + len(vertices) * np.arange(INSTANCES)[:, None, None]).reshape(-1, 3)
    exact = np.array([float(d) for d, _ in reference(world.reshape(-1, 3), merged, points[0][:n_exact])])

    rows = {}
    args = (vertices, faces, poses, points)
    runs = [
        ("instanced", "proximity, instanced, all threads", lambda: proximity_instanced(*args)),
        ("instanced[1]", "proximity, instanced, 1 thread", lambda: proximity_instanced(*args, threads=1)),
        ("rebuilt", "proximity, meshes rebuilt every frame", lambda: proximity_rebuilt(*args)),
    ]
    for name, label, call in PEERS:
        missing = _installed(name)
        if missing:
            rows[name] = {"label": label, "skipped": missing}
            continue
        runs.append((name, label, lambda call=call: call(*args)))
    answers = {}
    for name, label, call in runs:
        log(f"moving scene: {label}")
        times, answers[name] = call()
        error = np.abs(answers[name][0][:n_exact] - exact)
        rows[name] = {
            "label": label,
            "update": float(np.median([t["update"] for t in times])),
            "query": float(np.median([t["query"] for t in times])),
            "frame": float(np.median([t["frame"] for t in times])),
            "frames": times,
            "error": float(np.max(error) / size),
        }
    same = max(
        float(np.max(np.abs(a - b))) for a, b in zip(answers["instanced"], answers["rebuilt"], strict=True)
    )
    return {
        "instances": INSTANCES,
        "faces": int(len(faces)),
        "points": POINTS,
        "peer_points": PEER_POINTS,
        "frames": len(poses),
        "accuracy_points": n_exact,
        "size": size,
        "instanced_vs_rebuilt": same / size,
        "rows": rows,
    }


# -- refit -------------------------------------------------------------------------------------
def wobble(vertices):
    """A smooth deformation of 5% of the radius."""
    x, y, z = vertices.T
    return vertices * (1.0 + 0.05 * np.sin(3 * x) * np.cos(2 * y + z))[:, None]


def twist(vertices):
    """Half a turn about z from pole to pole."""
    x, y, z = vertices.T
    angle = np.pi / 2 * z / np.max(np.abs(z))
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * x - s * y, s * x + c * y, z], axis=1)


def _least(call, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def _warp_refit(vertices, faces, moved, repeats):
    import warp as wp

    wp.config.quiet = True
    wp.init()
    device = "cpu"
    indices = wp.array(faces.astype(np.int32).reshape(-1), dtype=wp.int32, device=device)
    points = wp.array(vertices.astype(np.float32), dtype=wp.vec3, device=device)
    start = time.perf_counter()
    mesh = wp.Mesh(points=points, indices=indices)
    wp.synchronize_device(device)
    build = time.perf_counter() - start
    new = moved.astype(np.float32)

    def refit():
        mesh.points.assign(new)
        mesh.refit()
        wp.synchronize_device(device)

    return build, _least(refit, repeats)


def refit_row(vertices, faces, rng):
    """One mesh's refit: build against ``with_vertices``, Warp's too, and the queries after."""
    moved = wobble(vertices)
    repeats = 2 if len(faces) > 100_000 else 5
    mesh = proximity.TriangleMesh(vertices, faces)
    mesh.with_vertices(moved)  # compiles the refit before the clock starts
    pose = np.eye(4)
    pose[:3, 3] = 1.0
    probe = rng.uniform(-1.1, 1.1, (10_000, 3))
    a = mesh.with_vertices(moved).closest_point(probe)
    b = proximity.TriangleMesh(moved, faces).closest_point(probe)
    keys = ("distance", "point", "face")
    row = {
        "faces": int(len(faces)),
        "build": _least(lambda: proximity.TriangleMesh(moved, faces), repeats),
        "refit": _least(lambda: mesh.with_vertices(moved), repeats),
        "posing": _least(lambda: mesh.transformed(pose), 5),
        "identical": all(np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True) for k in keys),
    }
    if _installed("warp") is None:
        row["warp_build"], row["warp_refit"] = _warp_refit(vertices, faces, moved, repeats)
    box = rng.uniform(-1.2, 1.2, (100_000, 3))
    row["query_after_refit"] = {}
    for name, deform in (("wobble", wobble), ("twist", twist)):
        new = deform(vertices)
        refitted, fresh = mesh.with_vertices(new), proximity.TriangleMesh(new, faces)
        refitted.distance(box[:100])
        slower = _least(lambda m=refitted: m.distance(box), 3) / _least(lambda m=fresh: m.distance(box), 3)
        row["query_after_refit"][name] = slower
    return row


def refit_rows(quick, seed, log):
    """The refit table's rows: icospheres of 20,480 and 1,310,720 faces (quick: 1,280 and 20,480)."""
    rng = np.random.default_rng(seed)
    rows = []
    for subdivisions in (3, 5) if quick else (5, 8):
        vertices, faces = peer_mesh("icosphere", subdivisions)
        log(f"refit: {len(faces):,} faces")
        rows.append(refit_row(vertices, faces, rng))
    return rows


def cutoff_row(quick, seed, log):
    """A small cutoff against none, on far points: the times and the check of the rows."""
    log("cutoff: 20,480 faces")
    rng = np.random.default_rng(seed)
    vertices, faces = peer_mesh("icosphere", 5)
    mesh = proximity.TriangleMesh(vertices, faces)
    points = rng.uniform(-4.0, 4.0, (10_000 if quick else 100_000, 3))
    limit = 0.02
    full, cut = mesh.distance(points), mesh.distance(points, max_distance=limit)
    within = full <= limit
    same = bool(np.array_equal(cut[within], full[within]) and np.all(np.isinf(cut[~within])))
    times = {"none": [], "cutoff": []}
    for _ in range(5):
        for key, call in (("none", lambda: mesh.distance(points)),
                          ("cutoff", lambda: mesh.distance(points, max_distance=limit))):  # fmt: skip
            start = time.perf_counter()
            call()
            times[key].append(time.perf_counter() - start)
    return {"faces": int(len(faces)), "points": len(points), "within": int(within.sum()), "limit": limit,
            "none": min(times["none"]), "cutoff": min(times["cutoff"]), "identical": same}  # fmt: skip


# -- output ------------------------------------------------------------------------------------
def _ms(seconds):
    return f"{seconds * 1e3:,.1f}"


def checks(raw):
    """The project's targets: ``(missed, lines)``."""
    rows = raw["scene"]["rows"]
    frame = rows["instanced"]["frame"]
    wanted = [("rebuilt", 10.0, "rebuilding the meshes"), ("warp", 5.0, "Warp's CPU frame"),
              ("coal", 20.0, "coal's frame")]  # fmt: skip
    lines, missed = [], 0
    for key, target, label in wanted:
        if "frame" not in rows.get(key, {}):
            lines.append(f"skipped  frame against {label}: not measured")
            continue
        ratio = rows[key]["frame"] / frame
        met = ratio >= target
        missed += not met
        lines.append(
            f"{'met   ' if met else 'MISSED'}  frame against {label}: {ratio:.1f}x "
            f"(target at least {target:g}x)"
        )
    for row in raw["refit"]:
        ratio = row["build"] / row["refit"]
        if row["faces"] > 1_000_000:
            met = ratio >= 5.0
            missed += not met
            lines.append(f"{'met   ' if met else 'MISSED'}  refit against build, {row['faces']:,} faces: "
                         f"{ratio:.1f}x (target at least 5x)")  # fmt: skip
            met = row["posing"] < 0.01 * row["build"]
            missed += not met
            lines.append(f"{'met   ' if met else 'MISSED'}  posing {row['faces']:,} faces: "
                         f"{row['posing'] / row['build']:.2%} of a build (target under 1%)")  # fmt: skip
        missed += not row["identical"]
        verdict = "met   " if row["identical"] else "MISSED"
        lines.append(f"{verdict}  refit answers bit for bit a fresh build's, "
                     f"{row['faces']:,} faces")  # fmt: skip
    cut = raw["cutoff"]
    ratio = cut["none"] / cut["cutoff"]
    for met, line in ((ratio >= 3.0, f"cutoff on far points: {ratio:.1f}x faster (target at least 3x)"),
                      (cut["identical"], "cutoff rows within the same bits, rows beyond inf")):  # fmt: skip
        missed += not met
        lines.append(f"{'met   ' if met else 'MISSED'}  {line}")
    return missed, lines


def report(raw):
    """The run as text: the frame table and the refit table."""
    scene = raw["scene"]
    lines = [
        f"moving scene: {scene['instances']} copies of {scene['faces']:,} faces, {scene['points']:,} points "
        f"per frame, median of {scene['frames']} frames (ms)",
        f"  {'':40s} {'update':>9s} {'queries':>9s} {'frame':>9s}  largest error / size",
    ]
    for row in scene["rows"].values():
        if "skipped" in row:
            lines.append(f"  {row['label']:40s} skipped: {row['skipped']}")
            continue
        lines.append(f"  {row['label']:40s} {_ms(row['update']):>9s} {_ms(row['query']):>9s} "
                     f"{_ms(row['frame']):>9s}  {row['error']:.2g}")  # fmt: skip
    lines.append(
        "  instanced against rebuilt, every point: largest difference / size "
        f"{scene['instanced_vs_rebuilt']:.2g}"
    )
    lines.append("refit (ms, least of the repeats)")
    for row in raw["refit"]:
        warp = ""
        if "warp_refit" in row:
            warp = f"; Warp build {_ms(row['warp_build'])}, refit {_ms(row['warp_refit'])}"
        loss = row["query_after_refit"]
        lines.append(
            f"  {row['faces']:>9,} faces: build {_ms(row['build'])}, with_vertices {_ms(row['refit'])} "
            f"({row['build'] / row['refit']:.1f}x), bit-identical {row['identical']}, transformed "
            f"{row['posing'] * 1e6:.1f} us{warp}; query time refitted / fresh: wobble "
            f"{loss['wobble']:.2f}, twist {loss['twist']:.2f}"
        )
    cut = raw["cutoff"]
    lines.append(
        f"cutoff: {cut['points']:,} points in a cube of side 8 around {cut['faces']:,} faces, "
        f"{cut['within']:,} within {cut['limit']:g}: distance {_ms(cut['none'])} ms, with max_distance "
        f"{_ms(cut['cutoff'])} ms ({cut['none'] / cut['cutoff']:.1f}x); rows the same: {cut['identical']}"
    )
    lines.append(f"load average during the run: {raw['meta']['load_average']}")
    return "\n".join(lines)


def markdown(raw, path="docs/performance.md"):
    """The two tables for the page at ``path``."""
    scene, meta = raw["scene"], raw["meta"]
    load = ", ".join(f"{x:.1f}" for x in meta["load_average"])
    lines = [
        f"{scene['instances']} posed copies of an icosphere of {scene['faces']:,} faces, {scene['points']:,} "
        f"new points per frame uniform in the scene's box; milliseconds, median of {scene['frames']} frames. "
        f"fcl and coal loop over {scene['peer_points']:,} points per frame, scaled to {scene['points']:,}. "
        f"Largest error over {scene['accuracy_points']} points against the exact distance, relative to the "
        f"scene's size. Made by `python -m benchmarks.moving --write {path}` on {meta['cpus']} cores shared "
        f"with other jobs (load average {load}).",
        "",
        "| | pose update | queries | frame | largest error / size |",
        "|---|---:|---:|---:|---:|",
    ]
    for row in scene["rows"].values():
        if "skipped" in row:
            lines.append(f"| {row['label']} | skipped | | | |")
            continue
        lines.append(f"| {row['label']} | {_ms(row['update'])} | {_ms(row['query'])} | {_ms(row['frame'])} "
                     f"| {row['error']:.2g} |")  # fmt: skip
    lines += [
        "",
        "Refit of an icosphere whose vertices move by a wobble of 5% of the radius (milliseconds, least of "
        "the repeats); query time of 100,000 points in the box on the refitted tree over a fresh build's, "
        "for the wobble and for a twist of half a turn:",
        "",
        "| faces | build | `with_vertices` | `transformed` | Warp build | Warp refit "
        "| queries after a wobble "
        "| after a twist |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in raw["refit"]:
        warp = [_ms(row[k]) if k in row else "" for k in ("warp_build", "warp_refit")]
        loss = row["query_after_refit"]
        lines.append(
            f"| {row['faces']:,} | {_ms(row['build'])} | {_ms(row['refit'])} | {row['posing'] * 1e6:.0f} us "
            f"| {warp[0]} | {warp[1]} | {loss['wobble']:.2f}x | {loss['twist']:.2f}x |"
        )
    cut = raw["cutoff"]
    lines += [
        "",
        f"A distance cutoff: {cut['points']:,} points uniform in a cube of side 8 around the icosphere"
        f" of {cut['faces']:,} faces (radius 1), {cut['within']:,} of them within the cutoff of "
        f"{cut['limit']:g}; "
        f"`distance` took {_ms(cut['none'])} ms, `distance(max_distance={cut['limit']:g})` "
        f"{_ms(cut['cutoff'])} ms ({cut['none'] / cut['cutoff']:.1f}x faster; least of 5 calls each), with "
        f"the rows within the same bit for bit and the rows beyond `inf`: {cut['identical']}.",
    ]
    return "\n".join(lines)


def run(quick=False, seed=0, log=print):
    """Both parts; the raw data."""
    meta = {"cpus": os.cpu_count(), "quick": quick, "seed": seed, "numpy": np.__version__,
            "proximity": proximity.__version__}  # fmt: skip
    scene = moving_scene(quick, seed, log)
    refit = refit_rows(quick, seed, log)
    cutoff = cutoff_row(quick, seed, log)
    meta["load_average"] = list(os.getloadavg())
    return {"meta": meta, "scene": scene, "refit": refit, "cutoff": cutoff}


def main(argv=None):
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.moving", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer frames and smaller refits, a smoke run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="bench-results", help="directory for moving.json")
    parser.add_argument("--write", metavar="PATH", help="rewrite the moving-bench section of this page")
    args = parser.parse_args(argv)
    raw = measure_and_save(args, "moving", run, report, checks)
    if args.write:
        write_section(args.write, markdown(raw, args.write), marker="moving-bench")
    return 0


if __name__ == "__main__":
    sys.exit(main())
