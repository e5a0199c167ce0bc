"""Rough − flat radio maps of two scenes, each made rough in one call, at 3.5, 28 and 140 GHz.

Sionna's ``simple_street_canyon`` (its own ITU materials: concrete, brick, marble, wood, glass)
and emscatter's furnished room (:func:`emscatter.radio.scenes.furnished_room`, loaded with
Sionna's ``ITURadioMaterial`` per object: concrete, plasterboard, ceiling board, wood, glass)
are each roughened by ONE call of :func:`emscatter.radio.compare_rough_flat` (which calls
:func:`emscatter.radio.roughen` with emscatter's default roughness table,
:data:`emscatter.radio.DEFAULT_ROUGHNESS`, and gives the scene back flat). Sionna's
``RadioMapSolver`` (specular + diffuse reflection + refraction, same seed for both states)
gives the path gain per cell; the figure shows ``10 log10(rough / flat)`` [dB], grey where a
cell is unlit in either state.

Bands: every material of both scenes is inside its ITU-R P.2040 band at all three frequencies
(Sionna RT 2.2 carries the P.2040-4 bands above 100 GHz: concrete and brick 110–330 GHz,
marble, wood, glass, plasterboard and ceiling board 100–400 GHz), so nothing is extrapolated.
Neither scene has metal (ITU metal stops at 100 GHz); the check is made before any ray
(:func:`emscatter.radio.roughening.plan`) and fails, naming medium and band, if that changes.

Run (from the repository root, ≈ 2 min on 2 shared CPU cores, 10⁷ rays per map)::

    PYTHONPATH=src python validation/radio/rough_minus_flat_maps.py

writes ``docs/figures/radio_rough_minus_flat_maps.png`` and
``validation/radio/rough_minus_flat_maps.csv`` (one row per scene and frequency: cells lit,
median and 5/95 % quantiles of rough − flat, the power-weighted mean). ``--quick`` (coarse
cells, few rays, small tables; seconds) and ``--out DIR`` (both files there) are for tests.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
FREQUENCIES = (3.5e9, 28e9, 140e9)
#: scene → (transmitter [m], map height [m], cell [m]) — the street canyon's transmitter is
#: the one of ``emscatter radio --scene simple_street_canyon`` (main street, 10 m up).
SETUP = {
    "simple_street_canyon": ((20.0, 0.0, 10.0), 1.5, 1.0),
    "room": ((1.0, 1.0, 2.5), 1.2, 0.05),
}
TITLES = {"simple_street_canyon": "simple_street_canyon", "room": "furnished room"}


def load(name: str):
    """The scene with Sionna's own ITU materials (the flat reference)."""
    import sionna.rt as rt

    from emscatter.radio import scenes

    if name == "room":
        return scenes.load(
            scenes.furnished_room(),
            3.5e9,
            lambda o, m, t: rt.ITURadioMaterial(f"itu-{o}", itu_type=m, thickness=t),
        )
    return rt.load_scene(getattr(rt.scene, name), merge_shapes=False)


def run_scene(name: str, samples: int, depth: int, quick: bool) -> list[dict]:
    import sionna.rt as rt

    from emscatter import radio
    from emscatter.radio.roughening import plan

    tx, height, cell = SETUP[name]
    sc = load(name)
    # every medium in band at every frequency, checked before a ray is traced
    plan(sc, frequencies=FREQUENCIES)
    arr = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    sc.tx_array = sc.rx_array = arr
    sc.add(rt.Transmitter("tx", position=list(tx)))
    if name == "room":
        lo, hi = np.array([0.0, 0.0]), np.array([6.0, 5.0])
    else:
        box = sc.mi_scene.bbox()
        lo, hi = np.array(box.min)[:2], np.array(box.max)[:2]
    if quick:
        cell *= 8
    opts = None
    if quick:
        from emscatter.radio.tables import TableOptions

        opts = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)
    out = []
    for f in FREQUENCIES:
        sc.frequency = f
        t0 = time.perf_counter()
        res = radio.compare_rough_flat(
            sc,
            paths=False,
            table_options=opts,
            radio_map={
                "center": (*((lo + hi) / 2), height),
                "orientation": (0.0, 0.0, 0.0),
                "size": tuple(hi - lo),
                "cell_size": (cell, cell),
                "samples_per_tx": samples,
                "max_depth": depth,
            },
        )
        rm = res["radio_map"]
        out.append(
            {
                "scene": name,
                "frequency": f,
                "diff": rm["difference_db"][0],
                "lit": rm["lit"][0],
                "flat": rm["flat"][0],
                "rough": rm["rough"][0],
                "extent": (lo[0], hi[0], lo[1], hi[1]),
                "tx": tx,
                "materials": res["materials"],
                "seconds": time.perf_counter() - t0,
            }
        )
        print(f"{name} {f / 1e9:g} GHz: {out[-1]['seconds']:.1f} s", flush=True)
    return out


def summary(r: dict) -> dict:
    d = r["diff"][r["lit"]]
    flat, rough = r["flat"][r["lit"]], r["rough"][r["lit"]]
    media = sorted({m["medium"] for m in r["materials"]})
    return {
        "scene": r["scene"],
        "frequency_ghz": r["frequency"] / 1e9,
        "cells_lit": int(d.size),
        "median_db": float(np.median(d)),
        "p05_db": float(np.percentile(d, 5)),
        "p95_db": float(np.percentile(d, 95)),
        # rough / flat of the total power over the cells lit in both (one number per map)
        "total_ratio_db": float(10 * np.log10(rough.sum() / flat.sum())),
        "media": " ".join(media),
        "seconds": r["seconds"],
    }


def figure(results: list[dict], path: Path, command: str) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from emscatter.io import save_figure

    scenes_ = list(dict.fromkeys(r["scene"] for r in results))
    fig, axes = plt.subplots(
        len(scenes_), len(FREQUENCIES), figsize=(5.0 * len(FREQUENCIES), 4.0 * len(scenes_) + 0.6),
        squeeze=False, layout="constrained",
    )  # fmt: skip
    cmap = matplotlib.colormaps["RdBu_r"].copy()
    cmap.set_bad("0.8")
    for i, name in enumerate(scenes_):
        row = [r for r in results if r["scene"] == name]
        lim = 3.0 if name == "room" else 10.0
        for ax, r in zip(axes[i], row, strict=True):
            s = summary(r)
            im = ax.imshow(
                np.where(r["lit"], r["diff"], np.nan), origin="lower", extent=r["extent"],
                cmap=cmap, vmin=-lim, vmax=lim, interpolation="nearest",
            )  # fmt: skip
            ax.plot(*r["tx"][:2], "k*", ms=10)
            ax.set_title(
                f"{TITLES[name]}, {r['frequency'] / 1e9:g} GHz\nmedian {s['median_db']:+.2f} dB, "
                f"5–95 % [{s['p05_db']:+.1f}, {s['p95_db']:+.1f}] dB",
                fontsize=10,
            )
            ax.set_xlabel("x [m]")
        axes[i][0].set_ylabel("y [m]")
        fig.colorbar(im, ax=list(axes[i]), shrink=0.85, label="rough − flat path gain [dB]")
    fig.suptitle(
        "Radio maps, emscatter rough (one call: radio.compare_rough_flat, default roughness "
        "table) − the scene's own flat ITU materials\n(RadioMapSolver: specular + diffuse + "
        "refraction; every material inside its ITU-R P.2040 band, none extrapolated; grey: "
        "unlit; ★ transmitter)\n" + command,
        fontsize=9,
    )
    return save_figure(fig, path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="coarse cells, few rays (a test)")
    p.add_argument("--out", default=None, help="folder for the PNG and CSV (default: the repo's)")
    p.add_argument("--samples", type=int, default=10_000_000, help="rays per transmitter")
    p.add_argument("--max-depth", type=int, default=3, help="bounces")
    a = p.parse_args(argv)
    if a.samples < 1000 or not 1 <= a.max_depth <= 8:
        p.error(f"--samples ≥ 1000 and --max-depth in [1, 8], got {a.samples}, {a.max_depth}")
    samples, depth = (min(a.samples, 20_000), min(a.max_depth, 2)) if a.quick else (
        a.samples, a.max_depth)  # fmt: skip
    if a.out is None:
        png = ROOT / "docs" / "figures" / "radio_rough_minus_flat_maps.png"
        csv = ROOT / "validation" / "radio" / "rough_minus_flat_maps.csv"
    else:
        png = Path(a.out) / "radio_rough_minus_flat_maps.png"
        csv = Path(a.out) / "rough_minus_flat_maps.csv"
    from emscatter.io import write_csv

    command = (
        "PYTHONPATH=src python validation/radio/rough_minus_flat_maps.py"
        + (" " + " ".join(argv if argv is not None else sys.argv[1:])).rstrip()
    )
    results = []
    for name in SETUP:
        results += run_scene(name, samples, depth, a.quick)
    rows = [summary(r) for r in results]
    cols = list(rows[0])
    write_csv(
        csv, cols, [np.array([r[c] for r in rows]) for c in cols],
        metadata={"samples_per_tx": samples, "max_depth": depth, "quick": a.quick,
                  "command": command, "seed": 1},
        schema="emscatter.validation.radio/rough_minus_flat-1",
    )  # fmt: skip
    figure(results, png, command)
    for r in rows:
        print(
            f"{r['scene']:<22} {r['frequency_ghz']:6g} GHz: median {r['median_db']:+.2f} dB "
            f"[{r['p05_db']:+.2f}, {r['p95_db']:+.2f}], total {r['total_ratio_db']:+.2f} dB, "
            f"{r['cells_lit']} cells, {r['seconds']:.0f} s"
        )
    print(f"  {png}\n  {csv}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
