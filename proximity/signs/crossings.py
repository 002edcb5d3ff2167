"""The winding number of a mesh closed by position, exactly: signed crossings of a ray.

On a mesh whose every edge is run equally often both ways, the winding
number at a point off the surface is an integer: the signed number of times
any ray from the point crosses the surface (+1 where the face's normal
points along the ray).  The ray runs along the mesh's thinnest axis (fewest
nodes of the hierarchy to visit), perturbed symbolically to ``P + (0, e,
e^2)`` in its frame so that it meets no edge and no vertex: where an
orientation in the plane across the ray is exactly 0, the first nonzero
coefficient of the perturbation decides.  Each crossing is decided by the
exact predicates of :mod:`proximity.numerics.orient`, so the count is exact; a point
on a face (where the perturbed ray has a side and the point none) or whose
predicates underflow is left undecided, for the far-field series of
:mod:`proximity.signs.winding` to bound.  The faces of zero area count nothing
(seen edge-on from every direction).
"""

import math

import numpy as np
from numba import prange

from ..numerics.orient import DOUBT, orient2d, orient3d, warm
from ..runtime import threads
from ..runtime.jit import inline, kernel, part
from .winding import BLOCK, _visiting_order


@inline
def _edge_side(sv, sw, ev, ew, pv, pw):
    """Side of the perturbed point ``(pv + e, pw + e^2)`` of the edge ``s -> e`` in the
    plane across the ray (-1, 1, or DOUBT): its orientation, and where that is exactly 0
    the first nonzero coefficient of the perturbation."""
    d = orient2d(sv, sw, ev, ew, pv, pw)
    if d != 0:
        return d
    if ew != sw:
        return 1 if sw > ew else -1
    return 1 if ev > sv else -1


@part
def _on_face(u0, v0, w0, u1, v1, w1, u2, v2, w2, p0, p1, p2):
    """Whether ``P`` may lie on the closed face (True where undecided): in its plane, and
    in the triangle projected on the first coordinate plane where it has an area."""
    o = orient3d(u0, v0, w0, u1, v1, w1, u2, v2, w2, p0, p1, p2)
    if o != 0:
        return o == DOUBT
    for plane in range(3):
        if plane == 0:
            x0, y0, x1, y1, x2, y2, px, py = v0, w0, v1, w1, v2, w2, p1, p2
        elif plane == 1:
            x0, y0, x1, y1, x2, y2, px, py = w0, u0, w1, u1, w2, u2, p2, p0
        else:
            x0, y0, x1, y1, x2, y2, px, py = u0, v0, u1, v1, u2, v2, p0, p1
        area = orient2d(x0, y0, x1, y1, x2, y2)
        if area == 0:
            continue
        s1 = orient2d(x0, y0, x1, y1, px, py)
        s2 = orient2d(x1, y1, x2, y2, px, py)
        s3 = orient2d(x2, y2, x0, y0, px, py)
        if area == DOUBT or s1 == DOUBT or s2 == DOUBT or s3 == DOUBT:
            return True
        return (s1 >= 0 and s2 >= 0 and s3 >= 0) or (s1 <= 0 and s2 <= 0 and s3 <= 0)
    return False  # no area in any projection: a face of zero area, which has no weight


@inline
def _crossing(tri, j, a0, a1, a2, p0, p1, p2):
    """The signed crossing of row ``j`` by the ray from ``P`` along axis ``a0`` (coordinates
    in the cyclic order ``a0, a1, a2``), perturbed off every edge and vertex: +1 or -1
    where it passes through the face (the face's normal along or against the ray), 0
    where not, DOUBT where undecided: ``P`` on the face (where the perturbed ray has a
    side and ``P`` none), or underflow."""
    u0, v0, w0 = tri[j, a0], tri[j, a1], tri[j, a2]
    u1, v1, w1 = tri[j, 3 + a0], tri[j, 3 + a1], tri[j, 3 + a2]
    u2, v2, w2 = tri[j, 6 + a0], tri[j, 6 + a1], tri[j, 6 + a2]
    if max(u0, u1, u2) < p0:
        return 0
    if max(v0, v1, v2) < p1 or min(v0, v1, v2) > p1 or max(w0, w1, w2) < p2 or min(w0, w1, w2) > p2:
        return 0
    # P on the face: the perturbed ray has a side, P has none.
    if min(u0, u1, u2) <= p0 and _on_face(u0, v0, w0, u1, v1, w1, u2, v2, w2, p0, p1, p2):
        return DOUBT
    side = orient2d(v0, w0, v1, w1, v2, w2)
    if side == 0:
        return 0  # seen edge-on: the perturbed ray misses it
    if side == DOUBT:
        return DOUBT
    for k in range(3):
        if k == 0:
            s = _edge_side(v0, w0, v1, w1, p1, p2)
        elif k == 1:
            s = _edge_side(v1, w1, v2, w2, p1, p2)
        else:
            s = _edge_side(v2, w2, v0, w0, p1, p2)
        if s == DOUBT:
            return DOUBT
        if s != side:
            return 0
    # The ray meets the face's plane ahead of P where (a - P) . n has the sign of n's
    # component along the ray (cyclic coordinates keep orientations).
    ahead = orient3d(u0, v0, w0, u1, v1, w1, u2, v2, w2, p0, p1, p2)
    if ahead == 0 or ahead == DOUBT:
        return DOUBT
    return side if ahead == side else 0


@kernel(parallel=True)
def _crossings(boxes, child, count, tri, weight, points, order, scale, more, axis, w_out):
    """The signed crossings of each point's ray; NaN where a crossing is undecided or the
    point is not finite."""
    n = points.shape[0]
    m = child.shape[0]
    a0, a1, a2 = axis, (axis + 1) % 3, (axis + 2) % 3
    for block in prange((n + BLOCK - 1) // BLOCK):
        stack = np.empty(m + 1, np.int64)
        for o in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
            i = order[o]
            p0 = points[i, a0] * scale * more
            p1 = points[i, a1] * scale * more
            p2 = points[i, a2] * scale * more
            if not (math.isfinite(p0) and math.isfinite(p1) and math.isfinite(p2)):
                w_out[i] = math.nan
                continue
            total = 0.0
            stack[0] = 0
            sp = 1
            while sp > 0:
                sp -= 1
                k = stack[sp]
                if (
                    boxes[k, 3 + a0] < p0
                    or boxes[k, a1] > p1 or boxes[k, 3 + a1] < p1
                    or boxes[k, a2] > p2 or boxes[k, 3 + a2] < p2
                ):  # fmt: skip
                    continue
                if count[k] == 0:
                    stack[sp] = child[k]
                    stack[sp + 1] = child[k] + 1
                    sp += 2
                    continue
                for j in range(child[k], child[k] + count[k]):
                    if weight[j] == 0.0:
                        continue
                    c = _crossing(tri, j, a0, a1, a2, p0, p1, p2)
                    if c == DOUBT:
                        total = math.nan
                        sp = 0
                        break
                    total += weight[j] * c
            w_out[i] = total


def crossings(hierarchy, points):
    """The exact winding number at each point of a mesh closed by position, ``(n,)`` float64.

    The signed number of times a ray from the point along the mesh's
    thinnest axis crosses the surface, symbolically perturbed off every edge
    and vertex (``P + (0, e, e^2)`` in the ray's frame), with the exact
    predicates of :mod:`proximity.numerics.orient`: on a mesh whose every edge is
    run equally often both ways, the winding number, exactly.  NaN where a
    crossing cannot be decided (the point on the surface, or underflow) or
    the point is not finite.  Not for meshes that are not closed (see
    :attr:`Hierarchy.integral`).
    """
    h = hierarchy
    points = np.ascontiguousarray(points, dtype=np.float64)
    w = np.empty(len(points))
    if len(points):
        with threads.kernel():
            warm()
            _crossings(h.boxes, h.child, h.count, h.triangles, h.weight, points, _visiting_order(points),
                       *h.scale, h.axis, w)  # fmt: skip
    return w
