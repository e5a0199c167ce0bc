"""The 3-D measured-error table that ``method="auto"``'s ranking reads beside the 1-D one
(:func:`emscatter.solvers.measured.measured_errors_3d`), written from the 3-D method of
moments' validation cells (validation/mom3d/pec_table.py → ``pec_table_samples.json``, perfect
conductor; validation/mom3d/dielectric_table.py → ``dielectric_table_samples.json``, one map per
permittivity).

Per cell (θi, kσ, kℓ) and candidate of ``auto``: the σ⁰ error [dB] exactly as
validation/mom3d/pec_table.csv has it (the larger of h and v of the rms dB difference model −
mom3d over the 10° bins kept by :func:`emscatter.validation.maps._sigma0_error`), and its
Monte Carlo uncertainty by a **bootstrap over the realizations**: ``B`` resamples (with
replacement) of the cell's realizations, each giving mom3d's bin means and from them the
error again (over the bins kept by the full sample, so that the resampling does not change
which bins count; the coherent mean subtracted in each realization's sample is the full
sample's). ``se`` is the standard deviation of the ``B`` errors (Efron & Tibshirani 1993,
*An Introduction to the Bootstrap*, ch. 6); ``pair_se["a|b"]`` that of the difference of two
candidates' errors on the same resamples — the errors share the reference, so this paired
SE is the right "combined" one for comparing them (smaller than ``√(se_a² + se_b²)`` where
the errors move together). The models' σ⁰ carry no noise (closed forms).
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np

from ..io import atomic_path
from .maps import AUTO_TO_MAP, CAP_DB, DYNAMIC_RANGE_DB, _sigma0_error

__all__ = [
    "N_BOOT",
    "SCHEMAS",
    "TAGS",
    "bootstrap_cell",
    "map_tag",
    "measured_maps_3d",
    "write_measured_3d",
]

#: Bootstrap resamples per cell.
N_BOOT = 2000


def _keep(mean: np.ndarray, se: np.ndarray) -> np.ndarray:
    """Bins kept by the maps' rule (:func:`~emscatter.validation.maps._sigma0_error`)."""
    peak = np.max(mean, axis=-1, keepdims=True)
    return (mean >= 10 ** (-DYNAMIC_RANGE_DB / 10) * peak) & (se < 0.5 * mean)


def _rms_db(approx: np.ndarray, mom: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """rms over the kept bins of the clipped dB difference, larger of the pols: ``(…, 2, bins)``
    → ``(…)`` [dB] (nan where a pol keeps no bin)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        d = 10 * np.log10(np.maximum(approx, 1e-300) / mom)
    d = np.clip(np.nan_to_num(d, nan=CAP_DB), -CAP_DB, CAP_DB)
    n = keep.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.where(keep, d * d, 0.0).sum(axis=-1) / n)
    return np.max(rms, axis=-1)


def bootstrap_cell(mom: np.ndarray, models: dict, *, n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Errors and their bootstrap SE of one cell (module docstring).

    mom : ``(realizations, 2, bins)`` each realization's pooled co-pol bins (h, v).
    models : ``{auto name: (2, bins)}`` the models' bins.
    Returns ``{"errors", "se": {name: dB}, "pair_se": {"a|b": dB}}`` (nan where unmeasured)."""
    mom = np.asarray(mom, dtype=float)
    n = mom.shape[0]
    if n < 2:
        raise ValueError(f"realizations must be at least 2 for a bootstrap, got {n}")
    mean = mom.mean(axis=0)
    se = mom.std(axis=0, ddof=1) / math.sqrt(n)
    keep = _keep(mean, se)
    rng = np.random.default_rng(seed)
    boot = mom[rng.integers(0, n, size=(n_boot, n))].mean(axis=1)  # (B, 2, bins)
    errors, draws = {}, {}
    for name, approx in models.items():
        a = np.asarray(approx, dtype=float)
        per = [_sigma0_error(mean[p], se[p], a[p])["error_dB"] for p in (0, 1)]
        errors[name] = max(per) if all(math.isfinite(x) for x in per) else math.nan
        draws[name] = _rms_db(a[None], boot, keep[None])
    out_se = {m: float(np.std(d, ddof=1)) for m, d in draws.items()}
    pair = {
        f"{a}|{b}": float(np.std(draws[a] - draws[b], ddof=1))
        for a, b in itertools.combinations(models, 2)
    }
    return {"errors": errors, "se": out_se, "pair_se": pair}


#: Map tag of the perfect conductor per correlation.
TAGS = {"gaussian": "pec3d", "exponential": "pec3d_exp"}
#: Sample files :func:`write_measured_3d` reads.
SCHEMAS = ("mom3d_pec_samples/1", "mom3d_dielectric_samples/1")


def _eps_of(cell: dict):
    """``"pec"`` or ``(Re ε, Im ε)`` of a sample cell (cells without ``eps`` are PEC)."""
    e = cell.get("eps", "pec")
    return "pec" if isinstance(e, str) else (float(e[0]), float(e[1]))


def map_tag(correlation: str, eps) -> str:
    """``pec3d`` / ``pec3d_exp`` (:data:`TAGS`), or ``diel3d_eps<re>+<im>i`` (``_exp`` for the
    exponential) for a dielectric ``(Re ε, Im ε)``."""
    if eps == "pec":
        return TAGS[correlation]
    tail = "" if correlation == "gaussian" else "_exp"
    return f"diel3d_eps{eps[0]:g}+{eps[1]:g}i{tail}"


def measured_maps_3d(cells: list[dict], *, n_boot: int = N_BOOT) -> list[dict]:
    """The 3-D maps from sample cells (pec_table_samples.json's and
    dielectric_table_samples.json's): one per correlation (cells without one are Gaussian) and
    medium — the perfect conductor, and each permittivity ``eps`` of the dielectric cells (a
    map per ε, as the 1-D maps are per medium) — PEC maps first, then the dielectric ones by ε.
    Each has grids ``theta_i_deg × k_sigma × k_l`` and per candidate ``errors`` / ``se``
    [dB], per pair ``pair_se`` [dB], and ``realizations`` per cell (None where a cell is
    missing)."""
    groups: dict = {}
    for c in cells:
        groups.setdefault((str(c.get("correlation", "gaussian")), _eps_of(c)), []).append(c)
    order = sorted(groups, key=lambda g: (g[1] != "pec", str(g[1]), list(TAGS).index(g[0])))
    return [_map_3d(corr, groups[(corr, eps)], n_boot, eps) for corr, eps in order]


def _map_3d(correlation: str, cells: list[dict], n_boot: int, eps="pec") -> dict:
    inverse = {row: name for name, row in AUTO_TO_MAP.items()}
    ti = sorted({float(c["theta_i_deg"]) for c in cells})
    ks = sorted({float(c["k_sigma"]) for c in cells})
    kl = sorted({float(c["k_l"]) for c in cells})
    names = [inverse[m] for m in cells[0]["models"] if m in inverse] if cells else []

    def grid():
        return [[[None] * len(kl) for _ in ks] for _ in ti]

    errors = {n: grid() for n in names}
    se = {n: grid() for n in names}
    pairs = {f"{a}|{b}": grid() for a, b in itertools.combinations(names, 2)}
    real = grid()
    for c in cells:
        i, j = ti.index(float(c["theta_i_deg"])), ks.index(float(c["k_sigma"]))
        m = kl.index(float(c["k_l"]))
        models = {inverse[r]: v for r, v in c["models"].items() if r in inverse}
        got = bootstrap_cell(np.asarray(c["mom"], dtype=float), models, n_boot=n_boot)
        real[i][j][m] = int(c["realizations"])
        for name in names:
            e, s = got["errors"][name], got["se"][name]
            errors[name][i][j][m] = round(e, 3) if math.isfinite(e) else None
            se[name][i][j][m] = round(s, 3) if math.isfinite(s) else None
        for p, v in got["pair_se"].items():
            pairs[p][i][j][m] = round(v, 3) if math.isfinite(v) else None
    return {
        "tag": map_tag(correlation, eps),
        "correlation": correlation,
        "medium": "conductor" if eps == "pec" else "dielectric",
        "eps": "pec" if eps == "pec" else list(eps),
        "dimension": 2,
        "theta_i_deg": ti,
        "k_sigma": ks,
        "k_l": kl,
        "realizations": real,
        "errors": errors,
        "se": se,
        "pair_se": pairs,
    }


def write_measured_3d(samples, path=None, *, n_boot: int = N_BOOT) -> Path:
    """Write the 3-D table from ``samples`` (the path of a pec_table_samples.json or
    dielectric_table_samples.json, or a list of such paths: their cells together) to ``path``
    (default: the one the package reads, :data:`emscatter.solvers.measured.TABLE_3D_PATH`)
    atomically; clears the loader's cache.

    Command: ``PYTHONPATH=src python -c "from emscatter.validation.measured_table_3d import
    write_measured_3d; write_measured_3d(['validation/mom3d/pec_table_samples.json',
    'validation/mom3d/dielectric_table_samples.json'])"``."""
    from ..solvers import measured

    sources = [samples] if isinstance(samples, (str, Path)) else list(samples)
    if not sources:
        raise ValueError("samples must name at least one samples file, got an empty list")
    cells, names = [], []
    for s in sources:
        src = Path(s)
        if not src.exists():
            raise FileNotFoundError(
                f"samples={str(src)!r}: no such file (pec_table.py / dielectric_table.py write it)"
            )
        doc_in = json.loads(src.read_text())
        if doc_in.get("schema") not in SCHEMAS:
            raise ValueError(f"samples={str(src)!r}: schema {doc_in.get('schema')!r}, "
                             f"expected one of {SCHEMAS}")  # fmt: skip
        cells += doc_in["cells"]
        names.append(f"validation/mom3d/{src.name}")
    path = Path(path) if path else measured.TABLE_3D_PATH
    doc = {
        "about": "σ⁰ error [dB] vs the 3-D method of moments (larger of h, v) per cell, with "
        f"its Monte Carlo SE (bootstrap over realizations, B = {n_boot}; pair_se: SE of the "
        "difference of two candidates' errors on the same resamples); written by "
        "emscatter.validation.measured_table_3d.write_measured_3d from " + " and ".join(names),
        "maps": measured_maps_3d(cells, n_boot=n_boot),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(_dumps(doc))
    measured.load_table_3d.cache_clear()
    return path


def _dumps(doc: dict) -> str:
    """JSON with one θi slice per line (small, diffable)."""
    lines = ["{", f' "about": {json.dumps(doc["about"], ensure_ascii=False)},', ' "maps": [']
    grids = ("realizations", "errors", "se", "pair_se")
    for i, m in enumerate(doc["maps"]):
        head = {k: v for k, v in m.items() if k not in grids}
        lines.append("  {" + json.dumps(head, ensure_ascii=False)[1:-1] + ",")
        lines.append(f'   "realizations": {json.dumps(m["realizations"])},')
        for a, key in enumerate(grids[1:]):
            lines.append(f'   "{key}": {{')
            names = list(m[key])
            for b, name in enumerate(names):
                comma = "," if b < len(names) - 1 else ""
                lines.append(f'    "{name}": {json.dumps(m[key][name])}{comma}')
            lines.append("   }" + ("," if a < len(grids) - 2 else ""))
        lines.append("  }" + ("," if i < len(doc["maps"]) - 1 else ""))
    lines += [" ]", "}"]
    return "\n".join(lines) + "\n"
