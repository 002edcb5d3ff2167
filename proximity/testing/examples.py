"""Example shapes of every kind of primitive, for the tests that run over the registry.

:func:`example` makes a shape of a kind of :data:`proximity.primitives.REGISTRY`
with any batch shape, every member distinct; the contract tests, the Numba
smoke test and the benchmarks' scenes take their shapes from here, so that
a new primitive is covered by adding its builder to :data:`BUILDERS`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

import proximity

from .. import primitives

_TRIANGLE = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
_SEGMENT = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.25]])


def _round(cls: type) -> Callable[..., proximity.Shape]:
    def build(offsets: np.ndarray, dim: int) -> proximity.Shape:
        batch = offsets.shape[:-1]
        center = np.zeros(batch + (3,)) + offsets
        return cls(center=center, normal=[0.0, 0.0, 1.0], radius=1.0 + offsets[..., 0])

    return build


#: Per kind: ``build(offsets, dim)``, a shape whose member ``i`` is offset by
#: ``offsets[i]`` (shape ``batch + (1,)``), and the dimensions it takes.
BUILDERS: dict[str, tuple[Callable[..., proximity.Shape], tuple[int, ...]]] = {
    "triangle": (lambda offsets, dim: proximity.Triangle(_TRIANGLE[:, :dim] + offsets[..., None]), (3, 2)),
    "disk": (_round(proximity.Disk), (3,)),
    "circle": (_round(proximity.Circle), (3,)),
    "segment": (lambda offsets, dim: proximity.Segment(_SEGMENT[:, :dim] + offsets[..., None]), (3, 2)),
    "point": (lambda offsets, dim: proximity.Point(_SEGMENT[1, :dim] + offsets), (3, 2)),
}


def kinds() -> list[tuple[str, int]]:
    """``(kind name, dimension)`` of every registered primitive and dimension it takes."""
    missing = set(primitives.REGISTRY) - set(BUILDERS)
    assert not missing, f"no example builder for {sorted(missing)}"
    return [(name, dim) for name in primitives.REGISTRY for dim in BUILDERS[name][1]]


def example(kind: str, batch: tuple[int, ...] = (), dim: int = 3) -> proximity.Shape:
    """A shape of primitive ``kind`` with batch shape ``batch``, every member distinct.

    Examples
    --------
    >>> from proximity.testing import examples
    >>> examples.example("disk", (4,)).batch_shape
    (4,)
    """
    count = int(np.prod(batch, dtype=int))
    offsets = np.arange(count, dtype=float).reshape(tuple(batch) + (1,))
    return BUILDERS[kind][0](offsets, dim)
