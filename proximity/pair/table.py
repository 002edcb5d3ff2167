"""The pairs of primitive kinds a query between two shapes can be made for, and who answers each.

The twin of :mod:`proximity.primitives` for queries between two shapes:
one :class:`Pair` record per ordered pair of kinds, in :data:`REGISTRY`.
The batch pipeline of pairs, the fast path, the simultaneous descent of
two hierarchies (:mod:`proximity.pair.descent`) and the public
:func:`proximity.closest_points` read these records and never name a kind.

Two kinds of answer:

a pair kernel
    A module with the pair's own queries (``robust``, ``robust_unscaled``,
    ``certified``): :mod:`.segment_segment`, :mod:`.segment_triangle`,
    :mod:`.triangle_triangle`; each returns ``(distance, sqr_distance,
    point_a, point_b, feature_a, feature_b, the parameters of a, the
    parameters of b)``, with an exact fallback in :mod:`proximity.numerics.exact`.
a point query
    A point against any kind is that kind's point query (its kernel
    module's ``row_query``), the point being shape a (``point=True``).

A record answered by the kernel of the pair the other way round (a
triangle against a segment is the segment-triangle query) has
``swapped=True``: its sides are exchanged before the query and after.
Pairs that are not here (a disk or a circle against a segment, a triangle
or another disk or circle: their distance needs the roots of polynomials
of degree up to 8) raise :class:`NotImplementedError` from :func:`lookup`.
"""

from dataclasses import dataclass

from ..primitives import BY_CODE, POINT, SEGMENT, TRIANGLE
from ..primitives import REGISTRY as KINDS
from ..runtime import lazy

__all__ = ["REGISTRY", "Pair", "lookup"]


@dataclass(frozen=True, eq=False)
class Pair:
    """An ordered pair of primitive kinds, and what answers it.

    Attributes
    ----------
    a, b : Primitive
        The kinds of shape a and shape b.
    module : str
        The kernel module in :mod:`proximity` that answers it: the pair's
        (for ``(b, a)`` where ``swapped``), or the point query's kind's.
    swapped : bool
        Whether the module answers the pair the other way round.
    point : bool
        Whether the answer is a point query (the point as its shape a).
    extras : tuple of (int, int)
        How many parameters of each side the module's answer carries, in
        the module's order of sides: 1 for a segment (its ``t``), 3 for a
        triangle (barycentrics), 0 for a point; a point query's are the
        stored row's answer's (:mod:`proximity.primitives`).
    exact : str
        The exact fallback in :mod:`proximity.numerics.exact` (pair kernels).
    methods : tuple of str

    Examples
    --------
    >>> import proximity
    >>> p = proximity.pair.table.lookup("triangle", "segment")
    >>> p.module, p.swapped
    ('pair.segment_triangle', True)
    """

    a: object
    b: object
    module: str
    swapped: bool = False
    point: bool = False
    extras: tuple = (0, 0)
    exact: str = ""
    methods: tuple = ("robust", "certified")

    @property
    def name(self):
        """``"a_b"``, the kinds' names."""
        return f"{self.a.name}_{self.b.name}"

    @property
    def unswapped(self):
        """The record whose module answers this pair in its own order: this one, or the
        pair the other way round where ``swapped``."""
        return REGISTRY[(self.b.name, self.a.name)] if self.swapped else self

    @property
    def kernels(self):
        """The kernel module (importing it loads the compiler)."""
        return lazy.load(f"proximity.{self.module}")

    @property
    def code(self):
        """The pair's code in a chain over pairs of kinds: ``a.code * len(BY_CODE) + b.code``."""
        return self.a.code * len(BY_CODE) + self.b.code

    def __repr__(self):
        return f"Pair({self.a.name!r}, {self.b.name!r})"


def _records():
    kernel = {
        (SEGMENT, SEGMENT): ("segment_segment", (1, 1)),
        (SEGMENT, TRIANGLE): ("segment_triangle", (1, 3)),
        (TRIANGLE, TRIANGLE): ("triangle_triangle", (3, 3)),
    }
    out = []
    for (a, b), (name, extras) in kernel.items():
        out.append(Pair(a, b, f"pair.{name}", extras=extras, exact=name))
        if a is not b:
            out.append(Pair(b, a, f"pair.{name}", swapped=True, extras=extras, exact=name))
    for kind in BY_CODE:
        extras = (0, 3)
        out.append(Pair(POINT, kind, kind.module, point=True, extras=extras))
        if kind is not POINT:
            out.append(Pair(kind, POINT, kind.module, swapped=True, point=True, extras=extras))
    return out


#: Every supported pair, by ``(name of a, name of b)``.
REGISTRY = {(p.a.name, p.b.name): p for p in _records()}


def lookup(a, b, names=("a", "b")):
    """The :class:`Pair` of kinds ``a`` and ``b`` (names or Primitive records).

    Raises
    ------
    NotImplementedError
        Naming both arguments (``names``) and their kinds, for a pair that
        has no query.
    """
    key = (getattr(a, "name", a), getattr(b, "name", b))
    pair = REGISTRY.get(key)
    if pair is None:
        for name, kind in zip(names, key, strict=True):
            if kind not in KINDS:
                raise ValueError(f"{name} must be a kind of primitive ({', '.join(KINDS)}); got {kind!r}")
        raise NotImplementedError(
            f"the distance between a {key[0]} ({names[0]}) and a {key[1]} ({names[1]}) is not implemented: "
            "disks and circles answer queries from points only (against another disk, circle, segment or "
            "triangle the distance needs the roots of a polynomial of degree up to 8)"
        )
    return pair
