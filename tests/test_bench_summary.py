"""The benchmark summary never states an error where d* = 0 in ulps of 0."""

import math

from benchmarks import summary


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
