"""Pair queries of scenes of instances: each part of the scene against the other side, the least wins.

A scene of posed meshes or scenes (:class:`proximity.Scene` with
instances) has no hierarchy over all its primitives, only its prototypes'
and one over its loose primitives.  Its pair with another shape is the
least over its parts: each posed member (a posed view, searched in place
by :mod:`proximity.pair.queries`) and the loose primitives (the scene's
own tree, already numbered as the scene numbers them).  A pose or a radius
around the scene goes to each part: the distance to a union is the least
of the distances to its members, and posing or rounding a union poses or
rounds each member.

Where one pair is asked, each part is searched with the best distance so
far as its ``max_distance``, so that parts farther than the answer prune
at their roots; ties go to the lowest primitive, as in a scene's own
search.  Each row of the answer is one part's answer, bit for bit, its
``primitive`` and ``source`` renumbered into the scene.
"""

import numpy as np

from .._validate import freeze_result
from ..numerics.rounding import total_radius
from ..results import pair_result
from ..shapes.posed import Posed
from ..shapes.rounded import Inflated

#: The fields of a :class:`~proximity.results.PairResult`.
_FIELDS = ("distance", "sqr_distance", "point_a", "point_b", "feature_a", "feature_b") + tuple(
    f"{name}_{side}" for name in ("parameter", "barycentric", "face", "primitive", "source") for side in "ab"
)


def unwrapped(shape):
    """``(scene, transform, radius)`` where ``shape`` is a scene of instances,
    possibly posed and rounded (``transform`` a 4x4 or None, ``radius`` the
    radii, of the rounded shape's batch, or None); None otherwise."""
    from ..shapes.scene import Scene

    poses, radii, core = [], [], shape
    while isinstance(core, (Posed, Inflated)):
        if isinstance(core, Posed):
            poses.append(core)
            core = core.shape
        else:
            radii.append(core.radius)
            core = core.core
    if type(core) is not Scene or core._instanced is None:
        return None
    radius = total_radius(radii)
    from ..numerics.rigid import pose_matrix

    transform = None
    for view in reversed(poses):
        pose = pose_matrix(view.rotation, view.translation)
        transform = pose if transform is None else pose @ transform
    return core, transform, radius


def parts(scene, transform, radius):
    """``[(part, offset, source, kind)]`` of a scene of instances: each posed
    member (its primitives numbered from ``offset``, ``source`` its index,
    ``kind`` "face" for a mesh and "primitive" for a scene), then the loose
    primitives (numbered as the scene numbers them: offset 0, source None)."""
    from ..shapes.scene import _instance

    out = []
    for j, shape in enumerate(scene.shapes):
        if _instance(shape):
            kind = "face" if hasattr(shape.shape, "faces") else "primitive"
            out.append((_dressed(shape, transform, radius), int(scene.offsets[j]), j, kind))
    if scene._tree is not None:
        loose = object.__new__(type(scene))
        loose._init(**{name: getattr(scene, name) for name in type(scene).__slots__})
        loose._init(_instanced=None)
        out.append((_dressed(loose, transform, radius), 0, None, "primitive"))
    return out


def _dressed(part, transform, radius):
    if radius is not None:
        part = Inflated(part, radius)
    if transform is not None:
        part = part.transformed(transform)
    return part


def least(query, a, b, key, single, cutoff, signed):
    """The pair ``query(a, b, max_distance=...)`` where side ``key`` (``"a"`` or
    ``"b"``) is a scene of instances: the least over its parts (see the
    module docstring).  ``signed``: ``query`` returns values (distances),
    otherwise :class:`~proximity.results.PairResult`."""
    scene, transform, radius = unwrapped(a if key == "a" else b)
    best = None
    for part, offset, source, kind in parts(scene, transform, radius):
        bound = cutoff
        if single and best is not None:
            value = best if signed else best.distance
            bound = float(value) if cutoff is None else min(cutoff, float(value))
            if signed and bound < 0.0:
                bound = cutoff  # overlapping: the cutoff cannot prune below zero
        pa, pb = (part, b) if key == "a" else (a, part)
        got = query(pa, pb, max_distance=bound)
        if signed:
            got = np.asarray(got, np.float64)
            best = got if best is None else np.where(got < best, got, best)
            continue
        got = _renumbered(got, key, offset, source, kind)
        best = got if best is None else _merged(best, got, key)
    if signed:
        return freeze_result(np.array(best))[()]
    return best


def _renumbered(result, key, offset, source, kind):
    """A part's answer with the scene's numbering on side ``key``."""
    if source is None:
        return result
    local = np.asarray(getattr(result, f"{kind}_{key}"))
    found = local >= 0
    fields = {
        f"face_{key}": np.full(local.shape, -1, np.int64),
        f"primitive_{key}": np.where(found, local + offset, -1),
        f"source_{key}": np.where(found, source, -1),
    }
    return _with(result, fields)


def _merged(best, got, key):
    """Row by row, the nearer of two answers; ties to the lower primitive."""
    d0, d1 = np.asarray(best.distance), np.asarray(got.distance)
    p0, p1 = np.asarray(getattr(best, f"primitive_{key}")), np.asarray(getattr(got, f"primitive_{key}"))
    take = (d1 < d0) | ((d1 == d0) & (p1 >= 0) & ((p0 < 0) | (p1 < p0)))
    fields = {}
    for name in _FIELDS:
        old, new = np.asarray(getattr(best, name)), np.asarray(getattr(got, name))
        mask = take.reshape(take.shape + (1,) * (old.ndim - take.ndim))
        fields[name] = np.where(mask, new, old)
    return _with(best, fields, _Merged(best, got, take))


class _Merged:
    """The normals of a row-by-row choice between two answers (``chosen``: ``got``'s rows)."""

    __slots__ = ("best", "got", "chosen")

    def __init__(self, best, got, chosen):
        self.best, self.got, self.chosen = best, got, chosen

    def normal(self):
        mask = self.chosen[..., None]
        return np.where(mask, np.asarray(self.got.normal), np.asarray(self.best.normal))

    def take(self, index):
        return _Merged(self.best[index], self.got[index], self.chosen[index])

    def negated(self):
        return _Merged(self.best.swapped(), self.got.swapped(), self.chosen)


def _with(result, fields, normals=None):
    """``result`` with ``fields`` replaced, its normals ``normals`` (a source, see
    :attr:`~proximity.results.PairResult.normal`) or, without, its own."""
    values = {name: np.asarray(getattr(result, name)) for name in _FIELDS}
    values.update(fields)
    shape = np.shape(values["distance"])
    flat = {name: np.asarray(v).reshape((-1,) + np.shape(v)[len(shape) :]) for name, v in values.items()}
    out = pair_result(flat, shape, normals)
    if normals is None:
        out.__dict__.update({k: v for k, v in result.__dict__.items() if k in ("_pair", "_normal")})
    return out
