"""Meshes of other libraries in TriangleMesh, and the hints for what it cannot take."""

import numpy as np
import pytest

import proximity
from proximity import TriangleMesh

# A tetrahedron, and points whose distances to it are known exactly.
VERTICES = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
POINTS = [[-1.0, 0.2, 0.3], [0.2, 0.3, -2.0], [0.25, 0.25, 0.25]]


class _Vector:
    """Open3D's Vector3dVector / Vector3iVector: not arrays, but read by np.asarray."""

    def __init__(self, rows, dtype):
        self._rows = [list(r) for r in rows]
        self._dtype = dtype

    def __len__(self):
        return len(self._rows)

    def __array__(self, dtype=None, copy=None):
        return np.array(self._rows, dtype=dtype or self._dtype)


class Open3DLike:
    """As open3d.geometry.TriangleMesh: vertices and triangles, no faces."""

    def __init__(self, vertices, triangles):
        self.vertices = _Vector(vertices, np.float64)
        self.triangles = _Vector(triangles, np.int32)

    def compute_vertex_normals(self):  # a method, not data
        return self


class CellBlock:
    def __init__(self, type, data):
        self.type, self.data = type, np.asarray(data)


class MeshioLike:
    """As meshio.Mesh: points, and cells by type."""

    def __init__(self, points, cells):
        self.points = np.asarray(points)
        self.cells = [CellBlock(t, d) for t, d in cells]

    @property
    def cells_dict(self):
        return {c.type: c.data for c in self.cells}


class PyVistaLike:
    """As pyvista.PolyData: points, and faces as one flat array [n, i, j, k, n, ...]."""

    def __init__(self, points, faces):
        self.points = np.asarray(points)
        self.faces = np.concatenate([[len(f), *f] for f in faces]).astype(np.int64)


def _expected():
    return TriangleMesh(VERTICES, FACES).distance(POINTS)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Open3DLike(VERTICES, FACES),
        lambda: MeshioLike(VERTICES, [("vertex", [[0], [1]]), ("triangle", FACES)]),
        lambda: PyVistaLike(VERTICES, FACES),
    ],
    ids=["open3d", "meshio", "pyvista"],
)
def test_other_libraries_meshes_are_taken(make):
    mesh = TriangleMesh(make())
    np.testing.assert_array_equal(mesh.faces, FACES)
    np.testing.assert_array_equal(mesh.vertices, VERTICES)
    np.testing.assert_array_equal(mesh.distance(POINTS), _expected())


def test_a_trimesh_is_taken():
    trimesh = pytest.importorskip("trimesh")
    tm = trimesh.Trimesh(VERTICES, FACES, process=False)
    np.testing.assert_array_equal(TriangleMesh(tm).distance(POINTS), _expected())


@pytest.mark.parametrize(
    "obj, message",
    [
        (MeshioLike(VERTICES, [("tetra", [[0, 1, 2, 3]])]), r"cells of the types tetra.*Triangulate it"),
        (PyVistaLike(VERTICES, [[0, 1, 2, 3]]), r"not all triangles.*mesh\.triangulate\(\)"),
        (VERTICES, r"got a ndarray and no faces.*TriangleMesh\(vertices, faces\)"),
        (object(), r"got a object and no faces"),
    ],
    ids=["meshio-tetra", "pyvista-quads", "array-alone", "object"],
)
def test_what_cannot_be_taken_says_what_to_call(obj, message):
    with pytest.raises(TypeError, match=message):
        TriangleMesh(obj)


def test_faces_read_as_floats_are_taken_when_whole():
    faces = np.loadtxt(["0 2 1", "0 1 3", "0 3 2", "1 2 3"])
    assert faces.dtype == np.float64
    mesh = TriangleMesh(VERTICES, faces)
    assert mesh.faces.dtype == np.int64
    np.testing.assert_array_equal(mesh.faces, FACES)
    with pytest.raises(ValueError, match=r"faces must be integers.*got nan at index \(0, 0\) of a float64"):
        TriangleMesh(VERTICES, [[np.nan, 1, 2]])


@pytest.mark.parametrize("function", [proximity.distance, proximity.closest_point])
def test_a_foreign_mesh_in_a_query_names_triangle_mesh(function):
    with pytest.raises(TypeError, match=r"use proximity\.TriangleMesh\(mesh\) first"):
        function(Open3DLike(VERTICES, FACES), POINTS)
    with pytest.raises(TypeError, match="must be a proximity shape") as error:
        function(VERTICES, POINTS)
    assert "TriangleMesh(mesh)" not in str(error.value)


def test_a_misspelled_method_gets_a_suggestion():
    tri = proximity.Triangle(VERTICES[:3])
    with pytest.raises(ValueError, match=r"got 'Robust'; did you mean 'robust'\?$"):
        tri.distance(POINTS, method="Robust")
    with pytest.raises(ValueError, match=r"got 'certifed'; did you mean 'certified'\?$"):
        TriangleMesh(VERTICES, FACES).distance(POINTS, method="certifed")
    with pytest.raises(ValueError, match=r"got 'fast'$"):
        tri.distance(POINTS, method="fast")
