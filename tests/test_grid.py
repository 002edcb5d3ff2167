"""Signed distance grids: signed_distance at every grid point, bit for bit, and the band."""

import warnings

import numpy as np
import pytest

from proximity import TriangleMesh
from proximity.testing.meshes import defective, torus


def _grid_points(lower, upper, shape):
    axes = [np.linspace(lower[a], upper[a], shape[a]) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _banded(values, band):
    return np.where(np.abs(values) > band, np.copysign(np.inf, values), values)


@pytest.mark.parametrize("sign", ["auto", "winding"])
def test_grids_are_the_signed_distance_at_their_points(sign):
    mesh = TriangleMesh(*torus(40, 20))
    lower, upper, shape = [-1.5, -1.4, -0.5], [1.5, 1.4, 0.6], (40, 37, 19)
    expected = mesh.signed_distance(_grid_points(lower, upper, shape), sign=sign).reshape(shape)
    grid = mesh.sdf_grid(lower, upper, shape, sign=sign)
    assert grid.shape == shape and grid.dtype == np.float64 and grid.flags.writeable
    np.testing.assert_array_equal(grid, expected)
    for band in (0.0, 0.04, 0.3, np.inf):
        banded = mesh.sdf_grid(lower, upper, shape, max_distance=band, sign=sign)
        np.testing.assert_array_equal(banded, _banded(expected, band))
    assert np.isinf(mesh.sdf_grid(lower, upper, shape, max_distance=0.04)).mean() > 0.7


def test_the_band_skips_the_far_points(monkeypatch):
    mesh = TriangleMesh(*torus(40, 20))
    queried = []
    distance = TriangleMesh.distance

    def counted(self, points, **kwargs):
        queried.append(len(np.asarray(points).reshape(-1, 3)))
        return distance(self, points, **kwargs)

    monkeypatch.setattr(TriangleMesh, "distance", counted)
    shape = (64, 64, 24)
    mesh.sdf_grid([-2, -2, -0.7], [2, 2, 0.7], shape, max_distance=0.05, sign="winding")
    assert sum(queried) < 0.6 * np.prod(shape)


def test_grids_of_meshes_that_are_not_solids_and_not_closed():
    for name, sign in (("nested shells", "auto"), ("open", "winding")):
        mesh = TriangleMesh(*defective()[name])
        lower, upper, shape = [-1.2, -1.1, -1.3], [1.2, 1.1, 1.0], (17, 9, 12)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            expected = mesh.signed_distance(_grid_points(lower, upper, shape), sign=sign).reshape(shape)
            np.testing.assert_array_equal(mesh.sdf_grid(lower, upper, shape, sign=sign), expected)
            banded = mesh.sdf_grid(lower, upper, shape, max_distance=0.1, sign=sign)
        np.testing.assert_array_equal(banded, _banded(expected, 0.1))


def test_degenerate_grids_and_bad_arguments():
    mesh = TriangleMesh(*torus(16, 8))
    one = mesh.sdf_grid([1.0, 0.0, 0.0], [1.0, 0.0, 0.0], (1, 1, 1))
    assert one.shape == (1, 1, 1) and one[0, 0, 0] == mesh.signed_distance([1.0, 0.0, 0.0])
    line = mesh.sdf_grid([0, 0, 0], [2, 0, 0], (5, 1, 1))
    expected = mesh.signed_distance(_grid_points([0, 0, 0], [2, 0, 0], (5, 1, 1)))
    np.testing.assert_array_equal(line[:, 0, 0], expected)
    with pytest.raises(ValueError, match="shape must be 3 integers"):
        mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 0, 2))
    with pytest.raises(ValueError, match="lower must not exceed upper"):
        mesh.sdf_grid([0, 0, 2], [1, 1, 1], (2, 2, 2))
    with pytest.raises(ValueError, match="upper must be 3 finite"):
        mesh.sdf_grid([0, 0, 0], [1, np.nan, 1], (2, 2, 2))
    with pytest.raises(ValueError, match="max_distance must be"):
        mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 2, 2), max_distance=-1.0)
    with pytest.raises(TypeError, match="max_distance must be a number or None; got str 'x'"):
        mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 2, 2), max_distance="x")
    with pytest.raises(ValueError, match="sign must be one of"):
        mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 2, 2), sign="parity")
    with pytest.raises(TypeError, match="keyword-only"):
        mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 2, 2), 0.1)
