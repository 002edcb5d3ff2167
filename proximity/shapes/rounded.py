"""Rounded solids: the points within a radius of a shape.

``shape.inflated(radius)`` is the set of points within ``radius`` of
``shape``: a sphere from a point, a capsule from a segment, a rounded
triangle, a torus from a circle, a thick shell from a mesh.  Its distance
is the core's distance ``d`` less the radius: ``max(d - r, 0)`` unsigned,
``d - r`` signed (negative inside: the depth of penetration), and its
closest point the point of its surface nearest the query point, reached
from the core's closest point towards the point (or, from a point on the
core, along the core's normal).  The feature and the other fields are
the core's: they name where on the core the nearest point lies.

Inside a solid whose core is not convex (a circle, a mesh, a scene), the
balls around distant parts of the core overlap, and ``d - r`` is a lower
bound on the depth (the distance to the surface), which it equals where
the nearest core point's ball holds the nearest surface point.  The
closest point of a circle rounded by more than its radius (a spindle
torus) is exact: where the path from the nearest circle point crosses the
axis, it is the cusp where the surface meets the axis.  For meshes and
scenes, the point reached from the nearest core point may lie inside the
solid, where another part of the core is within ``r`` of it.  Outside the
solid (``d >= r``) the answers are the solid's own, to the bounds below.

Accuracy.  ``robust``: the core's distance is within ``8 eps S_core`` of
the exact one and ``d - r`` rounds once more, by at most ``eps/2 (S_core
+ r)``; the bound is stated as ``8 eps S + 2^-1075`` with ``S = S_core +
r``.  ``certified``: ``d`` is faithful, so ``d* - r`` lies within
``ulp(d)`` of ``d - r``; where that interval holds only ``d - r`` and its
neighbours the answer is taken, elsewhere (``d`` close to ``r``, where the
subtraction cancels) the exact squared distance is narrowed until the
rounding of ``sqrt(s) - r`` is decided (:func:`proximity.numerics.exact.minus_radius`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .. import primitives
from .._typing import ArrayLike, Bools, Distances, Floats
from .._validate import broadcast_batch, cutoff, freeze_result, frozen_float64, require_finite
from ..features import FACE
from ..numerics.rounding import (
    added_radii,
    certify_difference,
    outward,
    spindle_points,
    surface_points,
    total_radius,
)
from ..results import asdict, beyond, format_repr
from .base import DEFAULT_METHOD, VIEWS, Circle, Frozen, Point, Segment, check_method, keyword_only

if TYPE_CHECKING:
    from ..results import Result
    from .base import Shape

__all__ = ["Capsule", "Inflated", "Sphere"]


class Inflated(Frozen):
    """The points within ``radius`` of a shape: a rounded solid.

    Parameters
    ----------
    core : Shape
        Any shape of the package: a triangle, segment, point, disk or
        circle (or a batch of them), a mesh, a scene, or another rounded
        shape.
    radius : array_like, shape ``batch``
        Finite, >= 0; broadcasts with the core's batch dimensions.
    copy : bool, keyword-only, default False
        As for the other shapes: a C-contiguous float64 radius array is
        viewed without a copy unless ``copy=True``.

    Notes
    -----
    Made by :meth:`proximity.Triangle.inflated` and the other shapes'
    ``inflated``; :class:`Sphere` and :class:`Capsule` are the named
    forms.  See :mod:`proximity.shapes.rounded` for the closest point on the
    surface and the accuracy of each method.

    Examples
    --------
    >>> import proximity
    >>> pill = proximity.Segment([[0, 0, 0], [2, 0, 0]]).inflated(0.5)
    >>> pill.distance([[1, 2, 0], [1, 0.25, 0]]).tolist()
    [1.5, 0.0]
    >>> pill.signed_distance([[1, 0.25, 0]]).tolist()      # 0.25 deep
    [-0.25]
    >>> pill.closest_point([1, 2, 0]).point.tolist()
    [1.0, 0.5, 0.0]
    """

    __slots__ = ("core", "radius", "batch_shape", "dim")
    _public = ("__init__", "distance", "closest_point", "signed_distance", "contains")

    def __init__(self, core: Shape, radius: ArrayLike, *, copy: bool = False) -> None:
        if not hasattr(core, "_rows") or not hasattr(core, "closest_point"):
            raise TypeError(f"core must be a proximity shape; got {type(core).__name__}")
        r = frozen_float64(radius, "radius", "(...)", copy)
        require_finite(r, "radius")
        if (r < 0).any():
            index = tuple(int(i) for i in np.argwhere(r < 0)[0])
            raise ValueError(f"radius must be >= 0; got {r[index]} at index {index}")
        if isinstance(core, Inflated):
            # Rounding a rounded shape adds the radii (in floating point).
            r = frozen_float64(added_radii(core.radius, r), "radius", "(...)")
            core = core.core
        batch = broadcast_batch(
            [("core", core.batch_shape), ("radius", r.shape)], "the batch dimensions of core and radius"
        )
        # Below a posed view the radii are added by the queries that see through it: their sum
        # must be finite too.
        radii, inner, posed = [r], core, VIEWS.get("posed", Inflated)
        while isinstance(inner, (posed, Inflated)):
            if isinstance(inner, Inflated):
                radii.append(inner.radius)
                inner = inner.core
            else:
                inner = inner.shape
        if len(radii) > 1:
            total_radius(radii)
        self._init(core=core, radius=r, batch_shape=batch, dim=core.dim)

    @property
    def methods(self) -> tuple[str, ...]:
        """The values ``method`` accepts: the core's."""
        return self.core.methods

    @property
    def result_type(self) -> type[Result]:
        """The class of :meth:`closest_point`'s results: the core's."""
        return self.core.result_type

    def __repr__(self):
        return format_repr(self, ("radius",), core=self.core)

    def inflated(self, radius: ArrayLike) -> Inflated:
        """The points within ``radius`` of this rounded shape: the core
        inflated by the sum of the radii (rounded to a float)."""
        return Inflated(self, radius)

    def _rows(self):
        """``(kinds, params, radii)`` of every member of the batch, in C order,
        as a collection stores them (a rounded collection: all its primitives,
        for each radius)."""
        kinds, params = self.core._rows()
        batch = self.batch_shape
        count = int(np.prod(batch, dtype=int))
        if self.core.batch_shape == () and len(kinds) != 1:
            index = np.tile(np.arange(len(kinds)), count)
            radii = np.repeat(np.broadcast_to(self.radius, batch).reshape(-1), len(kinds))
        else:
            index = np.broadcast_to(np.arange(len(kinds)).reshape(self.core.batch_shape), batch).reshape(-1)
            radii = np.broadcast_to(self.radius, batch).reshape(-1)
        return kinds[index], params[index], np.array(radii, dtype=np.float64)

    def _answer(self, points, method, full):
        """``(signed distance, result or None)``: the core's answer, rounded."""
        method = check_method(method, self.methods)
        # The certified method's exact fallback needs each row's nearest
        # primitive, which a collection's distances alone do not say.
        full = full or (method.exact_fallback and not hasattr(self.core, "_primitive"))
        if full:
            core = self.core.closest_point(points, method=method.name)
            d = np.asarray(core.distance)
        else:
            core, d = None, np.asarray(self.core.distance(points, method=method.name))
        r = self.radius
        shape = np.broadcast_shapes(d.shape, r.shape)
        d, r = np.broadcast_to(d, shape), np.broadcast_to(r, shape)
        with np.errstate(invalid="ignore"):
            e = d - r
        if method.exact_fallback:
            e = certify_difference(e, d, r, lambda rows: self._exact_rows(core, points, shape, rows))
        return e, core, shape

    def _exact_rows(self, core, points, shape, rows):
        """Per flat row of ``rows``: ``(primitive, params, point)`` of the core's nearest primitive."""
        return _primitive_rows(self.core, core, points, shape, rows)

    def distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Distances:
        """Distance from each point to the rounded solid: ``max(d - r, 0)``.

        Parameters and broadcasting are those of :func:`proximity.distance`;
        ``max_distance`` is a cutoff, as for the other shapes.
        """
        if args:
            raise keyword_only(self, "distance", args)
        limit = cutoff(max_distance)
        e, _, _ = self._answer(points, method, full=False)
        return _frozen(beyond(np.maximum(e, 0.0) + 0.0, limit))

    def signed_distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Distances:
        """Signed distance to the rounded solid's surface, ``d - r``: negative inside.

        Examples
        --------
        >>> import proximity
        >>> ball = proximity.Sphere([0, 0, 0], 1.0)
        >>> ball.signed_distance([[0, 0, 0], [0, 3, 0]]).tolist()
        [-1.0, 2.0]
        """
        if args:
            raise keyword_only(self, "signed_distance", args)
        limit = cutoff(max_distance)
        e, _, _ = self._answer(points, method, full=False)
        return _frozen(beyond(e + 0.0, limit))

    def contains(self, points: ArrayLike, *args: object, method: str = DEFAULT_METHOD) -> Bools:
        """Whether each point is in the rounded solid: within ``r`` of the core."""
        if args:
            raise keyword_only(self, "contains", args)
        e, _, _ = self._answer(points, method, full=False)
        return _frozen(e <= 0.0)

    def closest_point(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Result:
        """The nearest point of the rounded solid's surface to each point.

        Returns the core's result type: ``distance`` and ``sqr_distance``
        of the solid (0 inside), ``point`` on its surface, the core's other
        fields.  For a point inside, the surface point nearest it.
        """
        if args:
            raise keyword_only(self, "closest_point", args)
        limit = cutoff(max_distance)
        e, core, shape = self._answer(points, method, full=True)
        p = np.broadcast_to(np.asarray(points, dtype=np.float64), shape + (self.dim,))
        c = np.broadcast_to(np.asarray(core.point), shape + (self.dim,))
        d = np.broadcast_to(np.asarray(core.distance), shape)
        r = np.broadcast_to(self.radius, shape)
        rows_of = lambda rows: _primitive_arrays(self._exact_rows(core, points, shape, rows))  # noqa: E731
        point = surface_points(p, c, d, r, rows_of)
        # Its normals: the rounded surface's, outwards (along P - point where P is outside);
        # the core's where the core's closest point is on a face.
        face = np.broadcast_to(np.asarray(core.feature), shape) == FACE
        normal = outward(point, c, r, np.broadcast_to(np.asarray(core.normal), point.shape), face)
        if isinstance(self.core, Circle):
            point, normal = spindle_points(point, normal, d, r, self.core, core)
        distance = np.maximum(e, 0.0) + 0.0
        fields = {name: np.broadcast_to(value, shape + np.shape(value)[np.ndim(core.distance) :])
                  for name, value in asdict(core).items()}  # fmt: skip
        with np.errstate(over="ignore", under="ignore"):
            fields.update(distance=distance, sqr_distance=distance * distance, point=point)
        result = type(core)(**fields)
        result.__dict__["_normal"] = freeze_result(np.array(normal))
        if limit < np.inf:
            far = np.asarray(result.distance) > limit
            result = beyond(result, limit)
            result.__dict__["_normal"] = freeze_result(np.where(far[..., None], np.nan, normal))
        return result


VIEWS["rounded"] = Inflated


class Sphere(Inflated):
    """A batch of balls: the points within ``radius`` of ``center``.

    ``Sphere(center, radius)`` is ``Point(center).inflated(radius)``.

    Examples
    --------
    >>> import proximity
    >>> ball = proximity.Sphere(center=[0, 0, 0], radius=2.0)
    >>> ball.distance([[0, 0, 5], [0, 1, 0]]).tolist()
    [3.0, 0.0]
    >>> ball.closest_point([0, 0, 5]).point.tolist()
    [0.0, 0.0, 2.0]
    """

    __slots__ = ()

    def __init__(self, center: ArrayLike, radius: ArrayLike, *, copy: bool = False) -> None:
        super().__init__(Point(center, copy=copy), radius, copy=copy)

    @property
    def center(self) -> Floats:
        """The centers, ``batch + (D,)``."""
        return self.core.position

    def __repr__(self):
        return format_repr(self, ("center", "radius"))


class Capsule(Inflated):
    """A batch of capsules: the points within ``radius`` of a segment.

    ``Capsule(vertices, radius)`` is ``Segment(vertices).inflated(radius)``.

    Examples
    --------
    >>> import proximity
    >>> rod = proximity.Capsule([[0, 0, 0], [0, 0, 4]], radius=0.5)
    >>> rod.distance([[3, 0, 2], [0, 0, 6]]).tolist()
    [2.5, 1.5]
    """

    __slots__ = ()

    def __init__(self, vertices: ArrayLike, radius: ArrayLike, *, copy: bool = False) -> None:
        super().__init__(Segment(vertices, copy=copy), radius, copy=copy)

    @property
    def vertices(self) -> Floats:
        """The segments' endpoints, ``batch + (2, D)``."""
        return self.core.vertices

    def __repr__(self):
        return format_repr(self, ("vertices", "radius"))


def _frozen(value):
    """An output: a read-only array, a NumPy scalar for one query."""
    return freeze_result(np.array(value))[()]


def _core_rows(core):
    """``(kinds, params, radii)`` of a shape's primitives, radii 0 where not rounded."""
    rows = core._rows()
    if len(rows) == 3:
        return rows
    kinds, params = rows
    return kinds, params, np.zeros(len(kinds))


def _primitive_rows(shape, result, points, out_shape, rows):
    """Per flat row of ``rows`` of a query of ``shape``: ``(primitive, params,
    point)`` of the primitive nearest the point (for a batch of primitives,
    the batch member the row queried; for a collection, the face or
    primitive of ``result``)."""
    pts = np.asarray(points, dtype=np.float64)
    pts = np.broadcast_to(pts, out_shape + (shape.dim,)).reshape(-1, shape.dim)
    pts = np.concatenate([pts, np.zeros((len(pts), 3 - shape.dim))], axis=1)
    kinds, params = shape._rows()[:2]
    if shape.batch_shape == () and len(kinds) > 1:  # a collection: its nearest primitive
        index = np.asarray(getattr(result, "face", getattr(result, "primitive", None))).reshape(-1)
        index = np.broadcast_to(index, (len(pts),))
    else:
        index = np.broadcast_to(np.arange(len(kinds)).reshape(shape.batch_shape), out_shape).reshape(-1)
    out = []
    for k in rows:
        i = int(index[k])
        out.append((primitives.BY_CODE[kinds[i]], params[i], pts[k]))
    return out


def _primitive_arrays(rows):
    kinds = np.array([p.code for p, _, _ in rows], np.int8)
    return kinds, np.array([q for _, q, _ in rows])
