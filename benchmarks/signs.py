"""Wrong signs: proximity's sign modes and the peers' on meshes that are not clean solids.

    python -m benchmarks.signs [--quick] [--out DIR] [--seed 0] [--write docs/performance.md]

The meshes are :func:`proximity.testing.meshes.defective` (overlapping and
nested shells, a self-intersecting octahedron, an internal double-sided
sheet, an inverted sphere, split seams, a zero-area face, a cavity, a sphere
with a hole) and a clean torus of 2,000 faces.  Each gets 20,000 seeded
points (``--quick``: 2,000): half uniform in 1.2 times its bounding box, 30%
on its surface moved along the face normal by a normal deviate of 1e-3 of its
size, and 20% around its edges (those of zero-area faces included), 1e-8 to
3e-8 of its size off them.  The truth is the exact integer winding number (signed ray crossings
in rational arithmetic, :func:`proximity.testing.winding.winding_numbers`),
inside where it is not 0; on the open sphere, the winding number summed
face by face with its rigorous bound, on the points where the bound decides
``|w| > 1/2``.  Points nearer the surface than ``SIGN_BAND`` of the size
are not judged.

For each mode: the wrong signs, whether it warned or refused, and the time
of the whole batch (median of 3 calls after a warm-up).  proximity's modes
(``sign="auto"``, ``"pseudonormal"``, ``"winding"``) run here; each peer
runs in a process of its own (``python -m benchmarks.signs --child NAME
DATA OUT``): libigl's pseudonormal and fast winding number signed
distances, Open3D's ``compute_signed_distance`` (ray crossings), Warp's
normal and winding-number signs, MeshLib's signed distance, pysdf and
trimesh's ``signed_distance``, each where it installs.  ``OUT/signs.json``
holds the raw data.
"""

import argparse
import json
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from proximity.testing.meshes import SIGN_BAND, defective, near_points, torus

# -- the peers, in their own process -----------------------------------------------------


def _libigl(mode):
    def signed(vertices, faces, points):
        import igl

        kind = igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL if mode == "pseudonormal" else (
            igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)  # fmt: skip
        return igl.signed_distance(points, vertices, faces, sign_type=kind)[0]

    return "igl", signed


def _open3d(vertices, faces, points):
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(vertices.astype(np.float32)), o3d.core.Tensor(faces.astype(np.uint32))
    )
    query = o3d.core.Tensor(points.astype(np.float32))
    return scene.compute_signed_distance(query).numpy().astype(np.float64)


def _warp(mode):
    def signed(vertices, faces, points):
        import warp as wp

        wp.config.quiet = True
        wp.init()

        @wp.kernel
        def normal(mesh: wp.uint64, q: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
            i = wp.tid()
            r = wp.mesh_query_point_sign_normal(mesh, q[i], 1.0e30)
            out[i] = r.sign * wp.length(q[i] - wp.mesh_eval_position(mesh, r.face, r.u, r.v))

        @wp.kernel
        def winding(mesh: wp.uint64, q: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
            i = wp.tid()
            r = wp.mesh_query_point_sign_winding_number(mesh, q[i], 1.0e30, 2.0, 0.5)
            out[i] = r.sign * wp.length(q[i] - wp.mesh_eval_position(mesh, r.face, r.u, r.v))

        mesh = wp.Mesh(
            points=wp.array(vertices.astype(np.float32), dtype=wp.vec3, device="cpu"),
            indices=wp.array(faces.astype(np.int32).reshape(-1), dtype=wp.int32, device="cpu"),
        )
        query = wp.array(points.astype(np.float32), dtype=wp.vec3, device="cpu")
        out = wp.empty(len(points), dtype=float, device="cpu")
        wp.launch(normal if mode == "normal" else winding, dim=len(points), inputs=[mesh.id, query, out],
                  device="cpu")  # fmt: skip
        wp.synchronize_device("cpu")
        return out.numpy().astype(np.float64)

    return "warp", signed


def _meshlib(vertices, faces, points):
    from meshlib import mrmeshnumpy, mrmeshpy

    mesh = mrmeshnumpy.meshFromFacesVerts(faces.astype(np.int32), vertices.astype(np.float32))
    part = mrmeshpy.MeshPart(mesh)
    out = np.empty(len(points))
    for k, p in enumerate(points.astype(np.float32)):
        result = mrmeshpy.findSignedDistance(mrmeshpy.Vector3f(*map(float, p)), part)
        out[k] = np.nan if result is None else result.dist
    return out


def _pysdf(vertices, faces, points):
    from pysdf import SDF

    return -np.asarray(
        SDF(vertices.astype(np.float32), faces.astype(np.uint32))(points.astype(np.float32)), dtype=np.float64
    )  # fmt: skip  (pysdf's is positive inside)


def _trimesh(vertices, faces, points):
    import trimesh

    return -trimesh.proximity.signed_distance(trimesh.Trimesh(vertices, faces, process=False), points)


def _meshlib_grid(mode):
    def grid(vertices, faces, lower, upper, shape, band):
        from meshlib import mrmeshnumpy, mrmeshpy

        mesh = mrmeshnumpy.meshFromFacesVerts(faces.astype(np.int32), vertices.astype(np.float32))
        params = mrmeshpy.MeshToDistanceVolumeParams()
        step = (np.asarray(upper) - np.asarray(lower)) / (np.asarray(shape) - 1)
        # MeshLib samples voxel centres: the origin half a step below the first point.
        params.vol.origin = mrmeshpy.Vector3f(*map(float, np.asarray(lower) - step / 2))
        params.vol.voxelSize = mrmeshpy.Vector3f(*map(float, step))
        params.vol.dimensions = mrmeshpy.Vector3i(*map(int, shape))
        params.dist.signMode = getattr(mrmeshpy.SignDetectionMode, mode)
        if band is not None:
            params.dist.maxDistSq = float(band) ** 2
        volume = mrmeshpy.meshToDistanceVolume(mrmeshpy.MeshPart(mesh), params)
        return mrmeshnumpy.getNumpy3Darray(volume.vol if hasattr(volume, "vol") else volume)

    return "meshlib", grid


#: Grids: ``name: (label, module, function(vertices, faces, lower, upper, shape, band) -> grid)``.
GRID_PEERS = {
    "meshlib-grid-normal": (
        "MeshLib meshToDistanceVolume, ProjectionNormal",
        *_meshlib_grid("ProjectionNormal"),
    ),
    "meshlib-grid-winding": ("MeshLib meshToDistanceVolume, WindingRule", *_meshlib_grid("WindingRule")),
}


#: ``name: (label, module, function(vertices, faces, points) -> signed distances, negative inside)``.
PEERS = {
    "libigl-pseudonormal": ("libigl signed_distance, pseudonormal", *_libigl("pseudonormal")),
    "libigl-fwn": ("libigl signed_distance, fast winding number", *_libigl("fwn")),
    "open3d": ("Open3D compute_signed_distance", "open3d", _open3d),
    "warp-normal": ("Warp mesh_query_point_sign_normal", *_warp("normal")),
    "warp-winding": ("Warp mesh_query_point_sign_winding_number", *_warp("winding")),
    "meshlib": ("MeshLib findSignedDistance, per point", "meshlib", _meshlib),
    "pysdf": ("pysdf SDF", "pysdf", _pysdf),
    "trimesh": ("trimesh.proximity.signed_distance", "trimesh", _trimesh),
}


def _timed(call, repeats=3):
    call()  # warm-up: compiles, loads
    times, answer = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        answer = call()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), answer


def grid_child(name, data_path):
    """Time grid peer ``name`` on the grid of ``data_path``, dense and banded; its record."""
    label, module, function = GRID_PEERS[name]
    try:
        __import__(module)
    except Exception as exc:  # an ImportError, or a library that fails as it loads
        return {"skipped": f"{module} does not import: {type(exc).__name__}: {exc}"}
    data = np.load(data_path)
    shape = tuple(int(n) for n in data["shape"])
    args = (data["vertices"], data["faces"], data["lower"], data["upper"], shape)
    record = {}
    for key, band in (("dense", None), ("band", float(data["band"]))):
        try:
            record[key] = {"seconds": _timed(lambda b=band: function(*args, b))[0]}
        except Exception as exc:  # noqa: BLE001  (a peer's failure is a result)
            record[key] = {"error": f"{type(exc).__name__}: {str(exc)[:200]}"}
    return record


def child(name, data_path, out_path):
    """Run peer ``name`` on every mesh of ``data_path``; its record as JSON, its answers to ``out_path``."""
    label, module, function = PEERS[name]
    try:
        __import__(module)
    except Exception as exc:  # an ImportError, or a library that fails as it loads
        return {"skipped": f"{module} does not import: {type(exc).__name__}: {exc}"}
    data = np.load(data_path)
    record, answers = {}, {}
    for key in sorted({k.rsplit(".", 1)[0] for k in data.files}):
        vertices, faces, points = data[f"{key}.vertices"], data[f"{key}.faces"], data[f"{key}.points"]
        try:
            seconds, answers[key] = _timed(lambda v=vertices, f=faces, p=points: function(v, f, p))
            record[key] = {"seconds": seconds}
        except Exception as exc:  # noqa: BLE001  (a peer's failure on one mesh is a result)
            record[key] = {"error": f"{type(exc).__name__}: {str(exc)[:200]}"}
    np.savez(out_path, **answers)
    return record


# -- the run ------------------------------------------------------------------------------


def _meshes(quick, seed):
    """``{name: (vertices, faces, points)}``."""
    n = 2_000 if quick else 20_000
    out = {}
    for name, (vertices, faces) in {**defective(), "torus": torus(40, 25)}.items():
        rng = np.random.default_rng(seed)
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        size = float(np.max(high - low))
        centre = (low + high) / 2
        box = centre + 1.2 * (rng.uniform(low, high, (n // 2, 3)) - centre)
        live = faces[_nonzero_area(vertices, faces)]
        near = near_points(rng, vertices, live, 3 * n // 10, 1e-3 * size)
        # Around edges (those of zero-area faces included), 1e-8 to 3e-8 of the size off them.
        m = n - n // 2 - 3 * n // 10
        edge = rng.integers(0, len(faces), m), rng.integers(0, 3, m)
        a, b = vertices[faces[edge[0], edge[1]]], vertices[faces[edge[0], (edge[1] + 1) % 3]]
        direction = rng.normal(size=(m, 3))
        direction *= (rng.uniform(1e-8, 3e-8, m) * size / np.linalg.norm(direction, axis=1))[:, None]
        close = a + rng.uniform(0, 1, (m, 1)) * (b - a) + direction
        out[name] = (vertices, faces, np.concatenate([box, near, close]))
    return out


def _nonzero_area(vertices, faces):
    tri = vertices[faces]
    return np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) > 0


def _truth(name, vertices, faces, points):
    """``(inside, judged)`` per point."""
    from proximity import TriangleMesh
    from proximity.testing import winding as exact_winding

    mesh = TriangleMesh(vertices, faces)
    size = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
    judged = np.asarray(mesh.distance(points)) > SIGN_BAND * size
    if mesh._hierarchy().integral:
        inside = np.zeros(len(points), dtype=bool)
        inside[judged] = exact_winding.winding_numbers(vertices, faces, points[judged]) != 0
        return inside, judged
    r = mesh.winding_number(points, full=True)
    return np.asarray(r.inside), judged & np.asarray(r.certain)


def run(quick=False, seed=0, out=Path("bench-results"), log=print):
    from proximity import TriangleMesh

    work = Path(out)
    work.mkdir(parents=True, exist_ok=True)
    meshes = _meshes(quick, seed)
    truth = {}
    raw = {"meta": {"command": "python -m benchmarks.signs" + (" --quick" if quick else ""), "seed": seed},
           "meshes": {}}  # fmt: skip
    for name, (vertices, faces, points) in meshes.items():
        start = time.perf_counter()
        truth[name] = _truth(name, vertices, faces, points)
        inside, judged = truth[name]
        raw["meshes"][name] = {"faces": len(faces), "points": len(points), "judged": int(judged.sum()),
                               "inside": int(inside[judged].sum()), "modes": {},
                               "reference_seconds": time.perf_counter() - start}  # fmt: skip
        for sign in ("auto", "pseudonormal", "winding"):
            entry = {}
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    mesh = TriangleMesh(vertices, faces)
                    mesh.signed_distance(points[:1], sign=sign)  # the tables, timed apart
                    seconds, signed = _timed(lambda m=mesh, s=sign, p=points: m.signed_distance(p, sign=s))
                    entry = {"seconds": seconds, "wrong": int(((signed < 0) != inside)[judged].sum())}
                except ValueError as exc:
                    entry = {"refused": str(exc)[:200]}
            entry["warned"] = [str(w.message)[:200] for w in caught if issubclass(w.category, RuntimeWarning)]
            raw["meshes"][name]["modes"][f"proximity {sign}"] = entry
        log(f"{name}: " + ", ".join(f"{k} {_brief(v)}" for k, v in raw["meshes"][name]["modes"].items()))
    data_path = work / "signs-data.npz"
    np.savez(data_path, **{f"{name}.{part}": array for name, (v, f, p) in meshes.items()
                           for part, array in (("vertices", v), ("faces", f), ("points", p))})  # fmt: skip
    for peer in PEERS:
        answers_path = work / f"signs-{peer}.npz"
        args = [sys.executable, "-m", "benchmarks.signs", "--child", peer, str(data_path), str(answers_path)]
        done = subprocess.run(args, capture_output=True, text=True, timeout=1800)
        try:
            record = json.loads(done.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            record = {"skipped": f"the child failed: {done.stderr.strip()[-300:]}"}
        if "skipped" in record:
            raw.setdefault("skipped", {})[peer] = record["skipped"]
            log(f"{peer}: skipped: {record['skipped']}")
            continue
        answers = np.load(answers_path)
        for name, entry in record.items():
            inside, judged = truth[name]
            if name in answers.files:
                signed = answers[name]
                entry["wrong"] = int((((signed < 0) != inside) | np.isnan(signed))[judged].sum())
            raw["meshes"][name]["modes"][PEERS[peer][0]] = entry
        answers_path.unlink()
        log(f"{peer}: " + ", ".join(f"{name} {_brief(entry)}" for name, entry in record.items()))
    data_path.unlink()
    raw["grid"] = run_grid(quick, work, log)
    (work / "signs.json").write_text(json.dumps(raw, indent=1), encoding="utf-8")
    return raw


def run_grid(quick, work, log=print):
    """``sdf_grid`` against the grid peers: a torus of 20,000 faces, dense and with a band of 2 steps."""
    from proximity import TriangleMesh

    vertices, faces = torus(100, 100)
    shape = (48, 48, 16) if quick else (128, 128, 40)
    lower, upper = np.array([-1.45, -1.45, -0.45]), np.array([1.45, 1.45, 0.45])
    band = 2.0 * float(np.max((upper - lower) / (np.array(shape) - 1)))
    record = {"faces": len(faces), "shape": list(shape), "band": band, "modes": {}}
    mesh = TriangleMesh(vertices, faces)
    mesh.sdf_grid(lower, upper, (4, 4, 4), sign="winding")  # the tables, timed apart
    for sign in ("auto", "winding"):
        for key, b in (("dense", None), ("band", band)):
            seconds, _ = _timed(
                lambda s=sign, b=b: mesh.sdf_grid(lower, upper, shape, max_distance=b, sign=s)
            )
            record["modes"].setdefault(f"proximity sdf_grid, sign={sign!r}", {})[key] = {"seconds": seconds}
    data_path = work / "grid-data.npz"
    np.savez(data_path, vertices=vertices, faces=faces, lower=lower, upper=upper, shape=shape, band=band)
    for peer in GRID_PEERS:
        args = [sys.executable, "-m", "benchmarks.signs", "--grid-child", peer, str(data_path)]
        done = subprocess.run(args, capture_output=True, text=True, timeout=1800)
        try:
            result = json.loads(done.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            result = {"skipped": f"the child failed: {done.stderr.strip()[-300:]}"}
        if "skipped" in result:
            record.setdefault("skipped", {})[peer] = result["skipped"]
        else:
            record["modes"][GRID_PEERS[peer][0]] = result
    data_path.unlink()
    for mode, entry in record["modes"].items():
        cells = ", ".join(f"{k} {1e3 * v.get('seconds', np.nan):.0f} ms" for k, v in entry.items())
        log(f"grid, {mode}: {cells}")
    return record


def _brief(entry):
    if "refused" in entry:
        return "refused"
    if "error" in entry:
        return "error"
    warned = " (warned)" if entry.get("warned") else ""
    return f"{entry['wrong']} wrong{warned}, {1e3 * entry['seconds']:.1f} ms"


def markdown(raw, path="docs/performance.md"):
    """The wrong-sign table: a row per mode, a column per mesh."""
    names = list(raw["meshes"])
    modes = []
    for entry in raw["meshes"].values():
        modes += [m for m in entry["modes"] if m not in modes]
    first = next(iter(raw["meshes"].values()))
    lines = [
        f"Wrong signs (of the points judged: farther than {SIGN_BAND:g} of the size from the surface) on "
        f"{first['points']:,} points per mesh (half uniform in 1.2 times the bounding box, 30% 1e-3 of the "
        "size off the surface, 20% 1e-8 to 3e-8 of the size off its edges), against the exact winding number "
        "(nonzero rule). *w*: warned; "
        "*refused*: a ValueError (the mesh is not closed). Time of the whole batch in ms, median of 3. "
        f"Made by `python -m benchmarks.signs --write {path}`.",
        "",
        "| mode | " + " | ".join(names) + " |",
        "|---|" + "---:|" * len(names),
        "| judged | " + " | ".join(f"{raw['meshes'][n]['judged']:,}" for n in names) + " |",
    ]
    for mode in modes:
        cells = []
        for name in names:
            entry = raw["meshes"][name]["modes"].get(mode)
            if entry is None:
                cells.append("")
            elif "refused" in entry:
                cells.append("refused")
            elif "error" in entry:
                cells.append("error")
            else:
                mark = " w" if entry.get("warned") else ""
                cells.append(f"{entry['wrong']:,}{mark} ({1e3 * entry['seconds']:.0f})")
        lines.append(f"| {mode} | " + " | ".join(cells) + " |")
    if raw.get("skipped"):
        skipped = "; ".join(f"{k} ({v[:80]})" for k, v in raw["skipped"].items())
        lines += ["", f"Not installed here: {skipped}"]
    grid = raw.get("grid")
    if grid:
        nx, ny, nz = grid["shape"]
        lines += [
            "",
            f"Signed distance grids: a torus of {grid['faces']:,} faces on a {nx} x {ny} x {nz} grid over "
            f"its box, every point (*dense*) and with a band of {grid['band']:.3g} (two steps), in ms, "
            "median of 3.",
            "",
            "| grid | dense | band |",
            "|---|---:|---:|",
        ]
        for mode, entry in grid["modes"].items():
            cells = [f"{1e3 * entry[k]['seconds']:.0f}" if "seconds" in entry.get(k, {}) else "error"
                     for k in ("dense", "band")]  # fmt: skip
            lines.append(f"| {mode} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--child"]:
        print(json.dumps(child(*argv[1:4])))
        return 0
    if argv[:1] == ["--grid-child"]:
        print(json.dumps(grid_child(*argv[1:3])))
        return 0
    parser = argparse.ArgumentParser(prog="python -m benchmarks.signs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("bench-results"))
    parser.add_argument("--write", metavar="PAGE", help="rewrite the sign-bench section of PAGE")
    args = parser.parse_args(argv)
    raw = run(quick=args.quick, seed=args.seed, out=args.out)
    text = markdown(raw, args.write or "docs/performance.md")
    print(text)
    if args.write:
        from benchmarks.meshes import write_section

        write_section(args.write, text, marker="sign-bench")
    return 0


if __name__ == "__main__":
    sys.exit(main())
