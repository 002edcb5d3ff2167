"""Scene families of pairs of shapes: segments and triangles (see :mod:`proximity.testing.scenes`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from .points import _dyadic, _normalized, _normals, _unit, _well_shaped, degenerate

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
