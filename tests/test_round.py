"""Point-circle and point-disk queries against the exact reference."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proximity import Circle, Disk, Feature
from proximity.testing import exact
from tests import strategies
from tests.checks import BOUND, check_round

EPS = 2.0**-52
SHAPES = {"circle": Circle, "disk": Disk}


@pytest.mark.parametrize(
    "point, circle, disk",
    [
        # (point, (feature, closest, distance) for the circle, ... for the disk)
        ([3.0, 0.0, 0.0], (Feature.RIM, [1.0, 0.0, 0.0], 2.0), (Feature.RIM, [1.0, 0.0, 0.0], 2.0)),
        (
            [0.5, 0.0, 2.0],
            (Feature.RIM, [1.0, 0.0, 0.0], 2.0615528128088303),
            (Feature.FACE, [0.5, 0.0, 0.0], 2.0),
        ),
        (
            [0.0, 3.0, -4.0],
            (Feature.RIM, [0.0, 1.0, 0.0], 4.47213595499958),
            (Feature.RIM, [0.0, 1.0, 0.0], 4.47213595499958),
        ),
        ([0.0, 0.0, 0.0], (Feature.RIM, None, 1.0), (Feature.FACE, [0.0, 0.0, 0.0], 0.0)),
        ([0.0, 0.0, -3.0], (Feature.RIM, None, np.sqrt(10.0)), (Feature.FACE, [0.0, 0.0, 0.0], 3.0)),
        ([0.6, 0.8, 0.0], (Feature.RIM, [0.6, 0.8, 0.0], 0.0), (Feature.FACE, [0.6, 0.8, 0.0], 0.0)),
    ],
)
def test_known_cases(point, circle, disk):
    for kind, (feature, closest, distance) in (("circle", circle), ("disk", disk)):
        r = SHAPES[kind]([0, 0, 0], [0, 0, 5], 1.0).closest_point(point)
        assert r.feature == feature
        assert abs(r.distance - distance) <= 2 * EPS * distance
        if closest is not None:
            np.testing.assert_allclose(r.point, closest, rtol=0, atol=2 * EPS)
        if kind == "circle":
            assert r.equidistant == (closest is None)
        check_round(kind, [0, 0, 0], [0, 0, 5], 1.0, point, r)


def test_height_is_signed_along_the_given_normal():
    up = Disk([0, 0, 0], [0, 0, 3], 1.0).closest_point([[0, 0, 2], [0, 0, -2]])
    down = Disk([0, 0, 0], [0, 0, -1e-200], 1.0).closest_point([[0, 0, 2], [0, 0, -2]])
    np.testing.assert_array_equal(up.height, [2.0, -2.0])
    np.testing.assert_array_equal(down.height, [-2.0, 2.0])


def test_on_axis_point_is_a_fixed_rim_point():
    c = Circle([1.0, 2.0, 3.0], [0.3, -0.4, 1.2], 2.0)
    r = c.closest_point([[1.0, 2.0, 3.0], [1.3, 1.6, 4.2]])
    a, b = r[0], r[1]
    assert a.equidistant and b.equidistant
    # The same rim point for every point of the axis: a function of the
    # circle, not of rounding noise.
    np.testing.assert_allclose(a.point, b.point, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(a.point - c.center), 2.0, rtol=1e-15)


@pytest.mark.parametrize("kind", sorted(SHAPES))
@pytest.mark.parametrize("family", sorted(strategies.DISK_FAMILIES))
def test_robust_bound_on_every_family(family, kind):
    @settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(strategies.DISK_FAMILIES[family])
    def check(scene):
        r = SHAPES[kind](scene.center, scene.normal, scene.radius).closest_point(scene.points)
        for k in range(len(scene.points)):
            check_round(kind, scene.center[k], scene.normal[k], scene.radius[k], scene.points[k], r[k])

    check()


@pytest.mark.parametrize("kind", sorted(SHAPES))
@settings(max_examples=60, deadline=None)
@given(scene=strategies.disk_scenes(), motion=strategies.rigid_motions())
def test_rigid_motion(kind, scene, motion):
    cls = SHAPES[kind]
    d = cls(scene.center, scene.normal, scene.radius).distance(scene.points)
    center, points = motion.apply(scene.center), motion.apply(scene.points)
    normal = motion.rotate(scene.normal)
    if not (np.isfinite(center).all() and np.isfinite(points).all() and np.any(normal, axis=-1).all()):
        return  # the motion itself over- or underflowed: nothing to compare
    moved = cls(center, normal, scene.radius).distance(points)
    for k in range(len(points)):
        scale = float(exact.circle_scale(scene.center[k], scene.radius[k], scene.points[k]))
        # The rounded motion moves coordinates by a few eps of the largest, and
        # tilts the normal by a few eps, which moves the rim by that times R.
        size = (
            np.max(np.abs(scene.center[k]))
            + np.max(np.abs(scene.points[k]))
            + np.max(np.abs(motion.translation))
        )
        assert abs(moved[k] - d[k]) <= 2 * BOUND * EPS * scale + 16 * EPS * (size + scene.radius[k])


@pytest.mark.parametrize("kind", sorted(SHAPES))
@settings(max_examples=60, deadline=None)
@given(
    seed=strategies.SEEDS,
    rel=strategies.powers_of_ten(-16, -10),
    height=st.floats(-10.0, 10.0, allow_nan=False),
)
def test_near_the_axis_with_any_normal(kind, seed, rel, height):
    """Just off the axis of a tilted circle, where Q - C is mostly rounding."""
    rng = np.random.default_rng(seed)
    center, normal = rng.normal(size=3), rng.normal(size=3) * 10.0 ** rng.uniform(-3, 3)
    unit = normal / np.linalg.norm(normal)
    side = np.cross(unit, rng.normal(size=3))
    point = center + height * unit + rel * (abs(height) + 1.0) * side / np.linalg.norm(side)
    radius = float(rng.uniform(0.1, 3.0))
    r = SHAPES[kind](center, normal, radius).closest_point(point)
    check_round(kind, center, normal, radius, point, r)
