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
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from types import MappingProxyType
from typing import Any, NamedTuple

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
    "FeaturePair",
    "PairClosest",
    "RoundClosest",
    "TriangleClosest",
    "circle_closest",
    "circle_distance",
    "circle_scale",
    "circle_sqr_distance",
    "disk_closest",
    "disk_distance",
    "disk_sqr_distance",
    "error_in_units",
    "pair_scale",
    "pairwise",
    "segment_segment_closest",
    "segment_triangle_closest",
    "to_mpf",
    "triangle_closest",
    "triangle_distance",
    "triangle_scale",
    "triangle_sqr_distance",
    "triangle_triangle_closest",
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
    v = _rationals(vertices, "vertices", (3, None))
    p = _vector(point, "point", v.shape[1])
    return _sqrt(max(_dot(_sub(row, p), _sub(row, p)) for row in v))


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


# -- pairs of shapes ---------------------------------------------------------

# The features of a segment (two vertices) and of a triangle (three), each
# with the indices of the vertices spanning it, in code order.
_SHAPE_FEATURES: dict[int, tuple[tuple[Feature, tuple[int, ...]], ...]] = {
    2: ((Feature.VERTEX0, (0,)), (Feature.VERTEX1, (1,)), (Feature.EDGE01, (0, 1))),
    3: (
        *((Feature(i), (i,)) for i in range(3)),
        *_EDGES.items(),
        (Feature.FACE, (0, 1, 2)),
    ),
}

FeaturePair = tuple[Feature, Feature]


@dataclass(frozen=True)
class PairClosest:
    """Exact closest points of two shapes (segments or triangles).

    Attributes
    ----------
    sqr_distance : Fraction
        Exact squared distance between the closed shapes.
    point_a, point_b : tuple of Fraction
        Exact closest points on shape a and on shape b, with ``point_b -
        point_a`` the same vector for every closest pair (the shapes are
        convex). Where the closest pairs are not unique (parallel edges,
        overlapping faces, intersecting triangles), the pair of the lowest
        `feature_a`, `feature_b`, which is unique there.
    feature_a, feature_b : Feature
        The features whose relative interiors hold `point_a` and `point_b`:
        of all feature pairs that hold a closest pair, the lowest
        ``(feature_a, feature_b)`` in code order (vertices before edges
        before the face, then by index).
    features : frozenset of (Feature, Feature)
        Every feature pair whose relative interiors hold a closest pair, the
        reported one included. Zero-length edges and zero-area faces have no
        relative interior of their own here, as in `triangle_closest`: the
        points they hold are their vertices' or edges'.
    weights_a, weights_b : tuple of Fraction
        Barycentric weights of `point_a` over shape a's vertices (two for a
        segment, ``(1 - s, s)``; three for a triangle), and of `point_b`.
    feature_sqr_distances : Mapping of (Feature, Feature) to Fraction
        Exact squared distance between each pair of closed features (a
        vertex, an edge with its endpoints, the whole triangle). Lets a test
        accept a computed feature pair that is wrong only by rounding.
    """

    sqr_distance: Fraction
    point_a: Vector
    point_b: Vector
    feature_a: Feature
    feature_b: Feature
    features: frozenset[FeaturePair]
    weights_a: tuple[Fraction, ...]
    weights_b: tuple[Fraction, ...]
    feature_sqr_distances: Mapping[FeaturePair, Fraction]

    @property
    def distance(self) -> mpmath.mpf:
        """Distance, correctly rounded to `PREC` bits."""
        return _sqrt(self.sqr_distance)


def _det(matrix: Sequence[Sequence[int]]) -> int:
    """Determinant of a square integer matrix of order 0 to 3 (Laplace)."""
    n = len(matrix)
    if n == 0:
        return 1
    if n == 1:
        return matrix[0][0]
    return sum(
        (-1) ** j * matrix[0][j] * _det([row[:j] + row[j + 1 :] for row in matrix[1:]]) for j in range(n)
    )


class _Candidate(NamedTuple):
    """The critical point of ``|x - y|**2`` over the affine hulls of two
    features, in integer units: ``x = sum(wa[i] A_i) / den`` and ``y =
    sum(wb[j] B_j) / den``, with ``offset = den * (y - x)``."""

    sqr: Fraction
    weights_a: tuple[int, ...]
    weights_b: tuple[int, ...]
    den: int
    offset: tuple[int, ...]


def _critical(
    a: Sequence[Sequence[int]], fa: tuple[int, ...], b: Sequence[Sequence[int]], fb: tuple[int, ...]
):
    """The unique critical point of the distance between the affine hulls of
    features ``fa`` of ``a`` and ``fb`` of ``b`` (integer coordinates), when it
    exists and lies in both relative interiors (every weight positive); else
    None.

    With ``x = A_i0 + sum s_k (A_ik - A_i0)`` and ``y = B_j0 + sum t_l (B_jl -
    B_j0)``, the normal equations ``G z = -C^T D`` of ``|D + C z|**2`` are solved
    by Cramer's rule; the critical point is unique exactly when the Gram
    matrix ``G`` is nonsingular (never for two faces in 3D).
    """
    columns = [_isub(a[i], a[fa[0]]) for i in fa[1:]] + [_isub(b[fb[0]], b[j]) for j in fb[1:]]
    d = _isub(a[fa[0]], b[fb[0]])
    gram = [[_idot(u, v) for v in columns] for u in columns]
    den = _det(gram)
    if den <= 0:  # a Gram determinant is >= 0; 0 when the hulls are parallel or degenerate
        return None
    rhs = [-_idot(u, d) for u in columns]
    nums = []
    for k in range(len(columns)):
        replaced = [row[:k] + [rhs[r]] + row[k + 1 :] for r, row in enumerate(gram)]
        nums.append(_det(replaced))
    p = len(fa) - 1
    s, t = nums[:p], nums[p:]
    weights_a = [0] * len(a)
    weights_b = [0] * len(b)
    weights_a[fa[0]] = den - sum(s)
    weights_b[fb[0]] = den - sum(t)
    for k, i in enumerate(fa[1:]):
        weights_a[i] = s[k]
    for k, j in enumerate(fb[1:]):
        weights_b[j] = t[k]
    if any(weights_a[i] <= 0 for i in fa) or any(weights_b[j] <= 0 for j in fb):
        return None
    # den * (y - x) = -(den D + C z_num), exactly in integers.
    offset = tuple(
        -(den * d[m] + sum(col[m] * z for col, z in zip(columns, nums, strict=True))) for m in range(len(d))
    )
    return _Candidate(
        Fraction(_idot(offset, offset), den * den), tuple(weights_a), tuple(weights_b), den, offset
    )


def _nondegenerate(points: Sequence[Vector]) -> bool:
    """Whether the points are affinely independent (a feature with a relative interior of its own)."""
    columns = [_sub(q, points[0]) for q in points[1:]]
    return _det([[_dot(u, v) for v in columns] for u in columns]) != 0


def _solve_affine(
    rows: list[list[Fraction]], rhs: list[Fraction]
) -> tuple[list[Fraction], list[list[Fraction]]] | None:
    """Solutions of ``rows z = rhs`` as ``z0 + sum c_k basis_k``, or None if
    there is none (exact elimination)."""
    m = [list(r) + [v] for r, v in zip(rows, rhs, strict=True)]
    n = len(rows[0])
    pivots = []
    r = 0
    for c in range(n):
        pivot = next((i for i in range(r, len(m)) if m[i][c] != 0), None)
        if pivot is None:
            continue
        m[r], m[pivot] = m[pivot], m[r]
        m[r] = [x / m[r][c] for x in m[r]]
        for i in range(len(m)):
            if i != r and m[i][c] != 0:
                m[i] = [x - m[i][c] * y for x, y in zip(m[i], m[r], strict=True)]
        pivots.append(c)
        r += 1
    if any(row[n] != 0 and all(x == 0 for x in row[:n]) for row in m):
        return None
    z0 = [Fraction(0)] * n
    for i, c in enumerate(pivots):
        z0[c] = m[i][n]
    basis = []
    for free in (c for c in range(n) if c not in pivots):
        z = [Fraction(0)] * n
        z[free] = Fraction(1)
        for i, c in enumerate(pivots):
            z[c] = -m[i][free]
        basis.append(z)
    return z0, basis


def _strictly_feasible(constraints: list[tuple[list[Fraction], Fraction]]) -> bool:
    """Whether some ``c`` satisfies every ``g . c + h > 0`` (Fourier-Motzkin elimination, exact)."""
    while constraints and constraints[0][0]:
        lower = [(g, h) for g, h in constraints if g[-1] > 0]
        upper = [(g, h) for g, h in constraints if g[-1] < 0]
        rest = [(g[:-1], h) for g, h in constraints if g[-1] == 0]
        for gl, hl in lower:
            for gu, hu in upper:
                # (gl c + hl) / gl[-1] > -c_last > ... combine to eliminate the last variable.
                wl, wu = -gu[-1], gl[-1]
                rest.append(
                    ([wl * x + wu * y for x, y in zip(gl[:-1], gu[:-1], strict=True)], wl * hl + wu * hu)
                )
        constraints = rest
    return all(h > 0 for _, h in constraints)


def _open_simplices_meet(p: Sequence[Vector], q: Sequence[Vector]) -> bool:
    """Whether the relative interiors of the simplices spanned by ``p`` and ``q``
    (affinely independent point lists) have a point in common.

    Unknowns: weights ``l`` of ``p`` and ``m`` of ``q``, with ``sum l P = sum m
    Q``, ``sum l = sum m = 1``, and every weight > 0.
    """
    dim = len(p[0])
    n = len(p) + len(q)
    rows = [[Fraction(x[k]) for x in p] + [-Fraction(y[k]) for y in q] for k in range(dim)]
    rows.append([Fraction(1)] * len(p) + [Fraction(0)] * len(q))
    rows.append([Fraction(0)] * len(p) + [Fraction(1)] * len(q))
    rhs = [Fraction(0)] * dim + [Fraction(1), Fraction(1)]
    solved = _solve_affine(rows, rhs)
    if solved is None:
        return False
    z0, basis = solved
    # Weight i is z0[i] + sum_k basis[k][i] c_k, which must be > 0.
    return _strictly_feasible([([b[i] for b in basis], z0[i]) for i in range(n)])


def _pair_closest(a: np.ndarray, b: np.ndarray) -> PairClosest:
    """`PairClosest` of two shapes given as exact (Fraction) vertex arrays."""
    (ia, ib), exponent = _dyadic(a, b)
    ia = [tuple(row) for row in ia]
    ib = [tuple(row) for row in ib]
    features_a, features_b = _SHAPE_FEATURES[len(ia)], _SHAPE_FEATURES[len(ib)]
    # Every pair of features whose affine hulls have a unique critical point
    # inside both relative interiors. The minimum over the closed shapes is
    # attained by the lowest pair that holds a closest pair, and that pair's
    # critical point is unique: a line of critical points through its relative
    # interiors would leave them through a lower pair (a vertex of an edge, an
    # edge of a face) at the same distance.
    candidates = {}
    for fa, support_a in features_a:
        for fb, support_b in features_b:
            found = _critical(ia, support_a, ib, support_b)
            if found is not None:
                candidates[fa, fb] = found
    sqr_scale = _power_of_two(2 * exponent)
    best_pair = min(candidates, key=lambda pair: (candidates[pair].sqr, pair))
    best = candidates[best_pair]
    sqr = best.sqr * sqr_scale

    closed = {}
    for fa, support_a in features_a:
        for fb, support_b in features_b:
            closed[fa, fb] = sqr_scale * min(
                c.sqr
                for (ga, gb), c in candidates.items()
                if _SUPPORT[ga] <= set(support_a) and _SUPPORT[gb] <= set(support_b)
            )

    unit = _power_of_two(exponent)
    point_a = tuple(
        Fraction(sum(w * v[m] for w, v in zip(best.weights_a, ia, strict=True)), best.den) * unit
        for m in range(len(ia[0]))
    )
    offset = tuple(Fraction(o, best.den) * unit for o in best.offset)
    point_b = tuple(x + o for x, o in zip(point_a, offset, strict=True))
    # Every pair of features whose relative interiors meet after moving shape
    # b by -offset holds a closest pair, and no other does: all closest pairs
    # of two convex sets differ by the same vector.
    holding = set()
    for fa, support_a in features_a:
        for fb, support_b in features_b:
            if closed[fa, fb] != sqr:
                continue
            pa = [tuple(a[i]) for i in support_a]
            pb = [_sub(tuple(b[j]), offset) for j in support_b]
            if _nondegenerate(pa) and _nondegenerate(pb) and _open_simplices_meet(pa, pb):
                holding.add((fa, fb))
    return PairClosest(
        sqr_distance=sqr,
        point_a=point_a,
        point_b=point_b,
        feature_a=best_pair[0],
        feature_b=best_pair[1],
        features=frozenset(holding),
        weights_a=tuple(Fraction(w, best.den) for w in best.weights_a),
        weights_b=tuple(Fraction(w, best.den) for w in best.weights_b),
        feature_sqr_distances=MappingProxyType(closed),
    )


def segment_segment_closest(a: Any, b: Any) -> PairClosest:
    """Exact closest points of two closed segments.

    Every pair of features (vertex or open edge of each) is searched in its
    relative interiors: the critical point of the squared distance over the
    two affine hulls, kept when it is unique and inside both. The nearest
    such candidate is the answer; which feature pairs tie is then decided by
    whether their relative interiors meet once shape b is moved onto shape a
    by the closest pairs' common difference vector. Nothing is rounded.

    Parameters
    ----------
    a, b : array_like, shape (2, D)
        The segments' endpoints, one per row, finite float64.

    Returns
    -------
    PairClosest

    Raises
    ------
    ValueError
        If a shape is wrong or a coordinate is not finite.

    Examples
    --------
    >>> r = segment_segment_closest([[0, 0, 0], [4, 0, 0]], [[1, -1, 2], [1, 1, 2]])
    >>> r.sqr_distance, r.feature_a.name, r.feature_b.name
    (Fraction(4, 1), 'EDGE01', 'EDGE01')
    >>> [float(x) for x in r.point_a], [float(x) for x in r.point_b]
    ([1.0, 0.0, 0.0], [1.0, 0.0, 2.0])

    Parallel segments tie along their overlap; the lowest pair is reported:

    >>> r = segment_segment_closest([[0, 0, 0], [4, 0, 0]], [[1, 1, 0], [6, 1, 0]])
    >>> r.feature_a.name, r.feature_b.name, sorted((fa.name, fb.name) for fa, fb in r.features)
    ('VERTEX1', 'EDGE01', [('EDGE01', 'EDGE01'), ('EDGE01', 'VERTEX0'), ('VERTEX1', 'EDGE01')])
    """
    sa = _rationals(a, "a", (2, None))
    return _pair_closest(sa, _rationals(b, "b", (2, sa.shape[1])))


def segment_triangle_closest(segment: Any, triangle: Any) -> PairClosest:
    """Exact closest points of a closed segment and a closed triangle.

    As `segment_segment_closest`, over the 3 x 7 feature pairs.

    Parameters
    ----------
    segment : array_like, shape (2, D)
        Endpoints, finite float64.
    triangle : array_like, shape (3, D)
        Vertices, finite float64.

    Returns
    -------
    PairClosest
        Shape a is the segment, shape b the triangle.

    Examples
    --------
    >>> r = segment_triangle_closest([[1, 1, -1], [1, 1, 3]], [[0, 0, 0], [4, 0, 0], [0, 4, 0]])
    >>> r.sqr_distance, r.feature_a.name, r.feature_b.name
    (Fraction(0, 1), 'EDGE01', 'FACE')
    >>> [str(w) for w in r.weights_a], [str(w) for w in r.weights_b]
    (['3/4', '1/4'], ['1/2', '1/4', '1/4'])
    """
    s = _rationals(segment, "segment", (2, None))
    return _pair_closest(s, _rationals(triangle, "triangle", (3, s.shape[1])))


def triangle_triangle_closest(a: Any, b: Any) -> PairClosest:
    """Exact closest points of two closed triangles.

    As `segment_segment_closest`, over the 7 x 7 feature pairs (two faces
    never have a unique critical point in 3D: a lower pair holds one).

    Parameters
    ----------
    a, b : array_like, shape (3, D)
        The triangles' vertices, one per row, finite float64.

    Returns
    -------
    PairClosest

    Examples
    --------
    Two triangles crossing along a segment: its ends are where an edge of
    one meets the face of the other, and the lowest such pair is reported.

    >>> r = triangle_triangle_closest([[0, 0, 0], [4, 0, 0], [0, 4, 0]], [[1, 1, -1], [1, 1, 1], [5, 5, 1]])
    >>> r.sqr_distance, r.feature_a.name, r.feature_b.name, r.point_a
    (Fraction(0, 1), 'EDGE12', 'FACE', (Fraction(2, 1), Fraction(2, 1), Fraction(0, 1)))
    """
    sa = _rationals(a, "a", (3, None))
    return _pair_closest(sa, _rationals(b, "b", (3, sa.shape[1])))


def pair_scale(a: Any, b: Any) -> Fraction:
    """Size ``S`` of a pair of shapes: the largest coordinate difference between their vertices.

    This is the unit of the pair queries' error bounds (``16 eps S``).

    Parameters
    ----------
    a, b : array_like, shape (n, D)
        Vertices of each shape, one per row (2 for a segment, 3 for a
        triangle), finite float64.

    Returns
    -------
    Fraction

    Examples
    --------
    >>> pair_scale([[0, 0, 0], [1, 0, 0]], [[0, 3, 0], [0, 0, -2]])
    Fraction(3, 1)
    """
    va = _rationals(a, "a", (None, None))
    vb = _rationals(b, "b", (None, va.shape[1]))
    rows = [*va, *vb]
    return max(abs(u[k] - v[k]) for u in rows for v in rows for k in range(va.shape[1]))


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
