"""The adapters' vocabulary: failure codes, model descriptions, results, and small numeric helpers.

What :mod:`._pairs` (pair queries) and :mod:`._base` (the backends' point queries and their
translation) both use, so that neither imports the other's module for it.
"""

import contextlib
import ctypes
import enum
import functools
import importlib
import importlib.metadata
import os
import sys
from dataclasses import dataclass, fields

import numpy as np

EPS = float(np.finfo(np.float64).eps)

#: Default modelling tolerance of tessellated shapes, relative to the radius.
DEFAULT_RELATIVE_TOL = 1e-3

#: Most segments a circle or disk may be cut into; a tolerance that needs more
#: is refused rather than silently loosened.
MAX_SEGMENTS = 1 << 16

INSTALL_HINT = "pip install '.[adapters]' in proximity's clone"

#: Where a library is given the caller's coordinates.
CALLER = "caller's coordinates"
#: Where a library is given the shapes of a pair in the caller's coordinates (each at its pose).
WORLD = "the world"
#: Where a library is given a pair in the frame of :func:`~proximity.adapters._pairs.scaled`.
PAIR_FRAME = "per call: origin at the center of both shapes' boxes, scaled by a power of two"


class Failure(enum.IntEnum):
    """Why a backend row has no answer.

    Failure arrays hold these codes as ``int8``.  Every row whose code is not
    ``OK`` has NaN in all float fields of the result and ``Feature.NONE``,
    but for ``CONTACT`` rows of a pair query, whose distance is 0.

    Examples
    --------
    fcl answers -1 for a point in a disk's plane inside the disk; that
    sentinel becomes NaN with the code ``SENTINEL``:

    >>> import proximity, proximity.adapters as adapters
    >>> disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> with adapters.get("fcl") as backend:
    ...     r = backend.closest_point(disk, [[0.5, 0, 0], [0.5, 0, 1]])
    >>> [adapters.Failure(f).name for f in r.failure], r.distance.tolist()
    (['SENTINEL', 'OK'], [nan, 1.0])
    """

    #: The library answered, and the answer is consistent with the geometry.
    OK = 0
    #: The query point contains NaN or inf; the library was not asked.
    NAN_INPUT = 1
    #: The library returned nothing (pybullet's empty list for degenerate triangles).
    NO_RESULT = 2
    #: The library returned a value that is not a distance: fcl's sentinel -1
    #: in contact, 1.797e308 for an unsupported pair, or any distance below
    #: minus the row's tolerance (none of these shapes has an inside).
    SENTINEL = 3
    #: The library reported contact (a distance within the row's tolerance
    #: of 0) where proximity puts the shape more than twice the tolerance away.
    FALSE_TOUCHING = 4
    #: The returned nearest point is farther from the shape than the tolerance.
    POINT_OFF_SHAPE = 5
    #: The returned nearest point is not at the returned distance from the
    #: query point (to within the tolerance).
    INCONSISTENT = 6
    #: The library raised an error while building the model or answering.
    EXCEPTION = 7
    #: Pair queries: the library reported the shapes in contact (a distance
    #: within the tolerance of 0, or negative), as proximity finds them, but
    #: its witness points are not a common point of both shapes (fcl's -1 or
    #: 0 with stale points, trimesh's and pybullet's negative values).  The
    #: distance is 0; the witness points are NaN.
    CONTACT = 8
    #: Pair queries: the library was given a mesh's convex hull (pybullet's
    #: model of a mesh on a body that can move) and its answer is the hull's:
    #: a witness point off the mesh, or contact where the shapes are apart.
    CONVEX_HULL = 9


@dataclass(frozen=True)
class Model:
    """What a backend built to answer a query.

    Attributes
    ----------
    library : str
        Distribution and version, e.g. ``"python-fcl 0.7.0.11"``.
    primitive : str
        The native model of one shape, e.g. ``"Cylinder(R, 0)"``.
    probe : str
        How the query point was given to the library; for a pair query,
        how the pair was asked.
    segments : ndarray of int64, shape ``batch``
        Number of segments ``K`` of each tessellated shape; 0 where the
        library was given an exact primitive (always, for a pair query,
        whose arrays have the broadcast shape of the pair).
    bound : ndarray of float64, shape ``batch``
        Hausdorff distance between each shape and its model: the sagitta
        ``R (1 - cos(pi / K))`` of a tessellated circle or disk, 0 otherwise.
        It bounds the modelling part of every distance error.
    margin : float
        Collision margin in effect, in the caller's length unit, as read back
        from the library; NaN for libraries without margins.
    rtol : float
        Relative accuracy the backend documents for the library's arithmetic.
    frame : str
        Coordinates the library worked in.

    Examples
    --------
    >>> import proximity, proximity.adapters as adapters
    >>> disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> with adapters.get("fcl") as backend:
    ...     model = backend.closest_point(disk, [0, 0, 1]).model
    >>> model.describe(), int(model.segments), float(model.bound)
    ('Cylinder(R, 0)', 0, 0.0)
    """

    library: str
    primitive: str
    probe: str
    segments: np.ndarray
    bound: np.ndarray
    margin: float
    rtol: float
    frame: str

    def __post_init__(self):
        for name in ("segments", "bound"):
            value = getattr(self, name)
            value.flags.writeable = False

    def describe(self):
        """One line: primitive, segments, margin and bound."""
        parts = [self.primitive]
        if self.segments.size and self.segments.max() > 0:
            low, high = int(self.segments.min()), int(self.segments.max())
            parts.append(f"K={low}" if low == high else f"K={low}..{high}")
            parts.append(f"bound<={float(self.bound.max()):.2g}")
        if not np.isnan(self.margin):
            parts.append(f"margin={self.margin:g}")
        return ", ".join(parts)


@dataclass(frozen=True)
class BackendResult:
    """A backend's answer, in proximity's result type, with the translation record.

    The fields of :attr:`result` can be read directly from this object
    (``r.distance`` is ``r.result.distance``).

    Attributes
    ----------
    result : TriangleResult, DiskResult, CircleResult, MeshResult or PairResult
        The same type proximity returns, of the broadcast shape.  Rows whose
        failure is not ``OK`` are NaN; fields listed in :attr:`unknown` are
        not given by the library: ``Feature.NONE`` for ``feature``, NaN for
        float parameters and False for ``equidistant``.
    failure : ndarray of int8, shape ``batch``
        :class:`Failure` code of each row.
    tolerance : ndarray of float64, shape ``batch``
        The error the backend documents for each row (see the module
        docstring); NaN where the point is not finite.
    model : Model
        What was built.
    unknown : tuple of str
        Fields of :attr:`result` the library cannot give.
    backend : str
        Name of the backend that answered.

    Examples
    --------
    >>> import numpy as np, proximity, proximity.adapters as adapters
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> with adapters.get("trimesh") as backend:
    ...     r = backend.closest_point(tri, [[0.2, 0.2, 1.0], [np.nan, 0, 0]])
    >>> r.distance.tolist(), r.ok.tolist(), [adapters.Failure(f).name for f in r.failure]
    ([1.0, nan], [True, False], ['OK', 'NAN_INPUT'])
    >>> r.backend, r.unknown      # trimesh gives no feature or barycentrics
    ('trimesh', ('feature', 'barycentric'))
    """

    result: object
    failure: np.ndarray
    tolerance: np.ndarray
    model: Model
    unknown: tuple
    backend: str

    def __post_init__(self):
        for name in ("failure", "tolerance"):
            value = getattr(self, name)
            if isinstance(value, np.ndarray):
                if value.ndim == 0:
                    value = value[()]
                else:
                    value.flags.writeable = False
            if name == "failure" and not isinstance(value, np.ndarray):
                value = Failure(int(value))
            object.__setattr__(self, name, value)

    def __getattr__(self, name):
        # Only the result's own fields are forwarded, so that typos and
        # protocol probes (copy, pickle) still raise AttributeError.
        result = self.__dict__.get("result")
        if result is not None and name in {f.name for f in fields(result)}:
            return getattr(result, name)
        raise AttributeError(f"{type(self).__name__!s} has no attribute {name!r}")

    @property
    def ok(self):
        """Boolean array: True where the library's answer was kept."""
        return np.asarray(self.failure) == Failure.OK


@contextlib.contextmanager
def _quiet_output():
    """Send what C code prints (file descriptors 1 and 2) to /dev/null."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
        yield
    finally:
        ctypes.CDLL(None).fflush(None)  # C's buffered output goes to /dev/null too
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)


def import_library(module, distribution, *, quiet=False):
    """Import ``module`` or raise an ImportError that names the extra to install.

    ``quiet`` silences what the library prints while it loads (pybullet's
    build banner).
    """
    try:
        if quiet and module not in sys.modules and os.name == "posix":
            with _quiet_output():
                return importlib.import_module(module)
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(
            f"{distribution} is not installed (module {module!r} cannot be imported): {INSTALL_HINT}",
            name=module,
        ) from exc


@functools.cache
def library_version(distribution):
    """``"name version"`` of an installed distribution."""
    try:
        return f"{distribution} {importlib.metadata.version(distribution)}"
    except importlib.metadata.PackageNotFoundError:
        return distribution


def best_method(shape):
    """The most accurate method ``shape`` offers: ``certified``, else ``robust``."""
    for method in ("certified", "robust"):
        if method in shape.methods:
            return method
    raise ValueError(f"{shape!r} offers neither 'certified' nor 'robust' methods: {shape.methods}")


def sagitta(radius, segments):
    """``R (1 - cos(pi / K))``, written as ``2 R sin^2(pi / 2K)`` to avoid cancellation."""
    s = np.sin(np.pi / (2.0 * np.asarray(segments, dtype=np.float64)))
    return 2.0 * np.asarray(radius, dtype=np.float64) * s * s


def segments_for(radius, tol=None):
    """Fewest segments ``K >= 3`` whose sagitta ``R (1 - cos(pi/K))`` is at most ``tol``.

    Parameters
    ----------
    radius : array_like
        Radii, >= 0.
    tol : float, optional
        Largest Hausdorff distance allowed between a circle (or disk) and the
        inscribed polygon, in the caller's length unit.  Default
        ``1e-3 * radius``, per shape.

    Returns
    -------
    ndarray of int64
        ``K`` for each radius.

    Examples
    --------
    >>> segments_for([1.0, 2.0]).tolist()
    [71, 71]
    >>> segments_for([1.0, 2.0], tol=1e-3).tolist()
    [71, 100]
    """
    radius = np.asarray(radius, dtype=np.float64)
    if tol is None:
        limit = DEFAULT_RELATIVE_TOL * radius
    else:
        tol = float(tol)
        if not (tol > 0 and np.isfinite(tol)):
            raise ValueError(f"tol must be a positive finite length; got {tol!r}")
        limit = np.broadcast_to(tol, radius.shape)
    positive = radius > 0
    ratio = np.where(positive, limit / np.where(positive, 2.0 * radius, 1.0), 1.0)
    # R (1 - cos(pi/K)) = 2 R sin^2(pi/2K) <= tol  <=>  K >= pi / (2 asin(sqrt(tol / 2R))).
    with np.errstate(divide="ignore"):
        guess = np.ceil(np.pi / (2.0 * np.arcsin(np.sqrt(np.minimum(ratio, 1.0)))))
    k = np.where(positive, np.maximum(guess, 3), 3)
    if (k > MAX_SEGMENTS).any():
        i = int(np.argmax(k))
        raise ValueError(
            f"tol={float(np.ravel(limit)[i])!r} needs more than {MAX_SEGMENTS} segments for radius "
            f"{float(np.ravel(radius)[i])!r}; pass a larger tol"
        )
    k = k.astype(np.int64)
    # The closed form is exact up to rounding of arcsin; settle the last step
    # on the bound itself, so that K is the smallest that meets it.
    while True:
        too_few = positive & (sagitta(radius, k) > limit)
        if not too_few.any():
            break
        k = k + too_few
    while True:
        fewer = positive & (k > 3) & (sagitta(radius, np.maximum(k - 1, 3)) <= limit)
        if not fewer.any():
            break
        k = k - fewer
    return k


def plane_frame(unit_normal):
    """Unit vectors ``u, v`` with ``(u, v, n)`` a right-handed orthonormal frame, per row."""
    n = np.asarray(unit_normal, dtype=np.float64)
    # Cross with the axis least aligned with n, so the cross product never cancels.
    axis = np.zeros_like(n)
    axis[np.arange(len(n)), np.argmin(np.abs(n), axis=1)] = 1.0
    u = np.cross(n, axis)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(n, u)
    return u, v


def polygon(center, u, v, radius, k):
    """The ``k + 1`` vertices (first repeated last) of the polygon inscribed in a circle."""
    theta = 2.0 * np.pi * np.arange(k + 1) / k
    pts = center + radius * (np.cos(theta)[:, None] * u + np.sin(theta)[:, None] * v)
    pts[-1] = pts[0]
    return pts


def unit(vectors):
    """Rows of ``vectors`` normalised, scaled first by a power of two against overflow."""
    vectors = np.asarray(vectors, dtype=np.float64)
    _, e = np.frexp(np.max(np.abs(vectors), axis=-1, keepdims=True))
    scaled = np.ldexp(vectors, -e)
    return scaled / np.linalg.norm(scaled, axis=-1, keepdims=True)


def norm(vectors):
    """Euclidean norms of the rows of ``vectors`` (last axis), without over- or underflow.

    Each row is scaled by a power of two (exact) before squaring, so that
    coordinates from 1e-300 to 1e300 are measured as accurately as unit ones.
    """
    vectors = np.asarray(vectors, dtype=np.float64)
    biggest = np.max(np.abs(vectors), axis=-1, keepdims=True, initial=0.0)
    with np.errstate(invalid="ignore"):
        factor = pow2_scale(np.where(np.isfinite(biggest), biggest, 0.0))
        return np.linalg.norm(vectors * factor, axis=-1) / factor[..., 0]


def pow2_scale(size):
    """A power of two ``f`` with ``size * f`` in ``[0.5, 1)``; 1 where ``size`` is 0."""
    size = np.asarray(size, dtype=np.float64)
    _, e = np.frexp(np.where(size > 0, size, 1.0))
    return np.where(size > 0, np.ldexp(1.0, -e), 1.0)
