# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint format bench clean

$(STAMP): pyproject.toml
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# torch is pinned exactly: the local CPU wheel, never a multi-GB CUDA build.
	$(BIN)/pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/rtaw-eval scenario=default policy=[mpdm,rbts,random] seeds=[0,1,2]

test: $(STAMP)
	$(BIN)/ruff check rtaw_marl tests experiments
	$(BIN)/ruff format --check rtaw_marl tests experiments
	$(BIN)/python -m pytest -n 2 -q

lint: $(STAMP)
	$(BIN)/ruff check rtaw_marl tests experiments
	$(BIN)/ruff format --check rtaw_marl tests experiments

format: $(STAMP)
	$(BIN)/ruff format rtaw_marl tests experiments
	$(BIN)/ruff check --fix rtaw_marl tests experiments

bench: $(STAMP)
	$(BIN)/python experiments/bench_env.py

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache
