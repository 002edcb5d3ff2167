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

from .mesh import TriangleMesh

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


def closest_point(mesh, points):
    """Closest point on a mesh to each point, as ``trimesh.proximity.closest_point``.

    Parameters
    ----------
    mesh : trimesh.Trimesh, (vertices, faces) or proximity.TriangleMesh
        The mesh.  A ``Trimesh`` is converted once and the result kept (with
        its bounding-volume hierarchy) while the mesh is alive and
        unchanged; a ``(vertices, faces)`` pair is converted on every call,
        so pass a :class:`proximity.TriangleMesh` to reuse one.
    points : array_like, shape ``(m, 3)``
        Points in space.

    Returns
    -------
    closest : ndarray of float64, shape ``(m, 3)``
        Closest point on the mesh for each point.
    distance : ndarray of float64, shape ``(m,)``
        Distance to the mesh.
    triangle_id : ndarray of int64, shape ``(m,)``
        Index of the face holding the closest point.

    Raises
    ------
    ValueError
        If ``points`` is not ``(m, 3)``, as trimesh does.

    Notes
    -----
    Distances are those of ``proximity``'s ``robust`` method: within
    ``8 eps S`` of the exact distance to the nearest face, where trimesh
    decides each face's closest feature with an absolute tolerance and is
    off by up to the size of a face on small faces.  ``triangle_id`` differs
    from trimesh's only where several faces hold the closest point (an edge
    or a vertex): trimesh takes the face whose normal points most towards
    the query point, this function the lowest index.  A point containing
    NaN or inf gives NaN and id -1.  The arrays are new and writable.

    Examples
    --------
    >>> from proximity.trimesh_compat import closest_point
    >>> vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    >>> closest, distance, triangle_id = closest_point((vertices, faces), [[1, 1, 1], [-1, 0.2, 0.3]])
    >>> closest.round(6).tolist(), distance.round(6).tolist(), triangle_id.tolist()
    ([[0.333333, 0.333333, 0.333333], [0.0, 0.2, 0.3]], [1.154701, 1.0], [3, 2])
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be (n, 3); got shape {points.shape}")
    r = _mesh(mesh).closest_point(points)
    return np.array(r.point), np.array(r.distance), np.array(r.face)


def signed_distance(mesh, points):
    """Signed distance to a closed mesh, as ``trimesh.proximity.signed_distance``: POSITIVE inside.

    Parameters
    ----------
    mesh : trimesh.Trimesh, (vertices, faces) or proximity.TriangleMesh
        A closed mesh (see :meth:`proximity.TriangleMesh.signed_distance`),
        converted and kept as in :func:`closest_point`.
    points : array_like, shape ``(n, 3)``

    Returns
    -------
    ndarray of float64, shape ``(n,)``
        The distance, positive inside the mesh, negative outside and
        ``+0.0`` on it: trimesh's convention, the opposite of
        :meth:`proximity.TriangleMesh.signed_distance`.  New and writable.

    Raises
    ------
    ValueError
        If ``points`` is not ``(n, 3)``, or the mesh is not closed.

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
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be (n, 3); got shape {points.shape}")
    return -np.asarray(_mesh(mesh).signed_distance(points)) + 0.0


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

        The vertices are queried as a mesh of point-like faces, so the
        distance is exact to rounding and ties go to the lowest index
        (trimesh's k-d tree breaks them its own way).  Vertices that no
        face uses count, as in trimesh.
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError(f"points must be (n, 3); got shape {points.shape}")
        mesh = _mesh(self._source)
        if self._vertices is None or self._vertices[0] is not mesh:
            index = np.arange(len(mesh.vertices))
            self._vertices = (mesh, TriangleMesh(mesh.vertices, np.stack([index, index, index], axis=1)))
        r = self._vertices[1].closest_point(points)
        return np.array(r.distance), np.array(r.face)
