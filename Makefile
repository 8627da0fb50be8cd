# fuzzkit: the README's commands. Each target sets up what it needs by itself.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.fuzzkit-installed
# The development and CI environment is pinned (hashes included) by requirements/dev.lock,
# resolved by `make lock`; users installing the package get the ranges in pyproject.toml.
LOCK := requirements/dev.lock
# The newest versions the ranges allow, in their own environment (`make test-latest`).
LATEST_VENV ?= .venv-latest
# Peer libraries for the benchmark live in their own environment: pyfuzzylite pins numpy<2,
# which would drag the project's environment back to an old rerun-sdk. typereduction is
# pyit2fls's optional C back end (its fastest Karnik-Mendel); the interop environment leaves it
# out, so the committed pyit2fls references stay its Python KM's.
BENCH_VENV ?= .venv-bench
BENCH_STAMP := $(BENCH_VENV)/.peers-installed
# The independent implementations the interop tests compare with: pyfuzzylite (own environment,
# for the same numpy<2 reason), pyit2fls (interval type-2) and the fuzzylite 6 program from
# Debian's fuzzylite package.
INTEROP_VENV ?= .venv-interop
INTEROP_STAMP := $(INTEROP_VENV)/.peers-installed
SUDO ?= $(shell [ "$$(id -u)" = 0 ] || echo sudo)
DEMO_OUT ?= demo-out
PYTEST_WORKERS ?= 2
# mypy and import-linter do not follow setuptools' editable-install finder, which is what maps
# codegen/ and planar_sim/ into the one installed package; they read this tree of symlinks,
# laid out as the wheel installs it (fuzzkit/, fuzzkit/codegen, fuzzkit/planar_sim, ...).
PACKAGE_TREE := build/package-tree
# mypy's incremental cache, outside the package tree (which is laid anew on every run): a fresh
# clone checks cold (about a minute), later runs only re-check what changed (a few seconds).
MYPY_CACHE := $(CURDIR)/.mypy_cache
# The repository folders installed inside fuzzkit (codegen planar_sim rulebases), read from setup.py.
MAPPED_FOLDERS := $(shell sed -n 's/^MAPPED_FOLDERS = (\(.*\))/\1/p' setup.py | tr -d '",')

.PHONY: demo test test-latest verify bench interop interop-refs fuzzylite-program lint typecheck imports golden lock clean package-tree embedded embedded-toolchain

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml setup.py $(LOCK) | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet --require-hashes -r $(LOCK)
	$(BIN)/python -m pip install --quiet --no-deps -e .
	touch $@

demo: $(STAMP)
	$(BIN)/fuzzkit demo --out $(DEMO_OUT)

# The whole suite: static checks first (cheap, and they catch what tests miss), then pytest.
# The live peer comparisons are `make interop`'s; here fuzzkit is compared with the peers'
# committed outputs (tests/peers/refs, `make interop-refs`), so no peer need be installed.
PEER_MARKS := needs_fuzzylite or needs_pyfuzzylite
# `$(call timed,TARGET)`: runs `make TARGET` and prints how long it took (the static checks'
# share of `make test` stays visible); a failure stops the recipe with the target's status.
define timed
	@start=$$(date +%s%N); $(MAKE) --no-print-directory $(1) VENV=$(VENV) || exit $$?; \
		echo "$(1): $$(( ($$(date +%s%N) - start) / 1000000 )) ms"
endef
# The numba kernels compile in the background while the static checks run (one process, on
# the core mypy leaves free, holding WARM_LOCK); pytest's own warm-up waits for it and finds
# them cached, its workers collect meanwhile (tests/conftest.py).
WARM_LOCK := build/warm.lock
test: $(STAMP)
	$(BIN)/python -m fuzzkit.studies.warm --background $(WARM_LOCK) --jobs 1
	$(call timed,lint)
	$(call timed,typecheck)
	$(call timed,imports)
	FUZZKIT_WARM_LOCK=$(CURDIR)/$(WARM_LOCK) $(BIN)/python -m pytest -n $(PYTEST_WORKERS) \
		--dist loadgroup -q -p no:cacheprovider -m "not ($(PEER_MARKS)) and not verify" \
		--durations=25

# The deep versions of the matrices that `make test` runs a covering set of (every value and
# every pair of values of two axes, tests/_pairwise.py): the tests marked `verify`, i.e. the
# full safety products at 50 seeds, every generated-C mutant, the full fuzz counts, the release
# build of the sdist and wheel (docs/development.md lists them with their sizes).
verify: $(STAMP)
	$(BIN)/python -m pytest -n $(PYTEST_WORKERS) --dist loadgroup -q -p no:cacheprovider -m verify \
		--durations=25

# The suite against the newest versions pyproject.toml's ranges allow (not the lock): run it on
# purpose to catch a dependency drift before the next `make lock` does.
test-latest:
	rm -rf $(LATEST_VENV)
	$(PYTHON) -m venv $(LATEST_VENV)
	$(LATEST_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(LATEST_VENV)/bin/python -m pip install --quiet --upgrade --upgrade-strategy eager -e '.[dev]'
	$(LATEST_VENV)/bin/python -m pip list --format=freeze | grep -iE '^(numpy|scipy|numba|pymunk|rerun-sdk|matplotlib)=='
	$(MAKE) --no-print-directory test VENV=$(LATEST_VENV) STAMP=$(LATEST_VENV)/bin/python

# Refresh the lock file from pyproject.toml (newest versions inside the ranges), with hashes.
lock: | $(BIN)/python
	$(BIN)/python -m pip install --quiet "uv==0.13.8"
	$(BIN)/uv pip compile pyproject.toml --extra dev --python-version 3.11 \
		--python-platform x86_64-unknown-linux-gnu --generate-hashes --no-header --quiet \
		--upgrade -o $(LOCK)

package-tree:
	rm -rf $(PACKAGE_TREE) && mkdir -p $(PACKAGE_TREE)/fuzzkit
	for entry in fuzzkit/*; do ln -s "$(CURDIR)/$$entry" $(PACKAGE_TREE)/fuzzkit/; done
	for folder in $(MAPPED_FOLDERS); do ln -s "$(CURDIR)/$$folder" $(PACKAGE_TREE)/fuzzkit/$$folder; done

lint: $(STAMP)
	$(BIN)/ruff check fuzzkit $(MAPPED_FOLDERS) tests bench setup.py
	$(BIN)/ruff format --check fuzzkit $(MAPPED_FOLDERS) tests bench setup.py

typecheck: $(STAMP) package-tree
	cd $(PACKAGE_TREE) && $(CURDIR)/$(BIN)/mypy --config-file $(CURDIR)/pyproject.toml \
		--cache-dir $(MYPY_CACHE) fuzzkit

# The layering contract of docs/architecture.md ([tool.importlinter] in pyproject.toml).
imports: $(STAMP) package-tree
	cd $(PACKAGE_TREE) && PYTHONPATH=$(CURDIR)/$(PACKAGE_TREE) \
		$(CURDIR)/$(BIN)/lint-imports --no-cache --config $(CURDIR)/pyproject.toml

$(BENCH_VENV)/bin/python:
	$(PYTHON) -m venv $(BENCH_VENV)

$(BENCH_STAMP): | $(BENCH_VENV)/bin/python
	$(BENCH_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(BENCH_VENV)/bin/python -m pip install --quiet "scikit-fuzzy==0.5.0" packaging networkx scipy "pyfuzzylite==8.0.6" "pyit2fls==0.9.0" "typereduction==0.2.2"
	touch $@

bench: $(STAMP) $(BENCH_STAMP)
	$(BIN)/python bench/run.py --peers-python $(BENCH_VENV)/bin/python

$(INTEROP_VENV)/bin/python:
	$(PYTHON) -m venv $(INTEROP_VENV)

$(INTEROP_STAMP): | $(INTEROP_VENV)/bin/python
	$(INTEROP_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(INTEROP_VENV)/bin/python -m pip install --quiet "pyfuzzylite==8.0.6" "pyit2fls==0.9.0"
	touch $@

fuzzylite-program:
	command -v fuzzylite >/dev/null || { $(SUDO) apt-get update -qq && \
		$(SUDO) apt-get install -y -qq --no-install-recommends fuzzylite; }

# FIS/FCL/FLL equivalence with fuzzylite 6 and pyfuzzylite 8: installs both, runs the marked
# tests (skips listed with -rs), then prints the largest differences per format.
interop: $(STAMP) $(INTEROP_STAMP) fuzzylite-program
	FUZZKIT_INTEROP_PYTHON=$(INTEROP_VENV)/bin/python $(BIN)/python -m pytest -q -n 0 \
		-p no:cacheprovider -m "$(PEER_MARKS)" -rs tests
	FUZZKIT_INTEROP_PYTHON=$(INTEROP_VENV)/bin/python $(BIN)/python bench/interop_equivalence.py

# Rewrite the peers' committed outputs (tests/peers/refs) that `make test` compares with.
interop-refs: $(STAMP) $(INTEROP_STAMP) fuzzylite-program
	FUZZKIT_INTEROP_PYTHON=$(INTEROP_VENV)/bin/python $(BIN)/python tests/peers/make_refs.py
	FUZZKIT_INTEROP_PYTHON=$(INTEROP_VENV)/bin/python $(BIN)/python tests/peers/make_it2_refs.py

# The generated controller (float, Cortex-M4F) and the Q15 table (Cortex-M3, M0) under QEMU,
# bit for bit against the host, with flash/RAM and instructions per call (bench/embedded/).
# Installs the cross toolchain and QEMU when missing and this runs as root (CI); otherwise
# says what to install.
EMBEDDED_PACKAGES := gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm
embedded: $(STAMP) embedded-toolchain
	$(BIN)/python bench/embedded/run.py --json build/embedded.json

# The cross toolchain alone: CI installs it before `make test`, so the nm "float-free" checks
# (tests/test_embedded_symbols.py) run there; with CI=true a missing toolchain fails them.
embedded-toolchain:
	@if ! command -v arm-none-eabi-gcc >/dev/null || ! command -v qemu-system-arm >/dev/null \
		|| [ ! -e /usr/lib/arm-none-eabi/newlib/libc.a ]; then \
		if [ "$$(id -u)" = 0 ]; then \
			apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
				apt-get install -y -qq --no-install-recommends $(EMBEDDED_PACKAGES); \
		else \
			echo "make embedded needs: $(EMBEDDED_PACKAGES)"; \
			echo "install them as root: apt-get install --no-install-recommends $(EMBEDDED_PACKAGES)"; \
			exit 2; \
		fi; \
	fi

# Rewrite the expected generated files under tests/golden/ after an intended change.
golden: $(STAMP)
	FUZZKIT_REFRESH_GOLDEN=1 $(BIN)/python -m pytest -q tests -k golden

clean:
	rm -rf $(VENV) $(LATEST_VENV) $(BENCH_VENV) $(INTEROP_VENV) $(DEMO_OUT) build dist *.egg-info .pytest_cache .mypy_cache .ruff_cache
