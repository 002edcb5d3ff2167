"""Ask several libraries the same query and summarise how they disagree with proximity.

The reference is proximity's most accurate method.  A backend's disagreement
on a row is ``|d_backend - d_reference|``, over the rows it answered; rows it
could not answer are counted by :class:`~proximity.adapters.Failure` reason instead.
A backend that cannot be given the query at all (a kind of shape, or a pair
of kinds, its library has no model of) is left out, with its reason
(:class:`LeftOut`).

The libraries are asked in the caller's coordinates, as they would be used
directly, unless ``rescale=True`` asks them in the backends' frames of each
query's own (see :class:`~proximity.adapters._base.Backend`), where
libraries with absolute tolerances answer as they do at a unit size.
"""

import types
from dataclasses import dataclass

import numpy as np

import proximity

from ._base import Backend, error_scale
from ._common import Failure, Model, best_method
from ._pairs import pair_scale
from .registry import available, get


@dataclass(frozen=True)
class Summary:
    """One backend's agreement with the reference.

    Attributes
    ----------
    backend : str
        Backend name.
    model : Model
        What the backend built.
    rows : int
        Number of query rows (the size of the broadcast shape).
    answered : int
        Rows whose failure code is ``OK``, or ``CONTACT`` (a pair in
        contact: distance 0 without witness points).
    failures : mapping of str to int
        Count of each other :class:`~proximity.adapters.Failure` reason that occurred.
    max_disagreement, median_disagreement : float
        Of ``|d - d_ref|`` over the answered rows (NaN if none).
    max_relative, median_relative : float
        Of ``|d - d_ref| / S`` with proximity's error scale ``S`` (for a
        pair query, the pair's size: see :meth:`Backend.closest_points`).
    beyond_tolerance : int
        Answered rows whose disagreement exceeds the backend's documented
        tolerance for that row.

    Examples
    --------
    >>> import numpy as np, proximity, proximity.adapters as adapters
    >>> circle = proximity.Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> points = np.random.default_rng(0).normal(size=(20, 3))
    >>> s = adapters.cross_check(circle, points, backends=["trimesh"]).summary("trimesh[raw]")
    >>> s.rows, s.answered, dict(s.failures), s.max_relative < 1e-3
    (20, 20, {}, True)
    """

    backend: str
    model: Model
    rows: int
    answered: int
    failures: types.MappingProxyType
    max_disagreement: float
    median_disagreement: float
    max_relative: float
    median_relative: float
    beyond_tolerance: int


@dataclass(frozen=True)
class Case:
    """One answered row, among a backend's largest disagreements.

    ``ratio`` is the disagreement divided by the backend's tolerance for the
    row: above 1 the backend is outside what it documents.

    Examples
    --------
    >>> import numpy as np, proximity, proximity.adapters as adapters
    >>> circle = proximity.Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> points = np.random.default_rng(0).normal(size=(20, 3))
    >>> case = adapters.cross_check(circle, points, backends=["trimesh"], worst=1).worst[0]
    >>> case.backend, bool(case.disagreement == abs(case.distance - case.reference)), case.ratio < 1
    ('trimesh[raw]', True, True)
    """

    backend: str
    index: tuple
    #: The query point; empty for a pair query.
    point: tuple
    reference: float
    distance: float
    disagreement: float
    tolerance: float
    ratio: float


@dataclass(frozen=True)
class LeftOut:
    """A backend that could not be given the query, and why.

    Examples
    --------
    trimesh's pair queries take triangles and meshes only:

    >>> import proximity, proximity.adapters as adapters
    >>> from proximity.testing.meshes import icosphere
    >>> ball = proximity.TriangleMesh(*icosphere(1, 1.0))
    >>> report = adapters.cross_check(proximity.Point([3, 0, 0]), ball, backends=["fcl", "trimesh"])
    >>> [s.backend for s in report.summaries], [x.backend for x in report.left_out]
    (['fcl[raw]'], ['trimesh[raw]'])
    >>> print(report)  # doctest: +ELLIPSIS
    Point of batch shape () and TriangleMesh of 80 primitives against proximity certified
    backend   model ...
    fcl[raw]  a: Sphere(0); b: BVHModel(F triangles) ...
    <BLANKLINE>
    left out, as they cannot be given this query:
      trimesh[raw]: the trimesh[raw] backend has no pair query for a point (a) and a mesh (b);
      it takes triangle, mesh
    """

    backend: str
    reason: str


@dataclass(frozen=True, repr=False)
class CrossCheck:
    """The result of :func:`cross_check`.

    Attributes
    ----------
    shape : str
        The shape queried, in a few words.
    reference : str
        The proximity method used as reference.
    summaries : tuple of Summary
        One per backend that answered, in the order asked.
    worst : tuple of Case
        For each backend, its answered rows with the largest
        disagreement-to-tolerance ratio, largest first.
    left_out : tuple of LeftOut
        The backends that could not be given the query, in the order asked,
        each with its reason.

    Examples
    --------
    >>> import numpy as np, proximity, proximity.adapters as adapters
    >>> circle = proximity.Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> points = np.random.default_rng(0).normal(size=(20, 3))
    >>> report = adapters.cross_check(circle, points, backends=["trimesh"])
    >>> report.reference, [s.backend for s in report.summaries], len(report.worst), report.left_out
    ('certified', ['trimesh[raw]'], 3, ())
    >>> print(report.table().splitlines()[0])
    Circle of batch shape () against proximity certified
    """

    shape: str
    reference: str
    summaries: tuple
    worst: tuple
    left_out: tuple = ()

    def summary(self, backend):
        """The :class:`Summary` of the backend named ``backend``.

        Raises
        ------
        KeyError
            If that backend was not asked, or was left out (the message
            gives its reason).
        """
        for s in self.summaries:
            if s.backend == backend:
                return s
        for x in self.left_out:
            if x.backend == backend:
                raise KeyError(f"backend {backend!r} was left out of this cross-check: {x.reason}")
        raise KeyError(
            f"no backend {backend!r} in this cross-check; have {[s.backend for s in self.summaries]}"
        )

    def __str__(self):
        return self.table()

    __repr__ = __str__

    def table(self):
        """The summaries, the worst cases and the backends left out, as plain text (what ``print`` shows)."""
        rows = [
            ("backend", "model", "answered", "max |dd|/S", "median |dd|/S", "max |dd|", ">tol", "failures")
        ]
        for s in self.summaries:
            failures = ", ".join(f"{name}:{count}" for name, count in s.failures.items()) or "-"
            rows.append(
                (
                    s.backend,
                    s.model.describe(),
                    f"{s.answered}/{s.rows}",
                    _num(s.max_relative),
                    _num(s.median_relative),
                    _num(s.max_disagreement),
                    str(s.beyond_tolerance),
                    failures,
                )
            )
        lines = [f"{self.shape} against proximity {self.reference}"]
        if self.summaries:
            lines += _format(rows)
        else:
            lines.append("no backend answered")
        if self.worst:
            cases = [("backend", "index", "distance", "reference", "|dd|", "tol", "|dd|/tol")]
            for c in self.worst:
                cases.append(
                    (
                        c.backend,
                        str(c.index),
                        _num(c.distance, 10),
                        _num(c.reference, 10),
                        _num(c.disagreement),
                        _num(c.tolerance),
                        _num(c.ratio),
                    )
                )
            lines += ["", "largest disagreements, relative to each backend's tolerance:", *_format(cases)]
        if self.left_out:
            lines += ["", "left out, as they cannot be given this query:"]
            lines += [f"  {x.backend}: {x.reason}" for x in self.left_out]
        return "\n".join(lines)


def cross_check(shape, points, backends=None, tol=None, *, worst=3, rescale=False):
    """Ask every backend and proximity the same query, and compare.

    Parameters
    ----------
    shape : Shape
        One shape or a batch: for a point query, a shape the backends'
        :meth:`Backend.closest_point` takes (triangles, disks, circles,
        meshes); for a pair query, any shape :meth:`Backend.closest_points`
        takes.  A backend that takes neither is left out.
    points : array_like, shape ``(..., D)``, or Shape
        Query points, broadcast against the shape's batch; or a second
        shape: the backends' :meth:`Backend.closest_points` of the pair are
        compared with :func:`proximity.distance` of the pair, as
        :func:`proximity.distance` reads its second argument.
    backends : iterable of str or Backend, optional
        Backend names (created here, with ``rescale``, and closed
        afterwards) or backend objects (asked as they were made, and left
        open).  Default: every name in :func:`available`.
    tol : float, optional
        Modelling tolerance passed to each backend (see
        :meth:`Backend.closest_point`); default ``1e-3 R``.
    worst : int, optional
        How many of its largest disagreements to keep per backend.
    rescale : bool, optional
        Create the named backends with ``rescale=True``, which asks each
        library in a frame of each query's own (a pair centered and scaled
        by a power of two to a size of about 1; for trimesh and pybullet,
        each point query's row or shape likewise).  Default False: the
        libraries are given the caller's coordinates, as they would be used
        directly, and the backends are named ``<name>[raw]``.

    Returns
    -------
    CrossCheck
        Per-backend summaries and worst cases, and the backends left out
        with their reasons; ``.table()`` formats them.

    Raises
    ------
    TypeError, ValueError
        Where proximity refuses the query (it is validated as
        :func:`proximity.distance` validates it).
    NotImplementedError
        Where proximity itself has no answer for the pair.  A backend that
        cannot be given the query is left out, never raised.

    Examples
    --------
    >>> import numpy as np, proximity, proximity.adapters as adapters
    >>> circle = proximity.Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> points = np.random.default_rng(0).normal(size=(20, 3))
    >>> report = adapters.cross_check(circle, points, backends=["trimesh"])
    >>> s = report.summary("trimesh[raw]")
    >>> s.answered, s.beyond_tolerance, s.max_disagreement <= 1e-3
    (20, 0, True)
    >>> print(report)  # doctest: +ELLIPSIS
    Circle of batch shape () against proximity certified
    backend       model  answered  max |dd|/S  median |dd|/S  max |dd|  >tol  failures
    trimesh[raw]  ...    20/20     ...

    A pair query: 50 capsules against 50 triangles, the last 10 of them
    crossing the capsules' axes.  fcl answers those with witness points
    that are not a point of contact: distance 0, code ``CONTACT``.

    >>> rng = np.random.default_rng(1)
    >>> axes = rng.normal(size=(50, 2, 3))
    >>> tri = rng.normal(size=(50, 3, 3)) + [4, 0, 0]
    >>> around = [[2, 0, 0], [-1, 2, 0], [-1, -2, 0]]      # centroid at the origin
    >>> tri[40:] = axes[40:].mean(axis=1, keepdims=True) + around
    >>> pair = adapters.cross_check(proximity.Capsule(axes, 0.25), proximity.Triangle(tri), backends=["fcl"])
    >>> s = pair.summary("fcl[raw]")
    >>> s.rows, s.answered, s.beyond_tolerance, s.failures["CONTACT"]
    (50, 50, 0, 10)

    Triangle pairs of a size of 1e-4: fcl's triangle tests have absolute
    tolerances, so that in the caller's coordinates some of its distances
    are wrong, which it is not in a frame of the pair's own.

    >>> a = proximity.Triangle(rng.normal(size=(200, 3, 3)) * 1e-4)
    >>> b = proximity.Triangle((rng.normal(size=(200, 3, 3)) + [3, 0, 0]) * 1e-4)
    >>> raw = adapters.cross_check(a, b, backends=["fcl"]).summary("fcl[raw]")
    >>> rescaled = adapters.cross_check(a, b, backends=["fcl"], rescale=True).summary("fcl")
    >>> raw.beyond_tolerance > 0, raw.max_relative > 1e-3, rescaled.beyond_tolerance
    (True, True, 0)
    """
    names = available() if backends is None else list(backends)
    owned = []
    instances = []
    try:
        for b in names:
            if isinstance(b, Backend):
                instances.append(b)
            else:
                instance = get(b, rescale=rescale)
                owned.append(instance)
                instances.append(instance)
        pair = isinstance(points, proximity.Shape)
        # proximity validates the query (and raises where it has no answer) before any backend is asked.
        if pair:
            methods = set(shape.methods) & set(points.methods)
            method = "certified" if "certified" in methods else "robust"
            reference = np.asarray(proximity.distance(shape, points, method=method), dtype=np.float64)
        else:
            method = best_method(shape)
            reference = np.asarray(shape.distance(points, method=method), dtype=np.float64)
        answers, left_out = [], []
        for backend in instances:
            try:
                if pair:
                    answers.append(backend.closest_points(shape, points))
                else:
                    answers.append(backend.closest_point(shape, points, tol=tol))
            except NotImplementedError as exc:  # the library has no model of the query
                left_out.append(LeftOut(backend=backend.name, reason=str(exc)))
    finally:
        for instance in owned:
            instance.close()
    summaries, cases = [], []
    if answers:  # the scales are those of shapes some backend takes
        if pair:
            scale = np.asarray(pair_scale(shape, points), dtype=np.float64)
            point_rows = np.zeros(reference.shape + (0,))
        else:
            scale = np.asarray(error_scale(shape, points), dtype=np.float64)
            point_rows = np.broadcast_to(np.asarray(points, dtype=np.float64), reference.shape + (shape.dim,))
        for r in answers:
            summary, worst_cases = _summarise(r.backend, r, reference, scale, point_rows, worst)
            summaries.append(summary)
            cases.extend(worst_cases)
    described = f"{_describe(shape)} and {_describe(points)}" if pair else _describe(shape)
    return CrossCheck(
        shape=described,
        reference=method,
        summaries=tuple(summaries),
        worst=tuple(cases),
        left_out=tuple(left_out),
    )


def _describe(shape):
    batch = getattr(shape, "batch_shape", ())
    if batch == () and hasattr(shape, "__len__"):
        return f"{type(shape).__name__} of {len(shape)} primitives"
    return f"{type(shape).__name__} of batch shape {batch}"


def _summarise(name, r, reference, scale, point_rows, worst):
    failure = np.asarray(r.failure).reshape(-1)
    distance = np.asarray(r.result.distance, dtype=np.float64).reshape(-1)
    ref = reference.reshape(-1)
    tolerance = np.asarray(r.tolerance, dtype=np.float64).reshape(-1)
    # A pair in contact has a distance (0) and no witness points: it is compared.
    ok = (failure == Failure.OK) | (failure == Failure.CONTACT)
    gap = np.abs(distance - ref)[ok]
    relative = gap / np.maximum(scale.reshape(-1)[ok], np.finfo(np.float64).tiny)
    counts = {
        Failure(code).name: int(np.sum(failure == code)) for code in np.unique(failure[failure != Failure.OK])
    }
    summary = Summary(
        backend=name,
        model=r.model,
        rows=int(failure.size),
        answered=int(ok.sum()),
        failures=types.MappingProxyType(counts),
        max_disagreement=_stat(np.max, gap),
        median_disagreement=_stat(np.median, gap),
        max_relative=_stat(np.max, relative),
        median_relative=_stat(np.median, relative),
        beyond_tolerance=int(np.sum(gap > tolerance[ok])),
    )
    ratio = gap / tolerance[ok]
    rows = np.flatnonzero(ok)
    order = np.argsort(-ratio, kind="stable")[:worst]
    shape = reference.shape
    flat_points = point_rows.reshape(failure.size, point_rows.shape[-1])
    cases = [
        Case(
            backend=name,
            index=tuple(int(i) for i in np.unravel_index(rows[j], shape)) if shape else (),
            point=tuple(float(x) for x in flat_points[rows[j]]),
            reference=float(ref[rows[j]]),
            distance=float(distance[rows[j]]),
            disagreement=float(gap[j]),
            tolerance=float(tolerance[rows[j]]),
            ratio=float(ratio[j]),
        )
        for j in order
    ]
    return summary, cases


def _stat(func, values):
    return float(func(values)) if values.size else float("nan")


def _num(value, digits=2):
    if value != value:
        return "-"
    return f"{value:.{digits}g}" if digits > 3 else f"{value:.{digits}e}"


def _format(rows):
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() for row in rows]
