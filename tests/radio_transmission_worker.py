"""Sionna RT checks of diffuse transmission through rough walls (``transmission="diffuse"``),
run in a fresh interpreter (Dr.Jit variants are per process):
``python tests/radio_transmission_worker.py CHECK ...`` prints one JSON object
``{check: {"result" | "error", "warnings"}}`` on its last line. Used by
tests/test_radio_transmission_material.py."""

from __future__ import annotations

import math
import sys
import warnings

import numpy as np

F = 28e9
# GO holds at 28 GHz: kσ = 1.76 ((2kσ)² = 12.4 ≥ 10), kℓ = 11.7 ≥ 6
SIGMA, LENGTH = 3e-3, 20e-3
MEDIUM, THICKNESS = "brick", 0.1


def _surface():
    from emscatter.spectra import GaussianCorrelation

    return GaussianCorrelation(sigma=SIGMA, length=LENGTH)


def _material_at(name, f=F, transmission="diffuse", surface="rough", medium=MEDIUM,
                 thickness=THICKNESS):  # fmt: skip
    """A material with its tables of frequency ``f`` set by hand (no scene: the material's own
    sample/eval are called with Dr.Jit arrays)."""
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.material_slice import _Slice
    from emscatter.radio.tables import build_tables
    from emscatter.radio.transmission_tables import build_transmission_tables

    rough = _surface() if surface == "rough" else None
    m = EmscatterRadioMaterial(name, surface=rough, medium=medium, thickness=thickness,
                               transmission=transmission)  # fmt: skip
    m._set_medium_constants(f)
    m._frequency = f
    if rough is not None:
        t = build_tables(rough, m._eps, f, label=name)
        tt = None
        if transmission == "diffuse":
            tt = build_transmission_tables(rough, m._eps, f, thickness, t)
        m._active = _Slice(t, tt)
    return m


def _interaction(theta, n, enabled):
    import drjit as dr
    import mitsuba as mi

    si = dr.zeros(mi.SurfaceInteraction3f, n)
    nrm = mi.Vector3f(0.0, 0.0, 1.0)
    si.n = nrm
    si.sh_frame.n = nrm
    si.initialize_sh_frame()
    k = mi.Vector3f(math.sin(theta), 0.0, -math.cos(theta))
    si.wi = si.to_local(k)
    si.dp_du = mi.Vector3f(0.0, 0.0, 0.0)
    si.dp_du.z = dr.reinterpret_array(mi.Float, mi.UInt(int(enabled)))
    si.t = mi.Float(1.0)  # the incident tube's solid angle Ω [sr]
    return si


def _powers(jones):
    """|J e|² for the incident world-implicit θ̂ (= local v here: the normal is z) and φ̂ (h)."""
    import drjit as dr
    import mitsuba as mi
    from sionna.rt.utils import spectrum_to_matrix_4f

    j = spectrum_to_matrix_4f(jones)
    out = []
    for e in (mi.Vector4f(0.0, 1.0, 0.0, 0.0), mi.Vector4f(1.0, 0.0, 0.0, 0.0)):  # h, v
        out.append(np.asarray(dr.squared_norm(j @ e), dtype=np.float64))
    return np.stack(out)  # (2 [h, v], n)


def _eval_budget(m, theta, n_quad=64):
    """The material's R_coh, R_diff, T_coh, T_diff per incident polarization from eval():
    the diffuse parts by Gauss–Legendre quadrature over each hemisphere (Ω = 1)."""
    import mitsuba as mi
    from sionna.rt.constants import InteractionType

    x, w = np.polynomial.legendre.leggauss(n_quad)
    mu, wmu = 0.5 * (x + 1), 0.5 * w
    phi, wphi = math.pi * (x + 1), math.pi * w
    mm, pp = np.meshgrid(mu, phi, indexing="ij")
    ww = np.outer(wmu, wphi).ravel()
    ctx = mi.BSDFContext(mode=mi.TransportMode.Importance, type_mask=0, component=0)
    out = {}
    sin = np.sqrt(1 - mm**2).ravel()
    for name, sign in (("r_diff", 1.0), ("t_diff", -1.0)):
        si = _interaction(theta, sin.size, InteractionType.DIFFUSE)
        ko = mi.Vector3f(sin * np.cos(pp.ravel()), sin * np.sin(pp.ravel()), sign * mm.ravel())
        p = _powers(m.eval(ctx, si, si.to_world(ko), True))
        out[name] = p @ ww
    k = np.array([math.sin(theta), 0.0, -math.cos(theta)])
    for name, event, ko in (("r_coh", InteractionType.SPECULAR, k * [1, 1, -1]),
                            ("t_coh", InteractionType.REFRACTION, k)):  # fmt: skip
        si = _interaction(theta, 1, event)
        p = _powers(m.eval(ctx, si, mi.Vector3f(*(float(v) for v in ko)), True))
        out[name] = p[:, 0]
    return out


def _sample_budget(m, theta, n, seed, path_solver=False):
    """Mean power per event class from sample(): |J e|² × (2π for a diffuse event: the new
    tube's solid angle; 1 otherwise) over ``n`` lanes, and the Monte Carlo standard errors."""
    import mitsuba as mi
    from sionna.rt.constants import NO_JONES_MATRIX, InteractionType

    every = InteractionType.SPECULAR | InteractionType.DIFFUSE | InteractionType.REFRACTION
    si = _interaction(theta, n, every)
    ctx = mi.BSDFContext(mode=mi.TransportMode.Importance, type_mask=0, component=0)
    rng = np.random.default_rng(seed)
    s1 = mi.Float(rng.random(n))
    s2 = mi.Point2f(rng.random(n), rng.random(n))
    if path_solver:  # Sionna's PathSolver samples with NO_JONES_MATRIX (then eval() per path)
        ctx.component |= NO_JONES_MATRIX
        bs, _ = m.sample(ctx, si, s1, s2, True)
        ev = np.asarray(bs.sampled_component)
        wz = np.asarray(si.to_local(bs.wo).z)
        return {"diffuse_back": int(np.sum((ev == InteractionType.DIFFUSE) & (wz < 0))),
                "diffuse": int(np.sum(ev == InteractionType.DIFFUSE))}  # fmt: skip
    bs, jones = m.sample(ctx, si, s1, s2, True)
    p = _powers(jones)
    ev = np.asarray(bs.sampled_component)
    wz = np.asarray(si.to_local(bs.wo).z)
    diffuse = ev == InteractionType.DIFFUSE
    p = p * np.where(diffuse, 2 * math.pi, 1.0)
    classes = {
        "r_coh": ev == InteractionType.SPECULAR,
        "r_diff": diffuse & (wz > 0),
        "t_coh": ev == InteractionType.REFRACTION,
        "t_diff": diffuse & (wz < 0),
    }
    out, se = {}, {}
    for name, sel in classes.items():
        x = p * sel
        out[name] = x.mean(axis=1)
        se[name] = x.std(axis=1) / math.sqrt(n)
    return out, se, int(np.sum(ev == InteractionType.NONE))


def check_material_budget(medium=MEDIUM, thickness=THICKNESS):
    """R_coh + R_diff + T_coh + T_diff (+ A) per incidence from the material's own eval() and
    sample(), against its tables and emscatter.radio.slab_diffuse."""
    import sionna.rt  # noqa: F401  (sets the variant)

    from emscatter.radio.slab_diffuse import diffuse_transmission

    m = _material_at("budget", medium=medium, thickness=thickness)
    tt = m.active_transmission_tables
    nodes = tt.theta_nodes
    thetas = [float(nodes[0]), float(nodes[10]), math.radians(37.0), float(nodes[25]),
              math.radians(63.0)]  # fmt: skip
    sl = diffuse_transmission(_surface(), m._eps, F, thickness, theta=np.array(thetas))
    rows = []
    for i, th in enumerate(thetas):
        ev = _eval_budget(m, th)
        smp, se, none = _sample_budget(m, th, 1 << 18, seed=i)
        j = int(np.argmin(np.abs(nodes - th)))
        at_node = bool(abs(nodes[j] - th) < 1e-9)
        scale = np.array([np.interp(th, nodes, tt.scale[p]) for p in (0, 1)])
        absorbed = np.array([np.interp(th, nodes, tt.absorbed[p]) for p in (0, 1)])
        rows.append({
            "theta_deg": math.degrees(th), "at_node": at_node,
            "eval": {k: v.tolist() for k, v in ev.items()},
            "sample": {k: v.tolist() for k, v in smp.items()},
            "sample_se": {k: v.tolist() for k, v in se.items()},
            "none_events": none,
            "tables": {"t_diff": tt.t_diff[:, j].tolist(),
                       "r_diff": (tt.r_front[:, j] + tt.r_internal[:, j]).tolist(),
                       "r_coh": tt.r_coh[:, j].tolist(), "t_coh": tt.t_coh[:, j].tolist()},
            "slab": {"t_diff": sl.t_diff[:, i].tolist(), "r_diff": sl.r_diff[:, i].tolist(),
                     "r_coh": sl.r_coh[:, i].tolist(), "t_coh": sl.t_coh[:, i].tolist(),
                     "absorbed": sl.absorbed[:, i].tolist()},
            "scale": scale.tolist(), "absorbed_material": absorbed.tolist(),
        })  # fmt: skip
    return {"rows": rows, "valid": bool(tt.valid)}


def check_path_solver_sampling():
    """With NO_JONES_MATRIX (Sionna's PathSolver) no diffuse event goes into the back
    hemisphere and a DiffuseTransmissionWarning is issued once; RadioMapSolver-style
    sampling does send some there."""
    import sionna.rt  # noqa: F401

    m = _material_at("paths")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ps = _sample_budget(m, math.radians(30.0), 1 << 14, seed=1, path_solver=True)
        _sample_budget(m, math.radians(30.0), 1 << 14, seed=2, path_solver=True)
    msgs = [str(w.message) for w in caught if "DiffuseTransmission" in type(w.message).__name__]
    smp, _, _ = _sample_budget(m, math.radians(30.0), 1 << 14, seed=1)
    return {**ps, "warnings": msgs, "rm_t_diff": smp["t_diff"].tolist(), "text": m.to_string()}


TX = (-1.0, 0.0, 1.5)  # V-polarized isotropic transmitter above the wall (z = 0)
WALL = 8.0  # [m] side of the square wall
MAP = {"center": (0.0, 0.0, -1.5), "size": (4.0, 4.0), "cell_size": (0.5, 0.5)}  # behind it


def _wall_map(material, samples, seed=7):
    import mitsuba as mi
    import sionna.rt as rt

    from emscatter.radio import scenes

    sc = scenes.load(scenes.plate(WALL), F, lambda o, m, t: material)
    sc.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    sc.rx_array = sc.tx_array
    sc.add(rt.Transmitter("tx", position=list(TX)))
    rm = rt.RadioMapSolver()(
        sc, center=mi.Point3f(*MAP["center"]), orientation=mi.Point3f(0, 0, 0),
        size=mi.Point2f(*MAP["size"]), cell_size=mi.Point2f(*MAP["cell_size"]),
        samples_per_tx=samples, max_depth=1, los=True, specular_reflection=True,
        diffuse_reflection=True, refraction=True, seed=seed,
    )  # fmt: skip
    pg = np.asarray(rm.path_gain.numpy(), dtype=np.float64)[0]
    centers = np.asarray(rm.cell_centers.numpy(), dtype=np.float64)
    return pg, centers


def wall_prediction(centers, eps, n_grid=161, n_sub=2):
    """Path gain behind the wall per radio-map cell from emscatter alone: the bistatic radar
    equation with the slab_diffuse lobe, ``P_r/P_t = (λ/4π)² ∫ cosθi T_v(θi → θo, φ) /
    (r₁² r₂²) dA`` (isotropic unit-gain antennas; the V transmitter is TM = v at every point
    of the wall in z = 0), averaged over ``n_sub²`` Gauss points per cell, plus the coherent
    slab ray ``|T_v|² (λ / 4π r)²``; and the diffuse part alone."""
    from scipy.interpolate import RegularGridInterpolator

    from emscatter.conventions import wavenumber
    from emscatter.radio.slab import slab_coefficients
    from emscatter.radio.slab_diffuse import diffuse_transmission

    rough = _surface()
    th_nodes = np.radians(np.linspace(0.0, 80.0, 41))
    b = diffuse_transmission(rough, eps, F, THICKNESS, theta=th_nodes, n_mu=48, n_phi=48,
                             n_modes=24)  # fmt: skip
    modes = b.t_modes[1] / (2 * math.pi * b.mu_weights[None, :, None])  # v: (θ, μ, m)
    mu = b.mu_nodes
    interp = RegularGridInterpolator((th_nodes, mu), modes, bounds_error=False, fill_value=None)
    lam = 2 * math.pi / wavenumber(frequency=F)
    tx = np.array(TX)
    g = np.linspace(-WALL / 2, WALL / 2, n_grid)
    wg = np.full(n_grid, g[1] - g[0])
    wg[[0, -1]] *= 0.5
    yx, yy = np.meshgrid(g, g, indexing="ij")
    wa = np.outer(wg, wg)
    r1v = np.stack([yx - tx[0], yy - tx[1], -tx[2] * np.ones_like(yx)], -1)
    r1 = np.linalg.norm(r1v, axis=-1)
    cos_i = tx[2] / r1
    th_i = np.arccos(cos_i)
    m = np.arange(modes.shape[-1])
    xs, ws = np.polynomial.legendre.leggauss(n_sub)
    half = 0.5 * MAP["cell_size"][0]
    ny, nx = centers.shape[:2]
    diffuse = np.zeros((ny, nx))
    coherent = np.zeros((ny, nx))
    for iy in range(ny):
        for ix in range(nx):
            c = centers[iy, ix]
            acc_d = acc_c = 0.0
            for ax, wx in zip(xs, ws, strict=True):
                for ay, wy in zip(xs, ws, strict=True):
                    p = c + half * np.array([ax, ay, 0.0])
                    r2v = p - np.stack([yx, yy, np.zeros_like(yx)], -1)
                    r2 = np.linalg.norm(r2v, axis=-1)
                    mu_o = np.abs(r2v[..., 2]) / r2
                    den = np.hypot(r1v[..., 0], r1v[..., 1]) * np.hypot(r2v[..., 0], r2v[..., 1])
                    dot = r1v[..., 0] * r2v[..., 0] + r1v[..., 1] * r2v[..., 1]
                    cphi = np.where(den > 1e-12, dot / np.maximum(den, 1e-12), 1.0)
                    phi = np.arccos(np.clip(cphi, -1, 1))
                    coef = interp(np.stack([th_i.ravel(), mu_o.ravel()], -1))  # (n, m)
                    basis = np.where(m == 0, 1.0, 2.0) * np.cos(np.outer(phi.ravel(), m))
                    lobe = np.maximum((coef * basis).sum(-1), 0.0).reshape(yx.shape)
                    integrand = cos_i * lobe / (r1 * r1 * r2 * r2)
                    acc_d += wx * wy / 4 * (lam / (4 * math.pi)) ** 2 * np.sum(integrand * wa)
                    d = p - tx
                    r = np.linalg.norm(d)
                    ci = abs(d[2]) / r
                    _, _, _, tv = slab_coefficients(eps, ci, 2 * math.pi / lam, THICKNESS,
                                                    sigma=SIGMA, front=None)  # fmt: skip
                    acc_c += wx * wy / 4 * abs(tv) ** 2 * (lam / (4 * math.pi * r)) ** 2
            diffuse[iy, ix], coherent[iy, ix] = acc_d, acc_c
    return diffuse + coherent, diffuse


def check_wall_map():
    """RadioMapSolver behind a rough wall (transmission="diffuse" and "coherent") against the
    slab_diffuse prediction; a flat wall with transmission="diffuse" against Sionna's own
    ITU material (same seed)."""
    import sionna.rt as rt

    from emscatter.radio.material import EmscatterRadioMaterial

    samples = 2_000_000
    rough = EmscatterRadioMaterial("rough-wall", surface=_surface(), medium=MEDIUM,
                                   thickness=THICKNESS, transmission="diffuse")  # fmt: skip
    pg, centers = _wall_map(rough, samples)
    tt = rough.active_transmission_tables
    pred, pred_diffuse = wall_prediction(centers, rough._eps)
    coh = EmscatterRadioMaterial("rough-coherent", surface=_surface(), medium=MEDIUM,
                                 thickness=THICKNESS)  # fmt: skip
    pg_coh, _ = _wall_map(coh, samples)
    flat_e = EmscatterRadioMaterial("flat-wall", medium=MEDIUM, thickness=THICKNESS,
                                    transmission="diffuse")  # fmt: skip
    pg_fe, _ = _wall_map(flat_e, 200_000)
    builtin = rt.ITURadioMaterial("itu-wall", itu_type=MEDIUM, thickness=THICKNESS)
    pg_fb, _ = _wall_map(builtin, 200_000)
    both = (pg_fe > 0) & (pg_fb > 0)
    return {
        "map": pg.tolist(),
        "prediction": pred.tolist(),
        "prediction_diffuse": pred_diffuse.tolist(),
        "map_coherent": pg_coh.tolist(),
        "flat_same_support": bool(np.array_equal(pg_fe > 0, pg_fb > 0)),
        "flat_cells": int(both.sum()),
        "flat_max_db": float(np.max(np.abs(10 * np.log10(pg_fe[both] / pg_fb[both])))),
        "scale_range": [float(tt.scale[:, :36].min()), float(tt.scale[:, :36].max())],
        "samples": samples,
    }


def check_inputs():
    """Bad transmission= input names the parameter; the XML keyword reaches the material."""
    import mitsuba as mi
    import sionna.rt  # noqa: F401

    from emscatter.radio.material import PLUGIN_NAME, EmscatterRadioMaterial

    out = {}
    for key, kw in {
        "bad_value": {"transmission": "lambertian"},
        "half_space": {"transmission": "diffuse", "thickness": None},
        "textured": {"transmission": "diffuse", "texture_direction": (0, 0, 1)},
        "bad_face": {"transmission": "diffuse", "transmission_face": "lambertian"},
    }.items():
        try:
            EmscatterRadioMaterial(f"bad-{key}", surface=_surface(), medium=MEDIUM, **kw)
            out[key] = "no error"
        except ValueError as e:
            out[key] = str(e)
    props = mi.Properties(PLUGIN_NAME)
    props.set_id("xml-wall")
    props["medium"] = MEDIUM
    props["rms_height"] = SIGMA
    props["correlation_length"] = LENGTH
    props["transmission"] = "diffuse"
    props["transmission_face"] = "po"
    xml = EmscatterRadioMaterial(props=props)
    out["xml"], out["xml_face"] = xml.transmission, xml._face
    out["default"] = EmscatterRadioMaterial("default-wall", surface=_surface(),
                                            medium=MEDIUM).transmission  # fmt: skip
    return out


def check_material_budget_glassy():
    """The same budget for a thin low-loss pane (ε = 2.25 + 0.01j, 2 cm): 70 % goes through
    diffusely and up to 17 % of the incident power comes back out of the front face after
    crossing the slab (the internal light in the reflection lobe)."""
    return check_material_budget(medium=2.25 + 0.01j, thickness=0.02)


CHECKS = {
    "material_budget": check_material_budget,
    "material_budget_glassy": check_material_budget_glassy,
    "path_solver_sampling": check_path_solver_sampling,
    "wall_map": check_wall_map,
    "inputs": check_inputs,
}


def main(argv):
    from worker_checks import run_checks  # beside this script (its folder is on sys.path)

    return run_checks(CHECKS, argv)


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
