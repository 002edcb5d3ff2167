"""Meshes for tests and benchmarks: generators, query points and exact references.

Seeded where random: the same generator state gives the same mesh and points.
:func:`reference` and :func:`reference_inside` give each point's exact
distance and side, the yardsticks of the mesh tests and of the mesh
benchmark.
"""

import numpy as np

import proximity

EPS = 2.0**-52


def torus(n_major, n_minor, major=1.0, minor=0.35):
    """A closed torus of ``2 n_major n_minor`` triangles around the z axis.

    Returns ``(vertices (V, 3), faces (F, 3))``, faces oriented outwards.
    """
    u = 2.0 * np.pi * np.arange(n_major) / n_major
    v = 2.0 * np.pi * np.arange(n_minor) / n_minor
    uu, vv = np.meshgrid(u, v, indexing="ij")
    ring = major + minor * np.cos(vv)
    vertices = np.stack([ring * np.cos(uu), ring * np.sin(uu), minor * np.sin(vv)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    a = i * n_minor + j
    b = ((i + 1) % n_major) * n_minor + j
    c = ((i + 1) % n_major) * n_minor + (j + 1) % n_minor
    d = i * n_minor + (j + 1) % n_minor
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return vertices, faces


def icosphere(subdivisions, radius=1.0):
    """A sphere of ``20 * 4**subdivisions`` triangles, each edge split in two per level."""
    t = (1.0 + 5.0**0.5) / 2.0
    vertices = [
        [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
        [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
        [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1],
    ]  # fmt: skip
    faces = [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ]  # fmt: skip
    vertices = [np.array(v, dtype=np.float64) for v in vertices]

    def split(a, b, middle):
        key = (min(a, b), max(a, b))
        if key not in middle:
            middle[key] = len(vertices)
            vertices.append((vertices[a] + vertices[b]) / 2.0)
        return middle[key]

    for _ in range(subdivisions):
        middle = {}
        refined = []
        for a, b, c in faces:
            ab, bc, ca = split(a, b, middle), split(b, c, middle), split(c, a, middle)
            refined += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = refined
    v = np.array(vertices)
    v *= radius / np.linalg.norm(v, axis=1, keepdims=True)
    return v, np.array(faces, dtype=np.int64)


def soup(rng, n, size=0.2, degenerate=0.0):
    """``n`` independent triangles of about ``size`` in the unit cube, a fraction of them degenerate.

    Coordinates are multiples of ``2^-12``, so the degenerate ones are
    exactly so: collinear (``V2 = V0 + 2 (V1 - V0)``), two coincident
    vertices, or all three coincident, in turn.  Returns ``(vertices (3n, 3),
    faces (n, 3))``.
    """
    grid = 2.0**-12
    v0 = np.round(rng.uniform(0.0, 1.0, (n, 3)) / grid) * grid
    v1 = v0 + np.round(rng.normal(0.0, size, (n, 3)) / grid) * grid
    v2 = v0 + np.round(rng.normal(0.0, size, (n, 3)) / grid) * grid
    bad = np.flatnonzero(rng.uniform(size=n) < degenerate)
    kind = np.arange(len(bad)) % 3
    v2[bad[kind == 0]] = v0[bad[kind == 0]] + 2.0 * (v1[bad[kind == 0]] - v0[bad[kind == 0]])
    v1[bad[kind == 1]] = v0[bad[kind == 1]]
    v1[bad[kind == 2]] = v0[bad[kind == 2]]
    v2[bad[kind == 2]] = v0[bad[kind == 2]]
    vertices = np.stack([v0, v1, v2], axis=1).reshape(-1, 3)
    return vertices, np.arange(3 * n).reshape(n, 3)


def near_points(rng, vertices, faces, n, offset):
    """``n`` points on the surface (area-weighted), moved along the face normal by ``N(0, offset)``."""
    tri = vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(normal, axis=1)
    face = rng.choice(len(faces), size=n, p=area / area.sum())
    r1, r2 = rng.uniform(size=(2, n))
    s = np.sqrt(r1)
    weights = np.stack([1.0 - s, s * (1.0 - r2), s * r2], axis=1)
    on = np.einsum("ni,nij->nj", weights, tri[face])
    unit = normal[face] / area[face, None]
    return on + unit * rng.normal(0.0, offset, (n, 1))


def box_points(rng, vertices, n):
    """``n`` points uniform in the bounding box of the vertices."""
    return rng.uniform(vertices.min(axis=0), vertices.max(axis=0), size=(n, 3))


def reference(vertices, faces, points):
    """``[(d_exact, S)]`` per point: the exact distance to the mesh and the nearest face's scale.

    ``robust`` is within ``8 eps S`` of each face's exact distance, and a
    face's ``S`` is at most its distance plus its longest edge ``L``, so only
    faces whose ``robust`` distance is within ``16 eps (d_min + L_max)`` of
    the least can hold the exact minimum; those are evaluated exactly (with
    a factor 2 to spare).
    """
    from . import exact  # needs mpmath

    tri = vertices[faces]
    longest = float(np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=-1)))
    every_face = proximity.Triangle(tri)
    out = []
    for p in points:
        d = every_face.distance(p)
        least = float(np.min(d))
        candidates = np.flatnonzero(d <= least + 32.0 * EPS * (least + longest))
        face = min(candidates, key=lambda f: exact.triangle_sqr_distance(tri[f], p))
        out.append((exact.triangle_distance(tri[face], p), exact.triangle_scale(tri[face], p)))
    return out


def reference_inside(kind, size, vertices, faces, points):
    """Whether each point is inside the solid, known from the solid itself.

    The icosphere is convex with its vertices on the unit sphere: a point
    beyond radius 1 is outside, one within the least distance from the
    centre to a face's plane is inside.  The torus's vertices are on the
    torus of radii 1 and 0.35, and its faces stray from it by less than
    their sagittas: a point farther than twice that from the analytic torus
    is on the side the analytic torus says.  The points in between (few)
    are decided by the generalized winding number over every face.

    Returns ``(inside, by_winding)``, boolean arrays.
    """
    from ..signs import signed

    if kind == "icosphere":
        tri = vertices[faces]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        inradius = np.min(np.einsum("ij,ij->i", normal, tri[:, 0]) / np.linalg.norm(normal, axis=1))
        radius = np.linalg.norm(points, axis=1)
        inside = radius < inradius * (1 - 1e-12)
        doubt = ~inside & (radius <= 1 + 1e-12)
    else:
        n_major, n_minor = size
        stray = 1.35 * (1 - np.cos(np.pi / n_major)) + 0.35 * (1 - np.cos(np.pi / n_minor))
        ring = np.hypot(points[:, 0], points[:, 1]) - 1.0
        analytic = np.hypot(ring, points[:, 2]) - 0.35
        inside = analytic < 0
        doubt = np.abs(analytic) <= 2 * stray
    rows = np.flatnonzero(doubt)
    if len(rows):
        mesh = proximity.TriangleMesh(vertices, faces, broad_phase="brute")
        inside[rows] = signed.winding_numbers(mesh.vertices, mesh.faces, points[rows]) > 0.5
    return inside, doubt


#: ``(label, kind, size)`` of the meshes the peers are compared on: trimesh's
#: icospheres of ``subdivisions`` (20 * 4^size faces) and :func:`torus`.
PEER_MESHES = {
    False: (("icosphere, 20,480 faces", "icosphere", 5), ("icosphere, 1,310,720 faces", "icosphere", 8),
            ("torus, 1,000,000 faces", "torus", (1000, 500))),
    True: (("icosphere, 1,280 faces", "icosphere", 3), ("icosphere, 20,480 faces", "icosphere", 5),
           ("torus, 20,000 faces", "torus", (100, 100))),
}  # fmt: skip


#: A point nearer the surface than this fraction of the mesh's size may get either sign.
SIGN_BAND = 1e-9


def peer_mesh(kind, size):
    """``(vertices, faces)`` of a mesh of :data:`PEER_MESHES`."""
    if kind == "torus":
        return torus(*size)
    try:
        import trimesh
    except ImportError:
        return icosphere(size)
    sphere = trimesh.creation.icosphere(subdivisions=size)
    return np.ascontiguousarray(sphere.vertices, dtype=np.float64), np.ascontiguousarray(
        sphere.faces, np.int64
    )


def box(lower, upper):
    """A closed box of 12 faces between corners ``lower`` and ``upper``, faces oriented outwards."""
    lo, hi = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
    vertices = np.array([[(lo, hi)[x][0], (lo, hi)[y][1], (lo, hi)[z][2]] for x in (0, 1) for y in (0, 1)
                         for z in (0, 1)])  # fmt: skip
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])  # fmt: skip
    return vertices, faces


def _join(*meshes):
    vertices, faces, offset = [], [], 0
    for v, f in meshes:
        vertices.append(v)
        faces.append(np.asarray(f) + offset)
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(faces)


def defective():
    """Meshes whose signs go wrong in common ways, ``{name: (vertices, faces)}``.

    ``overlapping boxes``
        Two closed boxes that overlap (as in assemblies and game assets).
    ``nested shells``
        A sphere inside another, both facing outwards.
    ``pushed octahedron``
        An octahedron with its top vertex pushed through the bottom: it
        intersects itself, and the region below is wound -1.
    ``internal sheet``
        A box with a double-sided square sheet inside, the sheet's two
        sides on vertices of their own (closed and manifold by index).
    ``inverted``
        A sphere with every face reversed.
    ``split seams``
        A box whose faces each have vertices of their own, as textured
        files load.
    ``zero-area face``
        A box whose edge from ``(-1, -1, -1)`` to ``(-1, -1, 1)`` is split at
        a point of it by a collinear face of zero area, listed first.
    ``cavity``
        A sphere with a smaller one inside facing inwards: a valid solid
        (a hollow ball).
    ``open``
        A sphere with four faces missing.
    """
    sphere_v, sphere_f = icosphere(2)
    out = {}
    out["overlapping boxes"] = _join(box([-1, -1, -1], [1, 1, 1]), box([0.25, 0.5, -0.6], [2.0, 1.75, 0.45]))
    out["nested shells"] = _join((sphere_v, sphere_f), (0.5 * sphere_v, sphere_f))
    octa_v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    octa_f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                       [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])  # fmt: skip
    pushed = octa_v.copy()
    pushed[4] = [0.6, 0.1, -0.8]
    out["pushed octahedron"] = (pushed, octa_f)
    sheet_v = np.array([[-0.5, -0.5, 0.1], [0.5, -0.5, 0.1], [0.5, 0.5, 0.1], [-0.5, 0.5, 0.1]])
    out["internal sheet"] = _join(box([-1, -1, -1], [1, 1, 1]), (sheet_v, [[0, 1, 2], [0, 2, 3]]),
                                  (sheet_v, [[0, 2, 1], [0, 3, 2]]))  # fmt: skip
    out["inverted"] = (sphere_v, sphere_f[:, ::-1].copy())
    bv, bf = box([-1, -1, -1], [1, 1, 1])
    out["split seams"] = (bv[bf].reshape(-1, 3), np.arange(3 * len(bf)).reshape(-1, 3))
    # Edge (0, 1) of the box, from (-1, -1, -1) to (-1, -1, 1), is in faces 0 (0, 1, 3)
    # and 5 (0, 5, 1); vertex 8 splits it, face 5 becomes (0, 5, 8) and (8, 5, 1), and the
    # zero-area face (0, 8, 1) closes the surface.
    zv = np.vstack([bv, [[-1.0, -1.0, -0.2378146699592699]]])
    zf = [list(face) for face in bf]
    zf[5:6] = [[0, 5, 8], [8, 5, 1]]
    out["zero-area face"] = (zv, np.array([[0, 8, 1]] + zf))
    out["cavity"] = _join((sphere_v, sphere_f), (0.5 * sphere_v, sphere_f[:, ::-1]))
    out["open"] = (sphere_v, sphere_f[4:])
    return out
