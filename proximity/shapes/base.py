"""Shapes: thin frozen facades that validate once and call the kernels.

Every shape is a batch: its data have leading *batch* dimensions, and a query
broadcasts the points' leading dimensions against them like a NumPy ufunc.
The kernels are imported on first use, so that ``import proximity`` does not
pay for loading the compiler.
"""

from __future__ import annotations

import types
from typing import Protocol, runtime_checkable

import numpy as np

from .._typing import ArrayLike, Distances, Floats, Transform
from .._validate import (
    as_float64,
    broadcast_batch,
    cutoff,
    freeze_fields,
    frozen,
    frozen_float64,
    require_finite,
)
from ..features import EDGE01, EDGE20, VERTEX0, VERTEX2
from ..methods import DEFAULT, REGISTRY, resolve
from ..primitives import CIRCLE, DISK, N_PARAMS, POINT, SEGMENT, TRIANGLE
from ..results import (
    CircleResult,
    DiskResult,
    PointResult,
    Result,
    SegmentResult,
    TriangleResult,
    attach,
    beyond,
    circle_from_row,
    disk_from_row,
    format_repr,
    point_from_row,
    segment_from_row,
    triangle_from_row,
)
from ..runtime import counts, lazy, pool, threads

DEFAULT_METHOD = DEFAULT

#: The views every shape makes of itself, by name: ``"posed"`` (:class:`.posed.Posed`, made by
#: :meth:`Frozen.transformed`) and ``"rounded"`` (:class:`.rounded.Inflated`, made by
#: ``inflated``).  Their modules build on this one and enter their classes here when they are
#: imported (``proximity.shapes`` imports both), so that this module need not import them.
VIEWS = {}
_FLOAT64 = np.dtype(np.float64)
_POINT = (3,)
_REAL = frozenset("iuf")
_empty = np.empty


@runtime_checkable
class Shape(Protocol):
    """What every queryable shape provides.

    Attributes
    ----------
    batch_shape : tuple of int
        Leading dimensions of the shape's data; a single shape has ``()``.
    dim : int
        Dimension ``D`` of the space the shape lives in.
    methods : tuple of str
        The values ``method`` accepts.

    Examples
    --------
    Every shape of the package is a ``Shape``; so is any object with these
    attributes and methods:

    >>> import numpy as np, proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> isinstance(tri, proximity.Shape), tri.batch_shape, tri.dim
    (True, (), 3)
    >>> proximity.Triangle(np.zeros((4, 3, 3))).batch_shape
    (4,)
    >>> "robust" in tri.methods
    True
    """

    batch_shape: tuple
    dim: int
    methods: tuple

    def closest_point(self, points: ArrayLike, *, method: str = DEFAULT_METHOD) -> Result:
        """Closest point on the shape to each point; see :func:`proximity.closest_point`."""

    def distance(self, points: ArrayLike, *, method: str = DEFAULT_METHOD) -> Distances:
        """Distance from each point to the shape; see :func:`proximity.distance`."""


def check_method(method, methods):
    """The :class:`~proximity.methods.Method` named ``method``, which must be one of ``methods``."""
    resolved = resolve(method)
    if resolved.name not in methods:
        raise ValueError(f"method must be one of {methods}; got {method!r}")
    return resolved


def keyword_only(shape, function, args):
    """The TypeError for ``method`` (or more) passed by position."""
    name = f"{type(shape).__name__}.{function}"
    return TypeError(
        f"{name}() takes one positional argument, points; method is keyword-only: "
        f"{function}(points, method={args[0]!r})"
    )


class Frozen:
    """Immutability, pickling, per-class names and posing, shared by every shape.

    Each concrete class gets its own copies of the public methods it
    inherits, named after it, so that Python's own argument errors name the
    class the caller used.
    """

    __slots__ = ()
    _public = ("__init__", "distance", "closest_point")

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__name__.startswith("_"):
            return
        for name in cls._public:
            function = getattr(cls, name, None)
            if name in cls.__dict__ or not isinstance(function, types.FunctionType):
                continue
            copy = types.FunctionType(
                function.__code__, function.__globals__, name, function.__defaults__, function.__closure__
            )
            copy.__kwdefaults__ = function.__kwdefaults__
            copy.__annotations__ = dict(function.__annotations__)
            copy.__doc__ = function.__doc__
            copy.__qualname__ = f"{cls.__name__}.{name}"
            copy.__module__ = cls.__module__
            setattr(cls, name, copy)

    def transformed(self, transform: Transform) -> Shape:
        """The shape moved by the rigid ``transform`` (4x4), as a view that
        shares its data: :class:`proximity.Posed`, in O(1).

        Examples
        --------
        >>> import numpy as np, proximity
        >>> T = np.eye(4); T[:3, 3] = [10, 0, 0]
        >>> float(proximity.Sphere([0, 0, 0], 1.0).transformed(T).distance([13, 0, 0]))
        2.0
        """
        return VIEWS["posed"](self, transform)

    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __delattr__(self, name):
        raise AttributeError(f"{type(self).__name__} is immutable")

    def _init(self, **fields):
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    def _slots(self):
        for cls in type(self).__mro__:
            yield from cls.__dict__.get("__slots__", ())

    # Attributes computed from the others (by ``_derive``), left out of pickles.
    _derived = ()

    def __getstate__(self):
        return {name: getattr(self, name) for name in self._slots() if name not in self._derived}

    def __setstate__(self, state):
        # Arrays come back from a pickle writeable: make them read-only again.
        self._init(**freeze_fields(state))
        if self._derived:
            self._init(**self._derive())

    def __copy__(self):
        return self  # immutable

    def __deepcopy__(self, memo):
        return self  # immutable, and nothing it holds is shared writeably


class _Facade(Frozen):
    """Shared query plumbing: points, method and output shape.

    Subclasses set ``_primitive``, their kind of primitive
    (:mod:`proximity.primitives`), whose kernel module answers the queries.
    """

    __slots__ = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        # ``methods``: the values ``method`` accepts, the primitive's;
        # ``result_type``: the class of ``closest_point``'s results.
        if "_primitive" in cls.__dict__:
            cls.methods = cls._primitive.methods
        if "_result" in cls.__dict__:
            cls.result_type = cls._result

    def _kernels(self):
        return self._primitive.kernels

    def __getitem__(self, index):
        """The shapes at ``index`` of the batch: a shape of the same kind.

        Examples
        --------
        >>> import proximity
        >>> disks = proximity.Disk([[0, 0, 0], [0, 0, 5]], [0, 0, 1], [1.0, 2.0])
        >>> disks[1]
        Disk(center=array([0., 0., 5.]), normal=array([0., 0., 1.]), radius=array(2.))
        """
        if self.batch_shape == ():
            raise IndexError(f"a single {type(self).__name__} has no batch to index")
        args = []
        for name, core in self._fields:
            array = getattr(self, name)
            args.append(np.broadcast_to(array, self.batch_shape + array.shape[array.ndim - core :])[index])
        return type(self)(*args)

    def inflated(self, radius: float) -> Shape:
        """The points within ``radius`` of the shape: a rounded solid
        (:class:`proximity.Inflated`), ``radius`` broadcasting with the batch.

        Examples
        --------
        >>> import proximity
        >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> slab = tri.inflated(0.25)
        >>> slab.distance([[0.2, 0.2, 1.0], [0.2, 0.2, 0.1]]).tolist()
        [0.75, 0.0]
        """
        return VIEWS["rounded"](self, radius)

    def _prepare(self, points, method):
        method = check_method(method, self.methods)
        expected = f"(..., {self.dim})"
        points = as_float64(points, "points", expected)
        if points.ndim == 0 or points.shape[-1] != self.dim:
            raise ValueError(f"points must have shape {expected}; got shape {points.shape}")
        out_shape = broadcast_batch(
            [("points", points.shape[:-1]), (type(self).__name__.lower(), self.batch_shape)],
            "the batch dimensions of points and shape",
        )
        return method, points, out_shape

    def _single(self, points, method):
        """The fast path: a row of nine values for one 3D point against a
        single shape, or None when the query is not that.

        A drop-in narrow phase calls the query once per pair from Python, so
        this path hands plain arrays straight to the one-query kernel and
        skips validation of the shape (done at construction), broadcasting
        and the batch kernel's thread launch.
        """
        if self._args is None or type(method) is not str or method not in self.methods:
            return None
        if type(points) is not np.ndarray or points.dtype is not _FLOAT64:
            # What the batch path accepts (see as_float64), and nothing else:
            # for the rest, the batch path explains what is wrong.
            try:
                points = np.asarray(points)
            except (TypeError, ValueError, OverflowError):
                return None
            if points.dtype.kind not in _REAL:
                return None
            points = points.astype(_FLOAT64, copy=False)
        if points.shape != (3,):
            return None
        entry = self._entries.get(method)
        if entry is None:
            entry = self._entries[method] = self._compile_single(REGISTRY[method])
        kernel, exact_fallback = entry
        row = np.empty(10)
        kernel(row, self._args, points)
        if exact_fallback:
            self._certified_row(row, points)
        row.setflags(write=False)
        return row

    def _compile_single(self, method):
        """The one-query kernel of ``method``, as an entry point that skips Numba's dispatch."""
        # Loads the compiler, as the kernels do.
        single_entry = lazy.load("proximity.runtime.loops").single_entry
        return single_entry(self._kernels().single_kernel(method)), method.exact_fallback

    def _certified_row(self, row, point):
        """Count a certified fast-path query, and finish it exactly if its
        filter left it undecided."""
        undecided = bool(row[9])
        if undecided:
            self._kernels().exact_row(row, self._args, point)
        counts.count(1, int(undecided))

    def distance(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Distances:
        """Distance from each point to the shape; see :func:`proximity.distance`."""
        if args:
            raise keyword_only(self, "distance", args)
        if max_distance is not None:
            return beyond(self.distance(points, method=method), cutoff(max_distance))
        row = self._single(points, method)
        if row is not None:
            return row[0]
        out_shape, out = self._query(points, method, full=False)
        return out["distance"].reshape(out_shape)[()]

    def closest_point(
        self,
        points: ArrayLike,
        *args: object,
        method: str = DEFAULT_METHOD,
        max_distance: float | None = None,
    ) -> Result:
        """Closest point on the shape to each point; see :func:`proximity.closest_point`."""
        if args:
            raise keyword_only(self, "closest_point", args)
        if max_distance is not None:
            return beyond(self.closest_point(points, method=method), cutoff(max_distance))
        # One float64 point against a single shape is the drop-in narrow-phase
        # call, made once per pair from Python; it is :meth:`_single` written
        # out, because at a few microseconds a call every lookup counts.
        if type(points) is np.ndarray and points.shape == _POINT and points.dtype is _FLOAT64:
            args = self._args
            entry = self._entries.get(method) if type(method) is str else None
            if args is not None and entry is not None:
                kernel, exact_fallback = entry
                row = _empty(10)
                kernel(row, args, points)
                if exact_fallback:
                    self._certified_row(row, points)
                row.setflags(False)  # write=False, passed positionally: the faster call
                result = self._from_row(row)
                result.__dict__["_query"] = (points, None, self)  # for its normal (results.attach)
                return result
        row = self._single(points, method)
        if row is not None:
            return attach(self._from_row(row), points, None, self)
        out_shape, out = self._query(points, method, full=True)
        fields = {}
        for name, value in out.items():
            value = value.reshape(out_shape + value.shape[1:])
            if name == "point":
                value = value[..., : self.dim]
            fields[name] = value
        count = int(np.prod(self.batch_shape, dtype=int))
        members = np.arange(count).reshape(self.batch_shape) if self.batch_shape else None
        return attach(self._result(**fields), as_float64(points, "points", ""), members, self)

    def _elements(self, result, members):
        """The batch member each row of ``result`` asked (``members``; 0 where the shape is one)."""
        return np.zeros((), np.int64) if members is None else members

    def _feature_rows(self, index):
        """``(kinds, params)`` of batch members ``index``, as a collection stores them."""
        kinds, params = self._rows()
        return kinds[index], params[index]

    def _feature_normals(self, index, feature, points):
        """The normals of batch members ``index`` at closest points on their
        ``feature`` to ``points`` (``(n, 3)``): see :attr:`Result.normal`."""
        kinds, params = self._feature_rows(index)
        if self.dim == 2:
            return _normals_2d(getattr(self, "_corners", 0), params, feature)
        from ..numerics.normals import feature_normals

        return feature_normals(kinds, params, feature, points)


class _Hull(_Facade):
    """Shapes that are the convex hull of a few vertices: triangles, segments, points.

    Subclasses set the primitive, the number of vertices (``_corners``) and
    the result type.
    """

    __slots__ = ("vertices", "batch_shape", "dim", "_vertices3", "_args")
    _derived = ("_vertices3", "_args")
    _corners = 3
    _fields = (("vertices", 2),)  # the constructor's arrays, and their core dimensions

    def __init__(self, vertices: ArrayLike, *, copy: bool = False) -> None:
        n = self._corners
        expected = f"(..., {n}, D) with D = 2 or 3"
        v = frozen_float64(vertices, "vertices", expected, copy)
        if v.ndim < 2 or v.shape[-2] != n or v.shape[-1] not in (2, 3):
            raise ValueError(f"vertices must have shape {expected}; got shape {v.shape}")
        require_finite(v, "vertices")
        self._init(vertices=v, batch_shape=v.shape[:-2], dim=v.shape[-1])
        self._init(**self._derive())

    def _derive(self):
        v = self.vertices
        v3 = v if v.shape[-1] == 3 else frozen(_to_3d(v), new=True)
        return {"_vertices3": v3, "_args": v3.ravel() if v.shape == (self._corners, 3) else None}

    def __repr__(self):
        return format_repr(self, ("vertices",))

    def _query(self, points, method, full):
        method, points, out_shape = self._prepare(points, method)
        with threads.kernel():
            return out_shape, self._kernels().query(method, self._vertices3, _to_3d(points), out_shape, full)

    def _rows(self):
        """``(kinds, params)`` of the batch, in C order, as a collection stores them."""
        return _rows(self._primitive, self._vertices3.reshape(-1, 3 * self._corners))


class Triangle(_Hull):
    """A batch of triangles in 2D or 3D.

    Parameters
    ----------
    vertices : array_like, shape ``batch + (3, D)``
        The vertices ``V0, V1, V2`` of each triangle, finite, with D = 2 or 3.
        Degenerate triangles (collinear or coincident vertices) are valid:
        the ``robust`` method answers for the segment or point they are.
    copy : bool, keyword-only, default False
        A C-contiguous float64 array is used as it is, without a copy (the
        triangle holds a read-only view of it), so do not write to it while
        the triangle is in use; ``copy=True`` gives the triangle its own
        copy.  Other input is converted into a new array in any case.

    Examples
    --------
    >>> import proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> r = tri.closest_point([0.25, 0.25, 2.0])
    >>> float(r.distance), str(r.feature_name), r.point.tolist()
    (2.0, 'FACE', [0.25, 0.25, 0.0])
    >>> tri
    Triangle(vertices=array([[0., 0., 0.],
                             [1., 0., 0.],
                             [0., 1., 0.]]))
    >>> tri.distance([[2, 0, 0], [-1, -1, 0]]).round(6).tolist()
    [1.0, 1.414214]
    """

    __slots__ = ()
    _primitive = TRIANGLE
    _result = TriangleResult
    _from_row = staticmethod(triangle_from_row)
    _entries = {}  # method name -> (one-query entry point, exact fallback), compiled on first use


class Segment(_Hull):
    """A batch of line segments in 2D or 3D.

    Parameters
    ----------
    vertices : array_like, shape ``batch + (2, D)``
        The endpoints ``V0, V1`` of each segment, finite, with D = 2 or 3.
        A segment whose endpoints coincide is the point it is.
    copy : bool, keyword-only, default False
        As for :class:`Triangle`.

    Notes
    -----
    The closest point is ``V0 + t (V1 - V0)`` with ``t`` the result's
    ``parameter``, on feature ``VERTEX0`` (``t = 0``), ``VERTEX1``
    (``t = 1``) or ``EDGE01``.  Methods: ``robust`` (within ``8 eps S +
    2^-1075`` of the exact distance, ``S = max(|P - V0|, |P - V1|)``) and
    ``certified`` (faithfully rounded, with the exact feature); Eberly's
    two documents have no segment algorithm, so there is no ``eberly``.

    Examples
    --------
    >>> import proximity
    >>> rod = proximity.Segment([[0, 0, 0], [2, 0, 0]])
    >>> r = rod.closest_point([[0.5, 1, 0], [3, 0, 0], [-1, 0, 0]])
    >>> r.distance.tolist(), r.feature_name.tolist(), r.parameter.tolist()
    ([1.0, 1.0, 1.0], ['EDGE01', 'VERTEX1', 'VERTEX0'], [0.25, 1.0, 0.0])
    >>> rod.methods
    ('robust', 'certified')
    """

    __slots__ = ()
    _primitive = SEGMENT
    _corners = 2
    _result = SegmentResult
    _from_row = staticmethod(segment_from_row)
    _entries = {}


class Point(_Hull):
    """A batch of points in 2D or 3D: the core of a :class:`~proximity.Sphere`.

    Parameters
    ----------
    position : array_like, shape ``batch + (D,)``
        Finite coordinates, D = 2 or 3.
    copy : bool, keyword-only, default False
        As for :class:`Triangle`.

    Examples
    --------
    >>> import proximity
    >>> p = proximity.Point([[0, 0, 0], [3, 0, 0]])
    >>> p.distance([0, 4, 0]).tolist()
    [4.0, 5.0]
    """

    __slots__ = ()
    _primitive = POINT
    _corners = 1
    _fields = (("position", 1),)
    _result = PointResult
    _from_row = staticmethod(point_from_row)
    _entries = {}

    def __init__(self, position: ArrayLike, *, copy: bool = False) -> None:
        expected = "(..., D) with D = 2 or 3"
        p = frozen_float64(position, "position", expected, copy)
        if p.ndim < 1 or p.shape[-1] not in (2, 3):
            raise ValueError(f"position must have shape {expected}; got shape {p.shape}")
        require_finite(p, "position")
        self._init(vertices=p[..., None, :], batch_shape=p.shape[:-1], dim=p.shape[-1])
        self._init(**self._derive())

    @property
    def position(self) -> Floats:
        """The points, ``batch + (D,)``, read-only."""
        return self.vertices[..., 0, :]

    def __repr__(self):
        return format_repr(self, ("position",))


class _Round(_Facade):
    __slots__ = ("center", "normal", "radius", "batch_shape", "_unit_normal", "_args")
    _derived = ("_args",)
    _fields = (("center", 1), ("normal", 1), ("radius", 0))
    dim = 3
    _is_disk = False

    _entries = {}  # method name -> (one-query entry point, exact fallback), compiled on first use

    def __init__(
        self, center: ArrayLike, normal: ArrayLike, radius: ArrayLike, *, copy: bool = False
    ) -> None:
        c = frozen_float64(center, "center", "(..., 3)", copy)
        n = frozen_float64(normal, "normal", "(..., 3)", copy)
        r = frozen_float64(radius, "radius", "(...)", copy)
        for name, a in (("center", c), ("normal", n)):
            if a.ndim == 0 or a.shape[-1] != 3:
                raise ValueError(f"{name} must have shape (..., 3); got shape {a.shape}")
        unit = _unit_normals(c, n, r)
        batch = broadcast_batch(
            [("center", c.shape[:-1]), ("normal", n.shape[:-1]), ("radius", r.shape)],
            "the batch dimensions of center, normal and radius",
        )
        self._init(center=c, normal=n, radius=r, batch_shape=batch, _unit_normal=frozen(unit, new=True))
        self._init(**self._derive())

    def _derive(self):
        args = None
        if self.batch_shape == ():
            c, u, n, r = self.center, self._unit_normal, self.normal, self.radius
            args = frozen(np.concatenate([[float(self._is_disk)], c, u, n, [r]]), new=True)
        return {"_args": args}

    def __repr__(self):
        return format_repr(self, ("center", "normal", "radius"))

    def _rows(self):
        """``(kinds, params)`` of the batch, in C order, as a collection stores them."""
        batch = self.batch_shape
        columns = [
            np.broadcast_to(self.center, batch + (3,)).reshape(-1, 3),
            np.broadcast_to(self._unit_normal, batch + (3,)).reshape(-1, 3),
            np.broadcast_to(self.normal, batch + (3,)).reshape(-1, 3),
            np.broadcast_to(self.radius, batch).reshape(-1, 1),
        ]
        return _rows(DISK if self._is_disk else CIRCLE, np.concatenate(columns, axis=1))

    def _query(self, points, method, full):
        method, points, out_shape = self._prepare(points, method)
        with threads.kernel():
            out = self._kernels().query(
                method,
                self._is_disk,
                self.center,
                self._unit_normal,
                self.normal,
                self.radius,
                points,
                out_shape,
                full,
            )
        if self._is_disk and full:
            del out["equidistant"]
        return out_shape, out


class Circle(_Round):
    """A batch of circles in 3D.

    Parameters
    ----------
    center : array_like, shape ``batch + (3,)``
    normal : array_like, shape ``batch + (3,)``
        Normal of the circle's plane, of any non-zero length: only its
        direction matters, and its sign orients ``height``.
    radius : array_like, shape ``batch``
        Radius, >= 0.  The batch dimensions of the three broadcast.
    copy : bool, keyword-only, default False
        C-contiguous float64 arrays are used as they are, without a copy
        (the shape holds read-only views of them), so do not write to them
        while the shape is in use; ``copy=True`` gives the shape its own
        copies.

    Notes
    -----
    Method ``robust`` (default) decomposes ``P - C`` into height and radial
    terms and is accurate to ``8 eps (|P - C| + R) + 2^-1075``; ``eberly`` is the
    formula of Eberly's *Distance Between Point and Circle or Disk in 3D*
    as written, kept as a baseline.

    Examples
    --------
    >>> import proximity
    >>> ring = proximity.Circle(center=[0, 0, 0], normal=[0, 0, 2], radius=1.0)
    >>> r = ring.closest_point([[3, 0, 0], [0, 0, 1]])
    >>> r.distance.round(6).tolist(), r.equidistant.tolist()
    ([2.0, 1.414214], [False, True])
    """

    __slots__ = ()
    _primitive = CIRCLE
    _result = CircleResult
    _from_row = staticmethod(circle_from_row)


class Disk(_Round):
    """A batch of disks (filled circles) in 3D.

    Parameters are those of :class:`Circle`.

    Examples
    --------
    >>> import proximity
    >>> plate = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1.0)
    >>> r = plate.closest_point([[0.5, 0, 2], [3, 0, 0]])
    >>> r.distance.tolist(), r.feature_name.tolist()
    ([2.0, 2.0], ['FACE', 'RIM'])
    >>> plate
    Disk(center=array([0., 0., 0.]), normal=array([0., 0., 1.]), radius=array(1.))
    """

    __slots__ = ()
    _primitive = DISK
    _result = DiskResult
    _from_row = staticmethod(disk_from_row)
    _is_disk = True


def _normals_2d(corners, params, feature):
    """Normals of 2D hulls (embedded in ``z = 0``) at points on their
    ``feature``, in the plane: a segment's perpendicular; a triangle's
    outward edge normal on an edge, the sum of its two edges' at a vertex
    (normalised), and NaN inside, as for a point, which have no direction
    there."""
    out = np.full((len(params), 3), np.nan)
    if corners < 2:
        return out
    v = params[:, : 3 * corners].reshape(-1, corners, 3)[:, :, :2]
    v = v - v[:, :1]
    size = np.max(np.abs(v), axis=(1, 2), keepdims=True)
    v = v / np.where(size > 0, size, 1.0)  # in units of the largest: no product under- or overflows
    with np.errstate(invalid="ignore", divide="ignore"):
        if corners == 2:
            e = v[:, 1] - v[:, 0]
            out[:, :2] = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1, keepdims=True)
        else:
            # Edge k runs from vertex k to k + 1 (EDGE01, EDGE12, EDGE20); outward is to its
            # right on a counterclockwise triangle, to its left on a clockwise one.
            e = np.roll(v, -1, axis=1) - v
            area = e[:, 0, 0] * e[:, 1, 1] - e[:, 0, 1] * e[:, 1, 0]
            turn = np.where(area < 0, -1.0, 1.0)[:, None, None]
            edge = turn * np.stack([e[:, :, 1], -e[:, :, 0]], axis=2)
            edge = edge / np.linalg.norm(edge, axis=2, keepdims=True)
            k = np.asarray(feature).astype(np.intp)
            rows = np.arange(len(params))
            on_edge = (k >= EDGE01) & (k <= EDGE20)
            at_vertex = (k >= VERTEX0) & (k <= VERTEX2)
            n = np.full((len(params), 2), np.nan)
            n[on_edge] = edge[rows[on_edge], k[on_edge] - EDGE01]
            both = edge[rows[at_vertex], k[at_vertex]] + edge[rows[at_vertex], (k[at_vertex] + 2) % 3]
            n[at_vertex] = both / np.linalg.norm(both, axis=1, keepdims=True)
            out[:, :2] = n
    out[:, 2] = 0.0
    out[~np.isfinite(out[:, :2]).all(axis=1)] = np.nan
    return out + 0.0  # -0.0 from the perpendiculars' negations shown as 0.0


def _rows(primitive, params):
    """``(kinds, params)`` of ``primitive`` rows, padded to the stored width."""
    n = len(params)
    padding = np.zeros((n, N_PARAMS - params.shape[1]))
    return np.full(n, primitive.code, np.int8), np.concatenate([params, padding], axis=1)


def _to_3d(array):
    # 2D data are embedded in the z = 0 plane, which changes no distance.
    if array.shape[-1] == 3:
        return array
    return np.concatenate([array, np.zeros(array.shape[:-1] + (1,))], axis=-1)


# From this many normals on, a compiled loop computes the unit normals.
_COMPILED_UNIT = 1 << 16
# Read-only, as the shapes' arrays are, so that the loop compiles once.
_NO_ROWS = np.empty((0, 3))
_NO_ROWS.flags.writeable = False


def _unit_normals(center, normal, radius):
    """The unit normals of a circle or disk's arrays, or a ValueError naming
    the first argument with a non-finite entry, a negative radius or a zero
    normal."""
    if normal.size >= 3 * _COMPILED_UNIT:
        round_frames = lazy.load("proximity.point.disk").round_frames
        unit = pool.empty(normal.shape)
        rows = normal.size // 3
        c = center.reshape(-1, 3) if center.size == normal.size else _NO_ROWS[:, :3]
        r = radius.reshape(-1) if radius.size == rows else _NO_ROWS[:, 0]
        if round_frames(c, normal.reshape(-1, 3), r, unit.reshape(-1, 3)) == 0:
            if c.size == 0:
                require_finite(center, "center")
            if r.size == 0:
                _check_radius(radius)
            return unit
    require_finite(center, "center")
    require_finite(normal, "normal")
    _check_radius(radius)
    if not np.any(normal, axis=-1).all():
        index = tuple(int(i) for i in np.argwhere(~np.any(normal, axis=-1))[0])
        raise ValueError(f"normal must be non-zero; got a zero vector at index {index}")
    return _unit(normal)


def _check_radius(radius):
    require_finite(radius, "radius")
    if (radius < 0).any():
        index = tuple(int(i) for i in np.argwhere(radius < 0)[0])
        raise ValueError(f"radius must be >= 0; got {radius[index]} at index {index}")


def _unit(normal):
    # Scale by a power of two first (exact), so that squaring neither
    # overflows nor underflows for lengths from 1e-300 to 1e300.
    _, exponent = np.frexp(np.max(np.abs(normal), axis=-1, keepdims=True))
    scaled = np.ldexp(normal, -exponent)
    return scaled / np.sqrt(np.sum(scaled * scaled, axis=-1, keepdims=True))
