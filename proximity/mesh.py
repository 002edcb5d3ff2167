"""Triangle meshes: the nearest face to each point.

A :class:`TriangleMesh` is a single shape (``batch_shape == ()``) made of
faces; a query answers, for each point, with the nearest face's answer to
the per-triangle method (:func:`proximity.point_triangle.robust` by default),
bit for bit, and the index of that face.  Degenerate faces (collinear or
coincident vertices) are queried like any other: ``robust`` answers for the
segment or point they are.  How the nearest face is found without testing
every face, and why that never changes the answer, is in
:mod:`proximity.broadphase`.
"""

import numpy as np

from . import _lazy, _threads
from ._collection import Collection
from ._meshlike import vertices_and_faces
from ._validate import as_float64, as_index_array, freeze_result, frozen, frozen_float64, require_finite
from .primitives import TRIANGLE
from .results import MeshResult, format_repr
from .shapes import DEFAULT_METHOD, keyword_only

#: How :meth:`TriangleMesh.signed_distance` and :meth:`TriangleMesh.contains`
#: tell inside from outside.
SIGNS = ("pseudonormal", "winding")


class TriangleMesh(Collection):
    """A mesh of triangles given by vertices and faces.

    Parameters
    ----------
    vertices : array_like, shape ``(V, 3)``, or a mesh object
        Finite coordinates; or, with ``faces`` left out, a mesh of another
        library: a ``trimesh.Trimesh``, an Open3D ``TriangleMesh``, a meshio
        ``Mesh`` with triangle cells, a triangulated PyVista ``PolyData``,
        or any object with ``vertices`` (or ``points``) and ``faces`` (or
        ``triangles``) arrays.
    faces : array_like of int, shape ``(F, 3)``
        Indices into ``vertices``, ``0 <= index < V``; ``F >= 1``.  Floats
        are taken where every one is a whole number (as ``np.loadtxt``
        reads a face list).  Faces may be degenerate and need not form a
        manifold: the mesh is a triangle soup with shared vertices.
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

    __slots__ = ("vertices", "faces", "broad_phase", "_tree", "_signs")
    methods = TRIANGLE.methods
    result_type = MeshResult

    def __init__(self, vertices, faces=None, *, broad_phase="auto"):
        if faces is None:
            vertices, faces = vertices_and_faces(vertices)
        v = frozen_float64(vertices, "vertices", "(V, 3)")
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices must have shape (V, 3); got shape {v.shape}")
        require_finite(v, "vertices")
        f = as_index_array(faces, "faces", "(F, 3)")
        if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] == 0:
            raise ValueError(f"faces must have shape (F, 3) with F >= 1; got shape {f.shape}")
        if f.min() < 0 or f.max() >= len(v):
            bad = (f < 0) | (f >= len(v))
            index = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ValueError(
                f"faces must index vertices, 0 <= index < {len(v)}; got {int(f[index])} at index {index}"
            )
        f = frozen(f, dtype=np.int64, new=f is not faces and f.dtype == np.int64)
        resolved, tree = self._tree_for(
            broad_phase,
            len(f),
            lambda bp: bp.build_faces(v, f, TRIANGLE.code),
            lambda bp: bp.brute(*_primitives(v, f)),
        )
        self._init(vertices=v, faces=f, broad_phase=resolved, _tree=tree, _signs=None)

    def __repr__(self):
        return format_repr(self, ("vertices", "faces"), broad_phase=self.broad_phase)

    def __len__(self):
        """Number of faces."""
        return len(self.faces)

    @property
    def triangles(self):
        """The faces' vertices, ``(F, 3, 3)``: a new array."""
        return self.vertices[self.faces]

    def __getstate__(self):
        state = super().__getstate__()
        state["_signs"] = None  # rebuilt at first use: quicker than sending it
        return state

    def __setstate__(self, state):
        super().__setstate__({"_signs": None, **state})

    def signed_distance(self, points, *args, method=DEFAULT_METHOD, sign="pseudonormal"):
        """Distance to the surface, negative inside the closed mesh, positive outside.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        method : str, keyword-only
            The per-triangle method of the distance (see :attr:`methods`);
            default ``"robust"``.
        sign : {"pseudonormal", "winding"}, keyword-only
            How inside is told from outside.  ``"pseudonormal"`` (default):
            the angle-weighted pseudonormal of the closest face, edge or
            vertex, O(1) per point after the closest point; for closed
            meshes only.  ``"winding"``: the generalized winding number,
            inside where it exceeds 1/2, for any mesh (open, non-manifold,
            self-intersecting), at O(F) per point.

        Returns
        -------
        ndarray of float64, shape ``(...)``, read-only
            ``+0.0`` where the distance is 0 (never ``-0.0``); NaN where the
            point is not finite.  A NumPy scalar for one point.

        Raises
        ------
        ValueError
            With ``sign="pseudonormal"``, if the mesh is not closed: the
            message names an edge that is not shared by exactly two faces
            running it in opposite directions.

        Notes
        -----
        Inside is the side the faces' normals point away from: faces are
        ordered counterclockwise seen from outside, and a mesh whose faces
        all point inwards gives inverted signs.

        The pseudonormal test (Bærentzen and Aanæs, 2005) is exact in
        theory on a closed, consistently oriented surface that does not
        intersect itself, and needs nothing but the closest feature, which
        the distance query finds anyway; it was chosen over the winding
        number (Jacobson et al., 2013), which is also right on meshes with
        small holes but costs O(F) per point without a hierarchy of far-field
        approximations.  Closed means: every edge of the faces with three
        distinct vertex indices is shared by exactly two faces that run it in
        opposite directions; faces with a repeated vertex index are left out
        of that check.  The pseudonormals are computed at the first call
        and kept with the mesh (not pickled).

        The winding number decides the points the pseudonormal cannot:
        those within the bound of rounding errors of the closest feature's
        tangent plane, and those whose closest feature touches a face of
        zero area (whose normal is undefined).  Each such point costs O(F).
        A point within rounding error of the surface may get either sign.

        Examples
        --------
        A cube from -1 to 1, queried at its centre, outside a face, on a
        vertex and beyond an edge:

        >>> import numpy as np, proximity
        >>> vertices = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
        >>> faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        ...          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
        >>> cube = proximity.TriangleMesh(vertices, faces)
        >>> cube.signed_distance([[0, 0, 0], [0, 0, 3], [1, 1, 1], [2, 2, 0]]).round(6).tolist()
        [-1.0, 2.0, 0.0, 1.414214]
        >>> cube.contains([[0.5, 0.5, 0.5], [0, 0, 1.5]]).tolist()
        [True, False]
        """
        if args:
            raise keyword_only(self, "signed_distance", args)
        out_shape, distance, inside = self._signed(points, method, sign)
        signed = np.where(inside, -distance, distance) + 0.0  # -0.0 + 0.0 is +0.0
        return freeze_result(signed.reshape(out_shape))[()]

    def contains(self, points, *args, method=DEFAULT_METHOD, sign="pseudonormal"):
        """Whether each point is in the closed mesh: inside, or on the surface.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        method, sign : str, keyword-only
            As in :meth:`signed_distance`.

        Returns
        -------
        ndarray of bool, shape ``(...)``, read-only
            True where :meth:`signed_distance` is ``<= 0``;
            False where the point is not finite.

        Raises
        ------
        ValueError
            With ``sign="pseudonormal"``, if the mesh is not closed.

        Examples
        --------
        >>> import proximity
        >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
        >>> tetrahedron = proximity.TriangleMesh(vertices, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        >>> tetrahedron.contains([[0.1, 0.1, 0.1], [1, 1, 1], [0, 0, 0]]).tolist()
        [True, False, True]
        """
        if args:
            raise keyword_only(self, "contains", args)
        out_shape, distance, inside = self._signed(points, method, sign)
        return freeze_result((inside | (distance == 0)).reshape(out_shape))[()]

    def _signed(self, points, method, sign):
        """``(output shape, distances (n,), inside (n,))`` for :meth:`signed_distance`."""
        if sign not in SIGNS:
            raise ValueError(f"sign must be one of {SIGNS}; got {sign!r}")
        _signed = _lazy.load("proximity._signed")
        signs = None
        if sign == "pseudonormal":
            signs = self._signs
            if signs is None:
                signs = _signed.Signs(self.vertices, self.faces)
                object.__setattr__(self, "_signs", signs)  # a cache: the mesh does not change
            if not signs.closed:
                raise ValueError(
                    f"signed distance with sign='pseudonormal' needs a closed mesh; this one is not: "
                    f"{signs.reason}.  sign='winding' works on any mesh, at O(F) per point"
                )
        r = self.closest_point(points, method=method) if signs is not None else None
        distance = np.asarray(r.distance if r is not None else self.distance(points, method=method))
        out_shape = distance.shape
        distance = distance.reshape(-1)
        flat = as_float64(points, "points", "(..., 3)").reshape(-1, 3)
        if signs is not None:
            inside = _signed.inside(
                signs, self.vertices, self.faces, flat, r.face.reshape(-1), r.feature.reshape(-1), distance
            )
        else:
            inside = np.zeros(len(flat), dtype=bool)
            rows = np.flatnonzero(distance > 0)
            inside[rows] = _signed.winding_numbers(self.vertices, self.faces, flat[rows]) > 0.5
        return out_shape, distance, inside

    def with_vertices(self, vertices):
        """The mesh with the same faces over moved ``vertices``: its hierarchy
        refitted, not rebuilt.

        The tree keeps its structure and its node bounds are fitted again to
        the moved faces, in about a fifth of a build's time or less; the
        answers are those of a mesh built afresh on the new vertices, bit for
        bit (the search's pruning holds for any tree, and ties go to the
        lowest face either way).  What a refit loses is speed: a tree built
        for one shape prunes less for a much deformed one, whose faces have
        moved far within it.  Rebuild (``TriangleMesh(vertices, faces)``) when
        the deformation is large against the faces' size, or every so many
        frames (``docs/performance.md`` measures the loss).

        Parameters
        ----------
        vertices : array_like, shape ``(V, 3)``
            Finite, as many as the mesh's.

        Examples
        --------
        >>> import numpy as np, proximity
        >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
        ...                                 [[0, 1, 2], [0, 2, 3]])
        >>> lifted = square.with_vertices(square.vertices + [0, 0, 2])
        >>> float(lifted.distance([0.5, 0.5, 0.0]))
        2.0
        """
        v = frozen_float64(vertices, "vertices", f"({len(self.vertices)}, 3)")
        if v.shape != self.vertices.shape:
            expected = self.vertices.shape
            raise ValueError(f"vertices must have shape {expected}, the mesh's; got shape {v.shape}")
        require_finite(v, "vertices")
        tree = self._tree
        # A build leaves out exact copies of a face; moved, they may no longer be
        # copies, so such a mesh is built again.
        if len(tree.index) != len(self.faces):
            return TriangleMesh(v, self.faces, broad_phase=self.broad_phase)
        # The moved faces' rows in leaf order and their bounds; the nodes refitted.
        with _threads.kernel():
            broadphase = _lazy.load("proximity.broadphase")
            params = broadphase.face_params(v, self.faces, tree.index)
            moved = broadphase.assemble(tree.kinds, params, tree.index, tree.child, tree.count, tree.depth)
        mesh = object.__new__(TriangleMesh)
        mesh._init(vertices=v, faces=self.faces, broad_phase=self.broad_phase, _tree=moved, _signs=None)
        return mesh

    def _nearest_index(self, result):
        return np.asarray(result.face)

    def _kind_codes(self):
        return np.full(len(self.faces), TRIANGLE.code, np.int8)

    def _surface_normals(self, result, rows, members):
        """The normals at the closest points of rows ``rows`` (on the mesh):
        the angle-weighted pseudonormal of the closest face, edge or vertex
        where the mesh is closed, else the face's normal."""
        face = np.asarray(result.face).reshape(-1)[rows]
        feature = np.asarray(result.feature).reshape(-1)[rows]
        signs = self._signs
        if signs is None:
            signs = _lazy.load("proximity._signed").Signs(self.vertices, self.faces)
            object.__setattr__(self, "_signs", signs)  # a cache: the mesh does not change
        if not signs.closed:
            return super()._surface_normals(result, rows, members)
        table_rows, _ = _lazy.load("proximity._signed").feature_rows(signs, self.faces, face, feature)
        return signs.table[table_rows, :3]

    def _primitives(self, index):
        """``(kinds, params)`` of faces ``index``, as the tree stores them."""
        return _primitives(self.vertices, self.faces[index])

    def _rows(self):
        """``(kinds, params)`` of every face, in order, as a collection stores them."""
        return _primitives(self.vertices, self.faces)

    def _result(self, fields):
        del fields["flag"]
        barycentric = fields.pop("extra")
        face = fields.pop("index")
        return MeshResult(**fields, barycentric=barycentric, face=face)


def _primitives(vertices, faces):
    """``(kinds, params)`` of the broad phase for ``faces``: each face's nine coordinates."""
    broadphase = _lazy.load("proximity.broadphase")
    return np.full(len(faces), TRIANGLE.code, np.int8), broadphase.face_params(vertices, faces)
