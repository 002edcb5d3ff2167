"""The backends by name: which libraries there are adapters for, which are installed, and a new one.

What :func:`proximity.adapters.get` and :func:`proximity.adapters.available` are, apart from the
package's face, so that :mod:`.crosscheck` (which asks every backend) need not import the face that
hands it on.
"""

import importlib

#: Backend name -> (module, class).  Modules import their library only when
#: a backend is created or :func:`available` probes for it.
_REGISTRY = {
    "fcl": ("fcl_backend", "FclBackend"),
    "trimesh": ("trimesh_backend", "TrimeshBackend"),
    "pybullet": ("pybullet_backend", "PybulletBackend"),
}

#: Every backend name, whether or not its library is installed here.
NAMES = tuple(_REGISTRY)


def _module(name):
    if name not in _REGISTRY:
        raise ValueError(f"unknown backend {name!r}; expected one of {NAMES}")
    return importlib.import_module(f".{_REGISTRY[name][0]}", __package__)


def available():
    """Names of the backends whose library can be imported here.

    Only ``ImportError`` counts as "not installed": any other error while
    importing a library propagates.

    Returns
    -------
    list of str
        A subset of :data:`NAMES`, in that order.

    Examples
    --------
    >>> import proximity.adapters as adapters
    >>> adapters.NAMES
    ('fcl', 'trimesh', 'pybullet')
    >>> set(adapters.available()) <= set(adapters.NAMES)
    True
    """
    names = []
    for name in NAMES:
        # The adapter module itself must import: only its library may be missing.
        module = _module(name)
        try:
            module.load()
        except ImportError:
            continue
        names.append(name)
    return names


def get(name, **options):
    """A new backend for library ``name``.

    Parameters
    ----------
    name : {"fcl", "trimesh", "pybullet"}
    **options
        Passed to the backend's constructor: ``rescale`` for every backend
        (default True: each query in a frame of its own; False: the
        caller's coordinates, the backend named ``<name>[raw]``), ``hull``
        for pybullet.

    Returns
    -------
    Backend
        With ``closest_point(shape, points, *, tol=None)``,
        ``closest_points(a, b)`` and ``distance(shape, points, *, tol=None)``
        (or ``distance(a, b)``).  Close it (or use it as a
        context manager) to release what the library holds; pybullet
        backends own a physics client.

    Raises
    ------
    ImportError
        If the library is not installed; the message names the extra to
        install: ``pip install '.[adapters]'`` in proximity's clone.
    ValueError
        For an unknown name.

    Examples
    --------
    >>> import proximity, proximity.adapters as adapters
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> with adapters.get("trimesh") as backend:
    ...     r = backend.distance(tri, [[0.2, 0.2, 1.0], [2.0, 0.0, 0.0]])
    >>> r.tolist()
    [1.0, 1.0]
    """
    module = _module(name)
    return getattr(module, _REGISTRY[name][1])(**options)
