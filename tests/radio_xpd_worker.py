"""Sionna RT checks of XPD per radio-map cell (emscatter.radio.xpd_map), run in a fresh
interpreter (Dr.Jit variants are per process): ``python tests/radio_xpd_worker.py CHECK ...``
prints one JSON object ``{check: {"result" | "error", "warnings"}}`` on its last line. Used by
tests/test_radio_xpd_map.py."""

from __future__ import annotations

import sys

import numpy as np

F, TX = 28e9, (-2.0, 0.0, 2.0)
CELLS = ((6, 9), (9, 5), (2, 2), (8, 8))  # [iy, ix] of 12 × 12 cells, 0.5 m
MAP = {"center": (0.0, 0.0, 1.5), "orientation": (0.0, 0.0, 0.0), "size": (6.0, 6.0),
       "cell_size": (0.5, 0.5), "samples_per_tx": 400_000, "max_depth": 1,
       "diffuse_reflection": True, "refraction": False}  # fmt: skip


def _plate(material):
    import sionna.rt as rt

    from emscatter.radio import scenes

    sc = scenes.load(scenes.plate(8.0), F, lambda o, m, t: material)
    sc.add(rt.Transmitter("tx", position=list(TX)))
    return sc


def check_xpd_map_plate():
    """Flat ITU concrete plate (Sionna's own material) against the rough emscatter plate
    (σ = 0.4 mm, ℓ = 4 mm, SPM at 28 GHz): XPD per cell, the port maps against Sionna's own
    map, where diffuse power dominates, and a receiver in one cell against its path XPD."""
    import mitsuba as mi
    import sionna.rt as rt

    import emscatter as em
    from emscatter.radio.material import EmscatterRadioMaterial
    from emscatter.radio.xpd import path_xpd
    from emscatter.radio.xpd_map import polarized_radio_map, xpd_summary

    out = {}
    flat = _plate(rt.ITURadioMaterial("itu-plate", itu_type="concrete", thickness=0.2))
    fm = polarized_radio_map(flat, seed=3, **MAP)
    out["flat"] = xpd_summary(fm["xpd_db"][0], fm["lit"][0])
    out["flat_lit"] = int(fm["lit"][0].sum())
    rough_surface = em.GaussianCorrelation(sigma=0.4e-3, length=4e-3)
    sc = _plate(EmscatterRadioMaterial("rough-plate", surface=rough_surface, medium="concrete",
                                       thickness=None))  # fmt: skip
    rm = polarized_radio_map(sc, seed=3, **MAP)
    x = rm["xpd_db"][0]
    out["rough"] = xpd_summary(x, rm["lit"][0])
    out["rough_finite"] = int(np.isfinite(x).sum())
    # the V-transmitter port maps sum to Sionna's own map (same seed, same rays)
    sc.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    own = np.asarray(rt.RadioMapSolver()(
        sc, seed=3, center=mi.Point3f(*MAP["center"]), orientation=mi.Point3f(0, 0, 0),
        size=mi.Point2f(*MAP["size"]), cell_size=mi.Point2f(*MAP["cell_size"]),
        samples_per_tx=MAP["samples_per_tx"], max_depth=1, diffuse_reflection=True,
        refraction=False,
    ).path_gain.numpy(), dtype=np.float64)[0]  # fmt: skip
    tot = rm["ports"][0, 0, 0] + rm["ports"][1, 0, 0]
    m = own > 0
    out["ports_vs_sionna_max_rel"] = float(np.max(np.abs(tot[m] / own[m] - 1.0)))
    out["ports_same_support"] = bool(np.array_equal(own > 0, tot > 0))
    # diffuse share per cell: one more map without diffuse reflection (LoS + coherent specular)
    spec = polarized_radio_map(sc, seed=3, **{**MAP, "diffuse_reflection": False})
    share = 1.0 - (spec["co"][0] + spec["cross"][0]) / (rm["co"][0] + rm["cross"][0])
    out["spec_cross_max_db_below_co"] = float(np.min(spec["xpd_db"][0]))
    order = np.argsort(share.ravel())
    third = order.size // 3
    xr = x.ravel()
    out["xpd_low_share_median"] = float(np.median(xr[order[:third]]))
    out["xpd_high_share_median"] = float(np.median(xr[order[-third:]]))
    out["share_range"] = [float(share.min()), float(share.max())]
    # a receiver at a cell centre: its link XPD from PathSolver paths vs that cell and the 3×3
    # cells around it (ratio of summed co- and cross-polar powers)
    c = rm["cell_centers"]
    rows = []
    for iy, ix in CELLS:
        p = c[iy, ix]
        sc.add(rt.Receiver(f"rx{iy}_{ix}", position=[float(p[0]), float(p[1]), float(p[2])]))
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
    sc.tx_array = sc.rx_array = arr
    paths = rt.PathSolver()(sc, max_depth=1, samples_per_src=1_000_000,
                            max_num_paths_per_src=1_000_000, diffuse_reflection=True,
                            refraction=False, seed=1)  # fmt: skip
    link = path_xpd(paths)["link_db"][:, 0]
    for k, (iy, ix) in enumerate(CELLS):
        blk = (slice(iy - 1, iy + 2), slice(ix - 1, ix + 2))
        block = 10 * np.log10(rm["co"][0][blk].sum() / rm["cross"][0][blk].sum())
        rows.append({"cell": [iy, ix], "path_db": float(link[k]), "cell_db": float(x[iy, ix]),
                     "block_db": float(block)})  # fmt: skip
    out["receivers"] = rows
    return out


CHECKS = {"xpd_map_plate": check_xpd_map_plate}


def main(argv):
    from worker_checks import run_checks  # beside this script (its folder is on sys.path)

    return run_checks(CHECKS, argv)


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
