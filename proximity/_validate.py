"""Validation at the boundary: every check happens here, never in a kernel."""

import dataclasses
import inspect
import math

import numpy as np

_REAL = frozenset("iuf")


def keyword_only_signature(func):
    """``func``, its signature shown without its ``*args``.

    The public queries take ``*args`` only to answer ``method`` passed by
    position with a message saying it is keyword-only; ``help()`` and the
    documentation show what they accept: ``(shape, points, *, method=...)``.
    """
    signature = inspect.signature(func)
    kept = [p for p in signature.parameters.values() if p.kind is not p.VAR_POSITIONAL]
    func.__signature__ = signature.replace(parameters=kept)
    return func


def as_array(value, name, expected, dtype=None):
    """``np.asarray(value, dtype)``, or a ValueError naming ``name`` where it
    cannot be converted (a ragged sequence, strings for numbers)."""
    try:
        return np.asarray(value, dtype=dtype)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be an array of shape {expected}; got {value!r} ({exc})") from None


def as_index_array(value, name, expected):
    """``value`` as an integer array, or a ValueError naming ``name``.

    Floats are taken where every one is a whole number (a face list read by
    ``np.loadtxt``, which reads floats); others are refused with the first
    that is not, and booleans and other dtypes are refused.
    """
    array = as_array(value, name, expected)
    if array.dtype.kind in "iu":
        return array
    if array.dtype.kind == "f":
        whole = np.isfinite(array) & (array == np.round(array)) & (np.abs(array) < 2.0**63)
        if whole.all():
            return array.astype(np.int64)
        index = tuple(int(i) for i in np.argwhere(~whole)[0])
        raise ValueError(
            f"{name} must be integers, an array of shape {expected}; got {array[index]} at index "
            f"{index} of a {array.dtype} array, not a whole number"
        )
    raise ValueError(f"{name} must be an integer array of shape {expected}; got dtype {array.dtype}")


def _real(value, name, expected):
    array = as_array(value, name, expected)
    if array.dtype.kind not in _REAL:
        raise ValueError(
            f"{name} must be a real numeric array of shape {expected}; got dtype {array.dtype} "
            f"with shape {array.shape}"
        )
    return array


def as_float64(value, name, expected):
    """``value`` as a float64 array, or a ValueError naming ``name``.

    Integers and float32 are converted; booleans, complex numbers, strings,
    Python integers beyond the float range and ragged sequences are refused.
    A float64 array comes back as it is, without a copy.
    """
    return np.asarray(_real(value, name, expected), dtype=np.float64)


def frozen_float64(value, name, expected, copy=True):
    """:func:`as_float64` and :func:`frozen` in one, copying the data at most once.

    A list, or an array of another dtype, is converted into a new array,
    which is then the only copy; a float64 array is passed to :func:`frozen`.
    With ``copy=False``, a C-contiguous float64 array is not copied even
    where it is writeable: the result is a read-only view of the caller's
    memory, which the caller promises not to write to.
    """
    array = _real(value, name, expected)
    if array.dtype != np.float64:
        return frozen(array.astype(np.float64, order="C"), new=True)
    if isinstance(value, (list, tuple)):
        return frozen(array, new=array.flags.c_contiguous)
    if not copy and array.flags.c_contiguous:
        view = array.view()
        view.flags.writeable = False
        return view
    return frozen(array)


def require_finite(array, name):
    """Raise a ValueError naming the first non-finite entry of ``array``.

    A finite sum means every entry is finite (NaN and inf propagate), which
    checks a large array in one pass without a temporary array of its size;
    only a sum that is not finite (a non-finite entry, or an overflow) is
    looked at entry by entry.
    """
    if array.size == 0:
        return
    with np.errstate(over="ignore", invalid="ignore"):
        if np.isfinite(np.add.reduce(array, axis=None)):
            return
    if np.isfinite(array.min()) and np.isfinite(array.max()):
        return
    index = tuple(int(i) for i in np.argwhere(~np.isfinite(array))[0])
    raise ValueError(f"{name} must be finite; got {array[index]} at index {index}")


def _read_only_throughout(array):
    while isinstance(array, np.ndarray):
        if array.flags.writeable:
            return False
        array = array.base
    return True


def frozen(array, dtype=np.float64, new=False):
    """A read-only C-contiguous array of ``dtype`` that the caller cannot change.

    It is a new array (one copy, doing any conversion at the same time),
    except for an array of ``dtype`` that is already C-contiguous and either
    ``new`` (made by the caller for this purpose) or read-only down to the
    memory it views, so that no one can write to it: that one is shared.
    """
    if (
        isinstance(array, np.ndarray)
        and array.dtype == dtype
        and array.flags.c_contiguous
        and (new or _read_only_throughout(array))
    ):
        owner = array
    else:
        owner = np.array(array, dtype=dtype, order="C", copy=True)
    owner.flags.writeable = False
    # A view: NumPy refuses to make writeable again a view whose base is
    # read-only, where it lets the owner of the memory do so.
    view = owner.view()
    view.flags.writeable = False
    return view


def broadcast_batch(name_shapes, what):
    """Broadcast batch shapes, naming every argument if they do not fit."""
    try:
        return np.broadcast_shapes(*(shape for _, shape in name_shapes))
    except ValueError:
        listed = ", ".join(f"{name} {shape}" for name, shape in name_shapes)
        raise ValueError(f"{what} do not broadcast: {listed}") from None


def freeze_result(value):
    """``value`` (an output array) read-only, down to every array it views.

    An array that owns its memory could be made writeable again, so a view
    of it stands in for it.
    """
    if value.base is None:
        value.flags.writeable = False
        value = value.view()
    value.flags.writeable = False
    base = value.base
    while isinstance(base, np.ndarray):
        base.flags.writeable = False
        base = base.base
    return value


def freeze_fields(state):
    """``state`` (an unpickled object's attributes) with every array read-only.

    Arrays come back from a pickle writeable; so do those inside a frozen
    dataclass, which is rebuilt with read-only ones.
    """
    frozen_state = {}
    for name, value in state.items():
        if isinstance(value, np.ndarray):
            value = freeze_result(value)
        elif dataclasses.is_dataclass(value) and not isinstance(value, type):
            fields = {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
            value = dataclasses.replace(value, **freeze_fields(fields))
        frozen_state[name] = value
    return frozen_state


def cutoff(max_distance):
    """``max_distance`` as a float cutoff (``inf`` for None), or an error naming it:
    a real number (or a 0-d array of one), not a bool, a string or an array of many.
    Every query with a cutoff reads it here, points' and pairs' alike."""
    if max_distance is None:
        return math.inf
    number = isinstance(max_distance, (int, float, np.integer, np.floating)) or (
        isinstance(max_distance, np.ndarray) and max_distance.ndim == 0 and max_distance.dtype.kind in "iuf"
    )
    if isinstance(max_distance, bool) or not number:
        raise TypeError(
            f"max_distance must be a number or None; got {type(max_distance).__name__} {max_distance!r}"
        )
    value = float(max_distance)
    if not value >= 0.0:  # NaN as well
        raise ValueError(f"max_distance must be >= 0 (or None); got {max_distance!r}")
    return value


def one_of(value, name, options):
    """``value``, one of the strings ``options``, or an error naming ``name``: a TypeError
    where it is not a string (an array would compare element by element), else a ValueError."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, one of {options}; got {type(value).__name__} {value!r}")
    if value not in options:
        raise ValueError(f"{name} must be one of {options}; got {value!r}")
    return value


def flag(value, name):
    """``value`` as a bool, or a TypeError naming ``name`` where it is not True or False
    (a string, None, an array: any of them would pass for one)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False; got {type(value).__name__} {value!r}")
    return bool(value)
