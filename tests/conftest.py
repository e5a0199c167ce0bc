import os
import sys

# Shared test helpers (tests/laws.py) importable as `laws`.
sys.path.insert(0, os.path.dirname(__file__))
# Headless plotting everywhere.
os.environ.setdefault("MPLBACKEND", "Agg")
