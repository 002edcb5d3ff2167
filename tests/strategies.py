"""Hypothesis strategies over the scene families of ``proximity/testing/scenes.py``.

Each strategy draws the family's parameter, a seed and a small size ``n``, and
calls the generator with ``numpy.random.default_rng(seed)``; the scene is thus
reproducible from the values Hypothesis reports, and shrinking moves toward
small seeds and sizes. Every parameter strategy can be replaced, for example
``sliver_scenes(rel_height=st.just(1e-17))``; None means the default range
stated in the docstring.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from hypothesis import strategies as st

from proximity.testing import scenes

__all__ = [
    "DISK_FAMILIES",
    "PAIR_FAMILIES",
    "SEEDS",
    "TRIANGLE_FAMILIES",
    "SIZES",
    "RigidMotion",
    "degenerate_scenes",
    "disk_axis_scenes",
    "disk_in_plane_scenes",
    "disk_offset_scenes",
    "disk_rim_scenes",
    "disk_scenes",
    "disk_unnormalized_scenes",
    "disk_well_conditioned_scenes",
    "far_points_scenes",
    "magnitude_scenes",
    "near_surface_scenes",
    "needle_scenes",
    "offset_scenes",
    "on_feature_scenes",
    "pair_scenes",
    "powers_of_ten",
    "rigid_motions",
    "sliver_scenes",
    "small_scenes",
    "triangle_scenes",
    "well_conditioned_scenes",
]

SEEDS = st.integers(0, 2**32 - 1)
"""Seeds of ``numpy.random.default_rng``."""

SIZES = st.integers(1, 8)
"""Number of queries per scene: small, since every query is judged exactly."""

Strategy = st.SearchStrategy


def powers_of_ten(low: int, high: int) -> Strategy[float]:
    """Draw ``10.0**k`` for an integer k in ``[low, high]``."""
    return st.integers(low, high).map(lambda k: 10.0**k)


def _scenes(generator: Callable[..., Any], n: Strategy[int], **params: Strategy) -> Strategy:
    # Positional-only, so that a generator parameter may reuse these names.
    def build(seed: int, size: int, /, **kwargs: Any) -> Any:
        return generator(np.random.default_rng(seed), size, **kwargs)

    return st.builds(build, SEEDS, n, **params)


def _or(strategy: Strategy | None, default: Strategy) -> Strategy:
    return default if strategy is None else strategy


# -- triangles -------------------------------------------------------------------


def well_conditioned_scenes(n: Strategy[int] = SIZES) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.well_conditioned`."""
    return _scenes(scenes.well_conditioned, n)


def near_surface_scenes(
    offset: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.near_surface`; `offset` defaults to 1e-15 to 1e-3."""
    return _scenes(scenes.near_surface, n, offset=_or(offset, powers_of_ten(-15, -3)))


def sliver_scenes(
    rel_height: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.sliver`; `rel_height` defaults to 1e-17 to 1e-6."""
    return _scenes(scenes.sliver, n, rel_height=_or(rel_height, powers_of_ten(-17, -6)))


def degenerate_scenes(
    kind: Strategy[str] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.degenerate`; `kind` defaults to any kind."""
    kinds = st.sampled_from(["collinear", "two_coincident", "all_coincident"])
    return _scenes(scenes.degenerate, n, kind=_or(kind, kinds))


def needle_scenes(
    rel_width: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.needle`; `rel_width` defaults to 1e-15 to 0.1."""
    return _scenes(scenes.needle, n, rel_width=_or(rel_width, powers_of_ten(-15, -1)))


def small_scenes(
    size: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.small`; `size` defaults to 1e-12 to 0.1."""
    return _scenes(scenes.small, n, size=_or(size, powers_of_ten(-12, -1)))


def offset_scenes(
    offset: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.offset`; `offset` defaults to 1e4 to 1e10."""
    return _scenes(scenes.offset, n, offset=_or(offset, powers_of_ten(4, 10)))


def far_points_scenes(
    ratio: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.far_points`; `ratio` defaults to 1e3 to 1e8."""
    return _scenes(scenes.far_points, n, ratio=_or(ratio, powers_of_ten(3, 8)))


def magnitude_scenes(
    scale: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.magnitude`; `scale` defaults to 1e-300 to 1e300."""
    return _scenes(scenes.magnitude, n, scale=_or(scale, powers_of_ten(-300, 300)))


def on_feature_scenes(
    kind: Strategy[str] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.TriangleScene]:
    """Scenes of `proximity.testing.scenes.on_feature`; `kind` defaults to any kind."""
    kinds = st.sampled_from(["vertex", "edge", "plane"])
    return _scenes(scenes.on_feature, n, kind=_or(kind, kinds))


def triangle_scenes(n: Strategy[int] = SIZES) -> Strategy[scenes.TriangleScene]:
    """Scenes of any triangle family, with its default parameter range."""
    return st.one_of(
        well_conditioned_scenes(n=n),
        near_surface_scenes(n=n),
        sliver_scenes(n=n),
        degenerate_scenes(n=n),
        needle_scenes(n=n),
        small_scenes(n=n),
        offset_scenes(n=n),
        far_points_scenes(n=n),
        magnitude_scenes(n=n),
        on_feature_scenes(n=n),
    )


# -- circles and disks ---------------------------------------------------------------


def disk_well_conditioned_scenes(n: Strategy[int] = SIZES) -> Strategy[scenes.DiskScene]:
    """Scenes of `proximity.testing.scenes.disk_well_conditioned`."""
    return _scenes(scenes.disk_well_conditioned, n)


def disk_axis_scenes(
    rel_distance: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.DiskScene]:
    """Scenes of `proximity.testing.scenes.disk_axis`; `rel_distance` defaults to 0 or 1e-300 to 1e-8."""
    default = st.one_of(st.just(0.0), powers_of_ten(-300, -8))
    return _scenes(scenes.disk_axis, n, rel_distance=_or(rel_distance, default))


def disk_rim_scenes(
    rel_distance: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.DiskScene]:
    """Scenes of `proximity.testing.scenes.disk_rim`; `rel_distance` defaults to 1e-13 to 1e-3."""
    return _scenes(scenes.disk_rim, n, rel_distance=_or(rel_distance, powers_of_ten(-13, -3)))


def disk_in_plane_scenes(n: Strategy[int] = SIZES) -> Strategy[scenes.DiskScene]:
    """Scenes of `proximity.testing.scenes.disk_in_plane`."""
    return _scenes(scenes.disk_in_plane, n)


def disk_offset_scenes(
    offset: Strategy[float] | None = None, n: Strategy[int] = SIZES
) -> Strategy[scenes.DiskScene]:
    """Scenes of `proximity.testing.scenes.disk_offset`; `offset` defaults to 1e4 to 1e10."""
    return _scenes(scenes.disk_offset, n, offset=_or(offset, powers_of_ten(4, 10)))


def disk_unnormalized_scenes(n: Strategy[int] = SIZES) -> Strategy[scenes.DiskScene]:
    """Scenes of `proximity.testing.scenes.disk_unnormalized`."""
    return _scenes(scenes.disk_unnormalized, n)


def disk_scenes(n: Strategy[int] = SIZES) -> Strategy[scenes.DiskScene]:
    """Scenes of any circle or disk family, with its default parameter range."""
    return st.one_of(
        disk_well_conditioned_scenes(n=n),
        disk_axis_scenes(n=n),
        disk_rim_scenes(n=n),
        disk_in_plane_scenes(n=n),
        disk_offset_scenes(n=n),
        disk_unnormalized_scenes(n=n),
    )


# -- pairs of shapes ---------------------------------------------------------------------


def _signed_gaps() -> Strategy[float]:
    """0, or plus or minus ``10**k`` for k in [-15, -1]."""
    signs = st.sampled_from([-1.0, 1.0])
    return st.one_of(st.just(0.0), st.builds(lambda s, g: s * g, signs, powers_of_ten(-15, -1)))


def pair_scenes(pair: str, n: Strategy[int] = SIZES) -> Strategy[scenes.PairScene]:
    """Scenes of any pair family of `proximity.testing.scenes` for `pair` (a key of `scenes.PAIRS`).

    Parameters are drawn from the families' ranges: contact gaps of 0 or
    ``+-1e-15`` to ``+-0.1``, near-parallel angles of 1e-16 to 1e-1, scales of
    1e-300 to 1e300, offsets of 1e3 to 1e10 and distance ratios of 1e2 to 1e9.
    """
    fixed = st.just(pair)
    return st.one_of(
        _scenes(scenes.pair_well_conditioned, n, pair=fixed),
        _scenes(scenes.pair_contact, n, pair=fixed, gap=_signed_gaps()),
        _scenes(scenes.pair_near_parallel, n, pair=fixed, angle=powers_of_ten(-16, -1)),
        _scenes(scenes.pair_parallel, n, pair=fixed, kind=st.sampled_from(["touching", "apart"])),
        _scenes(
            scenes.pair_degenerate,
            n,
            pair=fixed,
            kind=st.sampled_from(["point", "collinear", "two_coincident"]),
        ),
        _scenes(scenes.pair_magnitude, n, pair=fixed, scale=powers_of_ten(-300, 300)),
        _scenes(scenes.pair_offset, n, pair=fixed, offset=powers_of_ten(3, 10)),
        _scenes(scenes.pair_far, n, pair=fixed, ratio=powers_of_ten(2, 9)),
    )


# -- rigid motions ----------------------------------------------------------------------


class RigidMotion(NamedTuple):
    """A proper rotation followed by a translation.

    The rotation matrix is computed in float, so it is orthogonal only to
    within rounding (about 1e-16): invariance tests must allow for that.

    Attributes
    ----------
    rotation : ndarray of float64, shape (3, 3)
    translation : ndarray of float64, shape (3,)
    """

    rotation: np.ndarray
    translation: np.ndarray

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Move points of shape ``(..., 3)``: ``rotation @ x + translation``."""
        return np.asarray(points) @ self.rotation.T + self.translation

    def rotate(self, vectors: np.ndarray) -> np.ndarray:
        """Rotate directions of shape ``(..., 3)`` (normals), without translating."""
        return np.asarray(vectors) @ self.rotation.T


def _rotation(quaternion: tuple[float, float, float, float]) -> np.ndarray:
    w, x, y, z = np.array(quaternion) / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def rigid_motions(max_translation: float = 10.0) -> Strategy[RigidMotion]:
    """Random proper rigid motions.

    The rotation comes from a quaternion drawn in [-1, 1]**4 (away from zero,
    then normalized), which covers every rotation; the translation is uniform
    in ``[-max_translation, max_translation]**3``.
    """
    unit = st.floats(-1.0, 1.0, allow_nan=False)
    quaternions = st.tuples(unit, unit, unit, unit).filter(lambda q: np.linalg.norm(q) > 0.1)
    coordinate = st.floats(-max_translation, max_translation, allow_nan=False)
    return st.builds(
        RigidMotion,
        quaternions.map(_rotation),
        st.tuples(coordinate, coordinate, coordinate).map(np.array),
    )


# -- every family, by name ------------------------------------------------------------

TRIANGLE_FAMILIES = {
    "well_conditioned": well_conditioned_scenes(),
    "near_surface": near_surface_scenes(),
    "sliver": sliver_scenes(),
    "degenerate": degenerate_scenes(),
    "needle": needle_scenes(),
    "small": small_scenes(),
    "offset": offset_scenes(),
    "far_points": far_points_scenes(),
    "magnitude": magnitude_scenes(),
    "on_feature": on_feature_scenes(),
}
"""A strategy per triangle family, with its default parameter range."""

DISK_FAMILIES = {
    "well_conditioned": disk_well_conditioned_scenes(),
    "axis": disk_axis_scenes(),
    "rim": disk_rim_scenes(),
    "in_plane": disk_in_plane_scenes(),
    "offset": disk_offset_scenes(),
    "unnormalized": disk_unnormalized_scenes(),
}
"""A strategy per circle and disk family, with its default parameter range."""

PAIR_FAMILIES = {pair: pair_scenes(pair) for pair in scenes.PAIRS}
"""A strategy per pair of shapes (a key of `proximity.testing.scenes.PAIRS`), over every pair family."""
