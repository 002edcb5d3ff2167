"""Pairs with a mesh or a scene on a side: the descent's driver, and its certified rows finished exactly.

:mod:`proximity.pair.descent` searches; this module sets the sides up
(a collection's tree, or a batch of primitives as a forest), splits a
large single query into tasks for the threads, and finishes in rational
arithmetic the queries whose least candidate the certified filter left
undecided.
"""

from fractions import Fraction

import numpy as np

from .. import primitives
from ..methods import CERTIFIED
from ..numerics import exact
from ..numerics.rounding import unfaithful
from ..runtime import lazy, threads


def _broadphase():
    return lazy.load("proximity.pair.descent")


def side_of(collection=None, kinds=None, params=None):
    """A side of a descent, ``(PairTree, depth, kinds present)``: a collection's tree, or a
    batch of primitive rows as a forest (depth 0)."""
    bp = _broadphase()
    if collection is not None:
        tree = collection._tree
        side = bp.from_tree(tree)
        return side, int(tree.depth), tree.present, bp.node_data(tree)[1]
    side = bp.forest(kinds, params)
    return side, 0, primitives.present(kinds), bp.side_magnitude(side)


def closest(sides, method, starts, radii, cutoff, pose, full, names):
    """The closest pair of primitives of each query: a dict of flat outputs (see
    :data:`proximity.pair.descent.Outputs`).

    ``starts`` is ``(start_a, start_b)``, the nodes each query starts at;
    ``radii`` ``(radius_a, radius_b)`` the sides' outer radii per query,
    ``cutoff`` the per-query ``max_distance`` (inf for none); ``pose`` a 3 x 4
    ``[R | t]`` for side b, or None.
    """
    bp = _broadphase()
    (side_a, depth_a, kinds_a, m_a), (side_b, depth_b, kinds_b, m_b) = sides
    present = bp.present_pairs(kinds_a, kinds_b, names)
    for p in present:
        if method.name not in p.methods:
            raise ValueError(f"method must be one of {p.methods} for a {p.a.name} and a {p.b.name}; got "
                             f"{method.name!r}")  # fmt: skip
    if pose is not None and any(k.vertices == 0 for k in kinds_b):
        names_b = ", ".join(k.name for k in kinds_b if k.vertices == 0)
        raise NotImplementedError(f"{names[1]} holds {names_b}, which cannot be posed in a pair query")
    n = len(starts[0])
    m = n if full else 0
    out = bp.Outputs(
        signed=np.empty(n), distance=np.empty(n), sqr_distance=np.empty(m), point_a=np.empty((m, 3)),
        point_b=np.empty((m, 3)), feature_a=np.empty(m, np.int8), feature_b=np.empty(m, np.int8),
        extra_a=np.empty((m, 3)), extra_b=np.empty((m, 3)), index_a=np.empty(m, np.int64),
        index_b=np.empty(m, np.int64), row_a=np.empty(m, np.int64), row_b=np.empty(m, np.int64),
        radius_a=np.empty(m), radius_b=np.empty(m), undecided=np.empty(n),
    )  # fmt: skip
    radius_a = np.ascontiguousarray(radii[0], np.float64)
    radius_b = np.ascontiguousarray(radii[1], np.float64)
    # Exactly the types of the descent's signature: it is called without Numba's dispatch.
    queries = bp.Queries(
        np.ascontiguousarray(starts[0], np.int64), np.ascontiguousarray(starts[1], np.int64),
        radius_a, radius_b, np.ascontiguousarray(cutoff, np.float64),
    )  # fmt: skip
    rmax = (
        (float(radius_a[0]) + float(radius_b[0]))
        if n == 1
        else (float(np.max(radius_a, initial=0.0)) + float(np.max(radius_b, initial=0.0)))
    )
    for side in (side_a, side_b):
        if side.params.shape[1] > primitives.N_PARAMS:
            rmax += float(np.max(side.params[:, primitives.N_PARAMS], initial=0.0))
    magnitude = bp.magnitude(m_a, m_b, pose, rmax)
    pose_array = np.zeros((3, 4)) if pose is None else np.ascontiguousarray(pose, np.float64)
    depth, magnitude = int(depth_a + depth_b), float(magnitude)
    column = [
        primitives.N_PARAMS if s.params.shape[1] > primitives.N_PARAMS else -1 for s in (side_a, side_b)
    ]
    if n == 0:  # an empty batch against a collection: no kinds of pairs to compile a descent for
        result = out._asdict()
        del result["undecided"]
        return result
    descend = bp.descent_kernel(method, present, pose is not None, column[0], column[1])
    args = (side_a, side_b, pose_array, depth, magnitude, queries, out, full)
    # Queries differ in work by orders of magnitude: handed out one at a time.
    threads.spread(lambda lo, hi: descend(lo, hi, *args), n, 1)
    rows = np.flatnonzero(~np.isnan(out.undecided))
    for q in rows:
        _resolve(side_a, side_b, present, q, queries, pose_array if pose is not None else None, depth,
                 magnitude, column, out, full)  # fmt: skip
    result = out._asdict()
    del result["undecided"]
    return result


def posed_rows(rows, kinds, pose):
    """Stored rows with their vertices posed by ``pose`` (3 x 4) as the descent poses them."""
    rows = np.array(rows, dtype=np.float64, copy=True)
    if pose is None:
        return rows
    counts = primitives.vertex_counts()[np.asarray(kinds, np.intp)]
    for v in range(3):
        sel = counts > v
        x = rows[sel, 3 * v : 3 * v + 3]
        posed = np.empty_like(x)
        for r in range(3):
            posed[:, r] = ((pose[r, 0] * x[:, 0] + pose[r, 1] * x[:, 1]) + pose[r, 2] * x[:, 2]) + pose[r, 3]
        rows[sel, 3 * v : 3 * v + 3] = posed
    return rows


def certified_answers(pair, rows_a, rows_b):
    """The certified answers of ``pair`` for row pairs ``rows_a[i]``, ``rows_b[i]`` (stored
    rows, shape a's first), exact fallback included: a dict of arrays in the pair's order,
    as :data:`proximity.pair.kernels.LAYOUT` names them (``point`` and ``feature`` are a's)."""
    pk = lazy.load("proximity.pair.kernels")
    n = len(rows_a)
    if pair.point:
        (points, other), kind = ((rows_b, rows_a), pair.a) if pair.swapped else ((rows_a, rows_b), pair.b)
        out = {name: [] for name in ("distance", "sqr_distance", "point", "feature", "point_b", "feature_b",
                                     "extra_a", "extra_b")}  # fmt: skip
        for i in range(n):
            r = kind.kernels.resolve(kind.code, other[i : i + 1, : kind.width], points[i, :3].copy())
            values = dict(distance=r["distance"][0], sqr_distance=r["sqr_distance"][0], point=points[i, :3],
                          feature=0, point_b=r["point"][0], feature_b=r["feature"][0],
                          extra_a=np.full(3, np.nan), extra_b=r["extra"][0])  # fmt: skip
            for name, value in values.items():
                out[name].append(value)
        out = {name: np.array(value) for name, value in out.items()}
        return _swap(out) if pair.swapped else out
    inner = pair.unswapped
    first, second = (rows_b, rows_a) if pair.swapped else (rows_a, rows_b)
    wa, wb = 3 * inner.a.vertices, 3 * inner.b.vertices
    a = np.ascontiguousarray(first[:, :wa])
    b = np.ascontiguousarray(second[:, :wb])
    out = pk.query(inner, CERTIFIED, a, b, (n,), True)
    return _swap(out) if pair.swapped else out


def _swap(out):
    swapped = dict(out)
    swapped["point"], swapped["point_b"] = out["point_b"], out["point"]
    swapped["feature"], swapped["feature_b"] = out["feature_b"], out["feature"]
    swapped["extra_a"], swapped["extra_b"] = out["extra_b"], out["extra_a"]
    return swapped


def _resolve(side_a, side_b, present, q, queries, pose, depth, magnitude, column, out, full):
    """Finish query ``q``: every pair of primitives within its bound, certified (exact fallback
    included), the least ``d - r`` winning, ties to the lowest indices."""
    bp = _broadphase()
    found = bp.gather(side_a, side_b, pose, depth, magnitude, queries, q, out.undecided[q], column)
    if len(found) == 0:
        return
    ka, kb = found[:, 0], found[:, 1]
    rows_b = posed_rows(side_b.params[kb], side_b.kinds[kb], pose)
    rows_a = side_a.params[ka]
    answers = []
    by_code = {p.code: p for p in present}
    for code in np.unique(side_a.kinds[ka].astype(np.int64) * len(primitives.BY_CODE) + side_b.kinds[kb]):
        pair = by_code[int(code)]
        sel = np.flatnonzero((side_a.kinds[ka] == pair.a.code) & (side_b.kinds[kb] == pair.b.code))
        r = certified_answers(pair, rows_a[sel], rows_b[sel])
        ra = queries.radius_a[q] + (rows_a[sel, column[0]] if column[0] >= 0 else 0.0)
        rb = queries.radius_b[q] + (rows_b[sel, column[1]] if column[1] >= 0 else 0.0)
        d = r["distance"]
        # Each row's radii: the rows' own (a column) or the query's (one for all of them).
        ra, rb = np.broadcast_to(ra, d.shape), np.broadcast_to(rb, d.shape)
        e = _minus_radii(d, ra, rb, pair, rows_a[sel], rows_b[sel])
        for j, i in enumerate(sel):
            if not np.isnan(e[j]):
                ia, ib = side_a.index[ka[i]], side_b.index[kb[i]]
                answers.append((float(e[j]), int(ia), int(ib), r, j, int(ka[i]), int(kb[i]), ra[j], rb[j]))
    if not answers:
        return
    e, ia, ib, r, j, row_a, row_b, ra, rb = min(answers, key=lambda t: (t[0], t[1], t[2]))
    if not e <= queries.cutoff[q]:
        out.signed[q], out.distance[q] = np.inf, np.inf
        if full:
            out.index_a[q] = out.index_b[q] = out.row_a[q] = out.row_b[q] = -1
        return
    out.signed[q] = e
    out.distance[q] = r["distance"][j]
    if full:
        out.sqr_distance[q] = r["sqr_distance"][j]
        out.point_a[q], out.point_b[q] = r["point"][j], r["point_b"][j]
        out.feature_a[q], out.feature_b[q] = r["feature"][j], r["feature_b"][j]
        out.extra_a[q], out.extra_b[q] = r["extra_a"][j], r["extra_b"][j]
        out.index_a[q], out.index_b[q], out.row_a[q], out.row_b[q] = ia, ib, row_a, row_b
        out.radius_a[q], out.radius_b[q] = ra, rb


def _minus_radii(d, ra, rb, pair, rows_a, rows_b):
    """``d - (ra + rb)`` certified: faithful for the exact ``d* - ra - rb`` (``d`` faithful),
    rows where the float path cannot tell finished in rational arithmetic."""
    d = np.asarray(d, np.float64)
    if not (np.any(ra) or np.any(rb)):
        return d.copy()
    r = ra + rb
    with np.errstate(invalid="ignore"):
        e = d - r
        back = r - ra
        err = (ra - (r - back)) + (rb - back)  # TwoSum: r + err == ra + rb exactly
    bad = set(unfaithful(e, d, r).tolist()) | set(np.flatnonzero(err != 0).tolist())
    e = np.array(e, copy=True)
    for k in sorted(bad):
        if not np.isfinite(d[k]):
            continue
        bounds = lazy.load("proximity.pair.kernels").exact_sqr_bounds(pair, rows_a[k], rows_b[k])
        e[k] = exact.minus_radius(bounds, Fraction(float(ra[k])) + Fraction(float(rb[k])))
    return e


minus_radii = _minus_radii
