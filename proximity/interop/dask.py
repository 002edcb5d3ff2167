"""Point clouds on Dask: distances and closest points of a ``dask.array``.

The points are a dask array of shape ``(N, D)`` chunked by rows; each chunk
becomes one task, which asks the shape for its rows, so that a cloud of any
size runs on whatever Dask runs on: the threaded scheduler of one process,
a :class:`distributed.LocalCluster`, or a cluster's scheduler.

The shape goes to each worker once: where a :mod:`distributed` client
would compute the graph (the default client, or one made current with
``client.as_current()``, when the function is called), the shape is
scattered to every worker before the graph is built, and the graph holds
a reference to it; otherwise it is one node of the graph that every task
depends on.

Threads.  Inside a task, the query runs on ``threads`` of Numba's threads
(:func:`proximity.threads`); the queries of a process's Dask threads run at
the same time (the parallel kernels release the GIL).  By default, on a
distributed worker, ``threads`` is the machine's cores divided by the tasks
that can run on it at once (the threads of all the workers on the same
host), at least one, so that workers x threads x Numba's threads stays
within the cores.  Under the threaded scheduler of one process it is every
thread: TBB, Numba's threading layer here, caps its worker threads for the
whole process, and concurrent queries share them.  With Dask's
``processes`` scheduler, or with Numba's OpenMP layer, pass ``threads``:
the cores divided by the tasks that run at once.

Dask is imported when a function is called: ``pip install '.[scale]'``
in proximity's clone installs it.
"""

import collections
import dataclasses
import operator
import os

import numpy as np

from .. import primitives
from .._validate import as_array
from ..results import CircleResult, DiskResult, MeshResult, SceneResult, TriangleResult, asdict
from ..runtime import threads as _threads
from ..shapes.base import DEFAULT_METHOD, Frozen, check_method
from ..shapes.mesh import TriangleMesh

__all__ = ["closest_point", "distance", "records"]

INSTALL = "pip install '.[scale]' in proximity's clone"

#: Rows per chunk when ``points`` is a NumPy array: 24 MB of float64 points.
CHUNK_ROWS = 1_000_000

_INT64 = ("face", "primitive", "source")


def _result_type(shape):
    result = getattr(shape, "result_type", None)
    if result is None:
        raise TypeError(f"shape must be a proximity shape; got {type(shape).__name__}")
    return result


def _field_dtype(name, dim):
    if name == "point":
        return np.dtype((np.float64, (dim,)))
    if name == "feature":
        return np.dtype(np.int8)
    if name in _INT64:
        return np.dtype(np.int64)
    for primitive in primitives.BY_CODE:
        for extra, width in primitive.extra:
            if extra == name and width == 0:
                return np.dtype(np.bool_)
            if extra == name and width > 1:
                return np.dtype((np.float64, (width,)))
    return np.dtype(np.float64)


def _arrays_type(result):
    """The namedtuple of ``result``'s fields as dask arrays, a global of this module (so that it pickles)."""
    name = result.__name__.replace("Result", "Arrays")
    arrays = globals().get(name)
    if arrays is None:
        names = tuple(f.name for f in dataclasses.fields(result))
        arrays = collections.namedtuple(name, names, module=__name__)
        arrays.__doc__ = f"The fields of a {result.__name__}, each a dask array."
        globals()[name] = arrays
    return arrays


TriangleArrays = _arrays_type(TriangleResult)
DiskArrays = _arrays_type(DiskResult)
CircleArrays = _arrays_type(CircleResult)
MeshArrays = _arrays_type(MeshResult)
SceneArrays = _arrays_type(SceneResult)


def _dask():
    try:
        import dask
        import dask.array
    except ImportError as exc:
        raise ImportError(f"proximity.dask needs Dask, which is not installed: {INSTALL}") from exc
    return dask


def _client(dask):
    """The distributed client that computing a collection would use now, or None."""
    scheduler = dask.base.get_scheduler()
    client = getattr(scheduler, "__self__", None)
    if client is None or type(client).__module__.split(".")[0] != "distributed":
        return None
    return client


def _token_parts(value):
    """What identifies a shape, as plain values and arrays that Dask hashes
    without pickling."""
    if isinstance(value, Frozen):
        return type(value).__qualname__, {k: _token_parts(v) for k, v in value.__getstate__().items()}
    if isinstance(value, (tuple, list)):
        return type(value).__name__, [_token_parts(v) for v in value]
    if isinstance(value, dict):
        return {k: _token_parts(v) for k, v in value.items()}
    return value


def _shipped(dask, shape):
    """``(argument, threads per host)``: the shape as a graph argument that
    goes to each worker once, and the Dask threads of each host of the
    active distributed cluster (None without one)."""
    name = "proximity-shape-" + dask.base.tokenize(_token_parts(shape))
    client = _client(dask)
    if client is None:
        return dask.delayed(shape, pure=True, name=name), None
    future = client.scatter({name: shape}, broadcast=True)[name]
    try:
        workers = client.scheduler_info(n_workers=-1)["workers"]
    except TypeError:  # versions that list every worker without being asked
        workers = client.scheduler_info()["workers"]
    per_host = collections.Counter()
    for info in workers.values():
        per_host[info["host"]] += info["nthreads"]
    return future, dict(per_host)


def _cores():
    """Cores this process may run on: the container's limit, the affinity mask."""
    try:
        from distributed.system import CPU_COUNT  # cgroup limits and affinity

        return CPU_COUNT
    except ImportError:
        pass
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def task_threads(threads, per_host):
    """Numba threads for one task: ``threads`` if given, else the cores per
    concurrent task on a distributed worker, else every thread."""
    limit = _threads.default_threads()
    if threads is not None:
        return min(threads, limit)
    if per_host is None:
        return limit
    try:
        from distributed import get_worker
        from distributed.comm import get_address_host

        worker = get_worker()
    except (ImportError, ValueError):
        return limit
    busy = per_host.get(get_address_host(worker.address)) or worker.state.nthreads
    return max(1, min(limit, _cores() // max(1, busy)))


def _distance_block(block, shape, method, threads, per_host):
    with _threads.threads(task_threads(threads, per_host)):
        return np.asarray(shape.distance(block, method=method))


def _records_block(block, shape, method, threads, per_host, dtype, sign=None):
    names = [name for name in dtype.names if name != "signed_distance"]
    with _threads.threads(task_threads(threads, per_host)):
        if names == ["distance"]:
            result = {"distance": shape.distance(block, method=method)}
        elif names:
            result = asdict(shape.closest_point(block, method=method))
        else:
            result = {}
        if len(names) < len(dtype.names):
            options = {} if sign is None else {"sign": sign}
            result["signed_distance"] = shape.signed_distance(block, method=method, **options)
    out = np.empty(len(block), dtype)
    for name in dtype.names:
        out[name] = result[name]
    return out


def _points(dask, shape, points):
    """``points`` as a dask array ``(N, D)`` with the columns in one chunk."""
    da = dask.array
    if not isinstance(points, da.Array):
        points = as_array(points, "points", f"(N, {shape.dim})")
        points = da.from_array(points, chunks=(CHUNK_ROWS, -1)) if points.ndim == 2 else points
    if points.ndim != 2 or points.shape[1] != shape.dim:
        raise ValueError(f"points must have shape (N, {shape.dim}); got shape {points.shape}")
    if points.dtype.kind not in "iuf":
        raise ValueError(f"points must be a real numeric array; got dtype {points.dtype}")
    if points.numblocks[1] != 1:
        points = points.rechunk({1: -1})
    return points


def _check(shape, threads):
    """``threads`` as an int (or None), once ``shape`` and ``threads`` are known to be valid."""
    _result_type(shape)
    if shape.batch_shape != ():
        raise ValueError(
            f"shape must be a single shape (batch_shape ()) in proximity.dask; got a {type(shape).__name__} "
            f"of batch_shape {shape.batch_shape}: gather many primitives in a TriangleMesh or a Scene"
        )
    if threads is None:
        return None
    try:
        count = operator.index(threads)  # any integer, Python's or NumPy's
    except TypeError:
        count = None
    if count is None or isinstance(threads, bool) or count < 1:
        raise ValueError(f"threads must be a positive int or None; got {threads!r}")
    return count


def distance(shape, points, *, method=DEFAULT_METHOD, threads=None):
    """Distance from each point of a dask array to ``shape``: a lazy dask array.

    Parameters
    ----------
    shape : Shape
        Any shape of the package (a batch, a mesh, a scene, a rounded shape).
        A single shape (``batch_shape == ()``).
    points : dask.array.Array, shape ``(N, D)``
        Chunked by rows; columns are brought into one chunk.  A NumPy array
        is split into chunks of :data:`CHUNK_ROWS` rows.
    method : str, keyword-only
        One of ``shape.methods``; default ``"robust"``.
    threads : int or None, keyword-only
        Numba threads per task; None chooses (see the module's notes).

    Returns
    -------
    dask.array.Array of float64, shape ``(N,)``
        Chunked as ``points``' rows; the answers are those of
        ``shape.distance`` on the whole array, bit for bit.

    Examples
    --------
    >>> import dask.array as da, numpy as np, proximity, proximity.dask
    >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                                 [[0, 1, 2], [0, 2, 3]])
    >>> points = da.from_array(np.array([[0.5, 0.5, 2.0], [3.0, 0.5, 0.0], [0.0, 0.0, -1.0]]), chunks=(2, 3))
    >>> d = proximity.dask.distance(square, points)
    >>> d.chunks, d.compute().tolist()
    (((2, 1),), [2.0, 2.0, 1.0])
    """
    dask = _dask()
    threads = _check(shape, threads)
    check_method(method, shape.methods)
    points = _points(dask, shape, points)
    shipped, per_host = _shipped(dask, shape)
    return points.map_blocks(
        _distance_block,
        shipped,
        method,
        threads,
        per_host,
        drop_axis=1,
        dtype=np.float64,
        meta=np.empty((0,), np.float64),
        token="proximity-distance",
    )


def records(shape, points, *, method=DEFAULT_METHOD, threads=None, fields=None, sign=None):
    """The closest-point fields of each point, as one dask array of records.

    Parameters are those of :func:`closest_point`; ``fields`` (a sequence of
    names of the shape's result, default all) chooses the fields kept.
    Asking for ``("distance",)`` alone runs the distance query.  For shapes
    with a ``signed_distance`` method (meshes, rounded shapes), the field
    ``"signed_distance"`` may be asked for too, with ``sign`` (a mesh's
    ``sign=`` option, see :meth:`proximity.TriangleMesh.signed_distance`).

    Returns
    -------
    dask.array.Array, shape ``(N,)``, of a structured dtype
        One field per name: ``point`` and ``barycentric`` are sub-arrays of
        3 floats, ``feature`` int8, indices int64.

    Examples
    --------
    >>> import dask.array as da, numpy as np, proximity, proximity.dask
    >>> disk = proximity.Disk([0, 0, 0], [0, 0, 1], 1.0)
    >>> points = da.from_array(np.array([[0.0, 0.0, 2.0], [3.0, 0.0, 0.0]]))
    >>> r = proximity.dask.records(disk, points, fields=["distance", "point"])
    >>> r.dtype.names, r.compute()["point"].tolist()
    (('distance', 'point'), [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    """
    dask = _dask()
    threads = _check(shape, threads)
    check_method(method, shape.methods)
    names = [f.name for f in dataclasses.fields(_result_type(shape))]
    signed = callable(getattr(shape, "signed_distance", None))
    if signed:
        names.append("signed_distance")
    if sign is not None and not isinstance(shape, TriangleMesh):
        raise TypeError(f"sign is an option of meshes; got a {type(shape).__name__}")
    if fields is not None:
        try:
            fields = [fields] if isinstance(fields, str) else list(fields)
        except TypeError:
            kind = type(fields).__name__
            raise TypeError(f"fields must be a str or a sequence of str; got {kind}") from None
        unknown = [name for name in fields if not isinstance(name, str) or name not in names]
        if unknown or not fields:
            raise ValueError(f"fields must be names among {names}; got {fields}")
        names = fields
    elif signed:
        names.remove("signed_distance")
    dtype = np.dtype([(name, _field_dtype(name, shape.dim)) for name in names])
    points = _points(dask, shape, points)
    shipped, per_host = _shipped(dask, shape)
    return points.map_blocks(
        _records_block,
        shipped,
        method,
        threads,
        per_host,
        dtype,
        sign,
        drop_axis=1,
        dtype=dtype,
        meta=np.empty((0,), dtype),
        token="proximity-records",
    )


def closest_point(shape, points, *, method=DEFAULT_METHOD, threads=None):
    """Closest points of a dask array of points: one lazy dask array per field.

    Parameters
    ----------
    shape : Shape
        Any shape of the package (a batch, a mesh, a scene, a rounded shape).
        A single shape (``batch_shape == ()``).
    points : dask.array.Array, shape ``(N, D)``
        Chunked by rows, as in :func:`distance`.
    method : str, keyword-only
        One of ``shape.methods``; default ``"robust"``.
    threads : int or None, keyword-only
        Numba threads per task; None chooses (see the module's notes).

    Returns
    -------
    MeshArrays, SceneArrays, TriangleArrays, DiskArrays or CircleArrays
        A named tuple with the fields of the shape's result type
        (:class:`proximity.MeshResult` for a mesh: ``distance``,
        ``sqr_distance``, ``point``, ``feature``, ``barycentric``, ``face``),
        each a dask array of ``N`` rows.  The fields come from one task per
        chunk: computing several together (``dask.compute(*r)``) runs each
        chunk once.

    Examples
    --------
    >>> import dask, dask.array as da, numpy as np, proximity, proximity.dask
    >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                                 [[0, 1, 2], [0, 2, 3]])
    >>> points = da.from_array(np.array([[0.25, 0.75, 1.0], [2.0, 0.5, 0.0]]))
    >>> r = proximity.dask.closest_point(square, points)
    >>> distance, point, face = dask.compute(r.distance, r.point, r.face)
    >>> distance.tolist(), point.tolist(), face.tolist()
    ([1.0, 1.0], [[0.25, 0.75, 0.0], [1.0, 0.5, 0.0]], [1, 0])
    """
    table = records(shape, points, method=method, threads=threads)
    return _arrays_type(_result_type(shape))(*(table[name] for name in table.dtype.names))
