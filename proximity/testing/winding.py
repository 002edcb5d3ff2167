"""Exact winding numbers of closed meshes: the reference of the sign tests and benchmark.

Signed crossings of a ray, counted in rational arithmetic (``Fraction`` of
each float's exact value) where a float filter cannot decide: it shares no
code with :mod:`proximity.signs.winding` or :mod:`proximity.signs.crossings`, whose
answers it judges.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np

__all__ = ["winding_numbers"]


def _sign(x: Fraction) -> int:
    return (x > 0) - (x < 0)


def _crossing(a: Sequence[Fraction], b: Sequence[Fraction], c: Sequence[Fraction],
              p: Sequence[Fraction]) -> int:  # fmt: skip
    """The signed crossing of face ``abc`` by the ray from ``p`` along +x, perturbed to
    ``p + (0, e, e^2)``: +1 where the face's normal has a positive x component, -1
    where negative, 0 where the ray misses it.  Raises where ``p`` is on the face."""
    # The projection on (y, z): the face's orientation there is the sign of its normal's x.
    nx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1])
    if nx == 0:
        return 0  # the perturbed ray misses a face seen edge-on
    side = _sign(nx)
    for u, v in ((a, b), (b, c), (c, a)):
        # (v - u) x (p' - u) in (y, z), expanded in powers of e.
        for term in (
            (v[1] - u[1]) * (p[2] - u[2]) - (v[2] - u[2]) * (p[1] - u[1]),
            -(v[2] - u[2]),
            v[1] - u[1],
        ):
            if term != 0:
                if _sign(term) != side:
                    return 0
                break
    # Inside the projection: the ray meets the face's plane ahead of p?
    n = (nx, (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
         (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))  # fmt: skip
    ahead = sum(n[k] * (a[k] - p[k]) for k in range(3))
    if ahead == 0:
        raise ValueError(f"point {[float(x) for x in p]} is on the surface")
    return side if _sign(ahead) == side else 0


def winding_numbers(vertices: Any, faces: Any, points: Any) -> np.ndarray:
    """The exact winding numbers of a closed mesh at points off its surface, ``(n,)`` int.

    Counts the signed crossings of a ray from each point along +x (faces
    whose normal points along the ray count +1), symbolically perturbed so
    that it never meets an edge or a vertex, in rational arithmetic.  Right
    only where every edge is run equally often both ways (the mesh is closed
    by position); raises ``ValueError`` for a point on the surface.

    A float filter with Shewchuk's error bounds (rounded up) decides most
    (point, face) pairs; the others are decided exactly.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    tri = v[f]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    out = np.zeros(len(p), dtype=np.int64)
    rational = {}

    def exact(x):
        key = x.tobytes()
        if key not in rational:
            rational[key] = tuple(Fraction(float(t)) for t in x)
        return rational[key]

    u = 2.0**-53
    lo, hi, far = tri[:, :, 1:].min(axis=1), tri[:, :, 1:].max(axis=1), tri[:, :, 0].max(axis=1)
    for i, q in enumerate(p):
        # Candidate faces: the ray's line passes within the projection's box.
        near = np.flatnonzero(
            (lo[:, 0] <= q[1]) & (q[1] <= hi[:, 0]) & (lo[:, 1] <= q[2]) & (q[2] <= hi[:, 1]) & (far >= q[0])
        )
        if len(near) == 0:
            continue
        aa, bb, cc = a[near], b[near], c[near]
        t1 = (bb[:, 1] - aa[:, 1]) * (cc[:, 2] - aa[:, 2])
        t2 = (bb[:, 2] - aa[:, 2]) * (cc[:, 1] - aa[:, 1])
        nx = t1 - t2
        doubt = np.abs(nx) <= 4 * u * (np.abs(t1) + np.abs(t2))
        sides = np.sign(nx)
        inside = np.ones(len(near), dtype=bool)
        for s_, e_ in ((aa, bb), (bb, cc), (cc, aa)):
            e1 = (e_[:, 1] - s_[:, 1]) * (q[2] - s_[:, 2])
            e2 = (e_[:, 2] - s_[:, 2]) * (q[1] - s_[:, 1])
            d = e1 - e2
            unsure = np.abs(d) <= 4 * u * (np.abs(e1) + np.abs(e2))
            doubt |= unsure
            inside &= unsure | (np.sign(d) == sides)
        # Where the projection holds the ray: ahead of the point?
        ad, bd, cd = aa - q, bb - q, cc - q
        m1 = bd[:, 1] * cd[:, 2] - bd[:, 2] * cd[:, 1]
        m2 = bd[:, 2] * cd[:, 0] - bd[:, 0] * cd[:, 2]
        m3 = bd[:, 0] * cd[:, 1] - bd[:, 1] * cd[:, 0]
        det = ad[:, 0] * m1 + ad[:, 1] * m2 + ad[:, 2] * m3
        perm = (np.abs(ad[:, 0]) * (np.abs(bd[:, 1] * cd[:, 2]) + np.abs(bd[:, 2] * cd[:, 1]))
                + np.abs(ad[:, 1]) * (np.abs(bd[:, 2] * cd[:, 0]) + np.abs(bd[:, 0] * cd[:, 2]))
                + np.abs(ad[:, 2]) * (np.abs(bd[:, 0] * cd[:, 1]) + np.abs(bd[:, 1] * cd[:, 0])))  # fmt: skip
        doubt |= inside & (np.abs(det) <= 16 * u * perm)
        # det = (a - q) . ((b - q) x (c - q)) = n . (a - q): ahead where it has the normal's x sign.
        sure = ~doubt
        out[i] += int(np.sum(np.where(sure & inside & (np.sign(det) == sides), sides, 0)))
        qq = exact(q)
        for k in near[doubt]:
            out[i] += _crossing(exact(a[k]), exact(b[k]), exact(c[k]), qq)
    return out
