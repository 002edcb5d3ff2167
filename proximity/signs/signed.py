"""Inside or outside a closed mesh: the sign of :meth:`TriangleMesh.signed_distance`.

Two tests, used together:

* The **angle-weighted pseudonormal** (J. A. Bærentzen and H. Aanæs, *Signed
  distance computation using the angle weighted pseudonormal*, IEEE TVCG
  11(3), 2005).  Each face, edge and vertex of a closed, consistently
  oriented surface has a normal: the face's unit normal; the sum of the
  two faces' unit normals at an edge; at a vertex, the sum of its faces'
  unit normals, each weighted by the face's angle there.  For a point ``P``
  off the surface whose closest point ``C`` lies on a feature with normal
  ``N``, ``(P - C) . N`` is positive outside and negative inside.  It costs
  O(1) per point once the closest point (and its face and feature, which
  the query reports) is known.  ``C`` is not needed: any vertex ``V`` of
  the feature gives the same product, as ``C - V`` runs along the feature
  and ``N`` is normal to it, and ``P - V`` is computed more accurately than
  ``P - C``.
* The **winding number** (:mod:`proximity.signs.winding`): exact signed ray
  crossings on a closed mesh, and a hierarchy of far-field series with a
  rigorous bound on any mesh; inside means nonzero (``|w| > 1/2``).

The pseudonormal decides every point whose product clears its margin of
rounding errors (see :func:`inside`); the winding number decides the rest:
points within rounding error of the surface's tangent plane, and points
whose closest feature touches a degenerate face (zero area), whose normal
is undefined and whose neighbours' normals do not describe the surface
there.  Faces whose vertex indices repeat (a collapsed face) are left out
of the surface's topology and normals altogether: the faces around them
close the surface without them.  The tables are built on the mesh's faces
with coincident vertices merged (:func:`proximity.signs.topology.merged_faces`),
and are used only where :mod:`proximity.signs.validity` finds that the mesh
bounds a solid (flipped where its faces point inwards).
"""

import warnings

import numba
import numpy as np

from ..features import EDGE01, FACE, VERTEX0
from ..runtime import threads

EPS = 2.0**-52

#: Margin of the pseudonormal test for a wrong closest feature: the reported
#: feature may be a neighbour of the exact one where the point is within
#: rounding error of where they meet, and the test of a neighbour is off
#: by at most the distance to that boundary.  Relative to the point's
#: distance to the feature's vertex plus the face's longest edge.
MARGIN = 2.0**-40


class Signs:
    """What the sign test needs of one mesh, computed once.

    Attributes
    ----------
    closed : bool
        Every edge (of faces with three distinct vertex indices) is shared
        by exactly two faces that run it in opposite directions.
    reason : str or None
        Why the mesh is not closed, naming an edge and a face.
    table : ndarray of float64, shape ``(V + 4 F + 1, 4)``
        Unit pseudonormal and the bound of its direction's error (radians),
        per vertex, per face side (``3 f + k``, the edge from vertex ``k``
        of face ``f`` to the next), per face, and a last row that decides
        nothing (an infinite bound).
    edge_row : ndarray of int64, shape ``(3 F,)``
        The row of ``table`` of each face side: its own, or for a side of a
        collapsed face, the row of the same edge in a face that is not, or
        of its vertex where the side is a point.
    longest : ndarray of float64, shape ``(F,)``
        Each face's longest edge.
    """

    __slots__ = ("closed", "reason", "table", "edge_row", "longest")

    def __init__(self, vertices, faces):
        n_vertices = len(vertices)
        start = faces.reshape(-1)  # side 3 f + k runs from vertex k of face f to the next
        end = faces[:, [1, 2, 0]].reshape(-1)
        twin, collapsed, self.reason = edge_twins(faces, n_vertices)
        self.closed = self.reason is None
        self.table = self.edge_row = self.longest = None
        if self.closed:
            live = np.flatnonzero(~np.repeat(collapsed, 3))
            key = start[live] * n_vertices + end[live]
            order = np.argsort(key, kind="stable")
            self._normals(vertices, faces, collapsed, twin)
            self._redirect(collapsed, start, end, key[order], live[order], n_vertices)

    def _normals(self, vertices, faces, collapsed, twin):
        n_vertices, n_faces = len(vertices), len(faces)
        tri = vertices[faces]
        e0 = tri[:, 1] - tri[:, 0]
        e1 = tri[:, 2] - tri[:, 1]
        e2 = tri[:, 0] - tri[:, 2]
        normal = np.cross(e2, e0)  # (V1 - V0) x (V2 - V0)
        length = np.sqrt(np.einsum("ij,ij->i", normal, normal))
        edges = np.sqrt(np.stack([np.einsum("ij,ij->i", e, e) for e in (e0, e1, e2)], axis=1))
        self.longest = edges.max(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            unit = np.where(length[:, None] > 0, normal / length[:, None], 0.0)
            # The cross product of the rounded edges is off by a few eps |e||e'|
            # in each component: its direction by that over its length.
            error = 16.0 * EPS * self.longest**2 / length + 4.0 * EPS
        # Every corner's angle, from |e x e'| (twice the area at each corner) and e . e'.
        dots = -np.stack([np.einsum("ij,ij->i", a, b) for a, b in ((e0, e2), (e1, e0), (e2, e1))], axis=1)
        angle = np.arctan2(length[:, None], dots)

        # Vertices: the angle-weighted sum, and the sum of each term's error
        # bound; a collapsed face adds nothing, a degenerate one an infinite error.
        corner = faces.reshape(-1)
        terms = (angle[:, :, None] * unit[:, None, :]).reshape(-1, 3)
        vertex = np.stack([np.bincount(corner, terms[:, c], n_vertices) for c in range(3)], axis=1)
        weight = np.where(collapsed[:, None], 0.0, (angle + 1.0) * error[:, None])
        vertex_error = np.bincount(corner, weight.reshape(-1), n_vertices)

        # Edges: the unit normals of the side's face and of its twin's.
        sides = np.arange(3 * n_faces)
        has_twin = twin >= 0
        other = np.where(has_twin, twin, sides) // 3
        edge = unit[sides // 3] + unit[other]
        edge_error = np.where(has_twin, 2.0 * (error[sides // 3] + error[other]), np.inf)

        table = np.empty((n_vertices + 4 * n_faces + 1, 4))
        for rows, vectors, errors in (
            (slice(0, n_vertices), vertex, vertex_error),
            (slice(n_vertices, n_vertices + 3 * n_faces), edge, edge_error),
            (slice(n_vertices + 3 * n_faces, -1), unit, error),
        ):
            norm = np.sqrt(np.einsum("ij,ij->i", vectors, vectors))
            with np.errstate(divide="ignore", invalid="ignore"):
                table[rows, :3] = np.where(norm[:, None] > 0, vectors / norm[:, None], 0.0)
                # A sum of unit vectors that nearly cancel has a direction no
                # better than its terms' errors over its length.
                table[rows, 3] = np.where(norm > 0, errors / norm + 4.0 * EPS, np.inf)
        table[-1] = (0.0, 0.0, 0.0, np.inf)
        self.table = table

    def _redirect(self, collapsed, start, end, keys, sorted_sides, n_vertices):
        """Each side's row of the table: its own; for a side of a collapsed face,
        the same edge's row in a live face, or its vertex's where the side is a point."""
        undecided = len(self.table) - 1
        edge_row = n_vertices + np.arange(len(start))
        dead = np.flatnonzero(np.repeat(collapsed, 3))
        a, b = start[dead], end[dead]
        found = np.full(len(dead), undecided)
        if len(keys):
            for key in (a * n_vertices + b, b * n_vertices + a):
                at = np.minimum(np.searchsorted(keys, key), len(keys) - 1)
                hit = (keys[at] == key) & (found == undecided)
                found[hit] = n_vertices + sorted_sides[at[hit]]
        found[a == b] = a[a == b]
        edge_row[dead] = found
        self.edge_row = edge_row


def edge_twins(faces, n_vertices):
    """``(twin side of each side or -1, collapsed faces, reason the surface is not closed or None)``.

    Side ``3 f + k`` runs from vertex ``k`` of face ``f`` to the next; faces
    with a repeated vertex index (collapsed) have no sides here.  Closed:
    every side has exactly one twin, the same edge run the other way.
    """
    start = faces.reshape(-1)
    end = faces[:, [1, 2, 0]].reshape(-1)
    collapsed = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    live = np.flatnonzero(~np.repeat(collapsed, 3))
    key = start[live] * n_vertices + end[live]
    order = np.argsort(key, kind="stable")
    keys, sorted_sides = key[order], live[order]
    twin = np.full(len(start), -1, dtype=np.int64)
    if len(keys) == 0:
        return twin, collapsed, None
    repeated = np.flatnonzero(keys[1:] == keys[:-1])
    if len(repeated):
        first, second = sorted_sides[repeated[0]], sorted_sides[repeated[0] + 1]
        a, b = int(start[first]), int(end[first])
        why = (
            f"faces {first // 3} and {second // 3} both run edge ({a}, {b}) from {a} to {b}: "
            "more than two faces meet there, or the faces' orientations disagree"
        )
        return twin, collapsed, why
    reverse = end[live] * n_vertices + start[live]
    at = np.minimum(np.searchsorted(keys, reverse), len(keys) - 1)
    missing = np.flatnonzero(keys[at] != reverse)
    if len(missing):
        side = live[missing[0]]
        a, b = int(start[side]), int(end[side])
        why = (
            f"edge ({a}, {b}) of face {side // 3} has no face running it from {b} to {a}: the surface "
            "has a boundary there (a hole), or the face on the other side has the opposite orientation"
        )
        return twin, collapsed, why
    twin[live] = sorted_sides[at]
    return twin, collapsed, None


def feature_rows(signs, faces, face, feature):
    """``(row of signs.table, anchor vertex)`` per query from its face and feature code."""
    n_vertices = len(signs.table) - 4 * len(faces) - 1
    k = feature.astype(np.int64)
    corner = np.where(k < EDGE01, k, np.where(k < FACE, k - EDGE01, 0))
    anchor = faces[face, corner]
    side = 3 * face + np.where((k >= EDGE01) & (k < FACE), k - EDGE01, 0)
    row = np.where(
        k < EDGE01, anchor, np.where(k < FACE, signs.edge_row[side], n_vertices + 3 * len(faces) + face)
    )
    # Features the mesh has none of (NONE, or a code that is not a triangle's) decide nothing.
    row = np.where((k >= VERTEX0) & (k <= FACE), row, len(signs.table) - 1)
    return row, anchor


def plan(state, sign, warn=True, stacklevel=4):
    """``(state, use_winding, proven)`` of a signed query with ``sign`` (validated) on a mesh of
    sign state ``state`` (its validity, pseudonormal tables and ``warned``; None for
    ``"winding"``): whether the winding number tells the sides, and whether a side the
    pseudonormal decides is proven (not on a mesh that is not a solid).  Raises where the sign
    cannot be had; with ``warn``, warns where the mesh is not a solid: at every query for
    ``"pseudonormal"``, whose sides can be wrong there, once per mesh for ``"auto"``, whose
    sides are right (the winding number's) but slower."""
    if sign == "winding":
        return None, True, True
    v = state.validity
    if not v.closed or (sign == "pseudonormal" and state.signs is None):
        kind = "closed mesh" if sign == "auto" else "closed manifold mesh"
        raise ValueError(
            f"signed distance with sign={sign!r} needs a {kind}, and {v.reason}.  "
            "sign='winding' works on any mesh"
        )
    if v.solid:
        return state, False, True
    use_winding = sign == "auto"
    if warn and (not use_winding or not state.warned):
        if use_winding:
            state.warned = True
            then = "the signs use the winding number instead (exact, slower)"
        else:
            then = ("the pseudonormal signs can be wrong, and are not certain; sign='auto' or 'winding' "
                    "are right")  # fmt: skip
        warnings.warn(f"this mesh does not bound a solid: {v.reason}; {then}", RuntimeWarning,
                      stacklevel=stacklevel)  # fmt: skip
    return state, use_winding, False  # the pseudonormal proves no side of a mesh that is not a solid


def inside(signs, vertices, faces, points, face, feature, distance, *, flip, winding, proven=True):
    """``(inside, certain)``: whether each point is inside the closed mesh, and proven so.

    ``face``, ``feature`` and ``distance`` are the query's answer for
    ``points`` (``(n, 3)``); ``faces`` the faces the tables were built on.
    The pseudonormal ``N`` of the closest feature decides where
    ``|(P - V) . N|`` exceeds its bound of error: ``E |P - V| + MARGIN (|P -
    V| + L)``, with ``E`` the bound on ``N``'s direction and ``L`` the face's
    longest edge; inside is ``(P - V) . N < 0``, or ``> 0`` where ``flip``
    (a solid whose faces point inwards).  ``winding(points, distance)``
    decides the other points at a positive distance, returning ``(inside,
    certain)``.  Rows at distance 0 or NaN are False in both.  With ``proven`` False (a mesh
    that is not a solid, where the pseudonormal's side can be wrong) no side it decides is
    certain.
    """
    out = np.zeros(len(points), dtype=bool)
    certain = np.zeros(len(points), dtype=bool)
    rows = np.flatnonzero(distance > 0)
    if len(rows) == 0:
        return out, certain
    f = face[rows]
    row, anchor = feature_rows(signs, faces, f, feature[rows])
    normal = signs.table[row]
    offset = points[rows] - vertices[anchor]
    dot = np.einsum("ij,ij->i", offset, normal[:, :3])
    reach = np.sqrt(np.einsum("ij,ij->i", offset, offset))
    with np.errstate(invalid="ignore"):  # inf * 0 where the point is on the anchor: undecided
        bound = normal[:, 3] * reach + MARGIN * (reach + signs.longest[f])
        decided = np.abs(dot) > bound
    out[rows[decided]] = (dot[decided] > 0.0) if flip else (dot[decided] < 0.0)
    certain[rows[decided]] = proven
    undecided = rows[~decided]
    if len(undecided):
        out[undecided], certain[undecided] = winding(points[undecided], distance[undecided])
    return out, certain


def winding_numbers(vertices, faces, points):
    """The generalized winding number of the mesh at each point, ``(n,)``: every face's solid
    angle, summed in floats without a bound (a reference for tests; the queries use
    :mod:`proximity.signs.winding`)."""
    from ..runtime.jit import kernel

    global _winding_kernel
    if _winding_kernel is None:
        _winding_kernel = kernel(parallel=True)(_winding)
    out = np.empty(len(points))
    with threads.kernel():
        _winding_kernel(vertices, faces, np.ascontiguousarray(points), out)
    return out


_winding_kernel = None


def _winding(vertices, faces, points, out):
    for i in numba.prange(len(points)):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        total = 0.0
        for f in range(len(faces)):
            a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
            ax, ay, az = vertices[a, 0] - px, vertices[a, 1] - py, vertices[a, 2] - pz
            bx, by, bz = vertices[b, 0] - px, vertices[b, 1] - py, vertices[b, 2] - pz
            cx, cy, cz = vertices[c, 0] - px, vertices[c, 1] - py, vertices[c, 2] - pz
            la = np.sqrt(ax * ax + ay * ay + az * az)
            lb = np.sqrt(bx * bx + by * by + bz * bz)
            lc = np.sqrt(cx * cx + cy * cy + cz * cz)
            det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
            den = (
                la * lb * lc
                + (ax * bx + ay * by + az * bz) * lc
                + (bx * cx + by * cy + bz * cz) * la
                + (cx * ax + cy * ay + cz * az) * lb
            )
            # Half the face's solid angle (van Oosterom and Strackee).
            total += np.arctan2(det, den)
        out[i] = total / (2.0 * np.pi)
