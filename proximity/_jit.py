"""How the kernels are compiled: inlining, the disk cache, and specialisation.

Three decorators and three functions, used by every kernel module:

``inline``
    A helper inlined by LLVM into its callers (``forceinline``).  Numba
    compiles it once per signature; inlining at Numba's IR level instead
    would run its front end again at every call site.
``part``
    A larger function compiled into the kernels that call it (a block of a
    batch loop, a scalar query), where LLVM decides whether to inline.
``kernel``
    A compiled function that is cached on disk, where a cache can be kept
    (see :mod:`proximity._cache`).
:func:`specialize`
    A kernel written once and compiled per method: its body refers to
    upper-case global names (``QUERY``, ``EVALUATE``, ...) that
    :func:`specialize` binds to one method's functions in a copy of the
    function.  A comparison of such a constant is folded before typing, so
    a specialised kernel compiles only the code of its method.  Nothing is
    compiled before the first call that needs it.
:func:`address` and :func:`function_at`
    A block function called by a parallel loop through its address, so
    that the loop compiles once for every method and the block is not
    compiled again inside it.

Where the disk cache is kept, and how it survives damaged files and full
disks, is :mod:`proximity._cache`.
"""

import hashlib
import os
import threading
import types

from llvmlite import ir
from numba import njit
from numba.core import cgutils
from numba.core import types as nb_types
from numba.experimental.function_type import _get_wrapper_address
from numba.extending import intrinsic

from ._cache import compiled

_OPTIONS = {"error_model": "numpy"}
# Helpers are called from compiled code only: no wrappers for Python callers
# or for first-class function pointers, which would cost compile time.
_PART = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True, **_OPTIONS}
_INLINE = {"forceinline": True, **_PART}


def inline(func):
    """A helper compiled into its callers by LLVM."""
    return njit(**_INLINE)(func)


def part(func):
    """A function compiled into the kernels that call it (which LLVM may or
    may not inline): callable from compiled code only, and cached as part of
    its callers rather than on its own."""
    return njit(**_PART)(func)


def kernel(*signature, parallel=False):
    """A kernel, cached on disk where possible; compiled at its first call,
    or at once when a ``signature`` is given."""
    return lambda func: compiled(func, signature, parallel=parallel, **_OPTIONS)


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
        here = os.path.dirname(os.path.abspath(__file__))
        digest = hashlib.blake2b(digest_size=6)
        for name in sorted(os.listdir(here)):
            if name.endswith(".py"):
                info = os.stat(os.path.join(here, name))
                digest.update(f"{name}:{info.st_size}:{info.st_mtime_ns};".encode())
        _stamp = digest.hexdigest()
    return _stamp


def specialize(func, tag, signature=None, parallel=False, role="kernel", **bindings):
    """The kernel ``func`` with the global names ``bindings`` bound, compiled
    for ``signature`` (lazily without one).

    ``role`` is ``"kernel"`` (cached, callable from Python), ``"part"`` or
    ``"inline"`` (compiled into its callers, as :func:`part` and
    :func:`inline`), or ``"pointer"``: cached, and called from compiled code
    through its address (see :func:`address` and :func:`function_at`).

    ``tag`` names the specialisation: it is part of the cached kernel's file
    name, so every distinct set of ``bindings`` of one ``func`` needs its own.
    Repeated calls return the same kernel.
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
            copy = types.FunctionType(func.__code__, namespace, func.__name__, func.__defaults__)
            copy.__qualname__ = f"{func.__qualname__}__{tag}__{_sources_stamp()}"
            copy.__doc__ = func.__doc__
            copy.__module__ = func.__module__
            args = (signature,) if signature is not None else ()
            if role == "pointer":
                kernel_ = compiled(copy, args, no_cpython_wrapper=True, **_OPTIONS)
            elif role != "kernel":
                kernel_ = njit(*args, **(_INLINE if role == "inline" else _PART))(copy)
            else:
                kernel_ = compiled(copy, args, parallel=parallel, **_OPTIONS)
            _specialised[key] = kernel_
    return kernel_


# A parallel loop compiles its body into a function of its own, and
# optimises and compiles it again with every function it calls linked in.
# A block function called through its address instead is compiled once, on
# its own, and the loop that calls it compiles once for every method.


def address(kernel_, signature):
    """The address of the C entry point of ``kernel_`` (a ``"pointer"`` kernel,
    see :func:`specialize`) for ``signature``: an int, which a kernel turns
    back into a function with :func:`function_at`."""
    return _get_wrapper_address(kernel_, signature)


def function_at(signature):
    """An intrinsic ``f(address)`` that gives, in compiled code, the function
    of ``signature`` at ``address`` (from :func:`address`), to be called.

    Passing the address as an int, rather than the function itself, keeps
    the call from Python as cheap as with arrays and numbers alone.
    """
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
