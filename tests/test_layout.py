"""The package's layout: small modules, no import circles, a test suite that needs no clone."""

import ast
import inspect
import pathlib

import proximity

PACKAGE = pathlib.Path(proximity.__file__).parent
TESTS = pathlib.Path(__file__).parent

#: The most lines a module of the package may hold.
MAX_LINES = 800


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        yield (".".join(parts[:-1]) if parts[-1] == "__init__" else ".".join(parts)), path


def _imports(name, path, deep=False, modules=()):
    """The modules ``name`` imports when it is imported (module level), or anywhere (``deep``),
    modules loaded by name at a first use (:func:`proximity.runtime.lazy.load`) included.

    ``from package import name`` depends on the module ``package.name``
    where there is one (of ``modules``), else on ``package`` itself.
    """
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree) if deep else tree.body:
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([node.module] if node.module else []))
            for alias in node.names:
                found.add(f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base)
        elif deep and isinstance(node, ast.Call) and _loads_by_name(node):
            found.add(node.args[0].value)
    return found


def _loads_by_name(call):
    """Whether ``call`` imports a module named by a string: ``lazy.load("proximity.x")``,
    ``importlib.import_module("proximity.x")``."""
    func = call.func
    named = isinstance(func, ast.Attribute) and func.attr in ("load", "import_module")
    return (
        named
        and isinstance(func.value, ast.Name)
        and func.value.id in ("lazy", "_lazy", "importlib")
        and len(call.args) == 1
        and isinstance(call.args[0], ast.Constant)
        and str(call.args[0].value).startswith("proximity.")
    )


def test_no_module_is_longer_than_the_limit():
    long = {name: n for name, path in _modules() if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_no_import_circles():
    modules = dict(_modules())
    graph = {
        name: sorted(_imports(name, path, modules=modules) & modules.keys() - {name})
        for name, path in modules.items()
    }
    state = {}

    def visit(node, stack):
        state[node] = "open"
        for nxt in graph[node]:
            if state.get(nxt) == "open":
                raise AssertionError("import circle: " + " -> ".join(stack[stack.index(nxt) :] + [nxt]))
            if nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = "done"

    for name in graph:
        if name not in state:
            visit(name, [name])


#: The package's parts from the bottom up: each may import only the parts before it, and itself.
#: A part is a folder, or a module at the root (``""``: the package's ``__init__.py``).
ORDER = (
    ("features", "methods", "_typing", "_validate"),  # the vocabulary
    ("runtime",),
    ("primitives",),  # the registry of kinds of primitive
    ("numerics",),
    ("results",),
    ("point",),
    ("broadphase",),
    ("signs",),
    ("shapes",),
    ("pair",),
    ("interop",),
    ("", "compile", "cloud", "dask", "trimesh_compat", "testing", "adapters"),  # the public face
)

#: The most modules at the package's root, and the fewest folders of one job each.
MAX_ROOT_MODULES = 12
MIN_FOLDERS = 6


def _part(module):
    """The part of :data:`ORDER` that the package's module ``module`` (``proximity.x.y``) is in."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _rank(part):
    for rank, level in enumerate(ORDER):
        if part in level:
            return rank
    raise AssertionError(f"{part!r} is in no level of ORDER: add it")


def _graph(deep):
    """``{module: modules of the package it imports}``, with the imports inside functions (``deep``)."""
    modules = dict(_modules())
    modules.update(_adapter_modules())
    return {
        name: sorted(_imports(name, path, deep=deep, modules=modules) & modules.keys() - {name})
        for name, path in modules.items()
    }


def _adapter_modules():
    # In a clone, adapters/ is installed as proximity.adapters; in an install it is in PACKAGE already.
    folder = PACKAGE.parent / "adapters"
    if (PACKAGE / "adapters").is_dir() or not (folder / "__init__.py").is_file():
        return {}
    return {
        ("proximity.adapters" if p.stem == "__init__" else f"proximity.adapters.{p.stem}"): p
        for p in sorted(folder.glob("*.py"))
    }


def _circle(graph):
    """A circle of ``graph`` as a list of nodes, or None."""
    state = {}

    def visit(node, stack):
        state[node] = "open"
        for nxt in graph.get(node, ()):
            if state.get(nxt) == "open":
                return stack[stack.index(nxt) :] + [nxt]
            if nxt not in state:
                found = visit(nxt, stack + [nxt])
                if found:
                    return found
        state[node] = "done"
        return None

    for name in sorted(graph):
        if name not in state:
            found = visit(name, [name])
            if found:
                return found
    return None


def test_no_import_circles_counting_imports_inside_functions():
    # A deferred import that dodges a circle is still a circle.
    circle = _circle(_graph(deep=True))
    assert circle is None, "import circle: " + " -> ".join(circle)


def test_no_part_imports_a_part_above_it():
    upward = []
    for name, imported in _graph(deep=True).items():
        for other in imported:
            if _rank(_part(other)) > _rank(_part(name)):
                upward.append(f"{name} -> {other}")
    assert not upward, "imports of a part above (see ORDER):\n" + "\n".join(upward)


def test_the_folders_have_one_job_each_and_the_root_is_small():
    root = [p.name for p in PACKAGE.glob("*.py")]
    assert len(root) <= MAX_ROOT_MODULES, sorted(root)
    folders = [p for p in PACKAGE.iterdir() if (p / "__init__.py").is_file() and p.name != "testing"]
    assert len(folders) >= MIN_FOLDERS, folders
    for folder in folders:
        doc = ast.get_docstring(ast.parse((folder / "__init__.py").read_text()))
        # Each says what lives there and what it may import.
        assert doc and "import" in doc, f"{folder.name}/__init__.py does not say what it may import"
    every = {part for level in ORDER for part in level}
    for p in list(PACKAGE.iterdir()):
        name = p.stem if p.suffix == ".py" else p.name
        if (p.suffix == ".py" or (p / "__init__.py").is_file()) and name != "__init__":
            assert name in every, f"{p.name} is in no level of ORDER"


def test_no_test_imports_the_benchmarks():
    # The suite runs from an installed package, where benchmarks/ is absent.
    for path in TESTS.glob("*.py"):
        for name in _imports(f"tests.{path.stem}", path, deep=True):
            assert name.split(".")[0] != "benchmarks", f"{path.name} imports {name}"


def test_adapters_import_from_the_clones_root_without_the_install_mapping():
    # Python started in the clone's root imports the checkout's proximity/,
    # where adapters/ is not; an install maps it in (here left out: -S skips
    # the site-packages .pth files that hold the editable install's mapping).
    import os
    import subprocess
    import sys

    import numpy
    import pytest

    root = PACKAGE.parent
    if not (root / "adapters" / "__init__.py").is_file():
        pytest.skip("not a source checkout: adapters/ is installed as proximity/adapters/")
    site = os.path.dirname(os.path.dirname(numpy.__file__))
    code = f"import sys; sys.path[:0] = ['', {site!r}]; import proximity.adapters as a; print(a.__file__)"
    run = subprocess.run([sys.executable, "-S", "-c", code], cwd=root, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert pathlib.Path(run.stdout.strip()) == root / "adapters" / "__init__.py"


def _public_callables():
    """The functions of ``proximity.__all__`` and the public methods of its classes."""
    import proximity

    for name in proximity.__all__:
        obj = getattr(proximity, name)
        if inspect.isfunction(obj):
            yield name, obj
        elif inspect.isclass(obj) and obj.__module__.startswith("proximity"):
            for attr, member in vars(obj).items():
                if attr.startswith("_") and attr != "__init__":
                    continue
                function = member.fget if isinstance(member, property) else member
                if inspect.isfunction(function):
                    yield f"{name}.{attr}", function


def test_the_public_api_has_type_hints():
    # The shapes, meshes, scenes and posed views, and the module's functions
    # (results are dataclasses, annotated by their fields).
    missing = []
    for name, function in _public_callables():
        if name.split(".")[0].endswith("Result") or name.startswith("Feature") or name == "Shape.__init__":
            continue  # dataclasses, an enum, and the protocol's own constructor
        signature = inspect.signature(function)
        for p in signature.parameters.values():
            if p.name not in ("self", "cls") and p.annotation is inspect.Parameter.empty:
                missing.append(f"{name}({p.name})")
        if signature.return_annotation is inspect.Signature.empty:
            missing.append(f"{name} -> ?")
    assert not missing, missing
