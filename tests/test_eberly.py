"""Eberly's algorithm as written in his document: faithful to the listings, and failing where documented."""

import numpy as np
import pytest
from numba import njit

from proximity import Triangle
from proximity.point import triangle as point_triangle
from proximity.testing import scenes


@njit(error_model="numpy")
def _both(rows):
    out = np.empty((rows.shape[0], 6))
    for k in range(rows.shape[0]):
        x = rows[k]
        literal = point_triangle.eberly(
            x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9], x[10], x[11]
        )
        select = point_triangle.eberly_select(
            x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9], x[10], x[11]
        )
        out[k, 0], out[k, 1], out[k, 2] = literal
        out[k, 3], out[k, 4], out[k, 5] = select
    return out


def test_select_form_is_bit_identical_to_the_listings():
    """The vectorised form performs the listings' operations, so its bits match."""
    rng = np.random.default_rng(7)
    n = 200_000
    b, e0, e1, p = (rng.normal(size=(n, 3)) for _ in range(4))
    e1[: n // 8] = 2.0 * e0[: n // 8]  # collinear
    e1[n // 8 : n // 4] = e0[n // 8 : n // 4] * (1 + 1e-12)  # slivers
    e0[n // 4 : 5 * n // 16] = 0.0  # coincident vertices
    grid = slice(3 * n // 8, n // 2)  # small integers: exact ties on every boundary
    for a in (b, e0, e1, p):
        a[grid] = rng.integers(-2, 3, size=a[grid].shape)
    out = _both(np.concatenate([b, e0, e1, p], axis=1))
    literal, select = out[:, :3], out[:, 3:]
    same = (literal.view(np.int64) == select.view(np.int64)) | (np.isnan(literal) & np.isnan(select))
    assert same.all(), np.argwhere(~same.all(axis=1))[:5].ravel()
    # The inputs reach every outcome, NaN included.
    assert np.isnan(literal[:, 0]).any()
    assert set(np.unique(literal[:, 2]).astype(int)) >= set(range(7))


@pytest.mark.parametrize("kind", ["two_coincident", "all_coincident"])
def test_nan_on_triangles_with_coincident_vertices(kind):
    """det = 0 puts every query in region 0, where 0 / 0 is NaN (documented, not patched)."""
    scene = scenes.degenerate(np.random.default_rng(1), 500, kind)
    assert np.isnan(Triangle(scene.vertices).distance(scene.points, method="eberly")).all()
    assert np.isfinite(Triangle(scene.vertices).distance(scene.points)).all()


def test_collinear_triangles_fail_often():
    """On collinear triangles rounding leaves det slightly off zero in some
    queries; the rest are NaN.  The robust method answers every one."""
    scene = scenes.degenerate(np.random.default_rng(2), 2000, "collinear")
    d = Triangle(scene.vertices).distance(scene.points, method="eberly")
    assert 0.1 < np.isnan(d).mean() < 0.9
    assert np.isfinite(Triangle(scene.vertices).distance(scene.points)).all()
