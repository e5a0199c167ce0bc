"""Metals from the η/k spectra that Mitsuba 3 ships (``mitsuba/data/ior/<name>.eta.spd`` and
``<name>.k.spd``), so that emscatter and Mitsuba's ``conductor`` / ``roughconductor`` with
``material="Au"`` use the very same data.

The files are read directly (Mitsuba is not imported, so no Dr.Jit variant is set): lines of
``wavelength [nm]  value``, ``#`` comments. Their headers name the origin of each table (for the
common metals: the luxpop.com database; the ``*_palik`` files: Palik's *Handbook of Optical
Constants of Solids*). Like Mitsuba's spectral variants, the index is interpolated linearly in
wavelength between the samples; outside them :class:`~emscatter.materials.OutOfBandError`
(or ``extrapolate=True``: end values held constant).
"""

from __future__ import annotations

import importlib.util
import sys
from functools import lru_cache
from pathlib import Path

import numpy as np

from .core import Tabulated

__all__ = ["metal", "available_metals", "mitsuba_ior_dir", "read_spd"]


def mitsuba_ior_dir() -> Path:
    """The folder of Mitsuba's η/k spectra, found without importing Mitsuba."""
    mod = sys.modules.get("mitsuba")
    origin = getattr(mod, "__file__", None) if mod is not None else None
    if origin is None:
        spec = importlib.util.find_spec("mitsuba")
        origin = spec.origin if spec is not None else None
    if origin is None:
        raise ModuleNotFoundError(
            "metal spectra come from Mitsuba 3's data files (mitsuba/data/ior); install it with "
            "`pip install mitsuba` (or `pip install emscatter[render]`), or give the metal's "
            "permittivity yourself (materials.Tabulated or materials.ComplexIndex)"
        )
    folder = Path(origin).parent / "data" / "ior"
    if not folder.is_dir():
        raise FileNotFoundError(f"Mitsuba is installed but has no η/k data folder at {folder}")
    return folder


def available_metals() -> list[str]:
    """Names with both an ``.eta.spd`` and a ``.k.spd`` file (e.g. Au, Ag, Cu, Al, Cr)."""
    return list(_metal_names(mitsuba_ior_dir()))


@lru_cache(maxsize=8)
def _metal_names(folder: Path) -> tuple[str, ...]:  # read once per process: a farm's tables
    eta = {p.name[: -len(".eta.spd")] for p in folder.glob("*.eta.spd")}  # each asked (10 ms)
    k = {p.name[: -len(".k.spd")] for p in folder.glob("*.k.spd")}
    return tuple(sorted(eta & k))


def read_spd(path: Path) -> tuple[np.ndarray, np.ndarray, str]:
    """``(wavelength [nm], value, header)`` of a Mitsuba ``.spd`` file."""
    lam, val, header = [], [], []
    for lineno, line in enumerate(Path(path).read_text().splitlines(), 1):
        text = line.strip()
        if not text:
            continue
        if text.startswith("#"):
            header.append(text.lstrip("# ;").strip())
            continue
        parts = text.split()
        try:
            a, b = float(parts[0]), float(parts[1])
        except (ValueError, IndexError):
            raise ValueError(
                f"{path}:{lineno}: expected 'wavelength value', got {text!r}"
            ) from None
        lam.append(a)
        val.append(b)
    if len(lam) < 2:
        raise ValueError(f"{path}: fewer than 2 samples")
    # the first header line names the origin ("data from www.luxpop.com database", Palik, ...)
    return np.array(lam), np.array(val), next((h for h in header if h), "")


@lru_cache(maxsize=64)
def _load(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    folder = mitsuba_ior_dir()
    eta_path, k_path = folder / f"{name}.eta.spd", folder / f"{name}.k.spd"
    if not (eta_path.is_file() and k_path.is_file()):
        raise ValueError(
            f"metal must be one of Mitsuba's η/k spectra {available_metals()}, got {name!r}"
        )
    lam_n, n, head = read_spd(eta_path)
    lam_k, k, _ = read_spd(k_path)
    if lam_n.shape != lam_k.shape or not np.allclose(lam_n, lam_k, rtol=0, atol=1e-6):
        # different sample grids: put k on η's grid (linear, as Mitsuba does per spectrum)
        k = np.interp(lam_n, lam_k, k)
    return lam_n, n, k, head


def metal(name: str, *, extrapolate: bool = False) -> Tabulated:
    """A metal from Mitsuba's own η/k tables (``name`` as Mitsuba's ``material=``: "Au", "Ag",
    "Cu", "Al", "Cr", "Cu_palik", ...); complex index interpolated linearly in wavelength."""
    if not isinstance(name, str):
        raise TypeError(f"metal name must be a string like 'Au', got {name!r}")
    lam_nm, n, k, head = _load(name)
    version = _mitsuba_version()
    source = f"Mitsuba 3{version} data/ior/{name}.eta.spd + {name}.k.spd" + (
        f" ({head})" if head else ""
    )
    return Tabulated(lam_nm * 1e-9, n=n, k=k, name=name, source=source, extrapolate=extrapolate)


@lru_cache(maxsize=1)
def _mitsuba_version() -> str:  # importlib.metadata scans sys.path: once per process
    try:
        from importlib.metadata import version

        return f" {version('mitsuba')}"
    except Exception:  # metadata missing: the data folder is still there
        return ""
