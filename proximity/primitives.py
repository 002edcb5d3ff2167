"""The kinds of primitive a query can be made against, and what each one brings.

The twin of :mod:`proximity.methods`: one :class:`Primitive` record per
kind, in :data:`REGISTRY`.  The broad phase, scenes, the compile command,
the adapters and the contract tests read these records and never name a
kind; adding a primitive is its kernel module, its facade and result, and
one line here (``docs/design.md`` walks through the segment).

A primitive is stored in a collection (a mesh or a scene) as one row of
parameters and its kind's ``code``; its first ``3 * vertices`` parameters
are the points it is the convex hull of (none for disks and circles,
which bound themselves by their box).  Its kernel module, imported at first
use, provides for every method:

``row_query(primitive, method)``
    The query of one stored row, ``(kind, params, k, px, py, pz)`` to
    ``(status, distance, sqr_distance, x, y, z, feature, a0, a1, a2, flag)``:
    ``a`` holds up to three of the result's extra values (see ``extra``),
    ``flag`` its boolean one.
``row_interval(primitive)``
    Bounds ``(lo, hi)`` on the certified distance of one stored row, from
    the robust one, for the rows the certified filter leaves undecided.
``cull(code, params, rows, out)``
    Each row's box and slab (``rows`` of ``params``, into ``out``), and
    the looser boxes of the ``eberly`` method where they differ.
``resolve(code, params, point)``
    The certified answers of rows, exact fallback included, as arrays.

and, where it can, for a method whose answers are always certain:

``row_batch(primitive, method, indexed=False)``
    The query of up to :data:`LANES` stored rows side by side (SIMD), or
    None: ``(params, rows, n, px, py, pz, z)`` answers rows ``rows[:n]``,
    writing row ``rows[j]``'s ``(distance, sqr_distance, x, y, z, feature,
    a0, a1, a2)`` to column ``j`` of rows ``PAIR_OUT ..`` of ``z``, scratch
    laid out as a batch block's (``_loops.PAIR_ROWS`` rows, ``LANES``
    columns); the same bits as ``row_query``.  The search of a tree of that
    kind alone evaluates its leaves' rows this way.
"""

from dataclasses import dataclass

import numpy as np

from .runtime import lazy

#: Rows answered side by side by a ``row_batch`` (see the module docstring):
#: the width of the vector units' float64 lanes on current x86 (AVX2), and
#: of the leaves of most trees.
LANES = 4

__all__ = [
    "BY_CODE",
    "CIRCLE",
    "DISK",
    "POINT",
    "REGISTRY",
    "SEGMENT",
    "TRIANGLE",
    "Primitive",
    "offering",
    "present",
    "transform_rows",
    "vertex_counts",
]


@dataclass(frozen=True, eq=False)
class Primitive:
    """A kind of primitive.

    Attributes
    ----------
    name : str
        Its name, as the facade's class is named in lower case.
    code : int
        Its kind code in a collection's rows.
    width : int
        Number of parameters of a stored row.
    vertices : int
        How many points, at the start of its row, it is the convex hull of
        (0: it is bounded by its box).
    module : str
        Its kernel module in :mod:`proximity`, imported at first use.
    extra : tuple of (str, int)
        The result fields it carries in the ``a0 .. a2`` values of a stored
        row's answer, with their widths; a width of 0 is the boolean flag.
    methods : tuple of str
        The methods it offers.
    axis : int or None
        The first of the three parameters that hold its unit normal, for a
        primitive with an axis (disks and circles), else None.
    points, directions : tuple of int
        The first columns of the row's points and of its directions, three
        values each: what a rigid motion moves and what it turns.

    Examples
    --------
    >>> import proximity
    >>> t = proximity.primitives.REGISTRY["triangle"]
    >>> t.code, t.width, t.extra
    (0, 9, (('barycentric', 3),))
    """

    name: str
    code: int
    width: int
    vertices: int
    module: str
    extra: tuple
    methods: tuple = ("robust", "certified", "eberly")
    axis: int | None = None
    points: tuple = ()
    directions: tuple = ()

    @property
    def kernels(self):
        """Its kernel module (importing it loads the compiler, under
        :func:`proximity.runtime.lazy.load`'s lock)."""
        return lazy.load(f"proximity.{self.module}")

    def __repr__(self):
        return f"Primitive({self.name!r})"


TRIANGLE = Primitive("triangle", 0, 9, 3, "point.triangle", (("barycentric", 3),), points=(0, 3, 6))
# A disk's and a circle's row: center, unit normal, normal as given, radius.
DISK = Primitive(
    "disk", 1, 10, 0, "point.disk", (("height", 1), ("radial", 1)), axis=3, points=(0,), directions=(3, 6)
)
CIRCLE = Primitive(
    "circle", 2, 10, 0, "point.disk", (("height", 1), ("radial", 1), ("equidistant", 0)),
    axis=3, points=(0,), directions=(3, 6),
)  # fmt: skip
SEGMENT = Primitive(
    "segment", 3, 6, 2, "point.segment", (("parameter", 1),), ("robust", "certified"), points=(0, 3)
)
POINT = Primitive("point", 4, 3, 1, "point.point", (), ("robust", "certified"), points=(0,))

#: Every primitive, by name, in code order.
REGISTRY = {p.name: p for p in (TRIANGLE, DISK, CIRCLE, SEGMENT, POINT)}

#: Every primitive, indexed by its code.
BY_CODE = tuple(sorted(REGISTRY.values(), key=lambda p: p.code))
assert [p.code for p in BY_CODE] == list(range(len(BY_CODE))), "codes must be 0, 1, 2, ..."

#: Columns of a collection's parameter rows: the widest primitive's.
N_PARAMS = max(p.width for p in BY_CODE)


def vertex_counts():
    """``vertices`` of every primitive, indexed by code: an int64 array for the kernels."""
    counts = np.array([p.vertices for p in BY_CODE], np.int64)
    counts.flags.writeable = False
    return counts


def present(kinds):
    """The primitives among the codes ``kinds``, in code order."""
    if len(kinds) == 0:
        return ()
    counts = np.bincount(kinds, minlength=len(BY_CODE))
    return tuple(p for p in BY_CODE if counts[p.code])


def offering(method):
    """The primitives that offer ``method`` (a :class:`~proximity.methods.Method`), in code order."""
    return tuple(p for p in BY_CODE if method.name in p.methods)


def transform_rows(kinds, params, rotation, translation):
    """Stored rows ``params`` moved by the rigid motion ``X -> R X + t``: each
    kind's points moved, its directions turned (a new array)."""
    out = np.array(params, dtype=np.float64, copy=True)
    for p in present(kinds):
        rows = kinds == p.code
        for c in p.points:
            out[rows, c : c + 3] = params[rows, c : c + 3] @ rotation.T + translation
        for c in p.directions:
            out[rows, c : c + 3] = params[rows, c : c + 3] @ rotation.T
    return out
