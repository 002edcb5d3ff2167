"""The batch pipeline that every primitive shares.

A batch query runs the same five steps whatever the shape: broadcast the
shape's arrays and the points into an ``(I, J)`` loop without copies
(:func:`proximity.runtime.loops.loop_views`), take the outputs from the memory
pool, hand blocks of :data:`~proximity.runtime.loops.BLOCK` queries to the threads,
finish the rows the certified filter left undecided in exact arithmetic,
and count them.  Each primitive describes its arrays once, in a
:class:`Layout`: the fields of its shape record and of its outputs, from
which the compiled signatures follow; its kernel module supplies the
block functions, one per method, and the exact answer of one query.
"""

import collections
import functools
from dataclasses import dataclass

import numpy as np
from numba import prange
from numba.core import types

from . import counts, pool
from .jit import launcher
from .loops import A_IN3, BLOCK, OUT_FLAG, loop_views, single_shape

# Bound by :func:`proximity.runtime.jit.launcher`: the call of the block function,
# and how many blocks of queries it is given at a time (:attr:`Layout.span`).
CALL = None
SPAN = 1


def _loop(handle, lo, hi, shape, P, n_j, out, exact, full):
    """Calls ``lo .. hi - 1`` of the block function over an ``(I, J)`` loop,
    ``SPAN`` blocks of queries each (the last one fewer queries).

    ``shape`` is the primitive's record of broadcast arrays ``(I, J, ...)``,
    ``P`` the points ``(I, J, 3)``, ``out`` the record of flat outputs;
    query ``k`` is loop index ``(k // J, k % J)``.  With ``full=False`` only
    the distances are written.
    """
    n = out[0].shape[0]
    run = SPAN * BLOCK
    for task in prange(lo, hi):
        k0 = task * run
        nb = min(run, n - k0)
        CALL(handle, shape, P, n_j, k0, nb, out, exact, full)


def _blocks(run, shape, P, n_j, out, exact, full):
    """The number of calls of the block function in :func:`_loop`, ``run`` queries each."""
    return (out[0].shape[0] + run - 1) // run


#: Fewest blocks of queries a thread takes at a time: a thread started for
#: fewer would cost more than the queries it answers (a layout of ``span``
#: blocks per call: this many over ``span`` calls).
BATCH_GRAIN = 16


_FLOAT1 = types.Array(types.float64, 1, "C")
_FLOAT2 = types.Array(types.float64, 2, "C")
_NUMBA = {
    (np.dtype(np.float64), 0): _FLOAT1,
    (np.dtype(np.float64), 1): _FLOAT2,
    (np.dtype(np.int8), 0): types.Array(types.int8, 1, "C"),
    (np.dtype(np.bool_), 0): OUT_FLAG,
}
_INPUT = {0: types.Array(types.float64, 2, "A", readonly=True)}
for _core in (1, 2):
    _INPUT[_core] = types.Array(types.float64, 2 + _core, "A", readonly=True)

#: The outputs every query writes first, in this order.
COMMON = (("distance", np.float64, 1), ("sqr_distance", np.float64, 1), ("point", np.float64, 3),
          ("feature", np.int8, 1))  # fmt: skip


@dataclass(frozen=True, eq=False)
class Layout:
    """The arrays of one primitive's batch queries.

    Parameters
    ----------
    name : str
        The primitive's name, which names the records.
    flags : tuple of str
        Leading boolean fields of the shape record (not broadcast).
    arrays : tuple of (str, int)
        The shape's float64 arrays and their number of core dimensions.
    extra : tuple of (str, dtype, int)
        Outputs after :data:`COMMON`: name, dtype and width (1 for a
        scalar per query).
    span : int
        Blocks of :data:`~proximity.runtime.loops.BLOCK` queries that a block
        function is given per call: ``nb`` is then up to ``span * BLOCK``,
        and the block function works through them a block at a time.  A
        call costs about as much as tens of cheap queries (its arguments are
        copied twice on the way in, and the compute loop's pipeline fills
        again), which a span spreads over more of them.
    """

    name: str
    flags: tuple
    arrays: tuple
    extra: tuple
    span: int = 1

    @functools.cached_property
    def outputs(self):
        """Every output: ``(name, dtype, width)``, :data:`COMMON` first."""
        return COMMON + self.extra

    @functools.cached_property
    def shape_record(self):
        """The namedtuple class of the shape's record."""
        return _record(f"{self.name.title()}Arrays", self.flags + tuple(a for a, _ in self.arrays))

    @functools.cached_property
    def out_record(self):
        """The namedtuple class of the outputs."""
        return _record(f"{self.name.title()}Outputs", tuple(name for name, _, _ in self.outputs))

    @functools.cached_property
    def block_signature(self):
        """The block functions' signature: ``(shape, P, n_j, k0, nb, out, exact, full)``."""
        # As Numba types the records passed in: uniform ones are NamedUniTuples.
        shape = types.BaseTuple.from_types(
            [types.boolean] * len(self.flags) + [_INPUT[core] for _, core in self.arrays], self.shape_record
        )
        out = types.BaseTuple.from_types(
            [_NUMBA[np.dtype(dtype), int(width > 1)] for _, dtype, width in self.outputs], self.out_record
        )
        i64 = types.int64
        return types.void(shape, A_IN3, i64, i64, i64, out, OUT_FLAG, types.boolean)

    @functools.cached_property
    def loop_signature(self):
        """The loop's signature: a handle, a range of blocks, then the block's arguments but ``k0, nb``."""
        args = self.block_signature.args
        return types.void(types.int64, types.int64, types.int64, *args[:3], *args[5:])


_records = {}


def _record(name, fields):
    """The namedtuple class ``name``, a global of this module: Numba's cache
    keys hold the compiled signatures, whose record types it pickles by
    reference to their class."""
    key = (name, fields)
    if key not in _records:
        cls = collections.namedtuple(name, fields, module=__name__)
        globals()[name] = _records[key] = cls
    return _records[key]


def batch_kernel(layout, block):
    """The compiled loop of ``layout`` over the block function ``block`` (a
    ``"pointer"`` kernel of :attr:`Layout.block_signature`), as a function
    of the loop's arguments but the handle."""
    span = layout.span
    return launcher(
        _loop,
        f"blocks_{layout.name}",
        layout.loop_signature,
        block,
        layout.block_signature,
        functools.partial(_blocks, span * BLOCK),
        max(1, BATCH_GRAIN // span),
        parallel=True,
        SPAN=span,
    )


def run(layout, kernels, method, flags, arrays, points, out_shape, full):
    """One batch query; returns a dict of flat outputs, by name.

    Parameters
    ----------
    layout : Layout
    kernels : module
        The primitive's kernel module: ``block(method, one)``, the block
        function for a method (``one``: every query is against the same
        shape), and ``exact(*flags, *arrays at a query, point)``, the exact
        answer of one query as a flat tuple in the order of the outputs.
    method : Method
    flags : tuple of bool
    arrays : tuple of ndarray
        The shape's validated float64 arrays, in the order of
        ``layout.arrays``.
    points : ndarray, shape ``(..., 3)``
    out_shape : tuple of int
        The broadcast batch shape.
    full : bool
        Whether to fill every output, or the distances alone.
    """
    cores = [core for _, core in layout.arrays]
    views, n_j = loop_views(out_shape, [*zip(arrays, cores, strict=True), (points, 1)])
    n = views[-1].shape[0] * views[-1].shape[1]
    m = n if full else 0
    values = [
        pool.empty(n if k == 0 else (m, width) if width > 1 else m, dtype)
        for k, (_, dtype, width) in enumerate(layout.outputs)
    ]
    out = layout.out_record(*values)
    exact = np.zeros(n if method.exact_fallback else 0, np.bool_)
    shape = layout.shape_record(*flags, *views[:-1])
    one = all(single_shape(view) for view in views[:-1])
    batch_kernel(layout, kernels.block(method, one))(shape, views[-1], n_j, out, exact, full)
    if method.exact_fallback:
        rows = np.flatnonzero(exact)
        for k in rows:
            i, j = divmod(int(k), n_j)
            answer = kernels.exact(*flags, *(view[i, j] for view in views))
            out[0][k] = answer[0]
            if full:
                column = 1
                for (_, _, width), field in zip(layout.outputs[1:], out[1:], strict=True):
                    field[k] = answer[column] if width == 1 else answer[column : column + width]
                    column += width
        counts.count(n, len(rows))
    return dict(zip(out._fields, out, strict=True))
