"""Cross-polar discrimination (XPD) per path and per link from Sionna RT paths traced with
dual-polarized (``"VH"``) antennas, and the value the material's scattering predicts.

For a path with field coefficients ``a_rt`` (receive port ``r``, transmit port ``t``, ``V``/``H``)

    XPD = 10 log10((|a_VV|² + |a_HH|²) / (|a_VH|² + |a_HV|²))   [dB]

(co-polar over cross-polar power, both transmit polarizations; ITU-R P.310-10 §5.1.7 /
3GPP TR 38.901 §7.5 step 9 define XPD as this power ratio). Per link it is the same ratio of the
power sums over paths. ``+inf`` where a path carries no cross-polar power (a specular bounce on
a plane whose incidence plane holds both antennas' polarizations: a flat wall's limit), NaN only
where there is no path.

Single-bounce diffuse path off a rough surface: ``XPD = (σ⁰_vv + σ⁰_hh) / (σ⁰_hv + σ⁰_vh)`` at the
path's angles (:func:`diffuse_xpd`; ``V``/``H`` = local TM/TE on the plane ``z = 0``), because
the emscatter material scales each polarization pair's diffuse field by ``√σ⁰_qp``. The flat
limit: as ``σ → 0`` the diffuse power falls as ``σ²`` (SPM) while the specular paths stay
co-polar, so the link XPD grows without bound.
"""

from __future__ import annotations

import numpy as np

from ..conventions import wavenumber
from .medium import real_number, resolve_medium

__all__ = ["path_xpd", "diffuse_xpd", "xpd_db"]


def xpd_db(co, cross) -> np.ndarray:
    """``10 log10(co / cross)`` [dB]: ``+inf`` where ``cross == 0 < co``, NaN where both are 0."""
    co, cross = np.asarray(co, dtype=np.float64), np.asarray(cross, dtype=np.float64)
    if np.any(co < 0) or np.any(cross < 0) or not (np.all(np.isfinite(co))
                                                   and np.all(np.isfinite(cross))):  # fmt: skip
        raise FloatingPointError("xpd: powers must be finite and non-negative")
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 10.0 * np.log10(co / cross)
    out = np.where((cross == 0) & (co > 0), np.inf, out)
    return np.where((cross == 0) & (co == 0), np.nan, out)


def path_xpd(paths) -> dict:
    """XPD of Sionna ``Paths`` traced with ``polarization="VH"`` arrays (one element each, or a
    synthetic array's first element): ``{"per_path_db": (n_rx, n_tx, n_path), "link_db":
    (n_rx, n_tx), "co", "cross": per path powers [linear], "tau": (n_rx, n_tx, n_path) [s],
    "valid": per path mask}`` (module docstring)."""
    re, im = (np.asarray(x.numpy(), dtype=np.float64) for x in paths.a)
    p = re**2 + im**2
    if p.ndim != 5 or p.shape[1] < 2 or p.shape[3] < 2:
        raise ValueError(
            "XPD needs dual-polarized antennas: scene.tx_array = scene.rx_array = "
            "sionna.rt.PlanarArray(num_rows=1, num_cols=1, pattern=..., polarization='VH') "
            f"(got field coefficients of shape {p.shape})"
        )
    co = p[:, 0, :, 0] + p[:, 1, :, 1]  # [rx, tx, path]: V→V + H→H
    cross = p[:, 0, :, 1] + p[:, 1, :, 0]
    tau = np.asarray(paths.tau.numpy(), dtype=np.float64)
    tau = tau[:, 0, :, 0] if tau.ndim == 5 else tau
    valid = np.asarray(paths.valid.numpy(), dtype=bool)
    valid = valid[:, 0, :, 0] if valid.ndim == 5 else valid
    co, cross = np.where(valid, co, 0.0), np.where(valid, cross, 0.0)
    link = xpd_db(np.sort(co, axis=-1).sum(axis=-1), np.sort(cross, axis=-1).sum(axis=-1))
    return {"per_path_db": xpd_db(co, cross), "link_db": link, "co": co, "cross": cross,
            "tau": tau, "valid": valid}  # fmt: skip


def diffuse_xpd(surface, frequency, tx, rx, points, *, medium="concrete", method="auto") -> dict:
    """XPD [dB] of single-bounce diffuse paths from ``tx`` (3,) via ``points`` (n, 3) on the
    plane ``z = 0`` to ``rx`` (3,) [m], from emscatter's σ⁰ at each path's exact angles:
    ``{"xpd_db": (n,), "sigma0": (2, 2, n) [pol_s, pol_i], "method"}``."""
    from .. import api

    f = real_number("frequency", frequency)
    k = wavenumber(frequency=f)
    eps = complex(np.asarray(resolve_medium(medium).eps(frequency=f)))
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    if pts.shape[-1] != 3 or not np.allclose(pts[:, 2], 0.0, atol=1e-3):
        raise ValueError("points must be (n, 3) [m] on the plane z = 0")
    name, module, _, _ = api.resolve_method(surface, k, method, "ignore", eps)
    d1, d2 = pts - np.asarray(tx, dtype=float), np.asarray(rx, dtype=float) - pts
    r1, r2 = np.linalg.norm(d1, axis=-1), np.linalg.norm(d2, axis=-1)
    ti = np.arccos(np.clip(-d1[:, 2] / r1, 0.0, 1.0))
    ts = np.arccos(np.clip(d2[:, 2] / r2, 0.0, 1.0))
    pi, ps = np.arctan2(d1[:, 1], d1[:, 0]), np.arctan2(d2[:, 1], d2[:, 0])
    import inspect

    skip = (
        {"coherent": False} if "coherent" in inspect.signature(module.bistatic).parameters else {}
    )
    sig = np.asarray(module.bistatic(surface, eps, k, ti, ts, ps, pi, **skip).sigma0)
    return {"xpd_db": xpd_db(sig[0, 0] + sig[1, 1], sig[0, 1] + sig[1, 0]), "sigma0": sig,
            "method": name}  # fmt: skip
