"""Meshes and scenes against each other: the simultaneous descent against brute force and the exact minimum.

For every pair of small meshes here the answer is compared with the
minimum over all pairs of faces: bit for bit with the same method's
answers of every pair (brute force over a batch of all face pairs), and
against the exact minimum (rational arithmetic on the float inputs, over
the face pairs that could hold it): ``robust`` within ``16 eps S``,
``certified`` within one ulp.
"""

from fractions import Fraction

import mpmath
import numpy as np
import pytest

import proximity
from proximity.pair import fast as pair_fast
from proximity.pair import queries as pair_queries
from proximity.results import asdict
from proximity.testing import exact, meshes

EPS = 2.0**-52


def _rotation(rng):
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def _posed(vertices, pose):
    """Vertices posed as the descent poses them: ``((r0 x + r1 y) + r2 z) + t``."""
    x, y, z = vertices[:, 0], vertices[:, 1], vertices[:, 2]
    rows = [((pose[r, 0] * x + pose[r, 1] * y) + pose[r, 2] * z) + pose[r, 3] for r in range(3)]
    return np.stack(rows, axis=1)


SPHERE = meshes.icosphere(1, radius=0.8)  # 80 faces
TORUS = meshes.torus(8, 6)  # 96 faces


def _pose(rng, gap):
    """A random pose of the torus whose robust distance to the sphere is about ``gap`` (< 0: overlapping)."""
    rotation, u = _rotation(rng), rng.normal(size=3)
    u /= np.linalg.norm(u)
    sphere = proximity.TriangleMesh(*SPHERE)
    torus = proximity.TriangleMesh(*TORUS)
    t = 3.0 * u
    for _ in range(40):
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = rotation, t
        d = float(pair_queries.distance(sphere, torus, pose_b=pose))
        t = t + (max(gap, 1e-3) - d) * u
    if gap < 0:
        pose[:3, 3] = t + gap * u
    return pose


def _brute(va, fa, vb, fb, method):
    """Every face pair's answer: ``(distances (Fa, Fb), result)``."""
    a = proximity.Triangle(va[fa][:, None])
    b = proximity.Triangle(vb[fb][None, :])
    r = proximity.closest_points(a, b, method=method)
    return r.distance, r


def _exact_minimum(va, fa, vb, fb, robust):
    """The exact minimum over all face pairs: only pairs within twice the robust bound of the
    least robust distance can hold it."""
    scale = max(np.ptp(np.concatenate([va, vb]), axis=0))
    bound = 16 * EPS * 2 * scale + 2.0**-1070
    rows = np.argwhere(robust <= robust.min() + 2 * bound)
    best = None
    for i, j in rows:
        ref = exact.triangle_triangle_closest(va[fa[i]], vb[fb[j]])
        if best is None or ref.sqr_distance < best:
            best = ref.sqr_distance
    with mpmath.workprec(exact.PREC):
        return mpmath.sqrt(exact.to_mpf(best)), scale


CASES = [(seed, gap) for seed, gap in ((0, 0.3), (1, 1e-3), (2, 1e-6), (3, 0.05), (4, -0.05))]


@pytest.mark.parametrize(("seed", "gap"), CASES)
def test_mesh_mesh_is_the_least_face_pair(seed, gap):
    pose = _pose(np.random.default_rng(seed), gap)
    va, fa = SPHERE
    vb, fb = _posed(TORUS[0], pose), TORUS[1]
    sphere = proximity.TriangleMesh(va, fa)
    torus = proximity.TriangleMesh(vb, fb)
    robust, pairs = _brute(va, fa, vb, fb, "robust")
    d_exact, scale = _exact_minimum(va, fa, vb, fb, robust)
    for method in ("robust", "certified"):
        r = proximity.closest_points(sphere, torus, method=method)
        torus0 = proximity.TriangleMesh(*TORUS)
        posed = pair_queries.closest_points(sphere, torus0, method=method, pose_b=pose)
        if method == "robust":
            # The least face pair's answer, or exactly 0 where that answer is within
            # rounding of 0 and the meshes certainly intersect.
            touching = r.distance == 0.0 and 0.0 < robust.min() <= 64 * EPS * np.abs(vb).max()
            assert r.distance == robust.min() or (touching and d_exact == 0)
            assert exact.error_in_units(float(r.distance), d_exact, scale) <= 16
        else:
            assert exact.ulps(float(r.distance), d_exact) < 1.0
        # Posing the torus on the fly gives the bits of the torus built from posed vertices; where
        # they overlap, the search stops at the first common point, which depends on the trees.
        names = ("distance", "point_a", "point_b", "face_a", "face_b", "feature_a", "feature_b")
        for name in names if r.distance > 0 else ("distance",):
            np.testing.assert_array_equal(getattr(posed, name), getattr(r, name), err_msg=name)
        if r.distance > 0:
            # The lowest pair of faces at that distance, with its own answer.
            i, j = np.argwhere(robust == robust.min())[0] if method == "robust" else (r.face_a, r.face_b)
            assert (r.face_a, r.face_b) == (i, j)
            np.testing.assert_array_equal(r.point_a, pairs.point_a[i, j] if method == "robust" else r.point_a)
        else:
            # Overlapping: a point of the intersection on both.
            np.testing.assert_array_equal(r.point_a, r.point_b)
            assert sphere.distance(r.point_a) <= 4 * EPS and torus.distance(r.point_a) <= 8 * EPS
        assert np.linalg.norm(r.point_a - r.point_b) == pytest.approx(float(r.distance), abs=1e-15)
        assert sphere.distance(r.point_a) <= 8 * EPS and torus.distance(r.point_b) <= 8 * EPS


def test_brute_force_and_hierarchies_agree():
    rng = np.random.default_rng(9)
    va, fa = meshes.icosphere(2)
    vb, fb = _posed(TORUS[0], _pose(rng, 0.02)), TORUS[1]
    answers = []
    for bp_a, bp_b in (("bvh", "bvh"), ("brute", "bvh"), ("bvh", "brute"), ("brute", "brute")):
        a = proximity.TriangleMesh(va, fa, broad_phase=bp_a)
        b = proximity.TriangleMesh(vb, fb, broad_phase=bp_b)
        r = proximity.closest_points(a, b)
        answers.append((float(r.distance), int(r.face_a), int(r.face_b), r.point_a.tolist()))
        if r.distance == 0:
            # Intersecting: the search stops at the first common point, which depends on the trees.
            np.testing.assert_array_equal(r.point_a, r.point_b)
            assert a.distance(r.point_a) <= 4 * EPS and b.distance(r.point_a) <= 8 * EPS
    assert all(x == answers[0] for x in answers) or all(x[0] == 0 for x in answers)


def test_a_batch_of_primitives_against_a_mesh():
    rng = np.random.default_rng(4)
    torus = proximity.TriangleMesh(*TORUS)
    tris = proximity.Triangle(rng.normal(size=(7, 3, 3)) * 0.3 + rng.normal(size=(7, 1, 3)))
    segs = proximity.Segment(rng.normal(size=(2, 1, 2, 3)))
    for shapes in (tris, segs):
        r = proximity.closest_points(shapes, torus)
        s = proximity.closest_points(torus, shapes)
        assert r.distance.shape == shapes.batch_shape
        for index in np.ndindex(*shapes.batch_shape):
            one = shapes[index]
            many = type(one)(np.broadcast_to(one.vertices, (len(TORUS[1]),) + one.vertices.shape))
            faces = proximity.Triangle(TORUS[0][TORUS[1]])
            # Each order against its own brute force: a robust pair need not be symmetric to the bit.
            brute, brute_swapped = proximity.distance(many, faces), proximity.distance(faces, many)
            if r.distance[index] == 0 and brute.min() > 0:
                # Intersecting, certainly: exactly 0 where the pair computes to rounding of 0.
                assert brute.min() <= 64 * EPS * 4 and proximity.distance(one, torus, method="certified") == 0
                assert s.distance[index] == 0
                continue
            assert r.distance[index] == brute.min() and s.distance[index] == brute_swapped.min()
            assert r.face_b[index] == np.argmin(brute) and s.face_a[index] == np.argmin(brute_swapped)
    points = proximity.Point(rng.normal(size=(5, 3)))
    r = proximity.closest_points(points, torus, method="certified")
    np.testing.assert_array_equal(r.distance, torus.distance(points.position, method="certified"))


def test_scenes_pair_every_kind_they_hold():
    rng = np.random.default_rng(6)
    tris = proximity.Triangle(rng.normal(size=(6, 3, 3)))
    segs = proximity.Segment(rng.normal(size=(5, 2, 3)) + [3, 0, 0])
    points = proximity.Point(rng.normal(size=(4, 3)) + [0, 3, 0])
    scene = proximity.Scene([tris, segs, points], broad_phase="bvh")
    mesh = proximity.TriangleMesh(*SPHERE)
    offset = np.eye(4)
    offset[:3, 3] = [1.5, 1.5, 4.0]
    for other in (mesh, proximity.Scene([proximity.Segment(rng.normal(size=(9, 2, 3)) + [1, 1, 4])])):
        r = pair_queries.closest_points(scene, other, pose_b=offset)
        # Brute force over every pair of primitives, posed by hand.
        best = (np.inf, -1, -1)
        kinds, params = other._rows()
        for k in range(len(kinds)):
            prim = params[k, : 9 if kinds[k] == 0 else 6].reshape(-1, 3)
            moved = _posed(prim, offset)
            shape_b = proximity.Triangle(moved) if len(moved) == 3 else proximity.Segment(moved)
            for j, shape_a in enumerate([tris[i] for i in range(6)] + [segs[i] for i in range(5)]
                                        + [points[i] for i in range(4)]):  # fmt: skip
                d = float(proximity.distance(shape_a, shape_b))
                if (d, j, k) < best:
                    best = (d, j, k)
        assert r.distance == best[0]
        source = np.searchsorted(scene.offsets, best[1], side="right") - 1
        assert (r.primitive_a, r.source_a) == (best[1], source)
        assert (r.face_b if hasattr(other, "faces") else r.primitive_b) == best[2]


def test_rounded_collections_and_max_distance():
    torus = proximity.TriangleMesh(*TORUS)
    far = np.eye(4)
    far[:3, 3] = [0, 0, 3.0]
    sphere = proximity.TriangleMesh(*SPHERE)
    d = float(pair_queries.distance(sphere, torus, pose_b=far))
    shell = sphere.inflated(0.25)
    assert pair_queries.signed_distance(shell, torus, pose_b=far) == pytest.approx(d - 0.25, abs=4 * EPS)
    ball = proximity.Sphere([0, 0, 0], 2.5)
    assert float(proximity.signed_distance(ball, torus)) == pytest.approx(
        float(proximity.distance(proximity.Point([0, 0, 0]), torus)) - 2.5, abs=4 * EPS
    )
    r = pair_queries.closest_points(sphere, torus, pose_b=far, max_distance=d / 2)
    assert r.distance == np.inf and r.face_a == -1 and np.isnan(r.point_a).all()
    within = pair_queries.closest_points(sphere, torus, pose_b=far, max_distance=2 * d)
    full = pair_queries.closest_points(sphere, torus, pose_b=far)
    for name in ("distance", "point_a", "point_b", "face_a", "face_b"):
        np.testing.assert_array_equal(getattr(within, name), getattr(full, name))
    spheres = proximity.Scene([proximity.Sphere([[0, 0, 2.0], [0, 0, 1.2]], [0.5, 0.1])])
    r = proximity.closest_points(spheres, sphere)
    assert r.primitive_a == 1 and r.distance == pytest.approx(float(sphere.distance([0, 0, 1.2])) - 0.1)


def _exact_core_distance(a, b):
    """The exact distance (mpmath) between two cores, each ``(n, 3)`` vertices: a point, a
    segment or a triangle."""
    a, b = (np.asarray(x, np.float64).reshape(-1, 3) for x in (a, b))
    if len(a) > len(b):
        a, b = b, a
    if len(a) == 1:
        if len(b) == 1:
            sqr = sum((Fraction(x) - Fraction(y)) ** 2 for x, y in zip(a[0], b[0], strict=True))
            return mpmath.sqrt(exact.to_mpf(sqr))
        return (exact.segment_distance if len(b) == 2 else exact.triangle_distance)(b, a[0])
    if len(b) == 2:
        return exact.segment_segment_closest(a, b).distance
    return (exact.segment_triangle_closest if len(a) == 2 else exact.triangle_triangle_closest)(a, b).distance


def _rounded_primitives(shape):
    """``[(core vertices (n, 3), radius)]`` of each primitive of a scene or a mesh, in order."""
    kinds, params = shape._rows()[:2]
    counts = {p.code: p.vertices for p in proximity.primitives.BY_CODE}
    radius = params[:, -1] if params.shape[1] > proximity.primitives.N_PARAMS else np.zeros(len(kinds))
    return [(params[k, : 3 * counts[kinds[k]]].reshape(-1, 3), radius[k]) for k in range(len(kinds))]


def test_certified_scenes_of_spheres_and_capsules_are_faithful_to_the_exact_least_pair():
    # Equal spheres at equal heights over a plane tie, so the certified
    # search finishes several rows of one pair in Python, each row with its
    # own radius; the answer is the exact least ``d - r_a - r_b`` faithfully
    # rounded, at its pair of primitives.
    balls = proximity.Sphere([[0.0, 0.0, 1.0], [0.5, 0.25, 1.0], [0.25, 0.5, 1.0]], 0.5)
    pills = proximity.Capsule([[[0.0, 0.0, 2.0], [1.0, 0.0, 2.0]], [[0.0, 1.0, 2.5], [1.0, 1.0, 2.5]]], 0.25)
    scene = proximity.Scene([balls, pills])
    plane = [[-2.0, -2.0, 0.0], [4.0, -2.0, 0.0], [-2.0, 4.0, 0.0]]
    others = [
        proximity.Triangle(plane),
        proximity.Segment([[-2.0, 0.0, 0.0], [4.0, 1.0, 0.0]]),
        proximity.TriangleMesh(SPHERE[0] + [0.2, 0.3, 3.6], SPHERE[1]),
        proximity.Scene([proximity.Sphere([[0.0, 0.0, -1.0], [0.5, 0.25, -1.0]], 0.5)]),
    ]
    for other in others:
        prims = _rounded_primitives(other) if hasattr(other, "_tree") else [(other.vertices, 0.0)]
        for a, b, swap in ((scene, other, False), (other, scene, True)):
            r = proximity.closest_points(a, b, method="certified")
            signed = proximity.signed_distance(a, b, method="certified")
            with mpmath.workprec(exact.PREC):
                table = {
                    (i, k): _exact_core_distance(core, prim) - exact.to_mpf(Fraction(ra) + Fraction(rb))
                    for i, (core, ra) in enumerate(_rounded_primitives(scene))
                    for k, (prim, rb) in enumerate(prims)
                }
                least = min(table.values())
            assert least > 0 and exact.ulps(float(signed), least) < 1.0
            assert r.distance == signed
            mine, theirs = ("b", "a") if swap else ("a", "b")
            field = "face" if hasattr(other, "faces") else "primitive"
            index = max(int(getattr(r, f"{field}_{theirs}")), 0)  # -1 for a single primitive
            assert table[int(getattr(r, f"primitive_{mine}")), index] == least


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_an_empty_batch_against_a_collection_has_empty_answers(method):
    # Like any batch, of its batch shape: no pair to search, no descent to compile.
    mesh = proximity.TriangleMesh(*SPHERE)
    pose = np.eye(4)
    pose[:3, 3] = [0.0, 0.0, 3.0]
    empties = [proximity.Segment(np.empty((0, 2, 3))), proximity.Sphere(np.empty((0, 4, 3)), 0.5)]
    for empty in empties:
        for other in (mesh, mesh.transformed(pose), proximity.Scene([mesh.transformed(pose)])):
            for a, b in ((empty, other), (other, empty)):
                r = proximity.closest_points(a, b, method=method)
                assert r.distance.shape == empty.batch_shape and r.point_a.shape == empty.batch_shape + (3,)
                assert proximity.distance(a, b, method=method).shape == empty.batch_shape
                assert proximity.signed_distance(a, b, method=method).shape == empty.batch_shape


def test_certified_overlapping_meshes_stop_at_a_certain_zero():
    a = proximity.TriangleMesh(*SPHERE)
    b = proximity.TriangleMesh(SPHERE[0] + [0.3, 0.1, 0.0], SPHERE[1])
    r = proximity.closest_points(a, b, method="certified")
    assert r.distance == 0 and (r.point_a == r.point_b).all()
    moved = SPHERE[0] + [0.3, 0.1, 0.0]
    exact_sqr = exact.triangle_triangle_closest(SPHERE[0][SPHERE[1][r.face_a]], moved[SPHERE[1][r.face_b]])
    assert exact_sqr.sqr_distance == Fraction(0)


def _rigid(rng, translation):
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = _rotation(rng), translation
    return pose


def _same(r, s, names=("distance", "sqr_distance", "point_a", "point_b", "face_a", "face_b", "feature_a",
                       "feature_b", "barycentric_a", "barycentric_b")):  # fmt: skip
    for name in names:
        np.testing.assert_array_equal(getattr(r, name), getattr(s, name), err_msg=name)


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_posed_views_are_searched_in_place(method):
    rng = np.random.default_rng(11)
    sphere, torus = proximity.TriangleMesh(*SPHERE), proximity.TriangleMesh(*TORUS)
    pose = _pose(rng, 0.02)
    ref = pair_queries.closest_points(sphere, torus, method=method, pose_b=pose)
    # A posed side b is the descent's own pose; a posed side a is swapped to b.
    _same(proximity.closest_points(sphere, torus.transformed(pose), method=method), ref)
    _same(proximity.closest_points(torus.transformed(pose), sphere, method=method), ref.swapped())
    assert proximity.distance(sphere, torus.transformed(pose), method=method) == ref.distance
    # Both posed: the exact minimum over the face pairs of the posed copies, within the bound of
    # the method plus the rounding of the relative pose.
    world = _rigid(rng, rng.normal(size=3) * 10)
    a, b = sphere.transformed(world), torus.transformed(world @ pose)
    r = proximity.closest_points(a, b, method=method)
    va = _posed(SPHERE[0], world)
    vb = _posed(TORUS[0], world @ pose)
    robust, _ = _brute(va, SPHERE[1], vb, TORUS[1], "robust")
    d_exact, _ = _exact_minimum(va, SPHERE[1], vb, TORUS[1], robust)
    magnitude = np.abs(np.concatenate([va, vb])).max()
    assert abs(float(r.distance) - float(d_exact)) <= 64 * EPS * magnitude
    assert a.distance(r.point_a) <= 64 * EPS * magnitude and b.distance(r.point_b) <= 64 * EPS * magnitude
    assert np.linalg.norm(r.point_a - r.point_b) == pytest.approx(float(r.distance), rel=1e-12)
    # The faces are those of the exact minimum (it is well separated here).
    exact_pair = exact.triangle_triangle_closest(va[SPHERE[1][r.face_a]], vb[TORUS[1][r.face_b]])
    with mpmath.workprec(exact.PREC):
        assert abs(float(mpmath.sqrt(exact.to_mpf(exact_pair.sqr_distance))) - float(d_exact)) <= 1e-15
    # Rounded and posed commute.
    shell = proximity.signed_distance(sphere.inflated(0.01).transformed(world), b, method=method)
    assert shell == pytest.approx(float(r.distance) - 0.01, abs=64 * EPS * magnitude)


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_the_distance_between_meshes_takes_a_shorter_path_to_the_same_bits(method):
    rng = np.random.default_rng(12)
    sphere, torus = proximity.TriangleMesh(*SPHERE), proximity.TriangleMesh(*TORUS)
    assert pair_fast.mesh_pair(sphere, torus, method) is not None
    for gap in (0.5, 1e-3, -0.02):
        pose = _pose(rng, gap)
        for b in (torus, torus.transformed(pose)):
            fast = proximity.distance(sphere, b, method=method)
            general = proximity.distance(sphere, b, method=method, max_distance=np.inf)  # the general path
            assert type(fast) is type(general) and fast.tobytes() == general.tobytes()
            # closest_points too: every field, its type and the normal.
            fast = proximity.closest_points(sphere, b, method=method)
            general = proximity.closest_points(sphere, b, method=method, max_distance=np.inf)
            for name, value in asdict(general).items():
                mine = getattr(fast, name)
                assert type(mine) is type(value), name
                assert np.asarray(mine).tobytes() == np.asarray(value).tobytes(), name
                assert not isinstance(mine, np.ndarray) or not mine.flags.writeable, name
            assert fast.normal.tobytes() == general.normal.tobytes()


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_a_mesh_against_itself_touches_everywhere(method):
    sphere = proximity.TriangleMesh(*SPHERE)
    r = proximity.closest_points(sphere, sphere, method=method)
    assert r.distance == 0 and r.sqr_distance == 0
    np.testing.assert_array_equal(r.point_a, r.point_b)
    va, fa = SPHERE
    assert exact.triangle_triangle_closest(va[fa[r.face_a]], va[fa[r.face_b]]).sqr_distance == 0
    assert sphere.distance(r.point_a, method="certified") <= 4 * EPS
    # A posed copy of itself, turned about its centre: still overlapping.
    turn = _rigid(np.random.default_rng(3), [0.0, 0.0, 0.0])
    r = proximity.closest_points(sphere, sphere.transformed(turn), method=method)
    assert r.distance == 0
    np.testing.assert_array_equal(r.point_a, r.point_b)


def _grid(n, z, reverse=False):
    """A flat ``n x n`` grid of unit squares at height ``z``, two triangles each."""
    x, y = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), np.full(x.size, z)], axis=1)
    k = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()
    faces = np.concatenate([np.stack([k, k + n + 1, k + 1], 1), np.stack([k + 1, k + n + 1, k + n + 2], 1)])
    return vertices, faces[::-1] if reverse else faces


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_ties_go_to_the_lowest_pair_of_faces(method):
    # Every face of one grid is 0.5 from the faces of the other above it: ties everywhere.
    (va, fa), (vb, fb) = _grid(4, 0.0), _grid(4, 0.5, reverse=True)
    a, b = proximity.TriangleMesh(va, fa), proximity.TriangleMesh(vb, fb)
    for (v1, f1), (v2, f2), first, second in (((va, fa), (vb, fb), a, b), ((vb, fb), (va, fa), b, a)):
        brute, _ = _brute(v1, f1, v2, f2, method)
        assert brute.min() == 0.5 and (brute == 0.5).sum() > 100
        i, j = np.argwhere(brute == brute.min())[0]
        r = proximity.closest_points(first, second, method=method)
        assert r.distance == 0.5 and (r.face_a, r.face_b) == (i, j)
        assert exact.triangle_triangle_closest(v1[f1[i]], v2[f2[j]]).sqr_distance == Fraction(1, 4)


def test_unsupported_pairs_are_named():
    sphere = proximity.TriangleMesh(*SPHERE)
    disk = proximity.Disk(center=[0, 0, 3], normal=[0, 0, 1], radius=1)
    with pytest.raises(NotImplementedError, match=r"triangle \(a\) and a disk \(b\)"):
        proximity.closest_points(sphere, disk)
    with pytest.raises(NotImplementedError, match="b is a posed Disk"):
        proximity.closest_points(sphere, disk.transformed(np.eye(4)))
    instances = proximity.Scene([sphere.transformed(np.eye(4)), disk])
    with pytest.raises(NotImplementedError, match=r"triangle \(a\) and a disk \(b\)"):
        proximity.closest_points(sphere, instances)
    with pytest.raises(ValueError, match="a and b must live in the same dimension"):
        proximity.closest_points(proximity.Segment([[0, 0], [1, 1]]), sphere)
    with pytest.raises(ValueError, match="method"):
        proximity.closest_points(sphere, sphere, method="eberly")


def _random_pose(rng, spread):
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = _rotation(rng), rng.uniform(-spread, spread, 3)
    return pose


@pytest.mark.parametrize("method", ["robust", "certified"])
def test_a_scene_of_instances_answers_as_the_nearest_of_its_members(method):
    # Each member's pair is searched on its own, so the scene's answer is
    # the least member answer bit for bit, renumbered into the scene; ties
    # to the lowest primitive.
    rng = np.random.default_rng(21)
    sphere = proximity.TriangleMesh(*SPHERE)
    inner = proximity.Scene([sphere, proximity.Triangle([[0, 0, 0], [0, 0, 2], [0, 1, 2]])])
    members = [sphere.transformed(_random_pose(rng, 3.0)) for _ in range(4)]
    members.append(inner.transformed(_random_pose(rng, 3.0)))
    members.append(proximity.Triangle([[0, 0, 6], [1, 0, 6], [0, 1, 6]]))
    scene = proximity.Scene(members)
    offsets = scene.offsets
    loose = proximity.Scene([members[-1]])
    others = [
        proximity.TriangleMesh(SPHERE[0] * 0.4 + 4.0, SPHERE[1]).transformed(_random_pose(rng, 1.0)),
        proximity.Segment(rng.uniform(-6, 6, (7, 2, 3))),
        proximity.Point([[0.0, 0.0, 7.0], [2.0, 2.0, 2.0], [9.0, -9.0, 0.0]]),
    ]
    if method == "certified":  # the kernels of certified posed pairs take long to compile
        others = others[2:]
    for other in others:
        got = proximity.closest_points(scene, other, method=method)
        each = [proximity.closest_points(m, other, method=method) for m in members[:5]]
        each.append(proximity.closest_points(loose, other, method=method))
        d = np.array([np.asarray(r.distance) for r in each])
        k = np.argmin(d, axis=0)
        np.testing.assert_array_equal(got.distance, d.min(axis=0))
        np.testing.assert_array_equal(got.source_a, k)
        local = [np.asarray(r.face_a) for r in each[:4]] + [np.asarray(r.primitive_a) for r in each[4:]]
        expect = np.choose(k, [loc + offsets[j] for j, loc in enumerate(local)])
        np.testing.assert_array_equal(got.primitive_a, expect)
        assert np.all(np.asarray(got.face_a) == -1)
        for j in range(3):
            np.testing.assert_array_equal(
                np.asarray(got.point_b)[..., j], np.choose(k, [np.asarray(r.point_b)[..., j] for r in each])
            )
        np.testing.assert_array_equal(got.feature_b, np.choose(k, [np.asarray(r.feature_b) for r in each]))
        # The other way round (posed against posed composes the poses the
        # other way, so compared with the members' answers that way), and
        # the distance alone.
        back = proximity.closest_points(other, scene, method=method)
        each = [proximity.distance(other, m, method=method) for m in members[:5]]
        each.append(proximity.distance(other, loose, method=method))
        np.testing.assert_array_equal(back.distance, np.min(each, axis=0))
        np.testing.assert_array_equal(proximity.distance(other, scene, method=method), back.distance)
        np.testing.assert_array_equal(proximity.distance(scene, other, method=method), got.distance)
    if method == "certified":
        return
    # A cutoff, a pose and a radius around the scene go to every member.
    T = _random_pose(rng, 2.0)
    mesh = others[0]
    posed = scene.transformed(T)
    expect = min(float(proximity.distance(m.transformed(T), mesh)) for m in members)
    assert float(proximity.distance(posed, mesh)) == pytest.approx(expect, rel=0, abs=1e-13)
    assert float(proximity.distance(posed, mesh, max_distance=expect * 0.99)) == np.inf
    rounded = proximity.Inflated(scene, 1.5)
    low = min(float(proximity.signed_distance(proximity.Inflated(m, 1.5), mesh)) for m in members)
    assert float(proximity.signed_distance(rounded, mesh)) == low
    # Both sides scenes of instances.
    far = [_random_pose(rng, 3.0) for _ in range(3)]
    for pose in far:
        pose[0, 3] += 9.0
    twin = proximity.Scene([sphere.transformed(pose) for pose in far])
    both = proximity.closest_points(scene, twin, method=method)
    brute = min(float(proximity.distance(m, t, method=method)) for m in members for t in twin.shapes)
    assert float(both.distance) == brute
