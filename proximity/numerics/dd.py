"""Double-double arithmetic: a value as an unevaluated sum ``hi + lo``.

About 106 bits of precision from pairs of float64, built on the error-free
transformations of :mod:`.fp`.  Each operation's relative error is a few
``u^2`` (``u = 2^-53``), which :mod:`.certified` turns into rigorous bounds
(with generous constants) to decide when a float64 result is faithfully
rounded.
"""

import math

from ..runtime.jit import inline
from .fp import fma, two_product, two_sum

U = 2.0**-53


@inline
def fast_two_sum(a, b):
    """``(s, e)`` with ``s + e == a + b`` exactly, provided ``|a| >= |b|`` or ``a == 0``."""
    s = a + b
    return s, b - (s - a)


@inline
def add(ah, al, bh, bl):
    """``a + b``; relative error below ``3 u^2`` (accurate double-double sum)."""
    s, e = two_sum(ah, bh)
    t, f = two_sum(al, bl)
    e += t
    s, e = fast_two_sum(s, e)
    e += f
    return fast_two_sum(s, e)


@inline
def sub(ah, al, bh, bl):
    """``a - b``; as :func:`add`."""
    return add(ah, al, -bh, -bl)


@inline
def mul(ah, al, bh, bl):
    """``a * b``; relative error below ``7 u^2``."""
    p, e = two_product(ah, bh)
    e = fma(ah, bl, e)
    e = fma(al, bh, e)
    return fast_two_sum(p, e)


@inline
def sqr(ah, al):
    """``a * a``; relative error below ``7 u^2``."""
    p, e = two_product(ah, ah)
    e = fma(2.0 * ah, al, e)
    return fast_two_sum(p, e)


@inline
def div(ah, al, bh, bl):
    """``a / b``; relative error below ``16 u^2`` for ``b != 0``."""
    q1 = ah / bh
    ph, pl = mul(q1, 0.0, bh, bl)
    rh, rl = sub(ah, al, ph, pl)
    q2 = rh / bh
    ph, pl = mul(q2, 0.0, bh, bl)
    rh, rl = sub(rh, rl, ph, pl)
    q3 = rh / bh
    s, e = fast_two_sum(q1, q2)
    return add(s, e, q3, 0.0)


@inline
def sqrt(ah, al):
    """``sqrt(a)`` for ``a >= 0``; relative error below ``8 u^2``."""
    if ah <= 0.0:
        return 0.0, 0.0
    r = math.sqrt(ah)
    # One Newton step on the residual, computed exactly with an FMA.
    e = fma(-r, r, ah) + al
    return fast_two_sum(r, e / (2.0 * r))


@inline
def diff(a, b):
    """``a - b`` of two floats, exactly, as a double-double."""
    return two_sum(a, -b)
