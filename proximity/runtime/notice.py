"""The line a cold first query prints while it compiles.

A query compiles its kernels at its first use on a machine and keeps them
in the disk cache (:mod:`proximity.runtime.cache`); until then a first mesh query
takes seconds (most of them in the hierarchy's build), with nothing else
to show for it, and a notebook looks hung.  So each kind of first use of a
process (one-point queries, batches, meshes and scenes, signs, the exact
predicates, pair queries; per method) whose first kernel is not in the disk
cache prints one line on stderr, in one wording: what is compiling, roughly
how long it takes, and the command that compiles every kernel ahead.  Later
compiles of the same kind in the process print nothing, and a process whose
kernels are all cached prints nothing at all.

Every kernel's compile takes from a fraction of a second to a few seconds
of one core, plus about a second for the compiler's own start in a new
process, and a first use compiles several: so every cold first use takes
more than about a second, and each one announces itself.

Set the environment variable ``PROXIMITY_QUIET`` (to anything but ``""``
or ``"0"``) to silence the line; it is read when the line would be
printed, so setting ``os.environ["PROXIMITY_QUIET"] = "1"`` in a running
process works too.
"""

import os
import sys
import threading

#: The environment variable that silences the line.
QUIET = "PROXIMITY_QUIET"

# What a first use compiles, from where its first kernel that misses the
# cache is defined, and roughly how many seconds of one core the whole first
# use compiles (the kernels of that use together, measured cold).
# Measured cold on a quiet 2-core machine, in new processes as the README's snippets run: the
# first mesh answer (its hierarchy and first search) about 8 s with the imports; the first
# signed distance about 15 s more (the predicates and the signs' checks, which the normals at a
# face use alone in about 4 s); the first pair of meshes 20 to 30 s per pair of kinds (a
# segment against a mesh 19 s, a mesh against a posed mesh 29 s, certified 45 s).
_BROAD_PHASE = (
    "meshes and scenes (hierarchy build and nearest-face search)",
    "about 8 s for a first mesh and its first answer",
)
_SIGNS = ("the winding number of signed distances", "about 1 s")
_PREDICATES = (
    "exact orientation predicates (of normals at a face, of the signs' checks)",
    "about 15 s with a first signed distance, 4 s for normals alone",
)
_PAIRS = (
    "pair queries (the pair kernels, the descent of two hierarchies)",
    "about 20 to 30 s for each pair of kinds, 45 s certified",
)
_SINGLE = ("one-point queries", "about 1 s")
_BATCH = ("batch queries", "about 2 to 5 s")

_lock = threading.Lock()
_said = set()  # the kinds of first use this process has announced


def quiet():
    """Whether the line is silenced (:data:`QUIET` is set, and not to ``"0"``)."""
    return os.environ.get(QUIET, "") not in ("", "0")


def _method(name):
    """The method whose kernel ``name`` is (a specialised kernel's name holds it), or ``""``."""
    from ..methods import REGISTRY

    parts = name.split("__")
    return next((m for m in REGISTRY if m in parts), "")


def describe(func):
    """``(what, how long)`` for a first use whose first uncached kernel is ``func``."""
    module = getattr(func, "__module__", "") or ""
    name = getattr(func, "__qualname__", "") or ""
    if module.startswith("proximity.broadphase"):
        what, seconds = _BROAD_PHASE
    elif module == "proximity.signs.signed":
        what, seconds = _SIGNS
    elif module == "proximity.numerics.orient":
        what, seconds = _PREDICATES
    elif module.startswith("proximity.pair"):
        what, seconds = _PAIRS
    elif name.startswith("_single"):
        what, seconds = _SINGLE
    else:
        what, seconds = _BATCH
    method = _method(name)
    return (f"{method} kernels of {what}" if method else f"kernels of {what}"), seconds


def compiling(func):
    """Print the line for a compile of the kernel ``func``, the first time in this process
    that its kind of first use (:func:`describe`) compiles."""
    what, seconds = describe(func)
    with _lock:
        if what in _said:
            return
        _said.add(what)
    if quiet():
        return
    print(
        f"proximity: compiling the {what}, once for this machine ({seconds}; later runs "
        f"load them from the disk cache).  Run `python -m proximity.compile` to compile them all ahead; "
        f"set {QUIET}=1 to hide this line.",
        file=sys.stderr,
        flush=True,
    )
