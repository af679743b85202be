# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: demo test lint bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet "torch==2.13.0"
	$(BIN)/python -m pip install --quiet -e ".[learn,export,ingest,dev]"
	$(BIN)/python -m pip install --quiet --no-deps rotorpy  # the peer-validation tests (its simulator needs only NumPy/SciPy)
	rm -f $(VENV)/.installed-* && touch $(STAMP)

demo: $(STAMP)
	$(BIN)/aerodock reproduce --quick --out out/demo

test: $(STAMP)
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check aerodock tests bench

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet --no-deps rotorpy torchdiffeq roma
	$(BIN)/aerodock bench

clean:
	rm -rf $(VENV) build *.egg-info
