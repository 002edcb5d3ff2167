"""Counts of the certified method's exact fallbacks (no compiled code here,
so that reading them does not load the compiler)."""

_STATS = {"queries": 0, "exact": 0}


def count(queries, exact):
    """Record ``queries`` certified queries, ``exact`` of them by the fallback."""
    _STATS["queries"] += queries
    _STATS["exact"] += exact


def stats(reset: bool = False) -> dict[str, int]:
    """How often the certified method fell back to exact arithmetic.

    Parameters
    ----------
    reset : bool
        Start counting afresh after reading.

    Returns
    -------
    dict
        ``{"queries": n, "exact": k}``: certified queries answered in this
        process (since the last reset), and how many of them needed the
        exact fallback.

    Examples
    --------
    >>> import proximity
    >>> _ = proximity.certified_stats(reset=True)
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> float(tri.distance([[0.25, 0.25, 1.0], [0.5, 0.5, 0.0]], method="certified")[1])
    0.0
    >>> proximity.certified_stats()
    {'queries': 2, 'exact': 1}
    """
    from .._validate import flag

    out = dict(_STATS)
    if flag(reset, "reset"):
        _STATS.update(queries=0, exact=0)
    return out
