"""Statistics of saved raw results: what the charts and the report show.

Everything here reads the dict written by :func:`benchmarks.suite.save`
and nothing else, so that charts and tables can be redrawn from a saved run.
Error statistics are over the answered rows only; rows without an answer
are counted by reason instead.  Errors in ulps of ``d*`` are over the rows
with ``d* > 0``: where the exact distance is 0 its ulp is the smallest
subnormal, and any error, however small against the query's size, is then
some 1e300 ulps.  Those rows are summarised apart, in ``eps * S``.

What the report and charts show a reader are the errors in ``eps * S``
(``eps = 2^-52``, ``S`` the query's size: robust's bound is 8) and the
relative error ``|d - d*| / d*`` where ``d* > 0`` (certified's bound is one
ulp of ``d*``, at most ``2^-52`` of it); ulps of ``d*`` stay in the
statistics for the tests and the raw data.
"""

import math
from dataclasses import dataclass, field

import numpy as np

KINDS = ("triangle", "disk", "circle")

#: Units of the error, as stored in each record, and how to say them.
UNITS = {
    "error_eps_s": "eps·S",
    "error_ulps": "ulps of d*, where d* > 0",
    "error_relative": "|d − d*| / d*, where d* > 0",
}

#: The units the report and the charts show.
SHOWN = ("error_eps_s", "error_relative")

EPS = 2.0**-52

#: Readable names of the failure reasons.
REASONS = {
    "NAN": "NaN",
    "INF": "inf",
    "EXCEPTION": "exception",
    "NAN_INPUT": "NaN input",
    "NO_RESULT": "no result",
    "SENTINEL": "sentinel",
    "FALSE_TOUCHING": "false touching",
    "POINT_OFF_SHAPE": "point off shape",
    "INCONSISTENT": "inconsistent",
    "NO_WITNESS": "no witness points",
}


@dataclass
class Stats:
    """Accuracy, failures and speed of one entity over one or more families.

    Attributes
    ----------
    n : int
        Queries asked.
    answered : int
        Queries with an answer.
    failures : dict of str to int
        Queries without an answer, by reason.
    beyond : int
        Answered queries beyond the entity's bound (``8 eps S`` for
        proximity's methods, the documented tolerance for backends).
    worst, median : dict of str to float
        By unit (``error_eps_s``, ``error_ulps``, ``error_relative``), over
        the answered queries (for the last two, those with ``d* > 0``); NaN
        when there are none.
    on_shape : int
        Answered queries whose exact distance is 0 (the point is on the
        shape), when the exact distances were given.
    on_shape_worst : float
        Worst error of those, in ``eps * S``; NaN when there are none.
    qps : float
        Queries per second: the median over families of each family's
        median timed repeat; NaN if never timed.
    failing_families : list of str
        Families where at least one query failed.
    """

    n: int = 0
    answered: int = 0
    failures: dict = field(default_factory=dict)
    beyond: int = 0
    worst: dict = field(default_factory=dict)
    median: dict = field(default_factory=dict)
    qps: float = math.nan
    failing_families: list = field(default_factory=list)
    on_shape: int = 0
    on_shape_worst: float = math.nan

    @property
    def failed(self):
        """Number of queries without an answer."""
        return self.n - self.answered


def answered_errors(record, unit, rows=None):
    """Errors of the answered rows of one record, as floats (inf where stored as None).

    ``rows``, a boolean mask, keeps only those rows.
    """
    failed = {i for rows in record["failed"].values() for i in rows}
    return np.array(
        [
            math.inf if e is None else e
            for i, e in enumerate(record[unit])
            if i not in failed and (rows is None or rows[i])
        ],
        dtype=np.float64,
    )


def _relative(record, d_exact, scale):
    """``|d - d*| / d*`` of the answered rows with ``d* > 0`` (inf where stored as None)."""
    d = np.asarray(d_exact, dtype=np.float64)
    rows = d > 0
    in_s = answered_errors(record, "error_eps_s", rows)
    failed = {i for rows_ in record["failed"].values() for i in rows_}
    kept = np.array([i for i in np.flatnonzero(rows) if i not in failed], dtype=np.intp)
    return in_s * EPS * np.asarray(scale, dtype=np.float64)[kept] / d[kept]


def stats(records, labels=None, exact=None, scales=None):
    """Pool the records of one entity (one per family) into :class:`Stats`.

    ``exact`` holds each family's exact distances (``d_exact``); with them,
    errors in ulps leave out the rows where ``d* = 0``, which are counted in
    ``on_shape`` instead.  ``scales`` (each family's ``scale``, the ``S`` of
    each row) gives the relative errors, with ``exact``.
    """
    labels = labels or [""] * len(records)
    exact = exact or [None] * len(records)
    scales = scales or [None] * len(records)
    out = Stats()
    pooled = {unit: [] for unit in UNITS}
    on_shape = []
    speeds = []
    for label, record, d_exact, scale in zip(labels, records, exact, scales, strict=True):
        n = len(record["error_eps_s"])
        out.n += n
        out.answered += record["answered"]
        out.beyond += record["beyond_bound"]
        for reason, rows in record["failed"].items():
            out.failures[reason] = out.failures.get(reason, 0) + len(rows)
        if record["answered"] < n:
            out.failing_families.append(label)
        zero = None if d_exact is None else np.asarray(d_exact, dtype=np.float64) == 0.0
        for unit in UNITS:
            if unit == "error_relative":
                if d_exact is not None and scale is not None:
                    pooled[unit].append(_relative(record, d_exact, scale))
                continue
            rows = None if zero is None or unit != "error_ulps" else ~zero
            pooled[unit].append(answered_errors(record, unit, rows))
        if zero is not None and zero.any():
            on_shape.append(answered_errors(record, "error_eps_s", zero))
        if record.get("timing"):
            speeds.append(record["timing"]["qps"])
    for unit in UNITS:
        errors = np.concatenate(pooled[unit]) if pooled[unit] else np.array([])
        out.worst[unit] = float(errors.max()) if len(errors) else math.nan
        out.median[unit] = float(np.median(errors)) if len(errors) else math.nan
    if on_shape:
        errors = np.concatenate(on_shape)
        out.on_shape = len(errors)
        out.on_shape_worst = float(errors.max()) if len(errors) else math.nan
    out.qps = float(np.median(speeds)) if speeds else math.nan
    return out


def entities(raw, kind):
    """``[(name, "method" | "backend")]`` measured for a query type, in run order."""
    return [tuple(e) for e in raw["meta"]["entities"][kind]]


def families(raw, kind):
    """The family records of one query type, in registry order."""
    return [f for f in raw["families"] if f["kind"] == kind]


def by_kind(raw, kind):
    """``{entity: Stats}`` pooled over every family of a query type."""
    records = families(raw, kind)
    labels = [f["family"] for f in records]
    exact = [f["d_exact"] for f in records]
    scales = [f["scale"] for f in records]
    return {
        name: stats([f["results"][name] for f in records], labels, exact, scales)
        for name, _ in entities(raw, kind)
        if all(name in f["results"] for f in records)
    }


def by_family(raw, kind):
    """``[(family record, {entity: Stats})]`` for a query type."""
    return [
        (
            f,
            {
                name: stats([record], [f["family"]], [f["d_exact"]], [f["scale"]])
                for name, record in f["results"].items()
            },
        )
        for f in families(raw, kind)
    ]


def sweeps(raw, kind):
    """Families of a query type grouped by generator: ``{name: [family record, ...]}``.

    Only generators with more than one member are sweeps; their members are
    in the registry's order.
    """
    groups = {}
    for f in families(raw, kind):
        groups.setdefault(f["name"], []).append(f)
    return {name: members for name, members in groups.items() if len(members) > 1}


def pareto(points):
    """Indices of the points ``(speed, error)`` no other point beats on both.

    A point is dominated when another is at least as fast and at least as
    accurate, and strictly better in one.  Points with a non-finite
    coordinate are left out.
    """
    finite = [i for i, (x, y) in enumerate(points) if math.isfinite(x) and math.isfinite(y)]
    front = []
    for i in finite:
        xi, yi = points[i]
        dominated = any(
            points[j][0] >= xi and points[j][1] <= yi and (points[j][0] > xi or points[j][1] < yi)
            for j in finite
        )
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: points[i][0])


def failure_text(failures, n):
    """``"12.5% (NaN 20, no result 5)"`` or ``""`` when nothing failed."""
    total = sum(failures.values())
    if not total:
        return ""
    reasons = ", ".join(
        f"{REASONS.get(reason, reason)} {count}" for reason, count in sorted(failures.items()) if count
    )
    return f"{100.0 * total / n:.3g}% ({reasons})"
