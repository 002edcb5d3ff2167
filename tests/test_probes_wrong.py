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
