"""A collection's broad phase: its primitives in leaf order and the nodes over them."""

import functools
from dataclasses import dataclass

import numpy as np

from .. import primitives
from ._alloc import readonly
from .bounds import CULL_COLUMNS, primitive_cull, stored_cull

#: The culling data of a search that reads none.
_NO_CULL = readonly(np.empty((0, CULL_COLUMNS), np.float32), np.float32)


@dataclass(frozen=True, eq=False)
class Tree:
    """A broad phase: primitives in leaf order and the nodes over them.

    Attributes
    ----------
    kinds : ndarray of int8, shape ``(n,)``
        The kind code of each stored primitive (see :mod:`proximity.primitives`).
    stored_params : ndarray of float64, shape ``(n, N_PARAMS)``, or None
        Each stored primitive's parameters (``FACE_COLUMNS`` wide in a tree
        of faces alone, one wider with radii); None in a tree of faces
        read through their vertices (see :attr:`params`).
    index : ndarray of int32, shape ``(n,)``
        The caller's index of each stored primitive.
    child, count : ndarray of int32, shape ``(m,)``
        Node topology: node ``i`` is a leaf holding stored primitives
        ``child[i] .. child[i] + count[i] - 1`` when ``count[i] > 0``, and
        otherwise has children ``child[i]`` and ``child[i] + 1``; one leaf
        for brute force.  32-bit, as ``index``: a tree holds at most
        ``2**30`` primitives (:data:`~._alloc.MOST_PRIMITIVES`).
    bounds : ndarray of float64, shape ``(m, NODE_COLUMNS)``
        Node boxes and oriented boxes (see :func:`refit`).
    cull : ndarray of float32, shape ``(n, 11)``, or None
        Each stored primitive's box and slab ``(lo, hi, u, h_min, h_max)``,
        rounded outwards (:func:`~.bounds.stored_cull`); None in a tree of
        faces read through their vertices, which computes them where a
        search needs them (:meth:`culling`).
    loose_bounds, loose_cull : ndarray of float64, float32
        The same for ``eberly`` (the same arrays unless there are circles).
    depth : int
        Depth of the deepest leaf.
    vertices : ndarray of float64, shape ``(V, 3)``, or None
        A tree of faces (of a mesh): the vertices of its faces, in the order
        in which the faces in leaf order first use them, so that a leaf's
        vertices lie together in memory.
    faces : ndarray of int32, shape ``(n, 3)``, or None
        Each stored face's three rows of ``vertices``: the search reads a
        face's coordinates through them (:meth:`rows`), 12 bytes a face and
        about 12 of vertices where the faces' rows take 72.
    sources : ndarray of int32, shape ``(V,)``, or None
        The index of each row of ``vertices`` in the mesh's vertices: a refit
        (:meth:`proximity.TriangleMesh.with_vertices`) reads the moved ones
        in the same order.
    """

    kinds: np.ndarray
    stored_params: np.ndarray | None
    index: np.ndarray
    child: np.ndarray
    count: np.ndarray
    bounds: np.ndarray
    cull: np.ndarray | None
    loose_bounds: np.ndarray
    loose_cull: np.ndarray | None
    depth: int
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    sources: np.ndarray | None = None

    @property
    def indexed(self):
        """Whether the faces are read through their vertices (:attr:`faces`)."""
        return self.faces is not None

    @property
    def params(self):
        """Each stored primitive's parameters, ``(n, columns)``; for a tree of
        faces read through their vertices, their rows gathered anew at each
        call (for the queries other than the nearest-face search)."""
        if self.faces is None:
            return self.stored_params
        params = self.vertices[self.faces].reshape(len(self.faces), 9)
        params.flags.writeable = False
        return params

    def params_of(self, rows):
        """``params[rows]``, without gathering the other rows."""
        if self.faces is None:
            return self.stored_params[rows]
        return self.vertices[self.faces[rows]].reshape(len(rows), 9)

    def rows(self):
        """What the search reads a stored primitive from: ``params``, or
        ``(vertices, faces)`` in a tree of faces read through their vertices."""
        return (self.vertices, self.faces) if self.faces is not None else self.stored_params

    @property
    def nodes(self):
        """Number of nodes; 1 for brute force."""
        return len(self.child)

    @functools.cached_property
    def present(self):
        """The kinds of primitive stored: :class:`~proximity.primitives.Primitive` records, in code order."""
        return primitives.present(self.kinds)

    @property
    def radius(self):
        """The column of the rows' radii where the tree holds rounded
        primitives (rows one wider than :data:`~proximity.primitives.N_PARAMS`), else -1."""
        return primitives.N_PARAMS if self.width > primitives.N_PARAMS else -1

    @property
    def width(self):
        """The number of columns of :attr:`params`."""
        return 9 if self.faces is not None else self.stored_params.shape[1]

    @property
    def loose(self):
        """Whether the loose boxes differ from the tight ones."""
        return self.loose_bounds is not self.bounds

    @functools.cached_property
    def _spheres(self):
        out = {}
        for loose in (False, True):
            bounds = self.boxes(loose, False)[0]
            centre = (bounds[0, :3] + bounds[0, 3:6]) / 2.0
            leaves = bounds[self.count > 0, :6]
            with np.errstate(invalid="ignore", over="ignore"):
                far = np.maximum(np.abs(leaves[:, :3] - centre), np.abs(leaves[:, 3:6] - centre))
                radius = float(np.sqrt(np.max(np.sum(far * far, axis=1), initial=0.0)))
                if self.faces is not None and not loose:
                    # A face is the hull of its vertices: the farthest of them
                    # bounds it, where a box's corner lies beyond the surface
                    # (a sphere's leaves reach 1.12 times its radius).
                    v = self.vertices - centre
                    radius = min(radius, float(np.sqrt(np.max(np.sum(v * v, axis=1), initial=0.0))))
            out[loose] = (centre, radius if np.isfinite(radius) and np.isfinite(centre).all() else np.inf)
        return out

    def sphere(self, loose):
        """``(centre, radius)`` of a sphere around everything stored: about the
        root box's centre, through the farthest corner of the leaves' boxes
        (tight or loose), or, in a tree of faces read through their vertices
        (tight), through the farthest vertex where it is nearer; an infinite
        radius where a box is unbounded."""
        return self._spheres[loose]

    @functools.cached_property
    def _face_cull(self):
        # Faces alone: tight and loose rows are the same.
        return readonly(stored_cull(primitive_cull(self.kinds, self.params)[0]), np.float32)

    def culling(self, loose):
        """Each stored primitive's cull row, tight or loose (:attr:`cull`):
        in a tree of faces read through their vertices, computed at the
        first call and kept (44 bytes a face); the robust search of such a
        tree does without them (:mod:`.traverse`)."""
        if self.faces is not None:
            return self._face_cull
        return self.loose_cull if loose else self.cull

    def boxes(self, loose, cull=True):
        """``(node boxes, primitive culling data, magnitude)``, tight or loose;
        ``cull=False``: an empty array for the culling data, which a search
        that reads none takes (:func:`.traverse.reads_cull`)."""
        bounds = self.loose_bounds if loose else self.bounds
        cull = self.culling(loose) if cull else _NO_CULL
        # A coordinate that overflowed leaves its box unbounded, which prunes
        # nothing; the scale is set by the finite ones.
        corners = np.abs(bounds[0, :6])
        return bounds, cull, float(np.max(corners, where=np.isfinite(corners), initial=0.0))
