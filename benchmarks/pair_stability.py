"""Stability of the primitive pairs: the worst error along sweeps of the pair scene families,
proximity's methods against python-fcl and coal.

    python -m benchmarks.pair_stability [--quick] [--seed 0] [--out DIR] [--report-only] [--publish]

``python -m benchmarks`` (what ``make bench`` runs) runs it as a step of the
suite, into the same report.

**The sweeps** (:data:`SWEEPS`).  For each pair of shapes (segment-segment,
segment-triangle, triangle-triangle), the pair families of
:mod:`proximity.testing.scenes` along their parameter:

* ``pair_contact``: shapes touching at one point, moved apart by ``gap``
  along the contact normal, from 1e-3 down to touching and on into
  crossing (negative gaps);
* ``pair_near_parallel``: an edge at ``angle`` from an edge or from the
  plane of the other shape, down to 0;
* ``pair_parallel``: exactly parallel features, on one line or plane or apart;
* ``pair_degenerate``: zero-length segments and zero-area triangles;
* ``pair_offset``: contacts of size 1e-3 at ``offset`` from the origin;
* ``pair_far``: shapes of size 1 whose centres are ``ratio`` apart;
* ``pair_magnitude``: well-conditioned pairs scaled to coordinates of 1e-300
  to 1e300.

Each point of a sweep is one seeded scene of 200 pairs (``--quick``: 16).

**Who answers.**  proximity's ``robust`` and ``certified`` methods, by
``proximity.closest_points`` on the whole scene; for segment-segment, the
textbook formula in vectorised NumPy (``numpy``: the closest points of the
two lines clamped to the segments, ``benchmarks.pairs._numpy_segments``),
which is what the robust method guards; and, where installed, python-fcl and
coal, one call per pair: a segment as a ``Capsule`` of radius 0 posed along
it (one of length 0 at its point), a triangle as a one-triangle hierarchy
(``BVHModel``: neither library answers a ``TriangleP`` against another), in
the caller's coordinates.  The pose rounds the capsule's ends as the library
sees them, which far from the origin is part of its error, as it is for its
users.  fcl is asked the triangle first: asked the capsule first, it returns
the two witness points in the other order.  A negative answer (the libraries'
"in collision") counts as 0.

**Judged** against the exact distance ``d*``
(:func:`proximity.testing.accuracy.pair_reference`): the error in units of
``eps S`` (``S`` the largest coordinate difference between the two shapes'
vertices; robust's bound is 16) and in ulps of ``d*``.  A pair has no answer
(a failure, by reason) when

* the distance is NaN (``NAN``), or +inf or 1.797e308, python-fcl's answer
  where it has none (``INF``), or the call raised (``EXCEPTION``);
* the library gave no witness points (``NO_WITNESS``; coal answers a capsule
  against a hierarchy in collision with -1.797e308 and none);
* a witness point is farther than ``2^-16 S`` (1.5e-5 S) from its shape
  (``POINT_OFF_SHAPE``), or the two are not the distance apart within that
  (``INCONSISTENT``), beyond the rounding of their own coordinates (``16 eps``
  times the pair's largest coordinate, which far from the origin is more
  than ``S``).

That tolerance is far beyond rounding and the libraries' iterative
tolerances (coal's witness points are off by up to about 1e-6 S): what it
catches is junk, such as the points 0.1 S apart that python-fcl and coal give
crossing triangles at distance 0, or fcl's points at the origin beside its
contact sentinel -1.  A witness point's distance to its shape is proximity's
robust point query, whose own error is a few ``eps S``.  ``numpy`` gives no
witness points.

Output: ``OUT/pair_stability.json`` (the layout of :mod:`benchmarks.suite`'s
records, so that :mod:`benchmarks.summary` and :mod:`benchmarks.charts` read
it), ``OUT/stability_pairs.png`` (:func:`benchmarks.charts.stability_pairs`),
and the worst error per sweep (:func:`table`); ``--publish`` copies the chart
to ``docs/`` and rewrites the pair section of ``docs/benchmarks.md``.
"""

import argparse
import dataclasses
import datetime
import importlib
import os
import re
import shutil
import sys
import time
from pathlib import Path
from types import MappingProxyType

import numpy as np

import proximity
from benchmarks import suite, summary
from benchmarks.moving import _installed
from benchmarks.pairs import _coal, _fcl, _numpy_segments
from benchmarks.report import num
from proximity.testing import scenes
from proximity.testing.accuracy import pair_reference, pair_shapes

ROOT = Path(__file__).resolve().parent.parent

#: Each sweep: the generator, its swept keyword and values, from easy to hard.
SWEEPS = (
    (scenes.pair_contact, "gap", (1e-3, 1e-6, 1e-9, 1e-12, 1e-15, 0.0, -1e-15, -1e-12, -1e-9)),
    (scenes.pair_near_parallel, "angle", (1e-1, 1e-4, 1e-8, 1e-12, 1e-15, 0.0)),
    (scenes.pair_parallel, "kind", ("touching", "apart")),
    (scenes.pair_degenerate, "kind", ("point", "collinear", "two_coincident")),
    (scenes.pair_offset, "offset", (1e2, 1e4, 1e7, 1e10)),
    (scenes.pair_far, "ratio", (1e3, 1e6, 1e9, 1e12)),
    (scenes.pair_magnitude, "scale", (1e-300, 1e-150, 1e150, 1e300)),
)

#: proximity's methods and the bound each is counted against (as in :mod:`benchmarks.suite`).
METHODS = {"robust": ("error_eps_s", 16.0), "certified": ("error_ulps", 1.0)}

#: The bound the others are counted against: robust's.
OTHERS_BOUND = ("error_eps_s", 16.0)

#: The libraries, by module name, and how they are called.
PEERS = {"fcl": "python-fcl", "coal": "coal"}

#: A witness point farther than this times ``S`` from its shape, or a pair of them not the
#: distance apart within it, is junk; beyond the rounding of the points' own coordinates,
#: :data:`COORDINATES` times the largest magnitude of the pair's.
WITNESS_TOLERANCE = 2.0**-16
COORDINATES = 16 * 2.0**-52

#: python-fcl's answer where it has no distance: a pair it has no function for, or an overflow.
UNSUPPORTED = 1.7e308

#: The section of ``docs/benchmarks.md`` this module owns.
MARKERS = ("<!-- pair-stability:start -->", "<!-- pair-stability:end -->")

TITLE = "Stability sweeps: primitive pairs"


@dataclasses.dataclass(frozen=True)
class Config:
    """Sizes of one run: ``n`` pairs per point of a sweep, the seed, and whether it is the smoke run."""

    n: int = 200
    seed: int = 0
    quick: bool = False


DEFAULT = Config()
QUICK = Config(n=16, quick=True)


def families(pair):
    """The :class:`proximity.testing.scenes.Family` of every point of every sweep, for one pair."""
    out = []
    for generator, key, values in SWEEPS:
        for value in values:
            params = MappingProxyType({"pair": pair, key: value})
            out.append(
                scenes.Family(
                    generator.__name__, generator, params, None if isinstance(value, str) else value
                )
            )
    return out


# -- the answers --------------------------------------------------------------------------


def _ours(pair, scene, method):
    """``(distance, point_a, point_b)`` of one of proximity's methods on the whole scene."""
    a, b = pair_shapes(pair, scene)
    r = proximity.closest_points(a, b, method=method)
    return np.asarray(r.distance), np.asarray(r.point_a), np.asarray(r.point_b)


def _norm(v):
    """Euclidean norms of the rows of ``v``, without the overflow and underflow of their squares."""
    return np.hypot(np.hypot(v[..., 0], v[..., 1]), v[..., 2])


def capsule_poses(segments):
    """``(rotation, centre, length)`` of segments ``(n, 2, 3)`` as capsules: the rotation takes z
    to each segment's direction (a capsule's axis in python-fcl and coal).

    Lengths are taken without squaring (segments of size 1e-300 are not of length 0), a
    zero-length segment is a capsule of length 0 at its point, and the centre is the sum of
    halves, which does not overflow.
    """
    centre = 0.5 * segments[:, 0] + 0.5 * segments[:, 1]
    axis = segments[:, 1] - segments[:, 0]
    length = _norm(axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = axis / length[:, None]
    z[~(length > 0)] = (0.0, 0.0, 1.0)
    helper = np.where(np.abs(z[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, z)
    x /= _norm(x)[:, None]
    return np.stack([x, np.cross(z, x), z], axis=-1), centre, length


def _objects(name, lib, shapes):
    """Each shape as the library models it, with its pose: ``[(geometry, rotation, translation)]``."""
    if shapes.shape[1] == 3:
        build = _coal if name == "coal" else _fcl
        return [(build(np.ascontiguousarray(t), [[0, 1, 2]]), np.eye(3), np.zeros(3)) for t in shapes]
    rotation, centre, length = capsule_poses(shapes)
    return [(lib.Capsule(0.0, float(h)), r, c) for r, c, h in zip(rotation, centre, length, strict=True)]


def _peer(name, pair, scene):
    """``(distance, point_a, point_b, exception rows)`` of python-fcl or coal, one call per pair."""
    lib = importlib.import_module(name)
    n = len(scene.a)
    distance = np.full(n, np.nan)
    points = np.full((2, n, 3), np.nan)
    raised = []
    objects = [_objects(name, lib, scene.a), _objects(name, lib, scene.b)]
    # Asked a capsule against a hierarchy, fcl returns the witness points the other way round.
    flip = name == "fcl" and pair == "segment_triangle"
    if flip:
        objects.reverse()
    if name == "coal":
        request = lib.DistanceRequest()

        def ask(first, second):
            result = lib.DistanceResult()
            d = lib.distance(
                first[0],
                lib.Transform3s(*first[1:]),
                second[0],
                lib.Transform3s(*second[1:]),
                request,
                result,
            )
            return d, (result.getNearestPoint1(), result.getNearestPoint2())
    else:
        request = lib.DistanceRequest(enable_nearest_points=True)

        def ask(first, second):
            result = lib.DistanceResult()
            o1 = lib.CollisionObject(first[0], lib.Transform(*first[1:]))
            o2 = lib.CollisionObject(second[0], lib.Transform(*second[1:]))
            return lib.distance(o1, o2, request, result), result.nearest_points

    for i in range(n):
        try:
            d, (p, q) = ask(objects[0][i], objects[1][i])
        except Exception:  # noqa: BLE001 (the row has no answer; counted by reason)
            raised.append(i)
            continue
        distance[i] = d
        points[:, i] = [_point(x) for x in ((q, p) if flip else (p, q))]
    return distance, points[0], points[1], raised


def _point(p):
    """A library's witness point as three floats; NaN where it gave none (fcl's None beside 1.797e308)."""
    try:
        return np.asarray(p, dtype=np.float64).reshape(3)
    except (TypeError, ValueError):
        return np.full(3, np.nan)


# -- judging ----------------------------------------------------------------------------


def _failures(pair, scene, ref, distance, point_a, point_b, raised=()):
    """Rows without an answer, by reason (see the module docstring)."""
    failed = {
        "EXCEPTION": np.asarray(raised, dtype=np.intp),
        "NAN": np.flatnonzero(np.isnan(distance)),
        "INF": np.flatnonzero(distance >= UNSUPPORTED),
    }
    failed["NAN"] = np.setdiff1d(failed["NAN"], failed["EXCEPTION"])
    if point_a is None:
        return failed
    # Any negative distance, coal's -1.797e308 included, is "in collision".
    answered = distance < UNSUPPORTED
    answered[failed["EXCEPTION"]] = False
    given = np.isfinite(point_a).all(axis=1) & np.isfinite(point_b).all(axis=1)
    magnitude = np.maximum(np.abs(scene.a).max(axis=(1, 2)), np.abs(scene.b).max(axis=(1, 2)))
    tolerance = WITNESS_TOLERANCE * np.array([float(s) for _, s in ref]) + COORDINATES * magnitude
    shape_a, shape_b = pair_shapes(pair, scene)
    with np.errstate(all="ignore"):
        on_a = shape_a.distance(np.where(given[:, None], point_a, 0.0)) <= tolerance
        on_b = shape_b.distance(np.where(given[:, None], point_b, 0.0)) <= tolerance
        apart = np.abs(_norm(point_b - point_a) - np.maximum(distance, 0.0)) <= tolerance
    failed["NO_WITNESS"] = np.flatnonzero(answered & ~given)
    failed["POINT_OFF_SHAPE"] = np.flatnonzero(answered & given & ~(on_a & on_b))
    failed["INCONSISTENT"] = np.flatnonzero(answered & given & on_a & on_b & ~apart)
    return failed


def _record(pair, scene, ref, answer, bound, raised=()):
    distance, point_a, point_b = answer
    distance = np.asarray(distance, dtype=np.float64)
    failed = _failures(pair, scene, ref, distance, point_a, point_b, raised)
    # The libraries' "in collision": a distance of 0.
    record = suite._errors_record(np.maximum(distance, 0.0), ref, failed, bound=bound)
    record["bound"] = f"{bound[1]:g} {'eps S' if bound[0] == 'error_eps_s' else 'ulp of d*'}"
    record["witness_checked"] = point_a is not None
    record["timing"] = None
    return record


def _entities(pair, peers):
    out = [[m, "method"] for m in METHODS]
    if pair == "segment_segment":
        out.append(["numpy", "baseline"])
    return out + [[name, "backend"] for name in peers]


def _family(pair, index, family, peers, config):
    scene = family(np.random.default_rng([config.seed, list(scenes.PAIRS).index(pair), index]), config.n)
    start = time.perf_counter()
    ref = pair_reference(pair, scene)
    reference_seconds = time.perf_counter() - start
    results = {}
    for name, role in _entities(pair, peers):
        start = time.perf_counter()
        if role == "method":
            try:
                results[name] = _record(pair, scene, ref, _ours(pair, scene, name), METHODS[name])
            except Exception as exc:  # recorded as the failure of every row, with its message
                results[name] = _record(
                    pair,
                    scene,
                    ref,
                    (np.full(config.n, np.nan), None, None),
                    METHODS[name],
                    raised=range(config.n),
                )
                results[name]["exception"] = f"{type(exc).__name__}: {exc}"
        elif role == "baseline":
            with np.errstate(all="ignore"):
                answer = (_numpy_segments(scene.a, scene.b), None, None)
            results[name] = _record(pair, scene, ref, answer, OTHERS_BOUND)
        else:
            with suite.quiet_libraries():
                d, pa, pb, raised = _peer(name, pair, scene)
            results[name] = _record(pair, scene, ref, (d, pa, pb), OTHERS_BOUND, raised)
        results[name]["step_seconds"] = time.perf_counter() - start
    return {
        "kind": pair,
        "family": family.label,
        "name": family.name,
        # Without the pair, which ``kind`` holds: the swept parameter alone.
        "params": {k: v for k, v in family.params.items() if k != "pair"},
        "difficulty": family.difficulty,
        "n": config.n,
        "seed": config.seed,
        "reference_seconds": reference_seconds,
        "d_exact": [float(d) for d, _ in ref],
        "scale": [float(s) for _, s in ref],
        "results": results,
    }


def run(config=DEFAULT, log=print):
    """Every sweep of every pair; the raw data, in the layout of :func:`benchmarks.suite.run`."""
    start = time.perf_counter()
    peers, skipped = [], {}
    with suite.quiet_libraries():
        for name in PEERS:
            problem = _installed(name)
            if problem:
                skipped[name] = problem
            else:
                peers.append(name)
    for name, problem in skipped.items():
        log(f"pair stability: {PEERS[name]} skipped ({problem})")
    records = []
    with np.errstate(all="ignore"):
        for pair in scenes.PAIRS:
            step = time.perf_counter()
            for index, family in enumerate(families(pair)):
                records.append(_family(pair, index, family, peers, config))
            log(
                f"pair stability: {pair}, {len(families(pair))} scenes of {config.n} pairs "
                f"in {time.perf_counter() - step:.0f} s"
            )
    versions = {"proximity": proximity.__version__, "commit": suite._git_commit(), "numpy": np.__version__}
    versions.update({PEERS[name]: suite._version(PEERS[name]) for name in peers})
    meta = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": "python -m benchmarks.pair_stability" + (" --quick" if config.quick else ""),
        # ``n_accuracy``: the name the charts' subtitle reads.
        "config": {"n_accuracy": config.n, "seed": config.seed, "quick": config.quick},
        "machine": {"cpu": suite._cpu(), "cores": os.cpu_count()},
        "versions": versions,
        "entities": {pair: _entities(pair, peers) for pair in scenes.PAIRS},
        "skipped": {PEERS[name]: problem for name, problem in skipped.items()},
        "wall_seconds": time.perf_counter() - start,
    }
    return {"schema": suite.SCHEMA, "meta": meta, "families": records}


# -- what is shown ----------------------------------------------------------------------------

#: Column labels of the entities.
LABELS = {
    "robust": "`robust`",
    "certified": "`certified`",
    "numpy": "NumPy textbook",
    "fcl": "python-fcl",
    "coal": "coal",
}


def _cell(records):
    """The worst error over the answered pairs of a sweep's records, and its failures."""
    s = summary.stats(records)
    text = num(s.worst["error_eps_s"])
    if s.failed:
        reasons = ", ".join(f"{summary.REASONS.get(r, r)} {k}" for r, k in sorted(s.failures.items()) if k)
        text += f" ({s.failed} of {s.n} failed: {reasons})"
    return text


def _values(members):
    values = [next(iter(f["params"].values())) for f in members]
    return ", ".join(v.replace("_", " ") if isinstance(v, str) else f"{v:g}" for v in values)


def table(raw, by_point=False):
    """Markdown: the worst error (eps·S) per pair and sweep (``by_point``: per point of each
    sweep), for each method and library, with the failures."""
    names = list(dict.fromkeys(name for pair in scenes.PAIRS for name, _ in raw["meta"]["entities"][pair]))
    lines = [
        "| pair | sweep | " + " | ".join(LABELS.get(n, n) for n in names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for pair in scenes.PAIRS:
        for name, members in summary.sweeps(raw, pair).items():
            groups = [[f] for f in members] if by_point else [members]
            for group in groups:
                sweep = name.removeprefix("pair_").replace("_", " ")
                sweep += f" = {_values(group)}" if by_point else f" ({_values(group)})"
                cells = [
                    _cell([f["results"][n] for f in group]) if n in group[0]["results"] else "" for n in names
                ]
                lines.append(f"| {pair.replace('_', '–')} | {sweep} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _provenance(raw):
    meta = raw["meta"]
    libraries = ", ".join(
        f"{k} {v}" for k, v in meta["versions"].items() if k not in ("proximity", "commit", "numpy")
    )
    text = (
        f"`{meta['command']}` on {meta['date'][:10]}: {meta['machine']['cpu']}, seed "
        f"{meta['config']['seed']}, {meta['config']['n_accuracy']} pairs per point of a sweep"
        f"{'; ' + libraries if libraries else ''}; it took {meta['wall_seconds']:.0f} s."
    )
    for name, problem in meta.get("skipped", {}).items():
        text += f" {name} not run: {problem}."
    return text


NOTES = (
    "Worst error over the answered pairs, in units of eps·S (eps = 2^-52, S the largest coordinate "
    "difference between the two shapes' vertices; `robust`'s bound is 16, `certified`'s one ulp of the "
    "exact distance), and the pairs without an answer: NaN, inf (fcl's 1.797e308 included), an "
    "exception, no witness points, or witness points off their shapes or not the distance apart by more "
    "than 2^-16 S (junk, such as the points both libraries give crossing triangles). python-fcl and coal "
    "are asked one pair per call: a segment as a capsule of radius 0, a triangle as a one-triangle "
    "hierarchy; a negative answer counts as 0. On triangle pairs the two give the same answers (their "
    "lines in the chart coincide). NumPy textbook: the closest points of the two lines, clamped to the "
    "segments, as most code has it."
)


def markdown(raw, chart=None, by_point=False):
    """The section of the report and of ``docs/benchmarks.md``: provenance, the table, the chart."""
    lines = [_provenance(raw), "", table(raw, by_point), "", NOTES]
    if chart is not None:
        from benchmarks.charts import CAPTIONS

        lines += ["", f"![{TITLE}]({Path(chart).name})", "", CAPTIONS["stability_pairs"]]
    return "\n".join(lines) + "\n"


def publish(raw, chart, docs=ROOT / "docs", page=ROOT / "docs" / "benchmarks.md"):
    """Copy the chart to ``docs`` and rewrite the section between this module's markers of ``page``."""
    docs, page = Path(docs), Path(page)
    image = None
    if chart is not None:
        image = docs / Path(chart).name
        shutil.copyfile(chart, image)
    text = page.read_text(encoding="utf-8")
    start, end = MARKERS
    pattern = re.compile(re.escape(start) + r"\n.*?" + re.escape(end), re.S)
    if not pattern.search(text):
        raise SystemExit(f"{page} has no {start} ... {end} markers")
    section = markdown(raw, image)
    page.write_text(pattern.sub(lambda m: f"{start}\n{section}{end}", text, count=1), encoding="utf-8")


def main(argv=None):
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.pair_stability", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--quick", action="store_true", help="16 pairs per point of a sweep, a smoke run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("bench-results"), help="output directory")
    parser.add_argument("--report-only", action="store_true", help="redraw from OUT/pair_stability.json")
    parser.add_argument(
        "--publish",
        action="store_true",
        help="copy the chart to docs/ and rewrite the pair section of docs/benchmarks.md",
    )
    args = parser.parse_args(argv)
    path = args.out / "pair_stability.json"
    if not args.report_only:
        config = dataclasses.replace(QUICK if args.quick else DEFAULT, seed=args.seed)
        raw = run(config, log=lambda text: print(text, file=sys.stderr, flush=True))
        suite.save(raw, path)
    raw = suite.load(path)
    from benchmarks import charts

    chart = charts.stability_pairs(raw, args.out / "stability_pairs.png")
    print(table(raw))
    print(f"raw data: {path}; chart: {chart}")
    if args.publish:
        publish(raw, chart)
        print(
            "published: docs/stability_pairs.png and the pair section of docs/benchmarks.md", file=sys.stderr
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
