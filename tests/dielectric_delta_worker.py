"""Mitsuba checks of the ``emscatter_dielectric`` delta lobes (test_render_dielectric_delta.py)
in a fresh interpreter (Dr.Jit variants are per process):
``python tests/dielectric_delta_worker.py JSON`` with ``{"variant", "method": "spm" | "go",
"k_sigma" (SPM roughness kσ at 550 nm), "n_theta", "theta_deg": [...] (viewer angles; each
used from outside and from inside), "n": samples per viewer, "mode": "radiance" |
"importance", "coherent": bool, "render": int (optional: sphere image side), "spp"}``.
Glass ε = 2.25, ℓ = 1 µm, 550 nm. Prints JSON on its last line: per viewer (outside ones first)
the mean sampled weight of reflection (``R``) and transmission (``T``) samples of this plugin
and of Mitsuba's smooth ``dielectric`` (``R_ref``, ``T_ref``, same random numbers), the tables'
``R_coh + R_inc + T_coh + T_inc`` at the outside viewers (``table_sum``), the standard error of
the mean weight (``se``), the worst ``|pdf(wo)/bs.pdf − 1|`` of the non-delta samples, the BSDF
flags, and the raw sample arrays' hash-able sums (``digest``).
"""

from __future__ import annotations

import json
import math
import sys
import warnings

import numpy as np

EPS = 2.25
WL = 550e-9


def tables(method: str, k_sigma: float, n_theta: int, polarized: bool = False):
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.spectra import GaussianCorrelation

    sigma = k_sigma * WL / (2 * math.pi)
    surf = GaussianCorrelation(sigma=sigma, length=1e-6)
    res = (n_theta, 2 * n_theta + 1)
    opts = {}
    if method == "go":  # GO glass as tests/dielectric_plugin_worker.py (α = 0.3)
        surf = GaussianCorrelation(sigma=0.15e-6, length=1e-6)
        opts = {"shadowing": "separable", "slope_variance": (0.045, 0.045)}
    build = build_mueller_table if polarized else build_table
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = build(surf, EPS, [WL], method=method, resolution=res, energy="off", **opts)
        inner = build(surf, 1 / EPS, [WL], method=method, resolution=res, energy="off", **opts)
        bt = build_btdf_table(surf, EPS, [WL], n_theta=n_theta, n_phi=2 * n_theta + 1,
                              method=method, polarized=polarized, **opts)  # fmt: skip
    return out, bt, inner


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    from emscatter.render import dielectric as em_d

    pol = "polarized" in args["variant"]
    out, bt, inner = tables(args["method"], float(args.get("k_sigma", 0.01)),
                            int(args["n_theta"]), pol)  # fmt: skip
    coh = bool(args.get("coherent", True))
    em_d.register()
    key = em_d.register_dielectric(out, bt, inner)
    em = mi.load_dict({"type": "emscatter_dielectric", "tables": key, "coherent": coh})
    ref = mi.load_dict({"type": "dielectric", "int_ior": EPS**0.5, "ext_ior": 1.0})
    mode = mi.TransportMode.Importance if args.get("mode") == "importance" else None
    ctx = mi.BSDFContext() if mode is None else mi.BSDFContext(mode)
    th = np.radians(np.asarray(args["theta_deg"], float))
    th = np.concatenate([th, math.pi - th])  # outside viewers, then inside ones
    n = int(args["n"])
    rng = np.random.default_rng(3)
    ph = rng.uniform(0, 2 * math.pi, th.size)
    v = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    vv = np.repeat(v, n, axis=0)
    si = dr.zeros(mi.SurfaceInteraction3f, vv.shape[0])
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = mi.Vector3f(*(mi.Float(c) for c in vv.T))
    if "spectral" in args["variant"]:
        si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    u1 = mi.Float(rng.random(vv.shape[0]))
    u2 = mi.Point2f(mi.Float(rng.random(vv.shape[0])), mi.Float(rng.random(vv.shape[0])))
    res = {"flags": int(em.flags()), "components": int(em.component_count())}
    names = ("Delta", "DeltaReflection", "DeltaTransmission", "GlossyReflection",
             "GlossyTransmission")  # fmt: skip
    res["flag_values"] = {k: int(getattr(mi.BSDFFlags, k)) for k in names}

    def s0(w):
        w00 = w[0, 0] if pol else w
        return np.array(w00[0], dtype=float)

    for name, b in (("", em), ("_ref", ref)):
        bs, w = b.sample(ctx, si, u1, u2)
        ww = s0(w).reshape(-1, n)
        wo_z = np.array(bs.wo.z, dtype=float).reshape(-1, n)
        refl = wo_z * np.repeat(v[:, 2:3], n, axis=1) > 0
        res["R" + name] = (ww * refl).mean(1).tolist()
        res["T" + name] = (ww * ~refl).mean(1).tolist()
        if not name:
            res["se"] = (ww.std(1) / math.sqrt(n)).tolist()
            delta = (np.array(bs.sampled_type, dtype=np.uint32) & int(
                mi.BSDFFlags.Delta)) != 0  # fmt: skip
            pdf = np.array(b.pdf(ctx, si, bs.wo), dtype=float)
            bp = np.array(bs.pdf, dtype=float)
            ok = (bp > 0) & ~delta
            res["pdf_err"] = float(np.max(np.abs(pdf[ok] / bp[ok] - 1))) if ok.any() else 0.0
            bad = np.abs(pdf[ok] / bp[ok] - 1) > 1e-3
            res["pdf_bad_fraction"] = float(np.mean(bad)) if ok.any() else 0.0
            res["delta_fraction"] = float(np.mean(delta))
            ev = np.array(b.eval(ctx, si, bs.wo)[0, 0][0] if pol else b.eval(ctx, si, bs.wo)[0])
            res["digest"] = [float(np.sum(np.abs(x), dtype=float)) for x in (
                ww, wo_z, bp, pdf, np.asarray(ev, float))]  # fmt: skip
            if pol:  # s0 row / full matrices of the delta samples against dielectric
                res["mueller"] = [[s0_elem(w, r, c, n) for c in range(4)] for r in range(4)]
        elif pol:
            res["mueller_ref"] = [[s0_elem(w, r, c, n) for c in range(4)] for r in range(4)]
    if res["components"] > 3:  # one delta component at a time: weight = its coherent part
        k = 3  # after the three glossy components (inner given)
        half = th.size // 2
        for name, b, comps in (("d", em, (k, k + 1, k + 2)), ("d_ref", ref, (0, 1, 0))):
            ws = []
            for c in comps:
                cx = mi.BSDFContext() if mode is None else mi.BSDFContext(mode)
                cx.component = c
                bs, w = b.sample(cx, si, u1, u2)
                ws.append(s0(w).reshape(-1, n)[:, 0])
                if pol:  # the full matrix of each viewer's first sample, channel 0
                    res.setdefault(name + "M", []).append(
                        [[np.array(w[r, c][0], float).reshape(-1, n)[:, 0].tolist()
                          for c in range(4)] for r in range(4)])  # fmt: skip
            r = np.where(np.arange(th.size) < half, ws[0], ws[2])
            res[name + "R"], res[name + "T"] = r.tolist(), ws[1].tolist()
    out = getattr(out, "table", out)  # a MuellerTable's unpolarized table
    t = out.albedo().total[0]
    ti = out.theta_i
    r_sum = np.interp(th[: th.size // 2], ti, t)
    t_sum = np.interp(th[: th.size // 2], bt.theta_i, bt.albedo()[0])
    res["table_sum"] = (r_sum + t_sum).tolist()
    c_r = np.interp(th[: th.size // 2], ti, np.asarray(t - out.albedo().incoherent[0]))
    c_t = 0.0 if bt.coherent is None else np.interp(th[: th.size // 2], bt.theta_i, bt.coherent[0])
    res["table_coherent"] = (c_r + c_t).tolist()
    side = int(args.get("render", 0))
    if side:
        res.update(render(mi, key, coh, side, int(args.get("spp", 64))))
    print(json.dumps(res))


def s0_elem(w, r, c, n):
    """Mean Mueller element (channel 0) per viewer."""
    return np.array(w[r, c][0], dtype=float).reshape(-1, n).mean(1).tolist()


def render(mi, key, coh, side, spp):
    imgs = {}
    for name, bdict in (
        ("em", {"type": "emscatter_dielectric", "tables": key, "coherent": coh}),
        ("ref", {"type": "dielectric", "int_ior": EPS**0.5, "ext_ior": 1.0}),
    ):
        scene = mi.load_dict({
            "type": "scene", "integrator": {"type": "path", "max_depth": 8},
            "sensor": {"type": "perspective", "fov": 30,
                       "to_world": mi.ScalarTransform4f().look_at(
                           origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": side, "height": side},
                       "sampler": {"type": "independent", "sample_count": spp}},
            "sphere": {"type": "sphere", "bsdf": bdict},
            "floor": {"type": "rectangle", "to_world": mi.ScalarTransform4f().translate(
                [0, 0, -2]).scale(6), "bsdf": {"type": "diffuse", "reflectance": {
                    "type": "checkerboard", "to_uv": mi.ScalarTransform3f().scale(8)}}},
            "emitter": {"type": "constant", "radiance": 1.0},
        })  # fmt: skip
        imgs[name] = np.array(mi.render(scene, seed=1), dtype=float)[..., 0]
        if name == "ref":
            imgs["ref2"] = np.array(mi.render(scene, seed=2), dtype=float)[..., 0]
    return {
        "render_mean": {k: float(x.mean()) for k, x in imgs.items()},
        "render_mean_abs_diff": float(np.mean(np.abs(imgs["em"] - imgs["ref"]))),
        "render_noise_floor": float(np.mean(np.abs(imgs["ref2"] - imgs["ref"]))),
    }


if __name__ == "__main__":
    main(sys.argv[1])
