# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-fast lint format bench clean lorr-kit browser docs

$(STAMP): pyproject.toml
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# .[dev] = the env, the cli and train extras, the test tools. torch is capped (<2.14):
	# the local CPU wheel, never a new multi-GB CUDA build.
	$(BIN)/pip install --quiet -e ".[dev]"
	# BenchMARL 1.5.2 declares torchrl<0.12; its code runs on torchrl 0.14 through the
	# alias in rtaw_marl/integrations/benchmarl.py, so it goes in without its declared
	# dependencies (its real ones are in [train]; docs/benchmarl.md).
	$(BIN)/pip install --quiet --no-deps benchmarl==1.5.2
	touch $(STAMP)

# What ruff checks: the package, its tests, the benchmarks project beside it.
SOURCES := rtaw_marl tests benchmarks

DEMO_RUN := runs/demo

# Train RTAW+ briefly (a lookahead warm start, then PPO), then compare it, the shipped
# generalist RTAW+ (one policy for every scenario) and the generalist searched at decision
# time (policy=search) with MPDM, RBTS, lookahead and the best rule of the setting on 20
# evaluation seeds of the default scenario; then a page to explore the searched generalist
# and lookahead side by side, executed collision-free (open runs/demo/view.html).
demo: $(STAMP)
	rm -rf $(DEMO_RUN)
	$(BIN)/rtaw-train model=rtaw_plus imitation.teacher=lookahead imitation.frames=16384 \
		frames=40960 selection.every_frames=20480 output_dir=$(DEMO_RUN)
	$(BIN)/rtaw-eval policy=[mpdm,rbts,lookahead,pretrained,search,checkpoint] \
		pretrained=generalist_plus search.policy=generalist_plus \
		checkpoint=$(DEMO_RUN)/checkpoints/best.pt \
		'seeds=$${range:0,20}' compare_to=best output=$(DEMO_RUN)/results.json
	$(BIN)/rtaw-view navigator=sipp sim.num_tasks=100 policy=[lookahead,search] \
		search.policy=generalist_plus output=$(DEMO_RUN)/view.html

# LoRR's start kit (../shared), built once per machine into ~/.cache/rtaw_marl/lorr: a
# few minutes the first time, then nothing. The system packages it needs (cmake, Boost)
# are installed here with apt-get when missing and root; the library itself never installs
# any. Its tests (tests/integrations/test_lorr_kit.py) run rtaw_marl schedulers in it.
lorr-kit: $(STAMP)
	@missing="$$($(BIN)/python -m rtaw_marl.integrations.lorr.kit --missing)"; \
	if [ -n "$$missing" ]; then \
		if [ "$$(id -u)" != 0 ]; then \
			echo "error: LoRR's start kit needs: sudo apt-get install $$missing" >&2; exit 2; fi; \
		export DEBIAN_FRONTEND=noninteractive; \
		apt-get install -y -qq --no-install-recommends $$missing >/dev/null || \
			{ apt-get update -qq && apt-get install -y -qq --no-install-recommends $$missing >/dev/null; }; \
	fi
	$(BIN)/python -m rtaw_marl.integrations.lorr.kit

# Headless Chromium and its driver (Debian's packages) for the viewer's browser tests
# (tests/viz/test_view_browser.py): installed with apt-get when missing and root.
browser:
	@if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then \
		if [ "$$(id -u)" != 0 ]; then \
			echo "error: the browser tests need Debian's chromium and chromium-driver:" \
				"sudo apt-get install chromium chromium-driver" >&2; exit 2; fi; \
		export DEBIAN_FRONTEND=noninteractive; \
		apt-get install -y -qq chromium chromium-driver >/dev/null || \
			{ apt-get update -qq && apt-get install -y -qq chromium chromium-driver >/dev/null; }; \
	fi

# Every tier, as CI runs it: unit, integration and system (venv installs, LoRR's kit, the
# browser, Ray); the API reference's build is one of the tests (tests/test_docs_build.py).
test: $(STAMP) lorr-kit browser
	$(BIN)/ruff check $(SOURCES)
	$(BIN)/ruff format --check $(SOURCES)
	$(BIN)/python -m pytest -n 2 -q

# The unit tier only, for your own loop (under 2 minutes on 2 cores).
test-fast: $(STAMP)
	$(BIN)/ruff check $(SOURCES)
	$(BIN)/ruff format --check $(SOURCES)
	$(BIN)/python -m pytest -n 2 -q --tier unit

lint: $(STAMP)
	$(BIN)/ruff check $(SOURCES)
	$(BIN)/ruff format --check $(SOURCES)

format: $(STAMP)
	$(BIN)/ruff format $(SOURCES)
	$(BIN)/ruff check --fix $(SOURCES)

bench: $(STAMP)
	$(BIN)/python -m benchmarks.scripts.bench_env

# The documentation site (mkdocs.yml): docs/ and the API reference generated from the
# docstrings (docs/api/), offline, into build/site. Browse it with
# `python -m http.server -d build/site` (http://localhost:8000).
docs: $(STAMP)
	$(BIN)/mkdocs build --strict --site-dir build/site

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache
