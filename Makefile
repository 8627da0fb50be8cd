# fuzzkit: the README's commands. Each target sets up what it needs by itself.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.fuzzkit-installed
# Peer libraries for the benchmark live in their own environment: pyfuzzylite pins numpy<2,
# which would drag the project's environment back to an old rerun-sdk.
BENCH_VENV ?= .venv-bench
BENCH_STAMP := $(BENCH_VENV)/.peers-installed
DEMO_OUT ?= demo-out
PYTEST_WORKERS ?= 2

.PHONY: demo test bench lint typecheck golden clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

demo: $(STAMP)
	$(BIN)/fuzzkit demo --out $(DEMO_OUT)

# The whole suite: static checks first (cheap, and they catch what tests miss), then pytest.
test: $(STAMP)
	$(BIN)/ruff check fuzzkit codegen planar_sim tests bench
	$(BIN)/mypy
	$(BIN)/python -m pytest -n $(PYTEST_WORKERS) -q -p no:cacheprovider

$(BENCH_VENV)/bin/python:
	$(PYTHON) -m venv $(BENCH_VENV)

$(BENCH_STAMP): | $(BENCH_VENV)/bin/python
	$(BENCH_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(BENCH_VENV)/bin/python -m pip install --quiet "scikit-fuzzy==0.5.0" packaging networkx scipy "pyfuzzylite==8.0.6"
	touch $@

bench: $(STAMP) $(BENCH_STAMP)
	$(BIN)/python bench/run.py --peers-python $(BENCH_VENV)/bin/python

lint: $(STAMP)
	$(BIN)/ruff check fuzzkit codegen planar_sim tests bench

typecheck: $(STAMP)
	$(BIN)/mypy

# Rewrite the expected generated files under tests/golden/ after an intended change.
golden: $(STAMP)
	FUZZKIT_REFRESH_GOLDEN=1 $(BIN)/python -m pytest -q tests -k golden

clean:
	rm -rf $(VENV) $(BENCH_VENV) $(DEMO_OUT) build dist *.egg-info .pytest_cache .mypy_cache .ruff_cache
