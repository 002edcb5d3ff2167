"""How kernels compile, cache, thread and batch: the machinery under every query.

:mod:`.jit`
    The decorators (``inline``, ``part``, ``kernel``) and ``specialize``, which compiles a kernel
    with its upper-case placeholders bound; cached files named by a stamp of the sources.
:mod:`.cache`
    The disk cache of compiled kernels, safe from damaged files and full disks.
:mod:`.notice`
    The one line on stderr before a first compile.
:mod:`.lazy`
    Modules that load Numba, imported at first use under one lock.
:mod:`.threads`
    Numba's threading layer, ``proximity.threads(n)``, and the kernels' thread limits.
:mod:`.pool`
    The recycled memory of large outputs.
:mod:`.loops`
    Gathers and scatters of the batch loop's blocks, and the one-query entry points.
:mod:`.batch`
    The batch pipeline: broadcasting, outputs and the parallel loop, for every primitive.
:mod:`.counts`
    The counts of certified queries finished in exact arithmetic.

It may import the root's vocabulary (:mod:`proximity.methods`, :mod:`proximity.features`,
:mod:`proximity._validate`) and nothing else of the package: it knows no shape, no primitive and
no numerics.
"""
