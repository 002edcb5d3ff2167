"""What the tests and the benchmarks share: the exact reference and the scene generators.

:mod:`proximity.testing.exact`
    Closest points in rational arithmetic on the floats' exact binary
    values, the yardstick every method is judged by (needs ``mpmath``,
    from the ``test`` extra).
:mod:`proximity.testing.scenes`
    Seeded generators of the adversarial scene families (slivers, needles,
    degenerate triangles, huge offsets, points on a circle's axis, ...).
:func:`example`
    The path of a mesh file installed with the package (``"torus.stl"``), for
    examples that read a file, from any directory.
"""

from importlib import resources

__all__ = ["example"]


def example(name):
    """The path (a str) of the example file ``name`` installed with the package.

    Examples
    --------
    >>> import proximity.testing
    >>> proximity.testing.example("torus.stl").endswith("torus.stl")
    True
    """
    path = resources.files(__name__) / "data" / name
    if not path.is_file():
        available = sorted(p.name for p in (resources.files(__name__) / "data").iterdir())
        raise ValueError(f"name must be one of {available}; got {name!r}")
    return str(path)
