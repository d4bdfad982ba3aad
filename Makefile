# Each target sets itself up: a fresh machine needs only python3 (3.11+) and make.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/mover demo

test: $(STAMP)
	$(PY) -m ruff check mover robots sim_hw programs experiments tests bench examples
	$(PY) -m ruff format --check mover robots sim_hw programs experiments tests bench examples README.md
	$(PY) -m mypy
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) bench/rpc.py

clean:
	rm -rf $(VENV) build *.egg-info
