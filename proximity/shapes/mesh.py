"""Triangle meshes: the nearest face to each point.

A :class:`TriangleMesh` is a single shape (``batch_shape == ()``) made of
faces; a query answers, for each point, with the nearest face's answer to
the per-triangle method (:func:`proximity.point.triangle.robust` by default),
bit for bit, and the index of that face.  Degenerate faces (collinear or
coincident vertices) are queried like any other: ``robust`` answers for the
segment or point they are.  How the nearest face is found without testing
every face, and why that never changes the answer, is in
:mod:`proximity.broadphase`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import ArrayLike, Bools, Distances, Floats
from .._validate import (
    as_float64,
    as_index_array,
    cutoff,
    flag,
    freeze_fields,
    freeze_result,
    frozen,
    frozen_float64,
    one_of,
    require_finite,
)
from ..features import FACE
from ..primitives import N_PARAMS, TRIANGLE
from ..results import MeshResult, format_repr
from ..results.base import _frozen
from ..runtime import lazy, pool, threads
from .base import DEFAULT_METHOD, keyword_only
from .collection import Collection
from .meshlike import vertices_and_faces

if TYPE_CHECKING:
    from ..signs.validity import Validity
    from ..signs.winding import WindingResult

#: How :meth:`TriangleMesh.signed_distance` and :meth:`TriangleMesh.contains`
#: tell inside from outside.
SIGNS = ("auto", "pseudonormal", "winding")


class _SignState:
    """What the signs of one mesh need, computed at the first signed query and kept (not pickled)."""

    __slots__ = ("validity", "faces", "signs", "warned")

    def __init__(self, validity, faces, signs):
        self.validity = validity
        self.faces = faces  # vertices merged by position
        self.signs = signs  # the pseudonormal tables, or None where the mesh is not a manifold
        self.warned = False


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
        :data:`proximity.shapes.scene.BRUTE_FORCE_MAX`).  The answers are identical.

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

    __slots__ = ("vertices", "faces", "broad_phase", "_tree", "_signs", "_winding", "_normals")
    _reads_faces = True
    methods = TRIANGLE.methods
    result_type = MeshResult

    def __init__(self, vertices: Any, faces: ArrayLike | None = None, *, broad_phase: str = "auto") -> None:
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
            lambda bp: bp.brute(*_primitives(v, f, TRIANGLE.width)),
        )
        self._init(
            vertices=v, faces=f, broad_phase=resolved, _tree=tree, _signs=None, _winding=None, _normals=None
        )

    def __repr__(self):
        return format_repr(self, ("vertices", "faces"), broad_phase=self.broad_phase)

    def __len__(self):
        """Number of faces."""
        return len(self.faces)

    @property
    def triangles(self) -> Floats:
        """The faces' vertices, ``(F, 3, 3)``: a new array."""
        return self.vertices[self.faces]

    def __getstate__(self):
        state = super().__getstate__()
        state["_signs"] = state["_winding"] = state["_normals"] = (
            None  # rebuilt at first use: quicker than sending them
        )
        return state

    def __setstate__(self, state):
        super().__setstate__({"_signs": None, "_winding": None, "_normals": None, **state})

    def signed_distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        sign: str = "auto",
        max_distance: float | None = None,
    ) -> Distances:
        """Distance to the surface, negative inside the mesh, positive outside.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        method : str, keyword-only
            The per-triangle method of the distance (see :attr:`methods`);
            default ``"robust"``.
        sign : {"auto", "pseudonormal", "winding"}, keyword-only
            How inside is told from outside (see Notes).  ``"auto"``
            (default): the pseudonormal on a mesh that bounds a solid, the
            winding number on other closed meshes, with a warning.
            ``"pseudonormal"``: the angle-weighted pseudonormal of the
            closest face, edge or vertex, O(1) per point after the closest
            point, on a closed manifold mesh; it warns where the mesh is not a
            solid.  ``"winding"``: inside where the winding number's
            magnitude exceeds 1/2, on any mesh.
        max_distance : float, optional, keyword-only
            A cutoff: a point farther from the surface gets ``-inf`` inside
            and ``+inf`` outside (its side from the winding number), and the
            search skips what lies beyond it; the others are as without it.

        Returns
        -------
        ndarray of float64, shape ``(...)``, read-only
            ``+0.0`` where the distance is 0 (never ``-0.0``); NaN where the
            point is not finite.  A NumPy scalar for one point.

        Raises
        ------
        ValueError
            With ``sign="auto"``, if the mesh is not closed (by position:
            coincident vertices count as one); with ``sign="pseudonormal"``,
            if it is not a closed manifold.  The message names an edge and
            suggests ``sign="winding"``.

        Warns
        -----
        RuntimeWarning
            Where the mesh is not a solid, saying why (see :attr:`validity`):
            at every query with ``sign="pseudonormal"``, whose signs can be
            wrong there (and are not :meth:`signed`'s ``certain``); once per
            mesh where ``sign="auto"`` turns to the winding number.

        Notes
        -----
        Inside is where the winding number is not 0 (the nonzero rule:
        ``|w| > 1/2``), whichever way the faces point: a mesh whose faces
        all point inwards has the same inside, and the inside of nested or
        overlapping shells is their union.

        The pseudonormal test (Bærentzen and Aanæs, 2005) is exact on a
        closed, consistently oriented surface that does not intersect
        itself, and needs nothing but the closest feature, which the
        distance query finds anyway.  :attr:`validity` checks that once
        per mesh (closed by position, manifold, no self-intersections, no
        nested or overlapping shells facing the same way, and which way the
        faces point); elsewhere it can be silently wrong, so ``"auto"``
        uses the winding number there instead.  The pseudonormal decides
        every point whose product clears its bound of rounding errors; the
        others, and those whose closest feature touches a face of zero
        area, are decided by the winding number.

        The winding number (Jacobson et al., 2013) is summed down a
        hierarchy of far-field expansions (Barill et al., 2018) with a
        rigorous bound on its error (see :mod:`proximity.signs.winding`); the
        evaluation goes on until the bound proves the side, so every side
        it proves is exact.  Points where it cannot (on a mesh with holes,
        where the winding number is within its bound of 1/2; within
        rounding of the surface) get the side of the computed value, and
        :meth:`signed` reports them as not certain.  Faces of zero area
        count exactly 0.  The tables are computed at the first signed query
        and kept with the mesh (not pickled).

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

        The same cube with every face reversed has the same inside:

        >>> inverted = proximity.TriangleMesh(vertices, np.array(faces)[:, ::-1])
        >>> inverted.signed_distance([[0, 0, 0], [0, 0, 3]]).tolist()
        [-1.0, 2.0]
        """
        if args:
            raise keyword_only(self, "signed_distance", args)
        out_shape, distance, inside, _ = self._signed(points, method, sign, max_distance)
        signed = np.where(inside, -distance, distance) + 0.0  # -0.0 + 0.0 is +0.0
        return freeze_result(signed.reshape(out_shape))[()]

    def contains(
        self, points: ArrayLike, *args: object, method: str = DEFAULT_METHOD, sign: str = "auto"
    ) -> Bools:
        """Whether each point is in the mesh: inside, or on the surface.

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
            As :meth:`signed_distance`.

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
        out_shape, distance, inside, _ = self._signed(points, method, sign)
        return freeze_result((inside | (distance == 0)).reshape(out_shape))[()]

    def signed(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        sign: str = "auto",
        max_distance: float | None = None,
    ) -> SignedResult:
        """:meth:`signed_distance` and :meth:`contains` in one query, and whether each side is certain.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        method, sign : str, keyword-only
            As in :meth:`signed_distance`.
        max_distance : float, optional, keyword-only
            As in :meth:`signed_distance`.

        Returns
        -------
        SignedResult
            ``signed_distance``, ``contains`` and ``certain``, each of shape
            ``(...)``.

        Raises
        ------
        ValueError
            As :meth:`signed_distance`.

        Notes
        -----
        ``certain`` is True where the side is proven: the pseudonormal's
        product clears its bound of rounding errors, or the winding
        number's bound keeps it on one side of 1/2.  It is False on the
        surface (distance 0), within rounding of it, on a mesh with holes
        where the winding number is within its bound of 1/2, where the
        point is not finite, and where ``sign="pseudonormal"`` decides on a
        mesh that is not a solid (:attr:`validity`), whose pseudonormals
        prove nothing.

        Examples
        --------
        An open box (its top missing), inside, outside, in the opening's
        plane (where the winding number is exactly 1/2), and on a face:

        >>> import proximity
        >>> vertices = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
        >>> faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        ...          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4]]
        >>> box = proximity.TriangleMesh(vertices, faces)
        >>> r = box.signed([[0, 0, 0], [3, 0, 0], [0, 0, 1], [1, 0, 0]], sign="winding")
        >>> r.signed_distance.tolist(), r.contains.tolist(), r.certain.tolist()
        ([-1.0, 2.0, 1.0, 0.0], [True, False, False, True], [True, True, False, False])
        """
        if args:
            raise keyword_only(self, "signed", args)
        out_shape, distance, inside, certain = self._signed(points, method, sign, max_distance)
        signed = np.where(inside, -distance, distance) + 0.0
        return SignedResult(
            signed_distance=signed.reshape(out_shape),
            contains=(inside | (distance == 0)).reshape(out_shape),
            certain=certain.reshape(out_shape),
        )

    def sdf_grid(
        self,
        lower: ArrayLike,
        upper: ArrayLike,
        shape: Sequence[int],
        *args: object,
        max_distance: float | None = None,
        method: str = DEFAULT_METHOD,
        sign: str = "auto",
    ) -> Floats:
        """Signed distances at the points of a regular grid, with an optional narrow band.

        Parameters
        ----------
        lower, upper : array_like, shape ``(3,)``
            The grid's first and last points: finite, ``lower <= upper``.
        shape : sequence of 3 int
            Points along x, y and z, ``(nx, ny, nz)``, each at least 1.  Point
            ``(i, j, k)`` is ``(x[i], y[j], z[k])`` with ``x = np.linspace(lower[0],
            upper[0], nx)`` and so on (``2 * np.linspace(lower[0] / 2, upper[0] / 2,
            nx)`` where ``upper[0] - lower[0]`` overflows).
        max_distance : float, optional, keyword-only
            The narrow band: where the distance exceeds it, ``-inf`` inside
            and ``+inf`` outside, without computing the distance.  None
            (default): every distance.
        method, sign : str, keyword-only
            As in :meth:`signed_distance`.

        Returns
        -------
        ndarray of float64, shape ``(nx, ny, nz)``
            :meth:`signed_distance` at each grid point, bit for bit, within
            the band; ``±inf`` beyond it.  A new, writeable array.

        Raises
        ------
        ValueError
            As :meth:`signed_distance`, or naming the argument that is not
            valid.

        Notes
        -----
        The grid is cut into blocks of 8 x 8 x 8 points, and the distance
        from each block's centre ``c`` is queried first.  A block farther
        than ``max_distance`` plus its half-diagonal ``r`` from the surface
        lies beyond the band: it gets the side of its centre and no
        distance.  On a closed mesh a block with ``d(c) > r`` does not
        touch the surface, so its points share its centre's side (the
        winding number is constant off the surface): their distances are
        queried without a sign.  Other blocks get :meth:`signed_distance`
        point by point.  Where a centre's side is not certain, or the mesh
        is not closed (``sign="winding"``), each point gets its own side.

        Examples
        --------
        A cube from -1 to 1 on a 5 x 5 x 5 grid over [-2, 2], the band at 0.6:

        >>> import proximity
        >>> vertices = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
        >>> faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        ...          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
        >>> cube = proximity.TriangleMesh(vertices, faces)
        >>> grid = cube.sdf_grid([-2, -2, -2], [2, 2, 2], (5, 5, 5))
        >>> grid[:, 2, 2].tolist()
        [1.0, 0.0, -1.0, 0.0, 1.0]
        >>> cube.sdf_grid([-2, -2, -2], [2, 2, 2], (5, 5, 5), max_distance=0.6)[:, 2, 2].tolist()
        [inf, 0.0, -inf, 0.0, inf]
        """
        if args:
            raise TypeError(
                "TriangleMesh.sdf_grid() takes three positional arguments, lower, upper and shape; "
                f"the others are keyword-only: got {len(args)} more"
            )
        one_of(sign, "sign", SIGNS)
        low = as_float64(lower, "lower", "(3,)")
        high = as_float64(upper, "upper", "(3,)")
        for name, corner in (("lower", low), ("upper", high)):
            if corner.shape != (3,) or not np.isfinite(corner).all():
                raise ValueError(f"{name} must be 3 finite coordinates; got {corner.tolist()}")
        if not (low <= high).all():
            raise ValueError(f"lower must not exceed upper; got lower={low.tolist()}, upper={high.tolist()}")
        counts = np.asarray(shape)
        if counts.shape != (3,) or counts.dtype.kind not in "iu" or (counts < 1).any():
            raise ValueError(f"shape must be 3 integers >= 1; got {shape!r}")
        band = None if max_distance is None else cutoff(max_distance)
        if sign != "winding" and self.validity.closed:
            self._sign_plan(sign, stacklevel=4)  # its warning, once for the grid's many queries
        from ..signs import grid

        return grid.sdf_grid(self, low, high, tuple(int(c) for c in counts), band, method, sign)

    def winding_number(self, points: ArrayLike, *args: object, full: bool = False) -> WindingResult:
        """The generalized winding number at each point, with a bound on its error.

        Parameters
        ----------
        points : array_like, shape ``(..., 3)``
        full : bool, keyword-only
            False (default): each point's sum stops as soon as its bound
            proves the side (``|w| > 1/2``), so ``winding`` is only as
            accurate as that needs.  True: every face is summed exactly,
            at O(F) per point, for the value itself.

        Returns
        -------
        proximity.signs.winding.WindingResult
            ``winding``, ``error``, ``inside`` and ``certain``, each of
            shape ``(...)``.

        Notes
        -----
        The sum of the faces' solid angles over ``4 pi`` (Jacobson et al.,
        2013), down a hierarchy of far-field expansions (Barill et al.,
        2018) with a rigorous bound (see :mod:`proximity.signs.winding`).  On a
        mesh closed by position it is an integer off the surface, given
        exactly wherever the bound leaves a single integer.  The hierarchy
        is built at the first call and kept with the mesh (not pickled).

        Examples
        --------
        A unit square, seen from above its centre and far away; two
        tetrahedra, one inside the other, both facing out:

        >>> import numpy as np, proximity
        >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
        ...                                 [[0, 1, 2], [0, 2, 3]])
        >>> r = square.winding_number([[0.5, 0.5, 1e-9], [0.5, 0.5, 1e6]], full=True)
        >>> r.winding.round(6).tolist(), r.inside.tolist()
        ([-0.5, -0.0], [False, False])
        >>> tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
        >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
        >>> both = faces + (np.array(faces) + 4).tolist()
        >>> nested = proximity.TriangleMesh(np.vstack([tet * 4 - 1, tet]), both)
        >>> r = nested.winding_number([[0.1, 0.1, 0.1], [-0.5, 0.5, 0.5], [5, 5, 5]])
        >>> r.winding.tolist(), r.error.tolist(), r.certain.tolist()
        ([2.0, 1.0, 0.0], [0.0, 0.0, 0.0], [True, True, True])
        """
        from ..signs import winding

        if args:
            raise keyword_only(self, "winding_number", args)
        pts = _points(points)
        out_shape = pts.shape[:-1]
        w, e, integral = self._winding_numbers(pts.reshape(-1, 3), full=flag(full, "full"))
        inside, certain, w, e = winding.sides(w, e, integral)
        return winding.WindingResult(
            winding=w.reshape(out_shape),
            error=e.reshape(out_shape),
            inside=inside.reshape(out_shape),
            certain=certain.reshape(out_shape),
        )

    @property
    def validity(self) -> Validity:
        """Whether the mesh bounds a solid, and why not: a :class:`proximity.signs.validity.Validity`.

        Checked at the first access (or signed query) and kept with the
        mesh: closed by position, manifold, shells neither nested the same
        way nor overlapping, no self-intersections (see
        :mod:`proximity.signs.validity`).

        Examples
        --------
        >>> import proximity
        >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
        >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
        >>> v = proximity.TriangleMesh(vertices, faces).validity
        >>> v.closed, v.solid, v.inverted, v.shells, v.reason
        (True, True, False, 1, None)
        >>> proximity.TriangleMesh(vertices, faces[1:]).validity.reason[:46]
        'it is not closed: edge (0, 1) of face 0 has no'
        """
        return self._sign_state().validity

    def _hierarchy(self):
        """The winding number's :class:`proximity.signs.winding.Hierarchy`, built at the first call."""
        h = self._winding
        if h is None:
            from ..signs import winding

            h = winding.build(self)
            object.__setattr__(self, "_winding", h)  # a cache: the mesh does not change
        return h

    def _sign_state(self):
        state = self._signs
        if state is None:
            from ..signs import signed as _signed
            from ..signs import validity

            checked, faces = validity.check(self, self._hierarchy())
            signs = _signed.Signs(self.vertices, faces) if checked.closed else None
            state = _SignState(checked, faces, signs if signs is not None and signs.closed else None)
            object.__setattr__(self, "_signs", state)  # a cache: the mesh does not change
        return state

    def _sign_plan(self, sign, warn=True, stacklevel=5):
        """:func:`proximity.signs.signed.plan` of a signed query with ``sign`` on this mesh."""
        state = None if sign == "winding" else self._sign_state()
        return lazy.load("proximity.signs.signed").plan(state, sign, warn, stacklevel)

    def _signed(self, points, method, sign, max_distance=None, warn=True):
        """``(output shape, distances (n,), inside (n,), certain (n,))`` for
        :meth:`signed_distance`; rows beyond ``max_distance`` at an infinite
        distance, their side from the winding number.  ``warn``: as :meth:`_sign_plan`
        (False where the caller has warned for its query)."""
        one_of(sign, "sign", SIGNS)
        cut = cutoff(max_distance)
        _signed = lazy.load("proximity.signs.signed")
        state, use_winding, proven = self._sign_plan(sign, warn)
        if use_winding:
            distance = np.asarray(self.distance(points, method=method, max_distance=max_distance))
            out_shape = distance.shape
            distance = distance.reshape(-1)
            flat = as_float64(points, "points", "(..., 3)").reshape(-1, 3)
            inside, certain = self._winding_sides(flat, distance)
            return out_shape, distance, inside, certain
        r = self.closest_point(points, method=method, max_distance=max_distance)
        distance = np.asarray(r.distance)
        out_shape = distance.shape
        distance = distance.reshape(-1)
        flat = as_float64(points, "points", "(..., 3)").reshape(-1, 3)
        face, feature = r.face.reshape(-1), r.feature.reshape(-1)
        near = distance <= cut  # NaN rows too: the pseudonormal leaves them out
        near |= np.isnan(distance)
        inside, certain = _signed.inside(
            state.signs, self.vertices, state.faces, flat[near], face[near], feature[near], distance[near],
            flip=state.validity.inverted, winding=self._winding_sides, proven=proven,
        )  # fmt: skip
        if near.all():
            return out_shape, distance, inside, certain
        # Beyond the cutoff there is no closest feature: the winding number tells the side.
        far_inside, far_certain = self._winding_sides(flat[~near], distance[~near])
        inside_all = np.empty(len(distance), dtype=bool)
        certain_all = np.empty(len(distance), dtype=bool)
        inside_all[near], certain_all[near] = inside, certain
        inside_all[~near], certain_all[~near] = far_inside, far_certain
        return out_shape, distance, inside_all, certain_all

    def _winding_sides(self, points, distance):
        """``(inside, certain)`` by the winding number for ``points`` ``(n, 3)`` at ``distance``
        ``(n,)``: both False where the distance is 0 or NaN."""
        inside = np.zeros(len(points), dtype=bool)
        certain = np.zeros(len(points), dtype=bool)
        rows = np.flatnonzero(distance > 0)
        if len(rows):
            w, e, integral = self._winding_numbers(points[rows])
            from ..signs import winding

            inside[rows], certain[rows], _, _ = winding.sides(w, e, integral)
        return inside, certain

    def _winding_numbers(self, points, full=False):
        """``(w, error, integral)`` at ``points`` ``(n, 3)``: on a mesh closed by position the
        signed crossings of a ray (exact integers), and the hierarchy's sum where a crossing is
        undecided or ``full``; elsewhere the sum."""
        from ..signs import crossings, winding

        h = self._hierarchy()
        if not h.integral:
            w, e = winding.numbers(h, points, full=full, rule=winding.NONZERO)
            return w, e, False
        if full:
            w, e = winding.numbers(h, points, full=True, rule=winding.INTEGRAL)
            return w, e, True
        w = crossings.crossings(h, points)
        e = np.zeros(len(points))
        rest = np.flatnonzero(np.isnan(w))
        if len(rest):
            w[rest], e[rest] = winding.numbers(h, points[rest], rule=winding.INTEGRAL)
        return w, e, True

    def with_vertices(self, vertices: ArrayLike) -> TriangleMesh:
        """The mesh with the same faces over moved ``vertices``: its hierarchy
        refitted, not rebuilt.

        The tree keeps its structure and its node bounds are fitted again to
        the moved faces, in O(faces): the leaves' bounds measured, the nodes'
        above merged from their children's.  The answers are those of a mesh
        built afresh on the new vertices, bit for bit (the search's pruning
        holds for any tree, and ties go to the lowest face either way).  What
        a refit loses is speed: a tree built for one shape prunes less for a
        much deformed one, whose faces have moved far within it.  Rebuild
        (``TriangleMesh(vertices, faces)``) when the deformation is large
        against the faces' size, or every so many frames:
        ``docs/performance.md`` measures both the refit against a build and
        the queries after a small and a large deformation.  A refit per
        frame reuses the memory of the meshes it replaced, once they are
        gone (see :func:`proximity.release_memory`).

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
        # A build leaves out exact copies of a face; moved, they may no longer
        # be copies, so such a mesh is built again, as is a tree that keeps
        # its faces' rows (one whose faces' hashes collided at the build).
        if len(tree.index) != len(self.faces) or (len(tree.child) > 1 and not tree.indexed):
            return TriangleMesh(v, self.faces, broad_phase=self.broad_phase)
        with threads.kernel():
            moved = lazy.load("proximity.broadphase").build.refitted(tree, v, self.faces, pool.empty)
        mesh = object.__new__(TriangleMesh)
        mesh._init(
            vertices=v,
            faces=self.faces,
            broad_phase=self.broad_phase,
            _tree=moved,
            _signs=None,
            _winding=None,
            _normals=None,
        )
        return mesh

    def _nearest_index(self, result):
        return np.asarray(result.face)

    def _kind_codes(self):
        return np.full(len(self.faces), TRIANGLE.code, np.int8)

    def _feature_normals(self, index, feature, points):
        """The normals of faces ``index`` at closest points on their
        ``feature`` to ``points``: at a face, its normal towards the point;
        on an edge or a vertex, the angle-weighted pseudonormal where the
        mesh is closed, else the face's normal (see :attr:`Result.normal`)."""
        normal = super()._feature_normals(index, feature, points)
        rest = np.flatnonzero(np.asarray(feature) != FACE)
        if len(rest) == 0:
            return normal
        signs = self._normals
        if signs is None:
            signs = lazy.load("proximity.signs.signed").Signs(self.vertices, self.faces)
            object.__setattr__(self, "_normals", signs)  # a cache: the mesh does not change
        if signs.closed:
            signed = lazy.load("proximity.signs.signed")
            table_rows, _ = signed.feature_rows(signs, self.faces, index[rest], np.asarray(feature)[rest])
            pseudo = signs.table[table_rows, :3]
            # Where a degenerate face leaves the pseudonormal undefined, the face's normal stays.
            length = np.linalg.norm(pseudo, axis=1)
            good = np.isfinite(length) & (length > 0.5)
            normal[rest[good]] = pseudo[good]
        return normal

    def _primitives(self, index):
        """``(kinds, params)`` of faces ``index``, as the tree stores them."""
        return _primitives(self.vertices, self.faces[index], TRIANGLE.width)

    def _rows(self):
        """``(kinds, params)`` of every face, in order, as a collection stores them."""
        return _primitives(self.vertices, self.faces)

    def _result(self, fields):
        del fields["flag"]
        barycentric = fields.pop("extra")
        face = fields.pop("index")
        return MeshResult(**fields, barycentric=barycentric, face=face)


def _points(points):
    """``points`` as float64 of shape ``(..., 3)``, or a ValueError naming them."""
    points = as_float64(points, "points", "(..., 3)")
    if points.ndim == 0 or points.shape[-1] != 3:
        raise ValueError(f"points must have shape (..., 3); got shape {points.shape}")
    return points


def _primitives(vertices, faces, width=N_PARAMS):
    """``(kinds, params)`` of the broad phase for ``faces``: each face's nine coordinates, ``width`` wide."""
    broadphase = lazy.load("proximity.broadphase")
    return np.full(len(faces), TRIANGLE.code, np.int8), broadphase.face_params(vertices, faces, width=width)


@dataclasses.dataclass(frozen=True, repr=False)
class SignedResult:
    """Signed distances, containment, and whether each side is certain (:meth:`TriangleMesh.signed`).

    Attributes
    ----------
    signed_distance : ndarray of float64, shape ``batch``
        As :meth:`TriangleMesh.signed_distance`.
    contains : ndarray of bool, shape ``batch``
        As :meth:`TriangleMesh.contains`.
    certain : ndarray of bool, shape ``batch``
        Whether the side is proven (see :meth:`TriangleMesh.signed`).
    """

    signed_distance: np.ndarray
    contains: np.ndarray
    certain: np.ndarray

    def __post_init__(self):
        for name, value in vars(self).items():
            object.__setattr__(self, name, _frozen(value))

    def __setstate__(self, state):
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return format_repr(self, [f.name for f in dataclasses.fields(self)])
