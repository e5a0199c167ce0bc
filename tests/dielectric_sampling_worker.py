"""Mitsuba sampling checks for tests/test_render_dielectric_sampling.py in a fresh interpreter
(Dr.Jit variants are per process): ``python tests/dielectric_sampling_worker.py JSON`` with
``{"variant", "check": "consistency" | "chi2" | "variance" | "frozen", "m_x", "m_y",
"thetas_deg": [...], "phis": [...] (the viewer directions, outside), "n": samples per
viewer, ...}``; the tables are tests/dielectric_aniso_worker.py's anisotropic GO glass
(ε = 2.25, slopes m_x along the tangent x, m_y along y; ``"grid"``: its ``GRIDS``).

* ``consistency``: per viewer, ``pdf(sample().wo)`` against the sampled pdf, ``eval/pdf``
  against the sample weight, the fractions of valid reflection/transmission samples and the
  integrals of ``pdf`` over the upper/lower hemispheres (stratified jittered Monte Carlo on
  an equal-area ``(cosθ, φ)`` grid of ``n_grid`` cells);
* ``chi2``: Mitsuba's ``ChiSquareTest`` (``mitsuba.chi2``) of ``sample`` against ``pdf``;
* ``variance``: mean and variance of the sample weights ``f cosθ/pdf`` (channel 0) for the
  default (anisotropic) lobe and ``lobe_sampling="isotropic"``, all lobes and the
  transmission alone (``ctx.component = 1``);
* ``frozen``: the transmission samples (``ctx.component = 1``) of an isotropic table and of
  the anisotropic one with ``lobe_sampling="isotropic"`` against a verbatim copy of the
  isotropic sampler before anisotropic sampling existed (:func:`_frozen_isotropic`):
  bitwise equality.

Prints the results as JSON on its last line.
"""

from __future__ import annotations

import json
import math
import sys
import warnings

import numpy as np

from dielectric_aniso_worker import EPS, tables


def _si(mi, dr, v):
    si = dr.zeros(mi.SurfaceInteraction3f, v.shape[0])
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Vector3f(0, 0, 1)
    si.wi = mi.Vector3f(*(mi.Float(c) for c in v.T))
    return si


def _viewers(args):
    th = np.radians(np.asarray(args["thetas_deg"], float))
    ph = np.asarray(args["phis"], float)
    return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)


def _uniforms(n, seed):
    rng = np.random.default_rng(seed)
    return rng.random(n), rng.random(n), rng.random(n)


def _sample(mi, dr, bsdf, ctx, v, n, seed=5):
    """``(bs, weight, si)`` for ``n`` samples per viewer row of ``v``."""
    vv = np.repeat(v, n, axis=0)
    si = _si(mi, dr, vv)
    a, b, c = _uniforms(vv.shape[0], seed)
    bs, w = bsdf.sample(ctx, si, mi.Float(a), mi.Point2f(mi.Float(b), mi.Float(c)))
    return bs, w, si


def consistency(mi, dr, bsdf, v, n, n_grid):
    ctx = mi.BSDFContext()
    bs, w, si = _sample(mi, dr, bsdf, ctx, v, n)
    pdf_at = np.array(bsdf.pdf(ctx, si, bs.wo), float)
    ev = np.array(bsdf.eval(ctx, si, bs.wo)[0], float)
    bp = np.array(bs.pdf, float)
    w0 = np.array(w[0], float)
    comp = np.array(bs.sampled_component, int)
    ok = (bp > 0) & (w0 > 0)
    rel_pdf = np.abs(pdf_at[ok] / bp[ok] - 1)
    rel_w = np.abs(ev[ok] / pdf_at[ok] / w0[ok] - 1)
    res = {
        "n_valid": int(ok.sum()),
        "pdf_rel_max": float(rel_pdf.max()),
        "pdf_rel_bad": int(np.sum(rel_pdf > 1e-5)),
        "weight_rel_max": float(rel_w.max()),
        "weight_rel_bad": int(np.sum(rel_w > 1e-5)),
        "components": np.bincount(comp[ok], minlength=2).tolist(),
    }
    okr = ok.reshape(len(v), n)
    cr = comp.reshape(len(v), n)
    res["frac_t"] = np.mean(okr & (cr == 1), axis=1).tolist()
    res["frac_r"] = np.mean(okr & (cr == 0), axis=1).tolist()
    # ∫ pdf dω on each hemisphere: jittered strata of an equal-area (z, φ) grid, 4π/N each
    nz, nphi = n_grid
    rng = np.random.default_rng(9)
    iz, ip = np.meshgrid(np.arange(nz), np.arange(nphi), indexing="ij")
    z = -1 + 2 * (iz.ravel() + rng.random(iz.size)) / nz
    ph = 2 * math.pi * (ip.ravel() + rng.random(ip.size)) / nphi
    s = np.sqrt(np.maximum(1 - z * z, 0))
    wo = np.stack([s * np.cos(ph), s * np.sin(ph), z], -1)
    wo_dr = mi.Vector3f(*(mi.Float(c) for c in wo.T))
    int_t, int_r = [], []
    for row in v:
        si1 = _si(mi, dr, np.repeat(row[None], wo.shape[0], axis=0))
        p = np.array(bsdf.pdf(ctx, si1, wo_dr), float) * (4 * math.pi / wo.shape[0])
        below = wo[:, 2] * row[2] < 0
        int_t.append(float(p[below].sum()))
        int_r.append(float(p[~below].sum()))
    res["int_t"], res["int_r"] = int_t, int_r
    return res


def chi2(mi, d, v, sample_count, res, component=None):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    ctx = mi.BSDFContext()
    if component is not None:  # one lobe alone (0: outside reflection, 1: transmission)
        ctx.component = int(component)
    out = []
    for row in v:
        sample_func, pdf_func = BSDFAdapter(d["type"], d, wi=[float(x) for x in row], ctx=ctx)
        test = ChiSquareTest(
            domain=SphericalDomain(),
            sample_func=sample_func,
            pdf_func=pdf_func,
            sample_dim=3,
            sample_count=sample_count,
            res=res,
            ires=16,  # the reflection lobe's density is piecewise constant: integrate finely
        )
        out.append({"passed": bool(test.run()), "messages": str(test.messages)[-2000:]})
    return out


def variance(mi, dr, bsdfs, v, n):
    res = {}
    for name, b in bsdfs.items():
        for comp in (None, 1):
            ctx = mi.BSDFContext()
            if comp is not None:
                ctx.component = comp
            _, w, _ = _sample(mi, dr, b, ctx, v, n, seed=13)
            ww = np.array(w[0], float).reshape(len(v), n)
            key = f"{name}_{'all' if comp is None else 't'}"
            res[key] = {"mean": ww.mean(1).tolist(), "var": ww.var(1).tolist()}
    return res


def _frozen_isotropic(mi, dr, v, u, alpha, eta_mean):
    """The isotropic refraction sampler and pdf as they were before anisotropic tables
    sampled their own lobe (a verbatim copy, GO tables: no wide mixture)."""
    a2 = alpha**2
    tan2 = -a2 * dr.log(dr.maximum(1.0 - u.x, 1e-30))
    c = dr.rsqrt(1.0 + tan2)
    s = dr.sqrt(dr.maximum(1.0 - c * c, 0.0))
    sp, cp = dr.sincos(2 * math.pi * u.y)
    m = mi.Vector3f(cp * s, sp * s, c)
    out = v.z > 0
    eta = dr.select(out, eta_mean, 1.0 / eta_mean)
    vm = dr.dot(v, m)
    k = 1.0 - (1.0 - vm * vm) / (eta * eta)
    ok = (k > 0) & (vm * v.z > 0)
    wo = dr.normalize(m * (vm / eta - dr.mulsign(dr.sqrt(dr.maximum(k, 0.0)), vm)) - v / eta)
    # the pdf (Walter et al. 2007 eq. 17 × Beckmann)
    n_i = dr.select(out, 1.0, eta_mean)
    n_o = dr.select(out, eta_mean, 1.0)
    mh = dr.normalize(-(n_i * v + n_o * wo))
    mh = dr.mulsign(mh, mh.z)
    vm2, om = dr.dot(v, mh), dr.dot(wo, mh)
    ok2 = (vm2 * om < 0) & (mh.z > 1e-7)
    c2 = dr.square(mh.z)
    d = dr.exp(-(1.0 - c2) / (c2 * a2)) / (math.pi * a2 * dr.square(c2))
    jac = dr.square(n_o) * dr.abs(om) / dr.maximum(dr.square(n_i * vm2 + n_o * om), 1e-30)
    ok = ok & (wo.z * v.z < 0)
    pdf = dr.select(ok2, d * mh.z * jac, 0.0)
    ok = ok & (pdf > 0)
    return wo, dr.select(ok, pdf, 0.0)


def frozen(mi, dr, bsdfs, v, n):
    out = {}
    for name, (b, bt) in bsdfs.items():
        ctx = mi.BSDFContext()
        ctx.component = 1
        vv = np.repeat(v, n, axis=0)
        si = _si(mi, dr, vv)
        a, b1, c = _uniforms(vv.shape[0], 21)
        u2 = mi.Point2f(mi.Float(b1), mi.Float(c))
        bs, _ = b.sample(ctx, si, mi.Float(a), u2)
        sx, sy = bt.metadata["slope_variance"]
        wo, pdf = _frozen_isotropic(mi, dr, si.wi, u2, math.sqrt(sx + sy), math.sqrt(EPS))
        got_wo = np.array(bs.wo, np.float32)
        want_wo = np.array(wo, np.float32)
        got_p, want_p = np.array(bs.pdf, np.float32), np.array(pdf, np.float32)
        valid = want_p > 0
        out[name] = {
            "n_valid": int(valid.sum()),
            "pdf_equal": bool(np.array_equal(got_p, want_p)),
            "wo_equal": bool(np.array_equal(got_wo[:, valid], want_wo[:, valid])),
        }
    return out


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args.get("variant", "llvm_ad_rgb"))
    from emscatter.render import dielectric as em_d

    m_x, m_y = float(args["m_x"]), float(args["m_y"])
    refl, bt, _ = tables(m_x, m_y, grid=str(args.get("grid", "coarse")))
    v = _viewers(args)
    n = int(args.get("n", 100_000))
    check = args["check"]
    d = em_d.bsdf_dict(refl, bt, coherent=False)
    bsdf = mi.load_dict(d)
    if check == "consistency":
        res = consistency(mi, dr, bsdf, v, n, tuple(args.get("n_grid", (2000, 2000))))
    elif check == "chi2":
        res = {"chi2": chi2(mi, d, v, n, int(args.get("res", 64)), args.get("component"))}
    elif check == "variance":
        iso = mi.load_dict(em_d.bsdf_dict(refl, bt, coherent=False, lobe_sampling="isotropic"))
        res = variance(mi, dr, {"aniso": bsdf, "iso": iso}, v, n)
    elif check == "frozen":
        from emscatter.brdf import build_table
        from emscatter.brdf.btdf_table import build_btdf_table
        from emscatter.spectra import GaussianCorrelation

        s2 = 0.3**2 / 2
        surf = GaussianCorrelation(sigma=0.15e-6, length=1e-6)
        opts = {"shadowing": "separable", "slope_variance": (s2, s2)}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r_iso = build_table(surf, EPS, [550e-9], method="go", resolution=(30, 61),
                                energy="off", **opts)  # fmt: skip
            bt_iso = build_btdf_table(surf, EPS, [550e-9], n_theta=30, n_phi=61, **opts)
        bsdfs = {
            "isotropic_table": (mi.load_dict(em_d.bsdf_dict(r_iso, bt_iso)), bt_iso),
            "aniso_table_isotropic_lobe": (
                mi.load_dict(em_d.bsdf_dict(refl, bt, coherent=False, lobe_sampling="isotropic")),
                bt,
            ),
        }
        v_both = np.concatenate([v, v * np.array([1, 1, -1.0])])  # outside and inside
        res = frozen(mi, dr, bsdfs, v_both, n)
    else:
        raise ValueError(f"check must be consistency, chi2, variance or frozen, got {check!r}")
    res["to_string"] = str(bsdf)
    print(json.dumps(res))


if __name__ == "__main__":
    main(sys.argv[1])
    sys.stdout.flush()
