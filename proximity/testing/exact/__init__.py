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

The reference is split by what it answers: :mod:`._core` (rationals,
errors in units), :mod:`.points` (from a point), :mod:`.pairs` (between
two shapes); every public name is here.
"""

from ._core import EPS, PREC, Feature, error_in_units, pairwise, to_mpf, ulps
from .pairs import (
    FeaturePair,
    PairClosest,
    pair_scale,
    segment_segment_closest,
    segment_triangle_closest,
    triangle_triangle_closest,
)
from .points import (
    RoundClosest,
    SegmentClosest,
    TriangleClosest,
    circle_closest,
    circle_distance,
    circle_scale,
    circle_sqr_distance,
    disk_closest,
    disk_distance,
    disk_sqr_distance,
    segment_closest,
    segment_distance,
    segment_scale,
    segment_sqr_distance,
    triangle_closest,
    triangle_distance,
    triangle_scale,
    triangle_sqr_distance,
)

__all__ = [
    "EPS",
    "PREC",
    "Feature",
    "FeaturePair",
    "PairClosest",
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
    "pair_scale",
    "pairwise",
    "segment_closest",
    "segment_distance",
    "segment_scale",
    "segment_segment_closest",
    "segment_sqr_distance",
    "segment_triangle_closest",
    "to_mpf",
    "triangle_closest",
    "triangle_distance",
    "triangle_scale",
    "triangle_sqr_distance",
    "triangle_triangle_closest",
    "ulps",
]
