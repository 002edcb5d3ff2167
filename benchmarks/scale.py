"""Point clouds on disk: ``python -m proximity.cloud`` in this process and on Dask.

    python -m benchmarks.scale [--quick] [--points N] [--chunk ROWS] [--dir DIR] [--out DIR]

The default run builds an icosphere of 1,310,720 faces (trimesh's
``icosphere(subdivisions=8)``, radius 1), writes it as a PLY file, and
writes 100,000,000 points (2.4 GB) to a ``.npy`` file on disk, a chunk at
a time.  The points are *near* the surface: uniform directions, at radii
uniform in ``[0.98, 1.02]``, so within 1% of the sphere's diameter from it
(points far inside a closed surface are the slow case of the hierarchy,
and the command's speed follows the query's).  It measures:

* in memory: ``TriangleMesh.distance`` on a block of 1,000,000 such points
  (after a warm-up call), twice before the runs below and twice after: the
  fastest of the four is the reference for the ratios;
* shipping: the mesh's pickle size, and the times to build the mesh and
  to unpickle it;
* the command in this process (the embedded default) and with
  ``--workers 2`` (a ``LocalCluster`` of two processes of one thread), each
  in a new process, on every point of the file: end-to-end seconds (Python
  start-up, reading the mesh and building its hierarchy included) and the
  seconds of the chunk loop, as points per second and as a ratio to the
  in-memory throughput, and the peak resident memory (``ru_maxrss``) of
  every process, from the command's ``--summary``;
* the same in-process command on a tenth of the points (a prefix of the
  file), to show that peak memory does not grow with ``N``.

``--quick``: an icosphere of 20,480 faces and 2,000,000 points.  The files
are deleted at the end; the table is printed and saved to ``OUT/scale.md``
with the raw numbers in ``OUT/scale.json``.
"""

import argparse
import json
import os
import pickle
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
WRITE_ROWS = 4_000_000  # rows generated and written at a time
BLOCK = 1_000_000  # the in-memory reference block


def near_points(rng, n):
    """``n`` points at radii uniform in [0.98, 1.02] around the unit sphere."""
    u = rng.normal(size=(n, 3))
    u /= np.sqrt(np.einsum("ij,ij->i", u, u))[:, None]
    u *= rng.uniform(0.98, 1.02, size=(n, 1))
    return u


def write_points(path, n, seed):
    """Write ``n`` near points to the ``.npy`` file ``path``, a window at a time."""
    out = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=(n, 3))
    offset = out.offset
    del out
    rng = np.random.default_rng(seed)
    for start in range(0, n, WRITE_ROWS):
        rows = min(WRITE_ROWS, n - start)
        window = np.memmap(path, dtype=np.float64, mode="r+", offset=offset + start * 24, shape=(rows, 3))
        window[:] = near_points(rng, rows)
        window.flush()
        del window


def prefix(path, n, folder):
    """A ``.npy`` file of the first ``n`` rows of ``path``."""
    small = folder / f"points_{n}.npy"
    source = np.load(path, mmap_mode="r")
    out = np.lib.format.open_memmap(small, mode="w+", dtype=np.float64, shape=(n, 3))
    for start in range(0, n, WRITE_ROWS):
        stop = min(n, start + WRITE_ROWS)
        out[start:stop] = source[start:stop]
    out.flush()
    del out, source
    return small


def reference_seconds(mesh, block, calls=2):
    """Seconds of ``calls`` in-memory distance queries of ``block``."""
    seconds = []
    for _ in range(calls):
        start = time.perf_counter()
        mesh.distance(block)
        seconds.append(time.perf_counter() - start)
    return seconds


def command(mesh, points, out, chunk, extra, folder):
    """Run the command in a new process; its summary, with the wall time from here."""
    summary = folder / "summary.json"
    args = [sys.executable, "-m", "proximity.cloud", str(mesh), str(points), "-o", str(out)]
    args += ["--chunk", str(chunk), "--no-progress", "--summary", str(summary), *extra]
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed:\n{done.stderr[-3000:]}")
    report = json.loads(summary.read_text())
    report["wall_seconds"] = wall
    return report


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m benchmarks.scale", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="20,480 faces and 2,000,000 points")
    parser.add_argument("--points", type=int, help="points (default 100,000,000; quick 2,000,000)")
    parser.add_argument("--chunk", type=int, default=1_000_000, help="rows per chunk (default 1,000,000)")
    parser.add_argument("--dir", type=Path, help="where to write the files (default: a temporary folder)")
    parser.add_argument("--out", type=Path, default=Path("bench-results"), help="where to save the table")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    import trimesh

    import proximity
    from proximity import broadphase, cloud

    n = args.points or (2_000_000 if args.quick else 100_000_000)
    subdivisions = 5 if args.quick else 8
    folder = Path(tempfile.mkdtemp(prefix="proximity-scale-", dir=args.dir))
    raw = {"points": n, "chunk": args.chunk, "cores": os.cpu_count(), "python": platform.python_version()}
    rows = []
    try:
        sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
        mesh_path = folder / "sphere.ply"
        sphere.export(mesh_path)
        faces = len(sphere.faces)
        raw["faces"] = faces
        print(f"mesh: icosphere of {faces:,} faces; writing {n:,} points to {folder}", file=sys.stderr)
        start = time.perf_counter()
        points_path = folder / "points.npy"
        write_points(points_path, n, args.seed)
        raw["write_seconds"] = time.perf_counter() - start

        # In memory: the reference throughput, and what shipping the mesh costs.
        start = time.perf_counter()
        mesh = cloud.read_mesh(mesh_path)
        raw["read_and_build_seconds"] = time.perf_counter() - start
        rng = np.random.default_rng(args.seed + 1)
        mesh.distance(near_points(rng, 10_000))  # loads the kernel
        block = near_points(rng, BLOCK)
        seconds = reference_seconds(mesh, block)
        reference = BLOCK / min(seconds)
        raw["numba_layer"] = proximity.runtime.threads.layer()
        blob = pickle.dumps(mesh, protocol=pickle.HIGHEST_PROTOCOL)
        built = []
        originals = broadphase.build_tree, broadphase.build_faces
        broadphase.build_tree = lambda *a, **k: built.append(1) or originals[0](*a, **k)
        broadphase.build_faces = lambda *a, **k: built.append(1) or originals[1](*a, **k)
        start = time.perf_counter()
        pickle.loads(blob)
        raw["unpickle_seconds"] = time.perf_counter() - start
        broadphase.build_tree, broadphase.build_faces = originals
        raw["pickle_bytes"] = len(blob)
        raw["unpickle_builds"] = len(built)
        print(
            f"in memory: {reference:,.0f} points/s; pickle {len(blob) / 1e6:.0f} MB, "
            f"unpickled in {raw['unpickle_seconds']:.2f} s (built {raw['read_and_build_seconds']:.2f} s)",
            file=sys.stderr,
        )
        del blob

        out = folder / "distances.npy"
        runs = [
            ("command, in-process", points_path, []),
            ("command, LocalCluster(2)", points_path, ["--workers", "2"]),
            ("command, in-process, N/10", prefix(points_path, n // 10, folder), []),
        ]
        raw["runs"] = {}
        for name, path, extra in runs:
            print(f"{name} ...", file=sys.stderr)
            report = command(mesh_path, path, out, args.chunk, extra, folder)
            raw["runs"][name] = report
            count = report["points"]
            peaks = {"main": report["peak_rss_bytes"]["main"]}
            for i, value in enumerate(report["peak_rss_bytes"]["workers"].values()):
                peaks[f"worker {i}"] = value
            rows.append((name, count, report["wall_seconds"], report["query_seconds"], peaks))
            out.unlink(missing_ok=True)
        # The reference again, after the runs: the faster of all its timings
        # is the one the ratios divide by, which favours the reference where
        # other work on the machine slowed some of them.
        seconds += reference_seconds(mesh, block)
        raw["in_memory_seconds"] = seconds
        raw["in_memory_points_per_second"] = BLOCK / min(seconds)
        rows.insert(0, ("in memory, `TriangleMesh.distance`", BLOCK, min(seconds), None, {}))
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    table = format_table(rows, raw)
    print(table)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "scale.md").write_text(table + "\n", encoding="utf-8")
    (args.out / "scale.json").write_text(json.dumps(raw, indent=1) + "\n", encoding="utf-8")
    return 0


def format_table(rows, raw):
    lines = [
        f"Icosphere of {raw['faces']:,} faces; {raw['points']:,} points within 1% of its diameter from it, "
        f"from a .npy file; chunks of {raw['chunk']:,} rows; {raw['cores']} cores, Numba layer "
        f"{raw['numba_layer']}.  Mesh pickle {raw['pickle_bytes'] / 1e6:.0f} MB, unpickled in "
        f"{raw['unpickle_seconds']:.2f} s ({raw['unpickle_builds']} builds); read and built in "
        f"{raw['read_and_build_seconds']:.2f} s.",
        "",
        "| run | points | seconds | points/s | ratio | loop points/s | loop ratio | peak memory (MB) |",
        "|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    reference = raw["in_memory_points_per_second"]
    for name, count, wall, loop, peaks in rows:
        rate = count / wall
        loop_rate = count / loop if loop else None
        memory = ", ".join(f"{k} {v / 2**20:,.0f}" for k, v in peaks.items() if v) or "-"
        lines.append(
            f"| {name} | {count:,} | {wall:.1f} | {rate:,.0f} | {rate / reference:.2f} | "
            + (f"{loop_rate:,.0f} | {loop_rate / reference:.2f}" if loop_rate else "- | -")
            + f" | {memory} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
