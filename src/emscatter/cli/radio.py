"""``emscatter radio``: Sionna RT scenes with emscatter materials against Sionna's defaults."""

from __future__ import annotations

import argparse

from .args import Integer, Number, OutputFolder, add_command

SCENES = ("room", "floor_wall", "box")


def _frequencies_ghz(text: str) -> tuple[float, ...]:
    """``'3.5,28,140'`` [GHz] → Hz; each in [1, 1000] GHz."""
    out = []
    for part in text.split(","):
        v = Number(low=1.0, high=1000.0, low_open=False, high_open=False, unit="GHz")(part.strip())
        out.append(v * 1e9)
    if not out:
        raise argparse.ArgumentTypeError("give at least one frequency [GHz], e.g. '3.5,28,140'")
    return tuple(out)


def register(subparsers) -> None:
    r = add_command(
        subparsers,
        "radio",
        help="indoor scenes in Sionna RT: emscatter rough materials vs Sionna's constant-S ones",
        description=(
            "Runs Sionna RT (CPU) on an indoor scene with three material sets: Sionna's ITU "
            "materials with a constant scattering coefficient S = 0.3 and a Lambertian lobe, "
            "emscatter materials without roughness, and emscatter rough materials. Writes path "
            "gain and RMS delay spread per receiver (CSV), radio-map difference images and a "
            "summary against frequency (PNG). --plate runs the large-plate cross-check instead."
        ),
    )
    r.add_argument("--scene", default="room", choices=[*SCENES, "all"], help="which scene(s)")
    r.add_argument(
        "--frequencies-ghz",
        type=_frequencies_ghz,
        default="3.5,28,140",
        metavar="LIST",
        help="comma-separated frequencies [GHz]",
    )
    r.add_argument(
        "--samples",
        type=Integer(low=1000, high=100_000_000),
        default=300_000,
        help="rays per source",
    )
    r.add_argument("--max-depth", type=Integer(low=1, high=8), default=3, help="bounces")
    r.add_argument(
        "--cell-size",
        type=Number(low=0.0, high=10.0, unit="m"),
        default=0.1,
        help="radio-map cell size [m]",
    )
    r.add_argument(
        "--extrapolate",
        action="store_true",
        help=(
            "allow materials outside their ITU-R P.2040 bands (e.g. ITU metal, 1–100 GHz, at "
            "140 GHz) with the documented extrapolation, recorded in the CSV and JSON outputs; "
            "without it such a run is an error before anything is computed"
        ),
    )
    r.add_argument("--quick", action="store_true", help="few rays, coarse maps and tables")
    r.add_argument("--plate", action="store_true", help="run the large-plate cross-check")
    r.add_argument("--out", type=OutputFolder(), default="out/radio", help="output folder")
    r.set_defaults(func=run)


def run(a) -> int:
    from pathlib import Path

    out = Path(a.out)
    if a.plate and a.extrapolate:
        raise ValueError(
            "--extrapolate applies to the indoor scenes, not to --plate (its media are in band)"
        )
    if a.plate:
        from ..radio import demo

        for p in demo.run(out, a.quick):
            print(f"  {p}")
        return 0
    from ..radio import indoor
    from ..radio.tables import TableOptions

    names = SCENES if a.scene == "all" else (a.scene,)
    # Every medium against its ITU-R P.2040 bands before any ray is traced (OutOfBandError,
    # naming medium, frequency and bands, unless --extrapolate).
    extrapolated = indoor.check_bands(names, a.frequencies_ghz, extrapolate=a.extrapolate)
    for e in extrapolated:
        print(
            f"extrapolating {e['medium']!r} ({e['scene']}) to {e['frequency_ghz']:g} GHz, outside "
            "its ITU-R P.2040 bands (recorded in the outputs)"
        )
    kw = {
        "samples": a.samples,
        "cell_size": a.cell_size,
        "max_depth": a.max_depth,
        "extrapolate": a.extrapolate,
    }
    if a.quick:
        kw.update(samples=min(a.samples, 20_000), cell_size=max(a.cell_size, 0.5), max_depth=2)
        kw["table_options"] = TableOptions(n_cos=65, n_cos_spm=9, n_theta=16, n_alpha=13, n_s=32)
    result = indoor.compare(names, a.frequencies_ghz, **kw)
    for p in indoor.write_outputs(result, out):
        print(f"  {p}")
    for s in indoor.summarize(result["rows"]):
        print(
            f"{s['scene']:<10} {s['frequency_ghz']:7g} GHz   rough − flat: median |Δ path gain| "
            f"{s['median_abs_dpg_vs_flat_db']:.2f} dB, |Δ delay spread| "
            f"{s['median_abs_dds_vs_flat_ns']:.2f} ns;   rough − Sionna S=0.3: "
            f"{s['median_abs_dpg_vs_sionna_db']:.2f} dB, {s['median_abs_dds_vs_sionna_ns']:.2f} ns"
        )
    return 0
