"""A collection's broad phase: its primitives in leaf order and the nodes over them."""

import functools
from dataclasses import dataclass

import numpy as np

from .. import primitives


@dataclass(frozen=True, eq=False)
class Tree:
    """A broad phase: primitives in leaf order and the nodes over them.

    Attributes
    ----------
    kinds : ndarray of int8, shape ``(n,)``
        The kind code of each stored primitive (see :mod:`proximity.primitives`).
    params : ndarray of float64, shape ``(n, N_PARAMS)``
        Each stored primitive's parameters (``FACE_COLUMNS`` wide in a tree
        of faces alone, one wider with radii).
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
    cull : ndarray of float32, shape ``(n, 11)``
        Each stored primitive's box and slab ``(lo, hi, u, h_min, h_max)``,
        rounded outwards (:func:`~.bounds.stored_cull`).
    loose_bounds, loose_cull : ndarray of float64, float32
        The same for ``eberly`` (the same arrays unless there are circles).
    depth : int
        Depth of the deepest leaf.
    """

    kinds: np.ndarray
    params: np.ndarray
    index: np.ndarray
    child: np.ndarray
    count: np.ndarray
    bounds: np.ndarray
    cull: np.ndarray
    loose_bounds: np.ndarray
    loose_cull: np.ndarray
    depth: int

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
        return primitives.N_PARAMS if self.params.shape[1] > primitives.N_PARAMS else -1

    @property
    def loose(self):
        """Whether the loose boxes differ from the tight ones."""
        return self.loose_cull is not self.cull

    @functools.cached_property
    def _spheres(self):
        out = {}
        for loose in (False, True):
            bounds = self.boxes(loose)[0]
            centre = (bounds[0, :3] + bounds[0, 3:6]) / 2.0
            leaves = bounds[self.count > 0, :6]
            with np.errstate(invalid="ignore", over="ignore"):
                far = np.maximum(np.abs(leaves[:, :3] - centre), np.abs(leaves[:, 3:6] - centre))
                radius = float(np.sqrt(np.max(np.sum(far * far, axis=1), initial=0.0)))
            out[loose] = (centre, radius if np.isfinite(radius) and np.isfinite(centre).all() else np.inf)
        return out

    def sphere(self, loose):
        """``(centre, radius)`` of a sphere around everything stored: about the
        root box's centre, through the farthest corner of the leaves' boxes
        (tight or loose); an infinite radius where a box is unbounded."""
        return self._spheres[loose]

    def boxes(self, loose):
        """``(node boxes, primitive culling data, magnitude)``, tight or loose."""
        bounds, cull = (self.loose_bounds, self.loose_cull) if loose else (self.bounds, self.cull)
        # A coordinate that overflowed leaves its box unbounded, which prunes
        # nothing; the scale is set by the finite ones.
        corners = np.abs(bounds[0, :6])
        return bounds, cull, float(np.max(corners, where=np.isfinite(corners), initial=0.0))
