"""Mitsuba evaluations for tests/test_render_dielectric_polarized.py in a fresh interpreter
(Dr.Jit variants are per process): ``python tests/dielectric_polarized_worker.py JSON`` with
``{"variant", "n_theta", "alpha", "v": [[x, y, z], ...] (Mitsuba's si.wi), "l": [...] (wo),
"smooth": bool (optional: also sample Mitsuba's smooth ``dielectric`` and this plugin's
transmission at the refracted direction of each ``v``)}``; builds GO tables of glass
(ε = 2.25, Beckmann α, separable Smith), loads ``emscatter_dielectric`` and prints JSON on its
last line: ``"em"`` the ``eval`` matrices (polarized variants: 4 × 4 of channel 0; others:
channel 0), ``"np"`` :meth:`BtdfTable.evaluate_mueller` (Mitsuba frames) at the same pairs.
"""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np

EPS = 2.25


def tables(n_theta: int, alpha: float):
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.spectra import GaussianCorrelation

    s2 = alpha**2 / 2
    surf = GaussianCorrelation(sigma=0.15e-6, length=1e-6)
    opts = {"shadowing": "separable", "slope_variance": (s2, s2)}
    th = np.linspace(0, np.radians(89), n_theta)
    ph = np.linspace(0, np.pi, 2 * n_theta + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kw = dict(method="go", theta=th, phi=ph, energy="off", **opts)
        out = build_mueller_table(surf, EPS, [550e-9], **kw)
        inner = build_mueller_table(surf, 1 / EPS, [550e-9], **kw)
        bt = build_btdf_table(
            surf, EPS, [550e-9], n_theta=n_theta, n_phi=2 * n_theta + 1, polarized=True, **opts
        )
    return out, bt, inner


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    from emscatter.render import dielectric as em_d

    out, bt, inner = tables(int(args["n_theta"]), float(args["alpha"]))
    pol = "polarized" in args["variant"]
    bsdf = mi.load_dict(em_d.bsdf_dict(out, bt, inner))
    v = np.asarray(args["v"], float)
    l_ = np.asarray(args["l"], float)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*v.T)
    si.wavelengths = mi.Spectrum(550.0) if False else si.wavelengths
    ctx = mi.BSDFContext()

    def mats(val):
        if not pol:
            return np.asarray(val[0] if hasattr(val, "__len__") else val).reshape(1, -1).tolist()
        return [[np.asarray(val[r, c][0] if False else val[r, c]).reshape(-1).tolist()
                 for c in range(4)] for r in range(4)]  # fmt: skip

    res = {"em": mats(bsdf.eval(ctx, si, mi.Vector3f(*l_.T)))}
    if pol:  # radiance: light l (table wi when above), viewer v
        below = v[:, 2] < 0
        m = np.zeros((4, 4, len(v)))
        if below.any():
            m[..., below] = bt.evaluate_mueller(l_[below], v[below], 550e-9) * np.abs(l_[below, 2])
        res["np"] = m.tolist()
    if args.get("smooth") and pol:
        ref = mi.load_dict({"type": "dielectric", "int_ior": EPS**0.5, "ext_ior": 1.0})
        bs, w = ref.sample(ctx, si, mi.Float(np.full(len(v), 0.9999)), mi.Point2f(0.5, 0.5))
        wo = bs.wo
        res["wo"] = np.array([wo.x, wo.y, wo.z]).T.tolist()
        res["ref"] = mats(w)
        res["em_t"] = mats(bsdf.eval(ctx, si, wo))
    print(json.dumps(res))


if __name__ == "__main__":
    main(sys.argv[1])
