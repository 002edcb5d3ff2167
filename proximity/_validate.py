"""Validation at the boundary: every check happens here, never in a kernel."""

import numpy as np


def as_float64(value, name, expected):
    """``value`` as a float64 array, or a ValueError naming ``name``.

    Integers and float32 are converted; booleans, complex numbers, strings
    and ragged sequences are refused.
    """
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of shape {expected}; got {value!r} ({exc})") from None
    if array.dtype.kind not in "iuf":
        raise ValueError(
            f"{name} must be a real numeric array of shape {expected}; got dtype {array.dtype} "
            f"with shape {array.shape}"
        )
    return np.asarray(array, dtype=np.float64)


def require_finite(array, name):
    """Raise a ValueError naming the first non-finite entry of ``array``."""
    bad = ~np.isfinite(array)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name} must be finite; got {array[index]} at index {index}")


def frozen(array):
    """A read-only array that does not share memory with the caller's."""
    array = np.array(array, dtype=np.float64, copy=True)
    array.flags.writeable = False
    return array


def broadcast_batch(name_shapes, what):
    """Broadcast batch shapes, naming every argument if they do not fit."""
    try:
        return np.broadcast_shapes(*(shape for _, shape in name_shapes))
    except ValueError:
        listed = ", ".join(f"{name} {shape}" for name, shape in name_shapes)
        raise ValueError(f"{what} do not broadcast: {listed}") from None
