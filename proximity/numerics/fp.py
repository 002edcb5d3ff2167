"""Floating-point building blocks for the compiled kernels.

Error-free transformations (``two_product``, ``two_sum``) and the products
built on them let the robust kernels evaluate a cross product or a dot
product as if in twice the working precision, which is what keeps the normal
of a sliver triangle meaningful.  Power-of-two scaling keeps squared terms
away from overflow and underflow without adding any rounding.
"""

import math

from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

from ..runtime.jit import inline

EPS = 2.0**-52
# Inside this window of the largest coordinate difference, no product of up
# to four differences of that size can overflow or lose relevant bits to
# underflow.  A shape far smaller than its distance from the point has far
# smaller terms (the square of a triangle's normal, a circle's radial part),
# which its kernel guards on its own.
SAFE_MIN = 2.0**-64
SAFE_MAX = 2.0**64
TINY = 5e-324  # the smallest subnormal: a divisor that is never zero


@intrinsic
def fma(typingctx, a, b, c):
    """Fused multiply-add ``a * b + c`` with a single rounding (LLVM ``fma``)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        double = ir.DoubleType()
        fnty = ir.FunctionType(double, [double, double, double])
        fn = builder.module.declare_intrinsic("llvm.fma", [double], fnty)
        return builder.call(fn, args)

    return sig, codegen


@inline
def two_product(a, b):
    """Return ``(p, e)`` with ``p = fl(a * b)`` and ``p + e == a * b`` exactly."""
    p = a * b
    return p, fma(a, b, -p)


@inline
def two_sum(a, b):
    """Return ``(s, e)`` with ``s = fl(a + b)`` and ``s + e == a + b`` exactly."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@inline
def diff_of_products(a, b, c, d):
    """``a * b - c * d`` to within about one ulp (Kahan's algorithm).

    Exactly zero when ``a * b == c * d`` exactly, so an exactly collinear
    pair of edges gives an exactly zero cross product.
    """
    w = c * d
    e = fma(-c, d, w)
    f = fma(a, b, -w)
    return f + e


@inline
def cross_accurate(ax, ay, az, bx, by, bz):
    """Cross product with each component correct to about one ulp."""
    return (
        diff_of_products(ay, bz, az, by),
        diff_of_products(az, bx, ax, bz),
        diff_of_products(ax, by, ay, bx),
    )


@inline
def dot3_accurate(ax, ay, az, bx, by, bz):
    """Dot product of 3-vectors as if computed in twice the precision (Dot2)."""
    p, s = two_product(ax, bx)
    h, r = two_product(ay, by)
    p, q = two_sum(p, h)
    s += q + r
    h, r = two_product(az, bz)
    p, q = two_sum(p, h)
    s += q + r
    return p + s


@inline
def pow2_scale(m):
    """Power-of-two factors ``(f1, f2)`` such that ``m * f1 * f2`` lies in [0.5, 1).

    Two factors because the single factor for a subnormal ``m`` would overflow.
    Multiplying by them is exact unless the product underflows, which only
    happens to terms that are negligible next to ``m``.
    """
    e = math.frexp(m)[1]
    half = (-e) // 2
    return math.ldexp(1.0, half), math.ldexp(1.0, -e - half)


#: The scale of a computation done in the frame it was given in.
UNSCALED = (1.0, 1.0, 1.0)


@inline
def unscale(x, g):
    """``x`` times the power of two ``g = (product, first, second)``.

    A computation done on inputs multiplied by ``1 / product`` is undone by
    this.  Where the product is past the float range (a distance from
    2^1023 on is scaled down by 2^-1024), the two factors it was made of are
    applied in turn, so a result that is finite comes out finite; elsewhere
    both give the same bits.
    """
    return x * g[0] if g[0] != math.inf else x * g[1] * g[2]


@inline
def edge_function(nx, ny, nz, vx, vy, vz, ex, ey, ez):
    # n . (v x e): twice the signed area of (projection of P, v, v + e), times |n|.
    return nx * (vy * ez - vz * ey) + ny * (vz * ex - vx * ez) + nz * (vx * ey - vy * ex)


@inline
def ulp(x):
    """The spacing of the floats at ``|x|``, toward larger magnitudes
    (``np.spacing``): ``2^(e - 53)`` for ``|x|`` in ``[2^(e-1), 2^e)``,
    ``2^-1074`` for subnormals and zero."""
    if x == 0.0:
        return 5e-324
    e = math.frexp(abs(x))[1]
    return math.ldexp(1.0, max(e - 53, -1074))


@inline
def faithful_difference(d, r):
    """``(ok, e)``: ``e = d - r`` rounded, and whether ``e`` is faithful for
    ``d* - r`` whatever ``d*`` within ``ulp(d)`` of ``d`` (``d*`` equal to
    ``d`` where ``d`` is 0), as a faithfully rounded distance ``d`` allows.

    The subtraction's error is exact (Knuth's TwoSum); ``e`` is faithful
    where it and the uncertainty of ``d`` stay within half the spacing at
    ``e``, the nearer neighbour's distance at most.
    """
    e = d - r
    back = e - d
    err = (d - (e - back)) + (-r - back)
    u = 0.0 if d == 0.0 else ulp(d)
    gap = 5e-324 if e == 0.0 else 0.5 * ulp(e)
    return (abs(err) + u) * (1.0 + 2.0**-50) < gap, e
