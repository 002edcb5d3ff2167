"""Inside and outside: the validity of a solid, winding numbers, signs and grids.

:mod:`.validity`
    Whether a mesh bounds a solid (closed, manifold, not self-intersecting, its shells).
:mod:`.winding`
    The exact winding number, down a hierarchy of the faces' moments.
:mod:`.crossings`
    Ray crossings, exact, for the points the winding number leaves undecided.
:mod:`.signed`
    The sign from the angle-weighted pseudonormal of the closest feature.
:mod:`.grid`
    Signed distance sampled on a grid.
:mod:`.topology`
    Edges, fans and shells of a face list.

It may import :mod:`proximity.broadphase`, :mod:`proximity.numerics`, :mod:`proximity.runtime`,
the registry of primitives and the root's vocabulary; meshes (:mod:`proximity.shapes.mesh`) call
it, it never calls them.
"""
