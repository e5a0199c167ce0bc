"""Mitsuba evaluations for tests/test_render_dielectric.py in a fresh interpreter (Dr.Jit
variants are per process): ``python tests/dielectric_plugin_worker.py JSON`` with
``{"variant", "n_theta", "v": [[x, y, z], ...] (towards the viewer, Mitsuba's si.wi),
"l": [...] (towards the light, Mitsuba's wo), "mode": "radiance" | "importance",
"samples": int (optional: sample/pdf check), "render": int (optional: sphere image side),
"wavelengths_nm": [...] (optional, default [550]: the tables' wavelengths; spectral variants
get random sampled wavelengths in [400, 700] nm and return every channel)}``
builds GO tables of glass (ε = 2.25, Beckmann α = 0.3, separable Smith: Mitsuba's
``roughdielectric`` within GO), loads them in the ``emscatter_dielectric`` plugin and prints
``{"em": [...], "rd": [...]}`` (``bsdf.eval``, channel 0) and the optional checks as JSON on
its last line.
"""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np

EPS = 2.25
ALPHA = 0.3


def tables(n_theta: int, wavelengths=(550e-9,), method: str = "go"):
    """GO tables (``method="po"``: the outside BRDF and the BTDF from PO, same surface)."""
    wl = list(wavelengths)
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.spectra import GaussianCorrelation

    s2 = ALPHA**2 / 2
    surf = GaussianCorrelation(sigma=0.15e-6, length=1e-6)
    opts = {"shadowing": "separable", "slope_variance": (s2, s2)}
    res = (n_theta, 2 * n_theta + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = build_table(surf, EPS, wl, method="go", resolution=res, energy="off", **opts)
        inner = build_table(surf, 1 / EPS, wl, method="go", resolution=res, energy="off", **opts)
        if method == "po":  # σ = 0.15 µm, ℓ = 1 µm: the same Beckmann α = 0.3 in PO's spectrum
            out = build_table(surf, EPS, wl, method="po", resolution=res, energy="off")
            bt = build_btdf_table(surf, EPS, wl, n_theta=n_theta, n_phi=2 * n_theta + 1,
                                  method="po", out_of_range="ignore")  # fmt: skip
            return out, bt, inner
    bt = build_btdf_table(surf, EPS, wl, n_theta=n_theta, n_phi=2 * n_theta + 1, **opts)
    return out, bt, inner


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    from emscatter.render import dielectric as em_d

    wls = [x * 1e-9 for x in args.get("wavelengths_nm", [550])]
    out, bt, inner = tables(int(args["n_theta"]), wls, args.get("method", "go"))
    spectral = "spectral" in args["variant"]
    bsdfs = {
        "em": mi.load_dict(em_d.bsdf_dict(out, bt, inner)),
        "rd": mi.load_dict({"type": "roughdielectric", "distribution": "beckmann",
                            "alpha": ALPHA, "int_ior": EPS**0.5, "ext_ior": 1.0,
                            "sample_visible": False}),
    }  # fmt: skip
    mode = mi.TransportMode.Importance if args.get("mode") == "importance" else None
    ctx = mi.BSDFContext() if mode is None else mi.BSDFContext(mode)
    v = np.asarray(args["v"], dtype=float)
    lt = np.asarray(args["l"], dtype=float)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Vector3f(0, 0, 1)
    si.wi = mi.Vector3f(*(mi.Float(c) for c in v.T))
    wo = mi.Vector3f(*(mi.Float(c) for c in lt.T))
    res = {}
    if spectral:
        rng = np.random.default_rng(7)
        lam = rng.uniform(400, 700, (4, v.shape[0]))
        si.wavelengths = mi.Spectrum(*(mi.Float(x) for x in lam))
        res["lambda_nm"] = lam.tolist()
    for name, b in bsdfs.items():
        val = b.eval(ctx, si, wo)
        if spectral:
            res[name] = [np.array(val[j], dtype=float).tolist() for j in range(4)]
        else:
            res[name] = np.array(val[0], dtype=float).tolist()
    n = int(args.get("samples", 0))
    if n:  # sample → pdf consistency and the mean weight (the albedo) per viewer direction
        b = bsdfs["em"]
        rng = np.random.default_rng(5)
        vv = np.repeat(v[:8], n, axis=0)
        s = dr.zeros(mi.SurfaceInteraction3f, vv.shape[0])
        s.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        s.wi = mi.Vector3f(*(mi.Float(c) for c in vv.T))
        u1 = mi.Float(rng.random(vv.shape[0]))
        u2 = mi.Point2f(mi.Float(rng.random(vv.shape[0])), mi.Float(rng.random(vv.shape[0])))
        bs, w = b.sample(ctx, s, u1, u2)
        pdf = np.array(b.pdf(ctx, s, bs.wo), dtype=float)
        bp = np.array(bs.pdf, dtype=float)
        ok = bp > 0
        err = np.abs(pdf[ok] / bp[ok] - 1)
        res["pdf_rel_err_max"] = float(err.max()) if ok.any() else 0.0
        res["pdf_bad_fraction"] = float(np.mean(err > 1e-3)) if ok.any() else 0.0
        comp = np.array(bs.sampled_component, dtype=int)[ok]
        res["pdf_bad_components"] = np.bincount(comp[err > 1e-3], minlength=3).tolist()
        ww = np.array(w[0], dtype=float).reshape(8, n)
        res["mean_weight"] = ww.mean(axis=1).tolist()
        for name in ("em", "rd"):
            bb = bsdfs[name]
            bs2, w2 = bb.sample(ctx, s, u1, u2)
            res[f"albedo_{name}"] = np.array(w2[0], dtype=float).reshape(8, n).mean(1).tolist()
    side = int(args.get("render", 0))
    if side:
        imgs = {}
        for name, b in (("em", em_d.bsdf_dict(out, bt, inner)), ("rd", None)):
            bdict = b if b is not None else {
                "type": "roughdielectric", "distribution": "beckmann", "alpha": ALPHA,
                "int_ior": EPS**0.5, "ext_ior": 1.0}  # fmt: skip
            scene = mi.load_dict({
                "type": "scene", "integrator": {"type": "path", "max_depth": 8},
                "sensor": {"type": "perspective", "fov": 30,
                           "to_world": mi.ScalarTransform4f().look_at(
                               origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                           "film": {"type": "hdrfilm", "width": side, "height": side},
                           "sampler": {"type": "independent",
                                       "sample_count": int(args.get("spp", 64))}},
                "sphere": {"type": "sphere", "bsdf": bdict},
                "floor": {"type": "rectangle", "to_world": mi.ScalarTransform4f().translate(
                    [0, 0, -2]).scale(6), "bsdf": {"type": "diffuse", "reflectance": {
                        "type": "checkerboard", "to_uv": mi.ScalarTransform3f().scale(8)}}},
                "emitter": {"type": "constant", "radiance": 1.0},
            })  # fmt: skip
            imgs[name] = np.array(mi.render(scene, seed=1), dtype=float)[..., 0]
            if name == "rd":  # the noise floor: the same scene, another seed
                imgs["rd2"] = np.array(mi.render(scene, seed=2), dtype=float)[..., 0]
        res["render_mean"] = {k: float(x.mean()) for k, x in imgs.items()}
        res["render_mean_abs_diff"] = float(np.mean(np.abs(imgs["em"] - imgs["rd"])))
        res["render_noise_floor"] = float(np.mean(np.abs(imgs["rd2"] - imgs["rd"])))
    print(json.dumps(res))


if __name__ == "__main__":
    main(sys.argv[1])
