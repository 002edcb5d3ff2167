"""Rigid transforms: the check that a 4x4 matrix is one, and points moved into and out of a pose.

A pose ``T = [[R, t], [0, 1]]`` is accepted as rigid when ``R`` is orthonormal within
:data:`RIGID_TOLERANCE` with determinant +1 (:func:`rigid`).  Points are moved with each
coordinate summed in one fixed order (:func:`to_local`, :func:`to_world`), the order the
compiled searches of posed shapes use, so that both give the same bits; the accuracy this
costs a query is in :mod:`proximity.shapes.posed`.
"""

import math

import numpy as np

from .._validate import as_float64, frozen

__all__ = ["RIGID_TOLERANCE", "pose_matrix", "rigid", "rotate", "to_local", "to_world"]

#: The largest ``max |R^T R - I|`` of a transform accepted as rigid.
RIGID_TOLERANCE = 1e-9


def to_local(points, rotation, translation):
    """``R^T (P - t)`` of ``(..., 3)`` points, summed in a fixed order (as the
    instanced search computes it, so that both give the same bits):
    ``x = d0 r00 + d1 r10 + d2 r20`` with ``d = P - t``, left to right.

    Each coordinate of ``d`` adds its terms to every output column in turn,
    so that a batch costs its output and two arrays of one coordinate, not
    a copy of every partial sum.
    """
    points, translation = np.asarray(points), np.asarray(translation)
    out = np.empty(np.broadcast_shapes(points.shape, translation.shape))
    d = np.empty(out.shape[:-1])
    term = np.empty(out.shape[:-1])
    for k in range(3):
        np.subtract(points[..., k], translation[..., k], out=d)
        for c in range(3):
            if k == 0:
                np.multiply(d, rotation[k, c], out=out[..., c])
            else:
                np.multiply(d, rotation[k, c], out=term)
                out[..., c] += term
    return out


def to_world(points, rotation, translation):
    """``R X + t`` of ``(..., 3)`` points, summed in a fixed order:
    ``x = (x0 r00 + x1 r01 + x2 r02) + t0``, left to right, as
    :func:`to_local` sums, with one array of one coordinate as scratch."""
    points, translation = np.asarray(points), np.asarray(translation)
    out = np.empty(np.broadcast_shapes(points.shape, translation.shape))
    term = np.empty(out.shape[:-1])
    for k in range(3):
        for c in range(3):
            if k == 0:
                np.multiply(points[..., k], rotation[c, k], out=out[..., c])
            else:
                np.multiply(points[..., k], rotation[c, k], out=term)
                out[..., c] += term
    out += translation
    return out


def rigid(transform, name="transform"):
    """``(R, t)`` of the rigid transforms ``transform``, ``(..., 4, 4)``, or a
    ValueError naming ``name``: not 4x4, not finite, a last row other than
    ``[0, 0, 0, 1]``, a rotation not orthonormal within
    :data:`RIGID_TOLERANCE`, or a determinant that is not +1 (a reflection)."""
    m = as_float64(transform, name, "(4, 4)")
    if m.shape == (4, 4):
        one = _rigid_one(m)
        if one is not None:
            return one
    if m.ndim < 2 or m.shape[-2:] != (4, 4):
        raise ValueError(f"{name} must be a 4x4 matrix; got shape {m.shape}")
    if not np.isfinite(m).all():
        raise ValueError(f"{name} must be finite")
    if not (m[..., 3, :] == (0.0, 0.0, 0.0, 1.0)).all():
        raise ValueError(f"{name} must have the last row [0, 0, 0, 1]; got {m[..., 3, :].tolist()}")
    r = m[..., :3, :3]
    error = np.abs(np.swapaxes(r, -1, -2) @ r - np.eye(3)).max(axis=(-1, -2), initial=0.0)
    if (error > RIGID_TOLERANCE).any():
        raise ValueError(
            f"{name} must be rigid: its rotation is orthonormal only to {float(np.max(error)):.3g} "
            f"(at most {RIGID_TOLERANCE:g})"
        )
    if (np.linalg.det(r) < 0).any():
        raise ValueError(f"{name} must be rigid, a rotation: its determinant is -1 (a reflection)")
    return frozen(np.ascontiguousarray(r), new=True), frozen(np.ascontiguousarray(m[..., :3, 3]), new=True)


def _rigid_one(m):
    """``(R, t)`` of one 4x4 transform that is certainly rigid, by checks in Python floats
    (faster than NumPy's on one matrix); None where a check fails or comes within half the
    tolerance of failing, for :func:`rigid`'s checks and messages to decide."""
    rows = m.tolist()
    if rows[3] != [0.0, 0.0, 0.0, 1.0] or not all(map(math.isfinite, rows[0] + rows[1] + rows[2])):
        return None
    (a, b, c, x), (d, e, f, y), (g, h, i, z) = rows[0], rows[1], rows[2]
    # max |R^T R - I|: the columns' dot products.
    error = max(
        abs(a * a + d * d + g * g - 1.0), abs(b * b + e * e + h * h - 1.0), abs(c * c + f * f + i * i - 1.0),
        abs(a * b + d * e + g * h), abs(a * c + d * f + g * i), abs(b * c + e * f + h * i),
    )  # fmt: skip
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if not error <= 0.5 * RIGID_TOLERANCE or det < 0.5:
        return None
    r = np.array(rows[:3])[:, :3]
    return frozen(np.ascontiguousarray(r), new=True), frozen(np.array([x, y, z]), new=True)


def rotate(vectors, rotation):
    """``R v`` of ``(..., 3)`` vectors, summed in a fixed order (:func:`to_world` without the
    translation): each row's bits are its own, whatever the batch."""
    v = np.asarray(vectors, dtype=np.float64)
    x = v[..., 0] * rotation[0, 0] + v[..., 1] * rotation[0, 1] + v[..., 2] * rotation[0, 2]
    y = v[..., 0] * rotation[1, 0] + v[..., 1] * rotation[1, 1] + v[..., 2] * rotation[1, 2]
    z = v[..., 0] * rotation[2, 0] + v[..., 1] * rotation[2, 1] + v[..., 2] * rotation[2, 2]
    return np.stack([x, y, z], axis=-1)


def pose_matrix(rotation, translation):
    """The 4x4 matrix ``[[R, t], [0, 1]]``."""
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, translation
    return pose
