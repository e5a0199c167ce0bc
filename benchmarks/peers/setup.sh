#!/usr/bin/env bash
# The peers' benchmark environment: SMRT, SurfaceTopography and tamaas in a separate virtual
# environment, so emscatter itself never depends on them. emscatter is used from this source
# tree (PYTHONPATH), with the same numpy/scipy/numba pins as the package.
#
#   bash benchmarks/peers/setup.sh            # -> $PEERS_VENV (default /tmp/emscatter-peers)
#   $PEERS_VENV/bin/python benchmarks/bench_peers.py
#
# Versions are pinned to the ones the results in benchmarks/results/ were measured with.
set -euo pipefail
PEERS_VENV="${PEERS_VENV:-/tmp/emscatter-peers}"
PYTHON="${PYTHON:-python3}"
if [ ! -x "$PEERS_VENV/bin/python" ]; then
    "$PYTHON" -m venv "$PEERS_VENV"
fi
"$PEERS_VENV/bin/python" -m pip install --quiet --upgrade pip
"$PEERS_VENV/bin/python" -m pip install --quiet \
    "smrt==1.7" "SurfaceTopography==1.27.1" "tamaas==2.9.0" \
    "numpy==2.4.6" "scipy==1.17.1" "numba==0.68.1" matplotlib tqdm
"$PEERS_VENV/bin/python" - <<'PY'
import importlib.metadata as md
for name in ("smrt", "SurfaceTopography", "tamaas", "numpy", "scipy", "numba"):
    print(f"{name} {md.version(name)}")
PY
echo "peers environment ready: $PEERS_VENV"
