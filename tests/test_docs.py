"""The documentation site: every public name has an entry, and the getting-started page runs."""

import doctest
import pathlib
import re

import pytest

import proximity

DOCS = pathlib.Path(__file__).resolve().parent.parent / "docs"


def _documented():
    """The objects of ``.. autoclass::``, ``.. autofunction::`` and ``.. autodata::``
    entries of the API pages, by full name."""
    names = set()
    for page in (DOCS / "api").glob("*.rst"):
        module = "proximity"
        for line in page.read_text(encoding="utf-8").splitlines():
            current = re.match(r"\.\. currentmodule:: (\S+)", line)
            if current:
                module = current.group(1)
            entry = re.match(r"\.\. auto(?:class|function|data|exception):: (\S+)", line)
            if entry:
                name = entry.group(1)
                names.add(name if name.startswith("proximity.") else f"{module}.{name}")
    return names


@pytest.mark.parametrize("module", ["proximity", "proximity.dask", "proximity.adapters"])
def test_every_public_name_has_an_entry(module):
    pytest.importorskip(module)
    public = __import__(module, fromlist=["__all__"]).__all__
    missing = sorted(f"{module}.{name}" for name in public if f"{module}.{name}" not in _documented())
    assert not missing, f"no entry in docs/api/*.rst for {missing}"


def test_every_page_is_in_the_navigation():
    index = (DOCS / "index.rst").read_text(encoding="utf-8")
    listed = set(re.findall(r"^   (\S+)$", index, re.M))
    pages = {p.stem for p in DOCS.glob("*.md")}
    assert pages <= listed, f"pages missing from the toctree of docs/index.rst: {sorted(pages - listed)}"


def test_the_getting_started_page_runs(tmp_path, monkeypatch):
    pytest.importorskip("trimesh")
    monkeypatch.chdir(tmp_path)  # it writes sphere.stl
    result = doctest.testfile(
        str(DOCS / "start.md"), module_relative=False, optionflags=doctest.NORMALIZE_WHITESPACE
    )
    assert result.attempted > 0 and result.failed == 0


def test_the_queries_show_their_keyword_only_signature():
    import inspect

    for function in (proximity.closest_point, proximity.distance):
        signature = inspect.signature(function)
        assert list(signature.parameters) == ["shape", "points", "method", "max_distance"]
        keyword_only = [p.name for p in signature.parameters.values() if p.kind is p.KEYWORD_ONLY]
        assert keyword_only == ["method", "max_distance"]
        assert signature.parameters["method"].default == "robust"
