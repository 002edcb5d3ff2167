"""Objects pickled by an earlier version of the package load, and answer as fresh ones do.

``data/pickles.pkl`` was written by ``data/make_pickles.py`` with the package as it stood before
its modules moved into folders: the pickles name the modules of that layout (``shapes``, ``mesh``,
``inflated``, ``posed``, ``scene`` and ``results``, each under ``proximity``).
"""

import dataclasses
import importlib.util
import pathlib
import pickle
import pickletools

import numpy as np
import pytest

import proximity

DATA = pathlib.Path(__file__).with_name("data")


def _maker():
    spec = importlib.util.spec_from_file_location("make_pickles", DATA / "make_pickles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


MAKER = _maker()
LOADED = pickle.loads((DATA / "pickles.pkl").read_bytes())
FRESH = MAKER.objects(proximity)


def _same(x, y):
    np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def test_the_file_holds_every_object():
    assert sorted(LOADED) == sorted(FRESH)
    ops = pickletools.genops((DATA / "pickles.pkl").read_bytes())
    old = {arg.split(".", 2)[1] for _, arg, _ in ops if isinstance(arg, str) and arg.startswith("proximity.")}
    # The modules the file names are those of the earlier layout.
    assert {"shapes", "mesh", "inflated", "posed", "scene", "results"} <= old


@pytest.mark.parametrize("name", [n for n in FRESH if not n.endswith("result")])
def test_a_loaded_shape_answers_as_a_fresh_one(name):
    loaded, fresh = LOADED[name], FRESH[name]
    assert type(loaded) is type(fresh)
    points = MAKER.QUERIES[:, None] if name in ("triangle", "inflated") else MAKER.QUERIES
    a, b = loaded.closest_point(points), fresh.closest_point(points)
    for field in dataclasses.fields(b):
        _same(getattr(a, field.name), getattr(b, field.name))
    _same(loaded.distance(points, method="certified"), fresh.distance(points, method="certified"))


@pytest.mark.parametrize("name", [n for n in FRESH if n.endswith("result")])
def test_a_loaded_result_holds_the_fresh_fields(name):
    loaded, fresh = LOADED[name], FRESH[name]
    assert type(loaded) is type(fresh)
    for field in dataclasses.fields(fresh):
        _same(getattr(loaded, field.name), getattr(fresh, field.name))
