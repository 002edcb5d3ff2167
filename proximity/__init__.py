"""proximity: exact, robust and fast closest-point queries in 3D.

Point-triangle, point-circle and point-disk distance, on single points and
NumPy batches, behind one shape protocol.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import os
import sys

from .runtime import threads as _threads

_threads.configure()  # before any kernel: Numba picks its threading layer once


class _SourceTreeAdapters:
    """Finds ``proximity.adapters`` in the top-level ``adapters/`` of a source
    checkout, as an install maps it, where the checkout's ``proximity/`` is
    imported rather than the installed one (Python started in the clone's root)."""

    def __init__(self, root):
        self.root = root

    def find_spec(self, fullname, path=None, target=None):
        if fullname != f"{__name__}.adapters":
            return None
        return importlib.machinery.PathFinder.find_spec(fullname, [self.root])


def _map_source_adapters():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    installed = os.path.isdir(os.path.join(here, "adapters"))
    checkout = os.path.isfile(os.path.join(root, "adapters", "__init__.py")) and os.path.isfile(
        os.path.join(root, "pyproject.toml")
    )
    if checkout and not installed:
        sys.meta_path.append(_SourceTreeAdapters(root))


_map_source_adapters()


class _MovedModules:
    """Imports the modules that objects pickled by earlier versions name (``proximity.mesh``,
    ``proximity.inflated``, ...) as the modules they moved to, so that those pickles load."""

    MOVED = {
        f"{__name__}.inflated": f"{__name__}.shapes.rounded",
        f"{__name__}.mesh": f"{__name__}.shapes.mesh",
        f"{__name__}.posed": f"{__name__}.shapes.posed",
        f"{__name__}.scene": f"{__name__}.shapes.scene",
        f"{__name__}.validity": f"{__name__}.signs.validity",
        f"{__name__}.winding": f"{__name__}.signs.winding",
    }

    def find_spec(self, fullname, path=None, target=None):
        if fullname not in self.MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec):
        return None

    def exec_module(self, module):
        # The import returns what sys.modules holds for the name once this has run.
        sys.modules[module.__name__] = importlib.import_module(self.MOVED[module.__name__])


sys.meta_path.append(_MovedModules())

from ._typing import ArrayLike, Distances  # noqa: E402
from ._validate import keyword_only_signature  # noqa: E402
from .pair import queries as _pairs  # noqa: E402
from .pair.fast import closest_route as _closest_route  # noqa: E402
from .results import (  # noqa: E402
    CircleResult,
    DiskResult,
    Feature,
    HausdorffResult,
    MeshResult,
    PairResult,
    PointResult,
    Result,
    SceneResult,
    SegmentResult,
    TriangleResult,
)
from .runtime import pool as _pool  # noqa: E402
from .runtime.counts import stats as certified_stats  # noqa: E402
from .runtime.threads import threads  # noqa: E402
from .shapes.base import DEFAULT_METHOD, Circle, Disk, Point, Segment, Shape, Triangle  # noqa: E402
from .shapes.mesh import TriangleMesh  # noqa: E402
from .shapes.posed import Posed  # noqa: E402
from .shapes.rounded import Capsule, Inflated, Sphere  # noqa: E402
from .shapes.scene import Scene  # noqa: E402

__all__ = [
    "Capsule",
    "Circle",
    "CircleResult",
    "Disk",
    "DiskResult",
    "Feature",
    "HausdorffResult",
    "Inflated",
    "MeshResult",
    "PairResult",
    "Point",
    "PointResult",
    "Posed",
    "Result",
    "Scene",
    "SceneResult",
    "Segment",
    "SegmentResult",
    "Shape",
    "Sphere",
    "Triangle",
    "TriangleMesh",
    "TriangleResult",
    "certified_stats",
    "closest_point",
    "closest_points",
    "distance",
    "hausdorff_distance",
    "release_memory",
    "signed_distance",
    "threads",
]

__version__ = "0.1.0"


_SHAPES = (Triangle, Segment, Point, Circle, Disk, TriangleMesh, Scene, Inflated, Sphere, Capsule, Posed)
_SHAPE_TYPES = frozenset(_SHAPES)


def _check(shape):
    # A set lookup on the exact class, not isinstance against the Protocol
    # (which inspects every attribute): the function form costs what the method does.
    if type(shape) in _SHAPE_TYPES or isinstance(shape, _SHAPES):
        return shape
    from .shapes.meshlike import looks_like_a_mesh

    hint = "; use proximity.TriangleMesh(mesh) first" if looks_like_a_mesh(shape) else ""
    raise TypeError(
        f"shape must be a proximity shape ({', '.join(s.__name__ for s in _SHAPES)}); "
        f"got {type(shape).__name__}{hint}"
    )


@keyword_only_signature
def closest_point(
    shape: Shape,
    points: ArrayLike,
    *args: object,
    method: str = DEFAULT_METHOD,
    max_distance: float | None = None,
) -> Result:
    """Closest point on ``shape`` to each of ``points``.

    The function form of ``shape.closest_point(points, method=method)``.

    Parameters
    ----------
    shape : Shape
        Any shape of the package: a :class:`Triangle`, :class:`Segment`,
        :class:`Point`, :class:`Circle` or :class:`Disk` (one, or a batch of
        them), a :class:`TriangleMesh`, a :class:`Scene`, or a rounded shape
        (:class:`Sphere`, :class:`Capsule`, :class:`Inflated`).  A mesh of
        another library (trimesh, Open3D, ...) is not one: wrap it in
        :class:`TriangleMesh` first.
    points : array_like, shape ``(..., 3)``
        Query points.  Against a batch of primitives, their leading
        dimensions broadcast against the batch's like a NumPy ufunc:
        ``(N, 3)`` against one shape, ``(N, 3)`` against ``N`` shapes
        pairwise, ``(N, 1, 3)`` against ``M`` shapes for all pairs.  Against
        a mesh, a scene or one shape, any ``(..., 3)``.  Rows containing NaN
        or inf give NaN (feature ``Feature.NONE``) in those rows only.
    method : str, keyword-only
        One of ``shape.methods``.  ``"robust"`` (the default) is accurate
        to a few units of rounding of the query's size on every finite
        input; ``"certified"`` gives the distance within one unit in the
        last place of the exact one, and the exact closest feature;
        ``"eberly"`` (triangles, circles, disks and meshes) is Eberly's
        algorithm as written, kept as a baseline.  The bounds are in
        ``docs/accuracy.md``.
    max_distance : float, optional, keyword-only
        A cutoff: a point farther than it from the shape gets an infinite
        distance, a NaN point, feature ``Feature.NONE`` and index ``-1``,
        and the search skips what lies beyond it; the other rows are the
        same bits as without it.  None (default): no cutoff.

    Returns
    -------
    Result
        The shape's result type (``shape.result_type``): a frozen result of
        arrays of the broadcast shape, with ``distance``, ``sqr_distance``,
        ``point`` and ``feature``, and the shape's own fields (barycentric
        coordinates for triangles, ``face`` for meshes, ``primitive`` for
        scenes, ...): :class:`TriangleResult`, :class:`SegmentResult`,
        :class:`PointResult`, :class:`DiskResult`, :class:`CircleResult`,
        :class:`MeshResult` or :class:`SceneResult`.

    Examples
    --------
    >>> import numpy as np, proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> r = proximity.closest_point(tri, [[2, 0, 0], [0.2, 0.2, -1], [np.nan, 0, 0]])
    >>> r.distance.tolist()
    [1.0, 1.0, nan]
    >>> r.feature_name.tolist()
    ['VERTEX1', 'FACE', 'NONE']
    >>> r.barycentric[1].round(6).tolist()
    [0.6, 0.2, 0.2]
    """
    if type(shape) not in _SHAPE_TYPES:
        _check(shape)
    if args:
        raise TypeError(
            "closest_point() takes two positional arguments, shape and points; method is keyword-only: "
            f"closest_point(shape, points, method={args[0]!r})"
        )
    return shape.closest_point(points, method=method, max_distance=max_distance)


@keyword_only_signature
def distance(
    shape: Shape,
    points: ArrayLike | Shape,
    *args: object,
    method: str = DEFAULT_METHOD,
    max_distance: float | None = None,
) -> Distances:
    """Distance from each of ``points`` to ``shape``, or between two shapes.

    The function form of ``shape.distance(points, method=method)``: any
    shape, points and method of :func:`closest_point` (a mesh, a scene, a
    rounded shape, a batch of primitives), the distances alone computed.
    Where ``points`` is a shape too, the distance between the two shapes,
    as :func:`closest_points` gives it.

    Parameters
    ----------
    shape : Shape
        As in :func:`closest_point`.
    points : array_like, shape ``(..., 3)``, or Shape
        As in :func:`closest_point`, or a second shape (see :func:`closest_points`).
    method : str, keyword-only
        As in :func:`closest_point`; default ``"robust"``.
    max_distance : float, optional, keyword-only
        As in :func:`closest_point`: ``inf`` beyond it.

    Returns
    -------
    ndarray of float64, read-only
        The distances, of the broadcast shape (a NumPy scalar for one point
        against one shape); NaN where a point is not finite.

    Examples
    --------
    >>> import proximity
    >>> disk = proximity.Disk(center=[0, 0, 0], normal=[0, 0, 1], radius=1)
    >>> float(proximity.distance(disk, [0, 0, 5]))
    5.0
    >>> proximity.distance(disk, [[[0, 0, 1]], [[4, 0, 0]]]).shape
    (2, 1)
    """
    if type(shape) not in _SHAPE_TYPES:
        _check(shape)
    if args:
        raise TypeError(
            "distance() takes two positional arguments, shape and points; method is keyword-only: "
            f"distance(shape, points, method={args[0]!r})"
        )
    if type(points) in _SHAPE_TYPES or hasattr(points, "_rows") and hasattr(points, "batch_shape"):
        return _pairs.distance(shape, points, method=method, max_distance=max_distance)
    return shape.distance(points, method=method, max_distance=max_distance)


@keyword_only_signature
def closest_points(
    a: Shape,
    b: Shape,
    *args: object,
    method: str = DEFAULT_METHOD,
    max_distance: float | None = None,
) -> PairResult:
    """Closest points of two shapes: the distance between them and a witness on each.

    Parameters
    ----------
    a, b : Shape
        Two shapes of the same dimension: batches of segments, triangles or
        points, a :class:`TriangleMesh` or a :class:`Scene`, posed views of
        them (``shape.transformed(T)``, searched in place, without a
        rebuild), or any of them rounded (:class:`Inflated`,
        :class:`Sphere`, :class:`Capsule`).  Batches broadcast against each
        other like points against a shape: ``(N,)`` segments with ``(N,)``
        triangles give N pairs, ``(M,)`` with ``(N, 1)`` all ``N x M``
        pairs; a mesh or a scene is one shape.  A scene of posed meshes or
        scenes (instances) answers with the least over its members, each
        searched in place with the best distance so far as its cutoff.
        Disks and circles pair with points only (``NotImplementedError``
        naming the pair).
    method : {"robust", "certified"}, keyword-only
        ``robust`` (default) is within ``16 eps S + 2^-1075`` of the exact
        distance, ``S`` the largest coordinate difference between the
        pair's vertices; ``certified`` is faithfully rounded, with the exact
        closest features (lowest feature codes among ties).  Meshes and
        scenes answer with the least of their primitives' pairs, computed
        by the same method, ties to the lowest ``(face_a, face_b)`` (or
        primitives), except between touching or overlapping shapes, where
        the search stops at the first common point it finds.  Posed views
        add the rounding of the pose, a few ``eps`` of the coordinates'
        magnitude (see :mod:`proximity.shapes.posed`).
    max_distance : float, keyword-only, optional
        Nothing within it: ``inf`` distance, NaN points, feature ``NONE``
        and index -1 for pairs farther apart.  It prunes the search of
        meshes and scenes.

    Returns
    -------
    PairResult
        Distance, squared distance, a witness point on each shape and its
        feature, each side's parameters (segment parameter, barycentrics,
        face, scene primitive).  Touching or overlapping shapes give 0 and a
        common point.  Rounded shapes give ``max(d - r_a - r_b, 0)`` and
        witnesses on their surfaces, along the cores' witness direction.

    Examples
    --------
    >>> import proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [4, 0, 0], [0, 4, 0]])
    >>> rod = proximity.Segment([[1, 1, 1], [1, 1, 3]])
    >>> r = proximity.closest_points(rod, tri)
    >>> float(r.distance), r.point_a.tolist(), r.point_b.tolist()
    (1.0, [1.0, 1.0, 1.0], [1.0, 1.0, 0.0])
    >>> str(r.feature_name_a), str(r.feature_name_b), r.barycentric_b.tolist()
    ('VERTEX0', 'FACE', [0.5, 0.25, 0.25])
    >>> pills = proximity.Capsule([[[0, 0, 0], [0, 0, 4]], [[3, 0, 0], [3, 0, 4]]], radius=0.5)
    >>> proximity.distance(pills, proximity.Sphere([1, 0, 2], 0.25)).tolist()
    [0.25, 1.25]
    >>> import numpy as np
    >>> tet = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    ...                              [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> T = np.eye(4); T[:3, 3] = [0, 0, 3]          # a copy moved up by 3
    >>> r = proximity.closest_points(tet, tet.transformed(T))
    >>> float(r.distance), r.point_a.tolist(), r.point_b.tolist()
    (2.0, [0.0, 0.0, 1.0], [0.0, 0.0, 3.0])
    """
    if args:
        raise TypeError(
            "closest_points() takes two positional arguments, a and b; method is keyword-only: "
            f"closest_points(a, b, method={args[0]!r})"
        )
    if max_distance is None:  # one pair of single primitives: its fast path, resolved once per types
        closest = _closest_route(a, b, method)
        if closest is not None:
            result = closest(a, b)
            if result is not None:
                return result
    return _pairs.closest_points(a, b, method=method, max_distance=max_distance)


@keyword_only_signature
def signed_distance(
    a: Shape,
    b: Shape,
    *args: object,
    method: str = DEFAULT_METHOD,
    max_distance: float | None = None,
) -> Distances:
    """Signed distance between two shapes: ``d - r_a - r_b``, negative where they overlap.

    For rounded shapes (:class:`Inflated`, :class:`Sphere`, :class:`Capsule`)
    the distance of their cores less both radii: minus the depth of
    penetration along the cores' witness direction where they overlap;
    for other shapes, the distance.  Arguments as for :func:`closest_points`.

    Examples
    --------
    >>> import proximity
    >>> a = proximity.Capsule([[0, 0, 0], [4, 0, 0]], radius=1.0)
    >>> b = proximity.Sphere([2, 0, 1.5], 1.0)
    >>> float(proximity.signed_distance(a, b))
    -0.5
    """
    if args:
        raise TypeError(
            "signed_distance() takes two positional arguments, a and b; method is keyword-only: "
            f"signed_distance(a, b, method={args[0]!r})"
        )
    return _pairs.signed_distance(a, b, method=method, max_distance=max_distance)


@keyword_only_signature
def hausdorff_distance(
    a: TriangleMesh | Posed,
    b: TriangleMesh | Posed,
    *args: object,
    directed: bool = False,
    rtol: float = 1e-6,
    atol: float = 0.0,
    method: str = DEFAULT_METHOD,
    max_points: int = 250_000,
) -> HausdorffResult:
    """Hausdorff distance between two meshes, with certified lower and upper bounds.

    The directed distance ``h(a, b) = max_{p in a} d(p, b)`` is the largest
    distance from a point of the surface ``a`` to the surface ``b``; the
    Hausdorff distance is ``max(h(a, b), h(b, a))``.  Any point of ``a``
    gives a *lower* bound, ``d(p, b) <= h(a, b)``; *upper* bounds come from
    each face of ``a`` (the distance to one face of ``b`` is convex, so
    its maximum over a triangle is at a vertex; and ``d(., b)`` is
    1-Lipschitz).  A branch and bound splits the faces of ``a`` where the
    two bounds disagree, until ``upper - lower <= rtol * upper`` (see
    :mod:`proximity.pair.hausdorff`).

    Parameters
    ----------
    a, b : TriangleMesh or posed view of one
        Two surfaces (``mesh.transformed(T)`` is searched in place).  A mesh
        of another library is wrapped in :class:`TriangleMesh` first.
    directed : bool, keyword-only
        True: ``h(a, b)`` alone, the farthest point of ``a`` from ``b``.
        False (default): ``max(h(a, b), h(b, a))``.
    rtol : float, keyword-only
        The relative gap to reach, ``upper - lower <= rtol * upper``
        (plus a rounding allowance of a few times the method's error bound,
        which is all that separates the bounds of meshes at distance 0).
        Finite and > 0; default 1e-6.
    atol : float, keyword-only
        An absolute gap that is enough as well: the search stops at
        ``upper - lower <= max(rtol * upper, atol)``.  Finite and >= 0;
        default 0.
    method : {"robust", "certified"}, keyword-only
        The point queries behind the bounds, whose error is allowed for:
        ``robust`` (default) by its documented bound, ``8 eps S + 2^-1075``
        per triangle (see ``docs/accuracy.md``); ``certified`` by one ulp
        (it is faithfully rounded).  The bounds are certified either way:
        ``lower <= H <= upper`` for the exact surfaces, the points of ``a``
        computed in floating point being allowed for too.  ``certified``
        runs its exact fallback for every point of ``a`` lying on ``b``,
        which is slow where the surfaces coincide over an area.
    max_points : int, keyword-only
        The most points measured per direction after the first pass (which
        measures every vertex and face centroid); beyond, the search stops
        with a ``RuntimeWarning`` and the bounds reached (``converged`` False).
        Default 250,000 (about a second).

    Notes
    -----
    The bounds meet quickly where one face of ``b`` is nearest to each
    part of ``a``, and where ``b``'s faces that compete are far from each
    other compared with the distance.  Two cases converge only as fast as
    the subtriangles shrink, and stop at ``max_points``: surfaces that
    coincide over an area but are triangulated differently (a remeshed or
    turned copy: ``upper`` stays about the size of the subtriangles where
    the true distance is 0), and curved surfaces close together compared
    with the size of their faces (two tessellations of one sphere), where
    the subtriangles must become about as small as the distance near every
    edge of ``b``.  Their bounds remain certified; ``atol`` stops earlier.

    Returns
    -------
    HausdorffResult
        ``lower`` and ``upper``; ``distance``, the distance from the
        witness point (the farthest found) to the other mesh; the witness
        pair ``point_a``, ``point_b`` and the ``side`` holding the witness.

    Raises
    ------
    TypeError
        Where ``a`` or ``b`` is not a :class:`TriangleMesh` or a posed view of one.
    ValueError
        Where ``rtol`` is not a finite number > 0, or ``method`` is not one of the two.

    Examples
    --------
    A unit square and a copy of it lifted by 0.5 and stretched to twice its
    width: the corner (2, 0, 0.5) is farthest from the square.

    >>> import proximity
    >>> square = proximity.TriangleMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                                 [[0, 1, 2], [0, 2, 3]])
    >>> wide = proximity.TriangleMesh([[0, 0, 0.5], [2, 0, 0.5], [2, 1, 0.5], [0, 1, 0.5]],
    ...                               [[0, 1, 2], [0, 2, 3]])
    >>> r = proximity.hausdorff_distance(square, wide)
    >>> r.lower <= 1.25**0.5 <= r.upper, r.upper - r.lower <= 1e-6 * r.upper
    (True, True)
    >>> r.side, r.point_b.tolist(), r.point_a.tolist()
    ('b', [2.0, 0.0, 0.5], [1.0, 0.0, 0.0])
    >>> round(proximity.hausdorff_distance(square, wide, directed=True).distance, 12)
    0.5
    """
    if args:
        raise TypeError(
            "hausdorff_distance() takes two positional arguments, a and b; the options are keyword-only: "
            f"hausdorff_distance(a, b, rtol={args[0]!r})"
        )
    from .pair import hausdorff

    return hausdorff.hausdorff_distance(
        a, b, directed=directed, rtol=rtol, atol=atol, method=method, max_points=max_points
    )


def release_memory() -> int:
    """Give back to the system the memory kept for the outputs of later batches.

    The outputs of a large batch (from 1 MB), and the arrays of a refitted
    mesh (:meth:`TriangleMesh.with_vertices`), are recycled: when every array of
    a dropped result is gone, its memory is kept, up to 256 MB in all, for the
    next batch of the same size, which then skips the operating system's
    slow first writes to fresh pages.  Memory is never reused while an array
    (or view) of it is alive.  Returns the number of bytes released.

    Examples
    --------
    >>> import numpy as np, proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> _ = proximity.release_memory()
    >>> d = tri.distance(np.zeros((200_000, 3)))  # 1.6 MB of distances
    >>> del d
    >>> proximity.release_memory()
    1600000
    """
    return _pool.clear()
