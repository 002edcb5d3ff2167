"""Triangle meshes: the nearest face to each point.

A :class:`TriangleMesh` is a single shape (``batch_shape == ()``) made of
faces; a query answers, for each point, with the nearest face's answer to
the per-triangle method (:func:`proximity.point_triangle.robust` by default),
bit for bit, and the index of that face.  Degenerate faces (collinear or
coincident vertices) are queried like any other: ``robust`` answers for the
segment or point they are.  How the nearest face is found without testing
every face, and why that never changes the answer, is in
:mod:`proximity.bvh`.
"""

import numpy as np

from ._collection import Collection
from ._validate import frozen, frozen_float64, require_finite
from .results import MeshResult, format_repr
from .shapes import Triangle


class TriangleMesh(Collection):
    """A mesh of triangles given by vertices and faces.

    Parameters
    ----------
    vertices : array_like, shape ``(V, 3)``, or a mesh object
        Finite coordinates; or, with ``faces`` left out, any object with
        ``vertices`` and ``faces`` attributes, such as a ``trimesh.Trimesh``.
    faces : array_like of int, shape ``(F, 3)``
        Indices into ``vertices``, ``0 <= index < V``; ``F >= 1``.  Faces may
        be degenerate and need not form a manifold: the mesh is a triangle
        soup with shared vertices.
    broad_phase : {"auto", "brute", "bvh"}, keyword-only
        ``"bvh"`` builds a bounding-volume hierarchy once, here;
        ``"brute"`` tests every face for every point; ``"auto"`` (default)
        chooses by the number of faces (see
        :data:`proximity.scene.BRUTE_FORCE_MAX`).  The answers are identical.

    Attributes
    ----------
    vertices : ndarray of float64, shape ``(V, 3)``, read-only
    faces : ndarray of int64, shape ``(F, 3)``, read-only
    broad_phase : str
        ``"brute"`` or ``"bvh"``, as resolved.
    methods : tuple of str
        The per-triangle methods: those of :class:`proximity.Triangle`.

    Examples
    --------
    A unit square of two faces, queried above it, beside it, and on a vertex:

    >>> import proximity
    >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                                 [[0, 1, 2], [0, 2, 3]])
    >>> r = square.closest_point([[0.25, 0.75, 2.0], [2.0, 0.5, 0.0], [1.0, 1.0, 0.0]])
    >>> r.distance.tolist(), r.face.tolist()
    ([2.0, 1.0, 0.0], [1, 0, 0])
    >>> r.feature_name.tolist(), r.point[1].tolist()
    (['FACE', 'EDGE12', 'VERTEX2'], [1.0, 0.5, 0.0])
    >>> float(proximity.distance(square, [0.5, 0.5, -3.0]))
    3.0
    """

    __slots__ = ("vertices", "faces", "broad_phase", "_tree")
    methods = Triangle.methods
    _has_circles = False

    def __init__(self, vertices, faces=None, *, broad_phase="auto"):
        if faces is None:
            if not (hasattr(vertices, "vertices") and hasattr(vertices, "faces")):
                raise TypeError(
                    "TriangleMesh takes vertices and faces, or one object with .vertices and .faces "
                    f"(such as a trimesh.Trimesh); got a {type(vertices).__name__} and no faces"
                )
            vertices, faces = vertices.vertices, vertices.faces
        v = frozen_float64(vertices, "vertices", "(V, 3)")
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices must have shape (V, 3); got shape {v.shape}")
        require_finite(v, "vertices")
        f = np.asarray(faces)
        if f.dtype.kind not in "iu":
            raise ValueError(f"faces must be an integer array of shape (F, 3); got dtype {f.dtype}")
        if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] == 0:
            raise ValueError(f"faces must have shape (F, 3) with F >= 1; got shape {f.shape}")
        if f.min() < 0 or f.max() >= len(v):
            bad = (f < 0) | (f >= len(v))
            index = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ValueError(
                f"faces must index vertices, 0 <= index < {len(v)}; got {int(f[index])} at index {index}"
            )
        f = frozen(f, dtype=np.int64, new=f is not faces and f.dtype == np.int64)
        resolved, tree = self._tree_for(*_primitives(v, f), broad_phase)
        self._init(vertices=v, faces=f, broad_phase=resolved, _tree=tree)

    def __repr__(self):
        return format_repr(self, ("vertices", "faces"), broad_phase=self.broad_phase)

    def __len__(self):
        """Number of faces."""
        return len(self.faces)

    @property
    def triangles(self):
        """The faces' vertices, ``(F, 3, 3)``: a new array."""
        return self.vertices[self.faces]

    def _primitives(self, index):
        """``(kinds, params)`` of faces ``index``, as the tree stores them."""
        return _primitives(self.vertices, self.faces[index])

    def _result(self, fields):
        del fields["flag"]
        barycentric = fields.pop("extra")
        face = fields.pop("index")
        return MeshResult(**fields, barycentric=barycentric, face=face)


def _primitives(vertices, faces):
    """``(kinds, params)`` of the broad phase for ``faces``: each face's nine coordinates."""
    params = np.zeros((len(faces), 10))
    params[:, :9] = vertices[faces].reshape(-1, 9)
    return np.zeros(len(faces), np.int8), params
