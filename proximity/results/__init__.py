"""Result types of the queries: frozen dataclasses of read-only arrays.

:mod:`.base`
    The :class:`Result` base of point queries, their normals, reprs and cutoffs.
:mod:`.point`
    One result type per kind of shape (:class:`TriangleResult`, :class:`MeshResult`, ...), and
    those the one-point fast path fills from its kernel's row.
:mod:`.pair`
    The results of queries between two shapes (:class:`PairResult`, :class:`HausdorffResult`).

Every query returns one of these; they may import :mod:`proximity.numerics` (the normals) and the
root's vocabulary, and nothing that answers a query.
"""

from ..features import Feature
from .base import (
    REPR_OPTIONS,
    Result,
    asdict,
    attach,
    attach_frame,
    beyond,
    format_repr,
    posed_normals,
)
from .pair import Fill, HausdorffResult, PairResult, pair_result
from .point import (
    CircleResult,
    DiskResult,
    MeshResult,
    PointResult,
    SceneResult,
    SegmentResult,
    TriangleResult,
    circle_from_row,
    disk_from_row,
    point_from_row,
    segment_from_row,
    triangle_from_row,
)

__all__ = [
    "REPR_OPTIONS",
    "CircleResult",
    "DiskResult",
    "Feature",
    "Fill",
    "HausdorffResult",
    "MeshResult",
    "PairResult",
    "PointResult",
    "Result",
    "SceneResult",
    "SegmentResult",
    "TriangleResult",
    "asdict",
    "attach",
    "attach_frame",
    "beyond",
    "circle_from_row",
    "disk_from_row",
    "format_repr",
    "pair_result",
    "point_from_row",
    "posed_normals",
    "segment_from_row",
    "triangle_from_row",
]
