"""Writes ``pickles.pkl``: shapes, meshes, scenes, views and results pickled by the package.

The file is kept as written, so that ``tests/test_pickles.py`` checks that objects pickled by an
earlier version of the package still load (and answer as fresh ones do) after its modules move.
Its objects are built by :func:`objects`, which the test calls again to compare.  Run from the
repository's root: ``python tests/data/make_pickles.py``.
"""

import pathlib
import pickle
import sys

import numpy as np

QUERIES = np.array([[0.3, 0.2, 0.9], [2.0, -1.0, 0.5], [0.0, 0.0, 0.0], [0.5, 0.5, 0.5]])


def _mesh(proximity):
    # An octahedron: a closed solid, small enough to keep the file short.
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    f = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return proximity.TriangleMesh(v, f)


def objects(proximity):
    """The shapes and results of the file, built afresh: ``{name: object}``."""
    mesh = _mesh(proximity)
    pose = np.eye(4)
    pose[:3, 3] = [0.25, -0.5, 3.0]
    triangles = proximity.Triangle([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1], [1, 0, 2], [0, 2, 1]]])
    shapes = {
        "triangle": triangles,
        "segment": proximity.Segment([[0, 0, 0], [1, 2, 3]]),
        "point": proximity.Point([1.0, 2.0, 3.0]),
        "circle": proximity.Circle(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0),
        "disk": proximity.Disk(center=[0, 0, 1], normal=[0, 1, 1], radius=2.0),
        "sphere": proximity.Sphere([0.0, 0.0, 0.0], 0.5),
        "capsule": proximity.Capsule([[0, 0, 0], [0, 0, 2]], radius=0.25),
        "inflated": triangles.inflated(0.125),
        "mesh": mesh,
        "posed": mesh.transformed(pose),
        "scene": proximity.Scene([mesh, proximity.Sphere([4.0, 0.0, 0.0], 1.0), mesh.transformed(pose)]),
    }
    batched = ("triangle", "inflated")  # batches of two: the points broadcast against them
    results = {
        f"{name} result": shape.closest_point(QUERIES[:, None] if name in batched else QUERIES)
        for name, shape in shapes.items()
    }
    # A segment clear of the mesh: its answer is the same before and after the move.
    results["pair result"] = proximity.closest_points(proximity.Segment([[1.5, 0.5, 0.25], [2, 2, 3]]), mesh)
    return {**shapes, **results}


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2]))
    import proximity

    target = pathlib.Path(__file__).with_name("pickles.pkl")
    target.write_bytes(pickle.dumps(objects(proximity), protocol=4))
    print(f"wrote {target} ({target.stat().st_size} bytes)")
