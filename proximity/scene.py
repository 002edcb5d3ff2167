"""Scenes: the nearest of many triangles, disks and circles to each point.

A :class:`Scene` is a flat list of primitives gathered from shapes (each shape
may be a batch).  Triangles stay triangles and disks and circles stay
analytic: nothing is tessellated.  Each query returns the nearest primitive's
answer, computed by the same per-primitive method as a single-shape query
(see :mod:`proximity.bvh`), with the index of that primitive.

The broad phase is chosen once, at construction: brute force over every
primitive for small scenes, a bounding-volume hierarchy above
:data:`BRUTE_FORCE_MAX` primitives.  Both give the same answer, bit for bit.
"""

import numpy as np

from . import _threads
from ._validate import as_float64, frozen
from .results import SceneResult
from .shapes import DEFAULT_METHOD, Circle, Disk, Frozen, Triangle, check_method, keyword_only

BROAD_PHASES = ("auto", "brute", "bvh")

#: Largest number of primitives for which ``broad_phase="auto"`` uses brute
#: force: up to ``LEAF_SIZE`` primitives the hierarchy is a single leaf and
#: saves nothing.  Measured with ``python -m benchmarks.meshes --crossover``;
#: the measurement is in ``docs/performance.md``.
BRUTE_FORCE_MAX = 4

_KIND_NAMES = ("triangle", "disk", "circle")


class _Nearest(Frozen):
    """What meshes and scenes share: validation, broad phase and the query.

    Subclasses set ``_tree`` (the broad phase of :mod:`proximity.bvh`),
    ``methods`` and ``_has_circles``, and implement ``_result``.
    """

    __slots__ = ()
    batch_shape = ()
    dim = 3

    @staticmethod
    def _tree_for(kinds, params, broad_phase):
        """``(resolved broad phase, tree)`` for primitives ``kinds``, ``params``."""
        if broad_phase not in BROAD_PHASES:
            raise ValueError(f"broad_phase must be one of {BROAD_PHASES}; got {broad_phase!r}")
        if broad_phase == "auto":
            broad_phase = "brute" if len(kinds) <= BRUTE_FORCE_MAX else "bvh"
        with _threads.kernel():
            from . import bvh

            tree = bvh.build(kinds, params) if broad_phase == "bvh" else bvh.brute(kinds, params)
        return broad_phase, tree

    def _query(self, points, method, full):
        method = check_method(method, self.methods)
        points = as_float64(points, "points", "(..., 3)")
        if points.ndim == 0 or points.shape[-1] != 3:
            raise ValueError(f"points must have shape (..., 3); got shape {points.shape}")
        out_shape = points.shape[:-1]
        # A method's closest point on a circle may leave the circle's box
        # (``Method.loose``); the hierarchy then bounds circles by the cube C +- R.
        loose = self._has_circles and method.loose
        with _threads.kernel():
            from . import bvh

            out = bvh.nearest(self._tree, method, points.reshape(-1, 3), full, loose=loose)
        return out_shape, out

    def distance(self, points, *args, method=DEFAULT_METHOD):
        """Distance from each point to the nearest primitive.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        method : str, keyword-only
            One of :attr:`methods`; default ``"robust"``.

        Returns
        -------
        ndarray of float64, shape ``(...)``
            A NumPy scalar for one point.  NaN where the point is not finite.

        Examples
        --------
        >>> import numpy as np, proximity
        >>> ring = proximity.Scene([proximity.Circle([0, 0, 0], [0, 0, 1], [1.0, 2.0])])
        >>> ring.distance([[0, 0, 0], [1.5, 0, 0], [np.nan, 0, 0]]).tolist()
        [1.0, 0.5, nan]
        """
        if args:
            raise keyword_only(self, "distance", args)
        out_shape, out = self._query(points, method, full=False)
        return out["distance"].reshape(out_shape)[()]

    def closest_point(self, points, *args, method=DEFAULT_METHOD):
        """Closest point, its distance and the nearest primitive, for each point.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
            Query points; rows containing NaN or inf give NaN, feature
            ``NONE`` and index -1 in those rows only.
        method : str, keyword-only
            One of :attr:`methods`; default ``"robust"``.

        Returns
        -------
        MeshResult or SceneResult
            Frozen result of arrays of shape ``(...)``.

        Examples
        --------
        >>> import proximity
        >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0]]
        >>> fan = proximity.TriangleMesh(vertices, [[0, 1, 2], [0, 2, 3]])
        >>> r = fan.closest_point([[-0.25, 0.25, 1.0], [0.0, 2.0, 0.0]])
        >>> r.distance.tolist(), r.face.tolist(), r.point[1].tolist()
        ([1.0, 1.0], [1, 0], [0.0, 1.0, 0.0])
        """
        if args:
            raise keyword_only(self, "closest_point", args)
        out_shape, out = self._query(points, method, full=True)
        fields = {name: value.reshape(out_shape + value.shape[1:]) for name, value in out.items()}
        return self._result(fields)


class Scene(_Nearest):
    """The nearest of a list of triangles, disks and circles.

    Parameters
    ----------
    shapes : sequence of Triangle, Disk, Circle or TriangleMesh
        Each may be a batch; its primitives are taken in C order of its
        batch (a mesh's in face order).  2D triangles are embedded in the
        ``z = 0`` plane.  At least one primitive in all.
    broad_phase : {"auto", "brute", "bvh"}, keyword-only
        ``"brute"`` tests every primitive for every point; ``"bvh"`` builds a
        bounding-volume hierarchy once, here, and prunes with it; ``"auto"``
        (default) picks brute force up to :data:`BRUTE_FORCE_MAX`
        primitives.  The answers are identical.

    Attributes
    ----------
    shapes : tuple
        The shapes given.
    offsets : ndarray of int64, shape ``(len(shapes) + 1,)``
        Primitive ``k`` of the flattened list comes from shape ``j`` with
        ``offsets[j] <= k < offsets[j + 1]``, as element
        ``np.unravel_index(k - offsets[j], shapes[j].batch_shape)`` of its
        batch (face ``k - offsets[j]`` of a mesh).
    broad_phase : str
        ``"brute"`` or ``"bvh"``, as resolved.
    methods : tuple of str
        The methods every kind of primitive in the scene offers.

    Examples
    --------
    >>> import proximity
    >>> scene = proximity.Scene([
    ...     proximity.Triangle([[[0, 0, 0], [1, 0, 0], [0, 1, 0]],
    ...                         [[0, 0, 5], [1, 0, 5], [0, 1, 5]]]),
    ...     proximity.Disk(center=[3, 0, 0], normal=[0, 0, 1], radius=1.0),
    ... ])
    >>> r = scene.closest_point([[0.2, 0.2, 4.0], [3.5, 0.0, 0.25]])
    >>> r.distance.tolist(), r.primitive.tolist(), r.source.tolist()
    ([1.0, 0.25], [1, 2], [0, 1])
    >>> scene
    Scene([<Triangle batch_shape=(2,)>, <Disk batch_shape=()>], broad_phase='brute')
    """

    __slots__ = ("shapes", "offsets", "broad_phase", "methods", "_tree", "_kinds", "_has_circles")

    def __init__(self, shapes, *, broad_phase="auto"):
        from .mesh import TriangleMesh

        if isinstance(shapes, (Triangle, Disk, Circle, TriangleMesh)) or not isinstance(
            shapes, (list, tuple)
        ):
            raise TypeError(
                "shapes must be a list or tuple of Triangle, Disk, Circle or TriangleMesh; "
                f"got {type(shapes).__name__}"
            )
        kinds, params, counts = [], [], []
        methods = None
        for j, shape in enumerate(shapes):
            if isinstance(shape, Triangle):
                v = shape._vertices3.reshape(-1, 9)
                kind = np.zeros(len(v), np.int8)
                p = np.concatenate([v, np.zeros((len(v), 1))], axis=1)
            elif isinstance(shape, TriangleMesh):
                v = shape.triangles.reshape(-1, 9)
                kind = np.zeros(len(v), np.int8)
                p = np.concatenate([v, np.zeros((len(v), 1))], axis=1)
            elif isinstance(shape, (Disk, Circle)):
                batch = shape.batch_shape
                c = np.broadcast_to(shape.center, batch + (3,)).reshape(-1, 3)
                u = np.broadcast_to(shape._unit_normal, batch + (3,)).reshape(-1, 3)
                n = np.broadcast_to(shape.normal, batch + (3,)).reshape(-1, 3)
                r = np.broadcast_to(shape.radius, batch).reshape(-1, 1)
                code = 1 if isinstance(shape, Disk) else 2
                kind = np.full(len(c), code, np.int8)
                p = np.concatenate([c, u, n, r], axis=1)
            else:
                raise TypeError(
                    f"shapes[{j}] must be a Triangle, Disk, Circle or TriangleMesh; "
                    f"got {type(shape).__name__}"
                )
            if len(kind):
                methods = (
                    shape.methods if methods is None else tuple(m for m in methods if m in shape.methods)
                )
            kinds.append(kind)
            params.append(p)
            counts.append(len(kind))
        if sum(counts) == 0:
            raise ValueError(f"shapes must hold at least one primitive; got {len(shapes)} shapes with none")
        kinds = np.concatenate(kinds)
        params = np.concatenate(params)
        resolved, tree = self._tree_for(kinds, params, broad_phase)
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        offsets.flags.writeable = False
        self._init(
            shapes=tuple(shapes),
            offsets=offsets,
            broad_phase=resolved,
            methods=methods,
            _tree=tree,
            _kinds=frozen(kinds, dtype=np.int8, new=True),
            _has_circles=bool((kinds == 2).any()),
        )

    def __len__(self):
        """Number of primitives."""
        return int(self.offsets[-1])

    def __repr__(self):
        shapes = ", ".join(_summary(shape) for shape in self.shapes[:4])
        if len(self.shapes) > 4:
            shapes += f", ... ({len(self.shapes) - 4} more)"
        return f"Scene([{shapes}], broad_phase={self.broad_phase!r})"

    def _result(self, fields):
        index = fields.pop("index")
        extra = fields.pop("extra")
        flag = fields.pop("flag")
        found = index >= 0
        source = np.where(found, np.searchsorted(self.offsets, index, side="right") - 1, -1)
        kind = self._kinds[np.where(found, index, 0)]
        triangle = found & (kind == 0)
        round_ = found & (kind != 0)
        return SceneResult(
            **fields,
            primitive=index,
            source=source,
            barycentric=np.where(triangle[..., None], extra, np.nan),
            height=np.where(round_, extra[..., 0], np.nan),
            radial=np.where(round_, extra[..., 1], np.nan),
            equidistant=flag & round_,
        )


def _summary(shape):
    """A shape in a few words: its class and batch, or its size."""
    if isinstance(shape, _Nearest):
        return f"<{type(shape).__name__} of {len(shape)} faces>"
    return f"<{type(shape).__name__} batch_shape={shape.batch_shape}>"
