"""Broadcasting for the compiled kernels, without broadcast copies.

The public functions broadcast points against shapes like a NumPy ufunc.
Materialising the broadcast (one triangle copied for each of a million
points) would cost memory that grows with the batch, so instead every input
is viewed with zero strides along its broadcast dimensions, and adjacent loop
dimensions are merged where all strides allow.  The usual cases (N points
against one shape, N pairs, N x M all pairs) collapse to at most two loop
dimensions ``(I, J)``, which is the one loop shape the kernels are compiled
for; anything else is copied to contiguous memory first.
"""

import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.core.errors import RequireLiteralValue
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array
from numpy.lib.stride_tricks import as_strided

from .jit import inline

# The kernels are compiled once, for these types: inputs as read-only arrays
# of any layout, outputs as flat C arrays.
A_IN2 = types.Array(types.float64, 2, "A", readonly=True)
A_IN3 = types.Array(types.float64, 3, "A", readonly=True)
A_IN4 = types.Array(types.float64, 4, "A", readonly=True)
OUT1 = types.Array(types.float64, 1, "C")
OUT2 = types.Array(types.float64, 2, "C")
OUT_FEATURE = types.Array(types.int8, 1, "C")
OUT_FLAG = types.Array(types.boolean, 1, "C")

# The one-query kernels' signature: the output row, the shape's values
# (read-only) and the point, in any layout.
SINGLE_ARGS = types.void(
    OUT1,
    types.Array(types.float64, 1, "C", readonly=True),
    types.Array(types.float64, 1, "A"),
)


def single_entry(kernel):
    """The compiled one-query ``kernel``, to be called without Numba's dispatch.

    The dispatcher matches the types of the arguments to its compiled
    versions on every call, which is a tenth of a fast-path query.  The
    entry point returned here skips that and reads its arguments as
    :data:`SINGLE_ARGS` without checking them, so the caller must pass
    exactly those: a C-contiguous float64 row of ten, the shape's float64
    values, and a float64 point of shape ``(3,)``.
    """
    return kernel.compile(SINGLE_ARGS.args)


def loop_views(out_shape, inputs):
    """View ``inputs`` over a loop of at most two dimensions.

    Parameters
    ----------
    out_shape : tuple of int
        The broadcast batch shape.
    inputs : sequence of (ndarray, int)
        Each array with its number of core (trailing, not broadcast)
        dimensions.

    Returns
    -------
    views : list of ndarray
        Read-only views of shape ``(I, J) + core``, with ``I * J`` equal to
        the number of elements of ``out_shape``.
    n_j : int
        ``J``, the length of the inner loop dimension.
    """
    broadcast = [_broadcast_strides(a, c, out_shape) for a, c in inputs]
    merged = []  # (length, [stride of each input])
    for axis, length in enumerate(out_shape):
        if length == 1:
            continue
        strides = [batch[axis] for batch, _ in broadcast]
        if merged:
            outer, outer_strides = merged[-1]
            if all(so == s * length for so, s in zip(outer_strides, strides, strict=True)):
                merged[-1] = (outer * length, strides)
                continue
        merged.append((length, strides))
    if len(merged) > 2:
        # An unusual broadcast pattern: copy, after which everything merges.
        full = [np.broadcast_to(a, tuple(out_shape) + a.shape[a.ndim - c :]) for a, c in inputs]
        contiguous = [np.ascontiguousarray(v) for v in full]
        return loop_views(out_shape, [(a, c) for a, (_, c) in zip(contiguous, inputs, strict=True)])
    while len(merged) < 2:
        merged.insert(0, (1, [0] * len(inputs)))
    (n_i, s_i), (n_j, s_j) = merged
    views = [
        _view(a, (n_i, n_j) + a.shape[a.ndim - c :], (si, sj) + core)
        for (a, c), (_, core), si, sj in zip(inputs, broadcast, s_i, s_j, strict=True)
    ]
    return views, n_j


def _broadcast_strides(a, core, out_shape):
    """The strides of ``a`` broadcast to ``out_shape`` plus its ``core``
    trailing dimensions, as ``np.broadcast_to`` gives them: ``(batch,
    core)``, zero along the broadcast axes."""
    lead = len(out_shape) - (a.ndim - core)
    batch = [
        a.strides[axis - lead] if axis >= lead and a.shape[axis - lead] == length else 0
        for axis, length in enumerate(out_shape)
    ]
    return batch, a.strides[a.ndim - core :]


def _view(a, shape, strides):
    """A read-only view of ``a``'s memory with ``shape`` and ``strides``.

    NumPy's constructor over ``a``'s own buffer where ``a`` is contiguous
    (fifteen times as fast as ``as_strided``, and a batch query makes one
    view of each of its arrays); ``as_strided`` otherwise.
    """
    if a.flags.c_contiguous:
        view = np.ndarray(shape, a.dtype, a, 0, strides)
        view.flags.writeable = False
        return view
    return as_strided(a, shape=shape, strides=strides, writeable=False)


def single_shape(view):
    """Whether a loop view from :func:`loop_views` repeats one element: the
    one shape that every point of the batch is queried against."""
    return all(n == 1 or stride == 0 for n, stride in zip(view.shape[:2], view.strides[:2], strict=True))


# Batch kernels work in blocks of this many queries: gathered from the
# broadcast inputs into local structure-of-arrays scratch, computed by a loop
# over the scratch that compiles to SIMD code, and scattered to the outputs.
# The compute loop vectorises only when it runs over scratch allocated in the
# same function, with this constant length, so every kernel's block function
# allocates its own (``np.empty``, or :func:`scratch` on the stack) and
# gathers into it with the helpers below.  They are written as plain loops
# over one run of the inner loop dimension at a time, which the compiler
# turns into straight strided loads and stores: slice assignments and
# per-element wrap-around tests cost more than the queries.  Disks and
# circles read their inputs and write their results in place instead,
# where they can (:func:`block_vectors`, :func:`round_sinks`).
BLOCK = 128


# A block runs once per 128 queries, so what it costs besides its queries
# counts.  For a million distances to one disk, ``np.empty`` for the scratch
# (the allocator, and back) took a third of the time, and the reference
# counts of the arguments and their views (atomic operations, on counts
# that every thread shares) a tenth.  The three intrinsics below make
# arrays that Numba does not count: they fill the array structure's fields
# with ``make_array`` and ``populate_array``, below Numba's public API but
# unchanged in every release this package accepts.


@intrinsic
def scratch(typingctx, rows, dtype):
    """A block's scratch: ``rows`` (a constant) rows of :data:`BLOCK` items
    of ``dtype`` (a NumPy scalar type), in C order, uninitialised, on the
    stack of the function it is compiled into.

    It holds no reference (no view of it outlives the block) and is not
    zero-filled, as Numba fills its own stack slots.
    """
    if not isinstance(rows, types.IntegerLiteral):
        raise RequireLiteralValue(rows)
    n = rows.literal_value
    array = types.Array(dtype.instance_type, 2, "C")

    def codegen(context, builder, signature, args):
        item = context.get_data_type(array.dtype)
        size = context.get_abi_sizeof(item)
        intp = context.get_value_type(types.intp)
        with builder.goto_entry_block():
            data = builder.alloca(ir.ArrayType(item, n * BLOCK))
        data.align = 64  # whole cache lines, for the SIMD loads and stores
        out = make_array(array)(context, builder)
        populate_array(
            out,
            data=builder.bitcast(data, item.as_pointer()),
            shape=(ir.Constant(intp, n), ir.Constant(intp, BLOCK)),
            strides=(ir.Constant(intp, size * BLOCK), ir.Constant(intp, size)),
            itemsize=ir.Constant(intp, size),
            meminfo=None,
        )
        return out._getvalue()

    return array(rows, dtype), codegen


def _without_count(context, builder, typ, value):
    """``value`` of type ``typ`` with the meminfo of every array in it null."""
    if isinstance(typ, types.Array):
        view = make_array(typ)(context, builder, value=value)
        view.meminfo = view.meminfo.type(None)
        return view._getvalue()
    if isinstance(typ, types.BaseTuple):
        for k, member in enumerate(typ):
            item = _without_count(context, builder, member, builder.extract_value(value, k))
            value = builder.insert_value(value, item, k)
    return value


@intrinsic
def borrowed(typingctx, a):
    """``a`` (an array, or a record of arrays) without reference counts:
    views of it cost no atomic operations.  Only for the arguments of a
    block, which outlive every view of them.

    A block that rebinds its arguments to these on its first line holds no
    reference at all: Numba counts a reference to each argument array from
    where the argument is read to its last use, and drops the pair only
    where it can follow it through the whole function, which a block's
    scalar path makes too large.  Otherwise each call of a block makes two
    atomic operations per array on counts that every thread shares.
    """

    def codegen(context, builder, signature, args):
        return _without_count(context, builder, a, args[0])

    return a(a), codegen


@intrinsic
def flat(typingctx, a):
    """The items of ``a`` as one 1-D C array, without its reference count:
    only for an array whose items the caller knows to be contiguous, in C
    order (a C array, or one whose strides it checked), and for reading
    where ``a`` is read-only.

    ``reshape`` and ``np.ascontiguousarray`` do this with a call to a
    helper of Numba's, and any call in a block keeps its arguments'
    reference counts (atomic operations on counts the threads share), which
    Numba removes where it sees the whole function.
    """
    array = types.Array(a.dtype, 1, "C")

    def codegen(context, builder, signature, args):
        src = make_array(a)(context, builder, value=args[0])
        intp = context.get_value_type(types.intp)
        count = ir.Constant(intp, 1)
        for extent in cgutils.unpack_tuple(builder, src.shape):
            count = builder.mul(count, extent)
        out = make_array(array)(context, builder)
        size = src.itemsize
        populate_array(out, data=src.data, shape=(count,), strides=(size,), itemsize=size, meminfo=None)
        return out._getvalue()

    return array(a), codegen


# The rows of a block's scratch, by name.  Each query is one column.
#: Pairs of triangles and points: the vertices V0, V1, V2 (nine rows) and
#: the point (three), then the query's nine results, then a flag.
PAIR_V, PAIR_P, PAIR_OUT, PAIR_OK, PAIR_ROWS = 0, 9, 12, 21, 22
#: Many points against one shape, read as scalars: the point, the nine
#: results, a flag.
ONE_P, ONE_OUT, ONE_OK, ONE_ROWS = 0, 3, 12, 13
#: Disks and circles read their inputs in place where they can, and copy
#: the others (see :func:`block_vectors`) into a scratch of these rows:
#: center, unit normal and point (three rows each, ``x0, y0, z0, x1,
#: ...``), radius.  They write their results in place too
#: (:func:`round_sinks`).
ROUND_C, ROUND_U, ROUND_P, ROUND_R, ROUND_ROWS = 0, 3, 6, 9, 10


@inline
def triangle_at(z, q):
    """Query ``q`` of a block of pairs: ``(v0x, v0y, v0z, v1x, ..., v2z, px, py, pz)``."""
    return (
        z[PAIR_V, q], z[PAIR_V + 1, q], z[PAIR_V + 2, q],
        z[PAIR_V + 3, q], z[PAIR_V + 4, q], z[PAIR_V + 5, q],
        z[PAIR_V + 6, q], z[PAIR_V + 7, q], z[PAIR_V + 8, q],
        z[PAIR_P, q], z[PAIR_P + 1, q], z[PAIR_P + 2, q],
    )  # fmt: skip


@inline
def point_at(z, first, q):
    """The point of query ``q`` from rows ``first .. first + 2``."""
    return z[first, q], z[first + 1, q], z[first + 2, q]


@inline
def _zero_tail(z, first, last, nb):
    # The columns past the last query of a short block are computed too.
    for row in range(first, last):
        for q in range(nb, BLOCK):
            z[row, q] = 0.0


@inline
def gather_triangles(z, V, P, n_j, k0, nb):
    """Rows :data:`PAIR_V` to :data:`PAIR_P` + 2 of ``z``: the vertices
    ``V0, V1, V2`` and the point of queries ``k0 .. k0 + nb`` of an
    ``(I, J)`` loop, one query per column."""
    i = k0 // n_j
    j = k0 - i * n_j
    q = 0
    while q < nb:
        run = min(nb - q, n_j - j)
        Vi = V[i]
        Pi = P[i]
        for t in range(run):
            z[PAIR_V, q + t] = Vi[j + t, 0, 0]
            z[PAIR_V + 1, q + t] = Vi[j + t, 0, 1]
            z[PAIR_V + 2, q + t] = Vi[j + t, 0, 2]
            z[PAIR_V + 3, q + t] = Vi[j + t, 1, 0]
            z[PAIR_V + 4, q + t] = Vi[j + t, 1, 1]
            z[PAIR_V + 5, q + t] = Vi[j + t, 1, 2]
            z[PAIR_V + 6, q + t] = Vi[j + t, 2, 0]
            z[PAIR_V + 7, q + t] = Vi[j + t, 2, 1]
            z[PAIR_V + 8, q + t] = Vi[j + t, 2, 2]
            z[PAIR_P, q + t] = Pi[j + t, 0]
            z[PAIR_P + 1, q + t] = Pi[j + t, 1]
            z[PAIR_P + 2, q + t] = Pi[j + t, 2]
        q += run
        i += 1
        j = 0
    _zero_tail(z, PAIR_V, PAIR_P + 3, nb)


@inline
def gather_points(z, first, P, n_j, k0, nb):
    """Rows ``first .. first + 2`` of ``z``: the points of queries
    ``k0 .. k0 + nb``, for the block functions of a single shape."""
    i = k0 // n_j
    j = k0 - i * n_j
    q = 0
    while q < nb:
        run = min(nb - q, n_j - j)
        Pi = P[i]
        for t in range(run):
            z[first, q + t] = Pi[j + t, 0]
            z[first + 1, q + t] = Pi[j + t, 1]
            z[first + 2, q + t] = Pi[j + t, 2]
        q += run
        i += 1
        j = 0
    _zero_tail(z, first, first + 3, nb)


@inline
def block_vectors(z, first, V, n_j, k0, nb):
    """The vectors of ``V`` ``(I, J, 3)`` at queries ``k0 .. k0 + nb`` as one
    run ``x0, y0, z0, x1, ...`` of :data:`BLOCK` vectors, for loops that
    read them in place.

    A full block whose vectors lie in one row of the loop, contiguous, is
    read where it lies: the loop's loads are then vector loads and
    shuffles, which the processor overlaps with the arithmetic.  Any other
    (a broadcast, a stride, a block across rows or the last one) is first
    copied into rows ``first .. first + 2`` of ``z`` (zeros past ``nb``).
    ``V`` is :func:`borrowed`, as the block's arguments are, so that the
    views cost no reference counts.
    """
    i = k0 // n_j
    j = k0 - i * n_j
    rows = V[i, j : j + BLOCK]
    if nb == BLOCK and rows.shape[0] == BLOCK and rows.strides[0] == 24 and rows.strides[1] == 8:
        return flat(rows)
    run = flat(z[first : first + 3])
    q = 0
    while q < nb:
        n = min(nb - q, n_j - j)
        Vi = V[i]
        for t in range(n):
            run[3 * (q + t)] = Vi[j + t, 0]
            run[3 * (q + t) + 1] = Vi[j + t, 1]
            run[3 * (q + t) + 2] = Vi[j + t, 2]
        q += n
        i += 1
        j = 0
    for e in range(3 * nb, 3 * BLOCK):
        run[e] = 0.0
    return run


@inline
def block_scalars(z, row, S, n_j, k0, nb):
    """:func:`block_vectors` for the scalars of ``S`` ``(I, J)``, copied
    into row ``row`` of ``z`` where they are not contiguous."""
    i = k0 // n_j
    j = k0 - i * n_j
    items = S[i, j : j + BLOCK]
    if nb == BLOCK and items.shape[0] == BLOCK and items.strides[0] == 8:
        return flat(items)
    run = flat(z[row])
    q = 0
    while q < nb:
        n = min(nb - q, n_j - j)
        Si = S[i]
        for t in range(n):
            run[q + t] = Si[j + t]
        q += n
        i += 1
        j = 0
    for e in range(nb, BLOCK):
        run[e] = 0.0
    return run


@inline
def store(z, first, q, res):
    """Column ``q`` of rows ``first .. first + 8`` of ``z``: one query's nine results."""
    z[first, q], z[first + 1, q], z[first + 2, q] = res[0], res[1], res[2]
    z[first + 3, q], z[first + 4, q], z[first + 5, q] = res[3], res[4], res[5]
    z[first + 6, q], z[first + 7, q], z[first + 8, q] = res[6], res[7], res[8]


@inline
def scatter_common(z, first, k0, nb, out, full):
    """Distance (always) and, with ``full``, squared distance, point and
    feature of queries ``k0 .. k0 + nb`` from rows ``first .. first + 5``,
    into the first four fields of the outputs record ``out``."""
    dist, sqr, point, feature = out[0], out[1], out[2], out[3]
    d = borrowed(dist)[k0 : k0 + nb]
    for q in range(nb):
        d[q] = z[first, q]
    if full:
        s = borrowed(sqr)[k0 : k0 + nb]
        # The points as one run x0, y0, z0, x1, ...: a constant stride, which
        # the compiler writes with vector shuffles and stores.
        p = flat(borrowed(point)[k0 : k0 + nb])
        f = borrowed(feature)[k0 : k0 + nb]
        for q in range(nb):
            s[q] = z[first + 1, q]
            p[3 * q] = z[first + 2, q]
            p[3 * q + 1] = z[first + 3, q]
            p[3 * q + 2] = z[first + 4, q]
            f[q] = np.int8(z[first + 5, q])


@inline
def scatter_triangles(z, first, k0, nb, out, full):
    """:func:`scatter_common`, and the barycentrics (``out[4]``) from rows ``first + 6 ..``."""
    scatter_common(z, first, k0, nb, out, full)
    if full:
        b = out[4][k0 : k0 + nb]
        for q in range(nb):
            b[q, 0] = z[first + 6, q]
            b[q, 1] = z[first + 7, q]
            b[q, 2] = z[first + 8, q]


@inline
def round_sinks(out, k0, nb, full, spare, codes, flags):
    """Where a block of disk or circle queries ``k0 .. k0 + nb`` writes its
    results: ``(distance, sqr_distance, point, feature, equidistant, height,
    radial)``, the point as one run ``x0, y0, z0, x1, ...``.

    A full block of closest points writes them in place, in the SIMD loop,
    so that its stores stream out among its loads and arithmetic: through
    scratch and a scatter after it, the stores of a million closest points
    took twice as long as a loop that only writes them.  Distances alone go
    to the scratch ``spare`` (float64, seven rows), which
    :func:`drain_round` copies out (in place, pairs took longer); so do
    all the results of the last, shorter block, to ``spare``, ``codes``
    (int8) and ``flags`` (bool).  Outputs that a query does not fill have
    no rows: their sinks are empty.  ``out`` is :func:`borrowed`, as the
    block's arguments are.
    """
    if full and nb == BLOCK:
        return (
            out[0][k0 : k0 + BLOCK],
            out[1][k0 : k0 + BLOCK],
            flat(out[2][k0 : k0 + BLOCK]),
            out[3][k0 : k0 + BLOCK],
            out[4][k0 : k0 + BLOCK],
            out[5][k0 : k0 + BLOCK],
            out[6][k0 : k0 + BLOCK],
        )
    if not full:
        unused = (out[1], spare[0, :0], out[3], out[4], out[5])
        return (spare[0], *unused, out[6])
    return spare[0], spare[1], flat(spare[2:5]), codes[0], flags[0], spare[5], spare[6]


@inline
def put_round(sinks, q, res, full):
    """Query ``q``'s results ``res`` (as :func:`store` takes them) into
    ``sinks`` (see :func:`round_sinks`): the distance alone unless ``full``."""
    d, s, p, f, e, h, r = sinks
    d[q] = res[0]
    if full:
        s[q] = res[1]
        p[3 * q], p[3 * q + 1], p[3 * q + 2] = res[2], res[3], res[4]
        f[q] = np.int8(res[5])
        e[q] = res[6] != 0
        h[q] = res[7]
        r[q] = res[8]


@inline
def drain_round(sinks, out, k0, nb, full):
    """Copy the results that :func:`round_sinks` did not put in place to
    ``out``: the distances alone, or every result of a block shorter than
    :data:`BLOCK`."""
    d, s, p, f, e, h, r = sinks
    if not full or nb < BLOCK:
        dist = out[0][k0 : k0 + nb]
        for q in range(nb):
            dist[q] = d[q]
    if full and nb < BLOCK:
        sqr, feature = out[1][k0 : k0 + nb], out[3][k0 : k0 + nb]
        point = flat(out[2][k0 : k0 + nb])
        flag, height, radial = (
            out[4][k0 : k0 + nb],
            out[5][k0 : k0 + nb],
            out[6][k0 : k0 + nb],
        )
        for q in range(nb):
            sqr[q] = s[q]
            point[3 * q], point[3 * q + 1], point[3 * q + 2] = p[3 * q], p[3 * q + 1], p[3 * q + 2]
            feature[q] = f[q]
            flag[q] = e[q]
            height[q] = h[q]
            radial[q] = r[q]
