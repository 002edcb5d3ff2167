"""Scenes: the nearest of many triangles, disks and circles to each point.

A :class:`Scene` is a flat list of primitives gathered from shapes (each shape
may be a batch).  Triangles stay triangles and disks and circles stay
analytic: nothing is tessellated.  Each query returns the nearest primitive's
answer, computed by the same per-primitive method as a single-shape query
(see :mod:`proximity.broadphase`), with the index of that primitive.

The broad phase is chosen once, at construction: brute force over every
primitive for small scenes, a bounding-volume hierarchy above
:data:`BRUTE_FORCE_MAX` primitives.  Both give the same answer, bit for bit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from .. import primitives
from .._typing import ArrayLike
from .._validate import frozen, one_of
from ..results import SceneResult
from .collection import BROAD_PHASES, BRUTE_FORCE_MAX, Collection

if TYPE_CHECKING:
    from .base import Shape

# The shapes a scene takes, for the messages.
_NAMES = "proximity shape (Triangle, Segment, Point, Disk, Circle, TriangleMesh, Scene or a rounded one)"

__all__ = ["BRUTE_FORCE_MAX", "Scene"]

_KIND_NAMES = ("triangle", "disk", "circle")


class Scene(Collection):
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

    __slots__ = ("shapes", "offsets", "broad_phase", "methods", "_tree", "_kinds", "_instanced")
    _derived = ("_instanced",)
    result_type = SceneResult

    def __init__(self, shapes: Iterable[Shape], *, broad_phase: str = "auto") -> None:
        if not isinstance(shapes, (list, tuple)):
            raise TypeError(f"shapes must be a list or tuple of {_NAMES}; got {type(shapes).__name__}")
        # Posed meshes and scenes are instances: their hierarchies are shared,
        # not merged; the other shapes' primitives make the scene's own tree.
        posed = [_instance(shape) for shape in shapes]
        loose = [shape for shape, inst in zip(shapes, posed, strict=True) if not inst]
        kinds, params, loose_counts, methods = _primitives(loose)
        counts, codes, start = [], [], 0
        remaining = iter(loose_counts)
        for shape, inst in zip(shapes, posed, strict=True):
            if inst:
                counts.append(len(shape.shape))
                codes.append(shape.shape._kind_codes())
                methods = _common(methods, shape.methods)
            else:
                count = next(remaining)
                counts.append(count)
                codes.append(kinds[start : start + count])
                start += count
        if sum(counts) == 0:
            raise ValueError(f"shapes must hold at least one primitive; got {len(shapes)} shapes with none")
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        offsets.flags.writeable = False
        tree, resolved = None, broad_phase
        if len(kinds):
            resolved, tree = self._tree_for(
                broad_phase,
                len(kinds),
                lambda bp: bp.build_tree(kinds, params),
                lambda bp: bp.brute(kinds, params),
            )
            if any(posed):  # the loose primitives, numbered among the instances'
                tree = dataclasses.replace(tree, index=_renumbered(tree.index, offsets, posed))
        else:
            one_of(broad_phase, "broad_phase", BROAD_PHASES)
        self._init(
            shapes=tuple(shapes),
            offsets=offsets,
            broad_phase="bvh" if any(posed) else resolved,
            methods=methods,
            _tree=tree,
            _kinds=frozen(np.concatenate(codes), dtype=np.int8, new=True),
        )
        self._init(**self._derive())

    def _derive(self):
        """The instances: the posed meshes and scenes, and the loose primitives
        as one more, unmoved (None where there are no posed ones).  A posed
        scene of instances brings its own instances, each posed by the view's
        pose after its own: its tree holds only its loose primitives."""
        posed = [_instance(shape) for shape in self.shapes]
        if not any(posed):
            return {"_instanced": None}
        trees, which, offset, view, inner = [], [], [], [], []

        def number(tree):
            known = [k for k, t in enumerate(trees) if t is tree]
            if not known:
                trees.append(tree)
            return known[0] if known else len(trees) - 1

        jobs = [j for j, inst in enumerate(posed) if inst]
        for k, j in enumerate(jobs):
            prototype, start = self.shapes[j].shape, int(self.offsets[j])
            nested = getattr(prototype, "_instanced", None)
            if nested is None:
                which.append(number(prototype._tree))
                offset.append(start)
                view.append(k)
                inner.append(None)
                continue
            members = nested.arrays[False]
            loose = len(members.prototype) - 1 if nested.loose_tree else -1
            for i, tree in enumerate(members.prototype):
                which.append(number(nested.trees[tree]))
                offset.append(start + int(members.offset[i]))
                view.append(k)
                inner.append(None if i == loose else (members.rotation[i], members.translation[i]))
        rotation = np.array([self.shapes[j].rotation for j in jobs])
        translation = np.array([self.shapes[j].translation for j in jobs])
        own = getattr(self, "_tree", None)  # unpickling: restored after the rest
        trees = tuple(trees) + (() if own is None else (own,))
        instances = _Instances(
            trees, np.array(which, np.int64), np.array(offset, np.int64), own is not None, view, inner
        )
        return {"_instanced": instances.posed(rotation, translation)}

    def with_poses(self, transforms: ArrayLike) -> Scene:
        """The scene with its posed meshes and scenes moved to ``transforms``,
        ``(n, 4, 4)``: one per posed view among :attr:`shapes`, in order.

        The instances' hierarchies are shared and only their poses change:
        a new frame costs O(instances), nothing per face.

        Examples
        --------
        >>> import numpy as np, proximity
        >>> tet = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
        ...                              [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        >>> scene = proximity.Scene([tet.transformed(np.eye(4)), tet.transformed(np.eye(4))])
        >>> T = np.tile(np.eye(4), (2, 1, 1)); T[:, 0, 3] = [0, 10]
        >>> scene.with_poses(T).distance([[12, 0, 0]]).tolist()
        [1.0]
        """
        from ..numerics.rigid import rigid
        from .posed import Posed

        if self._instanced is None:
            raise ValueError(
                "with_poses needs a scene of posed meshes or scenes (shape.transformed(T)); this has none"
            )
        jobs = [j for j, shape in enumerate(self.shapes) if _instance(shape)]
        rotation, translation = rigid(transforms, "transforms")
        if rotation.shape != (len(jobs), 3, 3):
            raise ValueError(
                f"transforms must have shape ({len(jobs)}, 4, 4), one per posed view; "
                f"got {rotation.shape[:-2] + (4, 4)}"
            )
        shapes = list(self.shapes)
        for k, j in enumerate(jobs):
            shapes[j] = Posed._at(self.shapes[j].shape, rotation[k], translation[k])
        scene = object.__new__(Scene)
        scene._init(**{name: getattr(self, name) for name in self._slots() if name not in self._derived})
        scene._init(shapes=tuple(shapes), _instanced=self._instanced.posed(rotation, translation))
        return scene

    def __len__(self):
        """Number of primitives."""
        return int(self.offsets[-1])

    def __repr__(self):
        shapes = ", ".join(_summary(shape) for shape in self.shapes[:4])
        if len(self.shapes) > 4:
            shapes += f", ... ({len(self.shapes) - 4} more)"
        return f"Scene([{shapes}], broad_phase={self.broad_phase!r})"

    def _nearest_index(self, result):
        return np.asarray(result.primitive)

    def _rows(self):
        """``(kinds, params)`` of every primitive, in order, as a collection stores them."""
        kinds, params, _, _ = _primitives(self.shapes)
        return kinds, params

    def _primitives(self, index):
        """``(kinds, params)`` of primitives ``index``, as the tree stores them."""
        kinds, params, _, _ = _primitives(self.shapes)
        return kinds[index], params[index]

    def _kind_codes(self):
        return self._kinds

    def _feature_normals(self, index, feature, points):
        """The normals of primitives ``index`` at closest points on their
        ``feature`` to ``points``: each shape's own where it has them (a
        mesh's pseudonormals; a posed view's, computed in its frame), else
        the primitive's (see :attr:`proximity.Result.normal`)."""
        from .posed import Posed

        index, feature = np.asarray(index), np.asarray(feature)
        normal = np.empty((len(index), 3))
        source = np.searchsorted(self.offsets, index, side="right") - 1
        own = np.array([isinstance(shape, (Posed, Collection)) for shape in self.shapes])
        loose = np.flatnonzero(~own[source])
        if len(loose):
            normal[loose] = super()._feature_normals(index[loose], feature[loose], points[loose])
        for j in np.unique(source[own[source]]):
            rows = np.flatnonzero(source == j)
            local = index[rows] - self.offsets[j]
            normal[rows] = self.shapes[j]._feature_normals(local, feature[rows], points[rows])
        return normal

    def _result(self, fields):
        index = fields.pop("index")
        extra = fields.pop("extra")
        flag = fields.pop("flag")
        found = index >= 0
        source = np.where(found, np.searchsorted(self.offsets, index, side="right") - 1, -1)
        kind = self._kinds[np.where(found, index, 0)]
        # Each kind's values from the columns of its answers (see
        # :mod:`proximity.primitives`); NaN (False) where the nearest
        # primitive is of another kind.
        values = {}
        for p in primitives.BY_CODE:
            mine = found & (kind == p.code)
            column = 0
            for name, width in p.extra:
                if width == 0:
                    value, empty = flag, False
                else:
                    value = extra[..., column : column + width] if width > 1 else extra[..., column]
                    column += width
                    empty = np.nan
                mask = mine[..., None] if width > 1 else mine
                values[name] = np.where(mask, value, values.get(name, empty))
        return SceneResult(**fields, primitive=index, source=source, **values)


class _Instances:
    """A scene's instances: the prototypes' trees (the loose primitives'
    last, where there are any), each instance's prototype and first
    primitive, the posed view it belongs to and its pose within that view
    (None: the view's own), and their poses' arrays for the search, made
    per pose of the views."""

    def __init__(self, trees, prototype, offset, loose_tree, view, inner):
        self.trees, self.prototype, self.offset, self.loose_tree = trees, prototype, offset, loose_tree
        self.view, self.inner = view, inner
        self.arrays = None

    def posed(self, rotation, translation):
        """The instances with the posed views at these poses (in order)."""
        from ..broadphase.instances import instance_arrays

        out = _Instances(self.trees, self.prototype, self.offset, self.loose_tree, self.view, self.inner)
        prototype, offset = self.prototype, self.offset
        rotation, translation = np.asarray(rotation).reshape(-1, 3, 3), np.asarray(translation).reshape(-1, 3)
        rotation, translation = rotation[self.view], translation[self.view]
        for i, pose in enumerate(self.inner):
            if pose is not None:  # X -> R (R' X + t') + t, composed as a posed view composes it
                r, t = rotation[i], translation[i]
                rotation[i], translation[i] = r @ pose[0], r @ pose[1] + t
        if self.loose_tree:
            prototype = np.append(prototype, len(self.trees) - 1)
            offset = np.append(offset, 0)
            rotation = np.concatenate([rotation, np.eye(3)[None]])
            translation = np.concatenate([translation, np.zeros((1, 3))])
        out.arrays = {
            loose: instance_arrays(self.trees, prototype, rotation, translation, offset, loose)
            for loose in (False, True)
        }
        return out


def _instance(shape):
    """Whether ``shape`` is a posed mesh or scene: an instance in a scene."""
    from .posed import Posed

    return isinstance(shape, Posed) and isinstance(shape.shape, Collection)


def _common(methods, more):
    return more if methods is None else tuple(m for m in methods if m in more)


def _renumbered(index, offsets, posed):
    """The loose primitives' tree indices as the scene numbers them, among the instances'."""
    numbers = np.concatenate(
        [np.arange(offsets[j], offsets[j + 1]) for j, inst in enumerate(posed) if not inst]
        or [np.zeros(0, int)]
    )
    from ..broadphase._alloc import indices

    # A tree keeps 32-bit indices: a scene numbering its loose primitives past 2**31 is refused.
    return indices(numbers[index])


def _summary(shape):
    """A shape in a few words: its class and batch, or its size."""
    if isinstance(shape, Collection):
        return f"<{type(shape).__name__} of {len(shape)} faces>"
    return f"<{type(shape).__name__} batch_shape={shape.batch_shape}>"


def _primitives(shapes):
    """``(kinds, params, counts, methods)``: every primitive of ``shapes`` in
    order, as the broad phase stores them, the number from each shape, and
    the methods they all offer."""
    kinds, params, radii, counts = [], [], [], []
    methods = None
    for j, shape in enumerate(shapes):
        rows = getattr(shape, "_rows", None)
        if rows is None:
            raise TypeError(f"shapes[{j}] must be a {_NAMES}; got {type(shape).__name__}")
        rows = rows()
        kind, p = rows[:2]
        if len(kind):
            methods = shape.methods if methods is None else tuple(m for m in methods if m in shape.methods)
        kinds.append(kind)
        params.append(p)
        radii.append(rows[2] if len(rows) == 3 else np.zeros(len(kind)))
        counts.append(len(kind))
    if not counts:
        return np.zeros(0, np.int8), np.zeros((0, primitives.N_PARAMS)), counts, methods
    params, radii = np.concatenate(params), np.concatenate(radii)
    if radii.any():
        # Rounded primitives: each row's radius in one more column (see proximity.broadphase).
        params = np.concatenate([params, radii[:, None]], axis=1)
    return np.concatenate(kinds), params, counts, methods
