# silbridge: the two commands of the README, and their set-up.
#   make bench   set up, then run the main job (the paper's protocol)
#   make test    set up, then run the whole test suite
# Set-up is idempotent: a virtual environment in .venv (created if missing) and
# the project installed editable (this also compiles the C extensions). `make bench`
# installs the light set only (pyproject.toml's dependencies: what fly, bench and
# its report need); `make test` adds the test extras and the Cortex-M4F cross
# compiler from Debian for the portability check of the flight-controller core.

VENV    ?= .venv
PY      := $(VENV)/bin/python
PIP     := $(PY) -m pip
PYTHON  ?= python3
BENCH_ARGS ?=
BENCH_OUT  ?= bench-out
SB      := $(VENV)/bin/silbridge

.PHONY: setup setup-light sysdeps test bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip "setuptools>=77" wheel

sysdeps:
	@./tools/install_sysdeps.sh

# setuptools always adds an informational "Editable installation." warning to an editable
# install; it says nothing about this project, so it is filtered out by its exact text.
setup: $(PY) sysdeps
	PYTHONWARNINGS="ignore:Editable installation" $(PIP) install -q -e ".[test]"

# No extras, no system packages: an environment set up by `make setup` keeps its extras.
setup-light: $(PY)
	PYTHONWARNINGS="ignore:Editable installation" $(PIP) install -q -e .

test: setup
	$(PY) -m pytest -q tests

# The paper's protocol: S1..S4, N = 20 runs of 120 s each (Table 1), then the
# transport comparison (Table 2). Change a gain and compare:
#   make bench BENCH_ARGS="--param ATC_RAT_RLL_D=0.004" BENCH_OUT=bench-d004
bench: setup-light
	$(SB) bench --out $(BENCH_OUT) $(BENCH_ARGS)
	$(SB) transport --out $(BENCH_OUT)/transport

clean:
	rm -rf build dist *.egg-info shm/*.so fc_sil/*.so bridge/*.so .pytest_cache
