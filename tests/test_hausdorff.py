"""Hausdorff distance between meshes: the certified bounds against exact values.

The references are exact: distances known in closed form (boxes moved or
nested, the circumcentre of three points) compared in rational arithmetic,
and, for curved meshes, exact distances (:mod:`proximity.testing.exact`) at
the witness and at sampled points of the mesh.
"""

import dataclasses
from fractions import Fraction

import numpy as np
import pytest

import proximity
from proximity.testing import exact
from proximity.testing.meshes import box, icosphere

EPS = 2.0**-52


def mesh(vertices, faces):
    return proximity.TriangleMesh(vertices, faces)


def pose(rotation=None, translation=(0, 0, 0)):
    t = np.eye(4)
    if rotation is not None:
        t[:3, :3] = rotation
    t[:3, 3] = translation
    return t


def brackets(result, value_squared):
    """``lower <= sqrt(value_squared) <= upper``, decided in rational arithmetic."""
    return Fraction(result.lower) ** 2 <= value_squared <= Fraction(result.upper) ** 2


def exact_sqr_distance(point, b_vertices, b_faces):
    """The exact squared distance from a float point to a mesh: the least over its faces."""
    return min(exact.triangle_sqr_distance(b_vertices[f], point) for f in b_faces)


def test_identical_meshes_give_zero():
    cube = mesh(*box([0, 0, 0], [1, 1, 1]))
    r = proximity.hausdorff_distance(cube, cube)
    assert r.lower == 0.0 and r.distance == 0.0
    assert 0.0 <= r.upper <= 64 * EPS
    assert r.converged
    # The cube turned a quarter about z and moved back onto itself (an exact pose): the same surface,
    # its square sides triangulated along the other diagonal.  Where the distance is 0 on both sides
    # of an edge of b, the bounds shrink only with the subtriangles: the guard stops the search with
    # certified bounds, [0, about the size of the last subtriangles].
    quarter = pose([[0, -1, 0], [1, 0, 0], [0, 0, 1]], [1, 0, 0])
    with pytest.warns(RuntimeWarning, match="max_points"):
        r = proximity.hausdorff_distance(cube, cube.transformed(quarter), max_points=20_000)
    assert r.lower == 0.0 and 0.0 < r.upper <= 1e-2 and not r.converged


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("method", ["robust", "certified"])
def test_a_box_against_its_translate_brackets_the_translation(axis, method):
    t = 0.375  # a dyadic number: the moved vertices are exact, and the distance is exactly t
    lo, hi = np.zeros(3), np.ones(3)
    moved = np.eye(3)[axis] * t
    a = mesh(*box(lo, hi))
    b = mesh(*box(lo + moved, hi + moved))
    for other in (b, a.transformed(pose(translation=moved))):
        r = proximity.hausdorff_distance(a, other, rtol=1e-9, method=method)
        assert r.lower <= t <= r.upper
        assert r.upper - r.lower <= 1e-9 * r.upper + 1e-13
        assert r.lower <= r.distance <= r.upper
        # The witness pair: a point of one box and its closest point on the other, t apart.
        assert abs(np.linalg.norm(r.point_a - r.point_b) - t) <= 1e-12


def test_directed_distances_of_nested_boxes_differ():
    small = mesh(*box([-0.25] * 3, [0.25] * 3))
    big = mesh(*box([-1.0] * 3, [1.0] * 3))
    inward = proximity.hausdorff_distance(small, big, directed=True, rtol=1e-9)
    outward = proximity.hausdorff_distance(big, small, directed=True, rtol=1e-9)
    # Every point of the small box's surface is 1 - 0.25 from the big one's; the big box's corners
    # are farthest from the small box, sqrt(3) * 0.75 away.
    assert inward.lower <= 0.75 <= inward.upper
    assert brackets(outward, 3 * Fraction(3, 4) ** 2)
    assert outward.directed and outward.side == "a"
    assert np.abs(outward.point_a).tolist() == [1.0, 1.0, 1.0]
    both = proximity.hausdorff_distance(small, big, rtol=1e-9)
    assert not both.directed and both.side == "b"
    assert brackets(both, 3 * Fraction(3, 4) ** 2)
    assert np.abs(both.point_b).tolist() == [1.0, 1.0, 1.0]
    assert np.abs(both.point_a).tolist() == [0.25, 0.25, 0.25]


def circumcentre(q):
    (ax, ay), (bx, by), (cx, cy) = [(Fraction(p[0]), Fraction(p[1])) for p in q]
    d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    sa, sb, sc = ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy
    ux = (sa * (by - cy) + sb * (cy - ay) + sc * (ay - by)) / d
    uy = (sa * (cx - bx) + sb * (ax - cx) + sc * (bx - ax)) / d
    return ux, uy, (ux - ax) ** 2 + (uy - ay) ** 2


@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-10])
def test_a_maximum_inside_a_face_is_found_by_subdivision(rtol):
    # b: three points (faces of one repeated vertex) at the corners of an acute triangle; a: a small
    # triangle around their circumcentre inside it.  The farthest point of a from b is the
    # circumcentre, at the circumradius R, in a's interior: a's vertices are far nearer to b.
    q = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.9, 0.0]])
    b = mesh(q, [[0, 0, 0], [1, 1, 1], [2, 2, 2]])
    a_vertices = np.array([[0.3, 0.2, 0.0], [0.7, 0.25, 0.0], [0.45, 0.55, 0.0]])
    a = mesh(a_vertices, [[0, 1, 2]])
    ux, uy, r2 = circumcentre(q[:, :2])
    r = proximity.hausdorff_distance(a, b, directed=True, rtol=rtol)
    assert brackets(r, r2)
    assert r.upper - r.lower <= rtol * r.upper + 1e-13
    vertex_best = max(min(exact.triangle_sqr_distance(np.stack([p, p, p]), v) for p in q) for v in a_vertices)
    assert Fraction(r.lower) ** 2 > vertex_best  # the vertices alone fall short
    # The witness is near the circumcentre (within what the gap allows: d is sqrt-flat near there).
    assert np.hypot(r.point_a[0] - float(ux), r.point_a[1] - float(uy)) <= 10 * np.sqrt(rtol) + 1e-6
    assert r.point_b.tolist() in q.tolist()


@pytest.mark.parametrize("posed", [False, True])
def test_a_sphere_against_a_scaled_copy_contains_exact_samples(posed):
    va, fa = icosphere(1)
    vb, fb = va * 1.25, fa  # the references take b's vertices as they are, rounded or not
    a = mesh(va, fa)
    if posed:
        # Turned a quarter about z, exactly: the sphere is not symmetric under it at this tessellation.
        quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
        b = mesh(vb, fb).transformed(pose(quarter))
        vb = vb @ quarter.T
    else:
        b = mesh(vb, fb)
    rtol = 1e-6
    r = proximity.hausdorff_distance(a, b, rtol=rtol)
    assert r.converged and r.upper - r.lower <= rtol * r.upper + 1e-13
    # Lower bound: the witness's exact distance to the other mesh is at least it.
    if r.side == "a":
        witness = exact_sqr_distance(r.point_a, vb, fb)
    else:
        witness = exact_sqr_distance(r.point_b, va, fa)
    assert Fraction(r.lower) ** 2 <= witness
    # Upper bound: exact distances at dense samples of both meshes.  A sample computed from
    # barycentric weights is within eta of its mesh; every exact distance is at most upper + eta.
    rng = np.random.default_rng(7)
    eta = 2.0**-44 * 2
    n = 16  # a grid of weights i/n, j/n: every point of a face is within edge/n of a sample
    grid = np.array([(i, j, n - i - j) for i in range(n + 1) for j in range(n + 1 - i)], np.float64) / n
    best_sample = Fraction(0)
    cover = 0.0
    for (v_from, f_from), (v_to, f_to), m_to in (((va, fa), (vb, fb), b), ((vb, fb), (va, fa), a)):
        tris = v_from[f_from]
        samples = np.einsum("sk,fkd->fsd", grid, tris).reshape(-1, 3)
        d = np.asarray(m_to.distance(samples))
        top = samples[np.argsort(d)[-12:]]
        top = np.concatenate([top, samples[rng.integers(0, len(samples), 4)]])
        for p in top:
            sqr = exact_sqr_distance(p, v_to, f_to)
            assert sqr <= (Fraction(r.upper) + Fraction(eta)) ** 2
            best_sample = max(best_sample, sqr)
        edges = np.linalg.norm(tris - np.roll(tris, 1, axis=1), axis=-1).max()
        cover = max(cover, edges / n)
    # The brute-force bracket [sample max - eta, sample max + cover + eta] meets [lower, upper].
    assert Fraction(r.lower) <= Fraction(float(np.sqrt(float(best_sample)))) + Fraction(cover + 2 * eta)
    assert Fraction(r.upper) ** 2 >= best_sample - Fraction(eta)


def test_the_size_guard_warns_and_keeps_certified_bounds():
    q = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.9, 0.0]])
    b = mesh(q, [[0, 0, 0], [1, 1, 1], [2, 2, 2]])
    a = mesh([[0.3, 0.2, 0.0], [0.7, 0.25, 0.0], [0.45, 0.55, 0.0]], [[0, 1, 2]])
    with pytest.warns(RuntimeWarning, match="max_points"):
        r = proximity.hausdorff_distance(a, b, directed=True, rtol=1e-12, max_points=20)
    assert not r.converged
    assert brackets(r, circumcentre(q[:, :2])[2])
    assert r.upper - r.lower > 1e-12 * r.upper


def test_result_is_frozen():
    cube = mesh(*box([0, 0, 0], [1, 1, 1]))
    r = proximity.hausdorff_distance(cube, cube)
    assert isinstance(r, proximity.HausdorffResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.lower = 1.0
    with pytest.raises(ValueError):
        r.point_a[0] = 1.0
    assert "HausdorffResult(" in repr(r)


class _MeshLike:
    vertices = np.eye(3)
    faces = np.array([[0, 1, 2]])


@pytest.mark.parametrize(
    ("args", "options", "error", "match"),
    [
        (("cube", "tri"), {}, TypeError, "b must be a proximity.TriangleMesh"),
        (("tri", "cube"), {}, TypeError, "a must be a proximity.TriangleMesh"),
        (("cube", "meshlike"), {}, TypeError, "TriangleMesh\\(mesh\\) first"),
        (("cube", "cube"), {"rtol": 0}, ValueError, "rtol must be a finite number > 0"),
        (("cube", "cube"), {"rtol": -1e-3}, ValueError, "rtol"),
        (("cube", "cube"), {"rtol": np.nan}, ValueError, "rtol"),
        (("cube", "cube"), {"rtol": np.inf}, ValueError, "rtol"),
        (("cube", "cube"), {"rtol": "1e-3"}, TypeError, "rtol"),
        (("cube", "cube"), {"atol": -1.0}, ValueError, "atol must be a finite number >= 0"),
        (("cube", "cube"), {"method": "eberly"}, ValueError, "method must be one of"),
        (("cube", "cube"), {"method": "fast"}, ValueError, "method"),
        (("cube", "cube"), {"max_points": 0}, ValueError, "max_points"),
        (("cube", "cube"), {"directed": "yes"}, TypeError, "directed"),
        (("cube", "cube", 1e-3), {}, TypeError, "keyword-only"),
    ],
)
def test_bad_input(args, options, error, match):
    shapes = {
        "cube": mesh(*box([0, 0, 0], [1, 1, 1])),
        "tri": proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
        "meshlike": _MeshLike(),
    }
    values = [shapes.get(x, x) if isinstance(x, str) else x for x in args]
    with pytest.raises(error, match=match):
        proximity.hausdorff_distance(*values, **options)
