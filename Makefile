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

DEMO_RUN := runs/demo

# Train RTAW briefly (the fast default PPO), then compare it with MPDM, RBTS and lookahead.
demo: $(STAMP)
	rm -rf $(DEMO_RUN)
	$(BIN)/rtaw-train frames=204800 eval.every_frames=40960 output_dir=$(DEMO_RUN)
	$(BIN)/rtaw-eval policy=[mpdm,rbts,lookahead,checkpoint] \
		checkpoint=$(DEMO_RUN)/checkpoints/best.pt seeds=[0,1,2,3,4,5,6,7,8,9] \
		output=$(DEMO_RUN)/results.json

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
