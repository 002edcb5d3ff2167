"""Modules loaded at a query's first use, one thread at a time.

``import proximity`` leaves Numba unloaded (it costs more than the rest of
the package together); the first query loads it, with the kernel module it
needs.  Numba's modules import one another in cycles, and Python locks each
module on its own while it runs: when two threads enter such a cycle at
different modules, Python breaks the deadlock by handing one of them a
module half initialised.  That thread fails (``partially initialized module
'numba.core.types' has no attribute 'boolean'``), and the modules it leaves
behind break every later query of the process.  So the first import of any
module that loads Numba, from code a query runs, goes through :func:`load`,
under one lock; a module once loaded is returned without locking.
"""

import importlib
import threading

# Reentrant: a module loaded under the lock may load another through load().
_LOCK = threading.RLock()
_loaded = {}


def load(name):
    """The module ``name`` (absolute: ``"numba"``, ``"proximity.bvh"``),
    imported under the lock the first time."""
    module = _loaded.get(name)
    if module is None:
        with _LOCK:
            # Entered by one thread at a time, the import finishes before
            # another thread can see the module here.
            module = _loaded[name] = importlib.import_module(name)
    return module
