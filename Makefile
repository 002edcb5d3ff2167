# `make test`, `make bench` and `make docs` each create .venv when missing and
# install the project into it with everything the job needs.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CORE := .venv-core
CORE_STAMP := $(CORE)/.installed
DOCS_STAMP := $(VENV)/.installed-docs
PEERS_STAMP := $(VENV)/.installed-peers

.PHONY: test bench bench-quick docs numba-floor numba-floor-env clean clean-cache

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test,bench,adapters,scale]"
	touch $(STAMP)

# The mesh benchmark's peers, for make bench only.
$(PEERS_STAMP): pyproject.toml $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[peers]"
	touch $(PEERS_STAMP)

$(DOCS_STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $(DOCS_STAMP)

# The package with its own dependencies alone, as `pip install proximity3d`
# gives it, for the speed benchmark's start-up rows: with scipy installed (the
# adapters extra needs it), Numba imports it while setting up its compiler.
# NumPy, Numba and llvmlite are pinned to .venv's versions, so that the two
# environments share the kernels cached next to the sources.
$(CORE_STAMP): $(STAMP)
	rm -rf $(CORE)
	$(PYTHON) -m venv $(CORE)
	$(BIN)/python -m pip freeze | grep -iE '^(numpy|numba|llvmlite)==' > $(CORE)/pins.txt
	$(CORE)/bin/python -m pip install --quiet -e . -c $(CORE)/pins.txt
	touch $(CORE_STAMP)

test: $(STAMP)
	$(BIN)/python -m ruff check proximity adapters benchmarks tests
	$(BIN)/python -m ruff format --check proximity adapters benchmarks tests
	$(BIN)/python -m pytest -n 2 --dist loadfile proximity adapters tests benchmarks/test_benchmarks.py README.md

# The oldest Numba that pyproject.toml accepts, in an environment of its own
# (with the NumPy that Numba version takes): every path of every shape must
# answer with the bits of the pinned Numba in .venv.  The pinned run uses the
# kernels cached beside the sources (compiled by `make test` where it ran
# first); the oldest Numba compiles into a cache of its own, on both cores.
NUMBA_FLOOR := $(shell sed -n 's/.*"numba>=\([0-9.]*\),.*/\1/p' pyproject.toml)
FLOOR := .venv-numba-floor

FLOOR_STAMP := $(FLOOR)/.installed

$(FLOOR_STAMP): pyproject.toml
	rm -rf $(FLOOR)
	$(PYTHON) -m venv $(FLOOR)
	$(FLOOR)/bin/python -m pip install --quiet -e . "numba==$(NUMBA_FLOOR).*"
	touch $(FLOOR_STAMP)

# The environment alone (CI makes it while the tests run).
numba-floor-env: $(FLOOR_STAMP)

numba-floor: $(STAMP) $(FLOOR_STAMP)
	rm -rf $(FLOOR)/cache $(FLOOR)/pinned.npz $(FLOOR)/floor.npz
	$(BIN)/python -m proximity.testing.smoke $(FLOOR)/pinned.npz --jobs 2
	NUMBA_CACHE_DIR=$(FLOOR)/cache $(FLOOR)/bin/python -m proximity.testing.smoke $(FLOOR)/floor.npz \
		--jobs 2 --compare $(FLOOR)/pinned.npz

# A regular install byte-compiles the package; an editable one leaves that to
# the first import, which does not write the result where PYTHONDONTWRITEBYTECODE
# is set, so every new process would compile the sources again (about 60 ms
# of the start-up that the speed benchmark times).  The last step,
# benchmarks.scale, writes 100 million points (2.4 GB) to a temporary folder
# and deletes them at the end.
bench: $(STAMP) $(CORE_STAMP) $(PEERS_STAMP)
	$(BIN)/python -m compileall -q proximity adapters
	$(BIN)/python -m benchmarks --package-python $(CORE)/bin/python
	$(BIN)/python -m benchmarks.meshes
	$(BIN)/python -m benchmarks.moving
	$(BIN)/python -m benchmarks.pairs
	$(BIN)/python -m benchmarks.signs
	$(BIN)/python -m benchmarks.scale

bench-quick: $(STAMP) $(CORE_STAMP) $(PEERS_STAMP)
	$(BIN)/python -m compileall -q proximity adapters
	$(BIN)/python -m benchmarks --quick --package-python $(CORE)/bin/python
	$(BIN)/python -m benchmarks.meshes --quick
	$(BIN)/python -m benchmarks.moving --quick
	$(BIN)/python -m benchmarks.pairs --quick
	$(BIN)/python -m benchmarks.signs --quick
	$(BIN)/python -m benchmarks.scale --quick

# The documentation site, into docs/_build/html: the Markdown pages of docs/
# and the API reference from the docstrings; a warning fails the build.
docs: $(DOCS_STAMP)
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "documentation: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) $(CORE) $(FLOOR) bench-results .pytest_cache docs/_build

# Numba's cache of compiled kernels (index .nbi and data .nbc files), kept in
# __pycache__ beside the sources; the next import compiles them again.
clean-cache:
	find proximity -name '*.nbi' -delete -o -name '*.nbc' -delete
