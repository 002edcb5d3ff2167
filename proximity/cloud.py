"""``python -m proximity.cloud``: distances from a point cloud on disk to a mesh.

The command lives in :mod:`proximity.interop.cloud`; this module keeps its name.
"""

import sys

from .interop import cloud as _cloud

if __name__ == "__main__":
    sys.exit(_cloud.main())
else:
    sys.modules[__name__] = _cloud
