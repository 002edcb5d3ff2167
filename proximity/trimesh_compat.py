"""``proximity.trimesh_compat``: drop-ins for trimesh's proximity functions.

The functions live in :mod:`proximity.interop.trimesh_compat`; importing this module gives that one.
"""

import sys

from .interop import trimesh_compat as _trimesh_compat

sys.modules[__name__] = _trimesh_compat
