"""Tests of the benchmark's own code (``make test`` runs them from a clone).

The summary never states an error where d* = 0 in ulps of 0; relative errors
leave those rows out; the speed table states facts and the targets go to the
checks; the mesh chart draws, with a style for every peer; the mesh peers'
checks judge the targets of the same run, or say which peer did not run; the
peers' table shows each build's memory, measured as a build keeps and peaks;
the point-cloud benchmark runs and cleans up after itself; the mesh-pair
benchmark's reference is the exact minimum over every pair of faces; the
pair stability sweeps hold proximity's methods to their bounds, count junk
witness points and sentinels as failures, and draw.
"""

import json
import math

from benchmarks import scale, summary


def _record(eps_s, ulps, failed=None):
    failed = failed or {}
    answered = len(eps_s) - sum(len(rows) for rows in failed.values())
    return {
        "error_eps_s": eps_s,
        "error_ulps": ulps,
        "failed": failed,
        "answered": answered,
        "beyond_bound": 0,
    }


def test_rows_with_zero_exact_distance_leave_the_ulps_statistics():
    # Row 1 is on the shape: 0.5 eps S there is ~1e300 ulps of the smallest subnormal.
    record = _record([0.25, 0.5, 0.125], [0.75, 1e300, 0.5])
    s = summary.stats([record], exact=[[1.0, 0.0, 2.0]])
    assert s.worst["error_ulps"] == 0.75
    assert s.median["error_ulps"] == 0.625
    assert s.worst["error_eps_s"] == 0.5  # every answered row, in eps S
    assert s.on_shape == 1
    assert s.on_shape_worst == 0.5


def test_failed_rows_on_the_shape_are_not_counted():
    record = _record([0.25, None, 0.125], [0.75, None, 0.5], failed={"NAN": [1]})
    s = summary.stats([record], exact=[[1.0, 0.0, 2.0]])
    assert s.on_shape == 0
    assert math.isnan(s.on_shape_worst)
    assert s.worst["error_ulps"] == 0.75


def test_without_exact_distances_every_answered_row_counts():
    record = _record([0.25, 0.5], [0.75, 1e300])
    s = summary.stats([record])
    assert s.worst["error_ulps"] == 1e300
    assert s.on_shape == 0


def test_the_scale_benchmark_runs_and_deletes_its_files(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    args = ["--quick", "--points", "30000", "--chunk", "7000", "--dir", str(data), "--out", str(tmp_path)]
    assert scale.main(args) == 0
    assert list(data.iterdir()) == []
    raw = json.loads((tmp_path / "scale.json").read_text())
    assert raw["unpickle_builds"] == 0 and raw["faces"] == 20_480
    runs = raw["runs"]
    assert [r["points"] for r in runs.values()] == [30_000, 30_000, 3_000]
    assert len(runs["command, LocalCluster(2)"]["peak_rss_bytes"]["workers"]) == 2
    table = (tmp_path / "scale.md").read_text().splitlines()
    assert sum(line.startswith("| command") for line in table) == 3


def test_relative_errors_are_over_the_rows_off_the_shape():
    # Row 1 is on the shape (no relative error); rows 0 and 2: error * eps * S / d*.
    record = _record([0.25, 0.5, 4.0], [0.75, 1e300, 0.5])
    s = summary.stats([record], exact=[[1.0, 0.0, 2.0]], scales=[[2.0, 1.0, 1.0]])
    assert s.worst["error_relative"] == 4.0 * 2.0**-52 / 2.0
    assert s.median["error_relative"] == (0.25 * 2.0**-52 * 2.0 + 4.0 * 2.0**-52 / 2.0) / 2


def _speed_rows():
    from benchmarks import speed

    rows = [
        speed._row("pairs: robust vs trimesh", 1.0, 30.0, 1e6, 15.0),
        speed._row("pairs: eberly vs trimesh", 1.0, 20.0, 1e6, 25.0),  # 20x: below its target
        speed._seconds_row("empty cache: first result", 2.5, 3.0),
        speed._seconds_row("start-up floor", 0.3, None),
    ]
    return speed, rows


def test_the_speed_table_states_facts_and_the_checks_hold_the_targets():
    speed, rows = _speed_rows()
    table = speed.format_table(rows)
    assert "30.00x" in table and "20.00x" in table and "2.50 s" in table
    assert table.splitlines()[0] == "| case | proximity | baseline | ratio |"
    assert not any(word in table for word in ("target", "limit", "**no**", "yes", "BELOW"))
    missed, lines = speed.checks(rows)
    assert missed == 1 and len(lines) == 3
    assert lines[1].startswith("MISSED  pairs: eberly vs trimesh: 20.00x (target at least 25x)")
    assert lines[2].startswith("met     empty cache: first result: 2.50 s (target at most 3 s)")


def test_the_mesh_chart_draws_from_the_peers_data(tmp_path):
    from benchmarks import charts

    def run(qps, error, off=0):
        timing = {"qps": qps, "errors": {"max_error": error, "off": off, "n": 1000}}
        return {"1": {"sets": {"near": {"unsigned": timing}, "box": {"unsigned": timing}}}}

    raw = {
        "meta": {
            "command": "python -m benchmarks.meshes --quick",
            "seed": 0,
            "points": 1000,
            "exact_sample": 50,
            "cpus": 2,
        },  # fmt: skip
        "meshes": {
            "icosphere, 1,280 faces": {
                "size": 2.0,
                "peers": {
                    "proximity": {"label": "proximity (robust)", "runs": run(1e6, 0.0)},
                    "open3d": {"label": "Open3D RaycastingScene", "runs": run(5e5, 1e-7, off=3)},
                    "fcpw": {"label": "FCPW (wheel)", "runs": run(8e5, 6e-8)},
                    "meshlib": {"label": "MeshLib findSignedDistances", "runs": run(7e5, 5e-8)},
                    "fcl": {"label": "python-fcl, per point", "runs": {"1": {"skipped": "not installed"}}},
                },
            }
        },
    }
    path = charts.mesh_peers(raw, tmp_path / "mesh_peers.png")
    assert path.exists() and path.stat().st_size > 10_000


def test_every_peer_has_a_style_of_its_own_in_the_mesh_chart():
    from benchmarks import charts, peers

    assert set(peers.PEERS) <= set(charts.PEER_STYLE)
    assert len(set(charts.PEER_STYLE.values())) == len(charts.PEER_STYLE)


def test_the_pairs_reference_is_the_exact_minimum_over_every_face_pair():
    import mpmath
    import numpy as np

    from benchmarks import pairs
    from proximity.numerics.rigid import to_world
    from proximity.testing import exact
    from proximity.testing.meshes import icosphere, torus

    (va, fa), (vb, fb) = icosphere(1), torus(6, 4)
    rng = np.random.default_rng(2)
    for gap in (0.3, -0.05):
        pose = pairs.poses(pairs.proximity.TriangleMesh(va, fa), pairs.proximity.TriangleMesh(vb, fb), rng,
                           gap, 1)[0]  # fmt: skip
        posed = to_world(vb, pose[:3, :3], pose[:3, 3])
        every = min(exact.triangle_triangle_closest(va[i], posed[j]).sqr_distance for i in fa for j in fb)
        with mpmath.workprec(exact.PREC):
            expected = mpmath.sqrt(exact.to_mpf(every))
            got, checked = pairs.exact_distance(va, fa, posed, fb, max(gap, 0.0) + 0.01)
            assert got == expected and checked < len(fa) * len(fb)
        assert (expected == 0) == (gap < 0)


def test_the_mesh_pair_rows_hold_every_library_or_why_it_was_skipped():
    import numpy as np

    from benchmarks import pairs
    from proximity.testing.meshes import icosphere, torus

    rng = np.random.default_rng(0)
    rows, gaps = pairs.mesh_pair(icosphere(1), torus(8, 6), rng, 1, 2, log=lambda _: None)
    assert set(rows) == {key for key, *_ in pairs.LIBRARIES}
    assert [row["gap"] for row in gaps] == list(pairs.GAPS)
    for row in gaps:
        for key, result in row["libraries"].items():
            assert len(result["answers"]) == 1 and result["missing"] == (result["answers"][0] is None)
            assert (result["error"] is None) == bool(result["missing"])
            if key in ("robust", "certified"):
                assert result["error"] <= 1e-15
        if "pybullet_meshes" in row["libraries"]:  # two triangle meshes: pybullet reports no points
            assert row["libraries"]["pybullet_meshes"]["answers"] == [None]
    size = {"faces": [80, 96], "rows": rows, "gaps": gaps}
    lines = pairs.mesh_report(size, {"poses": 1, "repeats": 2})
    blocks = sum(line.split()[:1] == ["gap"] for line in lines)
    assert "icosphere of 80 faces" in lines[0] and blocks >= 1
    assert sum(line.split()[:1] == ["overlap"] for line in lines) == blocks
    missed, lines = pairs.checks({"meshes": [size]})
    assert missed == sum(line.startswith("MISSED") for line in lines)


def test_the_hausdorff_rows_bracket_a_sampled_estimate():
    import numpy as np

    from benchmarks import pairs
    from proximity.testing.meshes import icosphere, torus

    out = pairs.hausdorff(icosphere(1), torus(8, 6), np.random.default_rng(0), True, log=lambda _: None)
    assert len(out["rows"]) == 2
    for row in out["rows"]:
        assert row["converged"] and 0 < row["lower"] <= row["upper"] <= row["lower"] * (1 + 1e-6) + 1e-12
        if "trimesh" in row:  # a sample's greatest distance is at most the exact one
            assert row["trimesh"]["estimate"] <= row["upper"]
    assert "pose 1:" in "\n".join(pairs.hausdorff_report(out))


def test_the_primitive_pair_rows_are_exact_within_the_bound_and_name_their_peers():
    import numpy as np

    from benchmarks import pairs

    rows = pairs.primitives(np.random.default_rng(1), True, log=lambda _: None, sizes=(2_000, 20, 10))
    assert [row["kind"] for row in rows] == ["segment", "capsule", "triangle"]
    for row in rows:
        # The robust pair bound, 16 eps S with S at most 4 here.
        assert row["proximity"] > 0 and row["error"] <= 16 * 2.0**-52 * 4
        assert all("rate" in peer or "skipped" in peer for peer in row["libraries"].values())
    # The NumPy baseline agrees on the segments (no degenerate ones among random pairs).
    assert rows[0]["libraries"]["numpy"]["error"] < 1e-12
    missed, lines = pairs.checks({"gaps": [], "primitives": rows})
    # Per kind: distance and closest_points against coal and one against the other, or one line skipped.
    expected = sum(3 if "rate" in row["libraries"]["coal"] else 1 for row in rows)
    assert len(lines) == expected and missed == sum(line.startswith("MISSED") for line in lines)
    assert "capsule (2,000 pairs)" in "\n".join(pairs.primitives_report(rows))
    assert all(row["proximity_points"] > 0 for row in rows)


def test_the_single_call_rows_time_every_library_on_the_same_pairs():
    import numpy as np

    from benchmarks import pairs

    rows = pairs.single_calls(np.random.default_rng(2), True, log=lambda _: None)
    assert [row["kind"] for row in rows] == [kind for kind, _ in pairs.SINGLE_KINDS]
    for row in rows:
        assert {"closest_points", "distance"} <= set(row["seconds"])
        assert all(0 < seconds < np.inf for seconds in row["seconds"].values())
    missed, lines = pairs.checks({"gaps": [], "single": rows})
    assert missed == sum(line.startswith("MISSED") for line in lines)
    assert sum("closest_points:" in line for line in lines) == 2  # capsules and segments
    assert "capsule:" in "\n".join(pairs.single_report(rows))


def test_the_memory_row_measures_a_query_in_a_fresh_process():
    from benchmarks.speed import memory_row

    row = memory_row(10_000)
    # The outputs of 10,000 closest points: distance, squared distance, point, feature, barycentrics.
    assert row["baseline"] * 2**20 == 10_000 * (8 + 8 + 24 + 1 + 24)
    assert row["ours"] >= row["baseline"]


def _pair_sweeps(monkeypatch, n=6):
    """A short run of the pair stability sweeps: two points of two sweeps per pair."""
    from benchmarks import pair_stability
    from proximity.testing import scenes

    monkeypatch.setattr(
        pair_stability,
        "SWEEPS",
        (
            (scenes.pair_contact, "gap", (1e-3, -1e-9)),
            (scenes.pair_degenerate, "kind", ("point", "collinear")),
        ),
    )
    return pair_stability, pair_stability.run(pair_stability.Config(n=n), log=lambda _: None)


def test_the_pair_sweeps_judge_every_answer_and_name_the_missing_peers(monkeypatch, tmp_path):
    from benchmarks import charts, summary

    pair_stability, raw = _pair_sweeps(monkeypatch)
    installed = [name for name, label in pair_stability.PEERS.items() if label not in raw["meta"]["skipped"]]
    assert len(raw["families"]) == 3 * 4
    for f in raw["families"]:
        results = f["results"]
        baseline = {"numpy"} if f["kind"] == "segment_segment" else set()
        assert set(results) == {"robust", "certified", *installed} | baseline
        robust = summary.stats([results["robust"]])
        certified = summary.stats([results["certified"]])
        assert robust.failed == 0 and robust.worst["error_eps_s"] <= 16
        assert certified.failed == 0 and certified.worst["error_ulps"] <= 1
    assert len(summary.sweeps(raw, "triangle_triangle")) == 2
    table = pair_stability.table(raw).splitlines()
    assert len(table) == 2 + 3 * 2 and table[2].startswith("| segment–segment | contact (0.001, -1e-09) |")
    path = charts.stability_pairs(raw, tmp_path / "stability_pairs.png")
    assert path.exists() and path.stat().st_size > 10_000


def test_junk_witness_points_are_failures_and_sentinels_are_not_distances():
    import numpy as np

    from benchmarks import pair_stability
    from proximity.testing import scenes
    from proximity.testing.accuracy import pair_reference

    # Two triangles crossing through each other, and the same two 1 apart along z.
    a = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    b = np.array([[0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.6, 0.3, 0.0]])
    scene = scenes.PairScene(np.stack([a] * 5), np.stack([b, b, b, b + [0, 0, 1.5], b + [0, 0, 1.5]]))
    ref = pair_reference("triangle_triangle", scene)
    distance = np.array([0.0, 0.0, 1.7976931348623157e308, -1.0, 1.0])
    # Row 0: distance 0, the points on the shapes but 0.41 apart (junk); row 1: a common point;
    # row 2: fcl's "no distance"; row 3: fcl's contact sentinel for shapes apart, with points at
    # the origin (a's vertex, b far from it); row 4: right, the points 1 apart on the shapes.
    point_a = np.array([[0.2, 0.2, 0.0], [0.2, 0.2, 0.0], [np.nan] * 3, [0.0, 0.0, 0.0], [0.2, 0.2, 0.0]])
    point_b = np.array([[0.6, 0.3, 0.0], [0.2, 0.2, 0.0], [np.nan] * 3, [0.0, 0.0, 0.0], [0.2, 0.2, 1.0]])
    failed = pair_stability._failures("triangle_triangle", scene, ref, distance, point_a, point_b)
    got = {reason: list(rows) for reason, rows in failed.items() if len(rows)}
    assert got == {"INCONSISTENT": [0], "INF": [2], "POINT_OFF_SHAPE": [3]}
    point_a[4] = np.nan
    failed = pair_stability._failures("triangle_triangle", scene, ref, distance, point_a, point_b)
    assert list(failed["NO_WITNESS"]) == [4]


def _peers_raw(with_peers=True):
    """A peers' run on the large icosphere and a 20k-face one; ``with_peers``: FCPW and Warp ran."""

    def runs(build, near, box, kept=None, peak=None, faces=1, threads=("1", "2")):
        memory = None
        if kept is not None:
            memory = {"faces": faces, "before_kib": 100, "kept_kib": kept * faces / 1024,
                      "peak_kib": peak * faces / 1024}  # fmt: skip
        sets = {"near": {"unsigned": {"qps": near}}, "box": {"unsigned": {"qps": box}}}
        return {t: {"build": build * (2 if t == "1" else 1), "memory": memory, "sets": sets} for t in threads}

    def entry(faces, peers):
        return {"faces": faces, "size": 2.0, "peers": peers}

    large = 1_310_720
    big = {"proximity": {"label": "proximity (robust)", "threads": "parameter", "rebuilds": [],
                         "runs": runs(0.4, 3e6, 1e6, kept=110, peak=260, faces=large)}}  # fmt: skip
    small = {"proximity": {"label": "proximity (robust)", "threads": "parameter", "rebuilds": [],
                           "runs": runs(0.01, 1.2e6, 5e5, kept=200, peak=300, faces=20_480)}}  # fmt: skip
    if with_peers:
        big["fcpw"] = {"label": "FCPW (wheel)", "threads": "affinity", "rebuilds": [],
                       "runs": runs(0.5, 1e6, 4e5, kept=80, peak=100, faces=large)}  # fmt: skip
        small["warp"] = {"label": "Warp (CPU)", "threads": "one", "rebuilds": [],
                         "runs": runs(0.005, 1.5e6, 2e5, threads=("1",))}  # fmt: skip
    return {
        "meta": {"threads_all": 2},
        "meshes": {
            "icosphere, 1,310,720 faces": entry(large, big),
            "icosphere, 20,480 faces": entry(20_480, small),
        },
    }


def test_the_peers_checks_judge_the_targets_from_the_same_run():
    from benchmarks import meshes

    missed, lines = meshes.peers_checks(_peers_raw())
    assert len(lines) == 6 and missed == 3
    # 110 bytes per face kept (at most 120), a peak of 260 (at most 250).
    assert lines[0].startswith("met     proximity's memory kept after the build, icosphere, 1,310,720 faces")
    assert ": 110 bytes per face" in lines[0] and ": 260 bytes per face" in lines[1]
    assert lines[1].startswith("MISSED  proximity's build peak, icosphere, 1,310,720 faces: 260")
    # 3e6 / 1e6 points/s on one thread (at least 2.5x); a build of 0.4 s / 0.5 s on 2 threads (at most 0.7x).
    assert lines[2].startswith("met     speed-up over FCPW's wheel") and "3.00x" in lines[2]
    assert lines[3].startswith("MISSED  build time over FCPW's wheel's") and "0.80x" in lines[3]
    # Near: 1.2e6 / 1.5e6 (below Warp), box: 5e5 / 2e5.
    warp = "speed-up over Warp (CPU), icosphere, 20,480 faces"
    assert lines[4].startswith(f"MISSED  {warp}, near") and "0.80x" in lines[4]
    assert lines[5].startswith(f"met     {warp}, box") and "2.50x" in lines[5]


def test_a_peers_check_whose_peer_or_mesh_did_not_run_says_so_and_is_not_missed():
    from benchmarks import meshes

    missed, lines = meshes.peers_checks(_peers_raw(with_peers=False))
    assert missed == 1 and len(lines) == 6  # the build peak alone
    assert [line.split()[0] for line in lines] == ["met", "MISSED", "n/a", "n/a", "n/a", "n/a"]
    assert "FCPW did not run" in lines[2] and "Warp did not run" in lines[5]
    raw = _peers_raw()
    raw["meshes"] = {"torus, 20,000 faces": raw["meshes"].pop("icosphere, 20,480 faces")}
    missed, lines = meshes.peers_checks(raw)
    assert lines[0].startswith("n/a") and "1,310,720-face icosphere: that mesh is not in this run" in lines[0]
    assert len(lines) == 3 and missed == 1


def test_the_peers_table_shows_the_memory_of_each_build():
    from benchmarks import meshes

    raw = _peers_raw()
    raw["meta"].update(points=1000, exact_sample=50, cpus=2, load_average=[(1.0, 1.0, 1.0)])
    for entry in raw["meshes"].values():
        for peer in entry["peers"].values():
            peer["precision"] = "float64"
            for run in peer["runs"].values():
                for timing in run["sets"].values():
                    timing["unsigned"]["errors"] = {"max_error": 0.0, "off": 0, "n": 1000}
    small = raw["meshes"]["icosphere, 20,480 faces"]["peers"]
    small["pcu"] = {"label": "point-cloud-utils", "precision": "float64", "threads": "environment",
                    "rebuilds": ["unsigned", "signed"], "runs": small["warp"]["runs"]}  # fmt: skip
    table = meshes.peers_markdown(raw).splitlines()
    header = next(line for line in table if line.startswith("| unsigned"))
    assert "| kept (B/face) | build peak (B/face) |" in header
    row = next(line for line in table if line.startswith("| FCPW (wheel)"))
    assert row.split(" | ")[2:5] == ["500", "80", "100"]  # build in ms (the 2-thread run), kept, peak
    row = next(line for line in table if line.startswith("| point-cloud-utils"))
    assert row.split(" | ")[3:5] == ["in every call", "in every call"]


def test_a_build_keeps_what_it_returns_and_peaks_at_what_it_made():
    import subprocess
    import sys
    from pathlib import Path

    import pytest

    from benchmarks import peers

    if not peers.can_reset_peak():
        pytest.skip("no /proc/self/clear_refs on this system: the peak cannot be reset")

    # In a process of its own, as the benchmark's children measure: in this
    # one, pages freed by earlier tests may take the new arrays without
    # growing the resident set.
    code = """
import json, numpy as np
from benchmarks import peers

def build():
    scratch = np.ones(12_500_000)  # 100 MB, freed on return
    return scratch[:1_250_000].copy()  # 10 MB kept

built, seconds, memory = peers.measure_build(build)
print(json.dumps({"n": len(built), "seconds": seconds, "memory": memory}))
"""
    root = Path(__file__).resolve().parent.parent
    run = subprocess.run([sys.executable, "-c", code], cwd=root, check=True, capture_output=True, text=True)
    record = json.loads(run.stdout.strip().splitlines()[-1])
    memory = record["memory"]
    assert record["n"] == 1_250_000 and record["seconds"] > 0
    mib = 2**20 / 1024
    assert 9 * mib <= memory["kept_kib"] <= 12 * mib
    assert 100 * mib <= memory["peak_kib"] <= 115 * mib
