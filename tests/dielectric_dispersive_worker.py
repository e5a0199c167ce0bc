"""Mitsuba evaluations for tests/test_render_dielectric_dispersive.py in a fresh interpreter
(Dr.Jit variants are per process): ``python tests/dielectric_dispersive_worker.py JSON`` with
``{"v": [[x, y, z], ...] (towards the viewer, Mitsuba's si.wi), "l": [...] (towards the
light), "modes": ["radiance", "importance"] (default both), "variant" (default
``llvm_ad_spectral``; ``llvm_ad_spectral_polarized``: Mueller tables, the (0, 0) entries
compared), "table_nm": [...] (the tables'
wavelengths), "eval_nm": [...] (wavelengths to evaluate at, all four spectral lanes at one
wavelength)}``.

Builds GO tables of a dispersive glass — Schott N-BK7, Sellmeier ``n²(λ) = 1 + Σ B_j λ²/(λ² −
C_j)`` (Schott data sheet: B = 1.03961212, 0.231792344, 1.01046945; C = 0.00600069867,
0.0200179144, 103.560653 µm²; n = 1.5168 at 587.6 nm) — Beckmann α = 0.3, separable Smith,
in ``llvm_ad_spectral``, loads them in the ``emscatter_dielectric`` plugin and, per evaluation
wavelength λ, Mitsuba's ``roughdielectric`` with ``int_ior = n(λ)`` (the per-wavelength
reference). Prints ``{mode: {"em": [[...] per λ], "rd": [[...] per λ], "n": [...]}}`` (channel
0 of ``eval``) as JSON on its last line.
"""

from __future__ import annotations

import json
import math
import sys
import warnings

import numpy as np

ALPHA = 0.3
B = (1.03961212, 0.231792344, 1.01046945)
C = (0.00600069867, 0.0200179144, 103.560653)  # [µm²]


def bk7_eps(wavelength: float) -> float:
    """N-BK7 ε = n² at ``wavelength`` [m] (Sellmeier, Schott)."""
    x = (float(wavelength) * 1e6) ** 2
    return 1.0 + sum(b * x / (x - c) for b, c in zip(B, C, strict=True))


def tables(n_theta: int, wavelengths, polarized: bool = False):
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.spectra import GaussianCorrelation

    wl = list(wavelengths)
    s2 = ALPHA**2 / 2
    surf = GaussianCorrelation(sigma=0.15e-6, length=1e-6)
    opts = {"shadowing": "separable", "slope_variance": (s2, s2)}
    res = (n_theta, 2 * n_theta + 1)
    build = build_mueller_table if polarized else build_table
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = build(surf, bk7_eps, wl, method="go", resolution=res, energy="off", **opts)
        inner = build(
            surf, lambda w: 1.0 / bk7_eps(w), wl, method="go", resolution=res, energy="off", **opts
        )
        bt = build_btdf_table(
            surf, bk7_eps, wl, n_theta=n_theta, n_phi=2 * n_theta + 1, polarized=polarized, **opts
        )
    return out, bt, inner


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    variant = args.get("variant", "llvm_ad_spectral")
    mi.set_variant(variant)
    pol = "polarized" in variant
    from emscatter.render import dielectric as em_d

    wls = [x * 1e-9 for x in args["table_nm"]]
    out, bt, inner = tables(int(args.get("n_theta", 90)), wls, pol)

    def m00(val):  # polarized: the Mueller matrix's (0, 0) entry (frame-invariant), lane 0
        return np.array(val[0, 0][0] if pol else val[0], dtype=float).tolist()

    em = mi.load_dict(em_d.bsdf_dict(out, bt, inner))
    v = np.asarray(args["v"], dtype=float)
    lt = np.asarray(args["l"], dtype=float)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Vector3f(0, 0, 1)
    si.wi = mi.Vector3f(*(mi.Float(c) for c in v.T))
    wo = mi.Vector3f(*(mi.Float(c) for c in lt.T))
    out_all = {}
    for mode in args.get("modes", ["radiance", "importance"]):
        tm = mi.TransportMode.Importance if mode == "importance" else mi.TransportMode.Radiance
        ctx = mi.BSDFContext(tm)
        res = {"em": [], "rd": [], "n": []}
        for nm in args["eval_nm"]:
            n = math.sqrt(bk7_eps(nm * 1e-9))
            rd = mi.load_dict({"type": "roughdielectric", "distribution": "beckmann",
                               "alpha": ALPHA, "int_ior": n, "ext_ior": 1.0,
                               "sample_visible": False})  # fmt: skip
            lanes = (mi.Float(np.full(v.shape[0], nm)) for _ in range(4))
            si.wavelengths = mi.UnpolarizedSpectrum(*lanes)
            res["em"].append(m00(em.eval(ctx, si, wo)))
            res["rd"].append(m00(rd.eval(ctx, si, wo)))
            res["n"].append(n)
        out_all[mode] = res
    print(json.dumps(out_all))


if __name__ == "__main__":
    main(sys.argv[1])
