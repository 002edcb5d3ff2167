"""The broad phase: the nearest primitive of a collection, by brute force or down a hierarchy.

A collection (a mesh or a scene) stores its primitives as rows of
parameters with a kind code each (:mod:`proximity.primitives`); the
distance from a point to it is the minimum, over the primitives, of the
per-primitive method's computed distance, called with the same arguments
as a single-shape query, so that a collection answers with exactly the bits
the per-shape query gives for its nearest primitive.  Among primitives at
the same computed distance the one with the lowest index wins; primitives
whose method gives NaN (``eberly`` on a zero-area triangle) are passed
over, and a row where every primitive gives NaN has no answer.

Nothing here names a kind of primitive: each kind's kernel module answers
for its rows.  One module per job:

:mod:`.tree`
    The :class:`Tree`: primitives in leaf order, nodes, bounds.
:mod:`.build`
    The hierarchy's build (binned SAH), brute force, duplicate rows.
:mod:`.bounds`
    Primitive and node bounds, and why pruning never changes an answer.
:mod:`.refit`
    Node bounds fitted to the primitives below.
:mod:`.traverse`
    The compiled search of one block of points.
:mod:`.nearest`
    The search of a batch, and the certified rows finished exactly.
:mod:`.instances`
    Many posed copies of a few collections, searched without a tree of their primitives.

It may import :mod:`proximity.numerics`, :mod:`proximity.runtime`, the registry of primitives
(whose kernel modules it reaches through their records) and the root's vocabulary; the
descent of two hierarchies at once is a pair query's (:mod:`proximity.pair.descent`).
"""

from .bounds import FACE_COLUMNS
from .build import LEAF_SIZE, assemble, brute, build_faces, build_tree, face_params
from .nearest import nearest
from .refit import refit_faces, refit_indexed
from .tree import Tree

__all__ = [
    "FACE_COLUMNS",
    "LEAF_SIZE",
    "Tree",
    "assemble",
    "brute",
    "build_faces",
    "build_tree",
    "face_params",
    "nearest",
    "refit_faces",
    "refit_indexed",
]
