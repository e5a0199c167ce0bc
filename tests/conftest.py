import os
import sys

# Shared test helpers (tests/laws.py) importable as `laws`.
sys.path.insert(0, os.path.dirname(__file__))
# Headless plotting everywhere.
os.environ.setdefault("MPLBACKEND", "Agg")
# The on-disk result cache (emscatter.cache) is off in tests unless a test turns it on with its
# own EMSCATTER_CACHE_DIR: results and evaluation counts must come from this run's code.
os.environ.setdefault("EMSCATTER_CACHE", "0")
