"""Mitsuba evaluations for tests/test_render_polarized.py in a fresh interpreter (Dr.Jit
variants are per process): ``python tests/plugin_polarized_worker.py JSON`` with ``{"variant",
"step_deg", "wi": [[x, y, z], ...] (towards the light), "wo": [...] (towards the viewer),
"wavelength" [nm], "mode": "radiance" | "importance"}`` builds the GO gold Mueller table of
tests/test_brdf_pbsdf.py (Beckmann m = 0.3, separable Smith shadowing: Mitsuba's
``roughconductor`` within GO), registers it with the emscatter plugin and prints ``{"em": [...],
"rc": [...]}`` (polarized variants: each a 4×4 Mueller matrix of ``bsdf.eval``, cosθ of the
light included; others: the scalar s0) as JSON on its last line.
"""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np

EPS_AU = (0.2 + 3.0j) ** 2  # n + ik = 0.2 + 3i (Mitsuba's eta, k)
M_SLOPE = 0.3


def go_table(step_deg: float):
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.spectra import GaussianCorrelation

    s2 = M_SLOPE**2 / 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_mueller_table(
            GaussianCorrelation(sigma=1e-6, length=6e-6, dimension=2), EPS_AU,
            [450e-9, 650e-9], method="go", theta=np.radians(np.arange(0, 90, step_deg)),
            phi=np.radians(np.arange(0, 180.01, step_deg)), energy="off",
            shadowing="separable", slope_variance=(s2, s2),
        )  # fmt: skip


#: The SPM table of the delta-lobe tests: σ = 5 nm, ℓ = 100 nm at 550 nm (kσ = 0.057, rms
#: slope 0.07: inside SPM), gold-like ε = (0.2 + 3i)², one wavelength.
SPM_SIGMA, SPM_LENGTH, SPM_LAMBDA = 5e-9, 1e-7, 550e-9


def spm_table(step_deg: float, order: int = 2):
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.spectra import GaussianCorrelation

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_mueller_table(
            GaussianCorrelation(sigma=SPM_SIGMA, length=SPM_LENGTH, dimension=2), EPS_AU,
            [SPM_LAMBDA], method="spm", theta=np.radians(np.arange(0, 90, step_deg)),
            phi=np.radians(np.arange(0, 180.01, step_deg)), energy="off", order=order,
        )  # fmt: skip


def main_spm(args) -> None:
    """``{"table": "spm", "variant", "step_deg", "wi", "wo", "delta_wi", "mode"}``: prints
    ``{"em": [eval per pair], "em_delta": [delta sample weight × pdf per delta_wi],
    "cond_delta": [Mitsuba's smooth conductor's sample weight per delta_wi], "p_delta": [...]}``
    (polarized variants: 4×4 Mueller matrices; others: the scalar s0)."""
    import mitsuba as mi

    from emscatter.render import mitsuba as em_mi

    polarized = "polarized" in args["variant"]
    key = em_mi.register_table(spm_table(float(args["step_deg"]), int(args.get("order", 2))))
    em_mi.register()
    em = mi.load_dict({"type": "emscatter", "table": key})
    cond = mi.load_dict({"type": "conductor", "eta": 0.2, "k": 3.0})
    mode = mi.TransportMode.Importance if args.get("mode") == "importance" else (
        mi.TransportMode.Radiance)  # fmt: skip
    ctx = mi.BSDFContext(mode)

    def si_of(w):
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.n = mi.Vector3f(0, 0, 1)
        si.wavelengths = [SPM_LAMBDA * 1e9] * 4
        si.wi = mi.Vector3f(w)
        return si

    def cast(m):
        m = np.array(m)
        return m.reshape(4, 4, -1)[:, :, 0].tolist() if polarized else float(np.ravel(m)[0])

    out = {"em": [], "em_delta": [], "cond_delta": [], "p_delta": []}
    importance = args.get("mode") == "importance"
    for wi, wo in zip(args["wi"], args["wo"], strict=True):
        a, b = (wi, wo) if importance else (wo, wi)
        out["em"].append(cast(em.eval(ctx, si_of(a), mi.Vector3f(b))))
    for w in args["delta_wi"]:
        si = si_of(w)
        bs, val = em.sample(ctx, si, 0.0, mi.Point2f(0.5, 0.5))
        assert int(np.ravel(bs.sampled_type)[0]) == int(mi.BSDFFlags.DeltaReflection)
        out["em_delta"].append(cast(np.array(val) * float(np.ravel(bs.pdf)[0])))
        out["p_delta"].append(float(np.ravel(bs.pdf)[0]))
        _, cval = cond.sample(ctx, si, 0.0, mi.Point2f(0.5, 0.5))
        out["cond_delta"].append(cast(cval))
    print(json.dumps(out))


def aniso_table(n_theta: int, n_phi: int, m_x: float, m_y: float):
    """GO gold, anisotropic Beckmann slopes (m_x along the tangent x, m_y along y), separable
    Smith shadowing: Mitsuba's ``roughconductor`` with ``alpha_u = m_x``, ``alpha_v = m_y``."""
    from emscatter.brdf.mueller import build_mueller_table
    from emscatter.spectra import GaussianCorrelation

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_mueller_table(
            GaussianCorrelation(sigma=1e-6, length=6e-6, dimension=2), EPS_AU, [550e-9],
            method="go", resolution=(n_theta, n_phi), anisotropic=True, energy="off",
            shadowing="separable", slope_variance=(m_x**2 / 2, m_y**2 / 2),
        )  # fmt: skip


def main_aniso(args) -> None:
    """``{"table": "aniso", "variant", "n_theta", "n_phi", "m_x", "m_y", "wi", "wo",
    "n_nodes", "seed"}``: prints ``{"em", "rc"}`` at the pairs (radiance mode), ``"em_nodes"``
    at ``n_nodes`` random table nodes in and around the lobe and ``"ref_nodes"`` the table's
    own Mueller matrices there brought to Mitsuba's frames in numpy
    (:func:`emscatter.brdf.mueller.to_mitsuba`), each cosθ of the light included (polarized
    variants: 4×4; others: the scalar s0)."""
    import mitsuba as mi

    from emscatter.brdf import frames
    from emscatter.brdf.mueller import to_mitsuba
    from emscatter.render import mitsuba as em_mi

    polarized = "polarized" in args["variant"]
    mt = aniso_table(args["n_theta"], args["n_phi"], args["m_x"], args["m_y"])
    key = em_mi.register_table(mt)
    em_mi.register()
    em = mi.load_dict({"type": "emscatter", "table": key})
    rc = mi.load_dict({"type": "roughconductor", "distribution": "beckmann",
                       "alpha_u": args["m_x"], "alpha_v": args["m_y"],
                       "eta": 0.2, "k": 3.0})  # fmt: skip
    ctx = mi.BSDFContext(mi.TransportMode.Radiance)

    def ev(bsdf, wi, wo):  # wi towards the light, wo towards the viewer
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.n = mi.Vector3f(0, 0, 1)
        si.wavelengths = [550.0] * 4
        si.wi = mi.Vector3f(wo)
        m = np.array(bsdf.eval(ctx, si, mi.Vector3f(wi)))
        return m.reshape(4, 4, -1)[:, :, 0].tolist() if polarized else float(np.ravel(m)[0])

    out = {"em": [], "rc": [], "em_nodes": [], "ref_nodes": []}
    for wi, wo in zip(args["wi"], args["wo"], strict=True):
        out["em"].append(ev(em, wi, wo))
        out["rc"].append(ev(rc, wi, wo))
    t = mt.table
    rng = np.random.default_rng(args["seed"])
    n = args["n_nodes"]
    i_ti, i_pi = rng.integers(1, t.theta_i.size, n), rng.integers(0, t.phi_i.size, n)
    # nodes in and around the lobe: θo within a node of θi, φo within two of the mirror
    i_to = np.clip(i_ti + rng.integers(-1, 2, n), 1, t.theta_o.size - 1)
    i_po = (i_pi + t.phi_o.size // 2 + rng.integers(-2, 3, n)) % t.phi_o.size
    idx = [i_ti, i_pi, i_to, i_po]
    ang = (t.theta_i[idx[0]], t.phi_i[idx[1]], t.theta_o[idx[2]], t.phi_o[idx[3]])
    m_nodes = mt.mueller[0][(slice(None), slice(None), *idx)]  # (4, 4, n)
    ref = to_mitsuba(m_nodes, *ang) * np.cos(ang[0])
    wi_n, wo_n = frames.directions(ang[0], ang[1]), frames.directions(ang[2], ang[3])
    for k in range(n):
        out["em_nodes"].append(ev(em, wi_n[k], wo_n[k]))
        out["ref_nodes"].append(ref[:, :, k].tolist() if polarized else float(ref[0, 0, k]))
    print(json.dumps(out))


def main_render(args) -> None:
    """``{"table": "render", "variant", "order", "spp"}``: a plane under a constant
    environment seen obliquely (``stokes`` integrator around ``path``) with the SPM table's
    plugin and with Mitsuba's smooth ``conductor``; prints ``{"em": image, "cond": image}``
    (H × W × channels: the colour and the Stokes AOVs)."""
    import mitsuba as mi

    from emscatter.render import mitsuba as em_mi

    key = em_mi.register_table(spm_table(6.0, int(args.get("order", 2))))
    em_mi.register()

    def scene(bsdf):
        return mi.load_dict({
            "type": "scene",
            "integrator": {"type": "stokes", "nested": {"type": "path", "max_depth": 3}},
            "sensor": {
                "type": "perspective", "fov": 20,
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[0, -3, 1.6], target=[0, 0, 0], up=[0, 0, 1]),
                "film": {"type": "hdrfilm", "width": 12, "height": 12, "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": int(args["spp"])},
            },
            "env": {"type": "constant"},
            "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale(10),
                      "bsdf": bsdf},
        })  # fmt: skip

    out = {}
    for name, bsdf in (("em", {"type": "emscatter", "table": key}),
                       ("cond", {"type": "conductor", "eta": 0.2, "k": 3.0})):  # fmt: skip
        out[name] = np.array(mi.render(scene(bsdf), seed=1)).tolist()
    print(json.dumps(out))


def main(arg: str) -> None:
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    if args.get("table") == "spm":
        main_spm(args)
        return
    if args.get("table") == "aniso":
        main_aniso(args)
        return
    if args.get("table") == "render":
        main_render(args)
        return
    from emscatter.render import mitsuba as em_mi

    polarized = "polarized" in args["variant"]
    key = em_mi.register_table(go_table(float(args["step_deg"])))
    em_mi.register()
    bsdfs = {
        "em": mi.load_dict({"type": "emscatter", "table": key}),
        "rc": mi.load_dict({"type": "roughconductor", "distribution": "beckmann",
                            "alpha": M_SLOPE, "eta": 0.2, "k": 3.0}),
    }  # fmt: skip
    ctx = mi.BSDFContext(
        mi.TransportMode.Importance
        if args.get("mode") == "importance"
        else mi.TransportMode.Radiance
    )
    out = {}
    for name, bsdf in bsdfs.items():
        vals = []
        for wi, wo in zip(args["wi"], args["wo"], strict=True):
            si = mi.SurfaceInteraction3f()
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.n = mi.Vector3f(0, 0, 1)
            si.wavelengths = [float(args["wavelength"])] * 4
            # radiance: si.wi towards the viewer, wo towards the light; importance: swapped
            a, b = (wi, wo) if args.get("mode") == "importance" else (wo, wi)
            si.wi = mi.Vector3f(a)
            m = np.array(bsdf.eval(ctx, si, mi.Vector3f(b)))
            if polarized:
                vals.append(m.reshape(4, 4, -1)[:, :, 0].tolist())
            else:
                vals.append(float(np.ravel(m)[0]))
        out[name] = vals
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1])
