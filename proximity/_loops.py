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
from numba import njit
from numba.core import types
from numpy.lib.stride_tricks import as_strided

# The kernels are compiled once, for these types: inputs as read-only arrays
# of any layout, outputs as flat C arrays.
A_IN2 = types.Array(types.float64, 2, "A", readonly=True)
A_IN3 = types.Array(types.float64, 3, "A", readonly=True)
A_IN4 = types.Array(types.float64, 4, "A", readonly=True)
OUT1 = types.Array(types.float64, 1, "C")
OUT2 = types.Array(types.float64, 2, "C")
OUT_FEATURE = types.Array(types.int8, 1, "C")
OUT_FLAG = types.Array(types.boolean, 1, "C")


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
    full = [np.broadcast_to(a, tuple(out_shape) + a.shape[a.ndim - c :]) for a, c in inputs]
    nb = len(out_shape)
    merged = []  # (length, [stride of each input])
    for axis, length in enumerate(out_shape):
        if length == 1:
            continue
        strides = [v.strides[axis] for v in full]
        if merged:
            outer, outer_strides = merged[-1]
            if all(so == s * length for so, s in zip(outer_strides, strides, strict=True)):
                merged[-1] = (outer * length, strides)
                continue
        merged.append((length, strides))
    if len(merged) > 2:
        # An unusual broadcast pattern: copy, after which everything merges.
        contiguous = [np.ascontiguousarray(v) for v in full]
        return loop_views(out_shape, [(a, c) for a, (_, c) in zip(contiguous, inputs, strict=True)])
    while len(merged) < 2:
        merged.insert(0, (1, [0] * len(full)))
    (n_i, s_i), (n_j, s_j) = merged
    views = [
        as_strided(v, shape=(n_i, n_j) + v.shape[nb:], strides=(si, sj) + v.strides[nb:], writeable=False)
        for v, si, sj in zip(full, s_i, s_j, strict=True)
    ]
    return views, n_j


@njit(inline="always")
def copy_rows(dst, first_dst, src, first_src, rows):
    """``dst[first_dst:][:rows] = src[first_src:][:rows]`` for 2D arrays of
    equal width, written as plain loops: numba compiles a slice assignment
    to a generic broadcasting loop, which costs more per block than the
    queries in it."""
    for k in range(rows):
        for q in range(dst.shape[1]):
            dst[first_dst + k, q] = src[first_src + k, q]
