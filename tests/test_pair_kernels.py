"""The pair kernels (segment-segment, ...) against the exact reference.

No facade exists for pairs yet, so the compiled scalar functions are called
through small ``numba.njit`` batch loops.  For every pair of shapes:

* ``robust`` is within ``16 eps S + 2^-1075`` of the exact distance ``d*``
  (``S`` the largest coordinate difference between the shapes' vertices),
  its witness points lie within that bound of their shapes and are ``d``
  apart within it (plus the rounding of their own coordinates), its feature
  pair holds points within the bound of ``d*``, and a zero distance has one
  point as both witnesses;
* ``certified``, wherever it answers CERTAIN, is within one ulp of ``d*``
  with the exact lowest feature pair, and exactly 0 with one common point
  where the shapes touch;
* the exact fallback (``proximity.numerics.exact``) always is, with the reference's
  witnesses correctly rounded.

on seeded scenes of every pair family of ``proximity/testing/scenes.py``, on
hypothesis-drawn ones, on one hand-made case per feature pair, and at both
ends of the float range.
"""

from fractions import Fraction

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from numba import literal_unroll, njit

from proximity.numerics import certified
from proximity.numerics import exact as _exact
from proximity.pair import segment_segment, segment_triangle, triangle_triangle
from proximity.runtime.jit import specialize
from proximity.testing import exact, scenes
from proximity.testing.exact import Feature
from proximity.testing.exact import _core as exact_core
from tests import strategies

BOUND = 16
"""The robust pair bound, in units of ``eps * S``."""

HALF_SUBNORMAL = mpmath.mpf(2) ** -1075
V0, V1, V2, E01, E12, E20, FACE = (Feature(code) for code in range(7))


# -- compiled batch loops ------------------------------------------------------


@njit
def _store(out, i, row):
    _store_at(out, i, 0, row)


@njit
def _store_at(out, i, k, row):
    for value in literal_unroll(row):
        out[i, k] = value
        k += 1


@njit
def _seg(p):
    return p[0, 0], p[0, 1], p[0, 2], p[1, 0], p[1, 1], p[1, 2]


@njit
def _tri(p):
    return p[0, 0], p[0, 1], p[0, 2], p[1, 0], p[1, 1], p[1, 2], p[2, 0], p[2, 1], p[2, 2]


# The batch loops: robust rows with, after a flag, robust_unscaled's; certified rows.


def _ss_robust(a, b):
    out = np.empty((a.shape[0], 25))
    for i in range(a.shape[0]):
        args = (*_seg(a[i]), *_seg(b[i]))
        _store(out, i, segment_segment.robust(*args))
        _store_at(out, i, 12, segment_segment.robust_unscaled(*args))
    return out


def _ss_certified(a, b):
    out = np.empty((a.shape[0], 13))
    for i in range(a.shape[0]):
        _store(out, i, segment_segment.certified(*_seg(a[i]), *_seg(b[i])))
    return out


def _st_robust(a, b):
    out = np.empty((a.shape[0], 29))
    for i in range(a.shape[0]):
        args = (*_seg(a[i]), *_tri(b[i]))
        _store(out, i, segment_triangle.robust(*args))
        _store_at(out, i, 14, segment_triangle.robust_unscaled(*args))
    return out


def _st_certified(a, b):
    out = np.empty((a.shape[0], 15))
    for i in range(a.shape[0]):
        _store(out, i, segment_triangle.certified(*_seg(a[i]), *_tri(b[i])))
    return out


def _tt_robust(a, b):
    out = np.empty((a.shape[0], 33))
    for i in range(a.shape[0]):
        args = (*_tri(a[i]), *_tri(b[i]))
        _store(out, i, triangle_triangle.robust(*args))
        _store_at(out, i, 16, triangle_triangle.robust_unscaled(*args))
    return out


def _tt_certified(a, b):
    out = np.empty((a.shape[0], 17))
    for i in range(a.shape[0]):
        _store(out, i, triangle_triangle.certified(*_tri(a[i]), *_tri(b[i])))
    return out


# Cached on disk like the library's kernels (the name carries a stamp of
# proximity's sources, so an edit compiles them again): compiling the pair
# kernels costs more than all the checks of a warm run.
_ss_robust, _ss_certified, _st_robust, _st_certified, _tt_robust, _tt_certified = (
    specialize(loop, "pair-kernels-test")
    for loop in (_ss_robust, _ss_certified, _st_robust, _st_certified, _tt_robust, _tt_certified)
)


class Spec:
    """What the checks need to know of one pair of shapes."""

    def __init__(self, robust, certified_, fallback, reference, sizes):
        self.robust, self.certified, self.fallback, self.reference = robust, certified_, fallback, reference
        self.sizes = sizes

    def params(self, ref):
        """The exact parameters of a reference answer, as the kernels' rows hold them:
        ``s`` for a segment, the barycentric weights for a triangle."""
        out = []
        for weights in (ref.weights_a, ref.weights_b):
            out += [weights[1]] if len(weights) == 2 else list(weights)
        return out

    def weights(self, params):
        """Barycentric weights of each witness over its shape's vertices, from the row's parameters."""
        ka, _ = self.sizes
        if ka == 2:
            wa, rest = (1.0 - params[0], params[0]), params[1:]
        else:
            wa, rest = tuple(params[:3]), params[3:]
        wb = (1.0 - rest[0], rest[0]) if len(rest) == 1 else tuple(rest)
        return wa, wb


SPECS = {
    "segment_segment": Spec(
        _ss_robust, _ss_certified, _exact.segment_segment, exact.segment_segment_closest, (2, 2)
    ),
    "segment_triangle": Spec(
        _st_robust, _st_certified, _exact.segment_triangle, exact.segment_triangle_closest, (2, 3)
    ),
    "triangle_triangle": Spec(
        _tt_robust, _tt_certified, _exact.triangle_triangle, exact.triangle_triangle_closest, (3, 3)
    ),
}


def _batch(kernel, a, b):
    return kernel(np.ascontiguousarray(a, dtype=np.float64), np.ascontiguousarray(b, dtype=np.float64))


def robust_rows(spec, a, b):
    """The robust rows of a batch, after checking that ``robust_unscaled``
    (the SIMD pass of a batch loop) gives the same bits wherever it claims
    its inputs were in the safe window."""
    both = _batch(spec.robust, a, b)
    width = (both.shape[1] - 1) // 2
    robust, in_window, fast = both[:, :width], both[:, width] != 0.0, both[:, width + 1 :]
    np.testing.assert_array_equal(fast[in_window], robust[in_window])
    return robust


# -- checks ----------------------------------------------------------------------


def _mpf(x):
    return exact.to_mpf(Fraction(float(x)))


def _slack(point):
    """Rounding allowed for a witness stored as floats, as a distance: half an
    ulp per coordinate, at least half the subnormal spacing."""
    return exact.to_mpf(exact.EPS) * _mpf(np.max(np.abs(point))) + 2 * HALF_SUBNORMAL


def _norm(u, v):
    sqr = sum((Fraction(float(x)) - Fraction(float(y))) ** 2 for x, y in zip(u, v, strict=True))
    with mpmath.workprec(exact.PREC):
        return mpmath.sqrt(exact.to_mpf(sqr))


def _to_shape(vertices, point):
    """Exact distance from a point to a segment or triangle."""
    v = np.asarray(vertices)
    return exact.triangle_distance(v if len(v) == 3 else v[[0, 1, 1]], point)


def _within(value, limit, what):
    with mpmath.workprec(exact.PREC):
        assert value <= limit, f"{what}: {mpmath.nstr(value, 6)} > allowed {mpmath.nstr(limit, 6)}"


def _unpack(row):
    """``(distance, sqr, pa, pb, fa, fb, params)`` of a robust row."""
    return row[0], row[1], row[2:5], row[5:8], Feature(int(row[8])), Feature(int(row[9])), row[10:]


def check_robust(spec, a, b, row, ref=None):
    """Assert the robust contract for one pair; return the error in units of eps S."""
    ref = spec.reference(a, b) if ref is None else ref
    scale = exact.pair_scale(a, b)
    context = f"a={np.asarray(a).tolist()!r}, b={np.asarray(b).tolist()!r}"
    d, _, pa, pb, fa, fb, params = _unpack(row)
    error = exact.error_in_units(float(d), ref.distance, scale)
    with mpmath.workprec(exact.PREC):
        unit = exact.to_mpf(exact.EPS) * exact.to_mpf(scale)
        allowed = BOUND * unit + HALF_SUBNORMAL
        _within(abs(_mpf(d) - ref.distance), allowed, f"distance error ({error:.3g} eps S), {context}")
        _within(_to_shape(a, pa), allowed + _slack(pa), f"witness a off its shape, {context}")
        _within(_to_shape(b, pb), allowed + _slack(pb), f"witness b off its shape, {context}")
        _within(
            abs(_norm(pa, pb) - _mpf(d)),
            allowed + _slack(pa) + _slack(pb),
            f"|pa - pb| != distance, {context}",
        )
        # The feature pair must hold points within the bound of the minimum.
        closed = mpmath.sqrt(exact.to_mpf(ref.feature_sqr_distances[fa, fb]))
        _within(closed - ref.distance, allowed, f"features {fa!r}, {fb!r} (exact {ref.features}), {context}")
    if d == 0.0:
        assert (pa == pb).all(), f"zero distance with distinct witnesses {pa}, {pb}, {context}"
    for weights, feature, vertices, point in zip(
        spec.weights(params), (fa, fb), (a, b), (pa, pb), strict=True
    ):
        w = np.asarray(weights)
        assert (w >= 0).all() and abs(w.sum() - 1.0) <= 4e-16, f"weights {w} for {context}"
        support = {i for i, x in enumerate(w) if x != 0.0}
        assert support == set(exact_core._SUPPORT[feature]) or feature == FACE and support <= {0, 1, 2}, (
            f"weights {w} do not match feature {feature!r}, {context}"
        )
        if feature <= V2:
            assert (point == np.asarray(vertices)[int(feature)]).all(), f"vertex witness not exact, {context}"
        if len(w) == 2:
            # The point at the parameter s = w[1], exactly: 1 - s in float would
            # lose the digits of a segment far from the origin.
            p0, p1 = ([Fraction(float(x)) for x in v] for v in np.asarray(vertices))
            s = Fraction(float(w[1]))
            along = [x + s * (y - x) for x, y in zip(p0, p1, strict=True)]
            _within(_norm(along, point), allowed + _slack(point), f"parameter off its witness, {context}")
    return error


def check_certified(spec, a, b, row, ref=None):
    """Assert the certified contract where the row is CERTAIN; return whether it was."""
    if row[0] != certified.CERTAIN:
        assert row[0] == certified.EXACT
        return False
    ref = spec.reference(a, b) if ref is None else ref
    context = f"a={np.asarray(a).tolist()!r}, b={np.asarray(b).tolist()!r}"
    d, _, pa, pb, fa, fb, _ = _unpack(row[1:])
    assert exact.ulps(float(d), ref.distance) < 1.0, f"{d!r} vs {float(ref.distance)!r}, {context}"
    assert (fa, fb) == (ref.feature_a, ref.feature_b), f"{fa!r}, {fb!r} vs exact {ref.features}, {context}"
    if ref.sqr_distance == 0:
        assert d == 0.0 and (pa == pb).all(), context
    check_robust(spec, a, b, row[1:], ref)
    return True


def check_fallback(spec, a, b, ref=None):
    """Assert the exact fallback's answer: faithful, the lowest features, correctly rounded witnesses."""
    ref = spec.reference(a, b) if ref is None else ref
    context = f"a={np.asarray(a).tolist()!r}, b={np.asarray(b).tolist()!r}"
    d, sqr, pa, pb, fa, fb, params = _unpack(np.array(spec.fallback(a, b), dtype=np.float64))
    assert exact.ulps(float(d), ref.distance) < 1.0, context
    assert sqr == _exact._float(ref.sqr_distance), context
    assert (fa, fb) == (ref.feature_a, ref.feature_b), f"{fa!r}, {fb!r} vs exact {ref.features}, {context}"
    assert pa.tolist() == [_exact._float(x) for x in ref.point_a], context
    assert pb.tolist() == [_exact._float(x) for x in ref.point_b], context
    assert params.tolist() == [_exact._float(x) for x in spec.params(ref)], context


def check_scene(spec, a, b, fallback=True):
    """Every check on a batch of pairs; returns the worst robust error and the fallback count."""
    robust = robust_rows(spec, a, b)
    cert = _batch(spec.certified, a, b)
    worst, undecided = 0.0, 0
    for k in range(len(a)):
        ref = spec.reference(a[k], b[k])
        worst = max(worst, check_robust(spec, a[k], b[k], robust[k], ref))
        undecided += not check_certified(spec, a[k], b[k], cert[k], ref)
        if fallback:
            check_fallback(spec, a[k], b[k], ref)
    return worst, undecided


# -- every family ------------------------------------------------------------------

FAMILY_CASES = [
    pytest.param(pair, family, id=f"{pair}-{family.label}")
    for pair in SPECS
    for family in scenes.PAIR_FAMILIES[pair]
]


# Queries per family and hypothesis examples per pair: the exact reference
# and fallback of two triangles cost tens of milliseconds a query.
VOLUME = {"segment_segment": (40, 60), "segment_triangle": (30, 40), "triangle_triangle": (16, 25)}


@pytest.mark.parametrize(("pair", "family"), FAMILY_CASES)
def test_every_family(pair, family):
    scene = family(np.random.default_rng(2024), VOLUME[pair][0])
    check_scene(SPECS[pair], scene.a, scene.b)


@pytest.mark.parametrize("pair", sorted(SPECS))
def test_hypothesis_drawn_scenes(pair):
    @settings(max_examples=VOLUME[pair][1], deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(strategies.PAIR_FAMILIES[pair])
    def check(scene):
        check_scene(SPECS[pair], scene.a, scene.b)

    check()


@pytest.mark.parametrize("pair", sorted(SPECS))
def test_the_fallback_is_rare_on_well_conditioned_pairs(pair):
    """Seeded: fewer than 1 in 1,000 certified queries needs exact arithmetic."""
    scene = scenes.pair_well_conditioned(np.random.default_rng(7), 100_000, pair)
    status = _batch(SPECS[pair].certified, scene.a, scene.b)[:, 0]
    assert np.count_nonzero(status != certified.CERTAIN) < 100


# -- one exact case per feature pair ------------------------------------------------

SEGMENT = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]]
TRIANGLE = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]]

# (pair, shape a, shape b, sqr_distance, feature pair, witness on a, witness
# on b, whether the float filter must decide it): answers worked out by hand.
CASES = [
    ("segment_segment", SEGMENT, [[-1, -2, 0], [-3, -2, 0]], 5, (V0, V0), [0, 0, 0], [-1, -2, 0], True),
    ("segment_segment", SEGMENT, [[-3, -2, 0], [-1, -2, 0]], 5, (V0, V1), [0, 0, 0], [-1, -2, 0], True),
    ("segment_segment", SEGMENT, [[-1, -2, 0], [-1, 2, 0]], 1, (V0, E01), [0, 0, 0], [-1, 0, 0], True),
    ("segment_segment", SEGMENT, [[5, -2, 0], [7, -2, 0]], 5, (V1, V0), [4, 0, 0], [5, -2, 0], True),
    ("segment_segment", SEGMENT, [[7, -2, 0], [5, -2, 0]], 5, (V1, V1), [4, 0, 0], [5, -2, 0], True),
    ("segment_segment", SEGMENT, [[5, -2, 0], [5, 2, 0]], 1, (V1, E01), [4, 0, 0], [5, 0, 0], True),
    ("segment_segment", SEGMENT, [[2, -2, 0], [2, -5, 0]], 4, (E01, V0), [2, 0, 0], [2, -2, 0], True),
    ("segment_segment", SEGMENT, [[2, -5, 0], [2, -2, 0]], 4, (E01, V1), [2, 0, 0], [2, -2, 0], True),
    ("segment_segment", SEGMENT, [[2, -2, 3], [2, 2, 3]], 9, (E01, E01), [2, 0, 0], [2, 0, 3], True),
    # Crossing: zero, one common point (only exact arithmetic confirms it).
    ("segment_segment", SEGMENT, [[2, -2, 0], [2, 2, 0]], 0, (E01, E01), [2, 0, 0], [2, 0, 0], False),
    # Parallel: ties along the overlap go to the lowest pair.
    ("segment_segment", SEGMENT, [[1, 1, 0], [6, 1, 0]], 1, (V1, E01), [4, 0, 0], [4, 1, 0], False),
    ("segment_segment", SEGMENT, [[6, 1, 0], [1, 1, 0]], 1, (V1, E01), [4, 0, 0], [4, 1, 0], False),
    ("segment_segment", SEGMENT, [[-1, 1, 0], [6, 1, 0]], 1, (V0, E01), [0, 0, 0], [0, 1, 0], False),
    ("segment_segment", SEGMENT, [[1, 1, 0], [3, 1, 0]], 1, (E01, V0), [1, 0, 0], [1, 1, 0], False),
    # Collinear: overlapping (zero), then apart (vertex to vertex).
    ("segment_segment", SEGMENT, [[1, 0, 0], [6, 0, 0]], 0, (V1, E01), [4, 0, 0], [4, 0, 0], False),
    ("segment_segment", SEGMENT, [[6, 0, 0], [9, 0, 0]], 4, (V1, V0), [4, 0, 0], [6, 0, 0], True),
    # Degenerate: b a point, off a and on it.
    ("segment_segment", SEGMENT, [[1, 3, 0], [1, 3, 0]], 9, (E01, V0), [1, 0, 0], [1, 3, 0], True),
    ("segment_segment", SEGMENT, [[1, 0, 0], [1, 0, 0]], 0, (E01, V0), [1, 0, 0], [1, 0, 0], False),
    ("segment_segment", SEGMENT, [[4, 0, 0], [4, 0, 0]], 0, (V1, V0), [4, 0, 0], [4, 0, 0], False),
    # A segment against the triangle.
    ("segment_triangle", [[1, 1, 2], [1, 1, 5]], TRIANGLE, 4, (V0, FACE), [1, 1, 2], [1, 1, 0], True),
    ("segment_triangle", [[1, 1, 5], [1, 1, 2]], TRIANGLE, 4, (V1, FACE), [1, 1, 2], [1, 1, 0], True),
    ("segment_triangle", [[-1, -1, 1], [-3, -3, 1]], TRIANGLE, 3, (V0, V0), [-1, -1, 1], [0, 0, 0], True),
    ("segment_triangle", [[2, -1, 1], [2, -3, 1]], TRIANGLE, 2, (V0, E01), [2, -1, 1], [2, 0, 0], True),
    ("segment_triangle", [[5, -1, -1], [5, 1, -1]], TRIANGLE, 2, (E01, V1), [5, 0, -1], [4, 0, 0], True),
    ("segment_triangle", [[1, -1, 1], [3, -1, -1]], TRIANGLE, 1, (E01, E01), [2, -1, 0], [2, 0, 0], True),
    ("segment_triangle", [[3, 3, 1], [3, 3, -1]], TRIANGLE, 2, (E01, E12), [3, 3, 0], [2, 2, 0], True),
    # Through the face: an exact zero the filter confirms; through an edge: the fallback's.
    ("segment_triangle", [[1, 1, -1], [1, 1, 3]], TRIANGLE, 0, (E01, FACE), [1, 1, 0], [1, 1, 0], True),
    ("segment_triangle", [[2, 2, -1], [2, 2, 1]], TRIANGLE, 0, (E01, E12), [2, 2, 0], [2, 2, 0], False),
    # Parallel to the face above it: both endpoints and the edge tie.
    ("segment_triangle", [[1, 1, 2], [2, 1, 2]], TRIANGLE, 4, (V0, FACE), [1, 1, 2], [1, 1, 0], False),
    ("segment_triangle", [[1, 1, 3], [1, 1, 3]], TRIANGLE, 9, (V0, FACE), [1, 1, 3], [1, 1, 0], True),
    # Two triangles.
    (
        "triangle_triangle",
        TRIANGLE,
        [[1, 1, 2], [1, 1, 5], [2, 1, 5]],
        4,
        (FACE, V0),
        [1, 1, 0],
        [1, 1, 2],
        True,
    ),
    (
        "triangle_triangle",
        [[1, 1, 2], [1, 1, 5], [2, 1, 5]],
        TRIANGLE,
        4,
        (V0, FACE),
        [1, 1, 2],
        [1, 1, 0],
        True,
    ),
    (
        "triangle_triangle",
        TRIANGLE,
        [[5, -1, 1], [7, -1, 1], [5, -3, 1]],
        3,
        (V1, V0),
        [4, 0, 0],
        [5, -1, 1],
        True,
    ),
    (
        "triangle_triangle",
        TRIANGLE,
        [[2, -1, -1], [2, -1, 1], [2, -3, 0]],
        1,
        (E01, E01),
        [2, 0, 0],
        [2, -1, 0],
        True,
    ),
    (
        "triangle_triangle",
        TRIANGLE,
        [[3, 3, 2], [3, 3, 4], [5, 5, 3]],
        6,
        (E12, V0),
        [2, 2, 0],
        [3, 3, 2],
        True,
    ),
    # Crossing along a segment: its ends are edges through faces, the lowest wins.
    (
        "triangle_triangle",
        TRIANGLE,
        [[1, 1, -1], [1, 1, 1], [5, 5, 1]],
        0,
        (E12, FACE),
        [2, 2, 0],
        [2, 2, 0],
        True,
    ),
    (
        "triangle_triangle",
        [[1, 1, -1], [1, 1, 1], [5, 5, 1]],
        TRIANGLE,
        0,
        (E01, FACE),
        [1, 1, 0],
        [1, 1, 0],
        True,
    ),
    # Touching vertex to face, and coplanar overlap: exact arithmetic only.
    (
        "triangle_triangle",
        TRIANGLE,
        [[1, 1, 0], [1, 1, 3], [2, 1, 3]],
        0,
        (FACE, V0),
        [1, 1, 0],
        [1, 1, 0],
        False,
    ),
    (
        "triangle_triangle",
        TRIANGLE,
        [[1, 1, 0], [5, 1, 0], [1, 5, 0]],
        0,
        (E12, E01),
        [3, 1, 0],
        [3, 1, 0],
        False,
    ),
]


def _axes_and_shift(points, order, shift):
    return (np.asarray(points, dtype=np.float64)[:, order] + shift).tolist()


@pytest.mark.parametrize(("pair", "a", "b", "sqr", "features", "pa", "pb", "decided"), CASES)
@pytest.mark.parametrize("motion", [((0, 1, 2), 0.0), ((2, 0, 1), 8.0), ((1, 2, 0), -0.5)])
def test_one_case_per_feature_pair(pair, a, b, sqr, features, pa, pb, decided, motion):
    """Exact answers, moved by an axis permutation and a dyadic shift (both exact)."""
    order, shift = motion
    a, b = _axes_and_shift(a, order, shift), _axes_and_shift(b, order, shift)
    pa, pb = _axes_and_shift([pa], order, shift)[0], _axes_and_shift([pb], order, shift)[0]
    spec = SPECS[pair]
    ref = spec.reference(a, b)
    assert ref.sqr_distance == sqr and (ref.feature_a, ref.feature_b) == features
    assert [float(x) for x in ref.point_a] == pa and [float(x) for x in ref.point_b] == pb
    check_robust(spec, a, b, robust_rows(spec, [a], [b])[0], ref)
    check_fallback(spec, a, b, ref)
    cert = _batch(spec.certified, [a], [b])[0]
    check_certified(spec, a, b, cert, ref)
    # A unique minimum away from zero, or a proper crossing, is the filter's
    # to decide; ties and touching only exact arithmetic can.
    assert (cert[0] == certified.CERTAIN) == decided
    if pair != "segment_triangle":  # the swapped pair is of another kind
        check_robust(spec, b, a, robust_rows(spec, [b], [a])[0])


# -- both ends of the float range ---------------------------------------------------


@pytest.mark.parametrize("pair", sorted(SPECS))
@pytest.mark.parametrize(
    ("size", "offset"),
    [
        (1.0, 2.0**1020),  # far apart: the distance near the largest floats
        (2.0**1020, 2.0**1021),  # huge shapes
        (2.0**-1060, 2.0**-1060),  # subnormal coordinates
        (2.0**-1000, 2.0**-1070),  # subnormal gaps between normal shapes
        (1e-3, 1e308),  # small shapes next to the largest floats (distances below them)
    ],
)
def test_both_ends_of_the_float_range(pair, size, offset):
    spec = SPECS[pair]
    rng = np.random.default_rng(5)
    ka, kb = spec.sizes
    a = rng.uniform(-1, 1, (20, ka, 3)) * size
    b = rng.uniform(-1, 1, (20, kb, 3)) * size + rng.uniform(-1, 1, (20, 1, 3)) * offset
    check_scene(spec, a, b)


@pytest.mark.parametrize("pair", sorted(SPECS))
def test_differences_that_overflow(pair):
    """Coordinates of both signs near the float limit: their differences overflow, the distance does not."""
    spec = SPECS[pair]
    rng = np.random.default_rng(6)
    ka, kb = spec.sizes
    top = 1.7e308
    a = rng.uniform(-1, 1, (20, ka, 3)) * top
    b = rng.uniform(-1, 1, (20, kb, 3)) * top
    robust = robust_rows(spec, a, b)
    for k in range(len(a)):
        ref = spec.reference(a[k], b[k])
        if ref.distance < top:
            check_robust(spec, a[k], b[k], robust[k], ref)
            check_fallback(spec, a[k], b[k], ref)
        cert = _batch(spec.certified, a[k : k + 1], b[k : k + 1])[0]
        assert (
            cert[0] == certified.EXACT or ref.distance < top and check_certified(spec, a[k], b[k], cert, ref)
        )
