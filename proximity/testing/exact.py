"""Exact reference answers for the closest-point queries.

Every float64 input is converted to the rational number it denotes
(``fractions.Fraction(float)`` is exact), and the query is answered with
rational arithmetic. Where the answer is irrational (a distance is a square
root; a circle's radial distance is one too), the radicands are formed exactly
and only the final square roots are taken, in ``mpmath`` at `PREC` bits, far
beyond float64's 53.

This module is the judge of the float implementation, so it deliberately
shares none of its logic: it enumerates every feature of the triangle and keeps
the nearest, instead of classifying the point into a Voronoi region, and it
never rounds an intermediate value to float.

Each function answers ONE query. Use `pairwise` to loop over a batch.
"""

from __future__ import annotations

import enum
import math
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

try:
    import mpmath
    from mpmath import libmp
except ImportError as error:  # pragma: no cover - the test extra installs it
    raise ImportError("proximity.testing.exact needs mpmath: pip install 'proximity3d[test]'") from error

__all__ = [
    "EPS",
    "PREC",
    "Feature",
    "RoundClosest",
    "SegmentClosest",
    "TriangleClosest",
    "circle_closest",
    "circle_distance",
    "circle_scale",
    "circle_sqr_distance",
    "disk_closest",
    "disk_distance",
    "disk_sqr_distance",
    "error_in_units",
    "pairwise",
    "segment_closest",
    "segment_distance",
    "segment_scale",
    "segment_sqr_distance",
    "to_mpf",
    "triangle_closest",
    "triangle_distance",
    "triangle_scale",
    "triangle_sqr_distance",
    "ulps",
]

PREC = 256
"""Binary precision, in bits, of every `mpmath.mpf` this module returns."""

EPS = Fraction(1, 2**52)
"""float64 machine epsilon, the spacing of floats just above 1."""


class Feature(enum.IntEnum):
    """The feature of a shape on which the closest point lies.

    The codes match the ones the library reports, so a reference feature can be
    compared with a computed one directly.
    """

    VERTEX0 = 0
    VERTEX1 = 1
    VERTEX2 = 2
    EDGE01 = 3
    EDGE12 = 4
    EDGE20 = 5
    FACE = 6
    RIM = 7


_EDGES = {Feature.EDGE01: (0, 1), Feature.EDGE12: (1, 2), Feature.EDGE20: (2, 0)}

# The vertices spanning each triangle feature; a closed feature contains the
# features whose support is a subset of its own.
_SUPPORT = {
    **{Feature(i): frozenset({i}) for i in range(3)},
    **{feature: frozenset(pair) for feature, pair in _EDGES.items()},
    Feature.FACE: frozenset({0, 1, 2}),
}

Vector = tuple[Fraction, ...]


@dataclass(frozen=True)
class TriangleClosest:
    """Exact closest point of a triangle to a point.

    Attributes
    ----------
    sqr_distance : Fraction
        Exact squared distance.
    point : tuple of Fraction
        Exact closest point, one coordinate per dimension.
    feature : Feature
        The feature whose relative interior holds the closest point. When
        several do (only possible for degenerate triangles, for example a
        vertex lying on the opposite edge), the one with the lowest code,
        that is the lowest-dimensional one, is reported.
    features : frozenset of Feature
        Every feature attaining the minimum, `feature` included. It has more
        than one element only for degenerate triangles.
    barycentric : tuple of 3 Fraction
        Exact barycentric coordinates of `point` with respect to the
        vertices, expressed on `feature` (they are not unique when the
        triangle is degenerate).
    feature_sqr_distances : tuple of 7 Fraction
        Exact squared distance from the point to each closed feature, indexed
        by `Feature` code: a vertex, an edge with its endpoints, the whole
        triangle (equal to `sqr_distance`). Lets a test accept a computed
        feature that is wrong only by rounding: on a sliver the face and an
        edge can be closer to each other than the float error.
    """

    sqr_distance: Fraction
    point: Vector
    feature: Feature
    features: frozenset[Feature]
    barycentric: tuple[Fraction, Fraction, Fraction]
    feature_sqr_distances: tuple[Fraction, ...]

    @property
    def distance(self) -> mpmath.mpf:
        """Distance, correctly rounded to `PREC` bits."""
        return _sqrt(self.sqr_distance)


@dataclass(frozen=True)
class SegmentClosest:
    """Exact closest point of a segment to a point.

    Attributes
    ----------
    sqr_distance : Fraction
        Exact squared distance.
    point : tuple of Fraction
        Exact closest point, one coordinate per dimension.
    feature : Feature
        ``VERTEX0``, ``VERTEX1`` or ``EDGE01``: the feature whose relative
        interior holds the closest point. A zero-length segment's point is
        both vertices; the lower code, ``VERTEX0``, is reported.
    features : frozenset of Feature
        Every feature attaining the minimum, `feature` included. It has two
        elements only for a zero-length segment.
    t : Fraction
        Exact parameter of `point` along the segment: ``point = V0 + t (V1 -
        V0)`` with ``0 <= t <= 1``; 0 on ``VERTEX0`` (a zero-length segment
        included) and 1 on ``VERTEX1``.
    """

    sqr_distance: Fraction
    point: Vector
    feature: Feature
    features: frozenset[Feature]
    t: Fraction

    @property
    def distance(self) -> mpmath.mpf:
        """Distance, correctly rounded to `PREC` bits."""
        return _sqrt(self.sqr_distance)


@dataclass(frozen=True)
class RoundClosest:
    """Closest point of a circle or a disk to a point.

    Attributes
    ----------
    distance : mpmath.mpf
        Distance at `PREC` bits (a few units in the last of those bits).
    sqr_height : Fraction
        Exact squared distance from the point to the shape's plane.
    sqr_radial : Fraction
        Exact squared distance from the point to the shape's axis.
    feature : Feature
        ``Feature.FACE`` when the closest point of a disk is its projection
        onto the plane (``sqr_radial <= radius**2``, the rim included),
        ``Feature.RIM`` otherwise and always for a circle.
    on_axis : bool
        True when the point is exactly on the axis (``sqr_radial == 0``).
        Every point of a circle is then equally close.
    point : tuple of mpmath.mpf or None
        Closest point at `PREC` bits; None for a circle of nonzero radius
        queried from its axis, where no single point is closest.
    """

    distance: mpmath.mpf
    sqr_height: Fraction
    sqr_radial: Fraction
    feature: Feature
    on_axis: bool
    point: tuple[mpmath.mpf, ...] | None

    @property
    def sqr_distance(self) -> mpmath.mpf:
        """Squared distance at `PREC` bits."""
        with mpmath.workprec(PREC):
            return self.distance * self.distance


# -- conversions -------------------------------------------------------------


def _rationals(values: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """Return `values` as an object array of exact Fractions, after checks."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(array.shape, shape, strict=True)
    ):
        expected = tuple("D" if want is None else want for want in shape)
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array.tolist()}")
    # float() of a float64 scalar is exact, and so is Fraction(float).
    flat = [Fraction(float(x)) for x in array.ravel()]
    out = np.empty(len(flat), dtype=object)
    out[:] = flat
    return out.reshape(array.shape)


def _vector(values: Any, name: str, dim: int | None = None) -> Vector:
    return tuple(_rationals(values, name, (dim,)))


def _scalar(value: Any, name: str) -> Fraction:
    return _rationals(value, name, ())[()]


def to_mpf(value: Any) -> mpmath.mpf:
    """Convert a number to an `mpmath.mpf` of `PREC` bits without float rounding.

    Parameters
    ----------
    value : Fraction, int, float or mpmath.mpf
        Number to convert. Floats and ints are exact at `PREC` bits when they
        fit (all float64 values do); other rationals are correctly rounded.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> to_mpf(Fraction(1, 4)) == mpmath.mpf(0.25)
    True
    """
    if isinstance(value, mpmath.mpf):
        return value
    if isinstance(value, (float, np.floating)):
        value = Fraction(float(value))
    value = Fraction(value)
    with mpmath.workprec(PREC):
        return mpmath.mpf(libmp.from_rational(value.numerator, value.denominator, PREC, libmp.round_nearest))


def _sqrt(value: Fraction) -> mpmath.mpf:
    with mpmath.workprec(PREC):
        return mpmath.sqrt(to_mpf(value))


# -- exact vector algebra ----------------------------------------------------


def _sub(a: Sequence[Fraction], b: Sequence[Fraction]) -> Vector:
    return tuple(x - y for x, y in zip(a, b, strict=True))


def _dot(a: Sequence[Fraction], b: Sequence[Fraction]) -> Fraction:
    return sum((x * y for x, y in zip(a, b, strict=True)), Fraction(0))


def _affine(origin: Vector, weights: Iterable[Fraction], directions: Iterable[Vector]) -> Vector:
    """Return ``origin + sum(w * d)`` exactly."""
    out = list(origin)
    for weight, direction in zip(weights, directions, strict=True):
        for k, x in enumerate(direction):
            out[k] += weight * x
    return tuple(out)


# -- triangle ----------------------------------------------------------------


def _dyadic(*arrays: np.ndarray) -> tuple[list[np.ndarray], int]:
    """Write arrays of exact float values as integers times one ``2**exponent``.

    The exponent is the largest that makes every value an integer; the
    denominators of floats are powers of two, so this is exact.
    """
    shifts = [x.denominator.bit_length() - 1 for arr in arrays for x in arr.flat]
    exponent = -max(shifts, default=0)
    out = []
    for arr in arrays:
        ints = np.empty(arr.shape, dtype=object)
        for index, x in np.ndenumerate(arr):
            ints[index] = x.numerator << (-exponent - (x.denominator.bit_length() - 1))
        out.append(ints)
    return out, exponent


def _power_of_two(exponent: int) -> Fraction:
    return Fraction(2**exponent) if exponent >= 0 else Fraction(1, 2**-exponent)


def _isub(a: Sequence[int], b: Sequence[int]) -> tuple[int, ...]:
    return tuple(x - y for x, y in zip(a, b, strict=True))


def _idot(a: Sequence[int], b: Sequence[int]) -> int:
    return sum(x * y for x, y in zip(a, b, strict=True))


def triangle_closest(vertices: Any, point: Any) -> TriangleClosest:
    """Exact closest point of a closed triangle to a point.

    The minimum of ``|X - P|**2`` over the triangle is the minimum over its
    features, each searched in its relative interior: the 3 vertices, the 3
    open edges (projection parameter strictly in (0, 1); a clamped projection
    is a vertex, already a candidate) and the open face (the 2x2 normal
    equations solved exactly, kept only when their determinant is nonzero and
    ``s > 0, t > 0, s + t < 1``). This needs no case analysis, so it holds
    unchanged for degenerate triangles: a zero-length edge or a zero-area face
    simply contributes no candidate.

    Parameters
    ----------
    vertices : array_like, shape (3, D)
        Triangle vertices, D >= 1, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    TriangleClosest

    Raises
    ------
    ValueError
        If a shape is wrong or a coordinate is not finite.

    Examples
    --------
    >>> r = triangle_closest([[0, 0, 0], [4, 0, 0], [0, 4, 0]], [1, 1, 3])
    >>> r.sqr_distance, r.feature.name, r.barycentric
    (Fraction(9, 1), 'FACE', (Fraction(1, 2), Fraction(1, 4), Fraction(1, 4)))
    """
    v = _rationals(vertices, "vertices", (3, None))
    (v, p), exponent = _dyadic(v, _rationals(point, "point", (v.shape[1],)))
    # Integer coordinates (units of 2**exponent) relative to the point: every
    # product below is an exact int, and a Fraction is formed only once per
    # candidate, which keeps the rational arithmetic fast.
    a = [tuple(x - y for x, y in zip(row, p, strict=True)) for row in v]

    # A candidate X = (w0 V0 + w1 V1 + w2 V2) / den, with integer weights
    # summing to den, is kept as (feature, weights, den).
    candidates = [(Feature(i), tuple(int(k == i) for k in range(3)), 1) for i in range(3)]
    for feature, (i, j) in _EDGES.items():
        edge = _isub(a[j], a[i])
        length2 = _idot(edge, edge)
        along = -_idot(a[i], edge)  # t = along / length2
        if 0 < along < length2:
            weights = [0, 0, 0]
            weights[i], weights[j] = length2 - along, along
            candidates.append((feature, tuple(weights), length2))

    # Face, in Eberly's notation: minimize |D + s E0 + t E1|^2 with
    # s = s_num / det and t = t_num / det (det > 0 unless the area is 0).
    e0, e1, diff = _isub(a[1], a[0]), _isub(a[2], a[0]), a[0]
    aa, b, c = _idot(e0, e0), _idot(e0, e1), _idot(e1, e1)
    d, e = _idot(e0, diff), _idot(e1, diff)
    det = aa * c - b * b
    s_num, t_num = b * e - c * d, b * d - aa * e
    if det != 0 and s_num > 0 and t_num > 0 and s_num + t_num < det:
        candidates.append((Feature.FACE, (det - s_num - t_num, s_num, t_num), det))

    scored = []
    for feature, weights, den in candidates:
        offset = [sum(w * ak[m] for w, ak in zip(weights, a, strict=True)) for m in range(len(p))]
        scored.append((Fraction(_idot(offset, offset), den * den), feature, offset, weights, den))
    sqr, feature, offset, weights, den = min(scored, key=lambda item: item[:2])
    sqr_scale = _power_of_two(2 * exponent)
    closed = tuple(
        min(item[0] for item in scored if _SUPPORT[item[1]] <= _SUPPORT[f]) * sqr_scale for f in _SUPPORT
    )
    return TriangleClosest(
        sqr_distance=sqr * sqr_scale,
        point=tuple(
            (pk + Fraction(ok, den)) * _power_of_two(exponent) for pk, ok in zip(p, offset, strict=True)
        ),
        feature=feature,
        features=frozenset(item[1] for item in scored if item[0] == sqr),
        barycentric=tuple(Fraction(w, den) for w in weights),
        feature_sqr_distances=closed,
    )


def triangle_sqr_distance(vertices: Any, point: Any) -> Fraction:
    """Exact squared distance from a point to a closed triangle.

    Parameters
    ----------
    vertices : array_like, shape (3, D)
        Triangle vertices, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    Fraction

    See Also
    --------
    triangle_closest : the same query with the closest point and feature.

    Examples
    --------
    >>> triangle_sqr_distance([[0, 0], [4, 0], [0, 4]], [3, 3])
    Fraction(2, 1)
    """
    return triangle_closest(vertices, point).sqr_distance


def triangle_distance(vertices: Any, point: Any) -> mpmath.mpf:
    """Distance from a point to a closed triangle, correctly rounded to `PREC` bits.

    Parameters
    ----------
    vertices : array_like, shape (3, D)
        Triangle vertices, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> float(triangle_distance([[0, 0], [4, 0], [0, 4]], [-3, -4]))
    5.0
    """
    return _sqrt(triangle_sqr_distance(vertices, point))


def triangle_scale(vertices: Any, point: Any) -> mpmath.mpf:
    """Largest distance from the point to a vertex, at `PREC` bits.

    This is the magnitude of the differences a float implementation forms,
    hence the natural unit for its rounding error.

    Parameters
    ----------
    vertices : array_like, shape (3, D)
        Triangle vertices, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> float(triangle_scale([[0, 0], [4, 0], [0, 4]], [0, -3]))
    7.0
    """
    return _farthest(_rationals(vertices, "vertices", (3, None)), point)


def _farthest(vertices: np.ndarray, point: Any) -> mpmath.mpf:
    """Largest Euclidean distance from `point` to a row of `vertices` (exact), at `PREC` bits."""
    p = _vector(point, "point", vertices.shape[1])
    return _sqrt(max(_dot(_sub(row, p), _sub(row, p)) for row in vertices))


# -- segment -----------------------------------------------------------------


def segment_closest(vertices: Any, point: Any) -> SegmentClosest:
    """Exact closest point of a closed segment to a point.

    As `triangle_closest`, the minimum over the features, each searched in its
    relative interior: the 2 endpoints and the open segment (the projection
    parameter strictly between 0 and 1). A zero-length segment contributes
    no open segment, and its two endpoints tie.

    Parameters
    ----------
    vertices : array_like, shape (2, D)
        Segment endpoints ``V0, V1``, D >= 1, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    SegmentClosest

    Raises
    ------
    ValueError
        If a shape is wrong or a coordinate is not finite.

    Examples
    --------
    >>> r = segment_closest([[0, 0, 0], [4, 0, 0]], [1, 2, 2])
    >>> r.sqr_distance, r.feature.name, r.t, r.point
    (Fraction(8, 1), 'EDGE01', Fraction(1, 4), (Fraction(1, 1), Fraction(0, 1), Fraction(0, 1)))
    >>> segment_closest([[1, 1], [1, 1]], [4, 5]).features == {Feature.VERTEX0, Feature.VERTEX1}
    True
    """
    v = _rationals(vertices, "vertices", (2, None))
    (v, p), exponent = _dyadic(v, _rationals(point, "point", (v.shape[1],)))
    # Integer coordinates relative to the point, as in `triangle_closest`.
    a, b = (tuple(x - y for x, y in zip(row, p, strict=True)) for row in v)
    edge = _isub(b, a)
    length2 = _idot(edge, edge)
    along = -_idot(a, edge)  # t = along / length2

    # A candidate X = a + (num / den) * edge, as (feature, num, den).
    candidates = [(Feature.VERTEX0, 0, 1), (Feature.VERTEX1, 1, 1)]
    if 0 < along < length2:
        candidates.append((Feature.EDGE01, along, length2))
    scored = []
    for feature, num, den in candidates:
        offset = [den * ak + num * ek for ak, ek in zip(a, edge, strict=True)]
        scored.append((Fraction(_idot(offset, offset), den * den), feature, offset, num, den))
    sqr, feature, offset, num, den = min(scored, key=lambda item: item[:2])
    unit = _power_of_two(exponent)
    return SegmentClosest(
        sqr_distance=sqr * unit * unit,
        point=tuple((pk + Fraction(ok, den)) * unit for pk, ok in zip(p, offset, strict=True)),
        feature=feature,
        features=frozenset(item[1] for item in scored if item[0] == sqr),
        t=Fraction(num, den),
    )


def segment_sqr_distance(vertices: Any, point: Any) -> Fraction:
    """Exact squared distance from a point to a closed segment.

    Parameters
    ----------
    vertices : array_like, shape (2, D)
        Segment endpoints, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    Fraction

    See Also
    --------
    segment_closest : the same query with the closest point and feature.

    Examples
    --------
    >>> segment_sqr_distance([[0, 0], [4, 0]], [6, 1])
    Fraction(5, 1)
    """
    return segment_closest(vertices, point).sqr_distance


def segment_distance(vertices: Any, point: Any) -> mpmath.mpf:
    """Distance from a point to a closed segment, correctly rounded to `PREC` bits.

    Parameters
    ----------
    vertices : array_like, shape (2, D)
        Segment endpoints, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> float(segment_distance([[0, 0], [4, 0]], [-3, -4]))
    5.0
    """
    return _sqrt(segment_sqr_distance(vertices, point))


def segment_scale(vertices: Any, point: Any) -> mpmath.mpf:
    """Largest Euclidean distance from the point to an endpoint, at `PREC` bits.

    The error scale ``S = max(|P - V0|, |P - V1|)`` of a segment query, as
    `triangle_scale` is a triangle's.

    Parameters
    ----------
    vertices : array_like, shape (2, D)
        Segment endpoints, finite float64.
    point : array_like, shape (D,)
        Query point, finite float64.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> float(segment_scale([[0, 0], [4, 0]], [0, -3]))
    5.0
    """
    return _farthest(_rationals(vertices, "vertices", (2, None)), point)


# -- circle and disk ---------------------------------------------------------


def _round_closest(center: Any, normal: Any, radius: Any, point: Any, *, disk: bool) -> RoundClosest:
    c = _vector(center, "center", 3)
    n = _vector(normal, "normal", 3)
    r = _scalar(radius, "radius")
    p = _vector(point, "point", 3)
    nn = _dot(n, n)
    if nn == 0:
        raise ValueError("normal must be nonzero")
    if r < 0:
        raise ValueError(f"radius must be nonnegative, got {float(r)}")

    diff = _sub(p, c)
    along = _dot(n, diff) / nn
    radial = _affine(diff, [-along], [n])  # diff minus its axial part, exactly
    h2 = along * along * nn
    q2 = _dot(radial, radial)
    on_axis = q2 == 0
    on_face = disk and q2 <= r * r

    with mpmath.workprec(PREC):
        if on_face:
            distance = mpmath.sqrt(to_mpf(h2))
            closest = tuple(to_mpf(ck + rk) for ck, rk in zip(c, radial, strict=True))
        elif on_axis:
            # q = 0: the distance is sqrt(h^2 + R^2) to every rim point.
            distance = mpmath.sqrt(to_mpf(h2 + r * r))
            closest = tuple(to_mpf(x) for x in c) if r == 0 else None
        else:
            q = mpmath.sqrt(to_mpf(q2))
            # q - R = (q^2 - R^2) / (q + R): the numerator is exact and the
            # denominator adds positive terms, so near the rim, where q - R
            # cancels, the rounding of q is not amplified.
            gap = to_mpf(q2 - r * r) / (q + to_mpf(r))
            distance = mpmath.sqrt(to_mpf(h2) + gap * gap)
            ratio = to_mpf(r) / q
            closest = tuple(to_mpf(ck) + ratio * to_mpf(rk) for ck, rk in zip(c, radial, strict=True))
    return RoundClosest(
        distance=distance,
        sqr_height=h2,
        sqr_radial=q2,
        feature=Feature.FACE if on_face else Feature.RIM,
        on_axis=on_axis,
        point=closest,
    )


def circle_closest(center: Any, normal: Any, radius: Any, point: Any) -> RoundClosest:
    """Closest point of a circle (the rim only) to a point.

    With ``D = P - C`` the squared height ``h2 = (N.D)**2 / N.N`` and squared
    radial distance ``q2 = D.D - h2`` are exact rationals, and the distance is
    ``sqrt(h2 + (q - R)**2)`` with ``q - R = (q2 - R**2) / (q + R)``, where
    only ``q = sqrt(q2)`` and the final root are rounded (to `PREC` bits).

    Parameters
    ----------
    center : array_like, shape (3,)
        Center, finite float64.
    normal : array_like, shape (3,)
        Axis direction, nonzero and of any length, finite float64.
    radius : float
        Radius, nonnegative and finite.
    point : array_like, shape (3,)
        Query point, finite float64.

    Returns
    -------
    RoundClosest
        ``feature`` is always ``Feature.RIM``.

    Raises
    ------
    ValueError
        For a zero normal, a negative radius, a non-finite value or a wrong
        shape.

    Examples
    --------
    >>> r = circle_closest([0, 0, 0], [0, 0, 2], 3, [0, 0, 4])
    >>> float(r.distance), r.on_axis, r.point
    (5.0, True, None)
    """
    return _round_closest(center, normal, radius, point, disk=False)


def disk_closest(center: Any, normal: Any, radius: Any, point: Any) -> RoundClosest:
    """Closest point of a closed disk to a point.

    The closest point is the projection onto the plane when ``q2 <= R**2``
    (decided exactly), at distance ``sqrt(h2)``; otherwise it is the circle's.

    Parameters
    ----------
    center : array_like, shape (3,)
        Center, finite float64.
    normal : array_like, shape (3,)
        Axis direction, nonzero and of any length, finite float64.
    radius : float
        Radius, nonnegative and finite.
    point : array_like, shape (3,)
        Query point, finite float64.

    Returns
    -------
    RoundClosest
        ``feature`` is ``Feature.FACE`` or ``Feature.RIM``.

    Raises
    ------
    ValueError
        For a zero normal, a negative radius, a non-finite value or a wrong
        shape.

    Examples
    --------
    >>> r = disk_closest([0, 0, 0], [0, 0, 2], 3, [1, 2, 4])
    >>> float(r.distance), r.feature.name
    (4.0, 'FACE')
    """
    return _round_closest(center, normal, radius, point, disk=True)


def circle_distance(center: Any, normal: Any, radius: Any, point: Any) -> mpmath.mpf:
    """Distance from a point to a circle at `PREC` bits; see `circle_closest`."""
    return circle_closest(center, normal, radius, point).distance


def disk_distance(center: Any, normal: Any, radius: Any, point: Any) -> mpmath.mpf:
    """Distance from a point to a closed disk at `PREC` bits; see `disk_closest`."""
    return disk_closest(center, normal, radius, point).distance


def circle_sqr_distance(center: Any, normal: Any, radius: Any, point: Any) -> mpmath.mpf:
    """Squared distance to a circle at `PREC` bits; irrational in general."""
    return circle_closest(center, normal, radius, point).sqr_distance


def disk_sqr_distance(center: Any, normal: Any, radius: Any, point: Any) -> mpmath.mpf:
    """Squared distance to a closed disk at `PREC` bits; irrational off the face."""
    return disk_closest(center, normal, radius, point).sqr_distance


def circle_scale(center: Any, radius: Any, point: Any) -> mpmath.mpf:
    """Error scale ``|P - C| + R`` of a circle or disk query, at `PREC` bits.

    Parameters
    ----------
    center : array_like, shape (3,)
        Center, finite float64.
    radius : float
        Radius, finite.
    point : array_like, shape (3,)
        Query point, finite float64.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> float(circle_scale([0, 0, 0], 2, [3, 4, 0]))
    7.0
    """
    c = _vector(center, "center", 3)
    p = _vector(point, "point", 3)
    with mpmath.workprec(PREC):
        return _sqrt(_dot(_sub(p, c), _sub(p, c))) + to_mpf(_scalar(radius, "radius"))


# -- error measures ----------------------------------------------------------


def error_in_units(d: float, d_exact: Any, scale: Any) -> float:
    """Error of a computed value in units of ``eps * scale``.

    Parameters
    ----------
    d : float
        Computed value.
    d_exact : Fraction, int, float or mpmath.mpf
        Reference value.
    scale : Fraction, int, float or mpmath.mpf
        Magnitude the error is measured against, for example from
        `triangle_scale` or `circle_scale`.

    Returns
    -------
    float
        ``|d - d_exact| / (eps * scale)`` with ``eps = 2**-52``, evaluated at
        `PREC` bits; inf when `d` is not finite, or when the error is nonzero
        and `scale` is zero.

    Examples
    --------
    >>> error_in_units(1.0 + 2**-52, 1, 1)
    1.0
    >>> error_in_units(float("nan"), 1, 1)
    inf
    """
    if not math.isfinite(d):
        return math.inf
    with mpmath.workprec(PREC):
        error = abs(to_mpf(d) - to_mpf(d_exact))
        if error == 0:
            return 0.0
        unit = to_mpf(EPS) * abs(to_mpf(scale))
        if unit == 0:
            return math.inf
        return float(error / unit)


def ulps(d: float, d_exact: Any) -> float:
    """Error of a computed value in units in the last place of the exact value.

    Parameters
    ----------
    d : float
        Computed value.
    d_exact : Fraction, int, float or mpmath.mpf
        Reference value.

    Returns
    -------
    float
        ``|d - d_exact| / ulp(x)`` where ``x`` is the float nearest
        `d_exact` and ``ulp(x) = math.ulp(x)`` (``2**-1074`` for zero and
        subnormals, the top binade's spacing beyond the float range); inf when
        `d` is not finite.

    Examples
    --------
    >>> ulps(1.0 + 2**-52, 1)
    1.0
    >>> ulps(5e-324, 0)
    1.0
    """
    if not math.isfinite(d):
        return math.inf
    with mpmath.workprec(PREC):
        exact = to_mpf(d_exact)
        error = abs(to_mpf(d) - exact)
        if error == 0:
            return 0.0
        nearest = abs(float(exact))  # mpf -> float rounds to nearest
        unit = math.ulp(min(nearest, sys.float_info.max))
        return float(error / to_mpf(unit))


def pairwise(function: Callable[..., Any], *arrays: Any) -> list[Any]:
    """Apply a one-query reference function to each row of equally long arrays.

    Parameters
    ----------
    function : callable
        For example `triangle_distance` or `disk_closest`.
    *arrays : array_like
        Arguments of `function`, each with one extra leading axis of the same
        length n.

    Returns
    -------
    list
        ``[function(a[i], b[i], ...) for i in range(n)]``.

    Examples
    --------
    >>> tris = np.array([[[0, 0], [4, 0], [0, 4]]] * 2, dtype=float)
    >>> pairwise(triangle_sqr_distance, tris, [[3, 3], [-1, 0]])
    [Fraction(2, 1), Fraction(1, 1)]
    """
    return [function(*args) for args in zip(*arrays, strict=True)]
