"""Meshes: proximity against trimesh and fcl, BVH build time and memory; and against every peer.

    python -m benchmarks.meshes [--quick] [--out DIR] [--seed 0] [--write docs/performance.md]
                                [--no-peers | --peers-only] [--peer NAME ...]
    python -m benchmarks.meshes --crossover      # brute force against the BVH, n = 4..256

The run has two parts; ``--write`` rewrites the section of each part that
ran (markers ``mesh-bench`` and ``mesh-peers``).

**The torus** (about a minute) builds a torus of 20,000 triangles and two
seeded sets of 100,000 points: *near* (on the surface, moved along the
face normal by a normal deviate of 1% of the torus' size) and *box*
(uniform in the mesh's bounding box).  It measures:

* proximity (``TriangleMesh``, BVH, ``robust``): ``closest_point`` on all
  100,000 points, median of 5 calls after a warm-up call;
* ``trimesh.proximity.closest_point``, once, on the first 5,000 points of
  each set (it is slow), as points per second;
* fcl: a ``BVHModel`` of the mesh built once and a ``Sphere(0)`` moved to
  each point, ``fcl.distance`` in a Python loop over the first 2,000 points,
  as points per second;
* the ratios of throughputs (the project's own targets for them, 50x
  trimesh and 10x fcl, are checked apart: ``OUT/checks-meshes.txt``);
* the time to build the BVH of 1,000,000 triangles (a torus), as the
  ``TriangleMesh`` constructor;
* peak memory (``VmHWM`` after resetting it through ``/proc/self/clear_refs``,
  in a fresh subprocess) of the 100,000-point query, of the 1M-triangle
  build, and of trimesh's query on 5,000 points;
* accuracy of every method and of the backends on the first 200 points
  of each set, against the exact reference (rational arithmetic on every
  face that can be nearest), in the units of :mod:`benchmarks.suite`.

``OUT/meshes.json`` holds the raw data: ``meta``, ``speed`` (per entity and
point set: ``n``, ``seconds``, ``qps``), ``ratios``, ``build``, ``memory``,
and ``families``: records in the format of :mod:`benchmarks.suite` (kind
``"mesh"``) with ``d_exact``, ``scale`` and per-entity ``error_eps_s``,
``error_ulps`` and ``timing``, for the accuracy-against-speed chart.

**The peers** (``run_peers``; about ten minutes on two cores, ``--quick`` half a
minute) compare proximity with each library of :mod:`benchmarks.peers`
(Open3D, libigl, Warp on the CPU, FCPW's wheel, MeshLib, coal, python-fcl,
point-cloud-utils, trimesh), each in a process of its own, on trimesh's
icospheres of 20,480 and 1,310,720 faces and a torus of 1,000,000 faces
(``--quick``: 1,280, 20,480 and 20,000), with 100,000 points per set
(``--quick``: 5,000): *near* as above and *box*, uniform in 1.5 times the
bounding box.  For each library: the build time; the memory its build keeps
and its build's peak, in bytes per face (growth of ``VmRSS`` and of
``VmHWM`` over the build, in the child, with the mesh's arrays already
loaded; see :mod:`benchmarks.peers`); points per second of the unsigned and
of the signed distance, on one thread and on all; the largest error against the
exact distance on the first 200 points (``--quick``: 50); the points whose
distance is off the ``certified`` one (within an ulp of the exact
distance) by more than the library's precision allows, which is a face
that is not the nearest; and the wrong signs, on points farther than
``SIGN_BAND`` of the size from the surface, against the solid itself
(:func:`reference_inside`).  A library that does not install or import is
skipped with the reason.  ``OUT/mesh_peers.json`` holds the raw data.
The project's targets for this part (:data:`PEER_TARGETS`: proximity's
memory on the 1,310,720-face icosphere, its one-thread speed and its build
time against FCPW's wheel there, its one-thread speed against Warp's on the
meshes of about 20,000 faces) go to ``OUT/checks-meshes.txt`` with the
torus' (:func:`peers_checks`); a target whose mesh or library is not in the
run gets an ``n/a`` line.

``--crossover`` times brute force against the BVH on 10,000 points
uniform in the bounding box of ``n`` triangles scattered in a unit cube,
for ``n`` from 4 to 256 (one thread, least of 15 calls), and prints the
largest ``n`` at which brute force is still faster: the basis of
``proximity.shapes.scene.BRUTE_FORCE_MAX``.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import proximity
from benchmarks import accuracy
from benchmarks.peers import can_reset_peak, peak_kib, reset_peak, rss_kib
from benchmarks.suite import timed
from proximity.testing.meshes import (  # noqa: F401  (the benchmark's meshes and references)
    EPS,
    PEER_MESHES,
    SIGN_BAND,
    box_points,
    icosphere,
    near_points,
    peer_mesh,
    reference,
    reference_inside,
    soup,
    torus,
)

TARGETS = {"trimesh": 50.0, "fcl": 10.0}


# -- meshes and points ---------------------------------------------------------------


# -- the exact reference --------------------------------------------------------------


# -- timing ------------------------------------------------------------------------------


def time_proximity(mesh, points, method="robust", repeats=5):
    """Median of ``repeats`` calls of ``closest_point`` on all the points, after a warm-up call."""
    mesh.closest_point(points, method=method)
    return timed(lambda: mesh.closest_point(points, method=method), len(points), repeats)


def time_trimesh(vertices, faces, points):
    """``trimesh.proximity.closest_point`` once on the points (the mesh's r-tree built beforehand)."""
    import trimesh

    tm = trimesh.Trimesh(vertices, faces, process=False)
    trimesh.proximity.closest_point(tm, points[:10])  # builds and caches the r-tree
    return timed(lambda: trimesh.proximity.closest_point(tm, points), len(points), 1)


def fcl_loop(vertices, faces, points):
    """A function that queries fcl for each of ``points`` in a Python loop:
    ``fcl.distance`` between a ``BVHModel`` of the mesh and a ``Sphere(0)``
    moved to the point, with nearest points, as a narrow phase would.  The
    model is built here, outside what the function does."""
    import fcl

    from benchmarks.peers import FCL

    mesh = FCL().build(vertices, faces)
    probe = fcl.CollisionObject(fcl.Sphere(0.0), fcl.Transform())
    request = fcl.DistanceRequest(enable_nearest_points=True)

    def run():
        for p in points:
            probe.setTranslation(p)
            fcl.distance(mesh, probe, request, fcl.DistanceResult())

    return run


def time_fcl(vertices, faces, points):
    """:func:`fcl_loop` once on the points, model construction excluded."""
    return timed(fcl_loop(vertices, faces, points), len(points), 1)


class _threads:
    """Numba's thread count set to ``n`` inside the block."""

    def __init__(self, n):
        self.n = n

    def __enter__(self):
        import numba

        self.before = numba.get_num_threads()
        numba.set_num_threads(self.n)

    def __exit__(self, *exc):
        import numba

        numba.set_num_threads(self.before)


def _installed(module):
    try:
        __import__(module)
    except ImportError:
        return False
    return True


# -- memory ------------------------------------------------------------------------------


def _memory_child(what, n_points, n_major, n_minor, seed):
    """In a fresh process: ``{"before_mib", "peak_mib", "added_mib"}`` around one operation."""
    rng = np.random.default_rng(seed)
    vertices, faces = torus(n_major, n_minor)
    points = box_points(rng, vertices, n_points)
    if what == "query":
        mesh = proximity.TriangleMesh(vertices, faces)
        mesh.closest_point(points[:100])  # loads the kernels

        def run():
            return mesh.closest_point(points)
    elif what == "build":
        proximity.TriangleMesh(*torus(8, 8))  # loads the kernels

        def run():
            return proximity.TriangleMesh(vertices, faces)
    elif what == "trimesh":
        import trimesh

        tm = trimesh.Trimesh(vertices, faces, process=False)
        trimesh.proximity.closest_point(tm, points[:10])

        def run():
            return trimesh.proximity.closest_point(tm, points)
    else:
        raise ValueError(what)
    reset_peak()
    before = rss_kib()
    result = run()
    peak = peak_kib()
    del result
    return {"before_mib": before / 1024, "peak_mib": peak / 1024, "added_mib": (peak - before) / 1024}


def measure_memory(what, n_points, n_major, n_minor, seed):
    """:func:`_memory_child` in a subprocess; None where ``/proc`` cannot reset the peak."""
    if not can_reset_peak():
        return None
    args = [sys.executable, "-m", "benchmarks.meshes", "--memory-child", what, str(n_points)]
    args += [str(n_major), str(n_minor), str(seed)]
    root = Path(__file__).resolve().parent.parent
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run(args, capture_output=True, text=True, cwd=root, env=env, check=False)
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "failed"}
    return json.loads(done.stdout.strip().splitlines()[-1])


# -- accuracy records for the charts --------------------------------------------------


def accuracy_record(label, vertices, faces, points, speed):
    """A family record in the format of :mod:`benchmarks.suite`, kind ``"mesh"``."""
    from proximity import adapters

    ref = reference(vertices, faces, points)
    mesh = proximity.TriangleMesh(vertices, faces)
    results = {}
    for method in mesh.methods:
        d = np.asarray(mesh.closest_point(points, method=method).distance)
        results[method] = _errors(d, ref, {"NAN": np.flatnonzero(np.isnan(d))})
        results[method]["timing"] = speed.get(method)
    for name in ("trimesh", "fcl"):
        if name not in adapters.available() or (name == "trimesh" and not _installed("rtree")):
            continue
        with adapters.get(name) as backend:
            r = backend.closest_point(mesh, points)
        failure = np.asarray(r.failure)
        failed = {
            adapters.Failure(code).name: np.flatnonzero(failure == code)
            for code in np.unique(failure)
            if code != adapters.Failure.OK
        }
        results[name] = _errors(np.asarray(r.distance), ref, failed)
        results[name]["timing"] = speed.get(name)
    return {
        "kind": "mesh",
        "family": label,
        "name": label,
        "params": {"faces": len(faces)},
        "n": len(points),
        "d_exact": [float(d) for d, _ in ref],
        "scale": [float(s) for _, s in ref],
        "results": results,
    }


def _errors(distance, ref, failed):
    distance = np.array(distance, dtype=np.float64)
    bad = np.zeros(len(distance), dtype=bool)
    for rows in failed.values():
        bad[rows] = True
    distance[bad] = np.nan
    in_s = np.where(bad, np.nan, accuracy.errors(distance, ref))
    in_ulps = np.where(bad, np.nan, accuracy.ulp_errors(distance, ref))

    def finite(values):
        return [float(v) if np.isfinite(v) else None for v in values]

    return {
        "answered": int((~bad).sum()),
        "failed": {reason: [int(i) for i in rows] for reason, rows in failed.items() if len(rows)},
        "error_eps_s": finite(in_s),
        "error_ulps": finite(in_ulps),
    }


# -- the runs ------------------------------------------------------------------------------


def run(quick=False, seed=0, log=print):
    """Every measurement of the module docstring; returns the JSON-ready record."""
    sizes = (
        dict(major=100, minor=100, n=20_000, trimesh=1_000, fcl=500, build=(500, 200), accuracy=30, repeats=3)
        if quick
        else dict(
            major=100,
            minor=100,
            n=100_000,
            trimesh=5_000,
            fcl=2_000,
            build=(1000, 500),
            accuracy=200,
            repeats=5,
        )
    )
    rng = np.random.default_rng(seed)
    vertices, faces = torus(sizes["major"], sizes["minor"])
    size = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
    sets = {
        "near": near_points(rng, vertices, faces, sizes["n"], 0.01 * size),
        "box": box_points(rng, vertices, sizes["n"]),
    }
    log(f"torus: {len(faces)} triangles; {sizes['n']} points near the surface and {sizes['n']} in its box")
    start = time.perf_counter()
    mesh = proximity.TriangleMesh(vertices, faces)
    build_20k = time.perf_counter() - start  # includes loading the compiled kernels
    start = time.perf_counter()
    mesh = proximity.TriangleMesh(vertices, faces)
    build_20k = min(build_20k, time.perf_counter() - start)

    speed = {}
    for label, points in sets.items():
        for method in mesh.methods:
            part = points if method == "robust" else points[: sizes["n"] // 5]
            timing = time_proximity(mesh, part, method, sizes["repeats"] if method == "robust" else 3)
            speed.setdefault(method, {})[label] = timing
        log(f"  proximity robust, {label}: {speed['robust'][label]['qps']:.3g} points/s")
        with _threads(1):
            speed.setdefault("robust[1 thread]", {})[label] = time_proximity(mesh, points, "robust", 3)
        if _installed("trimesh") and _installed("rtree") and _installed("scipy"):
            speed.setdefault("trimesh", {})[label] = time_trimesh(vertices, faces, points[: sizes["trimesh"]])
            log(f"  trimesh.proximity.closest_point, {label}: {speed['trimesh'][label]['qps']:.3g} points/s")
        if _installed("fcl"):
            speed.setdefault("fcl", {})[label] = time_fcl(vertices, faces, points[: sizes["fcl"]])
            log(f"  fcl per-point BVH distance, {label}: {speed['fcl'][label]['qps']:.3g} points/s")

    ratios = {}
    for ours in ("robust", "robust[1 thread]"):
        for other in ("trimesh", "fcl"):
            for label in sets:
                if other in speed:
                    ratio = speed[ours][label]["qps"] / speed[other][label]["qps"]
                    key = f"{other}/{label}" + (" (1 thread)" if ours != "robust" else "")
                    ratios[key] = {"ratio": ratio, "target": TARGETS[other]}

    n_major, n_minor = sizes["build"]
    big_v, big_f = torus(n_major, n_minor)
    # The least of two: the first build of a large mesh in a process may
    # load or compile the fit that merges ranges, which smaller ones do not use.
    build_big = float("inf")
    for _ in range(2):
        start = time.perf_counter()
        big = proximity.TriangleMesh(big_v, big_f)
        build_big = min(build_big, time.perf_counter() - start)
    build = {
        "faces_20k": {"faces": len(faces), "seconds": build_20k},
        "large": {
            "faces": len(big_f),
            "seconds": build_big,
            "nodes": big._tree.nodes,
            "depth": big._tree.depth,
        },
    }
    del big, big_v, big_f

    memory = {
        "query": measure_memory("query", sizes["n"], sizes["major"], sizes["minor"], seed),
        "build": measure_memory("build", 0, n_major, n_minor, seed),
    }
    if "trimesh" in speed:
        memory["trimesh_query"] = measure_memory(
            "trimesh", sizes["trimesh"], sizes["major"], sizes["minor"], seed
        )

    families = []
    for label, points in sets.items():
        part = points[: sizes["accuracy"]]
        entity_speed = {name: by_set[label] for name, by_set in speed.items()}
        families.append(accuracy_record(f"torus_{label}", vertices, faces, part, entity_speed))

    return {
        "meta": {
            "command": "python -m benchmarks.meshes" + (" --quick" if quick else ""),
            "seed": seed,
            "sizes": sizes,
            "cpus": os.cpu_count(),
            "load_average": os.getloadavg(),
            "numba_threads": __import__("numba").get_num_threads(),
        },
        "speed": speed,
        "ratios": ratios,
        "build": build,
        "memory": memory,
        "families": families,
    }


def checks(raw):
    """The project's targets for the ratios: ``(missed, lines)``, a verdict per ratio."""
    lines, missed = [], 0
    for key, value in raw["ratios"].items():
        met = value["ratio"] >= value["target"]
        missed += not met
        lines.append(f"{'met   ' if met else 'MISSED'}  speed-up over {key}: {value['ratio']:.1f}x "
                     f"(target at least {value['target']:g}x)")  # fmt: skip
    return missed, lines


#: The targets of the peers' run: proximity's build memory on the large icosphere, in bytes per face
#: (kept, peak); its one-thread near-surface speed over FCPW's wheel's there (at least) and its build
#: time over FCPW's (at most); and, on the meshes of about 20,000 faces, its one-thread speed above
#: Warp's on the CPU.
PEER_TARGETS = {"kept": 120.0, "peak": 250.0, "fcpw_speed": 2.5, "fcpw_build": 0.7}
PEER_LARGE_FACES = 1_310_720
PEER_SMALL_FACES = (15_000, 30_000)


def _verdict(met, text):
    return ("met     " if met else "MISSED  ") + text


def _compare(text, ours, theirs, peer, target, bound="at least", note=""):
    """A verdict on ``ours / theirs`` against ``target`` (``bound``: "at least", "at most" or
    "above"), or ``n/a`` where one of them did not run."""
    if ours is None or theirs is None:
        return f"n/a     {text}: {peer if theirs is None else 'proximity'} did not run"
    ratio = ours / theirs
    met = {"at least": ratio >= target, "at most": ratio <= target, "above": ratio > target}[bound]
    return _verdict(met, f"{text}: {ratio:.2f}x (target {bound} {target:g}x{note})")


def peers_checks(raw):
    """The peers' run against :data:`PEER_TARGETS`: ``(missed, lines)``, one line per target; a
    target whose mesh or peer is not in the run gets an ``n/a`` line, which is not counted missed."""
    lines = []
    threads_all = raw["meta"]["threads_all"]
    low, high = PEER_SMALL_FACES
    large = [(label, e) for label, e in raw["meshes"].items() if e["faces"] == PEER_LARGE_FACES]
    small = [(label, e) for label, e in raw["meshes"].items() if low <= e["faces"] <= high]
    if not large:
        lines.append(f"n/a     proximity's memory, and its speed and build time over FCPW's, on the "
                     f"{PEER_LARGE_FACES:,}-face icosphere: that mesh is not in this run")  # fmt: skip
    for label, entry in large:
        kept, peak = _memory(entry, "proximity")
        for key, value, what in (("kept", kept, "memory kept after the build"), ("peak", peak, "build peak")):
            text = f"proximity's {what}, {label}"
            if value is None:
                lines.append(f"n/a     {text}: not measured (proximity did not run, or no /proc)")
            else:
                target = PEER_TARGETS[key]
                lines.append(_verdict(value <= target, f"{text}: {value:.0f} bytes per face (target at most "
                                      f"{target:g}; the larger of the runs)"))  # fmt: skip
        text = f"speed-up over FCPW's wheel, {label}, near points, unsigned, 1 thread"
        ours, theirs = (_qps(entry, name, 1, "near", "unsigned") for name in ("proximity", "fcpw"))
        lines.append(_compare(text, ours, theirs, "FCPW", PEER_TARGETS["fcpw_speed"]))
        ours, theirs = (_build(entry, name, threads_all) for name in ("proximity", "fcpw"))
        one = [_build(entry, name, 1) for name in ("proximity", "fcpw")]
        note = f"; on 1 thread {one[0] / one[1]:.2f}x" if None not in one else ""
        text = f"build time over FCPW's wheel's, {label}, {threads_all} threads"
        lines.append(_compare(text, ours, theirs, "FCPW", PEER_TARGETS["fcpw_build"], "at most", note))
    if not small:
        lines.append(f"n/a     speed-up over Warp (CPU) on the meshes of {low:,} to {high:,} faces: none in "
                     f"this run")  # fmt: skip
    for label, entry in small:
        for set_name in ("near", "box"):
            text = f"speed-up over Warp (CPU), {label}, {set_name} points, unsigned, 1 thread"
            ours, theirs = (_qps(entry, name, 1, set_name, "unsigned") for name in ("proximity", "warp"))
            lines.append(_compare(text, ours, theirs, "Warp", 1.0, "above"))
    return sum(line.startswith("MISSED") for line in lines), lines


def write_checks(path, missed, lines):
    """The verdicts to ``path``, and one line on standard error: how many of the judged ones were met."""
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    judged = sum(not line.startswith("n/a") for line in lines)
    print(f"the project's targets: {judged - missed} of {judged} met ({path})", file=sys.stderr)


def report(raw):
    """The run as text: throughput, ratios, build, memory, worst errors."""
    lines = ["points/s (proximity: all points, median of the repeats; others: one call on a subset)"]
    for name, by_set in raw["speed"].items():
        cells = ", ".join(f"{label} {t['qps']:.3g} (n={t['n']})" for label, t in by_set.items())
        lines.append(f"  {name:16s} {cells}")
    lines.append(
        "ratios (proximity robust / other; '1 thread': proximity on one thread, the others use one):"
    )
    for key, value in raw["ratios"].items():
        lines.append(f"  {key:24s} {value['ratio']:8.1f}x")
    build = raw["build"]
    lines.append(
        f"BVH build: {build['faces_20k']['faces']} faces {build['faces_20k']['seconds']:.3f} s; "
        f"{build['large']['faces']} faces {build['large']['seconds']:.2f} s "
        f"({build['large']['nodes']} nodes, depth {build['large']['depth']})"
    )
    for key, value in raw["memory"].items():
        if value is None or "error" in value:
            lines.append(f"memory {key}: not measured ({value})")
        else:
            lines.append(f"memory {key}: peak {value['peak_mib']:.1f} MiB, +{value['added_mib']:.1f} MiB")
    lines.append("worst error over the accuracy points, in eps*S (failed rows excluded):")
    for family in raw["families"]:
        cells = []
        for name, r in family["results"].items():
            errors = [e for e in r["error_eps_s"] if e is not None]
            failed = sum(len(rows) for rows in r["failed"].values())
            cells.append(f"{name} {max(errors):.3g}" + (f" ({failed} failed)" if failed else ""))
        lines.append(f"  {family['family']}: " + ", ".join(cells))
    lines.append(f"load average during the run: {raw['meta']['load_average']}")
    return "\n".join(lines)


def markdown(raw, path="docs/performance.md"):
    """The table of the run for the page at ``path``: throughput and ratios, build time, memory."""
    speed, meta = raw["speed"], raw["meta"]
    sizes = meta["sizes"]
    load = ", ".join(f"{x:.1f}" for x in meta["load_average"])
    threads = ""
    if "robust[1 thread]" in speed:
        gain = speed["robust"]["near"]["qps"] / speed["robust[1 thread]"]["near"]["qps"]
        threads = f"; two threads were {gain:.1f} times as fast as one"
    lines = [
        f"Torus of {raw['build']['faces_20k']['faces']:,} triangles; {sizes['n']:,} points near the "
        f"surface (moved off it by 1% of the size) and {sizes['n']:,} uniform in its bounding box. "
        f"Points per second; proximity (`robust`, BVH) on all points, median of {sizes['repeats']} calls; "
        f"trimesh once on the first {sizes['trimesh']:,} points, fcl (a `BVHModel` and a `Sphere(0)` "
        f"moved per point) on the first {sizes['fcl']:,}. Made by `python -m benchmarks.meshes "
        f"--write {path}` on {meta['cpus']} cores shared with other jobs (load average {load}"
        f"{threads}).",
        "",
        "| | near the surface | in the bounding box |",
        "|---|---:|---:|",
    ]
    names = {
        "robust": "proximity, 2 threads",
        "robust[1 thread]": "proximity, 1 thread",
        "trimesh": "`trimesh.proximity.closest_point`",
        "fcl": "fcl, per point",
    }
    for key, label in names.items():
        if key in speed:
            lines.append(f"| {label} | {speed[key]['near']['qps']:,.0f} | {speed[key]['box']['qps']:,.0f} |")
    for other, label in (("trimesh", "trimesh"), ("fcl", "fcl")):
        if f"{other}/near" in raw["ratios"]:
            near, box = raw["ratios"][f"{other}/near"], raw["ratios"][f"{other}/box"]
            lines.append(f"| speed-up over {label} | {near['ratio']:.0f}x | {box['ratio']:.0f}x |")
    build, memory = raw["build"], raw["memory"]
    lines += [
        "",
        f"BVH build: {build['large']['faces']:,} triangles in {build['large']['seconds']:.1f} s "
        f"({build['faces_20k']['faces']:,} in {build['faces_20k']['seconds'] * 1e3:.0f} ms).",
    ]
    parts = []
    for key, label in (
        ("query", f"the query of {sizes['n']:,} points"),
        ("build", f"the build of {build['large']['faces']:,} triangles"),
        ("trimesh_query", f"trimesh's query of {sizes['trimesh']:,} points"),
    ):
        value = memory.get(key)
        if value and "error" not in value:
            parts.append(f"{label} +{value['added_mib']:.0f} MiB")
    if parts:
        lines.append("Peak memory added (VmHWM, fresh process): " + "; ".join(parts) + ".")
    worst = []
    for family in raw["families"]:
        for name in ("robust", "certified"):
            errors = [e for e in family["results"][name]["error_eps_s"] if e is not None]
            worst.append(max(errors))
    lines.append(
        f"Worst error of `robust` and `certified` over {sizes['accuracy']} points of each set, against the "
        f"exact distance to the mesh: {max(worst):.2g} eps S."
    )
    return "\n".join(lines)


def write_section(path, text, marker="mesh-bench"):
    """Replace the text between the ``marker`` markers of ``path``."""
    page = Path(path).read_text(encoding="utf-8")
    pattern = re.compile(rf"(<!-- {marker}:start -->\n).*?(<!-- {marker}:end -->)", re.S)
    if not pattern.search(page):
        raise SystemExit(f"{path} has no {marker} markers")
    page = pattern.sub(lambda m: m.group(1) + text + "\n" + m.group(2), page)
    Path(path).write_text(page, encoding="utf-8")


# -- the peers ---------------------------------------------------------------------------


def _peer_child(name, data_path, threads, answers_path):
    """One peer's run in a new process (see :mod:`benchmarks.peers`); its JSON record."""
    root = Path(__file__).resolve().parent.parent
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]),
        OMP_NUM_THREADS=str(threads),
        IGL_NUM_THREADS=str(threads),
    )
    args = [sys.executable, "-m", "benchmarks.peers", name, str(data_path), str(threads), str(answers_path)]
    done = subprocess.run(args, capture_output=True, text=True, cwd=root, env=env, check=False)
    if done.returncode != 0:
        lines = done.stderr.strip().splitlines()
        return {"error": lines[-1] if lines else f"exit code {done.returncode}"}
    return json.loads(done.stdout.strip().splitlines()[-1])


def _unsigned_errors(distance, ref, precision, points):
    """Max error on the exact sample; rows off the ``certified`` distance by more than the precision."""
    n = len(distance)
    unit = 2.0**-24 if precision == "float32" else 2.0**-53
    d_ref = ref["certified"][:n]
    # Inputs rounded to the peer's precision move a distance by a few units of
    # the coordinates' magnitude; its arithmetic adds a few more.
    magnitude = ref["magnitude"] + np.max(np.abs(ref["points"][:n]), axis=1)
    with np.errstate(invalid="ignore"):
        off = ~np.isfinite(distance) | (np.abs(distance - d_ref) > 16.0 * unit * magnitude)
    k = min(n, len(ref["exact"]))
    with np.errstate(invalid="ignore"):
        max_error = float(np.max(np.abs(distance[:k] - ref["exact"][:k])))
    return {"n": int(n), "off": int(off.sum()), "max_error": max_error, "sample": int(k)}


def _sign_errors(signed, ref, size):
    n = len(signed)
    far = ref["certified"][:n] > SIGN_BAND * size
    wrong = far & (~np.isfinite(signed) | ((signed < 0) != ref["inside"][:n]))
    return {"n": int(n), "judged": int(far.sum()), "wrong": int(wrong.sum())}


def run_peers(quick=False, seed=0, out=Path("bench-results"), names=None, log=print):
    """proximity against every peer of :mod:`benchmarks.peers` on :data:`PEER_MESHES`.

    Returns the JSON-ready record: ``meta`` and, per mesh, ``faces``,
    ``reference`` (seconds and counts) and per peer ``label``,
    ``precision``, ``threads``, ``rebuilds`` and ``runs``: the children's
    records by thread count (``build``, ``memory``, ``sets``), with the
    errors of their answers.
    """
    import numba

    from benchmarks import peers

    n_points, n_exact = (5_000, 50) if quick else (100_000, 200)
    threads_all = numba.config.NUMBA_NUM_THREADS
    work = Path(out) / "peers"
    work.mkdir(parents=True, exist_ok=True)
    names = list(peers.PEERS) if names is None else names
    raw = {
        "meta": {
            "command": "python -m benchmarks.meshes" + (" --quick" if quick else ""),
            "seed": seed,
            "points": n_points,
            "exact_sample": n_exact,
            "cpus": os.cpu_count(),
            "threads_all": threads_all,
            "load_average": [os.getloadavg()],
        },
        "meshes": {},
    }
    for label, kind, size in PEER_MESHES[quick]:
        rng = np.random.default_rng(seed)
        vertices, faces = peer_mesh(kind, size)
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        extent = float(np.max(high - low))
        centre = (low + high) / 2
        sets = {
            "near": near_points(rng, vertices, faces, n_points, 0.01 * extent),
            "box": centre + 1.5 * (box_points(rng, vertices, n_points) - centre),
        }
        data_path = work / f"{kind}-{len(faces)}.npz"
        np.savez(data_path, vertices=vertices, faces=faces, **sets)
        log(f"{label}: the reference (certified distances, exact on {n_exact} points, signs)")
        start = time.perf_counter()
        mesh = proximity.TriangleMesh(vertices, faces)
        refs = {}
        for name, points in sets.items():
            inside, by_winding = reference_inside(kind, size, vertices, faces, points)
            refs[name] = {
                "points": points,
                "certified": np.asarray(mesh.distance(points, method="certified")),
                "exact": np.array([float(d) for d, _ in reference(vertices, faces, points[:n_exact])]),
                "magnitude": float(np.max(np.abs(vertices))),
                "inside": inside,
                "by_winding": int(by_winding.sum()),
            }
        del mesh
        entry = {
            "faces": len(faces),
            "size": extent,
            "reference": {
                "seconds": time.perf_counter() - start,
                "by_winding": {name: ref["by_winding"] for name, ref in refs.items()},
                "inside": {name: int(ref["inside"].sum()) for name, ref in refs.items()},
            },
            "peers": {},
        }
        for name in names:
            peer = peers.PEERS[name]
            runs = {}
            for threads in [1] if peer.threads == "one" else [1, threads_all]:
                answers_path = work / f"answers-{name}-{threads}.npz"
                record = _peer_child(name, data_path, threads, answers_path)
                if "sets" in record:
                    answers = np.load(answers_path)
                    for set_name, ref in refs.items():
                        timings = record["sets"][set_name]
                        timings["unsigned"]["errors"] = _unsigned_errors(
                            answers[f"{set_name}.unsigned"], ref, peer.precision, ref["points"]
                        )
                        if "signed" in timings:
                            timings["signed"]["errors"] = _sign_errors(
                                answers[f"{set_name}.signed"], ref, extent
                            )
                    answers_path.unlink()
                runs[str(threads)] = record
                log(f"  {name}, {threads} thread(s): " + _brief(record))
            entry["peers"][name] = {
                "label": peer.label,
                "precision": peer.precision,
                "threads": peer.threads,
                "rebuilds": list(peer.rebuilds),
                "runs": runs,
            }
        raw["meshes"][label] = entry
        data_path.unlink()
        raw["meta"]["load_average"].append(os.getloadavg())
    return raw


def _brief(record):
    if "sets" not in record:
        return record.get("skipped") or record.get("error", "?")
    cells = [f"build {1e3 * record['build']:.1f} ms"]
    memory = record.get("memory")
    if memory:
        kept, peak = (1024 * memory[key] / memory["faces"] for key in ("kept_kib", "peak_kib"))
        cells.append(f"kept {kept:.0f} B/face, peak {peak:.0f} B/face")
    for name, timings in record["sets"].items():
        for kind, timing in timings.items():
            cells.append(f"{name} {kind} {timing['qps']:,.0f}/s")
    return ", ".join(cells)


def _qps(entry, name, threads, set_name, kind):
    record = entry["peers"].get(name, {}).get("runs", {}).get(str(threads), {})
    timing = record.get("sets", {}).get(set_name, {}).get(kind)
    return None if timing is None else timing["qps"]


def _memory(entry, name):
    """``(kept, peak)`` of the peer's build in bytes per face, the larger over its runs (one per
    thread count); None where not measured."""
    runs = entry["peers"].get(name, {}).get("runs", {}).values()
    measured = [record["memory"] for record in runs if record.get("memory")]
    if not measured:
        return None, None
    return tuple(max(1024 * m[key] / m["faces"] for m in measured) for key in ("kept_kib", "peak_kib"))


def _build(entry, name, threads):
    """The peer's build time in seconds, from its run on ``threads`` (a one-thread peer's only run)."""
    runs = entry["peers"].get(name, {}).get("runs", {})
    record = runs.get(str(threads)) or runs.get("1", {})
    return record.get("build")


def peers_summary(raw):
    """Per mesh, point set, query kind and thread count: proximity's speed over the fastest peer's."""
    threads_all = raw["meta"]["threads_all"]
    rows = []
    for label, entry in raw["meshes"].items():
        for set_name in ("near", "box"):
            for kind in ("unsigned", "signed"):
                for threads in (1, threads_all):
                    ours = _qps(entry, "proximity", threads, set_name, kind)
                    best = None
                    for name, peer in entry["peers"].items():
                        # A one-thread peer is its own best on all threads.
                        qps = _qps(entry, name, 1 if peer["threads"] == "one" else threads, set_name, kind)
                        if name != "proximity" and qps is not None and (best is None or qps > best[1]):
                            best = (peer["label"], qps)
                    if ours is not None and best is not None:
                        rows.append((label, set_name, kind, threads, ours, best[0], best[1], ours / best[1]))
    return rows


def peers_report(raw):
    """The peers' run as text."""
    lines = []
    for label, entry in raw["meshes"].items():
        lines.append(f"{label} (reference: {entry['reference']['seconds']:.0f} s)")
        for name, peer in entry["peers"].items():
            for threads, record in peer["runs"].items():
                lines.append(f"  {name:10s} {threads} thread(s): {_brief(record)}")
                for set_name, timings in record.get("sets", {}).items():
                    for kind, timing in timings.items():
                        errors = timing.get("errors", {})
                        lines.append(f"    {set_name} {kind}: n={timing['n']} {errors}")
    lines.append("proximity / fastest peer:")
    for label, set_name, kind, threads, ours, name, best, ratio in peers_summary(raw):
        lines.append(
            f"  {label}, {set_name}, {kind}, {threads} thread(s): "
            f"{ours:,.0f} / {best:,.0f} ({name}) = {ratio:.2f}x"
        )
    return "\n".join(lines)


def _cell(value, digits=3):
    return "" if value is None else f"{value:,.0f}" if value >= 100 else f"{value:.{digits}g}"


def peers_markdown(raw, path="docs/performance.md", chart=None):
    """Tables of the peers' run for the page at ``path``: per mesh, unsigned and signed, after
    the chart (a PNG beside the page) where there is one."""
    meta = raw["meta"]
    threads_all = meta["threads_all"]
    load = ", ".join(f"{x:.1f}" for x in meta["load_average"][-1])
    lines = [
        f"{meta['points']:,} points per set: *near* (on the surface, moved along the normal by a normal "
        f"deviate of 1% of the size) and *box* (uniform in 1.5 times the bounding box). Points per second "
        f"on 1 and {threads_all} threads; each library in a process of its own, timed on as many of the "
        f"points as it answers in about a second (*n*; every point where a call builds a tree), median of "
        f"up to 3 calls. *max error*: against the "
        f"exact distance on the first {meta['exact_sample']} points; *off*: points whose distance differs "
        f"from the `certified` one (within an ulp of the exact distance) by more than 16 units of the "
        f"library's precision times the coordinates' magnitude: a face that is not the nearest, or no "
        f"answer. *wrong signs*: against the solid the mesh approximates, on points farther than "
        f"{SIGN_BAND:g} of the size from the surface. *kept*: the growth of the process's resident set "
        f"over the build, after the C heap's free pages go back to the system; *build peak*: the growth "
        f"of its peak; both with the mesh's arrays already made, in bytes per face, the larger of the "
        f"library's runs (the library's own copies of the mesh count). libigl's `signed_distance` and both "
        f"of point-cloud-utils' functions build their tree in every call, as their Python functions do; "
        f"Warp runs its CPU kernels on one thread; FCPW (its wheel: a binary BVH, float32, the wide SIMD "
        f"tree left out of the wheel) and MeshLib are held to 1 core by the process's affinity, as their "
        f"batch calls use every core they find; coal, fcl and trimesh answer one point at a time "
        f"(= 1 thread). "
        f"Made by `python -m benchmarks.meshes --write {path}` "
        f"on {meta['cpus']} cores shared with other jobs (load average at the end {load}).",
    ]
    if chart is not None:
        from benchmarks.charts import CAPTIONS

        lines += ["", f"![Meshes: accuracy against speed]({Path(chart).name})", "", CAPTIONS["mesh_peers"]]
    for label, entry in raw["meshes"].items():
        lines += ["", f"**{label[0].upper() + label[1:]}**", ""]
        lines += [
            f"| unsigned | precision | build (ms) | kept (B/face) | build peak (B/face) | near, 1 thread | "
            f"near, {threads_all} threads | box, 1 thread | box, {threads_all} threads | "
            f"max error (near, box) | off (near, box) |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---|",
        ]
        signed_rows, skipped = [], []
        for name, peer in entry["peers"].items():
            runs = peer["runs"]
            first = runs.get("1", {})
            if "sets" not in first:
                skipped.append(f"{peer['label']}: {first.get('skipped') or first.get('error')}")
                continue
            build = _build(entry, name, threads_all)
            if set(peer.get("rebuilds", ())) >= {"unsigned", "signed"}:
                memory = ["in every call"] * 2
            else:
                memory = [_cell(value) for value in _memory(entry, name)]
            speeds, errors, signed, wrong = [], [], [], []
            for set_name in ("near", "box"):
                for threads in (1, threads_all):
                    speeds.append(_qps(entry, name, threads, set_name, "unsigned"))
                    signed.append(_qps(entry, name, threads, set_name, "signed"))
                e = first["sets"][set_name]["unsigned"]["errors"]
                errors.append((e["max_error"], e["off"], e["n"]))
                if "signed" in first["sets"][set_name]:
                    w = first["sets"][set_name]["signed"]["errors"]
                    wrong.append(f"{w['wrong']:,} of {w['judged']:,}")
            one = peer["threads"] == "one"
            cells = [_cell(v) if v is not None else ("= 1 thread" if one else "") for v in speeds]
            max_error = ", ".join(f"{e[0]:.2g}" for e in errors)
            off = ", ".join(f"{e[1]:,} of {e[2]:,}" for e in errors)
            lines.append(
                f"| {peer['label']} | {peer['precision']} | {_cell(1e3 * build)} | {' | '.join(memory)} | "
                + " | ".join(cells)
                + f" | {max_error} | {off} |"
            )
            if wrong:
                cells = [_cell(v) if v is not None else ("= 1 thread" if one else "") for v in signed]
                prepare = first.get("prepare_signed")
                extra = f" (+{prepare:.2f} s pseudonormals)" if prepare is not None else ""
                signed_rows.append(
                    f"| {peer['label']}{extra} | " + " | ".join(cells) + f" | {', '.join(wrong)} |"
                )
        lines += [
            "",
            f"| signed | near, 1 thread | near, {threads_all} threads | box, 1 thread | "
            f"box, {threads_all} threads | wrong signs (near, box) |",
            "|---|---:|---:|---:|---:|---|",
            *signed_rows,
        ]
        if skipped:
            lines += ["", "Not run: " + "; ".join(skipped) + "."]
    lines += ["", "proximity's speed over the fastest other library's, same points and threads:", ""]
    lines += [
        "| mesh | points | query | threads | proximity | fastest other | ratio |",
        "|---|---|---|---:|---:|---|---:|",
    ]
    for label, set_name, kind, threads, ours, name, best, ratio in peers_summary(raw):
        lines.append(
            f"| {label} | {set_name} | {kind} | {threads} | {ours:,.0f} | {name} {best:,.0f} | {ratio:.2f}x |"
        )
    return "\n".join(lines)


def crossover(seed=0, sizes=(4, 8, 12, 16, 24, 32, 48, 64, 128, 256), n_points=10_000, repeats=15, log=print):
    """Query time of brute force and of the BVH against the number of triangles.

    One thread, so that the comparison is of the work per point (both broad
    phases are parallel over points in the same way) and not of how the
    operating system schedules two threads on a shared machine; the least
    of ``repeats`` calls, as other processes only ever add time.

    Returns ``{"n": [...], "brute": [...], "bvh": [...], "threshold": int}``
    with seconds per call, and the largest ``n`` at which brute force was
    faster.
    """
    import numba

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        rng = np.random.default_rng(seed)
        out = {"n": [], "brute": [], "bvh": []}
        for n in sizes:
            vertices, faces = soup(rng, n)
            points = box_points(rng, vertices, n_points)
            row = {}
            for phase in ("brute", "bvh"):
                mesh = proximity.TriangleMesh(vertices, faces, broad_phase=phase)
                mesh.distance(points)
                timing = timed(lambda m=mesh, p=points: m.distance(p), n_points, repeats)
                row[phase] = float(np.min(timing["seconds"]))
            out["n"].append(n)
            out["brute"].append(row["brute"])
            out["bvh"].append(row["bvh"])
            log(f"n={n:4d}  brute {row['brute'] * 1e3:8.3f} ms  bvh {row['bvh'] * 1e3:8.3f} ms")
    finally:
        numba.set_num_threads(threads)
    faster = [n for n, b, h in zip(out["n"], out["brute"], out["bvh"], strict=True) if b <= h]
    out["threshold"] = max(faster) if faster else 0
    log(f"brute force was faster up to n = {out['threshold']}")
    return out


def main(argv=None):
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.meshes", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes, a smoke run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="bench-results", help="directory for meshes.json")
    parser.add_argument("--crossover", action="store_true", help="brute force against the BVH, n = 4..256")
    parser.add_argument(
        "--write", metavar="PATH", help="rewrite the mesh-bench section of this page (docs/performance.md)"
    )
    parser.add_argument("--no-peers", action="store_true", help="skip the comparison with other libraries")
    parser.add_argument("--peers-only", action="store_true", help="only the comparison with other libraries")
    parser.add_argument("--peer", action="append", help="compare with this library only (repeatable)")
    parser.add_argument("--memory-child", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.memory_child:
        what, n_points, n_major, n_minor, seed = args.memory_child
        print(json.dumps(_memory_child(what, int(n_points), int(n_major), int(n_minor), int(seed))))
        return 0
    if args.crossover:
        crossover(seed=args.seed)
        return 0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    # Both parts' verdicts, written after each part.
    verdicts, missed, lines = out / "checks-meshes.txt", 0, []
    if not args.peers_only:
        with np.errstate(all="ignore"):
            raw = run(quick=args.quick, seed=args.seed)
        (out / "meshes.json").write_text(json.dumps(raw, indent=1))
        print(report(raw))
        print(f"raw data: {out / 'meshes.json'}")
        missed, lines = checks(raw)
        write_checks(verdicts, missed, lines)
        if args.write:
            write_section(args.write, markdown(raw, args.write))
    if not args.no_peers:
        with np.errstate(all="ignore"):
            raw = run_peers(quick=args.quick, seed=args.seed, out=out, names=args.peer)
        (out / "mesh_peers.json").write_text(json.dumps(raw, indent=1))
        print(peers_report(raw))
        print(f"raw data: {out / 'mesh_peers.json'}")
        more_missed, more = peers_checks(raw)
        write_checks(verdicts, missed + more_missed, lines + more)
        from benchmarks import charts

        with np.errstate(over="ignore"):
            chart = charts.mesh_peers(raw, out / "mesh_peers.png")
        if chart is not None:
            print(f"chart: {chart}")
        if args.write:
            image = None
            if chart is not None:
                image = Path(args.write).parent / chart.name
                shutil.copyfile(chart, image)
            write_section(args.write, peers_markdown(raw, args.write, image), marker="mesh-peers")
    return 0


if __name__ == "__main__":
    sys.exit(main())
