"""Rough minus flat in one call: path gains and radio maps of a Sionna scene with its own
materials and with emscatter's rough equivalents (:func:`.roughen.roughen`).

::

    res = radio.compare_rough_flat(scene, mapping={"brick": (0.8e-3, 8e-3)},
                                   radio_map={"cell_size": (2, 2), "samples_per_tx": 200_000})
    res["path_gain"]["difference_db"]        # (n_rx, n_tx) rough − flat [dB]
    res["radio_map"]["difference_db"]        # (n_tx, ny, nx) [dB], NaN where a map is unlit

The scene is solved twice with the same solver settings and seed — first as given
(``reference="original"``: the user's own materials) or with emscatter's flat equivalents
(``reference="flat"``: same media and slabs, no roughness; equal to Sionna's ITU slab), then
roughened — and is given back with its own materials, also when a solve fails.

Path gain per receiver and transmitter is ``Σ|a|²`` over paths, in float64 and summed in a fixed
(sorted) order, averaged over antenna pairs (Sionna's ``PathSolver(deterministic=True)``, so a
seed gives the same numbers). A radio map's path gain is Sionna's per cell. Differences in dB
are ``10 log10(rough / flat)`` where both are > 0 and NaN where either is 0 (no path, or an
unlit cell: ``"lit"`` says which cells have both); nothing else is NaN — a non-finite power from
the solver is an error.
"""

from __future__ import annotations

import math

import numpy as np

from .roughen import flatten, plan, roughen, roughened

__all__ = ["compare_rough_flat", "PATH_DEFAULTS", "MAP_DEFAULTS", "write_comparison"]

#: PathSolver settings used unless ``paths=`` says otherwise.
PATH_DEFAULTS = {
    "max_depth": 3,
    "samples_per_src": 100_000,
    "diffuse_reflection": True,
    "refraction": True,
}
#: RadioMapSolver settings used unless ``radio_map=`` says otherwise.
MAP_DEFAULTS = {
    "cell_size": (1.0, 1.0),
    "samples_per_tx": 100_000,
    "max_depth": 3,
    "diffuse_reflection": True,
    "refraction": True,
}
_POINT3 = ("center", "orientation")
_POINT2 = ("size", "cell_size")


def _settings(value, defaults, what):
    if value is None or value is False:
        return None
    if value is True:
        return dict(defaults)
    if isinstance(value, dict):
        if "seed" in value:
            raise ValueError(
                f"{what}: give the seed as compare_rough_flat(seed=...), not in {what}"
            )
        return {**defaults, **value}
    raise TypeError(f"{what} must be True, False/None or a dict of solver settings, got {value!r}")


def _mi_args(kw: dict) -> dict:
    import mitsuba as mi

    out = dict(kw)
    for key in _POINT3:
        if out.get(key) is not None and not isinstance(out[key], mi.Point3f):
            out[key] = mi.Point3f(*(float(x) for x in out[key]))
    for key in _POINT2:
        if out.get(key) is not None and not isinstance(out[key], mi.Point2f):
            out[key] = mi.Point2f(*(float(x) for x in out[key]))
    return out


def _finite(x, what):
    if not np.all(np.isfinite(x)):
        raise FloatingPointError(
            f"{what}: Sionna returned non-finite powers ({int(np.sum(~np.isfinite(x)))} of "
            f"{x.size}); not returned as a result"
        )
    return x


def path_gains(paths) -> np.ndarray:
    """``Σ|a|²`` per (receiver, transmitter) [linear], float64, summed in sorted order and
    averaged over antenna pairs (``synthetic_array`` or not)."""
    re, im = (np.asarray(x.numpy(), dtype=np.float64) for x in paths.a)
    p = re**2 + im**2
    if p.ndim == 5:  # [rx, rx_ant, tx, tx_ant, path]
        p = np.sort(p, axis=-1).sum(axis=-1).mean(axis=(1, 3))
    else:  # [rx, tx, path] (one antenna each)
        p = np.sort(p, axis=-1).sum(axis=-1)
    return _finite(p, "path gain")


def _dual_pol_xpd(scene, path_kw, seed):
    """Link XPD [dB] (n_rx, n_tx) with the scene's arrays swapped for one isotropic
    dual-polarized (``"VH"``) element each, restored afterwards (:mod:`..xpd`)."""
    import sionna.rt as rt

    from ..xpd import path_xpd

    saved = (scene.tx_array, scene.rx_array)
    try:
        dual = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
        scene.tx_array = scene.rx_array = dual
        paths = rt.PathSolver(deterministic=True)(scene, seed=seed, **path_kw)
        return path_xpd(paths)["link_db"]
    finally:
        scene.tx_array, scene.rx_array = saved


def _solve(scene, path_kw, map_kw, seed, xpd=False, xpd_map=False):
    import sionna.rt as rt

    out = {}
    if path_kw is not None:
        paths = rt.PathSolver(deterministic=True)(scene, seed=seed, **path_kw)
        out["path_gain"] = path_gains(paths)
        if xpd:
            out["xpd"] = _dual_pol_xpd(scene, path_kw, seed)
    if map_kw is not None:
        rm = rt.RadioMapSolver()(scene, seed=seed, **_mi_args(map_kw))
        out["radio_map"] = _finite(np.asarray(rm.path_gain.numpy(), dtype=np.float64), "radio map")
        out["cell_centers"] = np.asarray(rm.cell_centers.numpy(), dtype=np.float64)
        if xpd_map:
            from ..xpd_map import polarized_radio_map

            out["xpd_map"] = polarized_radio_map(scene, seed=seed, **map_kw)
    return out


def _db_difference(rough, flat):
    lit = (rough > 0) & (flat > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(
            lit, 10.0 * np.log10(np.where(lit, rough, 1.0) / np.where(lit, flat, 1.0)), np.nan
        )
    return d, lit


def compare_rough_flat(
    scene,
    roughness=None,
    mapping=None,
    *,
    paths=True,
    radio_map=None,
    reference: str = "original",
    seed: int = 1,
    xpd: bool = False,
    xpd_map: bool = False,
    **roughen_kw,
) -> dict:
    """Path gains (``paths``: True, False or PathSolver settings over :data:`PATH_DEFAULTS`)
    and radio maps (``radio_map``: None, True or RadioMapSolver settings over
    :data:`MAP_DEFAULTS`; points as tuples) of ``scene`` flat and rough (module docstring).

    ``roughness``, ``mapping`` and ``roughen_kw`` (``frequencies``, ``extrapolate``,
    ``method``, ``table_options``, …) go to :func:`~emscatter.radio.roughening.roughen.roughen`; the
    scene needs its transmitters (and receivers, for path gains) added. Returns ``{"frequency",
    "reference", "transmitters", "receivers", "materials" (one row per object), "settings",
    "path_gain": {"flat", "rough", "difference_db", "lit"}, "radio_map": {..., "cell_centers"}}``
    (powers linear; the radio map ``(n_tx, ny, nx)``, cell centres ``(ny, nx, 3)`` [m]).

    ``xpd=True`` (with ``paths``) adds ``"xpd": {"flat", "rough"}``: the cross-polar
    discrimination per link (n_rx, n_tx) [dB] (:func:`emscatter.radio.xpd.path_xpd`: co- over
    cross-polar power of all paths, both transmit polarizations), from one more PathSolver run
    per state with the scene's arrays swapped for one isotropic dual-polarized element
    each (restored afterwards); ``+inf`` where no cross-polar power arrives, NaN where no
    path does.

    ``xpd_map=True`` (with ``radio_map``) adds ``"xpd_map": {"flat", "rough"}``, each
    :func:`emscatter.radio.xpd_map.polarized_radio_map` (co- and cross-polar maps and XPD per
    cell [dB], from two more RadioMapSolver runs per state: a V and an H isotropic
    transmitter), and ``"difference_db"``: rough − flat XPD per cell [dB], NaN where either is
    unlit or both are ``+inf`` (``−inf`` where only the flat cell has no cross-polar power)."""
    if reference not in ("original", "flat"):
        raise ValueError(f"reference must be 'original' or 'flat', got {reference!r}")
    if "flat" in roughen_kw:
        raise TypeError("compare_rough_flat: use reference='flat', not flat=")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"seed must be an integer, got {seed!r}")
    path_kw = _settings(paths, PATH_DEFAULTS, "paths")
    map_kw = _settings(radio_map, MAP_DEFAULTS, "radio_map")
    if xpd and path_kw is None:
        raise ValueError("xpd=True needs path gains: give paths=True (or PathSolver settings)")
    if xpd_map and map_kw is None:
        raise ValueError(
            "xpd_map=True needs a radio map: give radio_map=True (or RadioMapSolver settings)"
        )
    if path_kw is None and map_kw is None:
        raise ValueError("nothing to compare: give paths=True and/or radio_map=True (or settings)")
    if not scene.transmitters:
        raise ValueError(
            "the scene has no transmitter: scene.add(sionna.rt.Transmitter(...)) first"
        )
    if path_kw is not None and not scene.receivers:
        raise ValueError(
            "paths=...: the scene has no receiver (scene.add(sionna.rt.Receiver(...))), or pass "
            "paths=False for radio maps only"
        )
    # everything checked (mapping, media, bands) before the first ray
    plan(
        scene, roughness, mapping, frequencies=roughen_kw.get("frequencies"),
        extrapolate=roughen_kw.get("extrapolate", False),
    )  # fmt: skip
    if roughened(scene) is not None:
        flatten(scene)
    try:
        if reference == "flat":
            roughen(scene, roughness, mapping, flat=True, **roughen_kw)
        flat = _solve(scene, path_kw, map_kw, seed, xpd, xpd_map)
        handle = roughen(scene, roughness, mapping, **roughen_kw)
        rough = _solve(scene, path_kw, map_kw, seed, xpd, xpd_map)
        rows = handle.rows()
    finally:
        if roughened(scene) is not None:
            flatten(scene)
    out = {
        "frequency": float(np.asarray(scene.frequency.numpy()).ravel()[0]),
        "reference": reference,
        "transmitters": list(scene.transmitters),
        "receivers": list(scene.receivers),
        "materials": rows,
        "settings": {"paths": path_kw, "radio_map": map_kw, "seed": int(seed)},
    }
    for key in ("path_gain", "radio_map"):
        if key in flat:
            d, lit = _db_difference(rough[key], flat[key])
            out[key] = {"flat": flat[key], "rough": rough[key], "difference_db": d, "lit": lit}
    if "radio_map" in out:
        out["radio_map"]["cell_centers"] = flat["cell_centers"]
    if xpd:
        out["xpd"] = {"flat": flat["xpd"], "rough": rough["xpd"]}
    if xpd_map:
        fx, rx = flat["xpd_map"]["xpd_db"], rough["xpd_map"]["xpd_db"]
        with np.errstate(invalid="ignore"):
            d = rx - fx  # inf − inf is NaN: both without cross-polar power
        out["xpd_map"] = {"flat": flat["xpd_map"], "rough": rough["xpd_map"], "difference_db": d}
    return out


def _db(x):
    with np.errstate(divide="ignore"):
        return np.where(x > 0, 10.0 * np.log10(np.where(x > 0, x, 1.0)), -np.inf)


def write_comparison(result: dict, out_dir, stem: str, *, title: str = "", tx_xy=None) -> list:
    """``<stem>_map.csv`` (per cell: x, y, z [m], flat / rough path gain [dB, −inf unlit],
    rough − flat [dB, nan where either is unlit]), ``<stem>_paths.csv`` (per receiver and
    transmitter; with ``flat_xpd_db`` / ``rough_xpd_db`` when compared with ``xpd=True``),
    ``<stem>_materials.csv`` and ``<stem>_map.png`` (flat, rough, rough − flat;
    first transmitter); atomic writes. Returns the paths written."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...io import save_figure, write_csv

    out = Path(out_dir)
    written = []
    meta = {"frequency_hz": result["frequency"], "reference": result["reference"],
            **{k: v for k, v in result["settings"].items() if v is not None}}  # fmt: skip
    rows = result["materials"]
    cols = list(rows[0])
    written.append(write_csv(out / f"{stem}_materials.csv", cols,
                             [np.array([r[c] for r in rows]) for c in cols]))  # fmt: skip
    if "path_gain" in result:
        pg = result["path_gain"]
        rx, tx = np.meshgrid(result["receivers"], result["transmitters"], indexing="ij")
        x = result.get("xpd")
        extra = (["flat_xpd_db", "rough_xpd_db"], [x["flat"].ravel(), x["rough"].ravel()]) if x \
            else ([], [])  # fmt: skip
        written.append(write_csv(
            out / f"{stem}_paths.csv",
            ["receiver", "transmitter", "flat_db", "rough_db", "rough_minus_flat_db", *extra[0]],
            [rx.ravel(), tx.ravel(), _db(pg["flat"]).ravel(), _db(pg["rough"]).ravel(),
             pg["difference_db"].ravel(), *extra[1]],
            metadata=meta, schema="emscatter.radio.compare/paths-1",
        ))  # fmt: skip
    if "radio_map" in result:
        rm = result["radio_map"]
        c = rm["cell_centers"]
        flat, rough, diff = (_db(rm["flat"][0]), _db(rm["rough"][0]), rm["difference_db"][0])
        written.append(write_csv(
            out / f"{stem}_map.csv",
            ["x_m", "y_m", "z_m", "flat_db", "rough_db", "rough_minus_flat_db"],
            [c[..., 0].ravel(), c[..., 1].ravel(), c[..., 2].ravel(), flat.ravel(),
             rough.ravel(), diff.ravel()],
            metadata=meta, schema="emscatter.radio.compare/map-1",
        ))  # fmt: skip
        hx = 0.5 * (c[0, 1, 0] - c[0, 0, 0]) if c.shape[1] > 1 else 0.5
        hy = 0.5 * (c[1, 0, 1] - c[0, 0, 1]) if c.shape[0] > 1 else 0.5
        ext = (c[0, 0, 0] - hx, c[0, -1, 0] + hx, c[0, 0, 1] - hy, c[-1, 0, 1] + hy)
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
        finite = np.concatenate([flat[np.isfinite(flat)], rough[np.isfinite(rough)]])
        lo, hi = np.percentile(finite, [2, 100]) if finite.size else (-150.0, -50.0)
        d = diff[np.isfinite(diff)]
        lim = float(np.clip(np.percentile(np.abs(d), 95), 1.0, 20.0)) if d.size else 6.0
        panels = (
            (np.where(np.isfinite(flat), flat, np.nan), f"{result['reference']} [dB]", "viridis",
             (lo, hi)),
            (np.where(np.isfinite(rough), rough, np.nan), "emscatter rough [dB]", "viridis",
             (lo, hi)),
            (diff, "rough − flat [dB]", "RdBu_r", (-lim, lim)),
        )  # fmt: skip
        for ax, (img, name, cmap, (vmin, vmax)) in zip(axes, panels, strict=True):
            im = ax.imshow(img, origin="lower", extent=ext, cmap=cmap, vmin=vmin, vmax=vmax)
            if tx_xy is not None:
                ax.plot(*tx_xy, "r*", ms=10)
            ax.set_title(name, fontsize=10)
            ax.set_xlabel("x [m]")
            fig.colorbar(im, ax=ax, shrink=0.8)
        axes[0].set_ylabel("y [m]")
        med = float(np.median(d)) if d.size else math.nan
        fig.suptitle(
            f"{title} {result['frequency'] / 1e9:g} GHz: path gain at z = {c[0, 0, 2]:g} m "
            f"(median rough − flat {med:+.2f} dB over {d.size} cells lit in both)".strip()
        )
        written.append(save_figure(fig, out / f"{stem}_map.png"))
    return written
