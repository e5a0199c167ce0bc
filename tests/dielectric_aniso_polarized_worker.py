"""Mitsuba evaluations for tests/test_render_dielectric_aniso_polarized.py in a fresh
interpreter (Dr.Jit variants are per process): ``python tests/dielectric_aniso_polarized_worker.py
JSON`` with ``{"variant", "tables": path of a pickle (the test's :func:`tables`), "v": [[x, y, z],
...] (towards the viewer, si.wi), "l": [...] (towards the light, wo), "rd": [alpha_u, alpha_v]
(optional: also Mitsuba's anisotropic Beckmann ``roughdielectric`` and, polarized,
:func:`facet_mueller`), "sample": bool (optional: :func:`sample_check` of ``"aniso"``)}`` loads the
``emscatter_dielectric`` plugin of each table set in the pickle (a dict name → (reflection,
transmission, inner or None)) and prints on its last line JSON with, per name and for ``"rd"``,
``bsdf.eval`` in radiance mode (polarized variants: the 4 × 4 matrices of channel 0,
``[r][c][pair]``; others: channel 0 per pair), ``"rd_mueller"`` (:func:`facet_mueller`),
``"error"`` (per name, the plugin's load error message, or None) and ``"to_string"``."""

from __future__ import annotations

import json
import pickle
import sys

import numpy as np

EPS = 2.25


def facet_mueller(mi, dr, v, lt):
    """Mitsuba's transmission Mueller matrix at the refracting microfacet of each pair,
    normalized (``M₀₀ = 1``): ``mi.mueller.specular_transmission`` at ``l·m`` with its s axes
    ``m × (−l)`` and ``m × v``, rotated onto ``stokes_basis(−l)``, ``stokes_basis(v)`` — the
    construction of Mitsuba's polarized ``roughconductor`` (the microfacet's Fresnel matrix)
    applied to the transmission of its polarized ``dielectric``, needed because Mitsuba 3's
    ``roughdielectric`` returns a depolarizer in polarized variants (``eval`` ends in
    ``depolarizer<Spectrum>(result)``). Radiance mode: light along ``−l``, viewer ``v``."""
    eta = EPS**0.5
    lv = mi.Vector3f(*(mi.Float(c) for c in lt.T))
    vv = mi.Vector3f(*(mi.Float(c) for c in v.T))
    n_l = dr.select(lv.z > 0, 1.0, eta)  # index on the light's side
    n_v = dr.select(lv.z > 0, eta, 1.0)
    m = dr.normalize(-(n_l * lv + n_v * vv))  # Walter et al. 2007 eq. 16
    m = dr.mulsign(m, m.z)
    t = mi.mueller.specular_transmission(dr.dot(lv, m), mi.Float(eta))
    sb = mi.mueller.stokes_basis
    s_in, s_out = dr.normalize(dr.cross(m, -lv)), dr.normalize(dr.cross(m, vv))
    t = mi.mueller.rotate_mueller_basis(t, -lv, s_in, sb(-lv), vv, s_out, sb(vv))
    n = v.shape[0]
    t00 = np.broadcast_to(np.array(t[0, 0], dtype=float).reshape(-1), (n,))
    return [[(np.broadcast_to(np.array(t[r, c], dtype=float).reshape(-1), (n,)) / t00).tolist()
             for c in range(4)] for r in range(4)]  # fmt: skip


def sample_check(mi, dr, b, v, pol):
    """``sample`` at each viewer ``v`` (4 draws each): ``{"w_pdf": weight · pdf, "eval":
    eval at the sampled direction, "pdf", "t": transmitted}`` (polarized: the 16 elements of channel
    0 as rows; radiance mode)."""
    n = v.shape[0] * 4
    vv = np.repeat(v, 4, axis=0)
    rng = np.random.default_rng(2)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Vector3f(0, 0, 1)
    si.wi = mi.Vector3f(*(mi.Float(c) for c in vv.T))
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    ctx = mi.BSDFContext()
    u1 = mi.Float(rng.uniform(0, 1, n))
    u2 = mi.Point2f(mi.Float(rng.uniform(0, 1, n)), mi.Float(rng.uniform(0, 1, n)))
    bs, w = b.sample(ctx, si, u1, u2)
    ev = b.eval(ctx, si, bs.wo)
    pdf = np.array(bs.pdf, dtype=float)

    def rows(x):
        if not pol:
            return [np.array(x[0], dtype=float).tolist()]
        return [np.broadcast_to(np.array(x[r, c][0], dtype=float).reshape(-1), (n,)).tolist()
                for r in range(4) for c in range(4)]  # fmt: skip

    wo_z = np.array(bs.wo.z, dtype=float)
    return {"w_pdf": (np.array(rows(w)) * pdf).tolist(), "eval": rows(ev), "pdf": pdf.tolist(),
            "t": (wo_z * vv[:, 2] < 0).tolist()}  # fmt: skip


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    from emscatter.render import dielectric as em_d

    with open(args["tables"], "rb") as fh:
        sets = pickle.load(fh)
    pol = "polarized" in args["variant"]
    v = np.asarray(args["v"], dtype=float)
    lt = np.asarray(args["l"], dtype=float)
    ctx = mi.BSDFContext()

    def evaluate(b):
        si = dr.zeros(mi.SurfaceInteraction3f, v.shape[0])
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.n = mi.Vector3f(0, 0, 1)
        si.wi = mi.Vector3f(*(mi.Float(c) for c in v.T))
        if "spectral" in args["variant"]:
            si.wavelengths = mi.UnpolarizedSpectrum(550.0)
        val = b.eval(ctx, si, mi.Vector3f(*(mi.Float(c) for c in lt.T)))
        if not pol:
            return np.array(val[0], dtype=float).tolist()
        n = v.shape[0]  # an element Mitsuba keeps as a literal has width 1: broadcast it

        def el(x):
            return np.broadcast_to(np.array(x, dtype=float).reshape(-1), (n,)).tolist()

        return [[el(val[r, c][0]) for c in range(4)] for r in range(4)]

    res: dict = {"error": {}}
    for name, (refl, bt, inner) in sets.items():
        try:
            b = mi.load_dict(em_d.bsdf_dict(refl, bt, inner, coherent=False))
        except Exception as err:  # the refusal's message is what the test checks
            res["error"][name] = str(err)
            continue
        res["error"][name] = None
        res[name] = evaluate(b)
        if name == "aniso" and args.get("sample"):
            res["sample"] = sample_check(mi, dr, b, v, pol)
        res["to_string"] = str(b)
    if args.get("rd"):
        a_u, a_v = (float(x) for x in args["rd"])
        rd = mi.load_dict({"type": "roughdielectric", "distribution": "beckmann",
                           "alpha_u": a_u, "alpha_v": a_v, "int_ior": EPS**0.5,
                           "ext_ior": 1.0, "sample_visible": False})  # fmt: skip
        res["rd"] = evaluate(rd)
        if pol:
            res["rd_mueller"] = facet_mueller(mi, dr, v, lt)
    print(json.dumps(res, allow_nan=True))


if __name__ == "__main__":
    main(sys.argv[1])
    sys.stdout.flush()
