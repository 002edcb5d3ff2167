"""The benchmark runner: every method and backend on every scene family, in one run.

For each query type (triangle, disk, circle) and each family of
:mod:`proximity.testing.scenes`, the runner measures every *entity*: proximity's
methods (whatever ``shape.methods`` offers) and every installed adapter
backend (:mod:`proximity.adapters`, plus trimesh on the caller's coordinates,
``trimesh[raw]``).  Three measurements, kept apart:

accuracy
    One seeded batch per family (the scene :mod:`benchmarks.accuracy` uses
    for the same seed and size), answered by every entity.  The exact
    reference is computed once per family and shared.  Errors are recorded
    per query in two units: ulps of ``d*`` and ``eps * S``.  Rows with no
    answer are recorded by reason (NaN, inf, exception for proximity; the
    :class:`proximity.adapters.Failure` code for backends) and get no error.
throughput
    A second seeded batch of the same family, timed with nothing else in
    the loop: the median over repeats of one ``closest_point`` call on ``n``
    queries, with ``n`` grown until a call takes a target time (up to half
    a million queries for proximity's batch kernels, a few thousand for the
    libraries, which mostly loop in Python).
tessellation
    Circles and disks of radius 1 asked of the backends that cut them into
    ``K`` segments, for a sweep of ``K``: error and time per query.

:func:`run` returns everything as one JSON-ready dict (schema in
:func:`run`); :func:`save` writes it.  Charts and the report are drawn from
the saved file only.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
import time
from contextlib import ExitStack
from pathlib import Path

import numba
import numpy as np

import proximity
from benchmarks import accuracy
from proximity import adapters
from proximity.testing import accuracy as testing_accuracy
from proximity.testing import scenes

SCHEMA = 1

EPS = 2.0**-52

#: The bound each of proximity's methods is counted against, as ``(unit,
#: limit)``: ``certified`` promises a faithfully rounded distance, less than
#: one ulp of ``d*`` from it; the others are held to robust's contract,
#: ``|d - d*| <= 8 eps S``, which ``eberly`` does not make, so that the
#: report shows where it breaks it.
METHOD_BOUNDS = {"certified": ("error_ulps", 1.0)}
DEFAULT_BOUND = ("error_eps_s", 8.0)

#: Query types and the families asked of each; disks and circles share scenes.
GROUPS = (
    ("triangle", scenes.TRIANGLE_FAMILIES),
    ("disk", scenes.DISK_FAMILIES),
    ("circle", scenes.DISK_FAMILIES),
)

#: Seed streams: the accuracy scene uses ``default_rng(seed)`` as
#: :func:`benchmarks.accuracy.measure` does; the others are independent.
TIMING_STREAM = 1
TESSELLATION_STREAM = 2

#: Per-method counters, recorded under ``"extra"`` of each accuracy record:
#: ``{method: callable() -> {name: int}}``, cumulative counts that are read
#: before and after the method answers the accuracy batch; the record holds
#: the difference.  This is the hook for methods that report how they
#: answered, such as the certified method's exact fallbacks.
DIAGNOSTICS = {}
if hasattr(proximity, "certified_stats"):
    DIAGNOSTICS["certified"] = proximity.certified_stats


@dataclasses.dataclass(frozen=True)
class Config:
    """Sizes of one run.

    Attributes
    ----------
    n_accuracy : int
        Queries per family in the accuracy batch.
    scene : int
        Queries generated per family for timing.
    batch : int
        Queries per timed call of proximity's batch kernels: the timing
        scene repeated (generating a million queries per family would cost
        more than timing them).
    call_max : int
        Most queries per timed call of a backend.
    target_seconds : float
        Aim for one timed repeat of a backend: the number of queries grows
        until a call takes this long, up to ``call_max``.
    method_seconds : float
        The same for proximity's methods, up to ``batch`` queries.
    repeats : int
        Timed repeats; the median is reported.
    segments : tuple of int
        The ``K`` of the tessellation sweep.
    n_tessellation : int
        Queries per ``K``.
    tessellation_budget : float
        Seconds one accuracy call of the sweep may take before larger ``K``
        are skipped for that backend.
    seed : int
        Seed of every scene.
    quick : bool
        Whether this is the smoke run; recorded with the results.
    """

    n_accuracy: int = testing_accuracy.N
    scene: int = 1 << 17
    batch: int = 1 << 19
    call_max: int = 4096
    target_seconds: float = 0.02
    method_seconds: float = 0.03
    repeats: int = 5
    segments: tuple = (6, 12, 24, 48, 96, 192, 384, 768, 1536, 3072)
    n_tessellation: int = 32
    tessellation_budget: float = 2.0
    seed: int = testing_accuracy.SEED
    quick: bool = False


DEFAULT = Config()
#: The smoke run: fewer queries for accuracy, smaller batches for proximity's
#: kernels, the tessellation sweep cut short; the libraries are timed as in
#: the full run (``call_max``, ``target_seconds``), so that their speeds
#: compare across the two (calls of a few queries measure the cost of a call).
QUICK = Config(
    n_accuracy=16,
    scene=1 << 12,
    batch=1 << 14,
    method_seconds=0.005,
    repeats=3,
    segments=(8, 64, 512),
    n_tessellation=8,
    tessellation_budget=0.3,
    quick=True,
)


# -- entities ------------------------------------------------------------------


def _open_backends(stack):
    """``{name: backend}`` for every installed library, trimesh twice; closed by ``stack``."""
    backends = {}
    for name in adapters.available():
        backends[name] = stack.enter_context(adapters.get(name))
        if name == "trimesh":
            raw = stack.enter_context(adapters.get("trimesh", rescale=False))
            backends[raw.name] = raw
    return backends


def _methods(kind):
    """proximity's methods for a query type, as the shape offers them."""
    scene = scenes.well_conditioned(np.random.default_rng(0), 1)
    if kind != "triangle":
        scene = scenes.disk_well_conditioned(np.random.default_rng(0), 1)
    return tuple(accuracy.shape_of(kind, scene).methods)


# -- measurements ----------------------------------------------------------------


def _head(scene, n):
    """The first ``n`` queries of a scene."""
    return type(scene)(**{f.name: getattr(scene, f.name)[:n] for f in dataclasses.fields(scene)})


def _finite_list(values):
    """A JSON list: floats, None where not finite."""
    return [float(x) if np.isfinite(x) else None for x in np.asarray(values, dtype=np.float64)]


def _errors_record(distance, ref, failed, tolerance=None, bound=DEFAULT_BOUND):
    """Errors of the answered rows and the rows beyond the bound or tolerance.

    ``tolerance`` is a per-row absolute error allowed (a backend's); else
    ``bound`` is ``(unit, limit)``, a limit on one of the two errors.

    ``failed`` maps a reason to row indices; those rows get no error.  An
    answered row whose error is not finite (only possible with ``S == 0``)
    is stored as None among answered rows.
    """
    distance = np.array(distance, dtype=np.float64)
    bad = np.zeros(len(distance), dtype=bool)
    for rows in failed.values():
        bad[rows] = True
    distance[bad] = np.nan
    in_s = accuracy.errors(distance, ref)
    in_ulps = accuracy.ulp_errors(distance, ref)
    scale = np.array([float(s) for _, s in ref])
    if tolerance is not None:
        beyond = ~bad & (in_s * EPS * scale > np.asarray(tolerance))
    else:
        unit, limit = bound
        beyond = ~bad & ((in_s if unit == "error_eps_s" else in_ulps) > limit)
    return {
        "answered": int((~bad).sum()),
        "failed": {reason: [int(i) for i in rows] for reason, rows in failed.items() if len(rows)},
        "beyond_bound": int(beyond.sum()),
        "error_eps_s": _finite_list(np.where(bad, np.nan, in_s)),
        "error_ulps": _finite_list(np.where(bad, np.nan, in_ulps)),
    }


def _method_accuracy(kind, scene, ref, method):
    shape = accuracy.shape_of(kind, scene)
    n = len(scene.points)
    bound = METHOD_BOUNDS.get(method, DEFAULT_BOUND)
    counters = DIAGNOSTICS.get(method)
    before = counters() if counters else None
    try:
        distance = np.asarray(shape.closest_point(scene.points, method=method).distance)
    except Exception as exc:  # recorded as the failure of every row, with its message
        failed = {"EXCEPTION": np.arange(n)}
        record = _errors_record(np.full(n, np.nan), ref, failed, bound=bound)
        record["exception"] = f"{type(exc).__name__}: {exc}"
        return record
    failed = {"NAN": np.flatnonzero(np.isnan(distance)), "INF": np.flatnonzero(np.isinf(distance))}
    record = _errors_record(distance, ref, failed, bound=bound)
    record["bound"] = f"{bound[1]:g} {'eps S' if bound[0] == 'error_eps_s' else 'ulp of d*'}"
    if counters:
        after = counters()
        record["extra"] = {key: after[key] - before.get(key, 0) for key in after}
    return record


def _backend_accuracy(kind, scene, ref, backend):
    shape = accuracy.shape_of(kind, scene)
    n = len(scene.points)
    try:
        r = backend.closest_point(shape, scene.points)
    except Exception as exc:  # recorded as the failure of every row, with its message
        failed = {"EXCEPTION": np.arange(n)}
        record = _errors_record(np.full(n, np.nan), ref, failed, tolerance=np.zeros(n))
        record["exception"] = f"{type(exc).__name__}: {exc}"
        return record
    failure = np.asarray(r.failure)
    failed = {
        adapters.Failure(code).name: np.flatnonzero(failure == code)
        for code in np.unique(failure)
        if code != adapters.Failure.OK
    }
    record = _errors_record(r.distance, ref, failed, tolerance=r.tolerance)
    record["bound"] = "documented tolerance"
    record["model"] = r.model.describe()
    return record


@contextlib.contextmanager
def quiet_libraries():
    """Send what the libraries print (file descriptors 1 and 2) to /dev/null for the duration.

    pybullet's C code prints a line ("eigen: too many iterations in Jacobi
    transform") for every degenerate triangle it is given, ten thousand in
    a run, through the progress bar.  What matters of a library's trouble
    is recorded: failures per row, and the message of any exception.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(fd) for fd in (1, 2)]
    try:
        with open(os.devnull, "w") as devnull:
            for fd in (1, 2):
                os.dup2(devnull.fileno(), fd)
        yield
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)


@contextlib.contextmanager
def serial_numba():
    """Run proximity's kernels on one thread for the duration.

    Every backend call also calls proximity, to translate and check the
    library's answers; on a loaded machine waking the kernels' worker
    threads for those few rows costs milliseconds, more than the library's
    own work.  The libraries run on one thread anyway.
    """
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(threads)


def timed(call, n, repeats):
    """``{"n", "repeats", "seconds", "qps"}``: the median of ``repeats`` timed calls."""
    seconds = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        seconds.append(time.perf_counter() - start)
    return {"n": int(n), "repeats": int(repeats), "seconds": seconds, "qps": n / float(np.median(seconds))}


def _tile(scene, n):
    """The scene's queries repeated to ``n`` rows."""
    reps = -(-n // len(scene.points))
    return type(scene)(
        **{f.name: np.concatenate([getattr(scene, f.name)] * reps)[:n] for f in dataclasses.fields(scene)}
    )


def _calibrated(make_call, start, cap, target, repeats):
    """Time ``make_call(n)()`` at the ``n`` whose call takes about ``target`` seconds.

    ``n`` grows from ``start`` (doubling, or faster while calls are much too
    short) until a call takes ``target`` or ``n`` reaches ``cap``; those
    calls also warm the caches.  Growing, rather than extrapolating from one
    small call, matters on a loaded machine: there a call to a parallel
    kernel costs at least a scheduler tick (4 ms) whatever its size, and a
    small probe would make a fast kernel look a hundred times slower.
    """
    n = start
    while True:
        call = make_call(n)
        begin = time.perf_counter()
        call()
        elapsed = time.perf_counter() - begin
        if elapsed >= target or n >= cap:
            break
        n = min(cap, n * int(np.clip(target / max(elapsed, 1e-9), 2, 16)))
    return timed(call, n, repeats)


def _method_timing(kind, scene, method, config):
    """Time a method on up to all the queries of ``scene`` (fewer where it is slow).

    A method with an exact fallback, on a family that needs it everywhere,
    answers a few thousand queries a second: a million would take minutes.
    """

    def make_call(n):
        part = _head(scene, n)
        shape = accuracy.shape_of(kind, part)
        return lambda: shape.closest_point(part.points, method=method)

    try:
        make_call(1)()  # loads (or compiles) the kernels
    except Exception:
        return None  # the accuracy record holds the message
    return _calibrated(make_call, 64, len(scene.points), config.method_seconds, config.repeats)


def _backend_timing(kind, scene, backend, config):
    """Time a backend on as many queries as take about ``config.target_seconds``."""

    def make_call(n):
        part = _head(scene, n)
        shape = accuracy.shape_of(kind, part)
        return lambda: backend.closest_point(shape, part.points)

    try:
        make_call(1)()  # imports and warms the library
    except Exception:
        return None  # the accuracy record holds the message
    return _calibrated(make_call, 8, config.call_max, config.target_seconds, config.repeats)


def _family(kind, index, family, entities, backends, config, bar):
    """The record of one family: the exact reference and every entity's accuracy and timing."""
    scene = family(np.random.default_rng(config.seed), config.n_accuracy)
    bar.set_postfix_str(f"{kind} {family.label}: exact reference", refresh=False)
    start = time.perf_counter()
    ref = accuracy.reference(kind, scene)
    reference_seconds = time.perf_counter() - start
    bar.update(1)
    timing_scene = family(np.random.default_rng([config.seed, TIMING_STREAM, index]), config.scene)
    batch = _tile(timing_scene, config.batch)
    results = {}
    for name, entity_type in entities:
        bar.set_postfix_str(f"{kind} {family.label}: {name}", refresh=False)
        start = time.perf_counter()
        if entity_type == "method":
            record = _method_accuracy(kind, scene, ref, name)
            record["timing"] = _method_timing(kind, batch, name, config)
        else:
            with serial_numba(), quiet_libraries():
                record = _backend_accuracy(kind, scene, ref, backends[name])
                record["timing"] = _backend_timing(kind, timing_scene, backends[name], config)
        # What this entity cost the run, accuracy and timing together: for keeping the run short.
        record["step_seconds"] = time.perf_counter() - start
        results[name] = record
        bar.update(1)
    return {
        "kind": kind,
        "family": family.label,
        "name": family.name,
        "params": dict(family.params),
        "difficulty": family.difficulty,
        "n": len(scene.points),
        "seed": config.seed,
        "reference_seconds": reference_seconds,
        "d_exact": [float(d) for d, _ in ref],
        "scale": [float(s) for _, s in ref],
        "results": results,
    }


def sagitta(radius, segments):
    """``R (1 - cos(pi / K))``, the distance from a circle to its inscribed ``K``-gon.

    Written as ``2 R sin^2(pi / 2K)``: the cosine form cancels for large ``K``.
    """
    s = np.sin(np.pi / (2.0 * segments))
    return float(2.0 * radius * s * s)


def _unit_radius(scene):
    """Each row of a disk scene scaled about its center to radius 1 (the geometry is unchanged)."""
    factor = 1.0 / scene.radius[:, None]
    points = scene.center + (scene.points - scene.center) * factor
    return scenes.DiskScene(scene.center, scene.normal, np.ones(len(scene.radius)), points)


def _tessellation(backends, config, bar):
    """Error and cost against the number of segments ``K``, for backends that tessellate."""
    rng = np.random.default_rng([config.seed, TESSELLATION_STREAM])
    scene = _unit_radius(scenes.disk_well_conditioned(rng, config.n_tessellation))
    records = []
    for kind in ("disk", "circle"):
        shape = accuracy.shape_of(kind, scene)
        ref = accuracy.reference(kind, scene)
        scale = np.array([float(s) for _, s in ref])
        robust = shape.closest_point(scene.points).distance
        records.append(
            {
                "kind": kind,
                "entity": "robust",
                "segments": None,
                "n": len(scene.points),
                "error": _finite_list(accuracy.errors(robust, ref) * EPS * scale),
            }
        )
        for name, backend in backends.items():
            # trimesh[raw] models a unit circle as trimesh does: once is enough.
            if name not in adapters.NAMES or kind not in getattr(backend, "tessellated", ()):
                continue
            too_slow = False
            for k in config.segments:
                bar.set_postfix_str(f"tessellation: {name} {kind} K={k}", refresh=False)
                if too_slow:
                    records.append({"kind": kind, "entity": name, "segments": k, "skipped": "too slow"})
                    bar.update(1)
                    continue
                # The sagitta of K segments, a hair above so that rounding cannot ask for K + 1.
                tol = sagitta(1.0, k) * (1 + 1e-9)
                with serial_numba(), quiet_libraries():
                    start = time.perf_counter()
                    r = backend.closest_point(shape, scene.points, tol=tol)
                    elapsed = time.perf_counter() - start
                    n = int(
                        np.clip(config.target_seconds * len(scene.points) / elapsed, 2, len(scene.points))
                    )
                    part = _head(scene, n)
                    part_shape = accuracy.shape_of(kind, part)
                    timing = timed(
                        lambda b=backend, s=part_shape, p=part.points, t=tol: b.closest_point(s, p, tol=t),
                        n,
                        max(3, config.repeats - 2),
                    )
                too_slow = elapsed > config.tessellation_budget
                failure = np.asarray(r.failure)
                distance = np.where(failure == adapters.Failure.OK, r.distance, np.nan)
                records.append(
                    {
                        "kind": kind,
                        "entity": name,
                        "segments": int(np.max(r.model.segments)),
                        "tol": tol,
                        "bound": float(np.max(r.model.bound)),
                        "n": len(scene.points),
                        "failed": int((failure != adapters.Failure.OK).sum()),
                        "error": _finite_list(accuracy.errors(distance, ref) * EPS * scale),
                        "timing": timing,
                    }
                )
                bar.update(1)
    return records


# -- the run ------------------------------------------------------------------------


def _cpu():
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _load():
    """The 1-minute load average, or None where the system does not tell."""
    try:
        return round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        return None


def _git_commit():
    root = Path(__file__).resolve().parent.parent
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return commit + ("+changes" if dirty else "")


def _version(distribution):
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None


def _meta(config, backends, entities):
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": "python -m benchmarks" + (" --quick" if config.quick else ""),
        "config": dataclasses.asdict(config),
        "machine": {
            "cpu": _cpu(),
            "cores": os.cpu_count(),
            "numba_threads": numba.get_num_threads(),
            "platform": platform.platform(),
            "python": platform.python_version(),
        },
        "versions": {
            "proximity": proximity.__version__,
            "commit": _git_commit(),
            "numpy": np.__version__,
            "numba": _version("numba"),
            **{name: backend.library for name, backend in backends.items()},
        },
        "entities": entities,
        "timed": "closest_point on the whole batch; backends include building the library's model "
        "for each shape and the adapter's translation, with proximity's kernels on one thread",
    }


def run(config=DEFAULT, progress=True):
    """Run the suite.

    Parameters
    ----------
    config : Config
        Sizes; :data:`DEFAULT` or :data:`QUICK`.
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    dict
        JSON-ready: ``schema``; ``meta`` (date, command, config, machine,
        versions, ``entities`` as ``{kind: [[name, "method" | "backend"]]}``,
        ``wall_seconds``); ``families``, one record per (kind, family) with
        ``d_exact``, ``scale`` (floats, per row), ``reference_seconds`` and
        ``results[entity]`` holding ``answered``, ``failed`` (``{reason:
        [row, ...]}``), ``bound`` and ``beyond_bound``, ``error_eps_s`` and
        ``error_ulps`` (per row, None where failed), ``timing`` (``n``,
        ``repeats``, ``seconds``, ``qps``; None if the entity raised, with
        the message in ``exception``), ``step_seconds``, ``extra`` (the
        method's counters, see :data:`DIAGNOSTICS`) and, for backends,
        ``model``; ``tessellation``, one record per (kind, backend, K) with
        the absolute ``error`` per row (radius 1), ``bound`` (the sagitta)
        and ``timing``, or ``skipped``.
    """
    from tqdm import tqdm

    start = time.perf_counter()
    load_before = _load()
    with ExitStack() as stack:
        # The libraries' own NumPy arithmetic warns on the inputs built to
        # break it (trimesh on degenerate triangles); the failures are measured.
        stack.enter_context(np.errstate(all="ignore"))
        with quiet_libraries():
            backends = _open_backends(stack)
        entities = {
            kind: [[m, "method"] for m in _methods(kind)] + [[b, "backend"] for b in backends]
            for kind, _ in GROUPS
        }
        tessellating = sum(
            kind in getattr(b, "tessellated", ())
            for name, b in backends.items()
            if name in adapters.NAMES
            for kind in ("disk", "circle")
        )
        total = sum(len(families) * (1 + len(entities[kind])) for kind, families in GROUPS)
        total += tessellating * len(config.segments)
        bar = tqdm(total=total, file=sys.stderr, disable=not progress, unit="step", desc="benchmarks")
        stack.callback(bar.close)
        families = []
        for kind, registry in GROUPS:
            for index, family in enumerate(registry):
                families.append(_family(kind, index, family, entities[kind], backends, config, bar))
        tessellation = _tessellation(backends, config, bar)
        meta = _meta(config, backends, entities)
    meta["wall_seconds"] = time.perf_counter() - start
    # The machine may be shared: its load says how far to trust the timings.
    meta["machine"]["load_average"] = {"before": load_before, "after": _load()}
    return {"schema": SCHEMA, "meta": meta, "families": families, "tessellation": tessellation}


def save(raw, path):
    """Write the raw results as JSON (strict: no NaN or inf)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(raw, f, allow_nan=False, separators=(",", ":"))
        f.write("\n")


def load(path):
    """Read raw results written by :func:`save`."""
    with open(path, encoding="utf-8") as f:
        raw = json.load(f)
    if raw.get("schema") != SCHEMA:
        raise ValueError(f"{path}: raw results of schema {raw.get('schema')!r}, expected {SCHEMA}")
    return raw
