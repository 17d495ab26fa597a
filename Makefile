# vibkit: two commands do everything on a fresh clone with Python 3.11.
#   make demo   creates .venv, installs, simulates the shipped scenes, analyses the field data, writes reports/
#   make test   creates .venv, installs, runs the whole test suite
#   make test-fast   the suite without the tests marked slow (the inner loop while editing)
PYTHON ?= python3.11
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test test-fast lint format bench docs install clean
# `make bench` regenerates benchmarks/results/ (about 30 min on 2 cores); `vibkit bench --quick` is a smoke
# run that writes into a temporary folder (or -o DIR), never into benchmarks/results/

$(BIN)/python:
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found; set PYTHON=/path/to/python3.11" >&2; exit 1; }
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

install: $(STAMP)

# the suite in as many processes as the machine has cores, at most 4 (pytest-xdist), each test file whole on one
# (its module fixtures built once); TEST_WORKERS=0 runs it in this process
TEST_WORKERS ?= auto
test: $(STAMP)
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --maxprocesses=4 --dist loadfile

# every test but those marked @pytest.mark.slow (the longest physics runs, the install test, the corpus cases
# that need a process of their own): the inner loop while editing; `make test` runs them all
test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow" -n $(TEST_WORKERS) --maxprocesses=4 --dist loadfile

# ruff's lint and format check, and mypy on the public API (the configurations are in pyproject.toml);
# `make format` rewrites
lint: $(STAMP)
	$(BIN)/ruff check vibkit tests benchmarks
	$(BIN)/ruff format --check vibkit tests benchmarks
	$(BIN)/mypy

format: $(STAMP)
	$(BIN)/ruff format vibkit tests benchmarks
	$(BIN)/ruff check --fix vibkit tests benchmarks

demo: $(STAMP)
	$(BIN)/python -m vibkit.demo

$(VENV)/.bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	@touch $(VENV)/.bench

bench: $(VENV)/.bench
	$(BIN)/vibkit bench -o benchmarks/results

# the documentation: docs/ -> docs/_build/html (Sphinx; every warning is an error; under a minute)
$(VENV)/.docs: $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,docs]'
	@touch $(VENV)/.docs

docs: $(VENV)/.docs
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html

clean:
	rm -rf $(VENV) build *.egg-info docs/_build docs/api/generated docs/benchmarks/results docs/auto_examples docs/sg_execution_times.rst
