"""How the kernels are compiled: inlining, the disk cache, and specialisation.

Four decorators and three functions, used by every kernel module:

``inline``
    A helper inlined by LLVM into its callers (``forceinline``).  Numba
    compiles it once per signature; inlining at Numba's IR level instead
    would run its front end again at every call site.
``spliced``
    A helper with a single call site, spliced into its caller at Numba's IR
    level (``inline="always"``): it is typed and lowered as part of its
    caller, without a compile of its own (which, for a small helper, costs
    as much as its code).
``part``
    A larger function compiled into the kernels that call it (a block of a
    batch loop, a scalar query), where LLVM decides whether to inline.
``kernel``
    A compiled function that is cached on disk, where a cache can be kept
    (see :mod:`proximity.runtime.cache`).
:func:`specialize`
    A kernel written once and compiled per method: its body refers to
    upper-case global names (``QUERY``, ``EVALUATE``, ...) that
    :func:`specialize` binds to one method's functions in a copy of the
    function.  A comparison of such a constant is folded before typing, so
    a specialised kernel compiles only the code of its method.  Nothing is
    compiled before the first call that needs it.
:func:`launcher`
    A loop over blocks of queries, run on Python threads, that calls a
    block function, through the block's address where Numba's internals
    allow it, so that the loop compiles once for every method and the block
    is not compiled again inside it.

Where the disk cache is kept, and how it survives damaged files and full
disks, is :mod:`proximity.runtime.cache`.
"""

import functools
import hashlib
import os
import threading
import types

from llvmlite import ir
from numba import njit
from numba.core import cgutils
from numba.core import types as nb_types
from numba.extending import intrinsic

from . import threads
from .cache import compiled

_OPTIONS = {"error_model": "numpy"}
# Helpers are called from compiled code only: no wrappers for Python callers
# or for first-class function pointers, which would cost compile time.
_PART = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True, **_OPTIONS}
_INLINE = {"forceinline": True, **_PART}


def inline(func):
    """A helper compiled into its callers by LLVM."""
    return njit(**_INLINE)(func)


def spliced(func):
    """A helper of one call site, spliced into its caller by Numba (see the module's docstring)."""
    return njit(inline="always", **_PART)(func)


def part(func):
    """A function compiled into the kernels that call it (which LLVM may or
    may not inline): callable from compiled code only, and cached as part of
    its callers rather than on its own."""
    return njit(**_PART)(func)


def kernel(*signature, parallel=False, nogil=False):
    """A kernel, cached on disk where possible; compiled at its first call,
    or at once when a ``signature`` is given.  ``nogil``: its calls release
    the GIL, so that Python threads run it side by side
    (:func:`proximity.runtime.threads.spread`).

    Its cached file is named with :func:`_sources_stamp`, as a specialised
    kernel's is: a kernel inlines helpers of other modules, and Numba
    checks only its own module's file for changes.
    """

    def decorate(func):
        options = dict(_OPTIONS, nogil=True) if nogil else _OPTIONS
        return compiled(_stamped(func, func.__globals__), signature, parallel=parallel, **options)

    return decorate


def _stamped(func, namespace, tag=None):
    """A copy of ``func`` over ``namespace``, its qualified name extended by
    ``tag`` and :func:`_sources_stamp` (which name its cached file)."""
    copy = types.FunctionType(func.__code__, namespace, func.__name__, func.__defaults__, func.__closure__)
    middle = "" if tag is None else f"__{tag}"
    copy.__qualname__ = f"{func.__qualname__}{middle}__{_sources_stamp()}"
    copy.__doc__ = func.__doc__
    copy.__module__ = func.__module__
    copy.__kwdefaults__ = func.__kwdefaults__
    return copy


_specialised = {}
_lock = threading.Lock()
_stamp = None


def _sources_stamp():
    """A short hash of the package's source files' names, sizes and times.

    A specialised kernel has code of several modules compiled into it, but
    Numba invalidates a cached kernel only when its own module changes;
    the stamp is part of the cached file's name, so that an edit to any
    module (or an upgrade) compiles the kernels again rather than loading
    stale ones.
    """
    global _stamp
    if _stamp is None:
        digest = hashlib.blake2b(digest_size=6)
        for name, path in stamped_sources():
            info = os.stat(path)
            digest.update(f"{name}:{info.st_size}:{info.st_mtime_ns};".encode())
        _stamp = digest.hexdigest()
    return _stamp


def stamped_sources():
    """``[(name relative to the package, path)]`` of every source file of the package (every
    folder's, the root's), which :func:`_sources_stamp` hashes."""
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = []
    for folder, subfolders, names in os.walk(package):
        subfolders[:] = sorted(d for d in subfolders if d != "__pycache__")
        for name in sorted(names):
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                out.append((os.path.relpath(path, package), path))
    return out


def specialize(func, tag, signature=None, parallel=False, role="kernel", nogil=False, **bindings):
    """The kernel ``func`` with the global names ``bindings`` bound, compiled
    for ``signature`` (lazily without one).

    ``role`` is ``"kernel"`` (cached, callable from Python), ``"part"``,
    ``"inline"`` or ``"spliced"`` (compiled into its callers, as :func:`part`,
    :func:`inline` and :func:`spliced`), or ``"pointer"``: cached, and called from compiled code
    through its address (see :func:`address` and :func:`function_at`).

    ``tag`` names the specialisation: it is part of the cached kernel's file
    name, so every distinct set of ``bindings`` of one ``func`` needs its own.
    Repeated calls return the same kernel.  ``nogil``: a kernel whose calls
    release the GIL (see :func:`kernel`).
    """
    key = (func, tag)
    kernel_ = _specialised.get(key)
    if kernel_ is not None:
        return kernel_
    with _lock:
        kernel_ = _specialised.get(key)
        if kernel_ is None:
            namespace = dict(func.__globals__)
            namespace.update(bindings)
            copy = _stamped(func, namespace, tag)
            args = (signature,) if signature is not None else ()
            if role == "pointer":
                kernel_ = compiled(copy, args, no_cpython_wrapper=True, **_OPTIONS)
            elif role == "spliced":
                kernel_ = spliced(copy)
            elif role != "kernel":
                kernel_ = njit(*args, **(_INLINE if role == "inline" else _PART))(copy)
            else:
                options = dict(_OPTIONS, nogil=True) if nogil else _OPTIONS
                kernel_ = compiled(copy, args, parallel=parallel, **options)
            _specialised[key] = kernel_
    return kernel_


# A loop over blocks of queries runs on Python threads, each thread a
# range of blocks (:func:`proximity.runtime.threads.spread`): a serial kernel
# compiles in a fraction of the time a parallel loop (prange) takes, the
# parfor lowering and its own compiled body left out.  The loop calls the
# block function through its address, so that it compiles once for every
# method and the block is not compiled again inside it.  The address and
# the call through it use Numba's private first-class function internals
# (:func:`_address`, :func:`_at`), which change between Numba releases;
# where they are missing or differ, the loop calls the block directly,
# through Numba's public API: the same code, the same bits, at the cost of
# compiling the block into each loop.

#: Whether blocks are called through their address; cleared, once per
#: process, when Numba's private internals do not work as expected, or
#: from the start where ``PROXIMITY_NUMBA_PUBLIC`` is set (for tests).
BY_ADDRESS = not os.environ.get("PROXIMITY_NUMBA_PUBLIC")
#: Why blocks are no longer called through their address, if they are not.
ADDRESS_ERROR = None


def _address(kernel_, signature):
    """The address of the C entry point of ``kernel_`` for ``signature`` (private Numba API)."""
    from numba.experimental.function_type import _get_wrapper_address

    return _get_wrapper_address(kernel_, signature)


def _at(signature):
    """An intrinsic ``f(address)`` giving, in compiled code, the function of
    ``signature`` at ``address`` (private Numba API: the members of its
    first-class function values)."""
    function_type = nb_types.FunctionType(signature)

    @intrinsic
    def at(typingctx, address_):
        def codegen(context, builder, sig, args):
            # The other members (the Python object, the Numba entry point)
            # start out null, so that the call goes to the C entry point.
            fn = cgutils.create_struct_proxy(function_type)(context, builder)
            fn.c_addr = builder.inttoptr(args[0], ir.IntType(8).as_pointer())
            return fn._getvalue()

        return function_type(nb_types.int64), codegen

    return at


def _call_through(at):
    @inline
    def call(handle, *args):
        fn = at(handle)
        fn(*args)

    return call


def _call_direct(block):
    @inline
    def call(handle, *args):
        block(*args)

    return call


_launchers = {}


def _entry(kernel_, signature):
    """The compiled entry point of ``kernel_`` for ``signature``, called
    without Numba's dispatch: its arguments are converted as the signature
    says, unchecked (records of arrays included, which dispatch would not
    match to a signature of arrays of any layout)."""
    return kernel_.overloads[tuple(signature.args)].entry_point


#: Ranges of blocks handed out per thread of a loop (:func:`launcher`):
#: blocks differ in work by orders of magnitude (points near the centre of a
#: sphere are near every face), so a thread that finishes early takes more.
RANGES_PER_THREAD = 8


def launcher(loop, tag, signature, block, block_signature, blocks, grain=1, parallel=False, **bindings):
    """``loop`` compiled to call ``block``: a function of the loop's arguments but the first three.

    ``loop`` is a kernel whose first arguments are a handle and a range of
    blocks ``lo, hi``; the handle is passed on as the first argument of
    every ``CALL(handle, ...)`` in its body, and ``block`` is a
    ``"pointer"`` kernel (see :func:`specialize`) of ``block_signature``,
    which ``CALL`` calls with the other arguments.  ``signature`` is the
    loop's: handle, ``lo`` and ``hi`` (int64) first.  ``tag`` names the
    loop's specialisation, one per block signature.

    Through the block's address where Numba's internals allow it (the loop
    compiles once for every block of a signature), else by a direct call.
    The function returned skips Numba's dispatch: it must be called with
    arguments of exactly the types of ``signature``.  It runs the blocks
    ``0 .. blocks(*args) - 1`` on the threads (:func:`proximity.runtime.threads.spread`),
    in ranges of at least ``grain`` blocks, about :data:`RANGES_PER_THREAD`
    per thread.  With ``parallel=True`` the loop is instead a parallel kernel
    (``prange(lo, hi)``) called once over every block: for blocks of even
    work, where Numba's threads run the loop faster than ranges handed to
    Python threads (about 15% on a million queries), at the cost of the
    parallel loop's compile.  ``bindings`` are bound in ``loop`` too (see :func:`specialize`); they
    must be the same at every call with one ``tag``.
    """
    global BY_ADDRESS, ADDRESS_ERROR
    key = (loop, tag, block)
    run = _launchers.get(key)
    if run is not None:
        return run
    entry = None
    options = {"parallel": True} if parallel else {"nogil": True}
    if BY_ADDRESS:
        try:
            call = _call_through(_at(block_signature))
            compiled = specialize(loop, f"{tag}__address", signature, **options, CALL=call, **bindings)
            entry = functools.partial(_entry(compiled, signature), _address(block, block_signature))
        except Exception as exc:  # noqa: BLE001  (any failure of the private internals)
            BY_ADDRESS = False
            ADDRESS_ERROR = exc
    if entry is None:
        name = hashlib.blake2b(block.py_func.__qualname__.encode(), digest_size=6).hexdigest()
        call = _call_direct(block)
        compiled = specialize(loop, f"{tag}__{name}", signature, **options, CALL=call, **bindings)
        entry = functools.partial(_entry(compiled, signature), 0)

    def run(*args):
        n = blocks(*args)
        if parallel:
            entry(0, n, *args)
            return
        chunk = max(grain, -(-n // (RANGES_PER_THREAD * threads.current())))
        threads.spread(lambda lo, hi: entry(lo, hi, *args), n, chunk)

    _launchers[key] = run
    return run
