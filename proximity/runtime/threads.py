"""Threads: Numba's threading layer, chosen so that forks and Python threads are safe, and Python threads.

The loops over blocks of queries, the hierarchy's build and its fit are
serial kernels that release the GIL, run side by side on Python threads
(:func:`spread`): a kernel of parallel loops takes seconds longer to
compile.  The other parallel kernels (the winding number, validity, ray
crossings) run on one of Numba's three threading layers, picked when the
first parallel kernel is compiled or loaded, once per process:

- ``tbb`` is safe under ``fork`` and under concurrent Python threads.  The
  ``tbb`` package from the package index installs its library where the
  dynamic loader does not look (``<prefix>/lib``), so it is loaded here,
  by path, before Numba looks for it by name.
- ``omp`` (GNU OpenMP on Linux) is thread-safe, but a child forked after it
  has run is terminated.
- ``workqueue`` survives ``fork`` but aborts the process when two Python
  threads launch kernels at once: :func:`kernel` then runs the launches one
  at a time.

Unless the environment names a layer (``NUMBA_THREADING_LAYER``), the layer
asked for is ``forksafe``: ``tbb`` where it can be loaded, else
``workqueue`` on Linux and ``omp`` elsewhere.
"""

from __future__ import annotations

import contextlib
import ctypes
import operator
import os
import site
import sys
import threading
from contextlib import AbstractContextManager

from . import lazy

_ENV = "NUMBA_THREADING_LAYER"
_LOCK = threading.RLock()
_threadsafe = False  # set once the layer is known to be safe under threads


def _tbb_paths():
    name = {"linux": "libtbb.so.12", "darwin": "libtbb.12.dylib", "win32": "tbb12.dll"}.get(sys.platform)
    if name is None:
        return []
    prefixes = [sys.prefix, getattr(site, "USER_BASE", None) or ""]
    folder = "Library/bin" if sys.platform == "win32" else "lib"
    return [os.path.join(prefix, folder, name) for prefix in prefixes if prefix]


def _load_tbb():
    """Load the TBB library installed beside this Python, if any; True if loaded."""
    for path in _tbb_paths():
        if os.path.exists(path):
            try:
                ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
            except OSError:
                continue
            return True
    return False


def configure():
    """Ask Numba for a fork-safe layer, unless the user chose one or it is running.

    Called on ``import proximity``, before any kernel can be compiled.
    """
    if _ENV in os.environ:
        if os.environ[_ENV].lower() in ("tbb", "safe", "forksafe", "default"):
            _load_tbb()
        return
    _load_tbb()
    numba = sys.modules.get("numba")
    if numba is None:
        # Numba reads its configuration from the environment when imported.
        os.environ[_ENV] = "forksafe"
        return
    from numba.np.ufunc import parallel

    if not parallel._is_initialized:
        numba.config.THREADING_LAYER = "forksafe"


def layer():
    """The threading layer Numba runs, or None before the first parallel kernel."""
    numba = sys.modules.get("numba")
    if numba is None:
        return None
    try:
        return numba.threading_layer()
    except ValueError:
        return None


@contextlib.contextmanager
def kernel():
    """Around the launch of a batch kernel (and the first import of its
    module, which may compile it): one thread at a time unless the layer is
    known to be thread-safe."""
    global _threadsafe
    if _threadsafe:
        yield
        return
    with _LOCK:
        yield
        current = layer()
        if current is not None and current != "workqueue":
            _threadsafe = True


def default_threads():
    """The number of threads Numba starts with: every core unless
    ``NUMBA_NUM_THREADS`` says otherwise."""
    return lazy.load("numba").config.NUMBA_NUM_THREADS


@contextlib.contextmanager
def threads(n: int | None = None) -> AbstractContextManager[None]:
    """Run the queries of the enclosed block on ``n`` threads.

    Parameters
    ----------
    n : int or None
        Threads for the batch queries made in this Python thread, from 1 to
        the number Numba started with (every core, unless the environment
        variable ``NUMBA_NUM_THREADS`` says otherwise); None for all of them.
        Single-point queries always run on the calling thread.

    Notes
    -----
    This is Numba's own per-thread setting (``numba.set_num_threads``),
    restored on leaving the block; it also applies to the user's own
    parallel Numba code run inside it.  Other Python threads keep theirs.

    Examples
    --------
    >>> import numpy as np, proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> points = np.random.default_rng(0).normal(size=(100_000, 3))
    >>> with proximity.threads(1):
    ...     one = tri.distance(points)
    >>> bool((one == tri.distance(points)).all())   # the same answers on every core
    True
    """
    numba = lazy.load("numba")
    limit = numba.config.NUMBA_NUM_THREADS
    if n is None:
        n = limit
    try:
        index = operator.index(n)  # any integer, Python's or NumPy's
    except TypeError:
        index = None
    if index is None or isinstance(n, bool):
        raise TypeError(f"n must be an int or None; got {type(n).__name__} {n!r}")
    n = index
    if not 1 <= n <= limit:
        raise ValueError(f"n must be from 1 to {limit} (the threads Numba started); got {n}")
    with kernel():
        previous = numba.get_num_threads()  # starts the layer, as the first query would
    numba.set_num_threads(n)
    try:
        yield n
    finally:
        numba.set_num_threads(previous)


# Serial kernels run on Python threads (:func:`spread`): a kernel compiled
# without ``parallel=True`` compiles in a fraction of the time, and with
# ``nogil=True`` its calls run side by side.
_pool = None
_pool_lock = threading.Lock()


def _reset_pool():
    # A child forked from a process whose pool had started inherits none of its threads.
    global _pool
    _pool = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_reset_pool)


def _workers():
    global _pool
    if _pool is None:
        with _pool_lock:
            if _pool is None:
                from concurrent.futures import ThreadPoolExecutor

                _pool = ThreadPoolExecutor(max(default_threads() - 1, 1), thread_name_prefix="proximity")
    return _pool


def current():
    """The number of threads batch queries of this Python thread run on (see :func:`threads`)."""
    return lazy.load("numba").get_num_threads()


def spread(run, tasks, chunk=1):
    """``run(lo, hi)`` over the tasks ``0 .. tasks - 1``, ``chunk`` at a time,
    on as many threads as batch queries use (see :func:`threads`).

    ``run`` calls a kernel compiled with ``nogil=True`` on its range of
    tasks, which must write nothing another range reads.  Ranges are
    handed out one at a time (tasks may differ in size by orders of
    magnitude); the calling thread takes its share.  Runs on the calling
    thread alone where there is a single range or a single thread.
    """
    ranges = [(lo, min(lo + chunk, tasks)) for lo in range(0, tasks, chunk)]
    n = min(len(ranges), current())
    if n <= 1:
        for lo, hi in ranges:
            run(lo, hi)
        return
    queue = iter(ranges)
    lock = threading.Lock()

    def work():
        while True:
            with lock:
                job = next(queue, None)
            if job is None:
                return
            run(*job)

    futures = [_workers().submit(work) for _ in range(n - 1)]
    try:
        work()
    finally:
        for future in futures:
            future.result()
