# emscatter — two commands on a fresh machine:
#   make demo   set up .venv (and a system libLLVM >= 17 for Mitsuba/Sionna's CPU backend), run the demo into out/
#   make test   the same setup, then the whole test suite
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test setup llvm lint bench validate clean

demo: setup
	$(VENV)/bin/emscatter demo --out out

test: setup
	$(PY) -m pytest -q -n 2

setup: llvm $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[all]"
	touch $(STAMP)

# Dr.Jit's LLVM backend (used by Mitsuba 3 and Sionna RT on the CPU) needs libLLVM >= 17 (libllvm19 on Debian 12).
llvm:
	@bash tools/ensure_llvm.sh

lint: setup
	$(VENV)/bin/ruff check src tests benchmarks validation examples
	$(VENV)/bin/ruff format --check src tests benchmarks validation examples

bench: setup
	$(PY) benchmarks/run_all.py

validate: setup
	$(VENV)/bin/emscatter validate

clean:
	rm -rf $(VENV) out .pytest_cache
