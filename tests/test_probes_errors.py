"""Bad values of the options that choose a mode: each refused with a message naming it."""

import numpy as np
import pytest

import proximity

TET = ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _option_calls():
    mesh = proximity.TriangleMesh(*TET)
    point = [[0.1, 0.1, 0.1]]
    segment = proximity.Segment([[0, 0, 0], [1, 0, 0]])
    return [
        ("sign", lambda v: mesh.signed_distance(point, sign=v)),
        ("sign", lambda v: mesh.contains(point, sign=v)),
        ("sign", lambda v: mesh.signed(point, sign=v)),
        ("sign", lambda v: mesh.sdf_grid([0, 0, 0], [1, 1, 1], (2, 2, 2), sign=v)),
        ("broad_phase", lambda v: proximity.TriangleMesh(*TET, broad_phase=v)),
        ("broad_phase", lambda v: proximity.Scene([mesh.transformed(np.eye(4))], broad_phase=v)),
        ("broad_phase", lambda v: proximity.Scene([segment], broad_phase=v)),
    ]


@pytest.mark.parametrize("value", [np.array(["auto", "bvh"]), np.zeros(3), np.empty(0), None, 1, b"auto"])
def test_a_mode_that_is_not_a_string_is_named_with_what_it_is(value):
    # An array compared with the names element by element gave NumPy's
    # "truth value of an array is ambiguous", naming nothing.
    for name, call in _option_calls():
        message = rf"{name} must be a str, one of \(.*\); got {type(value).__name__}"
        with pytest.raises(TypeError, match=message):
            call(value)


def test_a_mode_of_an_unknown_name_lists_the_names():
    for name, call in _option_calls():
        with pytest.raises(ValueError, match=rf"{name} must be one of \(.*\); got 'parity'"):
            call("parity")


@pytest.mark.parametrize("value", ["yes", "", None, 1, np.array([True, False])])
def test_full_is_true_or_false(value):
    # Anything Python takes for a truth value passed, a string "no" included.
    mesh = proximity.TriangleMesh(*TET)
    with pytest.raises(TypeError, match=f"full must be True or False; got {type(value).__name__}"):
        mesh.winding_number([0.1, 0.1, 0.1], full=value)
    exact = mesh.winding_number([0.1, 0.1, 0.1], full=True)
    assert mesh.winding_number([0.1, 0.1, 0.1], full=np.True_).winding == exact.winding == 1.0


def test_a_pair_of_dimensions_with_a_scene_of_instances_names_the_arguments_in_order():
    # The scene is searched part by part, its parts swapped to side b: the
    # message named "b and a" and a part's class for the scene's.
    instances = proximity.Scene([proximity.TriangleMesh(*TET).transformed(np.eye(4))])
    flat = proximity.Segment(np.zeros((2, 2)))
    message = "a and b must live in the same dimension; got {}D \\({}\\) and {}D \\({}\\)"
    for query in (proximity.closest_points, proximity.distance, proximity.signed_distance):
        with pytest.raises(ValueError, match=message.format(3, "Scene", 2, "Segment")):
            query(instances, flat)
        with pytest.raises(ValueError, match=message.format(2, "Segment", 3, "Scene")):
            query(flat, instances)
    with pytest.raises(TypeError, match="b must be a proximity shape; got str"):
        proximity.closest_points(instances, "mesh")


@pytest.mark.parametrize("value", ["no", None, 1, np.zeros(3)])
def test_certified_stats_reset_is_true_or_false(value):
    # "no" reset the counts; an array raised NumPy's ambiguous truth value.
    proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).distance([0.25, 0.25, 0.0], method="certified")
    before = proximity.certified_stats()
    with pytest.raises(TypeError, match=f"reset must be True or False; got {type(value).__name__}"):
        proximity.certified_stats(reset=value)
    assert proximity.certified_stats() == before and before["queries"] > 0
