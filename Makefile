# silbridge: the two commands of the README, and their set-up.
#   make bench   set up, then run the main job (the paper's protocol)
#   make test    set up, then run the whole test suite
# Set-up is idempotent: a virtual environment in .venv (created if missing),
# the project installed editable with its test extras (this also compiles the
# C extensions), and the Cortex-M4F cross compiler from Debian for the
# portability check of the flight-controller core.

VENV    ?= .venv
PY      := $(VENV)/bin/python
PIP     := $(PY) -m pip
PYTHON  ?= python3
BENCH_ARGS ?=

.PHONY: setup sysdeps test bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip "setuptools>=69" wheel

sysdeps:
	@./tools/install_sysdeps.sh

setup: $(PY) sysdeps
	$(PIP) install -q -e ".[test]"

test: setup
	$(PY) -m pytest -q tests

bench: setup
	$(VENV)/bin/silbridge shm-bench $(BENCH_ARGS)

clean:
	rm -rf build *.egg-info shm/*.so fc_sil/*.so .pytest_cache
