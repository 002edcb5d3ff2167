"""Meshes of other libraries: their vertices and triangles, or an error that names the call to make.

:class:`proximity.TriangleMesh` takes a mesh object in place of its
``vertices`` and ``faces`` arrays.  The libraries name them differently:

==========================  ==============  =================================
library                     vertices        triangles
==========================  ==============  =================================
trimesh ``Trimesh``         ``vertices``    ``faces`` ``(F, 3)``
Open3D ``TriangleMesh``     ``vertices``    ``triangles`` (``Vector3iVector``)
meshio ``Mesh``             ``points``      ``cells_dict["triangle"]``
PyVista ``PolyData``        ``points``      ``faces``: flat, ``[3, i, j, k, 3, ...]``
==========================  ==============  =================================

Anything else with ``vertices`` or ``points`` and ``faces`` or
``triangles`` arrays works the same.  The arrays are read as they are
(``np.asarray``); nothing of the other library is imported.
"""

import numpy as np


def _first(obj, names):
    """``(name, value)`` of the first attribute among ``names`` that ``obj`` has, or ``(None, None)``."""
    for name in names:
        try:
            value = getattr(obj, name)
        except Exception:  # noqa: BLE001  (a property that fails is an attribute that is not there)
            continue
        if value is not None and not callable(value):
            return name, value
    return None, None


def _meshio_triangles(obj, kind):
    """The triangles of a meshio-like mesh (``cells_dict``), or a TypeError."""
    cells = obj.cells_dict
    if "triangle" in cells:
        return cells["triangle"]
    found = ", ".join(sorted(cells)) or "none"
    raise TypeError(
        f"TriangleMesh needs triangles; this {kind} has cells of the types {found}.  "
        "Triangulate it first (meshio cannot; trimesh, PyVista's triangulate() and Open3D can)"
    )


def _padded(faces, kind):
    """PyVista's flat face array ``[n, i, j, k, n, ...]`` as ``(F, 3)``, where every ``n`` is 3."""
    flat = np.asarray(faces)
    if flat.ndim != 1 or flat.size % 4 or (flat.size and np.any(flat[::4] != 3)):
        raise TypeError(
            f"TriangleMesh needs triangles; the faces of this {kind} are not all triangles.  "
            "Triangulate it first: TriangleMesh(mesh.triangulate())"
        )
    return flat.reshape(-1, 4)[:, 1:]


def vertices_and_faces(obj):
    """``(vertices, faces)`` of the mesh object ``obj``, as the library holds them.

    Raises
    ------
    TypeError
        Where ``obj`` holds no vertices and triangles, naming the call to make.
    """
    kind = type(obj).__name__
    vertices_name, vertices = _first(obj, ("vertices", "points"))
    if vertices is not None:
        if isinstance(getattr(obj, "cells_dict", None), dict):
            return vertices, _meshio_triangles(obj, kind)
        faces_name, faces = _first(obj, ("faces", "triangles"))
        if faces is not None:
            if vertices_name == "points" and faces_name == "faces" and np.ndim(faces) == 1:
                return vertices, _padded(faces, kind)
            return vertices, faces
    raise TypeError(
        "TriangleMesh takes vertices and faces arrays, or one mesh object with vertices and triangles "
        "(trimesh, Open3D, meshio, PyVista); "
        f"got a {kind} and no faces.  Call TriangleMesh(vertices, faces) with a (V, 3) array of "
        "coordinates and an (F, 3) array of vertex indices"
    )


def looks_like_a_mesh(obj):
    """Whether ``obj`` is a mesh of another library that :class:`proximity.TriangleMesh` would take."""
    try:
        vertices_and_faces(obj)
    except TypeError:
        return False
    return True
