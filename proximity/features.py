"""The features of a shape on which a closest point lies, and their codes.

A leaf of the package: the kernels compare the plain integer codes, the
results hold them as ``int8`` and name them through :class:`Feature`.
"""

import enum

import numpy as np


class Feature(enum.IntEnum):
    """The feature of a shape on which the closest point lies.

    Triangles use ``VERTEX0``-``VERTEX2``, ``EDGE01``, ``EDGE12``, ``EDGE20``
    and ``FACE``; disks ``FACE`` (the projection falls inside the disk) or
    ``RIM``; circles ``RIM``.  ``NONE`` marks rows with no answer (a point
    containing NaN or inf).  Feature arrays hold these codes as ``int8`` and
    compare equal to the members.

    Examples
    --------
    >>> import proximity
    >>> tri = proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> r = tri.closest_point([[2, 0, 0], [0.5, -1, 0], [0.2, 0.2, 1]])
    >>> r.feature.tolist(), [proximity.Feature(f).name for f in r.feature]
    ([1, 3, 6], ['VERTEX1', 'EDGE01', 'FACE'])
    >>> bool(r.feature[2] == proximity.Feature.FACE)
    True
    """

    NONE = -1
    VERTEX0 = 0
    VERTEX1 = 1
    VERTEX2 = 2
    EDGE01 = 3
    EDGE12 = 4
    EDGE20 = 5
    FACE = 6
    RIM = 7

    @classmethod
    def names(cls, codes):
        """The member names of an array of feature codes, as an array of str.

        Examples
        --------
        >>> import numpy as np, proximity
        >>> proximity.Feature.names(np.array([6, 0, -1], dtype=np.int8)).tolist()
        ['FACE', 'VERTEX0', 'NONE']
        >>> str(proximity.Feature.names(np.int8(7)))
        'RIM'
        """
        codes = np.asarray(codes)
        if codes.dtype.kind not in "iu":
            raise TypeError(f"codes must be an integer array; got dtype {codes.dtype}")
        if codes.size and (codes.min() < -1 or codes.max() >= len(_NAMES) - 1):
            raise ValueError(f"codes must be Feature codes, -1 to {len(_NAMES) - 2}")
        return _NAMES[codes.astype(np.intp) + 1]


_NAMES = np.array([f.name for f in sorted(Feature)])  # by code + 1
# One query's feature, by the code the kernels write in a row: a NumPy int8
# scalar, as the feature arrays of batches hold.
_FEATURES = {float(f): np.int8(f) for f in Feature}

# Plain integer codes, for the compiled kernels (which compare ints).
NONE = int(Feature.NONE)
VERTEX0 = int(Feature.VERTEX0)
VERTEX1 = int(Feature.VERTEX1)
VERTEX2 = int(Feature.VERTEX2)
EDGE01 = int(Feature.EDGE01)
EDGE12 = int(Feature.EDGE12)
EDGE20 = int(Feature.EDGE20)
FACE = int(Feature.FACE)
RIM = int(Feature.RIM)
