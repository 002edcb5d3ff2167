"""The methods a query can use, and what each one promises.

Every query takes ``method=`` by name; :func:`resolve` turns the name into
a :class:`Method` once, at the public boundary, and everything below works
with that object.  Each shape's kernel module holds, per method name, the
compiled functions that implement it (its ``KERNELS`` table), and compiles
a method's kernels only when a query first uses them.

Adding a method is one entry in :data:`REGISTRY` and, in each kernel module,
one entry of ``KERNELS`` (see ``docs/design.md``).
"""

from dataclasses import dataclass

__all__ = ["CERTIFIED", "DEFAULT", "EBERLY", "REGISTRY", "ROBUST", "Method", "resolve"]


@dataclass(frozen=True)
class Method:
    """A query method.

    Attributes
    ----------
    name : str
        The value of ``method=`` that selects it.
    guarantee : str
        The error bound it is tested against, in words.
    exact_fallback : bool
        Whether queries its float filter cannot decide are finished in
        exact rational arithmetic (after the compiled loop).
    loose : bool
        Whether its closest point on a circle may leave the circle's
        bounding box (Eberly's rim direction near the axis), which the
        broad phase must then allow for.

    Examples
    --------
    >>> import proximity
    >>> m = proximity.methods.resolve("certified")
    >>> m.name, m.exact_fallback
    ('certified', True)
    """

    name: str
    guarantee: str
    exact_fallback: bool = False
    loose: bool = False

    def __repr__(self):
        return f"Method({self.name!r})"


ROBUST = Method(
    "robust",
    "|d - d*| <= 8 eps S + 2^-1075 for every finite input (S: the query's size)",
)
CERTIFIED = Method(
    "certified",
    "faithfully rounded distance and the exact closest feature, for every finite input",
    exact_fallback=True,
)
EBERLY = Method(
    "eberly",
    "none: Eberly's algorithms as written in his two documents, kept as the baseline",
    loose=True,
)

#: Every method, by name, in the order they are documented.
REGISTRY = {m.name: m for m in (ROBUST, CERTIFIED, EBERLY)}

#: The method used when none is given.
DEFAULT = ROBUST.name


def resolve(method):
    """The :class:`Method` named ``method``.

    Raises
    ------
    TypeError
        If ``method`` is not a string.
    ValueError
        If no method has that name.

    Examples
    --------
    >>> import proximity
    >>> proximity.methods.resolve("robust")
    Method('robust')
    >>> proximity.methods.resolve("fast")
    Traceback (most recent call last):
    ...
    ValueError: method must be one of ('robust', 'certified', 'eberly'); got 'fast'
    """
    if type(method) is Method:
        return method
    try:
        return REGISTRY[method]
    except (KeyError, TypeError):
        pass
    if not isinstance(method, str):
        raise TypeError(
            f"method must be a str, one of {tuple(REGISTRY)}; got {type(method).__name__} {method!r}"
        )
    raise ValueError(f"method must be one of {tuple(REGISTRY)}; got {method!r}{suggest(method, REGISTRY)}")


def suggest(name, names):
    """``"; did you mean 'robust'?"`` where ``name`` is close to one of ``names`` (a
    different case, a typo), else ``""``."""
    import difflib

    lowered = {n.lower(): n for n in names}
    close = lowered.get(name.lower()) or next(
        iter(difflib.get_close_matches(name.lower(), lowered, n=1, cutoff=0.75)), None
    )
    return "" if close is None else f"; did you mean {lowered.get(close, close)!r}?"
