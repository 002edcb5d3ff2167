"""Whether a triangle mesh bounds a solid: checked once per mesh, for the sign of its distance.

The pseudonormal sign of :meth:`proximity.TriangleMesh.signed_distance`
is right on every point of a mesh that bounds a solid and can be wrong on
others (overlapping or nested shells, self-intersections, sheets inside).
The checks, in order, each a condition of the next:

Closed
    By position: vertices with equal coordinates are one vertex (a mesh
    whose vertices are split along texture seams is closed), and every
    edge is run as often from one end to the other as back (faces with a
    repeated vertex, after merging, run none).  Then the winding number is
    an integer off the surface.  A mesh that is not closed has no inside
    that every point can be given: ``sign="auto"`` refuses it.
Manifold
    Every edge of the faces with three distinct vertices is run by exactly
    two faces, once each way, and the faces around each vertex form a
    single fan.  The pseudonormal tables need it.
Shells
    The faces connected through edges.  The winding number of the whole
    mesh at a vertex of a shell, with the faces at that vertex left out, is
    ``k + s``: ``k`` the integer winding number of the other shells there,
    ``s`` the shell's own, strictly between 0 and 1 (-1 and 0 for a shell
    facing inwards).  The regions' winding numbers are all 0 or 1 exactly
    when every shell's value lies in ``(0, 1)``; all in ``(-1, 0)`` is a
    solid whose faces all point inwards (``inverted``), whose pseudonormal
    signs are flipped.  Decided with :mod:`proximity.signs.winding`'s bound.
Not self-intersecting
    No two faces meet except at the vertices and edges they share (by
    position): every pair of faces whose boxes overlap, found down the
    winding number's hierarchy, is tested with exact orientation
    predicates (:mod:`proximity.numerics.orient`).  Faces of zero area are left
    out: they contribute nothing to the winding number, and the
    pseudonormal test leaves the points they are nearest to the winding
    number.

A mesh that passes all four bounds a solid whose inside is where the
winding number is 1 (or -1, inverted) and nowhere else.
"""

import dataclasses

import numpy as np
from numba import prange

from ..numerics.orient import DOUBT, orient2d, orient3d, warm
from ..runtime import threads
from ..runtime.jit import inline, kernel, part
from .topology import merged_faces, unbalanced


@dataclasses.dataclass(frozen=True)
class Validity:
    """Whether a mesh bounds a solid, as :attr:`proximity.TriangleMesh.validity` reports it.

    Attributes
    ----------
    closed : bool
        Closed by position: every edge run equally often both ways, with
        coincident vertices taken as one.
    solid : bool
        Closed, manifold, without self-intersections, and its shells
        neither nested with the same orientation nor overlapping: it
        bounds a solid, and the pseudonormal sign is right everywhere.
    inverted : bool
        A solid whose faces all point inwards.
    shells : int
        Number of edge-connected shells (0 where the mesh is not manifold).
    reason : str or None
        Why the mesh is not a solid, naming faces or an edge; None for a solid.
    """

    closed: bool
    solid: bool
    inverted: bool
    shells: int
    reason: str | None


@kernel()
def _fans_and_shells(faces, twin, live):
    """``(vertex with more than one fan or -1, shell label of each face or -1)``."""
    n_faces = faces.shape[0]
    # Shells: union-find over the faces, joined across each edge.
    parent = np.arange(n_faces)
    for s in range(3 * n_faces):
        t = twin[s]
        if t < 0:
            continue
        x, y = s // 3, t // 3
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        while parent[y] != y:
            parent[y] = parent[parent[y]]
            y = parent[y]
        if x != y:
            parent[max(x, y)] = min(x, y)
    label = np.full(n_faces, -1, np.int64)
    n_shells = 0
    root_label = np.full(n_faces, -1, np.int64)
    for f in range(n_faces):
        if not live[f]:
            continue
        x = f
        while parent[x] != x:
            x = parent[x]
        if root_label[x] < 0:
            root_label[x] = n_shells
            n_shells += 1
        label[f] = root_label[x]
    # Fans: walk around each vertex from corner to corner across the edges.
    n_vertices = 0
    for f in range(n_faces):
        for k in range(3):
            n_vertices = max(n_vertices, faces[f, k] + 1)
    fans = np.zeros(n_vertices, np.int64)
    seen = np.zeros(3 * n_faces, np.bool_)
    for c in range(3 * n_faces):
        if seen[c] or not live[c // 3]:
            continue
        fans[faces[c // 3, c % 3]] += 1
        d = c
        while not seen[d]:
            seen[d] = True
            # The side leaving this corner's vertex, across to its twin, which
            # ends at the vertex: the next corner is that side's end.
            t = twin[d]
            d = 3 * (t // 3) + (t % 3 + 1) % 3
    for v in range(n_vertices):
        if fans[v] > 1:
            return v, label
    return -1, label


# -- pairs of faces ---------------------------------------------------------------------


@part
def _axis(a, b, c):
    """An axis whose projection keeps triangle ``abc`` non-degenerate (exactly), or -1."""
    ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    nx, ny, nz = abs(uy * vz - uz * vy), abs(uz * vx - ux * vz), abs(ux * vy - uy * vx)
    first = 0 if nx >= ny and nx >= nz else (1 if ny >= nz else 2)
    for t in range(3):
        axis = (first + t) % 3
        s = _o2(a, b, c, axis)
        if s == 1 or s == -1:
            return axis
    return -1


@inline
def _uv(p, axis):
    if axis == 0:
        return p[1], p[2]
    if axis == 1:
        return p[2], p[0]
    return p[0], p[1]


@inline
def _o2(a, b, c, axis):
    au, av = _uv(a, axis)
    bu, bv = _uv(b, axis)
    cu, cv = _uv(c, axis)
    return orient2d(au, av, bu, bv, cu, cv)


@inline
def _o3(a, b, c, d):
    return orient3d(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2])


@inline
def _between(p, q, x):
    """Whether ``x``, collinear with ``p`` and ``q``, lies on the closed segment ``pq``."""
    for i in range(3):
        if x[i] < min(p[i], q[i]) or x[i] > max(p[i], q[i]):
            return False
    return True


@part
def _segments_2d(p, q, a, b, axis):
    """Whether closed segments ``pq`` and ``ab`` meet (coplanar, projected on ``axis``): 0, 1 or DOUBT."""
    d1, d2 = _o2(p, q, a, axis), _o2(p, q, b, axis)
    d3, d4 = _o2(a, b, p, axis), _o2(a, b, q, axis)
    if d1 == DOUBT or d2 == DOUBT or d3 == DOUBT or d4 == DOUBT:
        return DOUBT
    if d1 * d2 < 0 and d3 * d4 < 0:
        return 1
    if (d1 == 0 and _between(p, q, a)) or (d2 == 0 and _between(p, q, b)):
        return 1
    if (d3 == 0 and _between(a, b, p)) or (d4 == 0 and _between(a, b, q)):
        return 1
    return 0


@part
def _inside_2d(p, a, b, c, axis):
    """Whether ``p`` is in the closed triangle ``abc`` (coplanar, projected on ``axis``)."""
    s1, s2, s3 = _o2(a, b, p, axis), _o2(b, c, p, axis), _o2(c, a, p, axis)
    if s1 == DOUBT or s2 == DOUBT or s3 == DOUBT:
        return DOUBT
    return 1 if (s1 >= 0 and s2 >= 0 and s3 >= 0) or (s1 <= 0 and s2 <= 0 and s3 <= 0) else 0


@part
def _segment_triangle(p, q, a, b, c):
    """Whether the closed segment ``pq`` meets the closed triangle ``abc``: 0, 1 or DOUBT."""
    sp, sq = _o3(a, b, c, p), _o3(a, b, c, q)
    if sp == DOUBT or sq == DOUBT:
        return DOUBT
    if sp * sq > 0:
        return 0
    if sp == 0 and sq == 0:
        axis = _axis(a, b, c)
        if axis < 0:
            return DOUBT
        worst = 0
        for r in (
            _inside_2d(p, a, b, c, axis),
            _inside_2d(q, a, b, c, axis),
            _segments_2d(p, q, a, b, axis),
            _segments_2d(p, q, b, c, axis),
            _segments_2d(p, q, c, a, axis),
        ):
            if r == 1:
                return 1
            worst = max(worst, r)
        return worst
    # The line crosses the plane once, in the segment: through the triangle
    # when it passes on the same side of (or on) every edge.
    s1, s2, s3 = _o3(p, q, a, b), _o3(p, q, b, c), _o3(p, q, c, a)
    if s1 == DOUBT or s2 == DOUBT or s3 == DOUBT:
        return DOUBT
    return 1 if (s1 >= 0 and s2 >= 0 and s3 >= 0) or (s1 <= 0 and s2 <= 0 and s3 <= 0) else 0


@part
def _in_cone(v, d, e, x):
    """Whether ``x``, coplanar with triangle ``vde``, lies beyond ``v`` in its closed angle at ``v``."""
    axis = _axis(v, d, e)
    if axis < 0:
        return DOUBT
    o = _o2(v, d, e, axis)
    s1, s2 = _o2(v, d, x, axis), _o2(v, x, e, axis)
    if s1 == DOUBT or s2 == DOUBT:
        return DOUBT
    return 1 if o * s1 >= 0 and o * s2 >= 0 else 0


@inline
def _point(tri, i, k):
    return tri[i, 3 * k], tri[i, 3 * k + 1], tri[i, 3 * k + 2]


@part
def _glued(tri, zero, i, j):
    """0 where rows ``i`` and ``j`` have a side each on the same face of zero area (an edge
    split by a collinear vertex on one side, closed by that face) and are not coplanar,
    else -1 (or DOUBT).  Both then contain a segment of that face's line, and their
    planes meet on that line alone: so do the faces."""
    for ki in range(3):
        if zero[i, ki] < 0:
            continue
        for kj in range(3):
            if zero[j, kj] == zero[i, ki]:
                p, q, r = _point(tri, i, ki), _point(tri, i, (ki + 1) % 3), _point(tri, i, (ki + 2) % 3)
                o = _o3(p, q, r, _point(tri, j, (kj + 2) % 3))
                return -1 if o == 0 else (DOUBT if o == DOUBT else 0)
    return -1


@part
def _pair(tri, ids, zero, i, j):
    """Whether faces (rows) ``i`` and ``j`` meet beyond the vertices they share: 0, 1 or DOUBT.

    ``zero[i, k]`` is the face of zero area across side ``k`` of row ``i``, or -1."""
    glued = _glued(tri, zero, i, j)
    if glued >= 0:
        return glued
    shared = 0
    si, sj = -1, -1
    for a in range(3):
        for b in range(3):
            if ids[i, a] == ids[j, b]:
                shared += 1
                si, sj = a, b
    if shared >= 3:
        return 1  # the same three vertices: the faces coincide
    if shared == 2:
        # Edge (p, q) shared; r and s the third vertices.  They overlap
        # only when coplanar with r and s on the same side of the edge.
        ri, rj = 0, 0
        for a in range(3):
            if ids[i, a] != ids[j, 0] and ids[i, a] != ids[j, 1] and ids[i, a] != ids[j, 2]:
                ri = a
            if ids[j, a] != ids[i, 0] and ids[j, a] != ids[i, 1] and ids[j, a] != ids[i, 2]:
                rj = a
        p, q, r = _point(tri, i, (ri + 1) % 3), _point(tri, i, (ri + 2) % 3), _point(tri, i, ri)
        s = _point(tri, j, rj)
        o = _o3(p, q, r, s)
        if o != 0:
            return DOUBT if o == DOUBT else 0
        axis = _axis(p, q, r)
        if axis < 0:
            return DOUBT
        s1, s2 = _o2(p, q, r, axis), _o2(p, q, s, axis)
        if s2 == DOUBT:
            return DOUBT
        return 1 if s1 * s2 > 0 else 0
    a0, a1, a2 = _point(tri, i, 0), _point(tri, i, 1), _point(tri, i, 2)
    b0, b1, b2 = _point(tri, j, 0), _point(tri, j, 1), _point(tri, j, 2)
    worst = 0
    if shared == 1:
        v = _point(tri, i, si)
        b, c = _point(tri, i, (si + 1) % 3), _point(tri, i, (si + 2) % 3)
        d, e = _point(tri, j, (sj + 1) % 3), _point(tri, j, (sj + 2) % 3)
        # Away from v: the edge opposite v of one meets the other.
        for r in (_segment_triangle(b, c, v, d, e), _segment_triangle(d, e, v, b, c)):
            if r == 1:
                return 1
            worst = max(worst, r)
        # At v: an edge from v lies in the other's plane and enters it.
        for x, y, z, w in ((b, v, d, e), (c, v, d, e), (d, v, b, c), (e, v, b, c)):
            o = _o3(y, z, w, x)
            if o == DOUBT:
                worst = DOUBT
            elif o == 0:
                r = _in_cone(y, z, w, x)
                if r == 1:
                    return 1
                worst = max(worst, r)
        return worst
    for r in (
        _segment_triangle(a0, a1, b0, b1, b2),
        _segment_triangle(a1, a2, b0, b1, b2),
        _segment_triangle(a2, a0, b0, b1, b2),
        _segment_triangle(b0, b1, a0, a1, a2),
        _segment_triangle(b1, b2, a0, a1, a2),
        _segment_triangle(b2, b0, a0, a1, a2),
    ):
        if r == 1:
            return 1
        worst = max(worst, r)
    return worst


BLOCK = 64


@kernel(parallel=True)
def _intersections(tri, ids, zero, live, boxes, child, count, hit, doubt):
    """For each live row ``i``: a later row that meets it (``hit``), or whose test was
    undecided (``doubt``), found down the hierarchy; -1 where none."""
    n = tri.shape[0]
    m = child.shape[0]
    for block in prange((n + BLOCK - 1) // BLOCK):
        stack = np.empty(m + 1, np.int64)
        for i in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
            hit[i] = -1
            doubt[i] = -1
            if not live[i]:
                continue
            lo0 = min(tri[i, 0], tri[i, 3], tri[i, 6])
            lo1 = min(tri[i, 1], tri[i, 4], tri[i, 7])
            lo2 = min(tri[i, 2], tri[i, 5], tri[i, 8])
            hi0 = max(tri[i, 0], tri[i, 3], tri[i, 6])
            hi1 = max(tri[i, 1], tri[i, 4], tri[i, 7])
            hi2 = max(tri[i, 2], tri[i, 5], tri[i, 8])
            stack[0] = 0
            sp = 1
            while sp > 0 and hit[i] < 0:
                sp -= 1
                k = stack[sp]
                if (
                    boxes[k, 0] > hi0 or boxes[k, 1] > hi1 or boxes[k, 2] > hi2
                    or boxes[k, 3] < lo0 or boxes[k, 4] < lo1 or boxes[k, 5] < lo2
                ):  # fmt: skip
                    continue
                if count[k] == 0:
                    stack[sp] = child[k]
                    stack[sp + 1] = child[k] + 1
                    sp += 2
                    continue
                for j in range(max(child[k], i + 1), child[k] + count[k]):
                    if not live[j]:
                        continue
                    apart = False
                    for a in range(3):
                        low = min(tri[j, a], tri[j, 3 + a], tri[j, 6 + a])
                        high = max(tri[j, a], tri[j, 3 + a], tri[j, 6 + a])
                        apart = apart or low > (hi0, hi1, hi2)[a] or high < (lo0, lo1, lo2)[a]
                    if apart:
                        continue
                    r = _pair(tri, ids, zero, i, j)
                    if r == 1:
                        hit[i] = j
                        break
                    if r == DOUBT and doubt[i] < 0:
                        doubt[i] = j


# -- the check ------------------------------------------------------------------------


def _zero_neighbours(h, twin, live, n_faces):
    """``(n, 3)``: for each stored row's side, the face of zero area across it, or -1."""
    row = np.full(n_faces, -1, np.int64)
    row[h.index] = np.arange(len(h.index))
    area = np.zeros(n_faces, dtype=bool)
    area[h.index] = h.weight > 0
    zero = np.full((len(h.index), 3), -1, np.int64)
    for z in np.flatnonzero(live & ~area):
        for side in range(3 * z, 3 * z + 3):
            t = twin[side]
            if t >= 0 and row[t // 3] >= 0:
                zero[row[t // 3], t % 3] = z
    return zero


def check(mesh, hierarchy):
    """``(Validity, merged faces)`` of ``mesh``, given its :class:`proximity.signs.winding.Hierarchy`."""
    from . import signed, winding

    faces = merged_faces(mesh.vertices, mesh.faces)
    reason = unbalanced(faces)
    if reason is not None:
        return Validity(False, False, False, 0, f"it is not closed: {reason}"), faces
    twin, collapsed, reason = signed.edge_twins(faces, len(mesh.vertices))
    if reason is not None:
        return Validity(True, False, False, 0, f"it is not a manifold: {reason}"), faces
    live = ~collapsed
    with threads.kernel():
        vertex, label = _fans_and_shells(faces, twin, live)
    if vertex >= 0:
        return Validity(True, False, False, 0, f"it is not a manifold: the faces around vertex {vertex} "
                        "form more than one fan"), faces  # fmt: skip
    n_shells = int(label.max()) + 1 if live.any() else 0

    # Self-intersections, down the hierarchy.
    h = hierarchy
    ids = faces[h.index]
    live_rows = h.weight > 0  # a face with a repeated vertex has zero area
    zero = _zero_neighbours(h, twin, live, len(faces))
    with threads.kernel():
        hit = np.empty(len(ids), np.int64)
        doubt = np.empty(len(ids), np.int64)
        warm()
        _intersections(h.triangles, ids, zero, live_rows, h.boxes, h.child, h.count, hit, doubt)
    rows = np.flatnonzero(hit >= 0)
    if len(rows):
        i, j = sorted((int(h.index[rows[0]]), int(h.index[hit[rows[0]]])))
        return Validity(True, False, False, n_shells, f"it intersects itself: faces {i} and {j} meet "
                        "away from the vertices they share"), faces  # fmt: skip
    rows = np.flatnonzero(doubt >= 0)
    if len(rows):
        i, j = sorted((int(h.index[rows[0]]), int(h.index[doubt[rows[0]]])))
        return Validity(True, False, False, n_shells, f"whether faces {i} and {j} meet could not be "
                        "decided (vertices closer than 2^-300 of the mesh's size)"), faces  # fmt: skip

    # Shells: the winding number at a vertex of a face of nonzero area of each.
    area = np.zeros(len(faces), dtype=bool)
    area[h.index] = h.weight > 0
    shell_of = np.where(area, label, -1)
    order = np.argsort(shell_of, kind="stable")
    starts = np.searchsorted(shell_of[order], np.arange(n_shells))
    if n_shells == 0 or (starts >= len(order)).any() or (shell_of[order[np.minimum(starts, len(order) - 1)]]
                                                         != np.arange(n_shells)).any():  # fmt: skip
        return Validity(True, False, False, n_shells, "a shell has no face of nonzero area"), faces
    at = mesh.vertices[faces[order[starts], 0]]
    w, e = winding.numbers(h, at, rule=winding.FRACTIONAL)
    low, high = np.floor(w - e), np.floor(w + e)
    decided = (low == high) & (w - e > low)
    if not decided.all():
        s = int(np.flatnonzero(~decided)[0])
        return Validity(True, False, False, n_shells, f"the nesting of the shell of face {order[starts[s]]} "
                        "could not be decided"), faces  # fmt: skip
    if (low == 0).all():
        inverted = False
    elif (low == -1).all():
        inverted = True
    else:
        odd = np.flatnonzero((low != 0) & (low != -1))
        s = int(odd[0]) if len(odd) else int(np.flatnonzero(low == -1)[0])
        return Validity(True, False, False, n_shells, (
            f"its shells are nested or overlap: the shell of face {order[starts[s]]} lies inside another "
            "that faces the same way, or the shells face opposite ways"
        )), faces  # fmt: skip

    return Validity(True, True, inverted, n_shells, None), faces
