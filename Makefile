# Each target sets itself up: a fresh machine needs only python3 (3.11+) and make.
#   make check     ruff, the format check, mypy and the quick tests (minutes): before a commit
#   make test      the same checks and every test (what CI runs, through .ci/run)
#   make docs      the documentation site in site/ (strict: a warning fails it)
#   make coverage  the tests under coverage, processes they start included (TESTS= narrows)
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
CODE := mover robots sim_hw programs experiments tests bench examples
# The quick set: no test marked slow, none that starts a process (tests/conftest.py keeps the
# `processes` mark true).
QUICK := -m "not slow and not processes"
TESTS ?=

.PHONY: demo lint check test coverage bench docs clean

# The demo needs mover alone (no viewer, no test tools); every other target the test extra.
BASE := $(VENV)/.base

$(BASE): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e .
	touch $(BASE)

$(STAMP): $(BASE)
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

demo: $(BASE)
	$(VENV)/bin/mover demo

lint: $(STAMP)
	$(PY) -m ruff check $(CODE)
	$(PY) -m ruff format --check $(CODE) README.md docs
	$(PY) -m mypy

check: lint
	$(PY) -m pytest -q $(QUICK)

test: lint
	$(PY) -m pytest -q --durations=30

coverage: $(STAMP)
	$(PY) -m coverage erase
	$(PY) -m coverage run -m pytest -q --durations=30 $(TESTS)
	$(PY) -m coverage combine -q
	$(PY) -m coverage report

docs: $(STAMP)
	$(VENV)/bin/mkdocs build --strict

bench: $(STAMP)
	$(PY) bench/rpc.py

clean:
	rm -rf $(VENV) build site *.egg-info .coverage .coverage.* htmlcov
