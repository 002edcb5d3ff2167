"""Speed of the compiled kernels, side by side with the libraries people use.

Every ratio is measured in one run, on the same inputs, from medians of at
least five repeats (three rounds of five for the batch rows); nothing is
compared with a number from another run.

    python -m benchmarks.speed [--quick] [--package-python PYTHON] [--json FILE] [--checks FILE]
                               [--strict] [--write docs/performance.md]

The table states what was measured: throughputs, their ratios, seconds and
megabytes.  The project's own targets for those figures (``target`` in each
row of ``--json``) are checked apart: ``--checks FILE`` writes the verdict on
each, and ``--strict`` makes a missed one exit with status 1.  ``--write``
rewrites the ``speed-table`` section of a page with the table and how it
was measured.

Rows:

1. 1M well-conditioned (point, triangle) pairs: ``closest_point`` and
   ``distance`` against ``trimesh.triangles.closest_point`` plus the norm.
   The certified method's throughput on the same pairs, as a fraction of
   robust's (at least 25%).
2. 1M points against one triangle: the same.
3. 1M points against one disk and one circle: against the vectorised NumPy
   formula (project onto the plane, then ``hypot``).  The same queries, and
   1M (point, disk) and (point, circle) pairs, against the streaming floor:
   a compiled loop on the same threads that reads the bytes the query reads
   (24 a point; 80 a pair: center, unit normal, radius and point) and
   writes the bytes it writes (8 for ``distance``, 58 for
   ``closest_point``), and does nothing else: the time the memory traffic
   alone takes (at least 62.5% of it).
4. One point against one prebuilt triangle in a Python loop: ``closest_point``
   against ``fcl.distance`` with a one-triangle ``BVHModel`` and a
   ``Sphere(0)`` moved to the point.
5. Construction: ``Triangle`` of 2M triangles and ``Disk`` of 2M disks from
   writeable C-contiguous float64 arrays, against one ``distance`` query on
   as many points (construction must not take longer).
6. Peak memory of a 10M-pair query, above its inputs, against the size of its
   outputs plus 64 MB.
7. Start-up: ``import proximity``, and a new process's first result with the
   compiled kernels cached on disk, beside the first result of a one-line
   cached Numba kernel (Numba's own start-up, the floor under ours).
8. Cold start: a new process with an empty cache directory, as after a
   fresh install: the first single-point result (at most 3 s), the first
   batch result of every shape and method (at most 6 s each), and the CPU
   time of ``python -m proximity.compile``, which compiles every kernel (at
   most 45 s).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numba
import numpy as np
from numba import prange

import proximity
from proximity.testing import scenes

REPEATS = 5
ROUNDS = 3


def median_times(fns, repeats=REPEATS, rounds=ROUNDS):
    """Median wall time of each function in ``fns`` (a dict), over
    ``rounds`` rounds of ``repeats`` timed calls each.

    In a round every function takes its turn: one untimed call, then its
    timed calls back to back, so that each is timed in the steady state of
    repeating itself, as a program calling it in a loop would see it.
    Alternating single calls of different functions would time each one
    right after the other's large temporaries were freed, on fresh pages,
    which are slow to write (see ``docs/performance.md``).  The rounds spread each
    function's calls over the whole measurement, so that a slow phase of the
    shared machine, which lasts seconds, slows both sides of a ratio rather
    than only the side timed during it.
    """
    runs = {name: [] for name in fns}
    for _ in range(rounds):
        for name, fn in fns.items():
            fn()
            for _ in range(repeats):
                start = time.perf_counter()
                fn()
                runs[name].append(time.perf_counter() - start)
    return {name: float(np.median(times)) for name, times in runs.items()}


def trimesh_pairs(vertices, points):
    """trimesh's vectorised closest point, plus the norm for the distance."""
    from trimesh.triangles import closest_point

    closest = closest_point(vertices, points)
    return closest, np.linalg.norm(points - closest, axis=1)


def numpy_round(center, normal, radius, points, disk):
    """Distance and closest point to a circle or disk, as a plain NumPy formula."""
    unit = normal / np.linalg.norm(normal)
    d = points - center
    h = d @ unit
    radial = d - h[:, None] * unit
    q = np.linalg.norm(radial, axis=1)
    distance = np.hypot(h, q - radius)
    closest = center + radius * radial / q[:, None]
    if disk:
        inside = q <= radius
        distance = np.where(inside, np.abs(h), distance)
        closest = np.where(inside[:, None], center + radial, closest)
    return distance, closest


def _row(name, ours, theirs, n, target, unit="queries/s"):
    return {
        "case": name,
        "ours": n / ours,
        "baseline": n / theirs,
        "ratio": theirs / ours,
        "target": target,
        "unit": unit,
    }


def triangle_rows(n, repeats):
    """Rows 1 and 2: pairs and one triangle against trimesh."""
    rows = []
    scene = scenes.well_conditioned(np.random.default_rng(0), n)
    one = np.broadcast_to(scene.vertices[0], scene.vertices.shape)
    for label, vertices, shape in (
        (f"{n:,} pairs", scene.vertices, proximity.Triangle(scene.vertices)),
        (f"{n:,} points, one triangle", one, proximity.Triangle(scene.vertices[0])),
    ):
        fns = {"trimesh": lambda v=vertices: trimesh_pairs(v, scene.points)}
        methods = ("robust", "eberly", "certified") if shape.batch_shape else ("robust", "eberly")
        for method in methods:
            for call in ("closest_point", "distance"):
                query = getattr(shape, call)
                fns[method, call] = lambda q=query, m=method: q(scene.points, method=m)
        times = median_times(fns, repeats)
        for method, target in (("robust", 15.0), ("eberly", 25.0)):
            for call in ("closest_point", "distance"):
                case = f"{label}: {method} {call} vs trimesh + norm"
                rows.append(_row(case, times[method, call], times["trimesh"], n, target))
        if shape.batch_shape:
            # The certified method's throughput, as a fraction of robust's.
            for call in ("closest_point", "distance"):
                ours, robust = times["certified", call], times["robust", call]
                rows.append(_row(f"{label}: certified {call} vs robust", ours, robust, n, 0.25))
    return rows


# The streaming floor of row 3: every loop reads each input byte of its
# query once and writes each output byte once, with one cheap operation
# per value so that nothing is optimised away.  One shape's parameters are
# read once; pairs read a row of each of the shape's arrays.


@numba.njit(parallel=True, cache=True)
def _stream(center, unit, radius, points, distance, sqr, point, feature, flag, height, radial):
    n = points.shape[0]
    if center.shape[0] == 1:
        cx, cy, cz, r = center[0, 0], center[0, 1], center[0, 2], radius[0]
        if sqr.shape[0] == 0:
            for i in prange(n):
                distance[i] = (points[i, 0] - cx) + (points[i, 1] - cy) + (points[i, 2] - cz)
        else:
            for i in prange(n):
                x, y, z = points[i, 0] - cx, points[i, 1] - cy, points[i, 2] - cz
                distance[i], sqr[i], height[i], radial[i] = x, y, z, r
                point[i, 0], point[i, 1], point[i, 2] = z, y, x
                feature[i], flag[i] = np.int8(x > r), y > r
    elif sqr.shape[0] == 0:
        for i in prange(n):
            x = points[i, 0] - center[i, 0] + unit[i, 0]
            y = points[i, 1] - center[i, 1] + unit[i, 1]
            z = points[i, 2] - center[i, 2] + unit[i, 2]
            distance[i] = x + y + z + radius[i]
    else:
        for i in prange(n):
            x = points[i, 0] - center[i, 0] + unit[i, 0]
            y = points[i, 1] - center[i, 1] + unit[i, 1]
            z = points[i, 2] - center[i, 2] + unit[i, 2]
            r = radius[i]
            distance[i], sqr[i], height[i], radial[i] = x, y, z, r
            point[i, 0], point[i, 1], point[i, 2] = z, y, x
            feature[i], flag[i] = np.int8(x > r), y > r


def streaming_floor(center, unit, radius, points, full):
    """The floor under a batch query of disks or circles: :func:`_stream`
    over outputs allocated once (the queries reuse theirs from the pool)."""
    n, m = len(points), len(points) if full else 0
    outputs = (
        np.empty(n), np.empty(m), np.empty((m, 3)), np.empty(m, np.int8), np.empty(m, np.bool_),
        np.empty(m), np.empty(m),
    )  # fmt: skip
    center, unit, radius = np.atleast_2d(center), np.atleast_2d(unit), np.atleast_1d(radius)
    return lambda: _stream(center, unit, radius, points, *outputs)


def round_rows(n, repeats):
    """Row 3: one disk and one circle against the NumPy formula, and one
    disk, one circle and pairs of each against the streaming floor."""
    rows = []
    scene = scenes.disk_well_conditioned(np.random.default_rng(1), n)
    center, normal, radius = scene.center[0], scene.normal[0], float(scene.radius[0])
    unit = scene.normal / np.linalg.norm(scene.normal, axis=1, keepdims=True)
    calls = ("distance", "closest_point")
    for kind, cls in (("disk", proximity.Disk), ("circle", proximity.Circle)):
        shape = cls(center, normal, radius)
        pairs = cls(scene.center, scene.normal, scene.radius)
        fns = {"numpy": lambda d=(kind == "disk"): numpy_round(center, normal, radius, scene.points, d)}
        for call in calls:
            one_query, pairs_query = getattr(shape, call), getattr(pairs, call)
            fns["one", call] = lambda q=one_query: q(scene.points)
            fns["pairs", call] = lambda q=pairs_query: q(scene.points)
            full = call == "closest_point"
            fns["one floor", call] = streaming_floor(center, unit[0], radius, scene.points, full)
            fns["pairs floor", call] = streaming_floor(scene.center, unit, scene.radius, scene.points, full)
        times = median_times(fns, repeats)
        for call in calls:
            case = f"{n:,} points, one {kind}: robust {call} vs NumPy formula"
            rows.append(_row(case, times["one", call], times["numpy"], n, 10.0))
        for which, label in (("one", f"{n:,} points, one {kind}"), ("pairs", f"{n:,} ({kind}, point) pairs")):
            for call in calls:
                case = f"{label}: robust {call} vs streaming floor"
                rows.append(_row(case, times[which, call], times[f"{which} floor", call], n, 0.625))
    return rows


def loop_row(n, repeats):
    """Row 4: the narrow-phase call in a Python loop, against fcl."""
    from benchmarks.meshes import fcl_loop

    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.2, 0.9, 0.1]])
    points = list(np.random.default_rng(2).uniform(-0.5, 1.5, size=(n, 3)))
    with_fcl = fcl_loop(vertices, np.array([[0, 1, 2]]), points)

    shape = proximity.Triangle(vertices)

    def method_form():
        for p in points:
            shape.closest_point(p)

    def function_form():
        closest_point = proximity.closest_point
        for p in points:
            closest_point(shape, p)

    # Calls this short are at the mercy of a busy moment on a shared machine,
    # so the loops take turns, each timed many times.  (Unlike the batch
    # rows, none leaves large temporaries behind to slow the others.)
    loops = {"fcl": with_fcl, "method": method_form, "function": function_form}
    times = {name: [] for name in loops}
    for fn in loops.values():
        fn()
    for _ in range(3 * repeats):
        for name, fn in loops.items():
            start = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - start)
    median = {name: float(np.median(t)) for name, t in times.items()}
    return [
        _row(
            f"one point, one prebuilt triangle, Python loop: {label} vs fcl.distance",
            median[name],
            median["fcl"],
            n,
            1.5,
            unit="calls/s",
        )
        for name, label in (
            ("method", "tri.closest_point(p)"),
            ("function", "proximity.closest_point(tri, p)"),
        )
    ]


def construction_rows(n, repeats):
    """Row 5: building a batch of shapes against one query on as many points."""
    rng = np.random.default_rng(4)
    vertices, points = rng.random((n, 3, 3)), rng.random((n, 3))
    center, normal, radius = rng.random((n, 3)), rng.random((n, 3)) + 0.1, rng.random(n)
    tri, disk = proximity.Triangle(vertices), proximity.Disk(center, normal, radius)
    times = median_times(
        {
            "Triangle": lambda: proximity.Triangle(vertices),
            "Triangle.distance": lambda: tri.distance(points),
            "Disk": lambda: proximity.Disk(center, normal, radius),
            "Disk.distance": lambda: disk.distance(points),
        },
        repeats,
    )
    return [
        _row(
            f"{n:,} {name.lower()}s, construction vs one distance query on as many points",
            times[name],
            times[f"{name}.distance"],
            n,
            1.0,
            unit="shapes/s",
        )
        for name in ("Triangle", "Disk")
    ]


_MEMORY_CHILD = """
import numpy as np, proximity
n = {n}
rng = np.random.default_rng(3)
vertices = rng.random((n, 3, 3))
points = rng.random((n, 3))
shape = proximity.Triangle(vertices)
proximity.Triangle(vertices[:1000]).closest_point(points[:1000])  # load the kernels before measuring
def rss(field):
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) * 1024 for line in f if line.startswith(field))
base = rss("VmRSS:")
with open("/proc/self/clear_refs", "w") as f:
    f.write("5")  # reset the peak to the current size
r = shape.closest_point(points)
# The result's fields (not the query a lazy normal keeps).
out = sum(np.asarray(v).nbytes for v in proximity.results.asdict(r).values())
print(base, rss("VmHWM:"), out)
"""


def memory_row(n):
    """Row 6: peak memory above the inputs, in a fresh process."""
    child = subprocess.run(
        [sys.executable, "-c", _MEMORY_CHILD.format(n=n)], capture_output=True, text=True, check=True
    )
    base, peak, outputs = map(int, child.stdout.split())
    extra = peak - base - outputs
    return {
        "case": f"peak memory of a {n:,}-pair query above inputs",
        "ours": (peak - base) / 2**20,
        "baseline": outputs / 2**20,
        "ratio": extra / 2**20,
        "target": 64.0,
        "unit": "MB (baseline: the outputs; ratio column: MB beyond the outputs)",
    }


def _process_time(code, env=None, python=sys.executable):
    """Wall time of a new process of ``python`` running ``code``: until it
    prints its first line (the result), and until it has exited."""
    start = time.perf_counter()
    child = subprocess.Popen([python, "-c", code + "; print(flush=True)"], stdout=subprocess.PIPE, env=env)
    child.stdout.readline()
    result = time.perf_counter() - start
    if child.wait():
        raise subprocess.CalledProcessError(child.returncode, code)
    return result, time.perf_counter() - start


def _seconds_row(case, seconds, limit):
    return {
        "case": case,
        "ours": seconds,
        "baseline": limit,
        "ratio": None if limit is None else seconds / limit,
        "target": None if limit is None else 1.0,
        "unit": "s (ratio column: fraction of the limit)",
    }


def _over_floor_row(case, seconds, floor):
    return {
        "case": case,
        "ours": seconds,
        "baseline": floor,
        "ratio": seconds - floor,
        "target": None,
        "unit": "s over Numba's own start-up",
    }


# A one-line parallel kernel, cached on disk like proximity's: a new process
# that imports NumPy and Numba and runs it pays for Numba's own start-up
# (importing it, setting up its compiler, launching its threads) and little
# else, so its time is the floor under any first result of a Numba library.
_FLOOR_MODULE = """
from numba import njit, prange, types


@njit(types.void(types.float64[::1]), parallel=True, cache=True)
def fill(out):
    for i in prange(out.shape[0]):
        out[i] = i
"""

_FIRST_RESULTS = {
    "first batch result (triangles, cache warm)": (
        "import numpy as np, proximity; proximity.Triangle(np.eye(3)).closest_point(np.zeros((10, 3)))"
    ),
    "first single-point result (cache warm)": (
        "import numpy as np, proximity; proximity.Triangle(np.eye(3)).closest_point(np.zeros(3))"
    ),
    "first batch result (disks, cache warm)": (
        "import numpy as np, proximity; "
        "proximity.Disk(np.zeros(3), np.ones(3), 1).closest_point(np.zeros((10, 3)))"
    ),
}


def _environment(python):
    """Numba's version in ``python``'s environment, and whether it has scipy."""
    code = (
        "import numba; from importlib.util import find_spec; "
        "print(numba.__version__, find_spec('scipy') is not None)"
    )
    out = subprocess.run([python, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return out[0], out[1] == "True"


def startup_rows(repeats, package_python=None):
    """Row 6: import time, first results with a warm cache, and Numba's own
    start-up for comparison.

    ``package_python`` is an interpreter whose environment holds the package
    and its dependencies alone (NumPy, Numba), as ``pip install proximity3d``
    gives them, with this environment's Numba; ``make bench`` makes one.
    The limits apply to its rows.
    Where this environment also holds scipy, as the benchmark's does for
    trimesh, Numba imports ``scipy.linalg`` while it sets up its compiler;
    its first results are printed beside Numba's own start-up in the same
    environment.  Without ``package_python``, this environment's rows carry
    the limits.

    ``import proximity`` is timed to the end of the process.  The first
    results are timed to the moment the child prints after its query, which
    is what the one-second limit is about; the time to exit after it (when
    the interpreter tears down the compiler's modules) is printed too, for
    the whole command.  The commands take turns, one process each per
    round, so that a slow phase of the machine slows them all alike, and in
    a new order each round (seeded), so that none always runs at the same
    point of a round or right after the same other one.
    """
    pythons = {"package": package_python or sys.executable}
    if package_python is not None:
        numba_version, has_scipy = _environment(package_python)
        here_numba_version, here_has_scipy = _environment(sys.executable)
        if has_scipy:
            raise ValueError(f"{package_python} has scipy installed: not the package alone")
        if numba_version != here_numba_version:
            # Each would find the other's cached kernels stale and compile
            # them again, inside the timed first results.
            raise ValueError(f"{package_python} has Numba {numba_version}, this environment another")
        pythons["here"] = sys.executable
    with tempfile.TemporaryDirectory() as floor_dir:
        with open(os.path.join(floor_dir, "numba_floor.py"), "w", encoding="utf-8") as f:
            f.write(_FLOOR_MODULE)
        floor = (
            f"import sys; sys.path.insert(0, {floor_dir!r}); "
            "import numpy as np, numba_floor; numba_floor.fill(np.zeros(10))"
        )
        commands = {("package", "import"): "import proximity"}
        for where in pythons:
            commands.update({(where, label): code for label, code in _FIRST_RESULTS.items()})
            commands[where, "floor"] = floor
        for (where, _), code in commands.items():
            _process_time(code, python=pythons[where])  # warm the on-disk caches
        times = {key: [] for key in commands}
        keys, rng = list(commands), np.random.default_rng(0)
        for _ in range(repeats):
            for i in rng.permutation(len(keys)):
                where, label = keys[i]
                times[where, label].append(_process_time(commands[where, label], python=pythons[where]))
    first = {key: float(np.median([t[0] for t in ts])) for key, ts in times.items()}

    alone = "" if package_python is None else "package alone: "
    rows = [
        _seconds_row(
            f"{alone}python -c 'import proximity'",
            float(np.median([t[1] for t in times["package", "import"]])),
            0.5,
        )
    ]
    rows += [
        _seconds_row(f"{alone}new process, {label}", first["package", label], 1.0) for label in _FIRST_RESULTS
    ]
    rows.append(
        _seconds_row(
            f"{alone}new process, first result of a one-line cached Numba kernel (Numba's own start-up)",
            first["package", "floor"],
            None,
        )
    )
    exits = [t[1] for label in _FIRST_RESULTS for t in times["package", label]]
    rows.append(
        _seconds_row(
            f"{alone}the same three commands, to the end of the process", float(np.median(exits)), None
        )
    )
    if package_python is not None:
        scipy = "with" if here_has_scipy else "without"
        for label in _FIRST_RESULTS:
            case = f"this environment ({scipy} scipy): new process, {label}"
            rows.append(_over_floor_row(case, first["here", label], first["here", "floor"]))
    return rows


_COLD_SHAPES = {
    "triangles, pairs": "proximity.Triangle(np.eye(3) + np.zeros((10, 1, 1)))",
    "one disk": "proximity.Disk(np.zeros(3), np.ones(3), 1.0)",
    "circles, pairs": "proximity.Circle(np.zeros((10, 3)), np.ones(3), 1.0)",
    "mesh": "proximity.TriangleMesh(np.eye(3), [[0, 1, 2]])",
}


def _cold(code, python=sys.executable):
    """``(wall seconds to the first result, CPU seconds to the end)`` of a new
    process running ``code`` with an empty cache directory."""
    with tempfile.TemporaryDirectory() as cache:
        # Without the line a cold first query prints on stderr: it would be in
        # the step's output once per row.
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PROXIMITY_QUIET="1")
        before = os.times()
        wall, _ = _process_time(code, env, python)
        after = os.times()
    return wall, (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )


def cold_rows(quick=False, python=sys.executable):
    """Row 7: first results and compiling everything, each in a new process
    with an empty cache; one run each (each takes seconds)."""
    rows = [
        _seconds_row(
            "empty cache: first single-point result (triangle)",
            _cold(
                "import numpy as np, proximity; proximity.Triangle(np.eye(3)).closest_point(np.zeros(3))",
                python,
            )[0],
            3.0,
        )
    ]
    methods = ["robust"] if quick else list(proximity.methods.REGISTRY)
    for method in methods:
        for label, shape in _COLD_SHAPES.items():
            code = (
                f"import numpy as np, proximity; {shape}.closest_point(np.zeros((10, 3)), method={method!r})"
            )
            rows.append(
                _seconds_row(
                    f"empty cache: first batch result ({label}, {method})", _cold(code, python)[0], 6.0
                )
            )
    if not quick:
        cpu = _cold("import proximity.compile; proximity.compile.compile_all(log=None)", python)[1]
        rows.append(_seconds_row("empty cache: python -m proximity.compile, CPU time", cpu, 45.0))
    return rows


def passed(row):
    """Whether a row meets its target (None where there is none)."""
    if row["target"] is None:
        return None
    if row["unit"].startswith("MB"):
        return row["ratio"] <= row["target"]
    if row["unit"].startswith("s "):
        return row["ratio"] <= 1.0
    return row["ratio"] >= row["target"]


def format_table(rows):
    """The rows as a markdown table: what was measured, and nothing of the targets."""
    lines = ["| case | proximity | baseline | ratio |", "|---|---:|---:|---:|"]
    for row in rows:
        unit = row["unit"]
        if unit in ("queries/s", "calls/s", "shapes/s"):
            ours, base = f"{row['ours'] / 1e6:.2f} M{unit}", f"{row['baseline'] / 1e6:.3f} M{unit}"
            ratio = f"{row['ratio']:.2f}x"
        elif unit.startswith("MB"):
            ours, base = f"{row['ours']:.0f} MB", f"outputs {row['baseline']:.0f} MB"
            ratio = f"{row['ratio']:+.1f} MB"
        elif unit.startswith("s over"):
            ours, base = f"{row['ours']:.2f} s", f"Numba alone {row['baseline']:.2f} s"
            ratio = f"{row['ratio']:+.2f} s"
        else:
            ours, base, ratio = f"{row['ours']:.2f} s", "", ""
        lines.append(f"| {row['case']} | {ours} | {base} | {ratio} |")
    return "\n".join(lines)


def _target_text(row):
    if row["unit"].startswith("MB"):
        return f"at most +{row['target']:g} MB beyond the outputs", f"{row['ratio']:+.1f} MB"
    if row["unit"].startswith("s "):
        return f"at most {row['baseline']:g} s", f"{row['ours']:.2f} s"
    return f"at least {row['target']:g}x", f"{row['ratio']:.2f}x"


def checks(rows):
    """The project's targets for the rows: ``(missed, lines)``, a line per row that has one."""
    lines, missed = [], 0
    for row in rows:
        verdict = passed(row)
        if verdict is None:
            continue
        missed += not verdict
        target, value = _target_text(row)
        lines.append(f"{'met   ' if verdict else 'MISSED'}  {row['case']}: {value} (target {target})")
    return missed, lines


def provenance(quick, package_python):
    """How and where the table was measured: the paragraph above it on the page."""
    import datetime
    import platform

    import numba

    load = ", ".join(f"{x:.1f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    command = "python -m benchmarks.speed" + (" --quick" if quick else "")
    where = " (start-up rows: the package alone, as `make bench` sets it up)" if package_python else ""
    return (
        f"Measured by `{command}`{where} on {datetime.date.today().isoformat()}: {os.cpu_count()} cores "
        f"(load average {load} at the end), Python {platform.python_version()}, NumPy {np.__version__}, "
        f"Numba {numba.__version__}. Each batch row is the median of {ROUNDS} rounds of "
        f"{3 if quick else REPEATS} timed calls, in which every function of the row takes a turn (an "
        "untimed call, then its timed ones); the Python loops alternate with fcl; the start-up "
        "commands take turns, one new process each, in a new order each round; each empty-cache row is "
        "one new process with an empty cache directory. Every ratio compares two timings of the same run."
    )


def write_section(path, text, marker="speed-table"):
    """Replace the text between the ``marker`` markers of the page at ``path``."""
    import re
    from pathlib import Path

    page = Path(path).read_text(encoding="utf-8")
    pattern = re.compile(rf"(<!-- {marker}:start -->\n).*?(<!-- {marker}:end -->)", re.S)
    if not pattern.search(page):
        raise SystemExit(f"{path} has no {marker} markers")
    page = pattern.sub(lambda m: m.group(1) + text + "\n" + m.group(2), page)
    Path(path).write_text(page, encoding="utf-8")


def run(quick=False, package_python=None):
    """Measure every row; ``quick`` shrinks the sizes for a smoke run."""
    n = 100_000 if quick else 1_000_000
    repeats = 3 if quick else REPEATS
    rows = triangle_rows(n, repeats) + round_rows(n, repeats)
    rows += loop_row(2_000 if quick else 20_000, repeats)
    rows += construction_rows(200_000 if quick else 2_000_000, repeats)
    rows.append(memory_row(1_000_000 if quick else 10_000_000))
    rows += startup_rows(3 if quick else REPEATS, package_python)
    rows += cold_rows(quick, package_python or sys.executable)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    parser.add_argument("--json", help="also write the rows to this file")
    parser.add_argument(
        "--package-python",
        metavar="PYTHON",
        help="an interpreter with the package and its dependencies alone, for the start-up rows",
    )
    parser.add_argument("--checks", metavar="FILE", help="write the verdict on each of the project's targets")
    parser.add_argument("--strict", action="store_true", help="exit with status 1 if a target is missed")
    parser.add_argument("--write", metavar="PAGE", help="rewrite the speed-table section of PAGE")
    args = parser.parse_args(argv)
    rows = run(args.quick, args.package_python)
    text = format_table(rows)
    repeats = 3 if args.quick else REPEATS
    header = (
        f"numba threads: {proximity_threads()}; batch rows: median of {ROUNDS} rounds x {repeats} repeats, "
        f"Python loop: {3 * repeats} alternations\n\n"
    )
    print(header + text)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(rows, f, indent=1)
    if args.write:
        write_section(args.write, provenance(args.quick, args.package_python) + "\n\n" + text)
    missed, lines = checks(rows)
    if args.checks:
        with open(args.checks, "w", encoding="utf-8") as f:
            f.write("\n".join(lines) + "\n")
    if args.strict and missed:
        print(f"{missed} of the project's {len(lines)} targets missed", file=sys.stderr)
        return 1
    return 0


def proximity_threads():
    """Threads the compiled kernels run on."""
    import numba

    return numba.get_num_threads()


if __name__ == "__main__":
    sys.exit(main())
