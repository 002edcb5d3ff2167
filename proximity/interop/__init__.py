"""Other libraries and other scales: trimesh drop-ins, Dask arrays, the point-cloud command.

:mod:`.trimesh_compat`
    Drop-ins for trimesh's proximity functions (``proximity.trimesh_compat``).
:mod:`.dask`
    Queries mapped over Dask arrays of points (``proximity.dask``).
:mod:`.cloud`
    ``python -m proximity.cloud``: a point cloud on disk through a mesh, in bounded memory.

The public names above are modules at the package's root that hand these on. It may import
everything of the package but the root's face (``proximity/__init__.py``); nothing imports it
but that face.
"""
