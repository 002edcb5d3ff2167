"""Arithmetic that a certified answer rests on: filters, error-free transformations, exact fallbacks.

:mod:`.fp`
    Error-free transformations (two-sum, two-product with FMA), faithful differences, ``EPS``.
:mod:`.dd`
    Double-double arithmetic.
:mod:`.certified`
    The certified float filters of the point queries, and their status codes.
:mod:`.exact`
    The exact fallback: rational arithmetic on the floats' exact values, for every query the
    filters leave undecided.
:mod:`.orient`
    Exact orientation predicates (a float filter, then expansion arithmetic).
:mod:`.rounding`
    Rounded primitives: ``d - r`` certified where it cancels, points of the rounded surface.
:mod:`.rigid`
    Rigid transforms: their check, and points and vectors moved into and out of a pose.
:mod:`.normals`
    The normal at a closest point: a face's turned to the point's side (decided exactly), the
    pseudonormal within rounding of an edge or a vertex, and the normals of pair results.

It may import :mod:`proximity.runtime`, the root's vocabulary and the primitive registry
(:mod:`proximity.primitives`); it calls no query of a shape.
"""
