"""Exact orientation predicates on float coordinates: a float filter, then expansion arithmetic.

``orient3d(a, b, c, d)`` is the sign of ``(a - d) . ((b - d) x (c - d))``,
positive where ``d`` sees ``a, b, c`` clockwise (below the plane of a
counterclockwise triangle); ``orient2d(a, b, c)`` the sign of ``(b - a) x
(c - a)``, positive counterclockwise.  Each is evaluated in floats with
J. R. Shewchuk's static error bound (*Adaptive precision floating-point
arithmetic and fast robust geometric predicates*, Discrete Comput. Geom.
18, 1997, section 4.3: ``(7 + 56 u) u`` and ``(3 + 16 u) u`` of the
permanent, ``u = 2^-53``; rounded up here), and where the value is within
that bound of 0, exactly: the differences as two-term expansions
(``two_sum``), their products and sums by Shewchuk's Scale-Expansion and
Grow-Expansion, and the sign of the expansion's largest component.

The expansions are exact unless an error term underflows, which a
nonzero difference of magnitude below :data:`TINY` could cause: the
predicates then answer :data:`DOUBT` (2) rather than a sign.  Callers work
in a frame scaled so that coordinates are about 1 (see
:mod:`proximity.signs.winding`), where that needs vertices closer than ``2^-300``
of the mesh's size.
"""

import numpy as np

from ..runtime.jit import inline, kernel, part
from .fp import two_product, two_sum

#: The predicates' answer where underflow could make the exact sign wrong.
DOUBT = 2
#: Differences smaller than this (and nonzero) may underflow in the exact products.
TINY = 2.0**-300
ERR3 = 8.0e-16  # > (7 + 56 u) u = 7.77e-16
ERR2 = 3.4e-16  # > (3 + 16 u) u = 3.33e-16
# A dot product of a difference: the difference, the three products and the two sums each
# round once, so the error is at most (4 + 16 u) u = 4.44e-16 of the sum of the products'
# magnitudes.
ERR_DOT = 4.5e-16


@inline
def _sign_of(e, n):
    for i in range(n - 1, -1, -1):
        if e[i] > 0.0:
            return 1
        if e[i] < 0.0:
            return -1
    return 0


@part
def _grow(e, n, b, h):
    """Grow-Expansion: ``h[:n + 1] = e[:n] + b``; returns ``n + 1``."""
    q = b
    for i in range(n):
        q, x = two_sum(q, e[i])
        h[i] = x
    h[n] = q
    return n + 1


@part
def _scale(e, n, b, h):
    """Scale-Expansion: ``h[:2 n] = e[:n] * b``; returns ``2 n``."""
    q, x = two_product(e[0], b)
    h[0] = x
    k = 1
    for i in range(1, n):
        big, small = two_product(e[i], b)
        q, x = two_sum(q, small)
        h[k] = x
        q, x = two_sum(big, q)
        h[k + 1] = x
        k += 2
    h[k] = q
    return k + 1


@part
def _add(e, n, f, m, h):
    """Expansion-Sum: ``h[:n + m] = e[:n] + f[:m]`` (``h`` may not be ``e`` or ``f``)."""
    for i in range(n):
        h[i] = e[i]
    size = n
    scratch = np.empty(n + m)
    for j in range(m):
        size = _grow(h, size, f[j], scratch)
        for i in range(size):
            h[i] = scratch[i]
    return size


@part
def _times(e, n, f, h):
    """``h = e * f`` for a two-term ``f``: returns its length ``4 n``."""
    low = np.empty(2 * n)
    high = np.empty(2 * n)
    a = _scale(e, n, f[0], low)
    b = _scale(e, n, f[1], high)
    return _add(low, a, high, b, h)


@inline
def _diff(x, y):
    out = np.empty(2)
    s, t = two_sum(x, -y)
    out[0], out[1] = t, s
    return out


@inline
def _tiny(x):
    return x != 0.0 and abs(x) < TINY


@part
def _orient3d_exact(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    adx, ady, adz = _diff(ax, dx), _diff(ay, dy), _diff(az, dz)
    bdx, bdy, bdz = _diff(bx, dx), _diff(by, dy), _diff(bz, dz)
    cdx, cdy, cdz = _diff(cx, dx), _diff(cy, dy), _diff(cz, dz)
    total = np.empty(192)
    size = 0
    for t in range(3):
        if t == 0:
            p, q1, r1, q2, r2 = adx, bdy, cdz, bdz, cdy
        elif t == 1:
            p, q1, r1, q2, r2 = bdx, cdy, adz, cdz, ady
        else:
            p, q1, r1, q2, r2 = cdx, ady, bdz, adz, bdy
        one = np.empty(8)
        two = np.empty(8)
        n1 = _times(q1, 2, r1, one)
        n2 = _times(q2, 2, r2, two)
        for i in range(n2):
            two[i] = -two[i]
        minor = np.empty(16)
        nm = _add(one, n1, two, n2, minor)
        term = np.empty(64)
        nt = _times(minor, nm, p, term)
        merged = np.empty(size + nt)
        size = _add(total, size, term, nt, merged)
        for i in range(size):
            total[i] = merged[i]
    return _sign_of(total, size)


@part
def orient3d(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """Sign of ``(a - d) . ((b - d) x (c - d))``: -1, 0, 1, or :data:`DOUBT`."""
    adx, ady, adz = ax - dx, ay - dy, az - dz
    bdx, bdy, bdz = bx - dx, by - dy, bz - dz
    cdx, cdy, cdz = cx - dx, cy - dy, cz - dz
    p1, p2 = bdy * cdz, bdz * cdy
    q1, q2 = cdy * adz, cdz * ady
    r1, r2 = ady * bdz, adz * bdy
    det = adx * (p1 - p2) + bdx * (q1 - q2) + cdx * (r1 - r2)
    perm = abs(adx) * (abs(p1) + abs(p2)) + abs(bdx) * (abs(q1) + abs(q2)) + abs(cdx) * (abs(r1) + abs(r2))
    bound = ERR3 * perm
    if det > bound:
        return 1
    if -det > bound:
        return -1
    if (
        _tiny(adx) or _tiny(ady) or _tiny(adz) or _tiny(bdx) or _tiny(bdy) or _tiny(bdz)
        or _tiny(cdx) or _tiny(cdy) or _tiny(cdz)
    ):  # fmt: skip
        return DOUBT
    return _orient3d_exact(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz)


@part
def _orient2d_exact(ax, ay, bx, by, cx, cy):
    bax, bay = _diff(bx, ax), _diff(by, ay)
    cax, cay = _diff(cx, ax), _diff(cy, ay)
    one = np.empty(8)
    two = np.empty(8)
    n1 = _times(bax, 2, cay, one)
    n2 = _times(bay, 2, cax, two)
    for i in range(n2):
        two[i] = -two[i]
    total = np.empty(16)
    size = _add(one, n1, two, n2, total)
    return _sign_of(total, size)


@part
def orient2d(ax, ay, bx, by, cx, cy):
    """Sign of ``(b - a) x (c - a)``: -1, 0, 1, or :data:`DOUBT`."""
    bax, bay = bx - ax, by - ay
    cax, cay = cx - ax, cy - ay
    left, right = bax * cay, bay * cax
    det = left - right
    bound = ERR2 * (abs(left) + abs(right))
    if det > bound:
        return 1
    if -det > bound:
        return -1
    if _tiny(bax) or _tiny(bay) or _tiny(cax) or _tiny(cay):
        return DOUBT
    return _orient2d_exact(ax, ay, bx, by, cx, cy)


@part
def _dot_exact(px, py, pz, cx, cy, cz, nx, ny, nz):
    total = np.empty(12)
    size = 0
    for axis in range(3):
        if axis == 0:
            d, n = _diff(px, cx), nx
        elif axis == 1:
            d, n = _diff(py, cy), ny
        else:
            d, n = _diff(pz, cz), nz
        term = np.empty(4)
        nt = _scale(d, 2, n, term)
        merged = np.empty(size + nt)
        size = _add(total, size, term, nt, merged)
        for i in range(size):
            total[i] = merged[i]
    return _sign_of(total, size)


@part
def dot_sign(px, py, pz, cx, cy, cz, nx, ny, nz):
    """Sign of ``(p - c) . n``: -1, 0, 1, or :data:`DOUBT`."""
    dx, dy, dz = px - cx, py - cy, pz - cz
    a, b, c = dx * nx, dy * ny, dz * nz
    det = a + b + c
    bound = ERR_DOT * (abs(a) + abs(b) + abs(c))
    if det > bound:
        return 1
    if -det > bound:
        return -1
    if _tiny(dx) or _tiny(dy) or _tiny(dz) or _tiny(nx) or _tiny(ny) or _tiny(nz):
        return DOUBT
    return _dot_exact(px, py, pz, cx, cy, cz, nx, ny, nz)


@kernel()
def plane_sides(planar, rows, out):
    """Per row, the side of a point of a plane: ``out[i]`` the sign of ``(P - V0) . ((V1 - V0) x
    (V2 - V0))`` where ``planar[i]`` is 0 (``rows[i]`` holds ``V0, V1, V2, P``), of ``(P - C) .
    N`` where it is 1 (``C, N, P``), or :data:`DOUBT`."""
    for i in range(len(out)):
        r = rows[i]
        if planar[i] == 0:
            # orient3d(V0, V1, V2, P) is the sign of (V0 - P) . ((V1 - P) x (V2 - P)), the opposite.
            s = orient3d(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], r[10], r[11])
            out[i] = s if s == DOUBT else -s
        else:
            out[i] = dot_sign(r[6], r[7], r[8], r[0], r[1], r[2], r[3], r[4], r[5])


def orient3d_fraction(a, b, c, d):
    """The exact sign of :func:`orient3d` in rational arithmetic (for tests)."""
    from fractions import Fraction

    a, b, c, d = ([Fraction(x) for x in v] for v in (a, b, c, d))
    ad = [a[i] - d[i] for i in range(3)]
    bd = [b[i] - d[i] for i in range(3)]
    cd = [c[i] - d[i] for i in range(3)]
    det = (
        ad[0] * (bd[1] * cd[2] - bd[2] * cd[1])
        + bd[0] * (cd[1] * ad[2] - cd[2] * ad[1])
        + cd[0] * (ad[1] * bd[2] - ad[2] * bd[1])
    )
    return (det > 0) - (det < 0)


@kernel()
def _both(x):
    return orient3d(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9], x[10], x[11]) + orient2d(
        x[0], x[1], x[2], x[3], x[4], x[5]
    )


def warm():
    """Compile (or load) the predicates on their own, before a kernel that calls them is
    compiled: compiled first from inside a larger caller, they take several times as long
    (Numba 0.6x)."""
    _both(np.zeros(12))
