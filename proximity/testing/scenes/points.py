"""Scene families from a point: triangles, circles and disks (see :mod:`proximity.testing.scenes`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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
