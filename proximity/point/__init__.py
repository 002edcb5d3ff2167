"""Point queries, one module per kind of primitive, every method's kernels in each.

:mod:`.triangle`
    Eberly, *Distance Between Point and Triangle in 3D* (Geometric Tools): the document's
    algorithm (``eberly``), the robust and the certified queries.
:mod:`.segment`, :mod:`.point`
    A segment and a point.
:mod:`.disk`, :mod:`.circle`
    Eberly, *Distance Between Point and Circle or Disk in 3D* (Geometric Tools): disks and
    circles.

Each module provides the names the registry of primitives asks for (``KERNELS``, ``LAYOUT``,
``row_query``, ...: see :mod:`proximity.primitives`), and imports :mod:`proximity.numerics`,
:mod:`proximity.runtime`, the registry and the root's vocabulary; one may use another's kernels
(a triangle's edges are segments).
"""
