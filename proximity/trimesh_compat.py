"""A drop-in for ``trimesh.proximity.closest_point``.

Replace ::

    closest, distance, triangle_id = trimesh.proximity.closest_point(mesh, points)

with ::

    from proximity.trimesh_compat import closest_point
    closest, distance, triangle_id = closest_point(mesh, points)

The arguments and the return are trimesh's; trimesh itself is not needed
(nor ``rtree`` and ``scipy``, which trimesh's version requires).
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
