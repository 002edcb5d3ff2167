"""The hierarchical winding number: its bound holds, and every side it proves is exact.

The truth is the exact integer winding number of closed meshes (signed ray
crossings in rational arithmetic, :func:`proximity.testing.winding.winding_numbers`),
and, on open meshes, the sum over every face with its own rounding bound.
"""

import math

import numpy as np
import pytest

from proximity import TriangleMesh
from proximity.signs import crossings, winding
from proximity.testing import winding as exact_winding
from proximity.testing.meshes import box, box_points, defective, icosphere, near_points, torus


def _random_points(vertices, n, seed, margin=0.3):
    rng = np.random.default_rng(seed)
    return rng.uniform(vertices.min(axis=0) - margin, vertices.max(axis=0) + margin, (n, 3))


def test_the_legendre_gradient_bound_of_the_error_analysis():
    """``l^2 P_l^2 + (1 - t^2) P_l'^2 <= l (l + 1)`` on [-1, 1]: the gradient of a degree-l
    term is at most ``sqrt(l (l + 1))`` (the module's error bound rests on it)."""
    t = np.linspace(-1.0, 1.0, 20001)
    for degree in range(1, 12):
        p = np.polynomial.legendre.Legendre.basis(degree)
        value = degree**2 * p(t) ** 2 + (1 - t**2) * p.deriv()(t) ** 2
        assert value.max() <= degree * (degree + 1) * (1 + 1e-12)
        assert value.max() >= degree**2 * (1 - 1e-12)  # and it is not loose by more than (l + 1) / l


@pytest.mark.parametrize("seed", [0, 1])
def test_series_and_faces_stay_within_their_bounds_on_a_soup(seed):
    """A soup of triangles (no integer to snap to): the hierarchy's answer, stopped as
    soon as the side is proven, is within both bounds of every face summed exactly."""
    rng = np.random.default_rng(seed)
    n = 400
    v0 = rng.uniform(-1, 1, (n, 3))
    vertices = np.concatenate([v0, v0 + rng.normal(0, 0.2, (n, 3)), v0 + rng.normal(0, 0.2, (n, 3))])
    faces = np.arange(3 * n).reshape(3, n).T
    mesh = TriangleMesh(vertices, faces)
    points = np.concatenate([rng.uniform(-1.5, 1.5, (300, 3)), rng.uniform(-6, 6, (100, 3))])
    quick = mesh.winding_number(points)
    full = mesh.winding_number(points, full=True)
    assert (np.abs(quick.winding - full.winding) <= quick.error + full.error).all()
    assert (full.error < 1e-9).mean() > 0.95  # summed face by face, the rounding is small
    assert (quick.error > 10 * full.error).mean() > 0.5  # the series did the work
    sure = quick.certain & full.certain
    assert sure.mean() > 0.9 and (quick.inside == full.inside)[sure].all()


@pytest.mark.parametrize(
    "name", ["torus", "nested shells", "overlapping boxes", "pushed octahedron", "inverted", "internal sheet"]
)
def test_closed_meshes_get_their_exact_integer_winding_number(name):
    vertices, faces = torus(24, 12) if name == "torus" else defective()[name]
    mesh = TriangleMesh(vertices, faces)
    points = np.concatenate([_random_points(vertices, 600, 1), near_points(np.random.default_rng(2), vertices,
                                                                           faces, 200, 1e-6)])  # fmt: skip
    truth = exact_winding.winding_numbers(vertices, faces, points)
    r = mesh.winding_number(points)
    assert r.certain.all()
    assert (r.inside == (truth != 0)).all()
    assert (np.abs(r.winding - truth) <= r.error).all()
    # Where the bound leaves a single integer, it is given exactly.
    snapped = r.error == 0
    assert snapped.mean() > 0.8 and (r.winding[snapped] == truth[snapped]).all()
    assert len(np.unique(truth)) >= 2


def test_duplicated_faces_count_as_often_as_they_appear():
    vertices, faces = icosphere(2)
    twice = TriangleMesh(vertices, np.vstack([faces, faces]))
    r = twice.winding_number([[0.0, 0.0, 0.0], [0.0, 0.0, 0.9], [0.0, 0.0, 1.5]])
    assert r.inside.tolist() == [True, True, False] and r.certain.all()
    assert (np.abs(r.winding - [2, 2, 0]) <= r.error).all()
    np.testing.assert_allclose(twice.winding_number([0.0, 0.0, 0.0], full=True).winding, 2.0, atol=1e-12)


def test_zero_area_faces_contribute_exactly_nothing():
    """A collinear face alone: exactly 0 everywhere, even beside its line, where the
    solid-angle formula in floats gives half a turn."""
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [3.0, 3.0, 3.0], [0.0, 1.0, 0.0], [5, 0, 0]])
    mesh = TriangleMesh(vertices, [[0, 2, 1], [0, 2, 1], [0, 2, 1], [3, 4, 3], [0, 2, 1]])
    t = np.linspace(0.01, 0.99, 50)[:, None]
    points = t * vertices[2] + np.array([1e-14, -1e-14, 0.0])
    r = mesh.winding_number(points, full=True)
    assert (r.winding == 0).all() and (r.error == 0).all() and r.certain.all()


def test_zero_area_faces_on_a_closed_box_keep_points_near_them_exact():
    vertices, faces = defective()["zero-area face"]
    mesh = TriangleMesh(vertices, faces)
    rng = np.random.default_rng(3)
    # Off the split edge (x = y = -1), 1e-12 to 3e-9 away, all around it.
    z = rng.uniform(-1, 1, 400)
    height = np.exp(rng.uniform(np.log(1e-12), np.log(3e-9), 400))
    angle = rng.uniform(0, 2 * np.pi, 400)
    points = np.stack([-1 + height * np.cos(angle), -1 + height * np.sin(angle), z], axis=1)
    points = np.concatenate([points, [[-1.000000001914884, -1.0000000005772514, -0.23781466995926992]]])
    truth = exact_winding.winding_numbers(vertices, faces, points)
    r = mesh.winding_number(points)
    assert r.certain.all() and (r.inside == (truth != 0)).all() and 0 < truth.sum() < len(points)


def test_open_meshes_are_uncertain_only_near_one_half():
    vertices, faces = defective()["open"]
    mesh = TriangleMesh(vertices, faces)
    points = _random_points(vertices, 800, 4)
    r = mesh.winding_number(points)
    full = mesh.winding_number(points, full=True)
    assert (np.abs(r.winding - full.winding) <= r.error + full.error).all()
    assert (r.inside == full.inside)[r.certain].all()
    assert r.certain.mean() > 0.95
    # With one face missing, the winding number at a point of it is exactly 1/2.
    sphere_v, sphere_f = icosphere(2)
    hole = TriangleMesh(sphere_v, sphere_f[1:]).winding_number(sphere_v[sphere_f[0]].mean(axis=0))
    assert not hole.certain.any() and (np.abs(hole.winding - 0.5) <= hole.error).all()
    # A lone square: half a turn on it, and so 1e-300 above it.
    square = TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    assert not square.winding_number([[0.5, 0.5, 0.0], [0.25, 0.5, 1e-300]]).certain.any()


def test_points_on_the_surface_are_never_certain():
    vertices, faces = torus(24, 12)
    mesh = TriangleMesh(vertices, faces)
    assert not mesh.winding_number(vertices).certain.any()
    # Centroids and midpoints, rounded, are on the surface or within 1e-16 of it: where
    # the bound proves a side, it is the exact one (the reference raises on the surface).
    tri = vertices[faces]
    near = np.concatenate([tri[:100].mean(axis=1), (tri[:100, 0] + tri[:100, 1]) / 2])
    r = mesh.winding_number(near)
    assert 0 < r.certain.mean() < 1
    truth = exact_winding.winding_numbers(vertices, faces, near[r.certain])
    assert (r.inside[r.certain] == (truth != 0)).all()


def test_scaling_by_powers_of_two_and_far_points():
    vertices, faces = torus(16, 8)
    points = _random_points(vertices, 200, 5)
    expected = TriangleMesh(vertices, faces).winding_number(points)
    for k in (-900, -300, 300, 900):
        s = math.ldexp(1.0, k)
        r = TriangleMesh(vertices * s, faces).winding_number(points * s)
        np.testing.assert_array_equal(r.inside, expected.inside)
        assert r.certain.all()
    far = TriangleMesh(vertices, faces).winding_number([[1e300, 0, 0], [np.nan, 0, 0], [0, 0, np.inf]])
    assert far.winding[0] == 0 and far.certain[0] and np.isnan(far.winding[1:]).all()
    assert not far.certain[1:].any() and not far.inside[1:].any()


def test_results_are_frozen_and_shaped_like_the_points():
    mesh = TriangleMesh(*box([-1, -1, -1], [1, 1, 1]))
    r = mesh.winding_number(np.zeros((2, 3, 3)))
    assert r.winding.shape == r.error.shape == r.inside.shape == r.certain.shape == (2, 3)
    assert not r.winding.flags.writeable and r.inside.all()
    one = mesh.winding_number([0.0, 0.0, 0.0])
    assert np.ndim(one.winding) == 0 and one.winding == 1.0
    with pytest.raises(ValueError, match="points must have shape"):
        mesh.winding_number(np.zeros((3, 2)))
    with pytest.raises(TypeError, match="keyword-only"):
        mesh.winding_number([0, 0, 0], True)
    assert "WindingResult(" in repr(r)


def test_the_hierarchy_is_kept_but_not_pickled():
    import pickle

    mesh = TriangleMesh(*torus(16, 8))
    points = box_points(np.random.default_rng(6), mesh.vertices, 100)
    before = mesh.winding_number(points)
    assert mesh._winding is not None
    copy = pickle.loads(pickle.dumps(mesh))
    assert copy._winding is None
    np.testing.assert_array_equal(copy.winding_number(points).inside, before.inside)


def test_a_brute_force_mesh_gets_a_hierarchy_of_its_own():
    vertices, faces = torus(16, 8)
    brute = TriangleMesh(vertices, faces, broad_phase="brute")
    h = brute._hierarchy()
    assert len(h.child) > 1
    points = _random_points(vertices, 200, 7)
    expected = TriangleMesh(vertices, faces).winding_number(points).inside
    assert (brute.winding_number(points).inside == expected).all()
    assert winding.numbers(h, points[:0])[0].shape == (0,)


@pytest.mark.parametrize("name", ["overlapping boxes", "split seams", "internal sheet", "pushed octahedron"])
def test_crossings_are_exact_for_rays_through_edges_and_vertices(name):
    """Points on a grid of quarters, whose rays run along the boxes' faces and through their
    edges and vertices: every crossing count decided is the exact winding number, and the
    undecided points are on the surface."""
    vertices, faces = defective()[name]
    mesh = TriangleMesh(vertices, faces)
    h = mesh._hierarchy()
    grid = np.stack(np.meshgrid(*[np.arange(-1.25, 2.01, 0.25)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    w = crossings.crossings(h, grid)
    decided = ~np.isnan(w)
    truth = exact_winding.winding_numbers(vertices, faces, grid[decided])
    assert (w[decided] == truth).all()
    assert (mesh.distance(grid[~decided]) < 1e-15).all() and decided.mean() > 0.7
