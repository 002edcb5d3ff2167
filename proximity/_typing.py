"""Type aliases of the public API's annotations."""

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ArrayLike", "Bools", "Distances", "Floats", "Transform"]

#: A read-only array of float64.
Floats = NDArray[np.float64]
#: Distances of the broadcast shape; a NumPy scalar for one point against one shape.
Distances = NDArray[np.float64] | np.float64
#: Booleans of the broadcast shape; a NumPy scalar for one point.
Bools = NDArray[np.bool_] | np.bool_
#: A 4x4 rigid transform ``[[R, t], [0, 0, 0, 1]]`` (array_like).
Transform = ArrayLike
