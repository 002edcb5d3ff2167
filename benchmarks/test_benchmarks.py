"""Tests of the benchmark's own code (``make test`` runs them from a clone).

The summary never states an error where d* = 0 in ulps of 0; the
point-cloud benchmark runs and cleans up after itself.
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
