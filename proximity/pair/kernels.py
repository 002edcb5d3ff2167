"""The compiled code every pair of primitives shares: batch blocks, the fast path, stored rows.

Written once, for every :class:`proximity.pair.table.Pair`, with the pair's
functions and sizes bound by :func:`proximity.runtime.jit.specialize`:

* the batch of a pair kernel runs through :func:`proximity.runtime.batch.run`
  over :data:`LAYOUT` (shape a's rows as the shape's array, shape b's
  rows in the place of the points): blocks of :data:`~._loops.BLOCK`
  pairs are gathered into local scratch, computed by a loop over the
  kernel's ``robust_unscaled`` that compiles to SIMD code, and the pairs
  outside its safe window redone by ``robust``; ``certified`` goes pair by
  pair and leaves undecided pairs to the exact fallback;
* the fast path of two single shapes calls the kernel once, through its
  compiled entry point;
* the descent of two hierarchies (:mod:`proximity.pair.descent`) calls
  :func:`row_query`'s functions on stored rows, which give every pair the
  same answer: ``(status, distance, sqr_distance, pax, pay, paz, pbx, pby,
  pbz, feature_a, feature_b, a0, a1, a2, b0, b1, b2)``, the parameters of
  each side padded with NaN.

A pair kernel's answer is ``(distance, sqr_distance, point_a, point_b,
feature_a, feature_b, parameters of a, parameters of b)``, the parameters
as many as the record's ``extras`` say.
"""

import functools
import math

import numpy as np
from numba.core import types

from ..features import NONE, VERTEX0
from ..numerics import exact as _exact
from ..numerics.certified import CERTAIN
from ..runtime.batch import Layout, run
from ..runtime.jit import inline, specialize
from ..runtime.loops import BLOCK

NAN = math.nan

#: The arrays of a pair batch: shape a's rows (``"a"``), shape b's rows in
#: the place of the points, and the outputs after the common ones
#: (``point`` and ``feature`` are shape a's).
LAYOUT = Layout(
    "pair",
    flags=(),
    arrays=(("a", 1),),
    extra=(("point_b", np.float64, 3), ("feature_b", np.int8, 1), ("extra_a", np.float64, 3),
           ("extra_b", np.float64, 3)),
)  # fmt: skip


# -- a row's coordinates, as arguments ------------------------------------------


@inline
def _at3(z, f, q):
    return z[f, q], z[f + 1, q], z[f + 2, q]


@inline
def _at6(z, f, q):
    return z[f, q], z[f + 1, q], z[f + 2, q], z[f + 3, q], z[f + 4, q], z[f + 5, q]


@inline
def _at9(z, f, q):
    return (
        z[f, q], z[f + 1, q], z[f + 2, q], z[f + 3, q], z[f + 4, q], z[f + 5, q],
        z[f + 6, q], z[f + 7, q], z[f + 8, q],
    )  # fmt: skip


@inline
def _take3(p, k):
    return p[k, 0], p[k, 1], p[k, 2]


@inline
def _take6(p, k):
    return p[k, 0], p[k, 1], p[k, 2], p[k, 3], p[k, 4], p[k, 5]


@inline
def _take9(p, k):
    return p[k, 0], p[k, 1], p[k, 2], p[k, 3], p[k, 4], p[k, 5], p[k, 6], p[k, 7], p[k, 8]


#: By the width of a side's row (``3 * vertices``): its values from block
#: scratch (``(z, first row, column)``) and from stored rows (``(params, k)``).
_AT = {3: _at3, 6: _at6, 9: _at9}
_TAKE = {3: _take3, 6: _take6, 9: _take9}


# -- a kernel's parameters, each side's padded to three --------------------------


@inline
def _split_1_1(t):
    return (t[0], NAN, NAN), (t[1], NAN, NAN)


@inline
def _split_1_3(t):
    return (t[0], NAN, NAN), (t[1], t[2], t[3])


@inline
def _split_3_3(t):
    return (t[0], t[1], t[2]), (t[3], t[4], t[5])


_SPLIT = {(1, 1): _split_1_1, (1, 3): _split_1_3, (3, 3): _split_3_3}


# -- placeholders, bound per pair and method by specialize ----------------------

# The pair's scalar functions: ``robust`` and ``robust_unscaled`` (no
# status), the per-method query of two tuples (status first).
ROBUST = UNSCALED = QUERY = TOUCHING = None
# The arguments of each side, from scratch and from stored rows.
AT_A = AT_B = TAKE_A = TAKE_B = None
# Widths of the sides' rows, and the number of their parameters in the answer.
WA = WB = 9
EA = EB = 3
SPLIT = None
# A point query's stored-row function, and a row function to call with the sides exchanged.
ROW = INNER = None


def _robust_query(a, b):
    """``ROBUST`` of the tuples ``a`` and ``b``, status first (always certain)."""
    return (CERTAIN,) + ROBUST(*a, *b)


def _certified_query(a, b):
    """``ROBUST``, bound to a ``certified`` kernel: the status is its own."""
    return ROBUST(*a, *b)


# -- batch blocks -----------------------------------------------------------------


@inline
def _gather(z, first, width, V, n_j, k0, nb):
    """Rows ``first .. first + width - 1`` of ``z``: the rows ``V[i, j]`` of
    pairs ``k0 .. k0 + nb`` of an ``(I, J)`` loop, one pair per column, as
    :func:`proximity.runtime.loops.gather_triangles` does; the tail zeroed."""
    i = k0 // n_j
    j = k0 - i * n_j
    q = 0
    while q < nb:
        run_ = min(nb - q, n_j - j)
        Vi = V[i]
        for t in range(run_):
            for c in range(width):
                z[first + c, q + t] = Vi[j + t, c]
        q += run_
        i += 1
        j = 0
    for c in range(width):
        for q in range(nb, BLOCK):
            z[first + c, q] = 0.0


@inline
def _put(z, first, q, r):
    """Column ``q`` of rows ``first ..``: a kernel's answer (no status)."""
    z[first, q], z[first + 1, q] = r[0], r[1]
    z[first + 2, q], z[first + 3, q], z[first + 4, q] = r[2], r[3], r[4]
    z[first + 5, q], z[first + 6, q], z[first + 7, q] = r[5], r[6], r[7]
    z[first + 8, q], z[first + 9, q] = r[8], r[9]
    tail = r[10:]
    for c in range(len(tail)):
        z[first + 10 + c, q] = tail[c]


@inline
def _scatter(z, first, k0, nb, out, full, ea_count, eb_count):
    """Pairs ``k0 .. k0 + nb`` from rows ``first ..`` into the outputs record;
    each side has ``ea_count`` and ``eb_count`` parameters."""
    dist = out[0][k0 : k0 + nb]
    for q in range(nb):
        dist[q] = z[first, q]
    if full:
        sqr, pa, fa = out[1][k0 : k0 + nb], out[2][k0 : k0 + nb], out[3][k0 : k0 + nb]
        pb, fb = out[4][k0 : k0 + nb], out[5][k0 : k0 + nb]
        ea, eb = out[6][k0 : k0 + nb], out[7][k0 : k0 + nb]
        for q in range(nb):
            sqr[q] = z[first + 1, q]
            for c in range(3):
                pa[q, c] = z[first + 2 + c, q]
                pb[q, c] = z[first + 5 + c, q]
                ea[q, c] = z[first + 10 + c, q] if c < ea_count else NAN
                eb[q, c] = z[first + 10 + ea_count + c, q] if c < eb_count else NAN
            fa[q] = np.int8(z[first + 8, q])
            fb[q] = np.int8(z[first + 9, q])


def _robust_block(shape, P, n_j, k0, nb, out, exact, full):
    """Robust pairs ``k0 .. k0 + nb`` of a batch (see :mod:`proximity.runtime.batch`):
    a loop over ``robust_unscaled`` that compiles to SIMD code, then
    ``robust`` for the pairs outside its safe window."""
    out_row = WA + WB
    ok_row = out_row + 10 + EA + EB
    z = np.empty((ok_row + 1, BLOCK))
    _gather(z, 0, WA, shape.a, n_j, k0, nb)
    _gather(z, WA, WB, P, n_j, k0, nb)
    for q in range(BLOCK):
        r = UNSCALED(*AT_A(z, 0, q), *AT_B(z, WA, q))
        _put(z, out_row, q, r[1:])
        z[ok_row, q] = r[0]
    for q in range(nb):
        if z[ok_row, q] == 0.0:
            _put(z, out_row, q, ROBUST(*AT_A(z, 0, q), *AT_B(z, WA, q)))
    _scatter(z, out_row, k0, nb, out, full, EA, EB)


def _certified_block(shape, P, n_j, k0, nb, out, exact, full):
    """Certified pairs ``k0 .. k0 + nb`` of a batch, one by one; ``exact``
    flags the pairs left to the exact fallback."""
    out_row = WA + WB
    z = np.empty((out_row + 10 + EA + EB, BLOCK))
    _gather(z, 0, WA, shape.a, n_j, k0, nb)
    _gather(z, WA, WB, P, n_j, k0, nb)
    for q in range(nb):
        r = QUERY(AT_A(z, 0, q), AT_B(z, WA, q))
        exact[k0 + q] = r[0] != CERTAIN
        _put(z, out_row, q, r[1:])
    _scatter(z, out_row, k0, nb, out, full, EA, EB)


def _bindings(pair, method):
    """The placeholders of ``pair``'s kernel (its sides in the module's order) for ``method``."""
    k = pair.kernels
    wa, wb = (3 * p.vertices for p in ((pair.b, pair.a) if pair.swapped else (pair.a, pair.b)))
    ea, eb = pair.extras
    scalar = k.certified if method.exact_fallback else k.robust
    query = _certified_query if method.exact_fallback else _robust_query
    tag = f"{pair.name}__{method.name}"
    return {
        "ROBUST": scalar,
        "UNSCALED": k.robust_unscaled,
        "QUERY": specialize(query, tag, role="inline", ROBUST=scalar),
        "AT_A": _AT[wa],
        "AT_B": _AT[wb],
        "TAKE_A": _TAKE[wa],
        "TAKE_B": _TAKE[wb],
        "WA": wa,
        "WB": wb,
        "EA": ea,
        "EB": eb,
        "SPLIT": _SPLIT[ea, eb],
    }


@functools.cache
def _block(pair, method):
    """The block function of a pair kernel (``pair`` unswapped) for ``method``."""
    func = _certified_block if method.exact_fallback else _robust_block
    tag = f"{pair.name}__{method.name}"
    return specialize(func, tag, LAYOUT.block_signature, role="pointer", **_bindings(pair, method))


class _Kernels:
    """What :func:`proximity.runtime.batch.run` asks of a pair kernel (``pair`` unswapped)."""

    def __init__(self, pair):
        self.pair = pair

    def block(self, method, one):
        return _block(self.pair, method)

    def exact(self, a, b):
        return _layout_order(exact(self.pair, a, b), self.pair.extras)


def _layout_order(answer, extras):
    """A kernel's answer in the order of :data:`LAYOUT`'s outputs, parameters padded to three."""
    d, sqr, pa, pb, fa, fb, tail = (
        answer[0],
        answer[1],
        answer[2:5],
        answer[5:8],
        answer[8],
        answer[9],
        answer[10:],
    )
    ea, eb = extras
    pad_a = tuple(tail[:ea]) + (NAN,) * (3 - ea)
    pad_b = tuple(tail[ea : ea + eb]) + (NAN,) * (3 - eb)
    return (d, sqr, *pa, fa, *pb, fb, *pad_a, *pad_b)


def query(pair, method, a, b, out_shape, full):
    """A batch of a pair kernel: ``a`` and ``b`` the sides' rows ``batch + (width,)`` in the
    module's order (``pair`` unswapped); a dict of flat outputs as :data:`LAYOUT` names them."""
    return run(LAYOUT, _Kernels(pair), method, (), (a,), b, out_shape, full)


def exact(pair, a, b):
    """The exact answer of a pair kernel for rows ``a``, ``b`` (the module's order), flat."""
    wa, wb = len(a) // 3, len(b) // 3
    return getattr(_exact, pair.exact)(np.reshape(a, (wa, 3)), np.reshape(b, (wb, 3)))


def exact_sqr_bounds(pair, a, b):
    """``bits -> (lo2, hi2)``: the exact squared distance of rows ``a``, ``b`` (stored rows,
    or their leading vertices) of ``pair`` in its own order (shape a first); equal bounds
    where it is rational."""
    if pair.point:
        point, row = (b, a) if pair.swapped else (a, b)
        kind = pair.a if pair.swapped else pair.b
        return kind.kernels.exact_sqr_bounds(kind.code, np.asarray(row, np.float64), np.asarray(point[:3]))
    (a, ka), (b, kb) = ((b, pair.b), (a, pair.a)) if pair.swapped else ((a, pair.a), (b, pair.b))
    a = np.reshape(np.asarray(a)[: 3 * ka.vertices], (ka.vertices, 3))
    b = np.reshape(np.asarray(b)[: 3 * kb.vertices], (kb.vertices, 3))
    s = _exact.pair_sqr_distance(a, b)
    return lambda bits: (s, s)


# -- the fast path ------------------------------------------------------------------


def _single(out, a, b, ra, rb):
    """One pair, written to ``out`` (:data:`SINGLE_WIDTH` values): the status, then the
    answer of :func:`row_query`'s functions but its status (16 values); then, for the
    pair rounded by ``ra`` and ``rb``, what :func:`proximity.pair.queries.closest_points`
    makes of it (the same operations, so the same bits): ``d - ra - rb``, the distance
    ``max(d - ra - rb, 0)``, its square (the cores' where neither is rounded), each
    side's point of its surface (:func:`proximity.numerics.rounding.surface_points`), and
    1 where a surface point is lost in rounding or the status is not 0 (the general
    path then answers)."""
    r = QUERY(TAKE_A(a.reshape(1, -1), 0), TAKE_B(b.reshape(1, -1), 0))
    ea, eb = SPLIT(r[11:])
    out[0], out[1], out[2] = r[0], r[1], r[2]
    out[3], out[4], out[5], out[6], out[7], out[8] = r[3], r[4], r[5], r[6], r[7], r[8]
    out[9], out[10] = r[9], r[10]
    out[11], out[12], out[13] = ea
    out[14], out[15], out[16] = eb
    d = r[1]
    rounded = ra != 0.0 or rb != 0.0
    signed = d - (ra + rb) if rounded else d
    distance = max(signed, 0.0) + 0.0
    out[17], out[18] = signed, distance
    out[19] = distance * distance if rounded else r[2]
    out[26] = 0.0 if r[0] == 0.0 else 1.0
    for side in range(2):
        c0, c1, c2 = (r[3], r[4], r[5]) if side == 0 else (r[6], r[7], r[8])
        p0, p1, p2 = (r[6], r[7], r[8]) if side == 0 else (r[3], r[4], r[5])
        radius = ra if side == 0 else rb
        at = 20 + 3 * side
        if radius == 0.0:
            out[at], out[at + 1], out[at + 2] = c0, c1, c2
            continue
        m = max(max(max(abs(c0), abs(c1)), abs(c2)), max(max(abs(p0), abs(p1)), abs(p2)))
        m = max(m, radius)
        if d < radius and (d / m) * (d / m) < 64.0 * 2.0**-52 * (radius / m):
            out[26] = 1.0  # no direction from c to p: the core's normal there gives it
        if p0 == c0 and p1 == c1 and p2 == c2:
            out[at], out[at + 1], out[at + 2] = c0, c1, c2
            continue
        v0, v1, v2 = p0 - c0, p1 - c1, p2 - c2
        top = max(max(abs(v0), abs(v1)), abs(v2))
        v0, v1, v2 = v0 / top, v1 / top, v2 / top
        length = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        v0, v1, v2 = v0 / length, v1 / length, v2 / length
        out[at], out[at + 1], out[at + 2] = c0 + v0 * radius, c1 + v1 * radius, c2 + v2 * radius


#: How many values :func:`_single` writes.
SINGLE_WIDTH = 27

#: The fast path's signature: the output row, each side's row, each side's radius.
SINGLE_SIGNATURE = types.void(
    types.Array(types.float64, 1, "C"),
    types.Array(types.float64, 1, "C", readonly=True),
    types.Array(types.float64, 1, "C", readonly=True),
    types.float64,
    types.float64,
)


@functools.cache
def single(pair, method):
    """The fast path of a pair kernel (``pair`` unswapped), as an entry point that skips Numba's
    dispatch: ``f(out (SINGLE_WIDTH,), a (WA,), b (WB,), ra, rb)``, all C-contiguous float64."""
    tag = f"{pair.name}__{method.name}"
    kernel = specialize(_single, tag, SINGLE_SIGNATURE, **_bindings(pair, method))
    return kernel.overloads[tuple(SINGLE_SIGNATURE.args)].entry_point


# -- stored rows, for the descent ---------------------------------------------------


def _kernel_row(kind_a, qa, ka, kind_b, qb, kb):
    """A pair kernel on stored rows ``qa[ka]``, ``qb[kb]``."""
    r = QUERY(TAKE_A(qa, ka), TAKE_B(qb, kb))
    ea, eb = SPLIT(r[11:])
    return (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], float(r[9]), float(r[10]),
            ea[0], ea[1], ea[2], eb[0], eb[1], eb[2])  # fmt: skip


def _point_row(kind_a, qa, ka, kind_b, qb, kb):
    """The point of stored row ``qa[ka]`` against the primitive of row ``qb[kb]``:
    that kind's stored-row query (:mod:`proximity.primitives`)."""
    px, py, pz = qa[ka, 0], qa[ka, 1], qa[ka, 2]
    st, d, sqr, x, y, z, f, a0, a1, a2, _ = ROW(kind_b, qb, kb, px, py, pz)
    return st, d, sqr, px, py, pz, x, y, z, float(VERTEX0), float(f), NAN, NAN, NAN, a0, a1, a2


def _swap_row(kind_a, qa, ka, kind_b, qb, kb):
    """``INNER`` with the sides exchanged, and its answer exchanged back."""
    r = INNER(kind_b, qb, kb, kind_a, qa, ka)
    return (r[0], r[1], r[2], r[6], r[7], r[8], r[3], r[4], r[5], r[10], r[9],
            r[14], r[15], r[16], r[11], r[12], r[13])  # fmt: skip


@functools.cache
def row_query(pair, method):
    """The query of ``pair`` on stored rows by ``method``: ``f(kind_a, qa, ka, kind_b, qb, kb)``
    (the kinds of the rows ``qa[ka]`` and ``qb[kb]``, parameters as a collection stores them)
    to the 17 values of the module docstring; compiled into the descent."""
    if pair.swapped:
        inner = row_query(pair.unswapped, method)
        return specialize(_swap_row, f"{pair.name}__{method.name}", role="inline", INNER=inner)
    if pair.point:
        row = pair.b.kernels.row_query(pair.b, method)
        return specialize(_point_row, f"{pair.name}__{method.name}", role="inline", ROW=row)
    tag = f"{pair.name}__{method.name}"
    return specialize(_kernel_row, tag, role="inline", **_bindings(pair, method))


def touch_row(pair):
    """``f(kind_a, qa, ka, kind_b, qb, kb, fa, fb)``: ``pair``'s certified answer on stored
    rows (as :func:`row_query`'s) where its robust features ``fa``, ``fb`` cross and its
    primitives certainly intersect (distance 0), a request for the exact fallback
    elsewhere; None where its module has no such query (``touching``)."""
    if pair.swapped or pair.point or not hasattr(pair.kernels, "touching"):
        return None
    from ..methods import CERTIFIED

    bindings = _bindings(pair, CERTIFIED)
    bindings["TOUCHING"] = pair.kernels.touching
    return specialize(_touch_row, f"{pair.name}__touching", role="inline", **bindings)


def _touch_row(kind_a, qa, ka, kind_b, qb, kb, fa, fb):
    """``TOUCHING`` on stored rows ``qa[ka]``, ``qb[kb]`` (see :func:`touch_row`)."""
    r = TOUCHING(int(fa), int(fb), *TAKE_A(qa, ka), *TAKE_B(qb, kb))
    ea, eb = SPLIT(r[11:])
    return (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], float(r[9]), float(r[10]),
            ea[0], ea[1], ea[2], eb[0], eb[1], eb[2])  # fmt: skip


#: Candidate pairs per SIMD pass of the descent (:func:`candidates`).
CAP = 8


def _put_uniform(z, first, q, r, swap):
    """Column ``q`` of rows ``first ..``: a kernel's answer ``r`` (no status) as the 16 values
    of the module docstring but the status, the sides exchanged where ``swap``."""
    ea, eb = SPLIT(r[10:])
    if swap:
        ea, eb = eb, ea
    z[first, q], z[first + 1, q] = r[0], r[1]
    pa, pb, fa, fb = (r[2], r[3], r[4]), (r[5], r[6], r[7]), r[8], r[9]
    if swap:
        pa, pb, fa, fb = pb, pa, fb, fa
    z[first + 2, q], z[first + 3, q], z[first + 4, q] = pa
    z[first + 5, q], z[first + 6, q], z[first + 7, q] = pb
    z[first + 8, q], z[first + 9, q] = fa, fb
    z[first + 10, q], z[first + 11, q], z[first + 12, q] = ea
    z[first + 13, q], z[first + 14, q], z[first + 15, q] = eb


def _candidates(z, n):
    """The robust answers of the ``n`` candidate pairs in columns of ``z`` (rows ``0 ..
    SIDE_A - 1``: shape a's row, then shape b's), into rows ``SIDE_A + SIDE_B ..`` (16
    values each, as :func:`_put_uniform`): a loop over ``robust_unscaled`` that compiles to
    SIMD code, ``robust`` for the pairs outside its safe window."""
    first = SIDE_A + SIDE_B
    flag = first + 16
    for q in range(CAP):
        if SWAP:
            r = UNSCALED(*AT_A(z, SIDE_A, q), *AT_B(z, 0, q))
        else:
            r = UNSCALED(*AT_A(z, 0, q), *AT_B(z, SIDE_A, q))
        _put_uniform(z, first, q, r[1:], SWAP)
        z[flag, q] = r[0]
    for q in range(n):
        if z[flag, q] == 0.0:
            if SWAP:
                r = ROBUST(*AT_A(z, SIDE_A, q), *AT_B(z, 0, q))
            else:
                r = ROBUST(*AT_A(z, 0, q), *AT_B(z, SIDE_A, q))
            _put_uniform(z, first, q, r, SWAP)


SIDE_A = SIDE_B = 9
SWAP = False


@functools.cache
def candidates(pair):
    """The robust answers of up to :data:`CAP` candidate pairs of ``pair`` at once, for the
    descent: ``f(z, n)`` on scratch ``z`` of ``rows(pair)`` rows and ``CAP`` columns."""
    from ..methods import ROBUST as robust

    inner = pair.unswapped
    bindings = _bindings(inner, robust)
    bindings.update(SIDE_A=3 * pair.a.vertices, SIDE_B=3 * pair.b.vertices, SWAP=pair.swapped)
    put = specialize(_put_uniform, inner.name, role="inline", SPLIT=bindings["SPLIT"])
    return specialize(_candidates, pair.name, role="inline", _put_uniform=put, **bindings)


def candidate_rows(pair):
    """Rows of the scratch of :func:`candidates`: both sides' rows, 16 answers, a flag."""
    return 3 * pair.a.vertices + 3 * pair.b.vertices + 17


NONE_ROW = (NAN,) * 9 + (float(NONE), float(NONE)) + (NAN,) * 6
