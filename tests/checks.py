"""Assertions of the accuracy contract, judged by the exact reference.

``robust`` promises ``|d - d*| <= 8 eps S`` for every finite input, with
``S = max_i |P - V_i|`` for a triangle or a segment and ``S = |P - C| + R``
for a circle or a disk (plus ``2^-1075``, the rounding of a subnormal
distance, where a check says so).  The closest point is a float vector, so checks on it (that it lies
on the shape, that ``|P - point| == d``) also allow for the rounding of its
own coordinates: ``eps * |point|``.
"""

from fractions import Fraction

import mpmath
import numpy as np

from proximity.testing import exact

BOUND = 8.0
"""The robust error bound, in units of ``eps * S``."""


def _mpf(x):
    return exact.to_mpf(Fraction(float(x)))


def exact_norm(a, b):
    """``|a - b|`` of two float vectors, from their exact values."""
    sqr = sum((Fraction(float(x)) - Fraction(float(y))) ** 2 for x, y in zip(a, b, strict=True))
    with mpmath.workprec(exact.PREC):
        return mpmath.sqrt(exact.to_mpf(sqr))


def point_slack(point):
    """Rounding allowed for a closest point stored as floats, as a distance."""
    return exact.to_mpf(exact.EPS) * _mpf(np.max(np.abs(point)))


def _within(value, limit, what):
    with mpmath.workprec(exact.PREC):
        assert value <= limit, f"{what}: {mpmath.nstr(value, 6)} > allowed {mpmath.nstr(limit, 6)}"


def check_triangle(vertices, point, result, bound=BOUND):
    """Assert the robust contract for one query; return the error in eps*S."""
    ref = exact.triangle_closest(vertices, point)
    scale = exact.triangle_scale(vertices, point)
    error = exact.error_in_units(float(result.distance), ref.distance, scale)
    context = f"vertices={np.asarray(vertices).tolist()!r}, point={np.asarray(point).tolist()!r}"
    assert error <= bound, f"distance error {error:.3g} eps*S > {bound} for {context}"
    with mpmath.workprec(exact.PREC):
        allowed = exact.to_mpf(exact.EPS) * bound * scale + point_slack(result.point)
        _within(
            exact.triangle_distance(vertices, result.point),
            allowed,
            f"closest point off the triangle, {context}",
        )
        _within(
            abs(exact_norm(point, result.point) - _mpf(result.distance)),
            allowed,
            f"distance != |P - point|, {context}",
        )
        # The reported feature must hold a point within the bound of the
        # minimum: on a sliver, face and edge can be closer than rounding.
        feature_distance = mpmath.sqrt(exact.to_mpf(ref.feature_sqr_distances[int(result.feature)]))
        _within(
            feature_distance - ref.distance,
            exact.to_mpf(exact.EPS) * bound * scale,
            f"feature {result.feature!r} (exact {ref.features}), {context}",
        )
    b = np.asarray(result.barycentric)
    assert (b >= 0).all(), f"negative barycentric {b} for {context}"
    assert abs(b.sum() - 1.0) <= 1e-15, f"barycentric {b} does not sum to 1 for {context}"
    return error


HALF_SUBNORMAL = mpmath.mpf(2) ** -1075
"""The rounding of a subnormal distance: the absolute term of the robust bound."""


def check_segment(vertices, point, distance, closest, feature, t, bound=BOUND):
    """Assert the robust contract for one segment query; return the error in eps*S.

    ``vertices`` is ``(2, D)``, ``point`` and ``closest`` ``(D,)``.  Checks
    ``|d - d*| <= bound eps S + 2^-1075``; that ``closest`` lies on the
    segment, at distance ``d`` from ``P`` and at ``V0 + t (V1 - V0)``, each
    within that and the rounding of its own coordinates; ``0 <= t <= 1``;
    that ``VERTEX0`` and ``VERTEX1`` come with ``t`` 0 and 1 and the endpoint
    itself; and that the feature holds a point within the bound of the
    minimum (a vertex's own distance).
    """
    v = np.asarray(vertices, dtype=float)
    ref = exact.segment_closest(v, point)
    scale = exact.segment_scale(v, point)
    where = f"vertices={v.tolist()!r}, point={np.asarray(point).tolist()!r}"
    error = exact.error_in_units(float(distance), ref.distance, scale)
    with mpmath.workprec(exact.PREC):
        allowed = exact.to_mpf(exact.EPS) * bound * scale + HALF_SUBNORMAL
        _within(abs(_mpf(distance) - ref.distance), allowed, f"distance error ({error:.3g} eps*S), {where}")
        # The point's own rounding, subnormal coordinates included.
        on_segment = allowed + point_slack(closest) + HALF_SUBNORMAL * mpmath.sqrt(len(closest))
        _within(exact.segment_distance(v, closest), on_segment, f"closest point off the segment, {where}")
        _within(abs(exact_norm(point, closest) - _mpf(distance)), on_segment, f"d != |P - point|, {where}")
        # The point V0 + t (V1 - V0), exactly, and its distance from ``closest``.
        tt = Fraction(float(t))
        along = [Fraction(float(a)) + tt * (Fraction(float(b)) - Fraction(float(a))) for a, b in v.T]
        gap = sum((x - Fraction(float(c))) ** 2 for x, c in zip(along, closest, strict=True))
        _within(mpmath.sqrt(exact.to_mpf(gap)), on_segment, f"point != V0 + t (V1 - V0), t={t!r}, {where}")
        if int(feature) != exact.Feature.EDGE01:
            vertex = exact_norm(point, v[int(feature)])
            _within(vertex - ref.distance, allowed, f"feature {feature!r} ({set(ref.features)}), {where}")
    assert 0.0 <= t <= 1.0, f"t={t!r} outside [0, 1], {where}"
    ends = {exact.Feature.VERTEX0: (0.0, v[0]), exact.Feature.VERTEX1: (1.0, v[1])}
    if int(feature) in ends:
        end_t, end = ends[int(feature)]
        assert t == end_t and list(closest) == list(end), f"{feature!r}: t={t!r}, at {list(closest)}, {where}"
    else:
        assert feature == exact.Feature.EDGE01, f"feature {feature!r}, {where}"
    return error


def check_round(kind, center, normal, radius, point, result, bound=BOUND):
    """Assert the robust contract for one circle or disk query; return eps*S."""
    closest = exact.circle_closest if kind == "circle" else exact.disk_closest
    ref = closest(center, normal, radius, point)
    scale = exact.circle_scale(center, radius, point)
    error = exact.error_in_units(float(result.distance), ref.distance, scale)
    context = (
        f"{kind} center={list(center)!r}, normal={list(normal)!r}, radius={radius!r}, point={list(point)!r}"
    )
    assert error <= bound, f"distance error {error:.3g} eps*S > {bound} for {context}"
    with mpmath.workprec(exact.PREC):
        allowed = exact.to_mpf(exact.EPS) * bound * scale + point_slack(result.point)
        on_shape = closest(center, normal, radius, result.point).distance
        _within(on_shape, allowed, f"closest point off the {kind}, {context}")
        _within(
            abs(exact_norm(point, result.point) - _mpf(result.distance)),
            allowed,
            f"distance != |P - point|, {context}",
        )
    if kind == "disk":
        # FACE and RIM meet on the rim; either is right within the bound there.
        if result.feature != ref.feature:
            with mpmath.workprec(exact.PREC):
                gap = abs(mpmath.sqrt(exact.to_mpf(ref.sqr_radial)) - _mpf(radius))
                _within(
                    gap, exact.to_mpf(exact.EPS) * bound * scale, f"feature {result.feature!r}, {context}"
                )
    else:
        if ref.on_axis:
            assert result.equidistant, f"exactly on the axis but not equidistant: {context}"
    return error
