"""What a user holds: the shape protocol, frozen facades, rounded and posed views, meshes, scenes.

:mod:`.base`
    The :class:`Shape` protocol, the frozen facades and the primitives' shapes (triangles,
    segments, points, circles, disks).
:mod:`.rounded`
    Rounded shapes: a core and a radius (:class:`Inflated`, :class:`Sphere`, :class:`Capsule`).
:mod:`.posed`
    Posed views: a shape and a rigid transform, in O(1).
:mod:`.collection`, :mod:`.mesh`, :mod:`.scene`
    Collections of primitives searched down a hierarchy: triangle meshes and scenes.
:mod:`.meshlike`
    Other libraries' meshes taken apart by their attributes, without importing those libraries.

It may import :mod:`proximity.signs`, :mod:`proximity.broadphase`, :mod:`proximity.point`,
:mod:`proximity.numerics`, :mod:`proximity.runtime`, the registries and the root's vocabulary.
"""

from .base import DEFAULT_METHOD, Circle, Disk, Frozen, Point, Segment, Shape, Triangle
from .mesh import TriangleMesh
from .posed import Posed
from .rounded import Capsule, Inflated, Sphere
from .scene import Scene

__all__ = [
    "DEFAULT_METHOD",
    "Capsule",
    "Circle",
    "Disk",
    "Frozen",
    "Inflated",
    "Point",
    "Posed",
    "Scene",
    "Segment",
    "Shape",
    "Sphere",
    "Triangle",
    "TriangleMesh",
]
