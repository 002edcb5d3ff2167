"""Memory for the build: large arrays without huge-page stalls, and row gathers."""

import numpy as np
from numba import prange

from ..runtime.jit import kernel

#: From this many rows on, :func:`take_rows` and :func:`triangle_params`
#: (in the faces' own order) gather by compiled parallel loops; below, by
#: NumPy, which loads no kernel (about 2 ms at a kernel's first call in a
#: process, or its compile): a brute-force mesh compiles none of them.
GATHER_MIN = 1 << 15


#: The size (in float64s) from which NumPy asks for transparent huge pages: 4 MiB.
HUGE_PAGE_MIN = 1 << 19


@kernel()
def _empty(rows, columns):
    return np.empty((rows, columns))


def empty(rows, columns):
    """An uninitialised float64 array ``(rows, columns)`` for the build.

    Large ones come from Numba's allocator.  NumPy asks the kernel to back
    arrays of 4 MiB and more with transparent huge pages, and where the
    kernel compacts memory to find them on demand, the first writes to
    such an array can stall for a quarter of a second.
    """
    if rows * columns < HUGE_PAGE_MIN:
        return np.empty((rows, columns))
    return _empty(rows, columns)


def empty_ints(n):
    """An uninitialised int64 array of ``n``, from :func:`empty` (large ones from Numba's allocator)."""
    return empty(1, n).view(np.int64)[0]


@kernel(parallel=True)
def _take_rows(source, rows, out):
    for m in prange(rows.shape[0]):
        k = rows[m]
        for c in range(source.shape[1]):
            out[m, c] = source[k, c]


def take_rows(source, rows):
    """``source[rows]`` for a 2D float64 ``source``, as a new C-contiguous array."""
    if len(rows) < GATHER_MIN:
        return np.ascontiguousarray(source[rows])
    out = empty(len(rows), source.shape[1])
    _take_rows(readonly(source, np.float64), readonly(rows, np.int64), out)
    return out


def take_rows_into(source, rows, out):
    """:func:`take_rows` into ``out``, a float64 array ``(len(rows), source.shape[1])``."""
    if len(rows) < GATHER_MIN:
        np.take(source, rows, axis=0, out=out)
    else:
        _take_rows(readonly(source, np.float64), readonly(rows, np.int64), out)


#: The integers of a tree's topology (``child``, ``count``) and of its
#: primitives' indices (``index``): four bytes, where eight would cost about
#: 7 bytes a face more, and no tree comes near :data:`MOST_PRIMITIVES`.
INDEX = np.int32
#: The most primitives a tree holds: its nodes (``2 n - 1``) and indices fit in :data:`INDEX`.
MOST_PRIMITIVES = 1 << 30


def check_size(n, what="primitives"):
    """Raise a ValueError unless ``n`` primitives fit a tree (:data:`MOST_PRIMITIVES`)."""
    if n > MOST_PRIMITIVES:
        raise ValueError(f"a hierarchy holds at most 2**30 = {MOST_PRIMITIVES:,} {what}; got {n:,}")


def indices(array):
    """``array`` (integers below ``2**31``) as a read-only :data:`INDEX` array, as a tree keeps them."""
    array = np.asarray(array)
    if array.dtype != INDEX and array.size and (array.min() < -(1 << 31) or array.max() >= 1 << 31):
        raise ValueError(f"tree indices must be below 2**31; got {int(array.max()):,}")
    return readonly(array, INDEX)


def readonly(array, dtype):
    """``array`` as a C-contiguous read-only array of ``dtype`` (a view where it already is one)."""
    array = np.ascontiguousarray(array, dtype=dtype)
    view = array.view()
    view.flags.writeable = False
    return view
