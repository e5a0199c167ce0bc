"""Sampling consistency of the ``emscatter`` reflection plugin (render/mitsuba.py) for
tests/test_render_reflection_pdf.py in a fresh interpreter (Dr.Jit variants are per process):
``python tests/reflection_pdf_worker.py JSON`` with ``{"variant", "check": "consistency",
"tables": [{"alpha", "aspect", "resolution"}, ...] (tests/render_helpers.py's GO tables),
"thetas_deg": [...], "n": samples per viewer, "seed"}``.

``consistency``, per table, over viewers at each θi and a few azimuths: among the glossy
samples with weight > 0, the fraction whose ``pdf(wo)`` differs from the returned ``bs.pdf``
by more than 1e-4 relative and the range of that ratio; the largest relative difference of
``eval/pdf`` from the weight; for the samples with weight 0, how many carry ``bs.pdf > 0``
or ``pdf(wo) > 0``; and the fraction of samples whose drawn half-vector cell differs from the
one ``pdf`` finds for the final ``wo`` (``_sample_glossy``'s cell density against
``_glossy_pdf``: the residual that bounds the bias of returning ``pdf(wo)``).

Prints the results as JSON on its last line.
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np

AZIMUTHS = (0.0, 0.7, 2.0, 4.1)  # viewer φi [rad]


def _viewers(thetas_deg):
    out = []
    for deg in thetas_deg:
        th = math.radians(deg)
        for ph in AZIMUTHS:
            out.append([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
    return np.array(out)


def _consistency(mi, dr, bsdf, v, n, seed):
    vv = np.repeat(v, n, axis=0).astype(np.float32)
    si = dr.zeros(mi.SurfaceInteraction3f, vv.shape[0])
    si.wi = mi.Vector3f(*(mi.Float(c) for c in vv.T))
    rng = np.random.default_rng(seed)
    a, b, c = (rng.random(vv.shape[0]).astype(np.float32) for _ in range(3))
    ctx = mi.BSDFContext()
    bs, w = bsdf.sample(ctx, si, mi.Float(a), mi.Point2f(mi.Float(b), mi.Float(c)))
    pdf = np.array(bsdf.pdf(ctx, si, bs.wo), dtype=float)
    ev = np.array(bsdf.eval(ctx, si, bs.wo), dtype=float)[0]
    w = np.array(w, dtype=float)[0]
    bpdf = np.array(bs.pdf, dtype=float)
    glossy = np.array(bs.sampled_type) == int(mi.BSDFFlags.GlossyReflection)
    good = glossy & (w > 0)
    zero = glossy & ~(w > 0)
    ratio = pdf[good] / bpdf[good]
    bad = np.abs(ratio - 1) > 1e-4
    wo_z = np.array(bs.wo.z, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ew = np.abs(ev[good] / bpdf[good] - w[good]) / w[good]
    # the drawn cell's density (before the final wo) against the one pdf finds for wo
    p_d = np.array(bsdf._delta_probability(ctx, si, True), dtype=float)
    xi = np.clip((a - p_d) / np.maximum(1 - p_d, 1e-30), 0, 1).astype(np.float32)
    wo_c, pdf_cell = bsdf._sample_glossy(
        si, mi.Float(xi), mi.Point2f(mi.Float(b), mi.Float(c)), True
    )
    pdf_wo = np.array(bsdf._glossy_pdf(si, wo_c, True), dtype=float)
    pdf_cell = np.array(pdf_cell, dtype=float)
    up = (np.array(wo_c.z, dtype=float) > 0) & (pdf_cell > 0) & glossy
    cell_ratio = pdf_wo[up] / pdf_cell[up]
    cell_bad = np.abs(cell_ratio - 1) > 1e-4
    # where those samples lie: distance of the float64 half-vector of the final wo to the
    # nearest cell edge, in cell widths (columns uniform in u = √(2θh/π), rows in φh)
    res = bsdf._n
    wo64 = np.stack([np.array(x, dtype=float) for x in (wo_c.x, wo_c.y, wo_c.z)], -1)
    h = vv + wo64
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    u_t = np.sqrt(np.arccos(np.clip(h[:, 2], -1, 1)) * 2 / np.pi) * res
    phi = np.arctan2(h[:, 1], h[:, 0])
    if bsdf._data.isotropic:
        phi = phi - np.arctan2(vv[:, 1], vv[:, 0])
    u_p = np.mod((phi + np.pi) / (2 * np.pi), 1.0) * res
    edge = np.minimum(np.abs(u_t - np.rint(u_t)), np.abs(u_p - np.rint(u_p)))[up][cell_bad]
    return {
        "cell_mismatch_edge_distance_max": float(edge.max()) if edge.size else 0.0,
        "n_zero_below_horizon_with_pdf": int((zero & (wo_z <= 0) & ((bpdf > 0) | (pdf > 0))).sum()),
        "n_samples": int(vv.shape[0]),
        "n_weighted": int(good.sum()),
        "mismatch_fraction": float(bad.mean()),
        "n_mismatch": int(bad.sum()),
        "ratio_min": float(ratio.min()),
        "ratio_max": float(ratio.max()),
        "eval_over_pdf_max_rel": float(np.nanmax(ew)),
        "n_weight_zero": int(zero.sum()),
        "n_zero_below_horizon": int((zero & (wo_z <= 0)).sum()),
        "n_zero_with_bs_pdf": int((zero & (bpdf > 0)).sum()),
        "n_zero_with_pdf": int((zero & (pdf > 0)).sum()),
        "cell_mismatch_fraction": float(cell_bad.mean()),
        "cell_ratio_min": float(cell_ratio.min()),
        "cell_ratio_max": float(cell_ratio.max()),
    }


def main(arg: str) -> None:
    import drjit as dr
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args.get("variant", "llvm_ad_rgb"))
    from emscatter.render import mitsuba as em_mi
    from render_helpers import go_table

    v = _viewers(args.get("thetas_deg", [5.0, 30.0, 55.0, 75.0]))
    n = int(args.get("n", 25_000))
    out = {}
    for spec in args["tables"]:
        kw = {"alpha": float(spec["alpha"])}
        if float(spec.get("aspect", 1.0)) != 1.0:
            kw["aspect"] = float(spec["aspect"])
        if "resolution" in spec:
            kw["resolution"] = tuple(spec["resolution"])
        table = go_table(**kw)
        bsdf = mi.load_dict(em_mi.bsdf_dict(table))
        name = f"alpha={kw['alpha']},aspect={spec.get('aspect', 1.0)}"
        out[name] = _consistency(mi, dr, bsdf, v, n, int(args.get("seed", 3)))
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1])
    sys.stdout.flush()
