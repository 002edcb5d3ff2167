"""Hausdorff distance between triangle meshes, with certified bounds.

The directed distance from a surface ``A`` to a surface ``B`` is
``h(A, B) = max_{a in A} d(a, B)``; the Hausdorff distance is
``H(A, B) = max(h(A, B), h(B, A))``.  It is found by branch and bound over
the faces of ``A`` (the scheme of Tang, Lee and Kim, *Interactive Hausdorff
distance computation for general polygonal models*, SIGGRAPH 2009, and of
Guthe, Borodin and Klein, 2005, with bounds of our own making certain):

* **Lower bound.**  Every point ``a`` of ``A`` gives ``d(a, B) <= h(A, B)``
  (sampled points bound the distance from below, the faces from above).
  The points tried are the vertices of the (sub)triangles of ``A`` and their
  centroids, each evaluated by ``B``'s batched point query.
* **Upper bound of a (sub)triangle ``T`` of ``A``** with vertices ``p_i``
  and centroid ``c``, the least of:

  - ``max_i d(p_i, g)`` for ``g`` among a few candidate faces of ``B``
    (the nearest faces of the ``p_i`` and of ``c``): ``d(., B) <= d(., g)``
    and ``d(., g)`` is convex, so its maximum over ``T`` is at a vertex;
  - ``d(c, B) + max_i |p_i - c|``: ``d(., B)`` is 1-Lipschitz.

* **Branch.**  The (sub)triangles whose upper bound exceeds the lower bound
  by more than ``rtol`` (and the rounding allowance below) are split at
  their edges' midpoints into four, the highest upper bounds first, a batch
  of them at a time; those whose upper bound is at most the best lower
  bound are dropped.  Where one face of ``B`` is nearest to a whole
  (sub)triangle the first bound meets the lower bound at once, so only the
  parts of ``A`` near ``B``'s medial axis, where ``d(., B)`` is near its
  maximum, are split further.

Subtriangles are held by barycentric coordinates over their face, halved
at each split: dyadic numbers, exact in floating point to depth
:data:`MAX_DEPTH`.

Certification.  Every bound is rounded outwards:

* a computed distance ``d~`` is within ``e`` of the exact one: for
  ``certified``, faithful rounding, ``e`` one ulp of ``d~``; for ``robust``,
  the per-triangle bound ``8 eps S + 2^-1075`` of :mod:`proximity.point.triangle`,
  with ``S <= (d~ + D) / (1 - 8 eps)`` and ``D`` the longest edge of ``B``
  (``S`` of the nearest face is at most its distance plus its diameter);
* a posed ``B`` (``mesh.transformed(T)``, ``T = [R | t]``) adds the
  rounding of ``R^T (P - t)``, ``4 eps |P - t|``, and where ``R`` is not
  exactly orthonormal (``e_R = max |R^T R - I|``), ``3 e_R (d + |P - t|)``
  between the query in ``B``'s frame and the affine image ``R B + t``;
* the points of ``A`` are computed in floating point: each is within
  ``delta = 2^-48 (M + |t_A|) + 2^-1060`` of the exact point of ``A`` with
  its barycentric coordinates (``M`` the largest vertex coordinate of ``A``
  in its own frame, ``t_A`` the translation of a posed ``A``), which is
  subtracted from lower bounds and added to upper bounds;
* every sum and product of a bound is rounded up (or down) by one ulp.

So ``lower <= H <= upper`` for the exact surfaces, ``A`` and ``B`` being
the meshes posed exactly by their transforms.  The search stops when
``upper - lower <= max(rtol * upper, atol) + 2 (s + s')``, ``s`` and ``s'`` the
rounding allowances (``e + delta``) of the worst subtriangle's bound and of
the best point: bounds closer than that cannot be told apart in floating
point (identical meshes give ``lower = 0`` and ``upper`` a few ``eps`` of
their size).

Slow cases.  The bounds meet at once where one face of ``B`` is nearest
to a whole subtriangle; elsewhere the gap shrinks with the subtriangles.
Where the distance near its maximum is decided by two faces of ``B`` far
apart compared with the distance, a few levels suffice; but two surfaces
that coincide over an area with different triangulations (distance 0 on
both sides of an edge of ``B``), or curved surfaces much closer than their
faces are wide, need subtriangles as small as the gap wanted along every
such edge: the search stops at ``max_points`` with a warning, its bounds
still certified.
"""

import warnings

import numpy as np

from ..methods import resolve
from ..numerics.rigid import to_local, to_world
from ..results import HausdorffResult
from ..shapes.posed import Posed

__all__ = ["MAX_DEPTH", "hausdorff_distance"]

#: Subtriangles this many halvings deep are not split (their barycentric
#: coordinates stay exact dyadic numbers; their size is ``2^-MAX_DEPTH`` of their face's).
MAX_DEPTH = 48

#: The number of subtriangles split together per round (one batch of point queries).
BATCH = 4096

_EPS = 2.0**-52
_TINY = 2.0**-1074
_INF = np.inf
_METHODS = ("robust", "certified")


def _up(x):
    """The float above ``x``: an upper bound of the exact value ``x`` rounds to nearest."""
    return np.nextafter(x, _INF)


def _down(x):
    return np.nextafter(x, -_INF)


def _norm_up(v):
    """An upper bound of ``|v|`` over the last axis (``hypot``, within one ulp, never over- or underflows)."""
    return _up(_up(np.hypot(np.hypot(v[..., 0], v[..., 1]), v[..., 2])))


def _mesh_of(shape, name):
    """``(mesh, rotation, translation)`` of a mesh or a posed view of one, or a TypeError naming ``name``."""
    from ..shapes.mesh import TriangleMesh

    if type(shape) is TriangleMesh or isinstance(shape, TriangleMesh):
        return shape, None, None
    if isinstance(shape, Posed) and isinstance(shape.shape, TriangleMesh):
        return shape.shape, shape.rotation, shape.translation
    from ..shapes.meshlike import looks_like_a_mesh

    hint = "; use proximity.TriangleMesh(mesh) first" if looks_like_a_mesh(shape) else ""
    raise TypeError(
        f"{name} must be a proximity.TriangleMesh or a posed view of one (mesh.transformed(T)); "
        f"got {type(shape).__name__}{hint}"
    )


class _Surface:
    """The side whose points are tried: faces, vertices in their own frame, pose, and ``delta``."""

    def __init__(self, mesh, rotation, translation):
        self.mesh = mesh
        self.vertices = np.asarray(mesh.vertices)
        self.faces = np.asarray(mesh.faces)
        self.rotation, self.translation = rotation, translation
        scale = float(np.max(np.abs(self.vertices)))
        if translation is not None:
            scale += float(np.max(_norm_up(np.asarray(translation))))
        self.delta = float(_up(2.0**-48 * scale + 2.0**-1060))

    def points(self, face, bary):
        """The points with barycentric coordinates ``bary`` ``(..., 3)`` over faces ``face``, in the world."""
        corners = self.vertices[self.faces[face]]  # (..., 3, 3)
        local = bary[..., 0, None] * corners[..., 0, :] + bary[..., 1, None] * corners[..., 1, :]
        local = local + bary[..., 2, None] * corners[..., 2, :]
        if self.rotation is None:
            return local
        return to_world(local, self.rotation, self.translation)


class _Target:
    """The side measured from: its mesh, pose and the bound of each computed distance."""

    def __init__(self, mesh, rotation, translation, method):
        self.mesh, self.method = mesh, method
        self.rotation, self.translation = rotation, translation
        self.triangles = np.asarray(mesh.triangles)
        edges = self.triangles - np.roll(self.triangles, 1, axis=1)
        span = float(np.max(_norm_up(edges)))  # the longest edge: every face's diameter is at most it
        self.span = span
        if rotation is not None:
            r = np.asarray(rotation)
            e_r = float(np.max(np.abs(r.T @ r - np.eye(3))))
            # r.T @ r rounds each entry by at most 3 eps (entries at most 1): the bound is 4 eps above.
            self.skew = float(_up(3.0 * _up(e_r + 4.0 * _EPS)))

    def local(self, points):
        """``(x, n)``: the points in ``B``'s frame and an upper bound of ``|P - t|`` (0 where unposed)."""
        if self.rotation is None:
            return points, None
        return to_local(points, self.rotation, self.translation), _norm_up(points - self.translation)

    def error(self, d, n):
        """An upper bound of ``|d~ - d(P, B)|`` for computed distances ``d``, from points ``|P - t| <= n``."""
        if self.method == "certified":
            e = np.spacing(d)  # faithful: the exact distance is within one ulp (spacing covers both sides)
        else:
            s = _up(_up(d + self.span) * (1.0 + 9.0 * _EPS))  # S <= (d~ + D) / (1 - 8 eps)
            e = _up(_up(8.0 * _EPS * s) + _TINY)
        if n is not None:
            e = _up(e + _up(4.0 * _EPS * n))
            e = _up(e + _up(self.skew * _up(_up(d + e) + n)))
        return e

    def nearest(self, points):
        """``(d~, e, face)`` of each world point: the distance to ``B``, its bound, the nearest face."""
        x, n = self.local(points)
        r = self.mesh.closest_point(x, method=self.method)
        d = np.asarray(r.distance, np.float64)
        return d, self.error(d, n), np.asarray(r.face, np.int64)

    def closest(self, point):
        """The closest point of ``B`` to one world point, in the world."""
        x, _ = self.local(point)
        p = np.asarray(self.mesh.closest_point(x, method=self.method).point)
        return p if self.rotation is None else to_world(p, self.rotation, self.translation)

    def face_bounds(self, points, faces):
        """Upper bounds ``(n, k, 3)`` of ``d(P, g)``: corners ``(n, 3, 3)``, faces ``(n, k)`` of ``B``."""
        from ..shapes.base import Triangle

        x, m = self.local(points)
        tri = Triangle(self.triangles[faces][:, :, None])  # batch (n, k, 1)
        d = np.asarray(tri.distance(x[:, None], method=self.method), np.float64)  # (n, k, 3)
        e = self.error(d, None if m is None else np.broadcast_to(m[:, None], d.shape))
        return _up(d + e)


class _Items:
    """Open (sub)triangles of ``A``: face, corners' barycentrics, corner points and their answers, bound."""

    __slots__ = ("face", "bary", "depth", "points", "d", "e", "g", "upper", "slack")

    def __init__(self, **fields):
        for name in self.__slots__:
            setattr(self, name, fields[name])

    def __len__(self):
        return len(self.face)

    def take(self, keep):
        return _Items(**{name: getattr(self, name)[keep] for name in self.__slots__})

    @staticmethod
    def join(parts):
        names = _Items.__slots__
        return _Items(**{name: np.concatenate([getattr(p, name) for p in parts]) for name in names})


class _Search:
    """The branch and bound of one direction, ``h(A, B)``."""

    def __init__(self, surface, target, tolerance, floor, budget):
        self.surface, self.target, self.budget = surface, target, budget
        self.rtol, self.atol = tolerance
        self.floor = floor  # a lower bound of the answer found elsewhere (the other direction)
        self.lower = 0.0  # of this direction: the best point's certified distance
        self.best = None  # (point, d~, slack)
        self.best_slack = 0.0
        self.evaluated = 0

    def evaluate(self, points):
        """Distances of ``points`` ``(n, 3)`` to ``B``; updates the best lower bound."""
        d, e, g = self.target.nearest(points)
        self.evaluated += len(points)
        lo = np.maximum(_down(_down(d - e) - self.surface.delta), 0.0)
        if len(lo):
            k = int(np.argmax(lo))
            if self.best is None or lo[k] > self.lower:
                self.lower = float(lo[k])
                self.best = (points[k], float(d[k]))
                self.best_slack = float(_up(e[k] + self.surface.delta))
        return d, e, g

    def bound(self, face, bary, depth, points, d, e, g):
        """The items of these subtriangles (corner answers given), their centroids evaluated."""
        centroid_bary = (bary[:, 0] + bary[:, 1] + bary[:, 2]) / 3.0
        c = self.surface.points(face, centroid_bary)
        dc, ec, gc = self.evaluate(c)
        delta = self.surface.delta
        candidates = np.concatenate([g, gc[:, None]], axis=1)  # (n, 4)
        by_face = self.target.face_bounds(points, candidates).max(axis=2).min(axis=1)
        radius = _norm_up(points - c[:, None]).max(axis=1)
        lipschitz = _up(_up(dc + ec) + radius)
        upper = _up(np.minimum(by_face, lipschitz) + delta)
        slack = _up(np.maximum(e.max(axis=1), ec) + delta)
        return _Items(face=face, bary=bary, depth=depth, points=points, d=d, e=e, g=g, upper=upper,
                      slack=slack)  # fmt: skip

    def start(self):
        """Every face of ``A`` as an item; its vertices evaluated once each."""
        surface = self.surface
        n_vertices = len(surface.vertices)
        eye = np.eye(3)
        vertex_points = surface.vertices
        if surface.rotation is not None:
            vertex_points = to_world(vertex_points, surface.rotation, surface.translation)
        used = np.unique(surface.faces)
        d = np.full(n_vertices, np.nan)
        e = np.full(n_vertices, np.nan)
        g = np.full(n_vertices, -1, np.int64)
        d[used], e[used], g[used] = self.evaluate(np.ascontiguousarray(vertex_points[used]))
        parts = []
        for start in range(0, len(surface.faces), 8 * BATCH):
            face = np.arange(start, min(start + 8 * BATCH, len(surface.faces)))
            corners = surface.faces[face]
            bary = np.broadcast_to(eye, (len(face), 3, 3)).copy()
            parts.append(self.bound(face, bary, np.zeros(len(face), np.int64), vertex_points[corners],
                                    d[corners], e[corners], g[corners]))  # fmt: skip
        return _Items.join(parts)

    def split(self, items):
        """The four children of each item: new corners at the edges' midpoints."""
        n = len(items)
        b = items.bary
        mid = np.stack([(b[:, 0] + b[:, 1]) / 2.0, (b[:, 1] + b[:, 2]) / 2.0, (b[:, 2] + b[:, 0]) / 2.0], 1)
        face3 = np.repeat(items.face[:, None], 3, axis=1)
        mp = self.surface.points(face3, mid)  # (n, 3, 3)
        md, me, mg = self.evaluate(mp.reshape(-1, 3))
        md, me, mg = md.reshape(n, 3), me.reshape(n, 3), mg.reshape(n, 3)
        # Corners: 0, 1, 2 the item's, 3, 4, 5 the midpoints of edges 01, 12, 20.
        bary6 = np.concatenate([b, mid], axis=1)
        pts6 = np.concatenate([items.points, mp], axis=1)
        d6 = np.concatenate([items.d, md], axis=1)
        e6 = np.concatenate([items.e, me], axis=1)
        g6 = np.concatenate([items.g, mg], axis=1)
        children = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])
        rows = np.arange(n)[:, None, None]
        pick = (rows, children[None])

        def cut(a):
            return a[pick].reshape((4 * n, 3) + a.shape[2:])

        face = np.repeat(items.face, 4)
        depth = np.repeat(items.depth + 1, 4)
        return self.bound(face, cut(bary6), depth, cut(pts6), cut(d6), cut(e6), cut(g6))

    def run(self):
        """``(lower, upper, converged)`` of this direction (items below ``floor`` dropped)."""
        items = self.start()
        self.budget += self.evaluated  # the first pass (every vertex and face) is not counted
        converged = True
        while True:
            level = max(self.lower, self.floor)
            items = items.take(items.upper > level)
            if not len(items):
                break
            wanted = np.maximum(self.rtol * items.upper, self.atol)
            allowance = _up(wanted + 2.0 * _up(items.slack + self.best_slack))
            open_ = items.upper - level > allowance
            if not open_.any():
                break
            open_ &= items.depth < MAX_DEPTH
            if not open_.any() or self.evaluated >= self.budget:
                converged = False
                break
            index = np.flatnonzero(open_)
            if len(index) > BATCH:
                index = index[np.argpartition(items.upper[index], -BATCH)[-BATCH:]]
            keep = np.ones(len(items), bool)
            keep[index] = False
            items = _Items.join([items.take(keep), self.split(items.take(index))])
        upper = max(self.lower, float(items.upper.max())) if len(items) else self.lower
        return self.lower, upper, converged


def _check_tolerance(value, name, least):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number {least}; got {type(value).__name__}")
    number = float(value)
    if not (np.isfinite(number) and (number > 0.0 if least == "> 0" else number >= 0.0)):
        raise ValueError(f"{name} must be a finite number {least}; got {value!r}")
    return number


def _check_budget(max_points):
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)):
        raise TypeError(f"max_points must be an int >= 1; got {type(max_points).__name__}")
    if max_points < 1:
        raise ValueError(f"max_points must be >= 1; got {max_points!r}")
    return int(max_points)


def hausdorff_distance(a, b, *, directed=False, rtol=1e-6, atol=0.0, method="robust", max_points=250_000):
    """The Hausdorff distance between two meshes; see :func:`proximity.hausdorff_distance`."""
    mesh_a, ra, ta = _mesh_of(a, "a")
    mesh_b, rb, tb = _mesh_of(b, "b")
    tolerance = (_check_tolerance(rtol, "rtol", "> 0"), _check_tolerance(atol, "atol", ">= 0"))
    budget = _check_budget(max_points)
    if not isinstance(directed, (bool, np.bool_)):
        raise TypeError(f"directed must be True or False; got {directed!r}")
    name = resolve(method).name
    if name not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS} for a Hausdorff distance; got {method!r}")
    with np.errstate(invalid="ignore", over="ignore"):
        forward = _Search(_Surface(mesh_a, ra, ta), _Target(mesh_b, rb, tb, name), tolerance, 0.0, budget)
        lower, upper, converged = forward.run()
        searches = [(forward, "a")]
        if not directed:
            # h(b, a) matters only where it exceeds h(a, b)'s lower bound: it prunes the second search.
            backward = _Search(_Surface(mesh_b, rb, tb), _Target(mesh_a, ra, ta, name), tolerance, lower,
                               budget)  # fmt: skip
            lower_b, upper_b, converged_b = backward.run()
            lower, upper, converged = max(lower, lower_b), max(upper, upper_b), converged and converged_b
            searches.append((backward, "b"))
    search, side = max(searches, key=lambda s: s[0].lower)
    point, d = search.best
    other = search.target.closest(point)
    point_a, point_b = (point, other) if side == "a" else (other, point)
    if not converged:
        warnings.warn(
            f"hausdorff_distance stopped before reaching rtol={rtol:g}, atol={atol:g} (max_points={budget} "
            "points evaluated "
            f"per direction, or subtriangles {MAX_DEPTH} halvings deep): the distance is between {lower!r} "
            f"and {upper!r}",
            RuntimeWarning,
            stacklevel=3,
        )
    return HausdorffResult(
        distance=min(max(d, lower), upper),
        lower=lower,
        upper=upper,
        point_a=np.array(point_a, np.float64),
        point_b=np.array(point_b, np.float64),
        side=side,
        directed=bool(directed),
        converged=converged,
        points_evaluated=sum(s.evaluated for s, _ in searches),
    )
