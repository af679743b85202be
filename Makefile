# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)
# Where the CPU build of PyTorch comes from. Empty: pip's configured indexes (on the project's
# machines they hold the CPU wheel). Elsewhere on Linux, PyPI's torch is the CUDA build (GBs):
#   make test TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu
TORCH_INDEX_URL ?=
TORCH_PIP_ARGS := $(if $(TORCH_INDEX_URL),--index-url $(TORCH_INDEX_URL))
EXTRAS := learn,export,ingest,ros,gym,ray,parquet,viz,dev

.PHONY: demo test test-e2e lint bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet $(TORCH_PIP_ARGS) "torch==2.13.0"
	$(BIN)/python -m pip install --quiet -e ".[$(EXTRAS)]"
	$(BIN)/python -m pip install --quiet --no-deps rotorpy  # peer-validation tests (its simulator needs only NumPy/SciPy)
	$(BIN)/python -m aerodock.mission.warm  # compile the world's kernels once (numba's disk cache)
	rm -f $(VENV)/.installed-* && touch $(STAMP)

demo: $(STAMP)
	$(BIN)/aerodock reproduce --quick --out out/demo

# Two xdist workers (the machines have 2 cores), one file at a time each (a file's fixtures are
# built once), in collection order: tests/conftest.py puts the long `reproduce --quick` runs first.
PYTEST_XDIST := -n 2 --dist loadfile --no-loadscope-reorder --durations=15

# The import layering first (a second; pyproject.toml's [tool.importlinter] contracts): a broken
# contract fails CI before the tests run.
# Then the bytecode: where PYTHONDONTWRITEBYTECODE is set (this project's machines set it),
# every process the suite starts (its CLI runs, study scripts, xdist workers) would otherwise
# compile the package's sources again (importing the mission, the CLI and the learnt runtime:
# 1.4 s against 0.75 s from bytecode); compileall writes them once, and only what changed since.
test: $(STAMP)
	$(BIN)/lint-imports
	$(BIN)/python -m compileall -q aerodock tests studies tools > /dev/null
	$(BIN)/python -m pytest -q $(PYTEST_XDIST)

# The end-to-end run at the size `make demo` makes (`reproduce --quick`, about 10 minutes on one
# core) with its checks of the figures; `make test` runs it as `reproduce --smoke`.
test-e2e: $(STAMP)
	AERODOCK_E2E=quick $(BIN)/python -m pytest -q tests/e2e

lint: $(STAMP)
	$(BIN)/ruff check aerodock tests studies
	$(BIN)/lint-imports

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet --no-deps rotorpy torchdiffeq roma
	$(BIN)/aerodock bench

clean:
	rm -rf $(VENV) build *.egg-info
