# emscatter — two commands on a fresh machine:
#   make demo   set up .venv (and a system libLLVM >= 17 for Mitsuba/Sionna's CPU backend), run the demo into out/
#   make test   the same setup, then the whole test suite
#   make lint   ruff check + format check;  make demo-quick  the demo on small grids (CI)
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo demo-quick test setup llvm lint bench validate clean

demo: setup
	$(VENV)/bin/emscatter demo --out out

# the demo on small grids (CI runs it after the tests): a scratch folder, removed first
demo-quick: setup
	rm -rf out/ci-demo
	$(VENV)/bin/emscatter demo --quick --out out/ci-demo

test: setup
	$(PY) -m pytest -q -n 2

setup: llvm $(STAMP)

# after the install: compile every numba kernel into its disk cache (python -m emscatter.warm,
# ~1 min of CPU once; never fails the setup), so a method's first call in a fresh process
# loads its kernels instead of compiling them (~20 s for IEM)
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[all]"
	$(PY) -m emscatter.warm || true
	touch $(STAMP)

# Dr.Jit's LLVM backend (used by Mitsuba 3 and Sionna RT on the CPU) needs libLLVM >= 17 (libllvm19 on Debian 12).
llvm:
	@bash tools/ensure_llvm.sh

# the folders that exist (examples/ arrives with the renderer bridge; a missing path is an error)
LINT_PATHS := $(wildcard src tests benchmarks validation examples)

lint: setup
	$(VENV)/bin/ruff check $(LINT_PATHS)
	$(VENV)/bin/ruff format --check $(LINT_PATHS)

bench: setup
	$(PY) benchmarks/run_all.py

validate: setup
	$(VENV)/bin/emscatter validate

clean:
	rm -rf $(VENV) out .pytest_cache
