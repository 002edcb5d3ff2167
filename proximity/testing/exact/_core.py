"""Shared pieces of the exact reference: rationals, mpmath at `PREC` bits, errors in units."""

from __future__ import annotations

import enum
import math
import sys
from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from typing import Any

import numpy as np

try:
    import mpmath
    from mpmath import libmp
except ImportError as error:  # pragma: no cover - the test extra installs it
    raise ImportError(
        "proximity.testing.exact needs mpmath: pip install '.[test]' in proximity's clone"
    ) from error


PREC = 256
"""Binary precision, in bits, of every `mpmath.mpf` this module returns."""


EPS = Fraction(1, 2**52)
"""float64 machine epsilon, the spacing of floats just above 1."""


class Feature(enum.IntEnum):
    """The feature of a shape on which the closest point lies.

    The codes match the ones the library reports, so a reference feature can be
    compared with a computed one directly.
    """

    VERTEX0 = 0
    VERTEX1 = 1
    VERTEX2 = 2
    EDGE01 = 3
    EDGE12 = 4
    EDGE20 = 5
    FACE = 6
    RIM = 7


_EDGES = {Feature.EDGE01: (0, 1), Feature.EDGE12: (1, 2), Feature.EDGE20: (2, 0)}


# The vertices spanning each triangle feature; a closed feature contains the
# features whose support is a subset of its own.
_SUPPORT = {
    **{Feature(i): frozenset({i}) for i in range(3)},
    **{feature: frozenset(pair) for feature, pair in _EDGES.items()},
    Feature.FACE: frozenset({0, 1, 2}),
}


Vector = tuple[Fraction, ...]


def _rationals(values: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """Return `values` as an object array of exact Fractions, after checks."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(array.shape, shape, strict=True)
    ):
        expected = tuple("D" if want is None else want for want in shape)
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array.tolist()}")
    # float() of a float64 scalar is exact, and so is Fraction(float).
    flat = [Fraction(float(x)) for x in array.ravel()]
    out = np.empty(len(flat), dtype=object)
    out[:] = flat
    return out.reshape(array.shape)


def _vector(values: Any, name: str, dim: int | None = None) -> Vector:
    return tuple(_rationals(values, name, (dim,)))


def _scalar(value: Any, name: str) -> Fraction:
    return _rationals(value, name, ())[()]


def to_mpf(value: Any) -> mpmath.mpf:
    """Convert a number to an `mpmath.mpf` of `PREC` bits without float rounding.

    Parameters
    ----------
    value : Fraction, int, float or mpmath.mpf
        Number to convert. Floats and ints are exact at `PREC` bits when they
        fit (all float64 values do); other rationals are correctly rounded.

    Returns
    -------
    mpmath.mpf

    Examples
    --------
    >>> to_mpf(Fraction(1, 4)) == mpmath.mpf(0.25)
    True
    """
    if isinstance(value, mpmath.mpf):
        return value
    if isinstance(value, (float, np.floating)):
        value = Fraction(float(value))
    value = Fraction(value)
    with mpmath.workprec(PREC):
        return mpmath.mpf(libmp.from_rational(value.numerator, value.denominator, PREC, libmp.round_nearest))


def _sqrt(value: Fraction) -> mpmath.mpf:
    with mpmath.workprec(PREC):
        return mpmath.sqrt(to_mpf(value))


def _sub(a: Sequence[Fraction], b: Sequence[Fraction]) -> Vector:
    return tuple(x - y for x, y in zip(a, b, strict=True))


def _dot(a: Sequence[Fraction], b: Sequence[Fraction]) -> Fraction:
    return sum((x * y for x, y in zip(a, b, strict=True)), Fraction(0))


def _affine(origin: Vector, weights: Iterable[Fraction], directions: Iterable[Vector]) -> Vector:
    """Return ``origin + sum(w * d)`` exactly."""
    out = list(origin)
    for weight, direction in zip(weights, directions, strict=True):
        for k, x in enumerate(direction):
            out[k] += weight * x
    return tuple(out)


def _dyadic(*arrays: np.ndarray) -> tuple[list[np.ndarray], int]:
    """Write arrays of exact float values as integers times one ``2**exponent``.

    The exponent is the largest that makes every value an integer; the
    denominators of floats are powers of two, so this is exact.
    """
    shifts = [x.denominator.bit_length() - 1 for arr in arrays for x in arr.flat]
    exponent = -max(shifts, default=0)
    out = []
    for arr in arrays:
        ints = np.empty(arr.shape, dtype=object)
        for index, x in np.ndenumerate(arr):
            ints[index] = x.numerator << (-exponent - (x.denominator.bit_length() - 1))
        out.append(ints)
    return out, exponent


def _power_of_two(exponent: int) -> Fraction:
    return Fraction(2**exponent) if exponent >= 0 else Fraction(1, 2**-exponent)


def _isub(a: Sequence[int], b: Sequence[int]) -> tuple[int, ...]:
    return tuple(x - y for x, y in zip(a, b, strict=True))


def _idot(a: Sequence[int], b: Sequence[int]) -> int:
    return sum(x * y for x, y in zip(a, b, strict=True))


def _farthest(vertices: np.ndarray, point: Any) -> mpmath.mpf:
    """Largest Euclidean distance from `point` to a row of `vertices` (exact), at `PREC` bits."""
    p = _vector(point, "point", vertices.shape[1])
    return _sqrt(max(_dot(_sub(row, p), _sub(row, p)) for row in vertices))


def error_in_units(d: float, d_exact: Any, scale: Any) -> float:
    """Error of a computed value in units of ``eps * scale``.

    Parameters
    ----------
    d : float
        Computed value.
    d_exact : Fraction, int, float or mpmath.mpf
        Reference value.
    scale : Fraction, int, float or mpmath.mpf
        Magnitude the error is measured against, for example from
        `triangle_scale` or `circle_scale`.

    Returns
    -------
    float
        ``|d - d_exact| / (eps * scale)`` with ``eps = 2**-52``, evaluated at
        `PREC` bits; inf when `d` is not finite, or when the error is nonzero
        and `scale` is zero.

    Examples
    --------
    >>> error_in_units(1.0 + 2**-52, 1, 1)
    1.0
    >>> error_in_units(float("nan"), 1, 1)
    inf
    """
    if not math.isfinite(d):
        return math.inf
    with mpmath.workprec(PREC):
        error = abs(to_mpf(d) - to_mpf(d_exact))
        if error == 0:
            return 0.0
        unit = to_mpf(EPS) * abs(to_mpf(scale))
        if unit == 0:
            return math.inf
        return float(error / unit)


def ulps(d: float, d_exact: Any) -> float:
    """Error of a computed value in units in the last place of the exact value.

    Parameters
    ----------
    d : float
        Computed value.
    d_exact : Fraction, int, float or mpmath.mpf
        Reference value.

    Returns
    -------
    float
        ``|d - d_exact| / ulp(x)`` where ``x`` is the float nearest
        `d_exact` and ``ulp(x) = math.ulp(x)`` (``2**-1074`` for zero and
        subnormals, the top binade's spacing beyond the float range); inf when
        `d` is not finite.

    Examples
    --------
    >>> ulps(1.0 + 2**-52, 1)
    1.0
    >>> ulps(5e-324, 0)
    1.0
    """
    if not math.isfinite(d):
        return math.inf
    with mpmath.workprec(PREC):
        exact = to_mpf(d_exact)
        error = abs(to_mpf(d) - exact)
        if error == 0:
            return 0.0
        nearest = abs(float(exact))  # mpf -> float rounds to nearest
        unit = math.ulp(min(nearest, sys.float_info.max))
        return float(error / to_mpf(unit))


def pairwise(function: Callable[..., Any], *arrays: Any) -> list[Any]:
    """Apply a one-query reference function to each row of equally long arrays.

    Parameters
    ----------
    function : callable
        For example `triangle_distance` or `disk_closest`.
    *arrays : array_like
        Arguments of `function`, each with one extra leading axis of the same
        length n.

    Returns
    -------
    list
        ``[function(a[i], b[i], ...) for i in range(n)]``.

    Examples
    --------
    >>> from proximity.testing.exact import triangle_sqr_distance
    >>> tris = np.array([[[0, 0], [4, 0], [0, 4]]] * 2, dtype=float)
    >>> pairwise(triangle_sqr_distance, tris, [[3, 3], [-1, 0]])
    [Fraction(2, 1), Fraction(1, 1)]
    """
    return [function(*args) for args in zip(*arrays, strict=True)]
