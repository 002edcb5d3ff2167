"""What the tests and the benchmarks share: the exact reference and the scene generators.

:mod:`proximity.testing.exact`
    Closest points in rational arithmetic on the floats' exact binary
    values, the yardstick every method is judged by (needs ``mpmath``,
    from the ``test`` extra).
:mod:`proximity.testing.scenes`
    Seeded generators of the adversarial scene families (slivers, needles,
    degenerate triangles, huge offsets, points on a circle's axis, ...).
"""
