"""Signed distance grids (:meth:`proximity.TriangleMesh.sdf_grid`): blocks of points, far ones skipped.

The grid is cut into blocks of :data:`BLOCK` points a side.  Each block's
centre ``c`` and half-diagonal ``r`` (rounded up past the rounding of the
centre) bound its points: every point is within ``r`` of ``c``, so its
distance to the surface is at least ``d(c) - r``.  A block is

* *far* where ``d(c) - r`` exceeds the band: its points get ``±inf`` by the
  side of ``c``, with no distance;
* *clear* where ``d(c) > r``: the block does not touch the surface, and on a
  closed mesh the winding number (so the side) is the same at all its
  points: their unsigned distances are queried, with the side of ``c``;
* otherwise each point gets :meth:`~proximity.TriangleMesh.signed_distance`.

With a band, the points left are grouped again in blocks of 2 points a side,
and those beyond the band are skipped the same way.

A block's side is used only where it is certain and the sign is exact (the
winding number, or the pseudonormal on a solid); else its points get their
own sides.  Points are queried one slab of blocks (along x) at a time.
"""

import numpy as np

#: Points along each side of a block.
BLOCK = 8
EPS = 2.0**-52

# Categories of blocks (and points): each its own signed distance; their block's side
# and unsigned distances; ±inf by their block's side; each its own side, ±inf; filled.
_OWN, _CLEAR, _FAR, _FAR_OWN, _DONE = 0, 1, 2, 3, 4


def _blocks(axis, n):
    """``(start, stop, centre, half-extent)`` of the blocks along one axis, half-extent rounded up."""
    start = np.arange(0, n, BLOCK)
    stop = np.minimum(start + BLOCK, n)
    first, last = axis[start], axis[stop - 1]
    centre = first * 0.5 + last * 0.5
    half = np.maximum(np.abs(last - centre), np.abs(centre - first))
    with np.errstate(over="ignore"):  # inf past the float range: the block is never skipped
        return start, stop, centre, half * (1.0 + 4.0 * EPS) + 4.0 * EPS * np.abs(centre)


def axis(low, high, n):
    """``np.linspace(low, high, n)``; where ``high - low`` overflows, twice the points between
    the halves, ``low / 2`` and ``high / 2`` (exact: such corners are far from underflow), the
    points ``linspace`` would give without the overflow."""
    with np.errstate(over="ignore"):
        span = high - low
    if np.isfinite(span):
        return np.linspace(low, high, n)
    return np.linspace(low * 0.5, high * 0.5, n) * 2.0


def sdf_grid(mesh, low, high, shape, band, method, sign):
    """See :meth:`proximity.TriangleMesh.sdf_grid` (arguments validated there)."""
    axes = [axis(low[a], high[a], shape[a]) for a in range(3)]
    out = np.empty(shape)
    blocks = [_blocks(axes[a], shape[a]) for a in range(3)]
    centres = np.stack(np.meshgrid(*[b[2] for b in blocks], indexing="ij"), axis=-1)
    halves = np.stack(np.meshgrid(*[b[3] for b in blocks], indexing="ij"), axis=-1)
    n_blocks = centres.shape[:3]
    with np.errstate(over="ignore"):  # a radius past the float range is inf: no block is skipped
        radius = np.sqrt(np.sum(halves * halves, axis=-1)) * (1.0 + 4.0 * EPS)

    category = np.full(n_blocks, _OWN, np.int8)
    block_sign = np.ones(n_blocks)
    h = mesh._hierarchy()
    # A block's side stands for its points' where the sign is exact: the winding number, or
    # the pseudonormal on a solid ("auto" turns to the winding number elsewhere).
    exact_side = h.integral and (sign != "pseudonormal" or mesh.validity.solid)
    if exact_side or band is not None:
        flat = centres.reshape(-1, 3)
        d = np.asarray(mesh.distance(flat, method=method)).reshape(n_blocks)
        clear = d > radius
        with np.errstate(invalid="ignore"):  # inf - inf: not known to be far
            far = clear & (d - radius > band) if band is not None else np.zeros(n_blocks, dtype=bool)
        if exact_side:
            rows = np.flatnonzero(clear.reshape(-1))
            _, _, inside, certain = mesh._signed(flat[rows], method, sign, warn=False)
            sure = np.zeros(n_blocks, dtype=bool)
            sure.reshape(-1)[rows] = certain
            block_sign.reshape(-1)[rows] = np.where(inside, -1.0, 1.0)
            category[clear & sure] = _CLEAR
            category[far & sure] = _FAR
            category[far & ~sure] = _FAR_OWN
        else:
            category[far] = _FAR_OWN

    for bx in range(n_blocks[0]):
        xs = slice(blocks[0][0][bx], blocks[0][1][bx])
        width = xs.stop - xs.start
        cat = np.array(_spread(category[bx], width, shape))
        sides = _spread(block_sign[bx], width, shape).reshape(-1)
        slab = out[xs]
        far = cat == _FAR
        slab[far] = np.inf * sides.reshape(cat.shape)[far]
        flat = slab.reshape(-1)
        local = [axes[0][xs], axes[1], axes[2]]
        if band is not None:
            # Blocks of 2 points a side within those that touch the band: far ones skipped too.
            _refine(mesh, local, cat, sides, flat, band, method, sign, exact_side)
        for kind in (_CLEAR, _OWN, _FAR_OWN):
            index = np.flatnonzero(cat.reshape(-1) == kind)
            if len(index) == 0:
                continue
            points = _points(local, np.unravel_index(index, cat.shape))
            if kind == _CLEAR:
                value = np.asarray(mesh.distance(points, method=method)) * sides[index]
            elif kind == _OWN:
                _, distance, inside, _ = mesh._signed(points, method, sign, warn=False)
                value = np.where(inside, -distance, distance)
            else:
                inside = _sides(mesh, points, method, sign)
                value = np.where(inside, -np.inf, np.inf)
            value = value + 0.0  # -0.0 + 0.0 is +0.0
            if band is not None:
                value = np.where(np.abs(value) > band, np.copysign(np.inf, value), value)
            flat[index] = value
    return out


def _points(local, ijk):
    i, j, k = ijk
    return np.stack([local[0][i], local[1][j], local[2][k]], axis=-1)


def _refine(mesh, local, cat, sides, flat, band, method, sign, exact_side):
    """Within a slab, blocks of 2 points a side of the points still to query (categories
    ``_CLEAR`` and ``_OWN``): those beyond the band get ``±inf`` (their own centre's side
    where their block has none) and leave their category, ``cat``, for ``_DONE``."""
    todo = np.flatnonzero((cat.reshape(-1) == _CLEAR) | (cat.reshape(-1) == _OWN))
    if len(todo) == 0:
        return
    i, j, k = np.unravel_index(todo, cat.shape)
    n1, n2 = (cat.shape[1] + 1) // 2, (cat.shape[2] + 1) // 2
    keys, group = np.unique(((i // 2) * n1 + j // 2) * n2 + k // 2, return_inverse=True)
    group = group.reshape(-1)
    sub = ((keys // n2) // n1, (keys // n2) % n1, keys % n2)
    centre, half = [], []
    for a in range(3):
        first = 2 * sub[a]
        last = np.minimum(first + 1, len(local[a]) - 1)
        lo, hi = local[a][first], local[a][last]
        c = lo * 0.5 + hi * 0.5
        centre.append(c)
        with np.errstate(over="ignore"):
            h = np.maximum(np.abs(hi - c), np.abs(c - lo)) * (1.0 + 4.0 * EPS) + 4.0 * EPS * np.abs(c)
        half.append(h)
    centre = np.stack(centre, axis=-1)
    with np.errstate(over="ignore"):  # inf past the float range: the block is never skipped
        radius = np.sqrt(sum(h * h for h in half)) * (1.0 + 4.0 * EPS)
    d = np.asarray(mesh.distance(centre, method=method))
    with np.errstate(invalid="ignore"):  # inf - inf: not known to be far
        far = d - radius > band
    if not far.any():
        return
    # The side of each far block: its points' block's where that is known (a clear
    # block's), else its own centre's where the sign is exact and certain.
    kind = cat.reshape(-1)[todo]
    side = np.zeros(len(keys))
    clear_side = kind == _CLEAR
    side[group[clear_side]] = sides[todo[clear_side]]
    ask = np.flatnonzero(far & (side == 0.0))
    if exact_side and len(ask):
        _, _, inside, certain = mesh._signed(centre[ask], method, sign, warn=False)
        side[ask[certain]] = np.where(inside[certain], -1.0, 1.0)
    done = far[group] & (side[group] != 0.0)
    flat[todo[done]] = np.inf * side[group[done]]
    cat.reshape(-1)[todo[done]] = _DONE
    # Far blocks without a known side: each point its own side, no distance.
    alone = far[group] & (side[group] == 0.0)
    cat.reshape(-1)[todo[alone]] = _FAR_OWN


def _spread(per_block, width, shape):
    """A slab's array of blocks ``(by, bz)`` spread over its points ``(width, ny, nz)``."""
    spread = np.repeat(np.repeat(per_block, BLOCK, axis=0), BLOCK, axis=1)[: shape[1], : shape[2]]
    return np.broadcast_to(spread, (width, *spread.shape))


def _sides(mesh, points, method, sign):
    """Each point's side alone, without its distance where the winding number gives it."""
    if sign == "winding" or (sign == "auto" and not mesh.validity.solid):
        inside, _ = mesh._winding_sides(points, np.ones(len(points)))
        return inside
    _, _, inside, _ = mesh._signed(points, method, sign, warn=False)
    return inside
