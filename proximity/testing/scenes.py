"""Seeded scene generators for accuracy tests and benchmarks.

Each generator builds one family of queries, pairwise (point ``i`` against
shape ``i``), from ``(rng, n, **params)``: the same generator state gives the
same scene. Triangle families return a `TriangleScene`, circle and disk
families a `DiskScene` (the same scenes serve both shapes). All arrays are
float64 and finite.

Where a family promises an exact property (zero area, a point exactly on an
edge or on an axis, a sliver thinner than the float spacing of its vertices),
the construction only uses float operations that are exact: multiplication by
powers of two, sums of numbers on a common dyadic grid that does not exceed 53
bits, and differences of numbers within a factor of two of each other
(Sterbenz's lemma). The docstrings say which.

`TRIANGLE_FAMILIES` and `DISK_FAMILIES` list every family with the parameter
sweep used by the tests and the benchmarks.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

__all__ = [
    "DISK_FAMILIES",
    "PAIRS",
    "PAIR_FAMILIES",
    "TRIANGLE_FAMILIES",
    "DiskScene",
    "Family",
    "PairScene",
    "TriangleScene",
    "degenerate",
    "disk_axis",
    "disk_in_plane",
    "disk_offset",
    "disk_rim",
    "disk_unnormalized",
    "disk_well_conditioned",
    "far_points",
    "magnitude",
    "near_surface",
    "needle",
    "offset",
    "on_feature",
    "pair_contact",
    "pair_degenerate",
    "pair_far",
    "pair_magnitude",
    "pair_near_parallel",
    "pair_offset",
    "pair_parallel",
    "pair_well_conditioned",
    "sliver",
    "small",
    "well_conditioned",
]


@dataclass(frozen=True, eq=False)
class TriangleScene:
    """Pairwise point-triangle queries.

    Attributes
    ----------
    vertices : ndarray of float64, shape (n, 3, 3)
        Triangle ``i`` is ``vertices[i]``, one vertex per row.
    points : ndarray of float64, shape (n, 3)
        Query point of triangle ``i``.
    """

    vertices: np.ndarray
    points: np.ndarray


@dataclass(frozen=True, eq=False)
class DiskScene:
    """Pairwise point-circle or point-disk queries.

    Attributes
    ----------
    center : ndarray of float64, shape (n, 3)
    normal : ndarray of float64, shape (n, 3)
        Axis directions, nonzero but not necessarily of unit length.
    radius : ndarray of float64, shape (n,)
    points : ndarray of float64, shape (n, 3)
    """

    center: np.ndarray
    normal: np.ndarray
    radius: np.ndarray
    points: np.ndarray


# -- building blocks ------------------------------------------------------------


def _unit(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniformly distributed unit vectors, shape (n, 3)."""
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _normalized(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniformly distributed rotation matrices, shape (n, 3, 3)."""
    w, x, y, z = _normalized(rng.standard_normal((n, 4))).T
    return np.stack(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    ).transpose(2, 0, 1)


def _planar_triangles(rng: np.random.Generator, n: int, min_angle: float = math.radians(10)) -> np.ndarray:
    """Planar triangles with every angle above `min_angle`, shape (n, 3, 2).

    The angles are drawn uniformly from those allowed, and the triangle is
    built from them by the law of sines, then scaled to a longest edge of 1
    and centered on its centroid.
    """
    alpha, beta, gamma = (min_angle + (np.pi - 3 * min_angle) * rng.dirichlet([1, 1, 1], n)).T
    b = np.sin(beta) / np.sin(gamma)  # |AC| when |AB| = 1
    tri = np.zeros((n, 3, 2))
    tri[:, 1, 0] = 1.0
    tri[:, 2] = b[:, None] * np.stack([np.cos(alpha), np.sin(alpha)], axis=-1)
    longest = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=-1).max(axis=1)
    tri /= longest[:, None, None]
    return tri - tri.mean(axis=1, keepdims=True)


def _well_shaped(rng: np.random.Generator, n: int) -> np.ndarray:
    """Randomly oriented triangles of diameter 1 centered at the origin, (n, 3, 3)."""
    flat = np.concatenate([_planar_triangles(rng, n), np.zeros((n, 3, 1))], axis=-1)
    return flat @ _rotations(rng, n).transpose(0, 2, 1)


def _normals(vertices: np.ndarray) -> np.ndarray:
    """Return unit face normals, computed in float (fine for well-shaped triangles)."""
    return _normalized(np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0]))


def _shuffle_vertices(rng: np.random.Generator, vertices: np.ndarray) -> np.ndarray:
    """Reorder the vertices of each triangle at random.

    The construction order would otherwise favor some code paths.
    """
    order = rng.permuted(np.tile([0, 1, 2], (len(vertices), 1)), axis=1)
    return np.take_along_axis(vertices, order[:, :, None], axis=1)


def _points_around(
    rng: np.random.Generator,
    vertices: np.ndarray,
    margin: np.ndarray | float,
    normals: np.ndarray | None = None,
) -> np.ndarray:
    """Query points for triangles: half above or below the face, half in a box.

    Half of the points are a uniformly random point of the triangle moved
    along ``normals`` (the face normal by default) by up to `margin` either
    way, since a uniform box puts few points in the face region. The rest
    are uniform in the bounding box grown by `margin`.
    """
    n = len(vertices)
    margin = np.broadcast_to(np.asarray(margin, dtype=np.float64), (n,))[:, None]
    normals = _normals(vertices) if normals is None else normals
    on_face = np.einsum("ni,nik->nk", rng.dirichlet([1, 1, 1], n), vertices)
    above = on_face + rng.uniform(-1, 1, (n, 1)) * margin * normals
    low = vertices.min(axis=1) - margin
    high = vertices.max(axis=1) + margin
    in_box = low + rng.random((n, 3)) * (high - low)
    return np.where(rng.random((n, 1)) < 0.5, above, in_box)


def _dyadic(rng: np.random.Generator, shape: tuple[int, ...], bits: int) -> np.ndarray:
    """Uniform values in [-1, 1] on the grid of spacing ``2**-bits``."""
    return rng.integers(-(2**bits), 2**bits, shape, endpoint=True) / 2.0**bits


# -- triangle families -------------------------------------------------------------


def well_conditioned(rng: np.random.Generator, n: int) -> TriangleScene:
    """Random well-shaped triangles in the unit cube: the baseline.

    Triangles have every angle above 10 degrees and a diameter in [0.2, 0.5],
    with the centroid in [0.35, 0.65]**3, hence inside the unit cube. Half of
    the points are above or below the face, the rest uniform in the bounding
    box grown by one diameter, so every Voronoi region is exercised.
    """
    size = rng.uniform(0.2, 0.5, n)
    centroid = rng.uniform(0.35, 0.65, (n, 1, 3))
    vertices = _well_shaped(rng, n) * size[:, None, None] + centroid
    return TriangleScene(vertices, _points_around(rng, vertices, size))


def near_surface(rng: np.random.Generator, n: int, offset: float = 1e-9) -> TriangleScene:
    """Points at a tiny relative distance from the triangle.

    A random point of a well-conditioned triangle is chosen on the face, on an
    edge or at a vertex (one third each), and moved by ``offset`` times the
    diameter in a random direction. This stresses region classification: the
    point is as close to the region boundaries as to the triangle. The chosen
    point of the triangle is rounded to float (by about 1e-16 of the
    coordinates), which dominates an `offset` below about 1e-15.
    """
    size = rng.uniform(0.2, 0.5, n)
    centroid = rng.uniform(0.35, 0.65, (n, 1, 3))
    vertices = _well_shaped(rng, n) * size[:, None, None] + centroid
    rows = np.arange(n)
    bary = rng.dirichlet([1, 1, 1], n)
    # Edge points: zero one weight and renormalize; vertex points: a unit weight.
    kind = rng.integers(0, 3, n)
    on_edge = kind == 1
    bary[rows[on_edge], rng.integers(0, 3, on_edge.sum())] = 0.0
    bary /= bary.sum(axis=1, keepdims=True)
    on_vertex = kind == 2
    bary[on_vertex] = np.eye(3)[rng.integers(0, 3, on_vertex.sum())]
    anchor = np.einsum("ni,nik->nk", bary, vertices)
    points = anchor + (offset * size)[:, None] * _unit(rng, n)
    return TriangleScene(vertices, points)


def sliver(rng: np.random.Generator, n: int, rel_height: float) -> TriangleScene:
    """Slivers: the smallest height is `rel_height` times the longest edge.

    A height below the float spacing of the vertex coordinates (about 1e-16
    of them) cannot be represented on a generic triangle, so the construction
    makes it exact: the long edge runs from ``-a w`` to ``b w`` through the
    origin, with ``a, b`` multiples of 1/64 and ``w`` a unit direction
    rounded to multiples of 2**-40, so both ends lie exactly on one line
    through the origin; the apex is ``rel_height * L`` times a unit vector
    perpendicular to ``w``, near the origin where floats are dense. The
    height is ``rel_height * L`` to about 1e-16 relative, whatever
    `rel_height`.

    Points: half above or below the face, the rest in the bounding box grown
    by the long edge.
    """
    w = np.round(_unit(rng, n) * 2.0**40) / 2.0**40
    a, b = rng.integers(1, 64, (2, n, 1)) / 64.0
    ends = np.stack([-a * w, b * w], axis=1)
    length = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=-1)
    across = _normalized(np.cross(w, _unit(rng, n)))
    apex = (rel_height * length)[:, None] * across
    vertices = _shuffle_vertices(rng, np.concatenate([ends, apex[:, None]], axis=1))
    normals = _normalized(np.cross(w, across))
    return TriangleScene(vertices, _points_around(rng, vertices, length, normals))


def degenerate(rng: np.random.Generator, n: int, kind: str) -> TriangleScene:
    """Triangles of exactly zero area.

    Parameters
    ----------
    kind : {"collinear", "two_coincident", "all_coincident"}
        ``"collinear"``: ``V1 = V0 + E`` and ``V2 = V0 + k E`` hold exactly
        (coordinates on the 2**-24 grid, ``k = m / 16`` with m in [-32, 48],
        k not 0 or 1), so the three distinct vertices are exactly collinear.
        ``"two_coincident"``: one vertex is an exact copy of another.
        ``"all_coincident"``: the three vertices are one point.

    Notes
    -----
    The vertex order is shuffled. Half of the points are near the segment or
    point (moved from a point of it in a random direction by up to 1), the
    rest uniform in its bounding box grown by 1.
    """
    if kind == "collinear":
        origin = _dyadic(rng, (n, 3), 20)
        step = _dyadic(rng, (n, 3), 20)
        while np.any(zero := ~step.any(axis=1)):
            step[zero] = _dyadic(rng, (int(zero.sum()), 3), 20)
        m = rng.choice([m for m in range(-32, 49) if m not in (0, 16)], n)
        k = (m / 16.0)[:, None]
        vertices = np.stack([origin, origin + step, origin + k * step], axis=1)
    elif kind == "two_coincident":
        pair = rng.uniform(-1, 1, (n, 2, 3))
        vertices = pair[:, [0, 1, 0]]
    elif kind == "all_coincident":
        vertices = np.repeat(rng.uniform(-1, 1, (n, 1, 3)), 3, axis=1)
    else:
        raise ValueError(f"unknown kind {kind!r}")
    vertices = _shuffle_vertices(rng, vertices)
    return TriangleScene(vertices, _points_around(rng, vertices, 1.0, _unit(rng, n)))


def needle(rng: np.random.Generator, n: int, rel_width: float) -> TriangleScene:
    """Needles: one edge `rel_width` times the two others, nearly parallel.

    The far vertex is at distance 1 from the origin and the short edge is
    centered on the origin, at 30 to 90 degrees from the needle's axis; near
    the origin floats are dense, so the short edge keeps its length to full
    relative precision whatever `rel_width`. The vertex order is shuffled.
    Points: half above or below the face, the rest in the bounding box grown
    by 1.
    """
    axis = _unit(rng, n)
    across = _normalized(np.cross(axis, _unit(rng, n)))
    angle = rng.uniform(np.pi / 6, np.pi / 2, (n, 1))
    short = np.cos(angle) * axis + np.sin(angle) * across
    half = 0.5 * rel_width * short
    vertices = _shuffle_vertices(rng, np.stack([axis, -half, half], axis=1))
    normals = _normalized(np.cross(axis, across))
    return TriangleScene(vertices, _points_around(rng, vertices, 1.0, normals))


def small(rng: np.random.Generator, n: int, size: float = 1e-3) -> TriangleScene:
    """Well-shaped triangles of diameter `size` at the origin.

    Points are at distances comparable to `size` (half above or below the
    face, half in the bounding box grown by `size`). Stresses absolute
    tolerances, which are wrong at small scales.
    """
    vertices = _well_shaped(rng, n) * size
    return TriangleScene(vertices, _points_around(rng, vertices, size))


def offset(rng: np.random.Generator, n: int, offset: float, size: float = 1e-3) -> TriangleScene:
    """Small triangles far from the origin.

    A `small` scene of diameter `size` is translated so that every coordinate
    has magnitude between ``offset / 2`` and `offset`. The translation rounds
    the coordinates to the float spacing at `offset`, so the triangles keep
    about ``log10(size / (offset * 1e-16))`` significant digits: this stresses
    the differences a distance computation forms.
    """
    local = small(rng, n, size)
    shift = rng.choice([-1.0, 1.0], (n, 3)) * rng.uniform(0.5, 1.0, (n, 3)) * offset
    return TriangleScene(local.vertices + shift[:, None], local.points + shift)


def far_points(rng: np.random.Generator, n: int, ratio: float) -> TriangleScene:
    """Points at `ratio` times the diameter from a well-shaped triangle.

    The triangles have diameter 1 and their centroid at the origin. A third of
    the points are at distance `ratio` from the centroid in a random direction
    (these nearly always see a vertex), a third at distance `ratio` straight
    above or below a random face point, and a third at distance `ratio` from a
    random edge point, in that edge's region (perpendicular to the edge,
    outward). Stresses the cancellation in projections that are large compared
    with the triangle.
    """
    vertices = _well_shaped(rng, n)
    normals = _normals(vertices)
    rows = np.arange(n)
    first = rng.integers(0, 3, n)
    start, end = vertices[rows, first], vertices[rows, (first + 1) % 3]
    opposite = vertices[rows, (first + 2) % 3]
    on_edge = start + rng.random((n, 1)) * (end - start)
    outward = _normalized(np.cross(end - start, normals))
    outward *= np.sign(np.einsum("nk,nk->n", outward, on_edge - opposite))[:, None]
    tilt = rng.uniform(-np.pi / 2, np.pi / 2, (n, 1))
    beyond_edge = on_edge + ratio * (np.cos(tilt) * outward + np.sin(tilt) * normals)
    on_face = np.einsum("ni,nik->nk", rng.dirichlet([1, 1, 1], n), vertices)
    above_face = on_face + ratio * rng.choice([-1.0, 1.0], (n, 1)) * normals
    anywhere = ratio * _unit(rng, n)
    kind = rng.integers(0, 3, (n, 1))
    points = np.select([kind == 0, kind == 1], [anywhere, above_face], beyond_edge)
    return TriangleScene(vertices, points)


def magnitude(rng: np.random.Generator, n: int, scale: float) -> TriangleScene:
    """Scale a `well_conditioned` scene: every coordinate times `scale`.

    For `scale` from 1e-300 to 1e300, the squared distance under- or overflows
    float64 although the distance does not.
    """
    scene = well_conditioned(rng, n)
    return TriangleScene(scene.vertices * scale, scene.points * scale)


def on_feature(rng: np.random.Generator, n: int, kind: str) -> TriangleScene:
    """Points exactly on the triangle or its plane.

    Parameters
    ----------
    kind : {"vertex", "edge", "plane"}
        ``"vertex"``: the point is a copy of a vertex of a well-conditioned
        triangle. ``"edge"``: vertices on the 2**-20 grid in [-1, 1]**3 and
        the point ``Vi + (m / 256) (Vj - Vi)`` with m in [1, 255], computed
        exactly. ``"plane"``: triangles (diameter 0.2 to 0.5) in the plane
        ``x[k] = c`` for a random axis k and float c, and points with
        ``x[k] = c`` exactly; the first ``n // 2`` points are inside the
        triangle (all barycentric coordinates >= 0.01), the rest anywhere in
        the bounding box grown by one diameter.

    Notes
    -----
    The exact distance is 0 for "vertex", "edge" and the inside "plane"
    points.
    """
    rows = np.arange(n)
    if kind == "vertex":
        vertices = well_conditioned(rng, n).vertices
        points = vertices[rows, rng.integers(0, 3, n)].copy()
    elif kind == "edge":
        vertices = _dyadic(rng, (n, 3, 3), 20)
        while np.any(zero_area := ~_cross(vertices).any(axis=1)):
            vertices[zero_area] = _dyadic(rng, (int(zero_area.sum()), 3, 3), 20)
        first = rng.integers(0, 3, n)
        start, end = vertices[rows, first], vertices[rows, (first + 1) % 3]
        t = rng.integers(1, 256, (n, 1)) / 256.0
        points = start + t * (end - start)
    elif kind == "plane":
        size = rng.uniform(0.2, 0.5, (n, 1, 1))
        flat = _planar_triangles(rng, n) * size + rng.uniform(0, 1, (n, 1, 2))
        bary = 0.01 + 0.97 * rng.dirichlet([1, 1, 1], n)
        inside = np.einsum("ni,nik->nk", bary, flat)
        low = flat.min(axis=1) - size[:, 0]
        high = flat.max(axis=1) + size[:, 0]
        anywhere = low + rng.random((n, 2)) * (high - low)
        in_plane = np.where((rows < n // 2)[:, None], inside, anywhere)
        level = rng.uniform(-1, 1, (n, 1))
        vertices = np.concatenate([flat, np.repeat(level[:, None], 3, axis=1)], axis=2)
        points = np.concatenate([in_plane, level], axis=1)
        # Move the constant coordinate to a random axis: a permutation is exact.
        axes = rng.permuted(np.tile([0, 1, 2], (n, 1)), axis=1)
        vertices = np.take_along_axis(vertices, axes[:, None, :], axis=2)
        points = np.take_along_axis(points, axes, axis=1)
    else:
        raise ValueError(f"unknown kind {kind!r}")
    return TriangleScene(vertices, points)


def _cross(vertices: np.ndarray) -> np.ndarray:
    return np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])


# -- disk and circle families -----------------------------------------------------


def disk_well_conditioned(rng: np.random.Generator, n: int) -> DiskScene:
    """Random disks in the unit cube: the baseline.

    Centers in [0.25, 0.75]**3, random normals of length 0.5 to 2, radii in
    [0.1, 0.5]; points uniform in the cube of half-side 2 R around the center,
    which covers the face region (the cylinder over the disk), the rim region
    and the axis neighborhood.
    """
    center = rng.uniform(0.25, 0.75, (n, 3))
    normal = _unit(rng, n) * rng.uniform(0.5, 2.0, (n, 1))
    radius = rng.uniform(0.1, 0.5, n)
    points = center + rng.uniform(-2, 2, (n, 3)) * radius[:, None]
    return DiskScene(center, normal, radius, points)


def _axis_aligned(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Random coordinate axis index and normal ``+-2**j e_k``, exactly."""
    axis = rng.integers(0, 3, n)
    normal = np.zeros((n, 3))
    normal[np.arange(n), axis] = rng.choice([-1.0, 1.0], n) * 2.0 ** rng.integers(-3, 4, n)
    return axis, normal


def disk_axis(rng: np.random.Generator, n: int, rel_distance: float) -> DiskScene:
    """Points at distance ``rel_distance * R`` from the axis, 0 included.

    Near the axis the radial direction is ill-defined, and on it every rim
    point is closest.

    For ``rel_distance == 0`` the orientation is generic and the point is
    exactly on the axis: the center and the point have coordinates within a
    factor 2 of each other with equal signs, so ``P - C`` is exact (Sterbenz)
    and the normal is ``+-2**j (P - C)``. A positive distance far below the
    float spacing of the coordinates cannot be represented next to a generic
    axis, so for ``rel_distance > 0`` the axis is a coordinate axis through a
    center whose two radial coordinates are 0, and the point's radial
    coordinates are ``rel_distance * R`` times a random planar unit vector.
    Heights along the axis are up to 2 R either way.
    """
    radius = rng.uniform(0.5, 2.0, n)
    if rel_distance == 0:
        center = rng.choice([-1.0, 1.0], (n, 3)) * rng.uniform(1.0, 2.0, (n, 3))
        # Factors in [0.5, 0.91] or [1.1, 2]: P - C is exact and never zero.
        factor = rng.uniform(1.1, 2.0, (n, 3)) ** rng.choice([-1.0, 1.0], (n, 3))
        points = center * factor
        scale = rng.choice([-1.0, 1.0], (n, 1)) * 2.0 ** rng.integers(-3, 4, (n, 1))
        normal = (points - center) * scale
        return DiskScene(center, normal, radius, points)
    axis, normal = _axis_aligned(rng, n)
    rows = np.arange(n)
    center = np.zeros((n, 3))
    center[rows, axis] = rng.uniform(-1, 1, n)
    angle = rng.uniform(0, 2 * np.pi, n)
    points = np.zeros((n, 3))
    points[rows, (axis + 1) % 3] = rel_distance * radius * np.cos(angle)
    points[rows, (axis + 2) % 3] = rel_distance * radius * np.sin(angle)
    points[rows, axis] = center[rows, axis] + rng.uniform(-2, 2, n) * radius
    return DiskScene(center, normal, radius, points)


def disk_rim(rng: np.random.Generator, n: int, rel_distance: float) -> DiskScene:
    """Points within ``rel_distance * R`` of the rim, in random directions.

    Disks as in `disk_well_conditioned`. Stresses the FACE/RIM decision of a
    disk and the cancellation in ``q - R`` of a circle. The rim point is
    rounded, so below about 1e-16 the distance to the rim is rounding noise.
    """
    scene = disk_well_conditioned(rng, n)
    radial = _normalized(np.cross(scene.normal, _unit(rng, n)))
    rim = scene.center + scene.radius[:, None] * radial
    shift = (rel_distance * scene.radius * rng.random(n))[:, None] * _unit(rng, n)
    return DiskScene(scene.center, scene.normal, scene.radius, rim + shift)


def disk_in_plane(rng: np.random.Generator, n: int) -> DiskScene:
    """Points exactly in the plane of the disk, inside and outside.

    The normal is ``+-2**j`` times a coordinate axis and the point's
    coordinate along it equals the center's, so the height is exactly 0.
    Radial coordinates are uniform within 2 R of the center. Stresses the sign
    and zero handling of the height.
    """
    axis, normal = _axis_aligned(rng, n)
    center = rng.uniform(0, 1, (n, 3))
    radius = rng.uniform(0.1, 0.5, n)
    points = center + rng.uniform(-2, 2, (n, 3)) * radius[:, None]
    rows = np.arange(n)
    points[rows, axis] = center[rows, axis]
    return DiskScene(center, normal, radius, points)


def disk_offset(rng: np.random.Generator, n: int, offset: float, size: float = 1e-3) -> DiskScene:
    """Disks of radius about `size` whose centers have magnitude `offset`.

    Random normals, radii in [size / 2, size], and points within 2 R of the
    center per coordinate, all translated so that every center coordinate has
    magnitude between ``offset / 2`` and `offset` (which rounds the points).
    """
    radius = rng.uniform(0.5, 1.0, n) * size
    normal = _unit(rng, n)
    center = rng.choice([-1.0, 1.0], (n, 3)) * rng.uniform(0.5, 1.0, (n, 3)) * offset
    points = center + rng.uniform(-2, 2, (n, 3)) * radius[:, None]
    return DiskScene(center, normal, radius, points)


def disk_unnormalized(rng: np.random.Generator, n: int) -> DiskScene:
    """Give a `disk_well_conditioned` scene normals of length 1e-100 to 1e100.

    Stresses normalization of the axis: squaring a 1e-100 or 1e100 normal
    under- or overflows.
    """
    scene = disk_well_conditioned(rng, n)
    length = 10.0 ** rng.uniform(-100, 100, (n, 1))
    return DiskScene(scene.center, _normalized(scene.normal) * length, scene.radius, scene.points)


# -- pair families --------------------------------------------------------------------

#: The shape pairs, by name: the number of vertices of shape a and of shape b.
PAIRS: Mapping[str, tuple[int, int]] = MappingProxyType(
    {"segment_segment": (2, 2), "segment_triangle": (2, 3), "triangle_triangle": (3, 3)}
)


@dataclass(frozen=True, eq=False)
class PairScene:
    """Pairwise shape-shape queries: shape ``a[i]`` against shape ``b[i]``.

    Attributes
    ----------
    a : ndarray of float64, shape (n, 2, 3) or (n, 3, 3)
        Segment or triangle ``i`` of the first kind, one vertex per row.
    b : ndarray of float64, shape (n, 2, 3) or (n, 3, 3)
        The shape it is queried against.
    """

    a: np.ndarray
    b: np.ndarray


def _pair_sizes(pair: str) -> tuple[int, int]:
    if pair not in PAIRS:
        raise ValueError(f"pair must be one of {sorted(PAIRS)}, got {pair!r}")
    return PAIRS[pair]


def _shape(rng: np.random.Generator, n: int, k: int) -> np.ndarray:
    """Well-shaped segments (k = 2) or triangles (k = 3) of diameter 1 centered at the origin."""
    if k == 3:
        return _well_shaped(rng, n)
    u = _unit(rng, n)
    return np.stack([-0.5 * u, 0.5 * u], axis=1)


def _grid_unit(rng: np.random.Generator, n: int) -> np.ndarray:
    """Unit vectors rounded to multiples of 2**-40: a small multiple of one is exact."""
    return np.round(_unit(rng, n) * 2.0**40) / 2.0**40


def _across(rng: np.random.Generator, u: np.ndarray) -> np.ndarray:
    """Unit vectors perpendicular to the rows of `u` (in float)."""
    return _normalized(np.cross(u, _unit(rng, len(u))))


def _sixty_fourths(rng: np.random.Generator, shape: tuple[int, ...], low: int = 8) -> np.ndarray:
    """Multiples ``m / 64`` with m in [low, 64]: their products with a `_grid_unit` are exact."""
    return rng.integers(low, 65, shape) / 64.0


def _side(rng: np.random.Generator, n: int, k: int, feature: str, away: np.ndarray, along: np.ndarray):
    """Shape with `feature` ("vertex", "edge" or "face") holding the origin, the rest
    strictly on the side of `away`; an edge runs along `along` (grid units), a
    face is given by two grid vectors (`along`, and the rows of `away` are then
    ignored). Returns the vertices, the contact feature first."""
    if feature == "vertex":
        rest = rng.standard_normal((n, k - 1, 3))
        height = np.einsum("nkj,nj->nk", rest, away)
        rest -= (height - np.abs(height) - rng.uniform(0.05, 0.5, (n, k - 1)))[..., None] * away[:, None]
        return np.concatenate([np.zeros((n, 1, 3)), rest], axis=1)
    if feature == "edge":
        ends = np.stack([-_sixty_fourths(rng, (n, 1)) * along, _sixty_fourths(rng, (n, 1)) * along], axis=1)
        if k == 2:
            return ends
        third = (
            rng.uniform(-0.5, 0.5, (n, 1)) * along
            + rng.uniform(-0.5, 0.5, (n, 1)) * _normalized(np.cross(along, away))
            + rng.uniform(0.1, 1.0, (n, 1)) * away
        )
        return np.concatenate([ends, third[:, None]], axis=1)
    # Face: p, q on the grid and r = -(alpha p + beta q), exactly, so the origin is
    # inside with weights proportional to (alpha, beta, 1).
    p, q = along
    alpha, beta = _sixty_fourths(rng, (2, n, 1))
    return np.stack([p, q, -(alpha * p + beta * q)], axis=1)


# The contact feature pairs each family can build, per pair of shapes.
_CONTACTS = {
    (2, 2): (("vertex", "vertex"), ("vertex", "edge"), ("edge", "vertex"), ("edge", "edge")),
    (2, 3): (
        ("vertex", "vertex"),
        ("vertex", "edge"),
        ("vertex", "face"),
        ("edge", "vertex"),
        ("edge", "edge"),
    ),
    (3, 3): (
        ("vertex", "vertex"),
        ("vertex", "edge"),
        ("vertex", "face"),
        ("edge", "vertex"),
        ("edge", "edge"),
        ("face", "vertex"),
    ),
}


def pair_contact(rng: np.random.Generator, n: int, pair: str, gap: float = 0.0) -> PairScene:
    """Shapes touching at one point, then moved apart by ``gap`` along the contact normal.

    A contact feature pair is drawn (vertex, edge or face of each shape, such
    that the pair can hold the unique closest points: vertex-vertex,
    vertex-edge, edge-edge, vertex-face), both features are built through
    the origin with the rest of each shape strictly on its own side of the
    contact, and shape b is moved by ``gap`` times the contact normal.  A
    negative `gap` pushes the shapes into each other: triangles then
    intersect, segments cross over.  Shapes have diameters of about 1.

    For ``gap == 0`` the contact is exact: edges are ``[-a u, b u]`` with
    ``u`` on the 2**-40 grid and ``a, b`` multiples of 1/64, faces ``(p, q,
    -(alpha p + beta q))`` with ``p, q`` on that grid and positive ``alpha,
    beta`` multiples of 1/64, so the origin lies exactly on both features;
    the whole scene is then translated by an integer vector in [-4, 4]**3,
    which is exact.  The vertex order is shuffled after construction.
    """
    ka, kb = _pair_sizes(pair)
    contacts = _CONTACTS[ka, kb]
    choice = rng.integers(0, len(contacts), n)
    a = np.empty((n, ka, 3))
    b = np.empty((n, kb, 3))
    for index, (fa, fb) in enumerate(contacts):
        rows = np.flatnonzero(choice == index)
        m = len(rows)
        if m == 0:
            continue
        u, v = _grid_unit(rng, m), _grid_unit(rng, m)
        if fb == "face":
            p, q = _grid_unit(rng, m), _grid_unit(rng, m)
            normal = _normalized(np.cross(p, q))
            a[rows] = _side(rng, m, ka, fa, -normal, u)
            b[rows] = _side(rng, m, kb, fb, normal, (p, q))
        elif fa == "face":
            p, q = _grid_unit(rng, m), _grid_unit(rng, m)
            normal = _normalized(np.cross(p, q))
            a[rows] = _side(rng, m, ka, fa, -normal, (p, q))
            b[rows] = _side(rng, m, kb, fb, normal, v)
        else:
            if fa == "edge" and fb == "edge":
                normal = _normalized(np.cross(u, v))
            elif fa == "edge":
                normal = _across(rng, u)
            elif fb == "edge":
                normal = _across(rng, v)
            else:
                normal = _unit(rng, m)
            a[rows] = _side(rng, m, ka, fa, -normal, u)
            b[rows] = _side(rng, m, kb, fb, normal, v)
        b[rows] += gap * normal[:, None]
    shift = rng.integers(-4, 5, (n, 1, 3)).astype(np.float64)
    a, b = a + shift, b + shift
    return PairScene(_shuffle_rows(rng, a), _shuffle_rows(rng, b))


def _shuffle_rows(rng: np.random.Generator, shapes: np.ndarray) -> np.ndarray:
    """Reorder the vertices of each shape at random."""
    k = shapes.shape[1]
    order = rng.permuted(np.tile(np.arange(k), (len(shapes), 1)), axis=1)
    return np.take_along_axis(shapes, order[:, :, None], axis=1)


def pair_well_conditioned(rng: np.random.Generator, n: int, pair: str) -> PairScene:
    """Well-shaped segments and triangles of diameter 0.2 to 0.5 in the unit cube.

    Centers uniform in [0.25, 0.75]**3, independently for the two shapes:
    some pairs intersect, most are apart by up to about one diameter.
    """
    ka, kb = _pair_sizes(pair)
    a = _shape(rng, n, ka) * rng.uniform(0.2, 0.5, (n, 1, 1)) + rng.uniform(0.25, 0.75, (n, 1, 3))
    b = _shape(rng, n, kb) * rng.uniform(0.2, 0.5, (n, 1, 1)) + rng.uniform(0.25, 0.75, (n, 1, 3))
    return PairScene(a, b)


def pair_near_parallel(rng: np.random.Generator, n: int, pair: str, angle: float) -> PairScene:
    """An edge of shape b at `angle` (radians) from an edge or the plane of shape a.

    Shape a is well-shaped, of diameter 1, centered at the origin; an edge of
    it is picked (for a triangle, half the time its plane instead), and the
    first edge of shape b is that direction turned by `angle` (out of the
    plane for a plane).  That edge starts at a random point of the edge (or
    the face) of a, moved along the turned direction by up to one length
    either way (overlapping or staggered) and off it by 0, 1e-6 or up to 1
    (a third each); the rest of b is random.  Stresses the conditioning of
    the interior (edge-edge, edge-face) case, which is singular for parallel
    features.
    """
    ka, kb = _pair_sizes(pair)
    a = _shape(rng, n, ka)
    rows = np.arange(n)
    first = rng.integers(0, ka, n) if ka == 3 else np.zeros(n, dtype=np.int64)
    start, end = a[rows, first], a[rows, (first + 1) % ka]
    direction = end - start
    length = np.linalg.norm(direction, axis=-1, keepdims=True)
    unit = direction / length
    anchor = start + rng.random((n, 1)) * direction
    turn = _across(rng, unit)
    if ka == 3:
        plane = rng.random(n) < 0.5
        normal = _normals(a)
        in_plane = _normalized(np.cross(normal, _unit(rng, n)))
        bary = rng.dirichlet([1, 1, 1], n)
        unit = np.where(plane[:, None], in_plane, unit)
        turn = np.where(plane[:, None], normal, turn)
        anchor = np.where(plane[:, None], np.einsum("ni,nik->nk", bary, a), anchor)
    tilted = np.cos(angle) * unit + np.sin(angle) * turn
    off = np.select(
        [rng.random((n, 1)) < 1 / 3, rng.random((n, 1)) < 1 / 2], [0.0, 1e-6], rng.random((n, 1))
    ) * _across(rng, tilted)
    b0 = anchor + rng.uniform(-1, 1, (n, 1)) * length * tilted + off
    b1 = b0 + rng.uniform(0.2, 1.5, (n, 1)) * length * tilted
    b = np.stack([b0, b1], axis=1)
    if kb == 3:
        b = np.concatenate([b, (b0 + rng.standard_normal((n, 3)))[:, None]], axis=1)
    return PairScene(a, b)


def pair_parallel(rng: np.random.Generator, n: int, pair: str, kind: str) -> PairScene:
    """Exactly parallel features: collinear or coplanar, or parallel apart.

    Parameters
    ----------
    kind : {"touching", "apart"}
        Segments: shape b's first edge is ``p + [c0, c1] d`` on the line ``p +
        s d`` of shape a's ``[p, p + d]`` (``"touching"``: the same line) or
        on that line moved by a grid vector (``"apart"``), with ``d`` on the
        2**-20 grid and ``c0, c1`` multiples of 1/16 in [-2, 3]: exactly
        parallel, overlapping or not.  Against a segment, half the triangles
        have one such edge (the third vertex random, off the line); the
        other half are ``(p, p + u, p + v)`` with ``u, v`` on the grid and
        the segment from ``p + h m + alpha u + beta v`` along ``gamma u +
        delta v`` (multiples of 1/16; ``m`` on the grid, ``h = 0`` for
        ``"touching"``): parallel to the face in a generic orientation,
        above it or beside it.  Two triangles both lie
        in such planes, coplanar or apart, with vertices on the 2**-20 grid:
        they overlap in an area, or not.
    """
    ka, kb = _pair_sizes(pair)
    if kind not in ("touching", "apart"):
        raise ValueError(f"unknown kind {kind!r}")
    apart = kind == "apart"
    if (ka, kb) == (3, 3):
        flat_a = _dyadic(rng, (n, 3, 2), 20)
        flat_b = _dyadic(rng, (n, 3, 2), 20) * 0.5 + _dyadic(rng, (n, 1, 2), 4) * 0.5
        level = _dyadic(rng, (n, 1, 1), 20)
        height = _dyadic(rng, (n, 1, 1), 6) if apart else np.zeros((n, 1, 1))
        a = np.concatenate([flat_a, np.repeat(level, 3, axis=1)], axis=2)
        b = np.concatenate([flat_b, np.repeat(level + height, 3, axis=1)], axis=2)
        axes = rng.permuted(np.tile([0, 1, 2], (n, 1)), axis=1)[:, None, :]
        return PairScene(np.take_along_axis(a, axes, axis=2), np.take_along_axis(b, axes, axis=2))
    p = _dyadic(rng, (n, 3), 20)
    d = _dyadic(rng, (n, 3), 20)
    while np.any(zero := ~d.any(axis=1)):
        d[zero] = _dyadic(rng, (int(zero.sum()), 3), 20)
    c = rng.integers(-32, 49, (n, 2)) / 16.0
    shift = _dyadic(rng, (n, 3), 6) if apart else np.zeros((n, 3))
    a = np.stack([p, p + d], axis=1)
    b = np.stack([p + shift + c[:, :1] * d, p + shift + c[:, 1:] * d], axis=1)
    if kb == 3:
        b = np.concatenate([b, (p + rng.standard_normal((n, 3)))[:, None]], axis=1)
        # Half: the triangle (V0, V0 + u, V0 + v), the segment from V0 + h m +
        # alpha u + beta v along gamma u + delta v: exactly parallel to the
        # face (h = 0: in its plane), in a generic orientation, so that equal
        # distances to the face round differently.
        flat = rng.random(n) < 0.5
        u, v, m = _dyadic(rng, (3, n, 3), 20)
        alpha, beta, gamma, delta = rng.integers(-16, 33, (4, n, 1)) / 16.0
        h = 1.0 if apart else 0.0
        tri = np.stack([p, p + u, p + v], axis=1)
        start = p + h * m + alpha * u + beta * v
        seg = np.stack([start, start + gamma * u + delta * v], axis=1)
        a = np.where(flat[:, None, None], seg, a)
        b = np.where(flat[:, None, None], tri, b)
    return PairScene(a, _shuffle_rows(rng, b))


def pair_degenerate(rng: np.random.Generator, n: int, pair: str, kind: str) -> PairScene:
    """Zero-length segments and zero-area triangles, against either kind.

    Parameters
    ----------
    kind : {"point", "collinear", "two_coincident"}
        A degenerate triangle as in `degenerate`; a degenerate segment is a
        point (both endpoints one copy) for every kind.  Shape a, shape b or
        both are degenerate (a third each); the other is well-shaped.  Both
        shapes lie in [-1, 1]**3.
    """
    ka, kb = _pair_sizes(pair)
    which = rng.integers(0, 3, n)
    triangle_kind = {"point": "all_coincident", "collinear": "collinear", "two_coincident": "two_coincident"}
    if kind not in triangle_kind:
        raise ValueError(f"unknown kind {kind!r}")

    def degenerate_shapes(k: int) -> np.ndarray:
        if k == 3:
            return degenerate(rng, n, triangle_kind[kind]).vertices
        return np.repeat(rng.uniform(-1, 1, (n, 1, 3)), 2, axis=1)

    a = np.where((which != 1)[:, None, None], degenerate_shapes(ka), _shape(rng, n, ka))
    b = np.where((which != 0)[:, None, None], degenerate_shapes(kb), _shape(rng, n, kb))
    return PairScene(a, b)


def pair_magnitude(rng: np.random.Generator, n: int, pair: str, scale: float) -> PairScene:
    """Scale a `pair_well_conditioned` scene: every coordinate times `scale`."""
    scene = pair_well_conditioned(rng, n, pair)
    return PairScene(scene.a * scale, scene.b * scale)


def pair_offset(rng: np.random.Generator, n: int, pair: str, offset: float, size: float = 1e-3) -> PairScene:
    """A `pair_contact` scene of diameter `size` (gaps of up to `size` either way) far from the origin.

    Every coordinate is translated to a magnitude between ``offset / 2`` and
    `offset`, which rounds the shapes to the float spacing there.
    """
    scene = pair_contact(rng, n, pair, 0.0)
    gap = rng.uniform(-1, 1, (n, 1, 1)) * size
    shift = rng.choice([-1.0, 1.0], (n, 1, 3)) * rng.uniform(0.5, 1.0, (n, 1, 3)) * offset
    center = scene.a.mean(axis=1, keepdims=True)
    a = (scene.a - center) * size + shift
    b = (scene.b - center) * size + shift + gap * _unit(rng, n)[:, None]
    return PairScene(a, b)


def pair_far(rng: np.random.Generator, n: int, pair: str, ratio: float) -> PairScene:
    """Shapes of diameter 1 whose centers are `ratio` apart, in a random direction."""
    ka, kb = _pair_sizes(pair)
    b = _shape(rng, n, kb) + ratio * _unit(rng, n)[:, None]
    return PairScene(_shape(rng, n, ka), b)


# -- registries ----------------------------------------------------------------------


class Family(NamedTuple):
    """One generator with one parameter setting.

    Attributes
    ----------
    name : str
        The generator's name.
    generator : callable
        Called as ``generator(rng, n, **params)``.
    params : mapping
        Keyword arguments of the generator (read-only).
    difficulty : float or None
        The swept parameter's value, for plotting error against it; None for
        families without a numeric sweep.
    """

    name: str
    generator: Callable[..., Any]
    params: Mapping[str, Any]
    difficulty: float | None

    @property
    def label(self) -> str:
        """A unique, readable identifier such as ``"sliver[rel_height=1e-12]"``."""
        if not self.params:
            return self.name
        args = ",".join(
            f"{key}={value!r}" if isinstance(value, str) else f"{key}={value:g}"
            for key, value in self.params.items()
        )
        return f"{self.name}[{args}]"

    def __call__(self, rng: np.random.Generator, n: int) -> Any:
        """Generate the scene: ``generator(rng, n, **params)``."""
        return self.generator(rng, n, **self.params)


def _sweep(generator: Callable[..., Any], **sweep: tuple) -> list[Family]:
    """List the families of one generator.

    One family without parameters, or one per value of the single swept keyword.
    """
    if not sweep:
        return [Family(generator.__name__, generator, MappingProxyType({}), None)]
    ((key, values),) = sweep.items()
    return [
        Family(
            generator.__name__,
            generator,
            MappingProxyType({key: value}),
            None if isinstance(value, str) else value,
        )
        for value in values
    ]


TRIANGLE_FAMILIES: list[Family] = [
    *_sweep(well_conditioned),
    *_sweep(near_surface, offset=(1e-3, 1e-6, 1e-9, 1e-12, 1e-15)),
    *_sweep(sliver, rel_height=(1e-6, 1e-9, 1e-12, 1e-15, 1e-17)),
    *_sweep(degenerate, kind=("collinear", "two_coincident", "all_coincident")),
    *_sweep(needle, rel_width=(1e-3, 1e-6, 1e-9, 1e-12, 1e-15)),
    *_sweep(small, size=(1e-3, 1e-6, 1e-9)),
    *_sweep(offset, offset=(1e4, 1e6, 1e8, 1e10)),
    *_sweep(far_points, ratio=(1e3, 1e4, 1e6, 1e8)),
    *_sweep(magnitude, scale=(1e-300, 1e-150, 1e-50, 1e50, 1e150, 1e300)),
    *_sweep(on_feature, kind=("vertex", "edge", "plane")),
]
"""Every triangle family with its parameter sweep."""

DISK_FAMILIES: list[Family] = [
    *_sweep(disk_well_conditioned),
    *_sweep(disk_axis, rel_distance=(1e-8, 1e-16, 1e-100, 1e-300, 0.0)),
    *_sweep(disk_rim, rel_distance=(1e-3, 1e-8, 1e-13)),
    *_sweep(disk_in_plane),
    *_sweep(disk_offset, offset=(1e4, 1e6, 1e8, 1e10)),
    *_sweep(disk_unnormalized),
]
"""Every circle and disk family with its parameter sweep."""


def _pair_sweep(generator: Callable[..., Any], pair: str, **sweep: tuple) -> list[Family]:
    """`_sweep` for a pair generator, with ``pair`` fixed."""
    return [
        Family(
            family.name,
            family.generator,
            MappingProxyType({"pair": pair, **family.params}),
            family.difficulty,
        )
        for family in _sweep(generator, **sweep)
    ]


PAIR_FAMILIES: Mapping[str, list[Family]] = MappingProxyType(
    {
        pair: [
            *_pair_sweep(pair_well_conditioned, pair),
            *_pair_sweep(pair_contact, pair, gap=(-1e-12, 0.0, 1e-12)),
            *_pair_sweep(pair_near_parallel, pair, angle=(1e-1, 1e-4, 1e-8, 1e-12, 1e-15)),
            *_pair_sweep(pair_parallel, pair, kind=("touching", "apart")),
            *_pair_sweep(pair_degenerate, pair, kind=("point", "collinear", "two_coincident")),
            *_pair_sweep(pair_magnitude, pair, scale=(1e-300, 1e-150, 1e150, 1e300)),
            *_pair_sweep(pair_offset, pair, offset=(1e4, 1e7, 1e10)),
            *_pair_sweep(pair_far, pair, ratio=(1e3, 1e6, 1e9)),
        ]
        for pair in PAIRS
    }
)
"""Every pair family with its parameter sweep, per pair of shapes (a key of `PAIRS`)."""
