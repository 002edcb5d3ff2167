"""Queries between two primitives through the public API: closest_points, distance, signed_distance.

The kernels themselves are checked in ``test_pair_kernels.py``; here the
public functions are held to the same contract against the exact
reference (``proximity.testing.exact``), single and batched, swapped
sides, points, rounded shapes, broadcasting and bad input.
"""

from fractions import Fraction

import mpmath
import numpy as np
import pytest

import proximity
from proximity import Feature
from proximity.numerics import certified
from proximity.results import asdict
from proximity.testing import exact, scenes
from tests.test_pair_kernels import SPECS, check_certified, check_robust

CLASSES = {2: proximity.Segment, 3: proximity.Triangle}


def _shapes(pair, scene):
    ka, kb = SPECS[pair].sizes
    return CLASSES[ka](scene.a), CLASSES[kb](scene.b)


def _row(pair, r, k=()):
    """The kernel's row of one pair of a result, as ``test_pair_kernels`` checks it."""
    ka, kb = SPECS[pair].sizes
    head = [r.distance[k], r.sqr_distance[k], *r.point_a[k], *r.point_b[k], r.feature_a[k], r.feature_b[k]]
    pa = [r.parameter_a[k]] if ka == 2 else list(r.barycentric_a[k])
    pb = [r.parameter_b[k]] if kb == 2 else list(r.barycentric_b[k])
    return np.array(head + pa + pb, dtype=np.float64)


FAMILIES = [
    pytest.param(pair, family, id=f"{pair}-{family.label}")
    for pair in SPECS
    for family in scenes.PAIR_FAMILIES[pair]
]


@pytest.mark.parametrize(("pair", "family"), FAMILIES)
def test_batches_and_single_pairs_keep_the_kernels_contract(pair, family):
    scene = family(np.random.default_rng(11), 5)
    a, b = _shapes(pair, scene)
    spec = SPECS[pair]
    robust = proximity.closest_points(a, b)
    cert = proximity.closest_points(a, b, method="certified")
    for k in range(len(scene.a)):
        ref = spec.reference(scene.a[k], scene.b[k])
        check_robust(spec, scene.a[k], scene.b[k], _row(pair, robust, k), ref)
        # Certified answers are final (the exact fallback ran where needed).
        check_certified(spec, scene.a[k], scene.b[k], np.r_[certified.CERTAIN, _row(pair, cert, k)], ref)
        # The single pair's fast path gives the batch's bits.
        single = proximity.closest_points(a[k], b[k])
        np.testing.assert_array_equal(_row(pair, single), _row(pair, robust, k))
        assert proximity.distance(a[k], b[k], method="certified") == cert.distance[k]


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_a_triangle_against_a_segment_is_the_segment_against_the_triangle(method):
    scene = scenes.pair_well_conditioned(np.random.default_rng(3), 40, "segment_triangle")
    seg, tri = proximity.Segment(scene.a), proximity.Triangle(scene.b)
    ab, ba = (
        proximity.closest_points(seg, tri, method=method),
        proximity.closest_points(tri, seg, method=method),
    )
    for name, value in asdict(ab.swapped()).items():
        np.testing.assert_array_equal(value, getattr(ba, name), err_msg=name)
    np.testing.assert_array_equal(ab.swapped().normal, ba.normal)
    one = proximity.closest_points(tri[0], seg[0], method=method)
    np.testing.assert_array_equal(one.point_a, ab.point_b[0])
    assert one.feature_b == ab.feature_a[0] and one.parameter_b == ab.parameter_a[0]


def test_touching_and_crossing_pairs_have_one_common_point():
    tri = proximity.Triangle([[0, 0, 0], [4, 0, 0], [0, 4, 0]])
    through = proximity.Segment([[1, 1, -1], [1, 1, 3]])
    other = proximity.Triangle([[1, 1, -1], [1, 1, 1], [5, 5, 1]])
    for a, b in ((through, tri), (tri, other), (tri, tri)):
        for method in ("robust", "certified"):
            r = proximity.closest_points(a, b, method=method)
            assert r.distance == 0.0 and (r.point_a == r.point_b).all()


def test_points_are_the_point_queries():
    rng = np.random.default_rng(5)
    tris = proximity.Triangle(rng.normal(size=(6, 3, 3)))
    points = proximity.Point(rng.normal(size=(6, 3)))
    r = proximity.closest_points(points, tris, method="certified")
    q = tris.closest_point(points.position, method="certified")
    np.testing.assert_array_equal(r.distance, q.distance)
    np.testing.assert_array_equal(r.point_b, q.point)
    np.testing.assert_array_equal(r.barycentric_b, q.barycentric)
    np.testing.assert_array_equal(r.point_a, points.position)
    assert (r.feature_a == Feature.VERTEX0).all()
    swapped = proximity.closest_points(tris, points, method="certified")
    np.testing.assert_array_equal(swapped.point_a, q.point)
    disk = proximity.Disk([0, 0, 0], [0, 0, 1], 1.0)
    assert proximity.distance(disk, proximity.Point([0.5, 0, 2])) == 2.0
    segs = proximity.Segment(rng.normal(size=(4, 2, 3)))
    r = proximity.closest_points(proximity.Point([0.0, 0.0, 0.0]), segs)
    np.testing.assert_array_equal(r.parameter_b, segs.closest_point([0.0, 0.0, 0.0]).parameter)


# -- rounded shapes -------------------------------------------------------------------


def _exact_minus(pair, a, b, radius):
    """The exact ``d* - radius`` of two segments or triangles (mpmath, high precision)."""
    ref = SPECS[pair].reference(a, b)
    with mpmath.workprec(exact.PREC):
        return ref.distance - exact.to_mpf(Fraction(radius))


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_capsules_are_their_segments_less_the_radii(method):
    rng = np.random.default_rng(8)
    segs_a, segs_b = rng.normal(size=(30, 2, 3)), rng.normal(size=(30, 2, 3))
    ra, rb = rng.uniform(0.0, 0.8, 30), rng.uniform(0.0, 0.8, 30)
    a, b = proximity.Capsule(segs_a, ra), proximity.Capsule(segs_b, rb)
    signed = proximity.signed_distance(a, b, method=method)
    r = proximity.closest_points(a, b, method=method)
    assert (signed < 0).any() and (signed > 0).any()
    for k in range(30):
        want = _exact_minus("segment_segment", segs_a[k], segs_b[k], Fraction(ra[k]) + Fraction(rb[k]))
        if method == "certified":
            assert exact.ulps(float(signed[k]), want) < 1.0
        else:
            scale = exact.pair_scale(segs_a[k], segs_b[k]) + Fraction(ra[k]) + Fraction(rb[k])
            assert exact.error_in_units(float(signed[k]), want, scale) <= 17
        assert r.distance[k] == max(signed[k], 0.0)
        # The witnesses lie on the capsules' surfaces, ``signed`` apart along the cores' direction.
        for p, segs, radius in ((r.point_a[k], segs_a, ra[k]), (r.point_b[k], segs_b, rb[k])):
            on = proximity.Segment(segs[k]).distance(p)
            assert abs(on - radius) <= 1e-14 * 8
        assert abs(np.linalg.norm(r.point_b[k] - r.point_a[k]) - abs(signed[k])) <= 1e-13


def test_rounded_triangles_and_spheres():
    ball = proximity.Sphere([0, 0, 2], 0.5)
    slab = proximity.Triangle([[-1, -1, 0], [3, -1, 0], [-1, 3, 0]]).inflated(0.25)
    assert proximity.signed_distance(ball, slab) == 1.25
    r = proximity.closest_points(ball, slab)
    np.testing.assert_allclose(r.point_a, [0, 0, 1.5])
    np.testing.assert_allclose(r.point_b, [0, 0, 0.25])
    deep = proximity.Sphere([0, 0, 0.5], 0.5)
    assert proximity.signed_distance(deep, slab) == -0.25
    assert proximity.distance(deep, slab) == 0.0


TET = proximity.TriangleMesh(
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
)


def _lifted(z):
    pose = np.eye(4)
    pose[2, 3] = z
    return pose


def _same_answers(query, got, want, others, shape=None):
    """``query`` of ``got`` and of ``want`` against each of ``others``, both ways: the same
    bits, of ``shape`` where given."""
    for other in others:
        for x, y in ((query(got, other), query(want, other)), (query(other, got), query(other, want))):
            x = asdict(x) if hasattr(x, "point_a") else {"distance": x}
            y = asdict(y) if hasattr(y, "point_a") else {"distance": y}
            for name, value in y.items():
                if shape is not None:
                    assert np.shape(x[name])[: len(shape)] == shape, name
                    value = np.reshape(value, np.shape(x[name]))
                np.testing.assert_array_equal(x[name], value, err_msg=name)


@pytest.mark.parametrize("query", [proximity.closest_points, proximity.distance, proximity.signed_distance])
def test_a_radius_of_one_element_is_that_radius_for_a_batch_of_one(query):
    # Each rounded shape with radius [r] against its form with radius r:
    # the same answers, of the batch shape (1,) the radius gives.
    instances = proximity.Scene([TET.transformed(_lifted(3.0)), TET])
    capsule = [[[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]]
    cases = [
        (proximity.Sphere(np.zeros((1, 3)), [0.5]), proximity.Sphere(np.zeros((1, 3)), 0.5)),
        (proximity.Capsule(capsule, [0.5]), proximity.Capsule(capsule, 0.5)),
        (TET.inflated([0.5]), TET.inflated(0.5)),
        (TET.transformed(_lifted(1.0)).inflated([0.5]), TET.transformed(_lifted(1.0)).inflated(0.5)),
        (proximity.Scene([TET, proximity.Segment(capsule)]).inflated([0.5]),
         proximity.Scene([TET, proximity.Segment(capsule)]).inflated(0.5)),
        (instances.inflated([0.5]), instances.inflated(0.5)),
    ]  # fmt: skip
    others = [proximity.Segment([[3.0, 0.0, 0.0], [3.0, 1.0, 2.0]]), proximity.Sphere([0.25, 0.25, 0.5], 0.1)]
    for one, scalar in cases:
        _same_answers(query, one, scalar, others, shape=(1,))


@pytest.mark.parametrize("query", [proximity.closest_points, proximity.signed_distance])
def test_rounding_between_poses_is_the_rounding_of_the_core_posed(query):
    # Rounding and posing commute: rounded by r1, posed, rounded by r2, posed
    # and rounded by r3 is the core rounded by (r1 + r2) + r3 (as rounding a
    # rounded shape adds the radii), then posed.  Quarter turns and integer
    # shifts compose exactly, so the two answer alike, bit for bit.
    quarter = np.array([[0.0, -1.0, 0.0, 2.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, -1.0], [0, 0, 0, 1]])
    shift = _lifted(3.0)
    cores = [
        TET,
        proximity.Scene([TET.transformed(shift), TET]),
        proximity.Segment([[[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]]),
    ]
    others = [proximity.Segment([[3.0, 0.0, 0.0], [3.0, 1.0, 2.0]]), TET.transformed(_lifted(-4.0))]
    for core in cores:
        nested = core.inflated(0.1).transformed(quarter).inflated(0.2).transformed(shift).inflated(0.3)
        flat = core.inflated(0.1).inflated(0.2).inflated(0.3).transformed(quarter).transformed(shift)
        assert flat.shape.radius == (0.1 + 0.2) + 0.3 != 0.1 + (0.2 + 0.3)  # the order shows
        _same_answers(query, nested, flat, others)


# -- broadcasting and bad input ---------------------------------------------------------


@pytest.mark.parametrize(
    ("batch_a", "batch_b", "out"),
    [((), (), ()), ((5,), (5,), (5,)), ((4,), (3, 1), (3, 4)), ((), (3,), (3,)), ((0,), (0,), (0,))],
)
@pytest.mark.parametrize(("ka", "kb"), [(2, 2), (2, 3), (3, 2), (3, 3), (1, 3)])
def test_broadcasting(batch_a, batch_b, out, ka, kb):
    rng = np.random.default_rng(2)
    make = {
        1: lambda s: proximity.Point(rng.normal(size=s + (3,))),
        2: proximity.Segment,
        3: proximity.Triangle,
    }
    a = make[ka](batch_a) if ka == 1 else make[ka](rng.normal(size=batch_a + (ka, 3)))
    b = make[kb](rng.normal(size=batch_b + (kb, 3)))
    r = proximity.closest_points(a, b)
    d = proximity.distance(a, b)
    assert np.shape(d) == out and np.shape(r.distance) == out and np.shape(r.point_a) == out + (3,)
    assert np.shape(r.barycentric_b) == out + (3,)
    ia = np.broadcast_to(np.arange(int(np.prod(batch_a, dtype=int))).reshape(batch_a), out)
    ib = np.broadcast_to(np.arange(int(np.prod(batch_b, dtype=int))).reshape(batch_b), out)
    for index in np.ndindex(*out):
        one_a = a[np.unravel_index(ia[index], batch_a)] if batch_a else a
        one_b = b[np.unravel_index(ib[index], batch_b)] if batch_b else b
        assert np.asarray(d)[index] == proximity.distance(one_a, one_b)
    if out == ():
        assert isinstance(r.distance, np.float64) and type(r.feature_a) is np.int8


def test_results_are_frozen():
    r = proximity.closest_points(
        proximity.Segment(np.zeros((3, 2, 3))), proximity.Segment(np.ones((3, 2, 3)))
    )
    with pytest.raises(ValueError):
        r.point_a[0, 0] = 1.0
    with pytest.raises(AttributeError):
        r.distance = 0


def test_bad_input_names_both_arguments():
    seg = proximity.Segment(np.zeros((3, 2, 3)))
    tri = proximity.Triangle(np.zeros((4, 3, 3)))
    with pytest.raises(ValueError, match=r"a \(3,\).*b \(4,\)"):
        proximity.closest_points(seg, tri)
    with pytest.raises(ValueError, match="a and b must live in the same dimension"):
        proximity.distance(proximity.Segment(np.zeros((2, 2))), proximity.Segment(np.zeros((2, 3))))
    with pytest.raises(NotImplementedError, match=r"disk \(a\) and a segment \(b\)"):
        proximity.closest_points(
            proximity.Disk([0, 0, 0], [0, 0, 1], 1.0), proximity.Segment(np.zeros((2, 3)))
        )
    with pytest.raises(NotImplementedError, match=r"triangle \(a\) and a circle \(b\)"):
        proximity.distance(tri[0], proximity.Circle([0, 0, 0], [0, 0, 1], 1.0))
    with pytest.raises(ValueError, match="method"):
        proximity.closest_points(seg, seg, method="eberly")
    with pytest.raises(ValueError, match="max_distance"):
        proximity.closest_points(seg, seg, max_distance=-1.0)
    with pytest.raises(ValueError, match="max_distance"):
        proximity.distance(seg, seg, max_distance=np.nan)
    with pytest.raises(TypeError, match="b must be a proximity shape"):
        proximity.closest_points(seg, "segment")
    with pytest.raises(TypeError, match="keyword-only"):
        proximity.closest_points(seg, seg, "robust")


def test_max_distance():
    a = proximity.Segment([[[0, 0, 0], [1, 0, 0]], [[0, 0, 0], [1, 0, 0]]])
    b = proximity.Segment([[[0, 0, 1], [1, 0, 1]], [[0, 0, 5], [1, 0, 5]]])
    r = proximity.closest_points(a, b, max_distance=2.0)
    assert r.distance.tolist() == [1.0, np.inf] and r.sqr_distance[1] == np.inf
    assert np.isnan(r.point_a[1]).all() and r.feature_a[1] == Feature.NONE
    full = proximity.closest_points(a, b)
    np.testing.assert_array_equal(r.point_a[0], full.point_a[0])
    assert proximity.distance(a, b, max_distance=2.0).tolist() == [1.0, np.inf]


def test_the_distance_of_points_to_a_shape_still_works():
    tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert proximity.distance(tri, [0.25, 0.25, 2.0]) == 2.0
    assert proximity.distance(tri, [[0.25, 0.25, 2.0]]).tolist() == [2.0]


@pytest.mark.parametrize("kinds", [(2, 2), (2, 3), (3, 2), (3, 3)])
def test_single_rounded_pairs_answer_with_the_batchs_bits(kinds):
    """One rounded segment or triangle against another (the fast path, resolved once per
    pair of types) answers with the bits of the same pair in a batch of two (the general
    path): distances, signed distances, witnesses on the surfaces, features, parameters
    and normals; radii 0 and positive, apart, overlapping and with crossing cores."""
    rng = np.random.default_rng(41)
    ka, kb = kinds
    for k in range(60):
        va, vb = rng.normal(size=(ka, 3)), rng.normal(size=(kb, 3)) + rng.uniform(0, 3, 3)
        ra, rb = (0.0 if k % 7 == 0 else rng.uniform(0.01, 1.5)), rng.uniform(0.0, 1.5)
        a = CLASSES[ka](va).inflated(ra)
        b = CLASSES[kb](vb).inflated(rb)
        batch_a = CLASSES[ka](np.stack([va, va])).inflated(ra)
        batch_b = CLASSES[kb](np.stack([vb, vb])).inflated(rb)
        one, both = proximity.closest_points(a, b), proximity.closest_points(batch_a, batch_b)
        for name, value in asdict(one).items():
            np.testing.assert_array_equal(value, getattr(both, name)[0], err_msg=name)
            assert type(value) is type(getattr(both[0], name)), name
        np.testing.assert_array_equal(one.normal, both.normal[0])
        assert proximity.distance(a, b) == both.distance[0]
        signed = proximity.signed_distance(a, b)
        assert signed == proximity.signed_distance(batch_a, batch_b)[0] and type(signed) is np.float64


def test_capsules_answer_a_single_pair_at_the_cost_of_their_kernel():
    """A pair of capsules takes the segments' fast path: no general-path step runs."""
    a = proximity.Capsule([[0, 0, 0], [1, 0, 0]], 0.1)
    b = proximity.Capsule([[0, 1, 0.5], [1, 2, 0.3]], 0.2)
    from proximity.pair import queries

    assert queries.fast_for(a, b, "robust") is not None
    r = proximity.closest_points(a, b)
    assert float(r.distance) == pytest.approx(float(r.sqr_distance) ** 0.5)
    assert np.linalg.norm(r.point_b - r.point_a) == pytest.approx(float(r.distance))
