"""A mesh's topology by position: vertices merged where their coordinates are equal, and closedness."""

import numpy as np


def merged_faces(vertices, faces):
    """``faces`` with each vertex replaced by the lowest-indexed vertex at the same position."""
    # + 0.0 makes -0.0 the same point as 0.0.
    _, first, inverse = np.unique(vertices + 0.0, axis=0, return_index=True, return_inverse=True)
    return first[inverse.reshape(-1)][faces]


def unbalanced(faces):
    """``None`` if every edge is run equally often both ways (self-loops ignored), else why not."""
    n = int(faces.max()) + 1
    start = faces.reshape(-1)
    end = faces[:, [1, 2, 0]].reshape(-1)
    keep = np.flatnonzero(start != end)
    a, b = start[keep], end[keep]
    key = np.minimum(a, b) * n + np.maximum(a, b)
    forward = np.where(a < b, 1, -1)
    keys, group = np.unique(key, return_inverse=True)
    net = np.bincount(group.reshape(-1), forward, len(keys))
    bad = np.flatnonzero(net != 0)
    if len(bad) == 0:
        return None
    sides = keep[np.flatnonzero(group.reshape(-1) == bad[0])]
    lo, hi = int(keys[bad[0]] // n), int(keys[bad[0]] % n)
    ahead = [s for s in sides if start[s] == lo]
    back = [s for s in sides if start[s] == hi]
    major, minor = (ahead, back) if len(ahead) > len(back) else (back, ahead)
    u, v = int(start[major[0]]), int(end[major[0]])
    if len(major) >= 2:
        return (
            f"faces {major[0] // 3} and {major[1] // 3} both run edge ({u}, {v}) from {u} to {v}, and fewer "
            f"faces run it back: more than two faces meet there, or the faces' orientations disagree"
        )
    return (
        f"edge ({u}, {v}) of face {major[0] // 3} has no face running it from {v} to {u}: the surface has a "
        "boundary there (a hole), or the face on the other side has the opposite orientation"
    )
