"""What meshes and scenes share: validation, the broad phase and the query.

A collection is a single shape (``batch_shape == ()``) made of many
primitives; a query answers, for each point, with the nearest primitive's
answer to the per-shape method.  The broad phase (:mod:`proximity.broadphase`) is
chosen once, at construction.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._typing import ArrayLike, Distances
from .._validate import as_float64, cutoff, freeze_result, frozen, one_of
from ..features import FACE
from ..numerics.normals import normals_at
from ..primitives import N_PARAMS
from ..results import attach
from ..runtime import lazy, threads
from .base import DEFAULT_METHOD, Frozen, check_method, keyword_only

if TYPE_CHECKING:
    from ..results import Result
    from .rounded import Inflated

BROAD_PHASES = ("auto", "brute", "bvh")

#: Largest number of primitives for which ``broad_phase="auto"`` uses brute
#: force: up to ``LEAF_SIZE`` primitives the hierarchy is a single leaf and
#: saves nothing.  Measured with ``python -m benchmarks.meshes --crossover``;
#: the measurement is in ``docs/performance.md``.
BRUTE_FORCE_MAX = 4


class Collection(Frozen):
    """What meshes and scenes share: validation, broad phase and the query.

    Subclasses set ``_tree`` (a :class:`proximity.broadphase.Tree`),
    and ``methods``, and implement ``_result`` and
    ``_primitives``.
    """

    __slots__ = ()
    #: Whether its tree reads its primitives, faces, through ``vertices`` and
    #: ``faces`` (:func:`proximity.broadphase.build.faces_reader`), as a mesh's does.
    _reads_faces = False
    batch_shape = ()
    dim = 3

    @staticmethod
    def _tree_for(broad_phase, n, build, brute):
        """``(resolved broad phase, tree)`` for ``n`` primitives, from the
        callables ``build(broadphase)`` (a hierarchy) or ``brute(broadphase)``,
        given the package :mod:`proximity.broadphase`."""
        one_of(broad_phase, "broad_phase", BROAD_PHASES)
        if broad_phase == "auto":
            broad_phase = "brute" if n <= BRUTE_FORCE_MAX else "bvh"
        with threads.kernel():
            broadphase = lazy.load("proximity.broadphase")
            tree = build(broadphase) if broad_phase == "bvh" else brute(broadphase)
        return broad_phase, tree

    # Pickling.  The tree's primitive data are copies of the collection's own
    # arrays, its primitives' boxes and slabs follow from them row by row
    # (:func:`proximity.broadphase.bounds.primitive_cull`), and its node
    # bounds from those and the topology (:func:`proximity.broadphase.refit.refit`, a
    # pass over the primitives), so a pickle holds only what the build
    # decided: which primitives, in which order, and the nodes.  Unpickling
    # builds no hierarchy, and the pickle is little more than the
    # collection's own data.

    def __getstate__(self):
        state = super().__getstate__()
        tree = state.pop("_tree")
        if tree is None:  # a scene of posed meshes alone: its instances have the trees
            state["_tree"] = None
            return state
        state["_hierarchy"] = {
            "index": tree.index,
            "child": tree.child,
            "count": tree.count,
            "depth": tree.depth,
            "faces": tree.indexed,  # whether it reads its faces through their vertices
        }
        return state

    def __setstate__(self, state):
        state = dict(state)
        hierarchy = state.pop("_hierarchy", None)
        super().__setstate__(state)
        if hierarchy is not None:  # else the state holds the tree itself
            object.__setattr__(self, "_tree", self._restore_tree(hierarchy))
            if self._derived:  # derived from the tree too
                self._init(**self._derive())

    def _restore_tree(self, hierarchy):
        broadphase = lazy.load("proximity.broadphase")

        def read_only(array, dtype):
            return frozen(np.ascontiguousarray(array, dtype=dtype), dtype=dtype, new=True)

        index = read_only(hierarchy["index"], np.int64)
        child = read_only(hierarchy["child"], np.int64)
        count = read_only(hierarchy["count"], np.int64)
        # Node bounds that pickles of earlier versions hold are not read.
        with threads.kernel():
            build = broadphase.build
            read = self._reads_faces and hierarchy.get("faces", False)
            depth = hierarchy["depth"]
            if read:
                tree = build.restored_faces(self.vertices, self.faces, index, child, count, depth)
                if tree is not None:
                    return tree
            kinds, params = self._primitives(index)
            kinds, params = read_only(kinds, np.int8), read_only(params, np.float64)
            faces = build.faces_reader(self.vertices, self.faces, index) if read else None
            return broadphase.assemble(kinds, params, index, child, count, depth, faces=faces)

    def _query(self, points, method, full, max_distance=None):
        method = check_method(method, self.methods)
        limit = cutoff(max_distance)
        points = as_float64(points, "points", "(..., 3)")
        if points.ndim == 0 or points.shape[-1] != 3:
            raise ValueError(f"points must have shape (..., 3); got shape {points.shape}")
        out_shape = points.shape[:-1]
        # A method's closest point may leave a primitive's box (``Method.loose``,
        # Eberly's circle); the hierarchy then has looser boxes for it.
        instanced = getattr(self, "_instanced", None)
        trees = (self._tree,) if instanced is None else instanced.trees
        loose = any(tree.loose for tree in trees) and method.loose
        with threads.kernel():
            broadphase = lazy.load("proximity.broadphase")
            flat = points.reshape(-1, 3)
            if instanced is None:
                out = broadphase.nearest(self._tree, method, flat, full, loose=loose, cutoff=limit)
            else:
                instances = lazy.load("proximity.broadphase.instances")
                arrays = instanced.arrays[loose]
                out = instances.nearest_instances(
                    trees, arrays, method, flat, full, loose=loose, cutoff=limit
                )
        if any(tree.radius >= 0 for tree in trees):
            self._rounded(out, points.reshape(-1, 3), full)
        return out_shape, out

    def _rounded(self, out, points, full):
        """The search's answers for rounded primitives (signed ``d - r``) as a
        collection's: the distance ``max(d - r, 0)``, the signed one kept as
        ``signed_distance``, and closest points moved to the rounded surface."""
        from ..numerics.rounding import outward, surface_points

        signed = out["distance"]
        distance = np.maximum(signed, 0.0) + 0.0
        out.update(distance=distance, signed_distance=signed)
        if not full:
            return
        index = out["index"]
        found = index >= 0
        kinds, params = self._primitives(np.where(found, index, 0))
        radius = np.where(found, params[:, -1] if params.shape[1] > N_PARAMS else 0.0, np.nan)
        with np.errstate(invalid="ignore"):
            core = signed + radius
        rows_of = lambda rows: (kinds[rows], params[rows])  # noqa: E731
        on_core = out["point"]
        out["point"] = surface_points(points, on_core, core, radius, rows_of)
        out["sqr_distance"] = distance * distance
        # The normals, outwards on the rounded surfaces; the cores' (as their point queries
        # give them) where unrounded and where the core's closest point is on a face.
        feature = out["feature"]
        fallback = normals_at(points, on_core, core, feature, np.where(found, index, 0), self)
        out["normal"] = outward(out["point"], on_core, radius, fallback, feature == FACE)

    def inflated(self, radius: float) -> Inflated:
        """The points within ``radius`` of the collection's surface: a thick
        shell of a mesh, rounded primitives of a scene (:class:`proximity.Inflated`)."""
        from .rounded import Inflated

        return Inflated(self, radius)

    def distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Distances:
        """Distance from each point to the nearest primitive.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        method : str, keyword-only
            One of :attr:`methods`; default ``"robust"``.
        max_distance : float, keyword-only, optional
            A cutoff: rows with nothing within it get ``inf`` (and, in a
            result, NaN points, feature ``NONE``, index -1); the search does
            not look farther, which makes small cutoffs fast.  The rows within
            it are answered as without it, bit for bit.

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
        out_shape, out = self._query(points, method, full=False, max_distance=max_distance)
        return out["distance"].reshape(out_shape)[()]

    def closest_point(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Result:
        """Closest point, its distance and the nearest primitive, for each point.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
            Query points; rows containing NaN or inf give NaN, feature
            ``NONE`` and index -1 in those rows only.
        method : str, keyword-only
            One of :attr:`methods`; default ``"robust"``.
        max_distance : float, keyword-only, optional
            A cutoff: rows with nothing within it get ``inf`` (and, in a
            result, NaN points, feature ``NONE``, index -1); the search does
            not look farther, which makes small cutoffs fast.  The rows within
            it are answered as without it, bit for bit.

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
        out_shape, out = self._query(points, method, full=True, max_distance=max_distance)
        out.pop("signed_distance", None)
        normal = out.pop("normal", None)
        fields = {name: value.reshape(out_shape + value.shape[1:]) for name, value in out.items()}
        result = attach(self._result(fields), as_float64(points, "points", ""), None, self)
        if normal is not None:
            result.__dict__["_normal"] = freeze_result(normal.reshape(out_shape + (3,)))
        return result

    def _elements(self, result, members):
        """The nearest face or primitive of each row of ``result``."""
        return self._nearest_index(result)

    def _feature_rows(self, index):
        """``(kinds, params)`` of faces or primitives ``index``, as the tree stores them."""
        return self._primitives(index)

    def _feature_normals(self, index, feature, points):
        """The normals of faces or primitives ``index`` at closest points on
        their ``feature`` to ``points``: their primitives'
        (:func:`proximity.numerics.normals.feature_normals`)."""
        from ..numerics.normals import feature_normals

        kinds, params = self._primitives(index)
        return feature_normals(kinds, params[:, :N_PARAMS], feature, points)

    def signed_distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Distances:
        """Signed distance to the nearest primitive: ``d - r`` for a rounded
        one, negative inside it (:class:`proximity.Inflated`); for the
        others, the distance.

        Examples
        --------
        >>> import proximity
        >>> scene = proximity.Scene([proximity.Sphere([0, 0, 0], 1.0), proximity.Point([3, 0, 0])])
        >>> scene.signed_distance([[0, 0, 0.5], [2, 0, 0]]).tolist()
        [-0.5, 1.0]
        """
        if args:
            raise keyword_only(self, "signed_distance", args)
        out_shape, out = self._query(points, method, full=False, max_distance=max_distance)
        return out.get("signed_distance", out["distance"]).reshape(out_shape)[()]
