"""Recycled memory for the outputs of large batches.

A batch of a million closest points writes 65 MB of results.  Memory that the
process has just been given by the operating system is slow to write the
first time (every page is faulted in and cleared), which can take as long as
the queries themselves (``docs/performance.md``).  A program that queries batches in a loop and drops each
result before the next (a simulation step, a sweep) can instead reuse the
memory of the result it dropped, which is what this module arranges.

Outputs of at least :data:`LARGE` bytes are NumPy arrays whose base is a
:class:`_Lease` on a block of memory; when the last array (or view) using the
block is gone, the lease hands the block back to the pool, which keeps up to
:data:`CAPACITY` bytes of them for the next batch of the same size.  Nothing
is reused while any array still refers to it, so results never change
under their owner.  :func:`clear` gives the kept blocks back to the system.
"""

import math
import threading

import numpy as np

LARGE = 1 << 20  # bytes; smaller outputs come from np.empty
CAPACITY = 256 << 20  # bytes of released blocks kept for reuse


class _Pool:
    def __init__(self, capacity):
        self.capacity = capacity
        self._free = {}  # nbytes -> list of blocks
        self._kept = 0
        # Reentrant: a lease can be released (by the garbage collector)
        # while this thread is inside the pool.
        self._lock = threading.RLock()

    def take(self, nbytes):
        with self._lock:
            blocks = self._free.get(nbytes)
            if blocks:
                self._kept -= nbytes
                return blocks.pop()
        return np.empty(nbytes, np.uint8)

    def give_back(self, block):
        with self._lock:
            if self._kept + block.nbytes <= self.capacity:
                self._free.setdefault(block.nbytes, []).append(block)
                self._kept += block.nbytes

    def clear(self):
        with self._lock:
            kept, self._kept = self._kept, 0
            self._free.clear()
        return kept

    def kept(self):
        with self._lock:
            return self._kept


_POOL = _Pool(CAPACITY)


class _Lease:
    """The base object of the arrays on one block: NumPy keeps it alive as
    long as any of them, and it returns the block to the pool after that."""

    def __init__(self, block, shape, dtype):
        self._block = block
        self.__array_interface__ = {
            "shape": shape,
            "typestr": dtype.str,
            "data": (block.__array_interface__["data"][0], False),
            "version": 3,
        }

    def __del__(self):
        pool = _POOL  # None while the interpreter shuts down
        if pool is not None:
            pool.give_back(self._block)


def empty(shape, dtype=np.float64):
    """An uninitialised array, on recycled memory when it is large."""
    shape = (shape,) if isinstance(shape, int) else tuple(shape)
    dtype = np.dtype(dtype)
    # math.prod: np.prod of a short tuple costs microseconds, seven times a query.
    nbytes = dtype.itemsize * math.prod(shape)
    if nbytes < LARGE:
        return np.empty(shape, dtype)
    return np.asarray(_Lease(_POOL.take(nbytes), shape, dtype))


def clear():
    """Return the memory kept for reuse to the system; the number of bytes."""
    return _POOL.clear()


def kept():
    """Bytes currently kept for reuse."""
    return _POOL.kept()
