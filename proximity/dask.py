"""``proximity.dask``: queries mapped over Dask arrays of points, chunk by chunk.

The functions live in :mod:`proximity.interop.dask`; importing this module gives that one.
"""

import sys

from .interop import dask as _dask

sys.modules[__name__] = _dask
