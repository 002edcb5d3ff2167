"""Seeded scene generators for accuracy tests and benchmarks.

Each generator builds one family of queries, pairwise (point ``i`` against
shape ``i``), from ``(rng, n, **params)``: the same generator state gives the
same scene. Triangle families return a `TriangleScene`, circle and disk
families a `DiskScene` (the same scenes serve both shapes). All arrays are
float64 and finite.

Where a family promises an exact property (zero area, a point exactly on an
edge or on an axis, a sliver thinner than the float spacing of its vertices),
the construction only uses float operations that are exact: multiplication by
powers of two, sums of numbers on a common dyadic grid that does not exceed 53
bits, and differences of numbers within a factor of two of each other
(Sterbenz's lemma). The docstrings say which.

`TRIANGLE_FAMILIES` and `DISK_FAMILIES` list every family with the parameter
sweep used by the tests and the benchmarks.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from .pairs import (
    PAIRS,
    PairScene,
    pair_contact,
    pair_degenerate,
    pair_far,
    pair_magnitude,
    pair_near_parallel,
    pair_offset,
    pair_parallel,
    pair_well_conditioned,
)
from .points import (
    DiskScene,
    TriangleScene,
    degenerate,
    disk_axis,
    disk_in_plane,
    disk_offset,
    disk_rim,
    disk_unnormalized,
    disk_well_conditioned,
    far_points,
    magnitude,
    near_surface,
    needle,
    offset,
    on_feature,
    sliver,
    small,
    well_conditioned,
)

__all__ = [
    "DISK_FAMILIES",
    "PAIRS",
    "PAIR_FAMILIES",
    "TRIANGLE_FAMILIES",
    "DiskScene",
    "Family",
    "PairScene",
    "TriangleScene",
    "degenerate",
    "disk_axis",
    "disk_in_plane",
    "disk_offset",
    "disk_rim",
    "disk_unnormalized",
    "disk_well_conditioned",
    "far_points",
    "magnitude",
    "near_surface",
    "needle",
    "offset",
    "on_feature",
    "pair_contact",
    "pair_degenerate",
    "pair_far",
    "pair_magnitude",
    "pair_near_parallel",
    "pair_offset",
    "pair_parallel",
    "pair_well_conditioned",
    "sliver",
    "small",
    "well_conditioned",
]


# -- registries ----------------------------------------------------------------------


class Family(NamedTuple):
    """One generator with one parameter setting.

    Attributes
    ----------
    name : str
        The generator's name.
    generator : callable
        Called as ``generator(rng, n, **params)``.
    params : mapping
        Keyword arguments of the generator (read-only).
    difficulty : float or None
        The swept parameter's value, for plotting error against it; None for
        families without a numeric sweep.
    """

    name: str
    generator: Callable[..., Any]
    params: Mapping[str, Any]
    difficulty: float | None

    @property
    def label(self) -> str:
        """A unique, readable identifier such as ``"sliver[rel_height=1e-12]"``."""
        if not self.params:
            return self.name
        args = ",".join(
            f"{key}={value!r}" if isinstance(value, str) else f"{key}={value:g}"
            for key, value in self.params.items()
        )
        return f"{self.name}[{args}]"

    def __call__(self, rng: np.random.Generator, n: int) -> Any:
        """Generate the scene: ``generator(rng, n, **params)``."""
        return self.generator(rng, n, **self.params)


def _sweep(generator: Callable[..., Any], **sweep: tuple) -> list[Family]:
    """List the families of one generator.

    One family without parameters, or one per value of the single swept keyword.
    """
    if not sweep:
        return [Family(generator.__name__, generator, MappingProxyType({}), None)]
    ((key, values),) = sweep.items()
    return [
        Family(
            generator.__name__,
            generator,
            MappingProxyType({key: value}),
            None if isinstance(value, str) else value,
        )
        for value in values
    ]


TRIANGLE_FAMILIES: list[Family] = [
    *_sweep(well_conditioned),
    *_sweep(near_surface, offset=(1e-3, 1e-6, 1e-9, 1e-12, 1e-15)),
    *_sweep(sliver, rel_height=(1e-6, 1e-9, 1e-12, 1e-15, 1e-17)),
    *_sweep(degenerate, kind=("collinear", "two_coincident", "all_coincident")),
    *_sweep(needle, rel_width=(1e-3, 1e-6, 1e-9, 1e-12, 1e-15)),
    *_sweep(small, size=(1e-3, 1e-6, 1e-9)),
    *_sweep(offset, offset=(1e4, 1e6, 1e8, 1e10)),
    *_sweep(far_points, ratio=(1e3, 1e4, 1e6, 1e8)),
    *_sweep(magnitude, scale=(1e-300, 1e-150, 1e-50, 1e50, 1e150, 1e300)),
    *_sweep(on_feature, kind=("vertex", "edge", "plane")),
]
"""Every triangle family with its parameter sweep."""

DISK_FAMILIES: list[Family] = [
    *_sweep(disk_well_conditioned),
    *_sweep(disk_axis, rel_distance=(1e-8, 1e-16, 1e-100, 1e-300, 0.0)),
    *_sweep(disk_rim, rel_distance=(1e-3, 1e-8, 1e-13)),
    *_sweep(disk_in_plane),
    *_sweep(disk_offset, offset=(1e4, 1e6, 1e8, 1e10)),
    *_sweep(disk_unnormalized),
]
"""Every circle and disk family with its parameter sweep."""


def _pair_sweep(generator: Callable[..., Any], pair: str, **sweep: tuple) -> list[Family]:
    """`_sweep` for a pair generator, with ``pair`` fixed."""
    return [
        Family(
            family.name,
            family.generator,
            MappingProxyType({"pair": pair, **family.params}),
            family.difficulty,
        )
        for family in _sweep(generator, **sweep)
    ]


PAIR_FAMILIES: Mapping[str, list[Family]] = MappingProxyType(
    {
        pair: [
            *_pair_sweep(pair_well_conditioned, pair),
            *_pair_sweep(pair_contact, pair, gap=(-1e-12, 0.0, 1e-12)),
            *_pair_sweep(pair_near_parallel, pair, angle=(1e-1, 1e-4, 1e-8, 1e-12, 1e-15)),
            *_pair_sweep(pair_parallel, pair, kind=("touching", "apart")),
            *_pair_sweep(pair_degenerate, pair, kind=("point", "collinear", "two_coincident")),
            *_pair_sweep(pair_magnitude, pair, scale=(1e-300, 1e-150, 1e150, 1e300)),
            *_pair_sweep(pair_offset, pair, offset=(1e4, 1e7, 1e10)),
            *_pair_sweep(pair_far, pair, ratio=(1e3, 1e6, 1e9)),
        ]
        for pair in PAIRS
    }
)
"""Every pair family with its parameter sweep, per pair of shapes (a key of `PAIRS`)."""
