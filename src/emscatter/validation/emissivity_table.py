"""Emissivity of a lossy dielectric: method of moments against second-order SPM.

``e = 1 − ⟨reflected power⟩/P_inc`` from the MoM (two-medium integral equations) against
``emscatter.emissivity(..., method="spm")`` (1 − SPM2 coherent − SPM1 incoherent reflectivity,
hemispherical quadrature), Gaussian 1-D profiles (validation/validity_maps/README.md).
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from ..io import write_csv
from .maps import K, rough_of

__all__ = ["mom_emissivity", "emissivity_table", "EMISSIVITY_CASES"]


def mom_emissivity(
    k_sigma: float,
    k_l: float,
    eps,
    theta_i_deg: float,
    *,
    realizations: int = 8,
    seed: int = 7,
    length_wl: float = 24.0,
    points_per_wavelength: float = 10.0,
    executor=None,
) -> dict:
    """Emissivity of a 1-D Gaussian profile: MoM ``e = 1 − ⟨P_reflected⟩/P_inc`` (mean over
    realizations, with its standard error) and the second-order SPM emissivity
    (:func:`emscatter.emissivity`, ``method="spm"``: 1 − SPM2 coherent − SPM1 incoherent).

    Returns ``{"h": {...}, "v": {...}}`` with ``mom``, ``mom_se``, ``spm``, ``fresnel`` (flat
    surface), ``difference`` (MoM − SPM), and the MoM discretization.
    """
    from emscatter.solvers.mom import model as mom

    from .. import emissivity
    from ..fresnel import fresnel

    rough = rough_of(k_sigma, k_l)
    ti = math.radians(theta_i_deg)
    ref = mom.bistatic(
        rough,
        eps,
        K,
        ti,
        np.array([0.0]),
        0.0,
        realizations=realizations,
        seed=seed,
        length=max(length_wl, 20 * rough.length),
        points_per_wavelength=points_per_wavelength,
        progress=False,
        executor=executor,
    )
    e_spm = emissivity(rough, eps, wavelength=1.0, theta_i=ti, method="spm")
    rh, rv = fresnel(eps, ti)[:2]
    flat = {"h": 1 - abs(rh) ** 2, "v": 1 - abs(rv) ** 2}
    out = {}
    for ip, p in enumerate("hv"):
        pp = ref.info["per_polarization"][p]
        e_m = 1.0 - pp["reflected"]
        e_s = float(np.ravel(e_spm.emissivity[ip])[0])
        out[p] = {
            "mom": e_m,
            "mom_se": pp["reflected_se"],
            "spm": e_s,
            "fresnel": float(flat[p]),
            "difference": e_m - e_s,
            "transmitted": pp["transmitted"],
        }
    out["unknowns"] = ref.info["unknowns"]
    out["realizations"] = ref.info["realizations"]
    return out


EMISSIVITY_CASES = (
    (0.1, 1.0, 5 + 0.5j, 0.0),
    (0.1, 1.0, 5 + 0.5j, 40.0),
    (0.1, 1.0, 17 + 2j, 0.0),
    (0.1, 1.0, 17 + 2j, 40.0),
    (0.2, 2.0, 17 + 2j, 0.0),
    (0.2, 2.0, 17 + 2j, 40.0),
)


def emissivity_table(out: Path, cases=EMISSIVITY_CASES, *, realizations: int = 8) -> Path:
    """MoM vs second-order SPM emissivity for ``cases`` of ``(kσ, kℓ, ε, θi [deg])``,
    written as ``emissivity_mom_spm2.csv`` under ``out``."""
    cols: dict[str, list] = {
        h: []
        for h in (
            "k_sigma",
            "k_l",
            "eps",
            "theta_i_deg",
            "pol",
            "e_mom",
            "e_mom_se",
            "e_spm2",
            "e_flat",
            "difference",
            "realizations",
            "unknowns",
        )
    }
    for ks, kl, eps, tdeg in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = mom_emissivity(
                ks,
                kl,
                eps,
                tdeg,
                realizations=realizations,
                length_wl=16.0,
                points_per_wavelength=15.0,
            )
        for p in "hv":
            vals = (
                ks,
                kl,
                str(complex(eps)),
                tdeg,
                p,
                r[p]["mom"],
                r[p]["mom_se"],
                r[p]["spm"],
                r[p]["fresnel"],
                r[p]["difference"],
                r["realizations"],
                r["unknowns"],
            )
            for h, v in zip(cols, vals, strict=True):
                cols[h].append(v)
    return write_csv(
        Path(out) / "emissivity_mom_spm2.csv",
        tuple(cols),
        [np.array(v, dtype=object) for v in cols.values()],
    )
