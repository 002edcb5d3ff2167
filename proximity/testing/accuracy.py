"""Errors of a method on a scene family, judged by the exact reference.

What the stability tests and the benchmark's accuracy sweeps share: the
shape of a family's scene, its exact answers, and the errors in units of
``eps * S`` and in ulps.  ``N`` and ``SEED`` are the size and seed of the
benchmark's accuracy batches, which the tests check query for query.
"""

import mpmath
import numpy as np

import proximity

from . import exact

#: Queries per family in the benchmark's accuracy batches, and their seed.
N = 200
SEED = 0


def shape_of(kind, scene):
    """The proximity shape of ``kind`` ("triangle", "disk", "circle") for a scene."""
    if kind == "triangle":
        return proximity.Triangle(scene.vertices)
    cls = proximity.Disk if kind == "disk" else proximity.Circle
    return cls(scene.center, scene.normal, scene.radius)


def reference(kind, scene):
    """Exact distances and scales ``S`` of a scene's queries, as mpmath numbers."""
    if kind == "triangle":
        rows = zip(scene.vertices, scene.points, strict=True)
        return [(exact.triangle_distance(v, p), exact.triangle_scale(v, p)) for v, p in rows]
    distance = exact.disk_distance if kind == "disk" else exact.circle_distance
    rows = zip(scene.center, scene.normal, scene.radius, scene.points, strict=True)
    return [(distance(c, n, r, p), exact.circle_scale(c, r, p)) for c, n, r, p in rows]


def errors(distances, ref):
    """Errors of float distances in units of ``eps * S``; inf where not finite."""
    return np.array(
        [exact.error_in_units(float(d), d_exact, s) for d, (d_exact, s) in zip(distances, ref, strict=True)]
    )


def ulp_errors(distances, ref):
    """Errors of float distances in ulps of the exact distance ``d*``; inf where not finite.

    Where ``d* == 0`` the unit is the smallest subnormal, so that only an
    exact zero is 0 ulps (see :func:`proximity.testing.exact.ulps`).
    """
    return np.array([exact.ulps(float(d), d_exact) for d, (d_exact, _) in zip(distances, ref, strict=True)])


#: The exact closest points of each pair of shapes, by the name of the pair (a key of ``scenes.PAIRS``).
_PAIR_CLOSEST = {
    "segment_segment": exact.segment_segment_closest,
    "segment_triangle": exact.segment_triangle_closest,
    "triangle_triangle": exact.triangle_triangle_closest,
}


def pair_shapes(pair, scene):
    """The proximity shapes ``(a, b)`` of a pair scene (``pair`` a key of ``scenes.PAIRS``)."""
    first, second = pair.split("_")
    kinds = {"segment": proximity.Segment, "triangle": proximity.Triangle}
    return kinds[first](scene.a), kinds[second](scene.b)


def pair_reference(pair, scene):
    """Exact distances (mpmath numbers) and sizes ``S`` (the largest coordinate difference between
    the two shapes' vertices, the unit of the pair queries' bound) of a pair scene's queries."""
    closest = _PAIR_CLOSEST[pair]
    out = []
    for a, b in zip(scene.a, scene.b, strict=True):
        with mpmath.workprec(exact.PREC):
            d = mpmath.sqrt(exact.to_mpf(closest(a, b).sqr_distance))
        out.append((d, exact.pair_scale(a, b)))
    return out
