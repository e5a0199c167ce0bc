"""Mitsuba evaluations for tests/test_render_dielectric_aniso.py in a fresh interpreter (Dr.Jit
variants are per process): ``python tests/dielectric_aniso_worker.py JSON`` with ``{"variant",
"m_x", "m_y", "v": [[x, y, z], ...] (towards the viewer, si.wi), "l": [...] (towards the
light, wo), "iso": bool (optional: also the isotropic plugin on the same nodes, m_x = m_y),
"grid": "fine" | "coarse" (:data:`GRIDS`), "rotated": bool (optional: also the plugin of the
surface turned by 90°, ℓx ↔ ℓy, at the directions turned with it)}`` builds GO tables of
glass (ε = 2.25, anisotropic Beckmann slopes m_x along the tangent x, m_y along y, separable
Smith: Mitsuba's anisotropic
``roughdielectric`` with ``alpha_u = m_x``, ``alpha_v = m_y``), loads them in the
``emscatter_dielectric`` plugin and prints ``{"em", "rd", "table", ...}`` (``bsdf.eval`` in
radiance mode, channel 0; ``table``: the BTDF table's own value × the light's cosine, NaN
where the pair is not light-above/viewer-below) as JSON on its last line."""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np

EPS = 2.25
GRIDS = {
    "fine": {"n_theta": 90, "n_phi_i": 25, "n_theta_t": 90, "n_phi": 240},  # 1°, 3.75°, 1°, 1.5°
    "coarse": {"n_theta": 30, "n_phi_i": 9, "n_theta_t": 40, "n_phi": 120},  # plugin vs plugin
}


def tables(m_x: float, m_y: float, iso: bool = False, grid: str = "fine"):
    """(reflection, anisotropic BTDF, isotropic BTDF on the same nodes or None)."""
    from emscatter.brdf import build_table
    from emscatter.brdf.btdf_aniso import build_anisotropic_btdf_table
    from emscatter.brdf.btdf_table import build_btdf_table
    from emscatter.spectra import GaussianCorrelation

    surf = GaussianCorrelation(sigma=0.15e-6, length=1e-6, dimension=2)
    opts = {"shadowing": "separable", "slope_variance": (m_x**2 / 2, m_y**2 / 2)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if iso:  # the same isotropic BRDF for both plugins
            refl = build_table(surf, EPS, [550e-9], method="go", resolution=(45, 91),
                               energy="off", **opts)  # fmt: skip
        else:
            refl = build_table(surf, EPS, [550e-9], method="go", resolution=(20, 41),
                               anisotropic=True, energy="off", **opts)  # fmt: skip
        g = GRIDS[grid]
        bt = build_anisotropic_btdf_table(surf, EPS, [550e-9], **g, dtype="float32", **opts)
        bt_iso = None
        if iso:
            bt_iso = build_btdf_table(surf, EPS, [550e-9], n_theta=g["n_theta"],
                                      n_theta_t=g["n_theta_t"], n_phi=g["n_phi"] // 2 + 1,
                                      **opts)  # fmt: skip
    return refl, bt, bt_iso


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    from emscatter.render import dielectric as em_d

    m_x, m_y = float(args["m_x"]), float(args["m_y"])
    grid = str(args.get("grid", "fine"))
    refl, bt, bt_iso = tables(m_x, m_y, bool(args.get("iso", False)), grid)
    bsdfs = {
        "em": mi.load_dict(em_d.bsdf_dict(refl, bt, coherent=False)),
        "rd": mi.load_dict({"type": "roughdielectric", "distribution": "beckmann",
                            "alpha_u": m_x, "alpha_v": m_y, "int_ior": EPS**0.5,
                            "ext_ior": 1.0, "sample_visible": False}),
    }  # fmt: skip
    if bt_iso is not None:
        bsdfs["iso"] = mi.load_dict(em_d.bsdf_dict(refl, bt_iso, coherent=False))
    v = np.asarray(args["v"], dtype=float)
    lt = np.asarray(args["l"], dtype=float)
    ctx = mi.BSDFContext()

    def evaluate(b, vv, ll):
        si = dr.zeros(mi.SurfaceInteraction3f, vv.shape[0])
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.n = mi.Vector3f(0, 0, 1)
        si.wi = mi.Vector3f(*(mi.Float(c) for c in vv.T))
        if "spectral" in args["variant"]:
            si.wavelengths = mi.Spectrum(550.0)
        val = b.eval(ctx, si, mi.Vector3f(*(mi.Float(c) for c in ll.T)))
        return np.array(val[0], dtype=float).tolist()

    res = {name: evaluate(b, v, lt) for name, b in bsdfs.items()}
    # the table itself: light l above, viewer v below (radiance: f_t(l → v) |cosθ_l|)
    fwd = (lt[:, 2] > 0) & (v[:, 2] < 0)
    tab = np.full(v.shape[0], np.nan)
    tab[fwd] = bt.evaluate(lt[fwd], v[fwd], 550e-9) * np.abs(lt[fwd, 2])
    res["table"] = tab.tolist()
    if args.get("rotated"):  # the surface turned by 90° about z: ℓx ↔ ℓy
        _, bt_r, _ = tables(m_y, m_x, grid=grid)
        rot = mi.load_dict(em_d.bsdf_dict(refl, bt_r, coherent=False))
        turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # x → y
        res["rotated"] = evaluate(rot, v @ turn.T, lt @ turn.T)
        res["turned_only"] = evaluate(bsdfs["em"], v @ turn.T, lt @ turn.T)
    res["to_string"] = str(bsdfs["em"])
    print(json.dumps(res, allow_nan=True))


if __name__ == "__main__":
    main(sys.argv[1])
    sys.stdout.flush()
