"""Both ends of the float range, for every shape and method, against the exact reference.

``robust`` promises ``|d - d*| <= 8 eps S + 2^-1075`` for every finite input:
the absolute term is the rounding of a distance that is subnormal (half the
subnormal spacing), which no multiple of ``eps S`` expresses once ``eps S``
is below the smallest subnormal.  ``certified`` is within one ulp of ``d*``.
"""

import mpmath
import numpy as np
import pytest

import proximity
from proximity.testing import exact
from proximity.testing.meshes import torus

HALF_SUBNORMAL = mpmath.mpf(2) ** -1075
METHODS = ("robust", "certified")


def _families():
    """``(name, scale of coordinates, scale of the point's offset)`` at both ends of the range."""
    return [
        ("far: the point 2^1023 and more from the shape", 1.0, 2.0**1023),
        ("huge: shape and point near the largest floats", 2.0**1020, 2.0**1022),
        ("subnormal: every coordinate below 2^-1022", 2.0**-1060, 2.0**-1060),
        ("tiny offsets of subnormal size from a normal shape", 2.0**-1000, 2.0**-1070),
    ]


def _check(method, d, d_exact, scale, where=""):
    if method == "robust":
        with mpmath.workprec(exact.PREC):
            error = abs(exact.to_mpf(float(d)) - exact.to_mpf(d_exact))
            limit = 8 * exact.to_mpf(exact.EPS) * exact.to_mpf(scale) + HALF_SUBNORMAL
            assert error <= limit, f"{where}: error {mpmath.nstr(error, 5)} > {mpmath.nstr(limit, 5)}"
    else:
        assert exact.ulps(float(d), d_exact) < 1.0, where


@pytest.mark.parametrize("method", METHODS)
def test_triangles_disks_and_circles_at_both_ends(method):
    rng = np.random.default_rng(5)
    for name, size, offset in _families():
        for _ in range(12):
            vertices = rng.uniform(-1, 1, (3, 3)) * size
            center, normal = rng.uniform(-1, 1, 3) * size, rng.normal(size=3)
            radius = abs(rng.uniform(0.1, 1)) * size
            # One coordinate of the offset from 1 to 1.9 times ``offset``, either
            # sign, the others up to ``offset`` / 4: the exact distance stays
            # below the largest float, whose rounding would be inf.
            offsets = rng.uniform(-0.25, 0.25, 3) * offset
            offsets[rng.integers(3)] = rng.uniform(1, 1.9) * offset * rng.choice([-1.0, 1.0])
            point = offsets + (vertices[0] if rng.random() < 0.5 else 0.0)
            if not np.isfinite(point).all():
                continue
            tri = proximity.Triangle(vertices)
            for d in (tri.distance(point, method=method), tri.distance(point[None], method=method)[0]):
                _check(
                    method, d, exact.triangle_distance(vertices, point), exact.triangle_scale(vertices, point)
                )
            for cls, reference in (
                (proximity.Disk, exact.disk_distance),
                (proximity.Circle, exact.circle_distance),
            ):
                shape = cls(center, normal, radius)
                d_exact = reference(center, normal, radius, point)
                scale = exact.circle_scale(center, radius, point)
                for d in (
                    shape.distance(point, method=method),
                    shape.distance(point[None], method=method)[0],
                ):
                    _check(method, d, d_exact, scale, f"{cls.__name__}, {name}")


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("size", [4e307, 2.0**-1060])
def test_meshes_and_scenes_answer_as_their_nearest_primitive_at_both_ends(method, size):
    """Same bits as the per-shape query of the nearest face, and the lowest index on ties."""
    rng = np.random.default_rng(6)
    vertices = rng.normal(size=(40, 3)) * size
    faces = rng.integers(0, 40, (60, 3))
    points = np.clip(rng.normal(size=(100, 3)) * 2, -4, 4) * size
    mesh = proximity.TriangleMesh(vertices, faces)
    per_face = proximity.Triangle(vertices[faces]).distance(points[:, None], method=method)
    result = mesh.closest_point(points, method=method)
    assert not np.isnan(result.distance).any()
    np.testing.assert_array_equal(result.distance, per_face.min(axis=1))
    np.testing.assert_array_equal(result.face, per_face.argmin(axis=1))
    disks = proximity.Disk(
        rng.normal(size=(5, 3)) * size, rng.normal(size=(5, 3)), rng.uniform(0.1, 1, 5) * size
    )
    scene = proximity.Scene([mesh, disks])
    per_disk = disks.distance(points[:, None], method=method)
    both = np.concatenate([per_face, per_disk], axis=1)
    np.testing.assert_array_equal(scene.distance(points, method=method), both.min(axis=1))
    np.testing.assert_array_equal(scene.closest_point(points, method=method).primitive, both.argmin(axis=1))


def test_a_point_2_to_the_1023_away_through_a_mesh_picks_the_nearer_face():
    """The exact distance to face A is 1e307 and to face B 2e307."""
    a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    b = [[-1e307, 0.0, 0.0], [-1e307, 1.0, 0.0], [-1e307, 0.0, 1.0]]
    mesh = proximity.TriangleMesh(np.array(a + b), [[0, 1, 2], [3, 4, 5]])
    point = [1.7e308, 0.0, 0.0]
    for method in ("robust", "certified"):
        r = mesh.closest_point([point], method=method)
        assert r.face.tolist() == [0]
        _check(method, r.distance[0], exact.triangle_distance(a, point), exact.triangle_scale(a, point))


def test_identical_faces_are_stored_once_and_the_lowest_index_wins():
    vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    faces = np.concatenate([np.tile([0, 1, 2], (50_000, 1)), [[0, 1, 3]], np.tile([0, 1, 2], (50_000, 1))])
    mesh = proximity.TriangleMesh(vertices, faces)
    assert len(mesh._tree.kinds) == 2  # one copy of each distinct face
    r = mesh.closest_point([[0.2, 0.2, -1.0], [0.2, -1.0, 0.5]])
    assert r.face.tolist() == [0, 50_000]


@pytest.mark.parametrize("closed", [True, False])
def test_a_mesh_of_subnormal_extent_signs_as_the_mesh_scaled_up(closed):
    # Integer coordinates times 2^-1074 and times 2^-20: each mesh is the
    # other scaled by 2^1054, exactly, as are the points.  The signs work in
    # a frame scaled to the mesh's extent, the same for both: the sides and
    # validity are the same, the winding numbers within their bounds of each
    # other (the same integers on the closed mesh; the hierarchies, built on
    # the coordinates as given, differ); the distances, the tiny mesh's
    # rounded at the subnormal spacing, are the same scaled, within that
    # rounding and the robust bound.
    vertices, faces = torus(12, 6)
    if not closed:
        faces = faces[: len(faces) - 6]
    ints = np.round(vertices * 2.0**20)
    points = np.round(np.random.default_rng(4).uniform(-1.5, 1.5, (300, 3)) * 2.0**20)
    tiny = proximity.TriangleMesh(np.ldexp(ints, -1074), faces)
    big = proximity.TriangleMesh(np.ldexp(ints, -20), faces)
    assert np.ptp(tiny.vertices) < 2.0**-1022
    p_tiny, p_big = np.ldexp(points, -1074), np.ldexp(points, -20)
    assert tiny.validity == big.validity
    w, v = tiny.winding_number(p_tiny), big.winding_number(p_big)
    np.testing.assert_array_equal(w.inside, v.inside)
    np.testing.assert_array_equal(w.certain, v.certain)
    assert (np.abs(w.winding - v.winding) <= w.error + v.error).all()
    if closed:
        np.testing.assert_array_equal(w.winding, v.winding)
    sign = "auto" if closed else "winding"
    a, b = tiny.signed(p_tiny, sign=sign), big.signed(p_big, sign=sign)
    np.testing.assert_array_equal(a.contains, b.contains)
    np.testing.assert_array_equal(a.certain, b.certain)
    np.testing.assert_array_equal(tiny.contains(p_tiny, sign=sign), b.contains)
    scaled = np.ldexp(tiny.signed_distance(p_tiny, sign=sign), 1054)
    limit = 2.0 ** (1054 - 1075) + 16 * 2.0**-52 * 4.0
    assert np.abs(scaled - big.signed_distance(p_big, sign=sign)).max() <= limit
