"""The generalized winding number of a mesh, over its hierarchy, with a bound on its error.

Two algorithms share one hierarchy: far-field series with a rigorous bound
(:func:`numbers`, here, any mesh), and exact signed ray crossings
(:func:`proximity.signs.crossings.crossings`, meshes closed by position).

The winding number of a triangle mesh at a point ``P`` is the sum of the
faces' solid angles seen from ``P`` over ``4 pi`` (A. Jacobson, L. Kavan and
O. Sorkine-Hornung, *Robust inside-outside segmentation using generalized
winding numbers*, ACM TOG 32(4), 2013): an integer off the surface of a
closed mesh (the number of times the surface wraps around ``P``), and a
smooth function with jumps of one across the faces elsewhere.  Inside means
``|w| > 1/2`` (the nonzero rule).

Far field
---------
G. Barill, N. Dickson, R. Schmidt, D. I. W. Levin and A. Jacobson, *Fast
winding numbers for soups and clouds*, ACM TOG 37(4), 2018, section 3.2:
the faces under a node of the hierarchy are, seen from far away, a dipole
layer, and their solid angle is a Taylor series in ``y = q - c`` (``q`` on a
face, ``c`` the node's centre) of the dipole kernel ``(q - P) / |q - P|^3``.
With ``r = c - P``, ``d = |r|`` and the node's moments ``N = sum a n``,
``M = sum a n g^T`` and ``T_ijk = sum a n_i S_jk`` (``a`` a face's area, ``n``
its unit normal, ``g`` its centroid and ``S`` its second moment of area per
area, both about ``c``), the solid angle to second order is

    r.N / d^3  +  tr(M) / d^3 - 3 r^T M r / d^5
    - 3 / (2 d^5) (2 r.t1 + r.t2)  +  15 / (2 d^7) T[r, r, r]

with ``t1_k = sum_i T_iik`` and ``t2_i = sum_j T_ijj``.

Error bound
-----------
The truncated series is the Legendre expansion of ``1 / |q - P|`` in
``rho = |y| < d`` through degree 3, and the gradient in ``y`` of its degree
``l`` term, ``rho^l P_l(cos) / d^(l+1)``, is at most ``sqrt(l (l + 1))
rho^(l-1) / d^(l+1)`` (from ``P_l^2 + (1 - t^2) P_l'^2 / (l (l + 1)) <= 1``).
Summing the dropped terms ``l >= 4`` for every face, with ``rho <= R`` (the
node's radius about ``c``) and ``X = R / d < 1``, the solid angle is off by at
most

    K / d^5  (4.5 / (1 - X) + X / (1 - X)^2)

where ``K`` bounds the integral of ``rho^3`` over the node's faces: the
lesser of ``R M2`` (``M2`` the integral of ``rho^2``, exact for triangles)
and the sum of each face's area times its farthest vertex's ``rho^3``.  A
node whose ball holds ``P`` (``X >= 1``) has no expansion.  To this, each
node adds a bound of the rounding of its moments (kept in float32, each
within ``2^-24`` of itself) and of the series' evaluation, ``2^-14 A / d^2``
(``A`` its area: ``|N| <= A``, and the other terms add up to at most a few
hundred times ``A / d^2``).

Near field
----------
A face near ``P`` adds its own solid angle, ``2 atan2(det, den)`` (A. van
Oosterom and J. Strackee, IEEE TBME 30(2), 1983), evaluated with a bound on
its error: ``det`` and ``den`` carry rounding bounds from the magnitudes of
their terms, and the angle is off by at most ``(pi / 2) delta / rho``
(``delta`` the bounds' length, ``rho = |(det, den)|``).  Where the bounds
reach the branch cut of ``atan2`` (``den < 0``, ``det`` within its bound of
0: ``P`` is within rounding of the face's interior) or the origin, the face's
term may be off by a whole turn, and the bound says so.  Faces of zero area
(collinear vertices, decided exactly) contribute exactly 0 and are left out.
A point that coincides with a vertex of a face is on the surface: that
face's term is 0 with a whole turn of doubt (except under the
:data:`FRACTIONAL` rule, which :mod:`proximity.signs.validity` asks for at
vertices, with the faces there left out).

The sum
-------
Each point starts from the root and repeatedly opens the node with the
largest error bound (a max-heap over the frontier): an inner node is
replaced by its children's expansions, a leaf by its faces' exact terms.
It stops as soon as the sum of the bounds (plus the rounding of the running
sums) decides the point's ``rule``: the distance of the sum from the
decision, ``||w| - 1/2|``; on a closed mesh an interval that excludes 0 or
holds no integer but 0; or when every face is exact.  The
reported bound is rigorous: the winding number is within ``error`` of
``winding``, and where ``error < ||winding| - 1/2|`` the side is certain.

Coordinates are scaled by a power of two (exact) so that the mesh's extent
is about 1, where no product of the kernels overflows or underflows; nodes
smaller than ``2^-160`` of the mesh are always opened, and a face term
whose magnitudes leave the float range is scaled by a power of two.
"""

import dataclasses
import math
from dataclasses import dataclass, fields

import numpy as np
from numba import prange

from .._validate import freeze_fields
from ..results.base import _frozen, format_repr
from ..runtime import threads
from ..runtime.jit import inline, kernel

U = 2.0**-53
FOUR_PI = 4.0 * math.pi
TWO_PI = 2.0 * math.pi
#: Columns of a node's record: centre (3), radius, ``K``, area, ``N`` (3),
#: ``tr M``, the symmetric part of ``M`` as a quadratic form (``xx yy zz xy xz
#: yz``), ``u = 2 t1 + t2`` (3), and ``T``'s symmetric part as a cubic form
#: (``xxx yyy zzz xxy xxz yyx yyz zzx zzy xyz``).
C_CENTRE, C_RADIUS, C_CUBES, C_AREA, C_N, C_TRACE, C_Q, C_U, C_C = 0, 3, 4, 5, 6, 9, 10, 16, 19
COLUMNS = 29
#: A node smaller than this (in the scaled frame) has no expansion.
SMALLEST = 2.0**-160
#: Bound of the rounding of a node's moments and series, relative to ``A / d^2``.
SERIES_ROUNDING = 2.0**-14
#: Points per parallel task.
BLOCK = 32


@dataclasses.dataclass(frozen=True, eq=False)
class Hierarchy:
    """What the winding number needs of one mesh, computed once.

    Attributes
    ----------
    nodes : ndarray of float64, shape ``(m, COLUMNS)``
        Each node's centre, radius and moments (see the module's notes).
    child, count : ndarray of int64, shape ``(m,)``
        The hierarchy's topology (as :class:`proximity.broadphase.Tree`'s).
    index : ndarray of int64, shape ``(n,)``
        The mesh's face of each stored row.
    triangles : ndarray of float64, shape ``(n, 9)``
        The stored faces' vertices, in leaf order, in the scaled frame.
    weight : ndarray of float64, shape ``(n,)``
        How many times each stored face counts: its number of exact copies
        in the mesh, or 0 for a face of zero area.
    boxes : ndarray of float64, shape ``(m, 6)``
        Each node's box (low, high corners) over its faces of nonzero
        weight, in the scaled frame; empty (``inf``, ``-inf``) where none.
    scale : tuple of float
        The powers of two the coordinates are multiplied by, one after the
        other (the second is 1 but for a mesh of subnormal extent).
    integral : bool
        Whether the mesh is closed by position (see
        :mod:`proximity.signs.validity`), where the winding number is an integer
        off the surface.
    axis : int
        The axis along which rays are cast
        (:func:`proximity.signs.crossings.crossings`): that of the mesh's least
        extent.
    """

    nodes: np.ndarray
    child: np.ndarray
    count: np.ndarray
    index: np.ndarray
    triangles: np.ndarray
    weight: np.ndarray
    boxes: np.ndarray
    scale: tuple
    integral: bool
    axis: int


# -- the mesh's hierarchy -------------------------------------------------------------


def _tree_of(mesh):
    """The hierarchy to expand over: the mesh's own, or one built here for a brute-force mesh."""
    tree = mesh._tree
    if len(tree.child) == 1 and len(tree.index) > 16:
        from .. import broadphase
        from ..primitives import TRIANGLE

        with threads.kernel():
            tree = broadphase.build_faces(mesh.vertices, mesh.faces, TRIANGLE.code)
    return tree


def _visiting_order(points):
    """An order of the points in which neighbours follow each other (the broad phase's)."""
    from ..broadphase.nearest import _visiting_order

    return _visiting_order(points)


def _topology(tree):
    """``(child, count, face of each stored row, its nine coordinates)`` of a broad-phase tree."""
    return tree.child, tree.count, tree.index, tree.params[:, :9]


def zero_area(vertices, faces):
    """Whether each face has zero area exactly: its three vertices are collinear.

    The cross product of two edges is computed in floats with a bound on
    its error; faces whose every component is within its bound of 0 are
    decided in rational arithmetic.
    """
    from fractions import Fraction

    tri = vertices[faces]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    cross = np.cross(e1, e2)
    # Each edge component is off by u |e|, each product by about 3 u; 8 u spares.
    bound = 8.0 * U * np.abs(e1[:, [1, 2, 0]] * e2[:, [2, 0, 1]]) + 8.0 * U * np.abs(
        e1[:, [2, 0, 1]] * e2[:, [1, 2, 0]]
    )
    doubt = np.flatnonzero((np.abs(cross) <= bound).all(axis=1))
    out = np.zeros(len(faces), dtype=bool)
    for f in doubt:
        a, b, c = ([Fraction(x) for x in v] for v in tri[f])
        u = [b[i] - a[i] for i in range(3)]
        v = [c[i] - a[i] for i in range(3)]
        out[f] = u[1] * v[2] == u[2] * v[1] and u[2] * v[0] == u[0] * v[2] and u[0] * v[1] == u[1] * v[0]
    return out


def _weights(vertices, faces, index, triangles):
    """Each stored face's weight: its copies in the mesh (the tree keeps one), 0 if of zero
    area (decided on ``triangles``, the stored faces in the scaled frame, where no product
    overflows)."""
    weight = np.ones(len(index))
    if len(index) < len(faces):
        rows = np.ascontiguousarray(vertices[faces].reshape(len(faces), 9))
        _, group, copies = np.unique(
            rows.view(np.dtype((np.void, 72))).ravel(), return_inverse=True, return_counts=True
        )
        weight = copies[group.reshape(-1)[index]].astype(np.float64)
    weight[zero_area(triangles.reshape(-1, 3), np.arange(3 * len(index)).reshape(-1, 3))] = 0.0
    return weight


def _scale_of(vertices):
    """``(s, t)``: powers of two whose product brings the mesh's extent near 1, keeping
    coordinates below ``2^500``.  ``t`` is 1 but for a mesh of subnormal extent, whose
    product is past ``2^1023``: multiplying by ``s`` and then by ``t`` is multiplying by the
    product, exactly (the powers are positive), or overflows where that does."""
    extent = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
    largest = float(np.max(np.abs(vertices)))
    if extent == 0.0:
        extent = largest if largest > 0.0 else 1.0
    exponent = -math.frexp(extent)[1]
    exponent = min(exponent, 500 - math.frexp(largest)[1]) if largest > 0.0 else exponent
    first = min(exponent, 1023)
    return math.ldexp(1.0, first), math.ldexp(1.0, exponent - first)


def build(mesh):
    """The :class:`Hierarchy` of a :class:`proximity.TriangleMesh`."""
    tree = _tree_of(mesh)
    child, count, index, params = _topology(tree)
    scale = _scale_of(mesh.vertices)
    triangles = np.ascontiguousarray(params * scale[0] * scale[1])
    weight = _weights(mesh.vertices, mesh.faces, index, triangles)
    with threads.kernel():
        nodes = _moments(child, count, triangles, weight)
        boxes = _boxes(child, count, triangles, weight)
    # Kept in float32, which halves what a query reads: the bounds (radius,
    # K, area) rounded up, the moments within 2^-24 of themselves
    # (covered by SERIES_ROUNDING).
    nodes[:, [C_RADIUS, C_CUBES, C_AREA]] *= 1.0 + 2.0**-22
    nodes = nodes.astype(np.float32)
    for array in (nodes, triangles, weight, boxes):
        array.flags.writeable = False
    from .topology import merged_faces, unbalanced

    integral = unbalanced(merged_faces(mesh.vertices, mesh.faces)) is None
    axis = int(np.argmin(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)))
    return Hierarchy(nodes, child, count, index, triangles, weight, boxes, scale, integral, axis)


@inline
def _face_moments(tri, j, wt, cx, cy, cz, out):
    """Add face ``j``'s moments about ``(cx, cy, cz)``, times ``wt``, to the record ``out``;
    returns its area times ``wt``."""
    ax, ay, az = tri[j, 0] - cx, tri[j, 1] - cy, tri[j, 2] - cz
    bx, by, bz = tri[j, 3] - cx, tri[j, 4] - cy, tri[j, 5] - cz
    qx, qy, qz = tri[j, 6] - cx, tri[j, 7] - cy, tri[j, 8] - cz
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = qx - ax, qy - ay, qz - az
    # The area vector a n, half the edges' cross product.
    nx = 0.5 * wt * (uy * vz - uz * vy)
    ny = 0.5 * wt * (uz * vx - ux * vz)
    nz = 0.5 * wt * (ux * vy - uy * vx)
    area = math.sqrt(nx * nx + ny * ny + nz * nz)
    sx, sy, sz = ax + bx + qx, ay + by + qy, az + bz + qz
    gx, gy, gz = sx / 3.0, sy / 3.0, sz / 3.0
    # S = (a a^T + b b^T + q q^T + s s^T) / 12: the second moment of area per area.
    s00 = (ax * ax + bx * bx + qx * qx + sx * sx) / 12.0
    s11 = (ay * ay + by * by + qy * qy + sy * sy) / 12.0
    s22 = (az * az + bz * bz + qz * qz + sz * sz) / 12.0
    s01 = (ax * ay + bx * by + qx * qy + sx * sy) / 12.0
    s02 = (ax * az + bx * bz + qx * qz + sx * sz) / 12.0
    s12 = (ay * az + by * bz + qy * qz + sy * sz) / 12.0
    trace_s = s00 + s11 + s22
    out[C_CUBES] += area * trace_s  # M2 for now; K at the end
    out[C_AREA] += area
    out[C_N] += nx
    out[C_N + 1] += ny
    out[C_N + 2] += nz
    out[C_TRACE] += nx * gx + ny * gy + nz * gz
    out[C_Q] += nx * gx
    out[C_Q + 1] += ny * gy
    out[C_Q + 2] += nz * gz
    out[C_Q + 3] += nx * gy + ny * gx
    out[C_Q + 4] += nx * gz + nz * gx
    out[C_Q + 5] += ny * gz + nz * gy
    out[C_U] += 2.0 * (s00 * nx + s01 * ny + s02 * nz) + nx * trace_s
    out[C_U + 1] += 2.0 * (s01 * nx + s11 * ny + s12 * nz) + ny * trace_s
    out[C_U + 2] += 2.0 * (s02 * nx + s12 * ny + s22 * nz) + nz * trace_s
    out[C_C] += nx * s00
    out[C_C + 1] += ny * s11
    out[C_C + 2] += nz * s22
    out[C_C + 3] += 2.0 * nx * s01 + ny * s00
    out[C_C + 4] += 2.0 * nx * s02 + nz * s00
    out[C_C + 5] += 2.0 * ny * s01 + nx * s11
    out[C_C + 6] += 2.0 * ny * s12 + nz * s11
    out[C_C + 7] += 2.0 * nz * s02 + nx * s22
    out[C_C + 8] += 2.0 * nz * s12 + ny * s22
    out[C_C + 9] += 2.0 * (nx * s12 + ny * s02 + nz * s01)
    return area


@kernel(parallel=True)
def _moments(child, count, tri, weight):
    """Every node's record, ``(m, COLUMNS)``: each node's moments summed over its faces."""
    m = child.shape[0]
    first = np.empty(m, np.int64)
    last = np.empty(m, np.int64)
    # Children come after their parent: a backward pass sees them first.
    for i in range(m - 1, -1, -1):
        if count[i] > 0:
            first[i] = child[i]
            last[i] = child[i] + count[i]
        else:
            first[i] = first[child[i]]
            last[i] = last[child[i] + 1]
    nodes = np.zeros((m, COLUMNS))
    for i in prange(m):
        out = nodes[i]
        # The centre: the area-weighted centroid of the faces (their vertices' mean
        # where they have no area), about which the first moment vanishes.
        total, cx, cy, cz, mean_x, mean_y, mean_z, n_points = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for j in range(first[i], last[i]):
            if weight[j] == 0.0:
                continue
            ux, uy, uz = tri[j, 3] - tri[j, 0], tri[j, 4] - tri[j, 1], tri[j, 5] - tri[j, 2]
            vx, vy, vz = tri[j, 6] - tri[j, 0], tri[j, 7] - tri[j, 1], tri[j, 8] - tri[j, 2]
            wx, wy, wz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
            a = weight[j] * math.sqrt(wx * wx + wy * wy + wz * wz)
            for v in range(3):
                cx += a * tri[j, 3 * v] / 3.0
                cy += a * tri[j, 3 * v + 1] / 3.0
                cz += a * tri[j, 3 * v + 2] / 3.0
                mean_x += tri[j, 3 * v]
                mean_y += tri[j, 3 * v + 1]
                mean_z += tri[j, 3 * v + 2]
            total += a
            n_points += 3.0
        if n_points == 0.0:
            # Nothing to expand: a centre anywhere, no radius, no moments.
            out[C_CENTRE] = tri[first[i], 0]
            out[C_CENTRE + 1] = tri[first[i], 1]
            out[C_CENTRE + 2] = tri[first[i], 2]
            continue
        if total > 0.0:
            cx, cy, cz = cx / total, cy / total, cz / total
        else:
            cx, cy, cz = mean_x / n_points, mean_y / n_points, mean_z / n_points
        # The record is kept in float32: the centre is one, and the moments are about it.
        cx, cy, cz = float(np.float32(cx)), float(np.float32(cy)), float(np.float32(cz))
        out[C_CENTRE], out[C_CENTRE + 1], out[C_CENTRE + 2] = cx, cy, cz
        radius = 0.0
        cubes = 0.0  # the sum of each face's area times its farthest vertex's distance cubed
        for j in range(first[i], last[i]):
            if weight[j] == 0.0:
                continue
            farthest = 0.0
            for v in range(3):
                dx, dy, dz = tri[j, 3 * v] - cx, tri[j, 3 * v + 1] - cy, tri[j, 3 * v + 2] - cz
                farthest = max(farthest, dx * dx + dy * dy + dz * dz)
            radius = max(radius, farthest)
            area = _face_moments(tri, j, weight[j], cx, cy, cz, out)
            cubes += area * farthest * math.sqrt(farthest)
        # Rounded up past the rounding of the squares and the root.
        radius = math.sqrt(radius) * (1.0 + 8.0 * U)
        out[C_RADIUS] = radius if radius >= SMALLEST else math.inf
        out[C_CUBES] = min(out[C_CUBES] * radius, cubes * (1.0 + 16.0 * U))
    return nodes


@kernel(parallel=True)
def _boxes(child, count, tri, weight):
    """Each node's box over its rows of nonzero weight, ``(m, 6)`` (low, high); empty where none."""
    m = child.shape[0]
    boxes = np.empty((m, 6))
    first = np.empty(m, np.int64)
    last = np.empty(m, np.int64)
    for i in range(m - 1, -1, -1):
        if count[i] > 0:
            first[i] = child[i]
            last[i] = child[i] + count[i]
        else:
            first[i] = first[child[i]]
            last[i] = last[child[i] + 1]
    for i in prange(m):
        for a in range(3):
            boxes[i, a] = math.inf
            boxes[i, 3 + a] = -math.inf
        for j in range(first[i], last[i]):
            if weight[j] == 0.0:
                continue
            for v in range(3):
                for a in range(3):
                    boxes[i, a] = min(boxes[i, a], tri[j, 3 * v + a])
                    boxes[i, 3 + a] = max(boxes[i, 3 + a], tri[j, 3 * v + a])
    return boxes


# -- evaluation -----------------------------------------------------------------------


@inline
def _expansion(nodes, k, px, py, pz):
    """``(value, error bound)`` of node ``k``'s series at ``P``, in turns; error inf without one."""
    rx = nodes[k, 0] - px
    ry = nodes[k, 1] - py
    rz = nodes[k, 2] - pz
    d2 = rx * rx + ry * ry + rz * rz
    radius = nodes[k, C_RADIUS]
    if not d2 > radius * radius * (1.0 + 8.0 * U):
        return 0.0, math.inf
    if d2 == math.inf:
        # Beyond 1e154 of a node of the mesh, whose extent is about 1: its area over d^2 is nothing.
        return 0.0, 1e-300
    d = math.sqrt(d2)
    inv = 1.0 / d
    inv2 = inv * inv
    inv3 = inv2 * inv
    inv5 = inv3 * inv2
    xx, yy, zz = rx * rx, ry * ry, rz * rz
    dipole = rx * nodes[k, C_N] + ry * nodes[k, C_N + 1] + rz * nodes[k, C_N + 2] + nodes[k, C_TRACE]
    quadratic = (
        nodes[k, C_Q] * xx + nodes[k, C_Q + 1] * yy + nodes[k, C_Q + 2] * zz
        + nodes[k, C_Q + 3] * rx * ry + nodes[k, C_Q + 4] * rx * rz + nodes[k, C_Q + 5] * ry * rz
    )  # fmt: skip
    linear = rx * nodes[k, C_U] + ry * nodes[k, C_U + 1] + rz * nodes[k, C_U + 2]
    cubic = (
        rx * (nodes[k, C_C] * xx + nodes[k, C_C + 3] * rx * ry + nodes[k, C_C + 4] * rx * rz)
        + ry * (nodes[k, C_C + 1] * yy + nodes[k, C_C + 5] * rx * ry + nodes[k, C_C + 6] * ry * rz)
        + rz * (nodes[k, C_C + 2] * zz + nodes[k, C_C + 7] * rx * rz + nodes[k, C_C + 8] * ry * rz)
        + nodes[k, C_C + 9] * rx * ry * rz
    )  # fmt: skip
    value = dipole * inv3 - (3.0 * quadratic + 1.5 * linear) * inv5 + 7.5 * cubic * inv5 * inv2
    x = radius * inv * (1.0 + 4.0 * U)
    over = 1.0 / (1.0 - x)
    tail = nodes[k, C_CUBES] * inv5 * over * (4.5 + x * over)
    error = (tail + SERIES_ROUNDING * nodes[k, C_AREA] * inv2) * (1.0 + 32.0 * U) / FOUR_PI + 1e-300
    return value / FOUR_PI, error


@inline
def _face(tri, j, px, py, pz, at_vertex):
    """``(value, error bound)`` of face ``j``'s solid angle at ``P``, in turns; at a vertex
    of the face, 0 within ``at_vertex``."""
    ax, ay, az = tri[j, 0] - px, tri[j, 1] - py, tri[j, 2] - pz
    bx, by, bz = tri[j, 3] - px, tri[j, 4] - py, tri[j, 5] - pz
    cx, cy, cz = tri[j, 6] - px, tri[j, 7] - py, tri[j, 8] - pz
    big = max(abs(ax), abs(ay), abs(az), abs(bx), abs(by), abs(bz), abs(cx), abs(cy), abs(cz))
    if big == 0.0:
        return 0.0, at_vertex
    if not 2.0**-300 < big < 2.0**300:
        # Products of three differences would leave the float range: a power
        # of two brings them back, exactly (the solid angle is scale-free).
        s = math.ldexp(1.0, -math.frexp(big)[1])
        ax, ay, az = ax * s, ay * s, az * s
        bx, by, bz = bx * s, by * s, bz * s
        cx, cy, cz = cx * s, cy * s, cz * s
    if (
        (ax == 0.0 and ay == 0.0 and az == 0.0)
        or (bx == 0.0 and by == 0.0 and bz == 0.0)
        or (cx == 0.0 and cy == 0.0 and cz == 0.0)
    ):
        return 0.0, at_vertex  # P is a vertex of the face
    la = math.sqrt(ax * ax + ay * ay + az * az)
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    lc = math.sqrt(cx * cx + cy * cy + cz * cz)
    p1, p2 = by * cz, bz * cy
    q1, q2 = bz * cx, bx * cz
    r1, r2 = bx * cy, by * cx
    det = ax * (p1 - p2) + ay * (q1 - q2) + az * (r1 - r2)
    perm = abs(ax) * (abs(p1) + abs(p2)) + abs(ay) * (abs(q1) + abs(q2)) + abs(az) * (abs(r1) + abs(r2))
    lll = la * lb * lc
    den = (
        lll
        + (ax * bx + ay * by + az * bz) * lc
        + (bx * cx + by * cy + bz * cz) * la
        + (cx * ax + cy * ay + cz * az) * lb
    )
    # The differences are off by u each, and each sum of products by a few u
    # of its terms' magnitudes: 16 u for det, 128 u of la lb lc for den (four
    # terms each at most la lb lc, each with a few u from the lengths).
    e_det = 16.0 * U * perm + 1e-300
    e_den = 128.0 * U * lll + 1e-300
    angle = math.atan2(det, den)
    rho = math.sqrt(det * det + den * den)
    spread = math.sqrt(e_det * e_det + e_den * e_den)
    if spread >= 0.5 * rho or (den - e_den < 0.0 and abs(det) <= e_det):
        # The true (det, den) may be across the cut, or anywhere around the
        # origin: the angle may be off by a whole turn.
        return angle / TWO_PI, 1.0
    # sin of the angle between the computed and a true (det, den) is at most
    # spread / rho, the angle at most pi/2 times that; atan2 adds 2 ulps.
    error = (1.6 * spread / rho + 4.0 * U) / TWO_PI + 4.0 * U * abs(angle) / TWO_PI
    return angle / TWO_PI, error


@inline
def _heap_push(err, node, val, size, e, k, v):
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        if err[parent] >= e:
            break
        err[i], node[i], val[i] = err[parent], node[parent], val[parent]
        i = parent
    err[i], node[i], val[i] = e, k, v
    return size + 1


@inline
def _heap_pop(err, node, val, size):
    """Remove the top (which the caller read) and restore the heap; returns the new size."""
    size -= 1
    if size == 0:
        return 0
    e, k, v = err[size], node[size], val[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        big = left
        if left + 1 < size and err[left + 1] > err[left]:
            big = left + 1
        if err[big] <= e:
            break
        err[i], node[i], val[i] = err[big], node[big], val[big]
        i = big
    err[i], node[i], val[i] = e, k, v
    return size


#: When a point's evaluation may stop (``rule``): the side under the nonzero
#: rule is proven; or, for a winding number known to be an integer (a closed
#: mesh), the interval excludes 0 or holds no integer but 0; or the interval
#: holds no integer (its integer part is proven).
NONZERO, INTEGRAL, FRACTIONAL = 0, 1, 2


@inline
def _certain(w, error, rule):
    """Whether a winding number within ``error`` of ``w`` is decided under ``rule``."""
    low, high = w - error, w + error
    if rule == INTEGRAL:
        return low > 0.0 or high < 0.0 or (low > -1.0 and high < 1.0)
    if rule == FRACTIONAL:
        return math.floor(low) == math.floor(high) and low > math.floor(low)
    return error < abs(abs(w) - 0.5)


@inline
def _winding_point(nodes, child, count, tri, weight, px, py, pz, full, rule, stack, h_err, h_node, h_val):
    """``(w, error bound)`` at ``P`` (see the module's notes); ``full``: every face exact."""
    # A point on a vertex is on the surface, where the winding number has no
    # value: a whole turn of doubt, except for the fractional rule, which
    # asks for the faces around the vertex left out.
    at_vertex = 0.0 if rule == FRACTIONAL else 1.0
    far = 0.0  # the sum of the frontier's series
    far_err = 0.0  # the sum of their bounds
    near = 0.0  # the sum of the exact faces' terms
    near_err = 0.0
    ops = 0.0  # a bound on the rounding of these running sums
    size = 0
    sp = 0
    if nodes[0, C_RADIUS] != 0.0:
        value, err = _expansion(nodes, 0, px, py, pz)
        if full or err == math.inf:
            stack[0] = 0
            sp = 1
        else:
            far, far_err = value, err
            size = _heap_push(h_err, h_node, h_val, size, err, 0, value)
    while True:
        # Open the nodes on the stack, and every node below them whose ball
        # holds P: faces go to the exact sum, series to the heap.
        while sp > 0:
            sp -= 1
            k = stack[sp]
            if count[k] > 0:
                for j in range(child[k], child[k] + count[k]):
                    if weight[j] != 0.0:
                        t, e = _face(tri, j, px, py, pz, at_vertex)
                        near += weight[j] * t
                        near_err += weight[j] * e
                        ops += U * (abs(near) + near_err)
                continue
            for c in range(child[k], child[k] + 2):
                if nodes[c, C_RADIUS] == 0.0:
                    continue  # nothing but faces of zero area below
                value, err = _expansion(nodes, c, px, py, pz)
                if full or err == math.inf:
                    stack[sp] = c
                    sp += 1
                else:
                    far += value
                    far_err += err
                    ops += U * (abs(far) + far_err)
                    size = _heap_push(h_err, h_node, h_val, size, err, c, value)
        if size == 0:
            break
        w = far + near
        if _certain(w, (far_err + near_err + ops + 4.0 * U * abs(w)) * (1.0 + 8.0 * U), rule):
            break
        # Replace the series with the largest bound by what is below it.
        k = h_node[0]
        ops += U * (abs(far) + abs(h_val[0]) + far_err + h_err[0])
        far -= h_val[0]
        far_err -= h_err[0]
        size = _heap_pop(h_err, h_node, h_val, size)
        stack[0] = k
        sp = 1
    w = far + near
    return w, (far_err + near_err + ops + 4.0 * U * abs(w)) * (1.0 + 8.0 * U)


@kernel(parallel=True)
def _winding_kernel(nodes, child, count, tri, weight, points, order, scale, more, full, rule, w_out, e_out):
    n = points.shape[0]
    m = child.shape[0]
    for block in prange((n + BLOCK - 1) // BLOCK):
        h_err = np.empty(m + 1)
        h_node = np.empty(m + 1, np.int64)
        h_val = np.empty(m + 1)
        stack = np.empty(m + 1, np.int64)
        for o in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
            i = order[o]
            x, y, z = points[i, 0], points[i, 1], points[i, 2]
            px, py, pz = x * scale * more, y * scale * more, z * scale * more
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
                w_out[i], e_out[i] = math.nan, math.nan
            elif not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
                w_out[i], e_out[i] = 0.0, 0.0  # beyond 2^500 of the mesh's extent: outside
            else:
                w, e = _winding_point(
                    nodes, child, count, tri, weight, px, py, pz, full, rule, stack, h_err, h_node, h_val
                )
                w_out[i], e_out[i] = w, e


def numbers(hierarchy, points, full=False, rule=NONZERO):
    """``(w, error)``: the winding number at each point, ``(n, 3)`` float64, and a bound on its error.

    ``|w_exact - w| <= error``.  Each point's evaluation stops as soon as
    ``rule`` (:data:`NONZERO`, :data:`INTEGRAL` or :data:`FRACTIONAL`) is
    decided, so ``w`` is only as accurate as that needs; ``full=True``
    evaluates every face exactly instead.  NaN where the point is not
    finite.
    """
    h = hierarchy
    points = np.ascontiguousarray(points, dtype=np.float64)
    w = np.empty(len(points))
    e = np.empty(len(points))
    if len(points):
        with threads.kernel():
            _winding_kernel(
                h.nodes,
                h.child,
                h.count,
                h.triangles,
                h.weight,
                points,
                _visiting_order(points),
                *h.scale,
                bool(full),
                int(rule),
                w,
                e,
            )
    return w, e


def sides(w, error, integral):
    """``(inside, certain, w, error)`` from :func:`numbers`' answers.

    Inside means ``|w| > 1/2``; certain where the bound proves it.  For an
    integral winding number whose interval holds a single integer, ``w``
    becomes that integer and ``error`` 0.
    """
    low, high = w - error, w + error
    with np.errstate(invalid="ignore"):
        if integral:
            excludes_zero = (low > 0.0) | (high < 0.0)
            certain = excludes_zero | ((low > -1.0) & (high < 1.0))
            inside = np.where(certain, excludes_zero, np.abs(w) > 0.5)
            single = np.floor(high) == np.ceil(low)
            w = np.where(single, np.ceil(low), w)
            error = np.where(single, 0.0, error)
        else:
            inside = np.abs(w) > 0.5
            certain = error < np.abs(np.abs(w) - 0.5)
    return inside, certain, w + 0.0, error


@dataclass(frozen=True, repr=False)
class WindingResult:
    """The winding number at each point, a bound on its error, and the side it gives.

    Attributes
    ----------
    winding : ndarray of float64, shape ``batch``
        The generalized winding number, within ``error`` of the exact one;
        on a mesh closed by position, the exact integer wherever the bound
        leaves one (``error`` 0 there).  NaN where the point is not finite.
    error : ndarray of float64, shape ``batch``
        A rigorous bound on ``|winding - exact|``.
    inside : ndarray of bool, shape ``batch``
        ``|winding| > 1/2``: inside under the nonzero rule.
    certain : ndarray of bool, shape ``batch``
        Whether ``inside`` is proven: ``error`` keeps the exact winding
        number on the same side of 1/2 (of 0 and 1, for an integer).
        False on the surface, within rounding of it, and on meshes with
        holes where the winding number is within ``error`` of 1/2.
    """

    winding: np.ndarray
    error: np.ndarray
    inside: np.ndarray
    certain: np.ndarray

    def __post_init__(self):
        for name, value in vars(self).items():
            object.__setattr__(self, name, _frozen(value))

    def __setstate__(self, state):
        self.__dict__.update(freeze_fields(state))

    def __repr__(self):
        return format_repr(self, [f.name for f in fields(self)])
