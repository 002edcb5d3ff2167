"""Drop-ins for ``trimesh.proximity``: ``closest_point``, ``signed_distance`` and ``ProximityQuery``.

Replace ::

    closest, distance, triangle_id = trimesh.proximity.closest_point(mesh, points)
    signed = trimesh.proximity.signed_distance(mesh, points)

with ::

    from proximity.trimesh_compat import closest_point, signed_distance
    closest, distance, triangle_id = closest_point(mesh, points)
    signed = signed_distance(mesh, points)

The arguments, the return and the sign convention are trimesh's (positive
inside); trimesh itself is not needed (nor ``rtree`` and ``scipy``, which
trimesh's versions require).
"""

import threading
import weakref

import numpy as np

from .._validate import as_array
from ..features import Feature
from ..shapes.mesh import TriangleMesh

#: Meshes built from ``trimesh.Trimesh`` objects, kept so that repeated calls
#: on the same unchanged mesh reuse its hierarchy, as trimesh reuses its
#: r-tree.  Keyed by ``id``, checked against a weak reference and trimesh's
#: content hash, and bounded.
_CACHE = {}
_CACHE_SIZE = 8
_LOCK = threading.Lock()


def _mesh(mesh):
    if isinstance(mesh, TriangleMesh):
        return mesh
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        vertices, faces = mesh
        return TriangleMesh(vertices, faces)
    if not (hasattr(mesh, "vertices") and hasattr(mesh, "faces")):
        raise TypeError(
            "mesh must be a trimesh.Trimesh, a (vertices, faces) pair or a proximity.TriangleMesh; "
            f"got {type(mesh).__name__}"
        )
    try:
        version = hash(mesh)  # trimesh: a hash of the mesh's data, cached until it changes
    except TypeError:
        return TriangleMesh(mesh.vertices, mesh.faces)
    key = id(mesh)
    with _LOCK:
        entry = _CACHE.get(key)
        if entry is not None and entry[0]() is mesh and entry[1] == version:
            return entry[2]
    built = TriangleMesh(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    try:
        ref = weakref.ref(mesh)
    except TypeError:
        return built
    with _LOCK:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = (ref, version, built)
    return built


def _points(points):
    """``points`` as a float64 array ``(n, 3)``, and whether it was one point ``(3,)``:
    converted as trimesh does (``np.asarray(points, dtype=np.float64)``), with
    errors that name them."""
    points = as_array(points, "points", "(n, 3)", dtype=np.float64)
    one = points.shape == (3,)
    if one:
        points = points[None]
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be (n, 3), or (3,) for one point; got shape {points.shape}")
    return points, one


def _one(arrays, one):
    """The answers of one point without their leading axis (NumPy scalars for
    per-point values), as scipy's k-d tree gives them; else as they are."""
    if not one:
        return arrays
    return tuple(a[0] for a in arrays)


# -- trimesh's choice among faces at the same distance ------------------------------------

# The two vertex columns of each edge feature, by feature code.
_EDGE_COLUMNS = {
    int(Feature.EDGE01): (0, 1),
    int(Feature.EDGE12): (1, 2),
    int(Feature.EDGE20): (2, 0),
}
_VERTEX_CODES = (int(Feature.VERTEX0), int(Feature.VERTEX1), int(Feature.VERTEX2))


class _Incidence:
    """The faces around each vertex of a mesh (by index), and the faces' unit normals."""

    def __init__(self, mesh):
        flat = mesh.faces.ravel()
        order = np.argsort(flat, kind="stable")
        self.face_of = order // 3
        self.start = np.searchsorted(flat[order], np.arange(len(mesh.vertices) + 1))
        t = mesh.vertices[mesh.faces]
        normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        length = np.linalg.norm(normal, axis=1, keepdims=True)
        self.normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)


_INCIDENCE = {}


def _incidence(mesh):
    """:class:`_Incidence` of ``mesh``, kept for the last few meshes (they are immutable)."""
    with _LOCK:
        entry = _INCIDENCE.get(id(mesh))
        if entry is not None and entry[0] is mesh:
            return entry[1]
    incidence = _Incidence(mesh)
    with _LOCK:
        if len(_INCIDENCE) >= _CACHE_SIZE:
            _INCIDENCE.pop(next(iter(_INCIDENCE)))
        _INCIDENCE[id(mesh)] = (mesh, incidence)
    return incidence


def _facing(mesh, points, r):
    """The nearest face of each point, where several hold its closest point, as trimesh picks it.

    A closest point on an edge or a vertex of the nearest face is on every
    face that shares that edge or vertex (by vertex index), at the same
    distance.  Of those, the one whose unit normal points most towards the
    query point is chosen (the lowest index among equals).
    """
    face = np.array(r.face)
    feature = np.asarray(r.feature)
    rows = np.flatnonzero((feature != int(Feature.FACE)) & (feature >= 0) & (np.asarray(r.distance) > 0))
    if len(rows) == 0:
        return face
    inc = _incidence(mesh)
    code = feature[rows].astype(np.int64)
    own = mesh.faces[face[rows]]
    # The columns of the feature's vertices in its face: a vertex's (its code),
    # or an edge's two, the faces around the first then checked for the second.
    first = np.where(np.isin(code, _VERTEX_CODES), code, 0)
    second = np.full(len(rows), -1)
    for c, (i, j) in _EDGE_COLUMNS.items():
        at = code == c
        first[at], second[at] = i, j
    k = np.arange(len(rows))
    a = own[k, first]
    b = np.where(second >= 0, own[k, np.maximum(second, 0)], -1)
    # Every (row, face around a) pair, flattened.
    counts = inc.start[a + 1] - inc.start[a]
    row = np.repeat(np.arange(len(rows)), counts)
    offset = np.arange(len(row)) - np.repeat(np.cumsum(counts) - counts, counts)
    candidate = inc.face_of[inc.start[a][row] + offset]
    keep = (b[row] < 0) | (mesh.faces[candidate] == b[row, None]).any(axis=1)
    row, candidate = row[keep], candidate[keep]
    towards = points[rows] - np.asarray(r.point)[rows]
    dot = np.einsum("ij,ij->i", inc.normal[candidate], towards[row])
    # Per row: the largest dot, then the lowest face index.
    order = np.lexsort((candidate, -dot, row))
    firsts = order[np.r_[True, row[order][1:] != row[order][:-1]]]
    face[rows[row[firsts]]] = candidate[firsts]
    return face


def closest_point(mesh, points):
    """Closest point on a mesh to each point, as ``trimesh.proximity.closest_point``.

    Parameters
    ----------
    mesh : trimesh.Trimesh, (vertices, faces) or proximity.TriangleMesh
        The mesh.  A ``Trimesh`` is converted once and the result kept (with
        its bounding-volume hierarchy) while the mesh is alive and
        unchanged; a ``(vertices, faces)`` pair is converted on every call,
        so pass a :class:`proximity.TriangleMesh` to reuse one.
    points : array_like, shape ``(m, 3)``, or ``(3,)`` for one point
        Points in space.

    Returns
    -------
    closest : ndarray of float64, shape ``(m, 3)``
        Closest point on the mesh for each point.
    distance : ndarray of float64, shape ``(m,)``
        Distance to the mesh.
    triangle_id : ndarray of int64, shape ``(m,)``
        Index of the face holding the closest point.

    For one point of shape ``(3,)`` (which trimesh refuses), the same
    without the leading axis: ``(3,)``, a float64 and an int64 scalar.

    Raises
    ------
    ValueError
        If ``points`` is neither ``(m, 3)`` nor ``(3,)``.

    Notes
    -----
    Distances are those of ``proximity``'s ``robust`` method: within
    ``8 eps S`` of the exact distance to the nearest face, where trimesh
    decides each face's closest feature with an absolute tolerance and is
    off by up to the size of a face on small faces.

    Where several faces hold the closest point (it lies on an edge or a
    vertex), ``triangle_id`` is the face whose normal points most towards
    the query point, as trimesh prefers (the lowest index among faces that
    point alike).  The candidates are the faces that share the edge or the
    vertex by index; trimesh's differ in two ways: it compares only the two
    nearest faces by its rounded distances (so at a vertex of more than two
    faces it may pick another), and it applies the rule only where the
    squared distance exceeds ``trimesh.tol.merge`` (1e-8, absolute), taking
    the first candidate closer in.  A point containing NaN or inf gives NaN
    and id -1.  The arrays are new and writable.

    Examples
    --------
    >>> from proximity.trimesh_compat import closest_point
    >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> closest, distance, triangle_id = closest_point((vertices, faces), [[1, 1, 1], [-1, 0.2, 0.3]])
    >>> closest.round(6).tolist(), distance.round(6).tolist(), triangle_id.tolist()
    ([[0.333333, 0.333333, 0.333333], [0.0, 0.2, 0.3]], [1.154701, 1.0], [3, 2])
    """
    points, one = _points(points)
    built = _mesh(mesh)
    r = built.closest_point(points)
    return _one((np.array(r.point), np.array(r.distance), _facing(built, points, r)), one)


def signed_distance(mesh, points):
    """Signed distance to a closed mesh, as ``trimesh.proximity.signed_distance``: POSITIVE inside.

    Parameters
    ----------
    mesh : trimesh.Trimesh, (vertices, faces) or proximity.TriangleMesh
        A closed mesh (see :meth:`proximity.TriangleMesh.signed_distance`),
        converted and kept as in :func:`closest_point`.
    points : array_like, shape ``(n, 3)``, or ``(3,)`` for one point

    Returns
    -------
    ndarray of float64, shape ``(n,)``
        The distance, positive inside the mesh, negative outside and
        ``+0.0`` on it: trimesh's convention, the opposite of
        :meth:`proximity.TriangleMesh.signed_distance`.  New and writable;
        a float64 scalar for one point.

    Raises
    ------
    ValueError
        If ``points`` is neither ``(n, 3)`` nor ``(3,)``, or the mesh is not closed.

    Notes
    -----
    trimesh takes the sign from the nearest face's normal where the point
    projects into that face, and from ray tests otherwise, and gives every
    point within ``trimesh.tol.merge`` (1e-8, absolute) of the surface a
    positive distance whichever its side; this function gives every point
    its side (``sign="auto"``: the angle-weighted pseudonormal of the
    closest feature on a mesh that bounds a solid, the exact winding number
    on other closed meshes, with a warning), down to rounding error.  A
    mesh whose vertices are split along seams (as textured files load, or
    after ``mesh.unmerge_vertices()``) is closed by position and accepted.
    Where trimesh answers an open mesh with ray tests, this function
    raises; use
    ``proximity.TriangleMesh(...).signed_distance(points, sign="winding")``
    (negative inside) for open meshes.

    Examples
    --------
    >>> from proximity.trimesh_compat import signed_distance
    >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> signed_distance((vertices, faces), [[0.1, 0.2, 0.2], [-1, 0.2, 0.3], [0, 0, 0]]).round(6).tolist()
    [0.1, -1.0, 0.0]
    """
    points, one = _points(points)
    signed = -np.asarray(_mesh(mesh).signed_distance(points)) + 0.0
    return signed[0] if one else signed


class ProximityQuery:
    """As ``trimesh.proximity.ProximityQuery`` (``mesh.nearest``): queries of one mesh.

    Parameters
    ----------
    mesh : trimesh.Trimesh, (vertices, faces) or proximity.TriangleMesh
        Converted at each call as in :func:`closest_point` (a ``Trimesh``
        once while it is unchanged, so that later edits are seen, as
        trimesh's query sees them).

    Examples
    --------
    >>> from proximity.trimesh_compat import ProximityQuery
    >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> query = ProximityQuery((vertices, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    >>> closest, distance, triangle_id = query.on_surface([[1, 1, 1]])
    >>> distance.round(6).tolist(), triangle_id.tolist()
    ([1.154701], [3])
    >>> query.signed_distance([[0.1, 0.2, 0.2]]).round(6).tolist()
    [0.1]
    >>> distance, vertex_id = query.vertex([[0.9, 0.1, 0.0], [0, 0, 3]])
    >>> distance.round(6).tolist(), vertex_id.tolist()
    ([0.141421, 2.0], [1, 3])
    >>> distance, vertex_id = query.vertex([0, 0, 3])  # one point
    >>> float(distance), int(vertex_id)
    (2.0, 3)
    """

    def __init__(self, mesh):
        if isinstance(mesh, (tuple, list)):
            mesh = _mesh(mesh)  # converted once: a pair cannot change
        self._source = mesh
        self._vertices = None

    def on_surface(self, points):
        """``(closest, distance, triangle_id)`` for each point: :func:`closest_point`."""
        return closest_point(self._source, points)

    def signed_distance(self, points):
        """Signed distance, positive inside: :func:`signed_distance`."""
        return signed_distance(self._source, points)

    def vertex(self, points):
        """``(distance, vertex_id)``: the nearest vertex of the mesh to each point.

        ``points`` is ``(n, 3)``, or ``(3,)`` for one point, which gives a
        float64 and an int64 scalar, as trimesh's k-d tree does.  The
        vertices are queried as a mesh of point-like faces, so the distance
        is exact to rounding and ties go to the lowest index (trimesh's k-d
        tree breaks them its own way).  Vertices that no face uses count,
        as in trimesh.
        """
        points, one = _points(points)
        mesh = _mesh(self._source)
        if self._vertices is None or self._vertices[0] is not mesh:
            index = np.arange(len(mesh.vertices))
            self._vertices = (mesh, TriangleMesh(mesh.vertices, np.stack([index, index, index], axis=1)))
        r = self._vertices[1].closest_point(points)
        return _one((np.array(r.distance), np.array(r.face)), one)
