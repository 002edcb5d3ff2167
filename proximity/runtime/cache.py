"""The disk cache of compiled kernels: where it is kept, and how its faults are survived.

The cache sits next to the sources (Numba's default).  Where that directory
cannot be written (a read-only install), Numba's user-wide cache directory
is used, or ``NUMBA_CACHE_DIR`` when it is set; where none can be written,
kernels are compiled in memory at every start, with a warning.

Numba keeps each cached function in an index file (``*.nbi``) and one data
file per compiled signature (``*.nbc``), and raises from the query that
compiles the function when either cannot be read (a file truncated by an
interrupted copy or a full disk: ``UnpicklingError``, ``EOFError``) or
written (``OSError``: a disk that fills up after the start, which the check
of the directory at import cannot foresee).  :func:`compiled` makes a
kernel whose cache survives both:

- an entry that cannot be read is compiled again, and the new one replaces
  it where the directory is writable (an unreadable index is started
  afresh);
- an entry that cannot be written stays in memory; the process then writes
  no more entries (with one warning) but still reads those already there.

The directory is checked by creating a file, not by writing to it: on a
full disk whose cache holds the kernels already, they are still read.

The first kernel of a process that is not in the cache prints a line on
stderr before it compiles (:mod:`proximity.runtime.notice`).

While a kernel compiles, Python's cyclic garbage collector is paused
(:class:`_Paused`): Numba's compiler makes objects by the million, and the
collector's passes over them, each over every object of the process (a
mesh library's among them), were a tenth of a first mesh's compile time.
The garbage of the compile is collected after it.
"""

import gc
import os
import tempfile
import warnings

from numba import njit
from numba.core import event
from numba.misc.appdirs import user_cache_dir

from . import notice


def _writable(directory):
    """Whether files can be created in ``directory`` (made if missing)."""
    try:
        os.makedirs(directory, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError:
        return False
    return True


def _cache_usable():
    configured = os.environ.get("NUMBA_CACHE_DIR")
    if configured:
        return _writable(configured)
    here = os.path.dirname(os.path.abspath(__file__))
    return _writable(os.path.join(here, "__pycache__")) or _writable(
        user_cache_dir(appname="numba", appauthor=False)
    )


def _warn_uncached(reason):
    warnings.warn(
        f"proximity: {reason}; kernels will be compiled again in every process",
        RuntimeWarning,
        stacklevel=3,
    )


#: Whether compiled kernels are kept on disk.
CACHE = _cache_usable()
if not CACHE:
    _warn_uncached("no writable cache directory (the package's, the user cache or NUMBA_CACHE_DIR)")

_saving = CACHE  # cleared at the first entry that cannot be written
_guarded = True  # cleared, with a warning, if Numba's cache cannot be guarded


def compiled(func, signature=(), **options):
    """``njit(*signature, **options)(func)``, kept in the disk cache where
    there is one (:data:`CACHE`): compiled now for each of ``signature``
    (and for no other), or at its first call without one."""
    global _guarded
    if CACHE and _guarded:
        dispatcher = njit(cache=True, **options)(func)
        if _guard_numba_cache(dispatcher):
            for sig in signature:
                dispatcher.compile(sig)
            if signature:
                dispatcher.disable_compile()
            return dispatcher
        _guarded = False
        _warn_uncached("this version of Numba's disk cache cannot be guarded against damaged files")
    return njit(*signature, **options)(func)


class _Guarded:
    """A dispatcher's Numba cache, whose faults fall back to compiling (see the module's docstring)."""

    def __init__(self, cache, func):
        self._cache = cache
        self._func = func

    def __getattr__(self, name):
        return getattr(self._cache, name)

    def load_overload(self, sig, target_context):
        # Whatever a damaged file raises, compiling again gives the right
        # kernel, and its save replaces the entry.
        try:
            loaded = self._cache.load_overload(sig, target_context)
        except Exception:
            loaded = None
        if loaded is None:  # Numba compiles it next
            notice.compiling(self._func)
        return loaded

    def save_overload(self, sig, data):
        global _saving
        if not _saving:
            return
        try:
            try:
                self._cache.save_overload(sig, data)
            except OSError:
                raise
            except Exception:
                # The index cannot be read: start it afresh with this entry.
                self._cache.flush()
                self._cache.save_overload(sig, data)
        except OSError as error:
            _saving = False
            _warn_uncached(f"the kernel cache cannot be written ({error})")


def _guard_numba_cache(dispatcher):
    """Put ``dispatcher``'s disk cache (Numba's private ``_cache``, made by
    ``cache=True``) behind :class:`_Guarded`; False, leaving it as it is,
    where this version of Numba has no such cache."""
    cache = getattr(dispatcher, "_cache", None)
    if not all(callable(getattr(cache, name, None)) for name in ("load_overload", "save_overload", "flush")):
        return False
    dispatcher._cache = _Guarded(cache, dispatcher.py_func)
    return True


class _Paused(event.Listener):
    """Python's garbage collector paused from the start to the end of the
    compile of one of the package's kernels (the kernels and Numba's own
    functions it compiles on the way), then resumed if it was running.

    Numba compiles under a lock, one function at a time, and announces the
    start and end of each (the end even where the compile raises).
    """

    def __init__(self):
        self._depth = 0
        self._resume = False

    def on_start(self, ev):
        if self._depth == 0:
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            if not (getattr(func, "__module__", None) or "").startswith(__package__ + "."):
                return
            self._resume = gc.isenabled()
            gc.disable()
        self._depth += 1

    def on_end(self, ev):
        if self._depth == 0:
            return
        self._depth -= 1
        if self._depth == 0 and self._resume:
            gc.enable()


event.register("numba:compile", _Paused())
