"""The NMM3D 40° backscatter look-up table and the peers run on its cases (shared by
``validation/iem/copol_ratio.py`` and ``validation/auto/nmm3d_table.py``).

The table: exact 3-D numerical solutions of Maxwell's equations (NMM3D) for exponentially
correlated surfaces, published by Tsang's group (Huang, Tsang, Njoku & Chen, IEEE TGRS 48
(2010) 2557 and the SMAP look-up tables). It is not in the repository: scripts take its path.
8 whitespace-separated columns, one case a row: θ [deg], ℓ/σ, Re ε, Im ε, σ/λ, σ⁰ VV, HH, HV
[dB] (``-Inf`` where the table has no HV). 40°: ℓ/σ ∈ {4, 7, 10, 15}, six soils
ε = 3 + i … 30 + 4.5i, σ/λ ∈ {0.021 … 0.21} (kσ 0.13–1.32; ℓ/σ = 4 stops at 0.168): 162 rows.

Peers run in a separate interpreter (``benchmarks/peers/setup.sh`` makes one with SMRT 1.7;
``pip install pyi2em`` into it adds pyi2em): each is used if it imports there.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np

#: The table's columns, in order.
COLUMNS = ("theta_deg", "l_over_sigma", "eps_re", "eps_im", "sigma_over_lambda", "vv", "hh", "hv")
#: The grid of the 40° table (used without the table: same cases, no exact columns).
RATIOS = (4.0, 7.0, 10.0, 15.0)
EPS = ((3.0, 1.0), (5.5, 2.0), (9.0, 2.5), (15.0, 3.5), (22.0, 4.0), (30.0, 4.5))
RMS = (0.021, 0.042, 0.063, 0.084, 0.126, 0.168, 0.210)
#: Frequency the peers are run at [Hz] (only kσ, kℓ matter; C band as SMRT's examples).
FREQUENCY = 5.405e9


def read_lut(path, theta_deg: float = 40.0) -> np.ndarray:
    """The table's rows at ``theta_deg`` as an ``(n, 8)`` float array (:data:`COLUMNS`).

    Raises ``ValueError`` naming the file when a row has not 8 columns or no row is at
    ``theta_deg``; ``-Inf`` (no HV in the table) is kept as ``-inf``."""
    path = Path(path)
    rows = []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        parts = line.split()
        if not parts or parts[0].startswith("#"):
            continue
        if len(parts) != len(COLUMNS):
            raise ValueError(
                f"nmm3d table {path.name!r} line {n}: {len(parts)} columns, "
                f"expected {len(COLUMNS)} ({', '.join(COLUMNS)})"
            )
        rows.append([float(p) for p in parts])  # float("-Inf") == -inf
    t = np.array(rows, dtype=float).reshape(-1, len(COLUMNS))
    t = t[np.isclose(t[:, 0], theta_deg, atol=1e-9)]
    if len(t) == 0:
        raise ValueError(f"nmm3d table {path.name!r}: no row at theta = {theta_deg} deg")
    if np.isnan(t).any():
        raise ValueError(f"nmm3d table {path.name!r}: NaN in the table")
    return t


def grid(theta_deg: float = 40.0) -> np.ndarray:
    """The 40° table's 162 cases without the exact columns (NaN there), same layout: the
    4 × 6 × 7 grid less ℓ/σ = 4 at σ/λ = 0.21 (slopes beyond the table's, absent there)."""
    return np.array(
        [[theta_deg, q, er, ei, h, math.nan, math.nan, math.nan]
         for q in RATIOS for er, ei in EPS for h in RMS if not (q == 4.0 and h == 0.21)]
    )  # fmt: skip


def atomic_write(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp's file is 0600: give it a normal file's mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


_PEERS = r"""
import json, sys, warnings
import numpy as np
warnings.simplefilter("ignore")
cases, theta, want, crosspol, f = json.loads(sys.argv[1])
k = 2 * np.pi * f / 299792458.0; mu = np.array([np.cos(np.radians(theta))])
out = {}
if "smrt" in want:
    try:
        from smrt.interface.iem_fung92 import IEM_Fung92
        from smrt.interface.iiem_fung02 import IIEM_Fung02
    except ImportError:
        pass
    else:
        for name, M, kw in (("smrt_iiem_fung02", IIEM_Fung02, dict(compute_crosspol=crosspol)),
                            ("smrt_iem_fung92", IEM_Fung92, {})):
            rows = []
            for ks, kl, er, ei in cases:
                m = M(roughness_rms=ks / k, corr_length=kl / k,
                      autocorrelation_function="exponential", warning_handling="nothing",
                      series_truncation=30, **kw)
                R = m.diffuse_reflection_matrix(f, 1, complex(er, ei), mu, mu, np.pi, 2)
                c = 4 * np.pi * mu[0]
                if M is IIEM_Fung02:
                    v = lambda i, j: float(np.asarray(R[i, j]).ravel()[0]) * c
                    hv = v(1, 0) if crosspol else float("nan")
                    rows.append([v(0, 0), v(1, 1), hv])
                else:
                    v = lambda i: float(np.asarray(R[i]).ravel()[0]) * c
                    rows.append([v(0), v(1), float("nan")])
            out[name] = rows
if "pyi2em" in want:
    try:
        import pyi2em
    except ImportError:
        pass
    else:
        rows = []
        for ks, kl, er, ei in cases:
            r = pyi2em.sigma0_backscatter(f / 1e9, ks / k, kl / k, theta, complex(er, ei),
                                          correl="exponential", include_hv=crosspol,
                                          return_db=False)
            hv = float(np.ravel(r["hv"])[0]) if crosspol else float("nan")
            rows.append([float(np.ravel(r["vv"])[0]), float(np.ravel(r["hh"])[0]), hv])
        out["pyi2em"] = rows
print(json.dumps(out))
"""


def run_peers(python, cases, theta_deg=40.0, want=("smrt", "pyi2em"), crosspol=True) -> dict:
    """Backscatter of the peers in interpreter ``python``: ``{name: (n, 3) array}`` of linear
    σ⁰ (VV, HH, HV; HV NaN where not computed or the model has none) for ``cases`` =
    ``[(kσ, kℓ, Re ε, Im ε), ...]``. Names: ``smrt_iiem_fung02``, ``smrt_iem_fung92``
    (SMRT 1.7, 30 series terms), ``pyi2em``; a peer that does not import there is absent."""
    cases = [list(map(float, c)) for c in cases]
    arg = json.dumps([cases, theta_deg, list(want), crosspol, FREQUENCY])
    res = subprocess.run(
        [str(python), "-c", _PEERS, arg], capture_output=True, text=True, check=True, timeout=3600
    )
    return {n: np.array(v, dtype=float) for n, v in json.loads(res.stdout).items()}
