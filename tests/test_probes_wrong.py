"""Wrong answers found by probing: each a short reproducer of the case that was wrong."""

import numpy as np
import pytest

import proximity
from proximity.testing import meshes

METHODS = ["robust", "certified"]
SPHERE = meshes.icosphere(2)  # 320 faces


@pytest.mark.parametrize("method", METHODS)
def test_rounded_meshes_whose_cores_cross_are_as_deep_as_their_radii(method):
    # A certain crossing of the cores ended the search with d - r = 0, the
    # radii forgotten: 0.0 for every order, inflated side and method.
    a = proximity.TriangleMesh(*SPHERE)
    b = proximity.TriangleMesh(SPHERE[0] + [0.5, 0.3, 0.1], SPHERE[1])
    assert proximity.distance(a, b, method=method) == 0.0
    moved = np.eye(4)
    moved[:3, 3] = [0.5, 0.3, 0.1]
    for x, y, depth in [
        (a.inflated(0.1), b, -0.1),
        (b, a.inflated(0.1), -0.1),
        (a.inflated(0.1), b.inflated(0.2), -(0.1 + 0.2)),
        (a.inflated(0.25), a.transformed(moved), -0.25),
        (a.transformed(moved), a.inflated(0.25), -0.25),
        (proximity.Capsule([[0.0, 0.0, 0.5], [0.0, 0.0, 1.5]], 0.125), a, -0.125),
        (a, proximity.Capsule([[0.0, 0.0, 0.5], [0.0, 0.0, 1.5]], 0.125), -0.125),
    ]:
        assert proximity.signed_distance(x, y, method=method) == depth
        r = proximity.closest_points(x, y, method=method)
        assert r.distance == 0.0
    # A sphere whose centre lies on the surface: its depth is its radius, to the centre's rounding.
    centre = SPHERE[0][0]
    for x, y in ((proximity.Sphere(centre, 0.125), a), (a, proximity.Sphere(centre, 0.125))):
        assert abs(proximity.signed_distance(x, y, method=method) + 0.125) <= 1e-15


@pytest.mark.parametrize("method", METHODS)
def test_separated_rounded_meshes_keep_their_answers(method):
    a = proximity.TriangleMesh(*SPHERE)
    b = proximity.TriangleMesh(SPHERE[0] + [2.5, 0.0, 0.0], SPHERE[1])
    d = proximity.distance(a, b, method=method)
    assert 0.4 < d < 0.6
    assert proximity.signed_distance(a.inflated(0.125), b, method=method) == d - 0.125
    assert proximity.signed_distance(a, b.inflated(0.125), method=method) == d - 0.125


def _overlapping_boxes():
    """Two boxes as one closed manifold mesh that intersects itself: not a solid."""
    first = meshes.box([0, 0, 0], [2, 2, 2])
    second = meshes.box([1, 0.5, 0.5], [3, 1.5, 1.5])
    return proximity.TriangleMesh(np.vstack([first[0], second[0]]), np.vstack([first[1], second[1] + 8]))


@pytest.mark.parametrize("before", [[], ["auto"], ["pseudonormal"], ["auto", "pseudonormal"]])
def test_pseudonormal_signs_of_a_mesh_that_is_not_a_solid_warn_and_are_not_certain_at_every_call(before):
    # The warning was once per mesh, spent by whichever call came first, and
    # the pseudonormal's sides were certain: (2.1, 1, 1), inside the second
    # box by the winding number, was outside, certain, without a warning.
    import warnings

    mesh = _overlapping_boxes()
    assert not mesh.validity.solid
    points = [[2.1, 1.0, 1.0], [1.9, 1.9, 1.9]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for sign in before:
            mesh.signed(points, sign=sign)
    with pytest.warns(RuntimeWarning, match="pseudonormal signs can be wrong") as caught:
        r = mesh.signed(points, sign="pseudonormal")
    assert len(caught) == 1
    assert not r.certain.any()
    truth = mesh.signed(points, sign="winding")
    assert truth.certain.all() and truth.contains.tolist() == [True, True]
    for call in (
        lambda: mesh.signed_distance(points, sign="pseudonormal"),
        lambda: mesh.contains(points, sign="pseudonormal"),
        lambda: mesh.sdf_grid([0, 0, 0], [3, 2, 2], (9, 9, 9), sign="pseudonormal"),
    ):
        with pytest.warns(RuntimeWarning, match="pseudonormal signs can be wrong") as caught:
            call()
        assert len(caught) == 1


def test_pseudonormal_signs_of_a_solid_stay_certain_and_silent():
    import warnings

    mesh = proximity.TriangleMesh(*meshes.box([0, 0, 0], [2, 2, 2]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = mesh.signed([[1.0, 1.0, 1.9], [1.0, 1.0, 2.1]], sign="pseudonormal")
    assert r.certain.tolist() == [True, True] and r.contains.tolist() == [True, False]
