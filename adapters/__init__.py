"""Other libraries' closest-point answers, behind proximity's query interface.

Each backend wraps one library (python-fcl, trimesh, pybullet), builds the
smallest native model that answers the query (the closest point to a
point, or the closest points of two shapes), and returns proximity's own
result types.  Answers that the library gives in its own conventions
(sentinels, missing results, contact where there is none, nearest points off
the shape) are translated to NaN with a :class:`Failure` code per row, so
that comparisons across libraries mean something.  :func:`cross_check` asks
them all and proximity itself, in the caller's coordinates unless asked to
rescale, summarises the disagreements, and lists the backends that cannot
be given the query, with their reasons.

Examples
--------
>>> import proximity, proximity.adapters as adapters
>>> names = adapters.available()     # those whose library is installed
>>> disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
>>> with adapters.get("trimesh") as backend:     # a fan of K triangles, K from the tolerance
...     r = backend.closest_point(disk, [[0.5, 0.0, 2.0], [3.0, 0.0, 0.0]])
>>> r.distance.round(4).tolist(), int(r.model.segments), round(float(r.model.bound), 6)
([2.0, 2.0004], 71, 0.000979)
"""

from ._common import BackendResult, Failure, Model, segments_for
from .crosscheck import Case, CrossCheck, LeftOut, Summary, cross_check
from .registry import NAMES, available, get

__all__ = [
    "BackendResult",
    "Case",
    "CrossCheck",
    "Failure",
    "LeftOut",
    "Model",
    "NAMES",
    "Summary",
    "available",
    "cross_check",
    "get",
    "segments_for",
]
