# `make test` and `make bench` each create .venv when missing and install the
# project into it with everything the job needs.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: test bench bench-quick clean clean-cache

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test,bench,adapters]"
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m ruff check proximity adapters benchmarks tests
	$(BIN)/python -m pytest proximity tests README.md

# A regular install byte-compiles the package; an editable one leaves that to
# the first import, which does not write the result where PYTHONDONTWRITEBYTECODE
# is set, so every new process would compile the sources again (about 60 ms
# of the start-up that the speed benchmark times).
bench: $(STAMP)
	$(BIN)/python -m compileall -q proximity adapters
	$(BIN)/python -m benchmarks

bench-quick: $(STAMP)
	$(BIN)/python -m compileall -q proximity adapters
	$(BIN)/python -m benchmarks --quick

clean:
	rm -rf $(VENV) bench-results .pytest_cache
