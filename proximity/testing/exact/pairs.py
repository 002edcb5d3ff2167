"""Exact closest points between two shapes: segment-segment, segment-triangle, triangle-triangle."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from types import MappingProxyType
from typing import Any, NamedTuple

import mpmath  # _core refuses to import without it, with the install hint
import numpy as np

from ._core import (
    _EDGES,
    _SUPPORT,
    Feature,
    Vector,
    _dot,
    _dyadic,
    _idot,
    _isub,
    _power_of_two,
    _rationals,
    _sqrt,
    _sub,
)

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
