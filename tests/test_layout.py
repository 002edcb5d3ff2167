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
    """The modules ``name`` imports when it is imported (module level), or anywhere (``deep``).

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
    return found


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
