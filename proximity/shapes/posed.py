"""Posed views: a shape moved by a rigid transform, sharing the shape's data.

``shape.transformed(T)`` returns a :class:`Posed` view in O(1): no copy of
the vertices, no new hierarchy.  A query moves its points into the shape's
own frame, ``R^T (P - t)``, asks the shape, and moves the closest points
(and normals) back, ``R X + t``; distances, features and parameters are
the shape's.  A shape without a batch of its own answers each point on its
own, and a large batch is moved and asked :data:`CHUNK` points at a time,
so that the moved copy costs a part's memory, not the batch's.  A scene of
posed views of one mesh shares the mesh's hierarchy (instancing,
:class:`proximity.Scene`).

Accuracy.  The transform ``T = [[R, t], [0, 1]]`` is rigid when ``R`` is
orthonormal with determinant +1; it is accepted when ``max |R^T R - I|``,
``e_R``, is at most :data:`RIGID_TOLERANCE`.  The answer is the shape's
own, within its bound, for the point ``R^T (P - t)`` as computed in floating
point, which is within ``3 eps |P - t|`` of the exact one; and the shape
posed by ``T`` exactly is within ``e_R |P - t|`` of the one posed rigidly.
So ``robust`` is within ``8 eps S + 2^-1075 + (3 eps + e_R) |P - t|`` of
the exact distance to the posed shape, ``S`` the shape's own size of the
query; ``certified`` is faithfully rounded for the moved point (not for the
exactly posed shape, which is not representable in floating point: its
vertices ``R V + t`` round), so within one ulp plus ``(3 eps + e_R) |P - t|``.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import ArrayLike, Bools, Distances, Floats, Transform
from .._validate import as_float64, freeze_result, frozen
from ..numerics.rigid import RIGID_TOLERANCE, rigid, rotate, to_local, to_world
from ..results import asdict, attach_frame, format_repr, posed_normals
from .base import DEFAULT_METHOD, VIEWS, Frozen, keyword_only

if TYPE_CHECKING:
    from ..results import Result
    from .base import Shape
    from .rounded import Inflated

__all__ = ["RIGID_TOLERANCE", "Posed", "rigid"]

#: Points moved into the shape's frame and asked at a time, where each point's
#: answer is its own (a shape without a batch of its own): the moved copy of a
#: large batch then costs 24 MiB rather than 24 bytes a point, and so does the
#: scratch of the shape's query.
CHUNK = 1 << 20


class Posed(Frozen):
    """A shape moved by a rigid transform, as a view that shares the shape's data.

    Parameters
    ----------
    shape : Shape
        Any 3D shape of the package, its batch included.
    transform : array_like, shape ``(4, 4)``
        ``[[R, t], [0, 0, 0, 1]]``: the shape's points ``X`` are at
        ``R X + t``.  ``R`` orthonormal with determinant +1 (within
        :data:`RIGID_TOLERANCE`).

    Notes
    -----
    Made by every shape's ``transformed(T)``; posing a posed view composes
    the transforms.  Answers are in world coordinates; see
    :mod:`proximity.shapes.posed` for their accuracy.

    Examples
    --------
    >>> import numpy as np, proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> T = np.eye(4); T[:3, 3] = [0, 0, 5]          # moved up by 5
    >>> r = tri.transformed(T).closest_point([0.25, 0.25, 7.0])
    >>> float(r.distance), r.point.tolist()
    (2.0, [0.25, 0.25, 5.0])
    """

    __slots__ = ("shape", "rotation", "translation", "batch_shape", "dim")
    _public = ("__init__", "distance", "closest_point")

    def __init__(self, shape: Shape, transform: Transform) -> None:
        if not hasattr(shape, "closest_point") or not hasattr(shape, "batch_shape"):
            raise TypeError(f"shape must be a proximity shape; got {type(shape).__name__}")
        if shape.dim != 3:
            raise ValueError(f"shape must be 3D to be transformed; got a {shape.dim}D {type(shape).__name__}")
        r, t = rigid(transform)
        if r.shape != (3, 3):
            raise ValueError(f"transform must be one 4x4 matrix; got shape {r.shape[:-2] + (4, 4)}")
        if isinstance(shape, Posed):
            # X -> R (R' X + t') + t: the inner pose first.
            r, t = frozen(r @ shape.rotation, new=True), frozen(r @ shape.translation + t, new=True)
            shape = shape.shape
        self._init(shape=shape, rotation=r, translation=t, batch_shape=shape.batch_shape, dim=3)

    @classmethod
    def _at(cls, shape, rotation, translation):
        """A view of ``shape`` at a pose already validated (no checks)."""
        view = object.__new__(cls)
        view._init(
            shape=shape, rotation=rotation, translation=translation, batch_shape=shape.batch_shape, dim=3
        )
        return view

    @property
    def methods(self) -> tuple[str, ...]:
        """The values ``method`` accepts: the shape's."""
        return self.shape.methods

    @property
    def result_type(self) -> type[Result]:
        """The class of :meth:`closest_point`'s results: the shape's."""
        return self.shape.result_type

    @property
    def transform(self) -> Floats:
        """The 4x4 matrix of the pose."""
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = self.rotation, self.translation
        return m

    def __repr__(self):
        return format_repr(self, ("rotation", "translation"), shape=self.shape)

    def transformed(self, transform: Transform) -> Posed:
        """The view moved by ``transform`` as well: the composed pose."""
        return Posed(self, transform)

    def inflated(self, radius: ArrayLike) -> Inflated:
        """The points within ``radius`` of the posed shape (:class:`proximity.Inflated`)."""
        return VIEWS["rounded"](self, radius)

    def _points(self, points):
        """``points`` as float64 of shape ``(..., 3)``, or a ValueError naming them."""
        p = as_float64(points, "points", "(..., 3)")
        if p.ndim == 0 or p.shape[-1] != 3:
            raise ValueError(f"points must have shape (..., 3); got shape {p.shape}")
        return p

    def _each(self, p, answer):
        """``answer(local)``, a dict of arrays, for the points ``p`` moved to the
        shape's frame (``R^T (P - t)``, as ``(P - t) R``).

        Where the shape has no batch of its own, a batch of more than
        :data:`CHUNK` points is moved and answered :data:`CHUNK` points at a
        time (each point's answer is its own, whatever else is asked with
        it), and the answers' rows are joined into arrays of the batch,
        read-only where a part's are.
        """
        batch = p.shape[:-1]
        n = math.prod(batch)
        if self.batch_shape != () or n <= CHUNK:
            return answer(to_local(p, self.rotation, self.translation))
        flat = p.reshape(-1, 3)
        joined, frozen = {}, set()
        for lo in range(0, n, CHUNK):
            part = answer(to_local(flat[lo : lo + CHUNK], self.rotation, self.translation))
            for name, value in part.items():
                value = np.asarray(value)
                if name not in joined:
                    joined[name] = np.empty((n,) + value.shape[1:], value.dtype)
                joined[name][lo : lo + len(value)] = value
                if not value.flags.writeable:
                    frozen.add(name)
            part = value = None  # its arrays freed before the next part is asked
        out = {name: value.reshape(batch + value.shape[1:]) for name, value in joined.items()}
        return {name: freeze_result(value) if name in frozen else value for name, value in out.items()}

    def distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Distances:
        """Distance from each point to the posed shape; see :func:`proximity.distance`."""
        if args:
            raise keyword_only(self, "distance", args)

        def answer(local):
            return {"distance": self.shape.distance(local, method=method, max_distance=max_distance)}

        return self._each(self._points(points), answer)["distance"]

    def signed_distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
        **options: Any,
    ) -> Distances:
        """The shape's signed distance at the moved points (meshes, scenes and rounded shapes)."""
        if args:
            raise keyword_only(self, "signed_distance", args)
        if max_distance is not None:
            options["max_distance"] = max_distance

        def answer(local):
            return {"distance": self.shape.signed_distance(local, method=method, **options)}

        return self._each(self._points(points), answer)["distance"]

    def contains(self, points: ArrayLike, *args: object, **options: Any) -> Bools:
        """Whether each point is in the posed shape (meshes and rounded shapes)."""
        if args:
            raise keyword_only(self, "contains", args)

        def answer(local):
            return {"inside": self.shape.contains(local, **options)}

        return self._each(self._points(points), answer)["inside"]

    def closest_point(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Result:
        """Closest point on the posed shape to each point, in world coordinates.

        The result is the shape's, with ``point`` (and ``normal``) moved back
        to the world; see :func:`proximity.closest_point`.
        """
        if args:
            raise keyword_only(self, "closest_point", args)
        p = self._points(points)
        whole = self.batch_shape != () or math.prod(p.shape[:-1]) <= CHUNK
        kept = {}  # the shape's result's type; with one part, the result itself

        def answer(local):
            core = self.shape.closest_point(local, method=method, max_distance=max_distance)
            kept["type"] = type(core)
            if whole:
                kept["core"] = core
            fields = asdict(core)
            fields["point"] = to_world(np.asarray(core.point), self.rotation, self.translation)
            return fields

        fields = self._each(p, answer)
        result = kept["type"](**fields)
        if whole:
            # One part: its normals are the shape's, from the moved point and the shape's
            # closest point (in the world, the two differ by the rounding of both moves
            # besides), turned to the world; the moved point is within rounding of the world's
            # coordinates.
            normals = functools.partial(posed_normals, kept["core"], self.rotation, p, self.translation)
            return attach_frame(result, normals)
        # Several parts: the shape's results are not kept (their memory is what the parts
        # save), so that the normals, when asked, ask each part again.
        return attach_frame(result, functools.partial(self._part_normals, p, method, max_distance))

    def _part_normals(self, p, method, max_distance):
        """The normals of a batch answered a part at a time, each part asked again (the same
        bits as the whole batch's: every step of a row's normal is the row's own)."""
        flat = p.reshape(-1, 3)
        out = np.empty(flat.shape)
        for lo in range(0, len(flat), CHUNK):
            part = flat[lo : lo + CHUNK]
            local = to_local(part, self.rotation, self.translation)
            core = self.shape.closest_point(local, method=method, max_distance=max_distance)
            out[lo : lo + len(part)] = posed_normals(core, self.rotation, part, self.translation)
        return out.reshape(p.shape)

    def _feature_normals(self, index, feature, points):
        """The shape's normals on elements ``index`` (see :attr:`Result.normal`), for
        world points ``points``: computed in the shape's frame, turned to the world."""
        local = to_local(np.asarray(points, dtype=np.float64), self.rotation, self.translation)
        return rotate(self.shape._feature_normals(index, feature, local), self.rotation)

    def _rows(self):
        """The shape's rows, moved to the world (see :func:`proximity.primitives.transform_rows`)."""
        from ..primitives import transform_rows

        rows = self.shape._rows()
        kinds, params = rows[:2]
        return (kinds, transform_rows(kinds, params, self.rotation, self.translation), *rows[2:])


VIEWS["posed"] = Posed
