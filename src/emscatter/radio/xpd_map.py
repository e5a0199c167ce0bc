"""Cross-polar discrimination (XPD) per radio-map cell: Sionna RT's ``RadioMapSolver`` with the
field arriving in each cell split into its vertical and horizontal components, for a vertically
and a horizontally polarized transmitter.

Sionna's radio map (``PlanarRadioMap.add_paths``) accumulates the full power ``|E|²`` of every ray
tube crossing a cell: it has no receive polarization (``scene.rx_array`` is not read; checked in
sionna-rt 1.x/2.x ``radio_map_solvers``). A ray's field ``E`` is stored as a real 4-vector
``(Re E_θ, Re E_φ, Im E_θ, Im E_φ)`` in the world implicit basis ``(θ̂(k), φ̂(k))`` of its
direction ``k`` (``sionna.rt.utils.implicit_basis_vector``). An isotropic ``"V"`` receiver's
pattern is ``θ̂`` and an ``"H"`` one ``φ̂`` (ITU-R/3GPP slant angles 0 and π/2), and
``θ̂(−k) = θ̂(k)``, so the power the ``V`` port of a dual-polarized isotropic receiver collects is
``|E_θ|²`` and the ``H`` port's ``|E_φ|²``: the same ports as
:func:`emscatter.radio.xpd.path_xpd` reads from PathSolver paths traced with ``"VH"`` arrays. The
radio map used here (:func:`port_map_class`) is Sionna's ``PlanarRadioMap`` that accumulates
these two powers into two maps (same rays, same weights ``Ω/cos θ`` and normalization as
Sionna's, for reflected, refracted, diffuse and diffracted rays alike); their sum is Sionna's own
map to float32 rounding (measured 2e-6 on the plate, 9e-7 in ``simple_street_canyon`` with
diffraction on).

Per cell, with ``P_rt`` the power into receive port ``r`` from transmit polarization ``t``:

    XPD = 10 log10((P_VV + P_HH) / (P_VH + P_HV))   [dB]

(ITU-R P.310-10 §5.1.7, 3GPP TR 38.901 §7.5 step 9; :mod:`emscatter.radio.xpd`). ``+inf`` where a
lit cell receives no cross-polar power (free space and specular bounces on planes that hold both
polarizations: a flat floor's limit), NaN where a cell is unlit. Monte-Carlo noise: a cell's
estimate averages the ray tubes that cross it, so its XPD scatters by ~``4.3 / √n`` dB for ``n``
tubes carrying its cross-polar power.
"""

from __future__ import annotations

import math

import numpy as np

from .xpd import xpd_db

__all__ = [
    "polarized_radio_map",
    "port_map_class",
    "xpd_summary",
    "write_xpd_map",
    "write_xpd_vs_frequency",
    "PORTS",
]

#: Index order of the port maps ``[pol_rx, pol_tx]`` (0 = V, 1 = H).
PORTS = ("V", "H")
_CLASS = None


def port_map_class():
    """Sionna's ``PlanarRadioMap`` with a second map: ``path_gain`` holds the ``V`` (``θ̂``)
    receive-port power, ``path_gain_h`` the ``H`` (``φ̂``) one (module docstring; imports
    Sionna RT)."""
    global _CLASS
    if _CLASS is not None:
        return _CLASS
    import drjit as dr
    import mitsuba as mi
    from sionna.rt.radio_map_solvers.planar_radio_map import PlanarRadioMap

    class PortRadioMap(PlanarRadioMap):
        """Planar radio map with the received field split into its ``θ̂`` and ``φ̂`` parts."""

        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self._h_map = dr.zeros(mi.TensorXf, dr.shape(self._pathgain_map))

        @property
        def path_gain_h(self):
            """``H``-port path gain per cell [linear] (``path_gain``: the ``V`` port)."""
            return self._h_map

        def add_paths(self, e_fields, array_w, *args, **kwargs):
            zero = mi.Float(0.0)
            v = [mi.Vector4f(e.x, zero, e.z, zero) for e in e_fields]
            h = [mi.Vector4f(zero, e.y, zero, e.w) for e in e_fields]
            super().add_paths(v, array_w, *args, **kwargs)
            full, self._pathgain_map = self._pathgain_map, self._h_map
            try:
                super().add_paths(h, array_w, *args, **kwargs)
            finally:
                self._h_map, self._pathgain_map = self._pathgain_map, full

    _CLASS = PortRadioMap
    return _CLASS


def _solve_ports(scene, seed, map_kw):
    """One RadioMapSolver run with :func:`port_map_class` in place of Sionna's planar map:
    ``(V, H)`` receive-port maps (n_tx, ny, nx) [linear] and the cell centres."""
    import sionna.rt as rt
    import sionna.rt.radio_map_solvers.radio_map_solver as rms

    if map_kw.get("measurement_surface") is not None:
        raise ValueError(
            "XPD maps: measurement_surface (mesh radio maps) is not supported; give a planar map "
            "(center, orientation, size, cell_size)"
        )
    if not hasattr(rms, "PlanarRadioMap"):
        raise RuntimeError(
            "XPD maps need sionna.rt.radio_map_solvers.radio_map_solver.PlanarRadioMap "
            "(Sionna RT 1.x/2.x); this Sionna version builds its maps differently"
        )
    cls = port_map_class()
    saved = rms.PlanarRadioMap
    rms.PlanarRadioMap = cls  # the solver builds its map by this module-level name
    try:
        rm = rt.RadioMapSolver()(scene, seed=seed, **map_kw)
    finally:
        rms.PlanarRadioMap = saved
    if not isinstance(rm, cls):
        raise RuntimeError("XPD maps: Sionna's RadioMapSolver did not build the port map")
    v = np.asarray(rm.path_gain.numpy(), dtype=np.float64)
    h = np.asarray(rm.path_gain_h.numpy(), dtype=np.float64)
    return v, h, np.asarray(rm.cell_centers.numpy(), dtype=np.float64)


def polarized_radio_map(scene, *, seed: int = 1, **map_kw) -> dict:
    """Co- and cross-polar radio maps of ``scene`` (module docstring): two RadioMapSolver runs
    (``map_kw``: its settings, points as tuples or Mitsuba points) with one isotropic ``"V"``
    and one ``"H"`` transmit element (the scene's ``tx_array`` restored afterwards). Returns
    ``{"ports": (2, 2, n_tx, ny, nx) [pol_rx, pol_tx] (0 = V, 1 = H) [linear], "co", "cross"
    (n_tx, ny, nx) [linear], "xpd_db" (n_tx, ny, nx) [dB], "lit" (co > 0), "cell_centers"
    (ny, nx, 3) [m]}``. A non-finite power from the solver is an error."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"seed must be an integer, got {seed!r}")
    if not scene.transmitters:
        raise ValueError(
            "the scene has no transmitter: scene.add(sionna.rt.Transmitter(...)) first"
        )
    import mitsuba as mi
    import sionna.rt as rt

    kw = dict(map_kw)
    for key, cls in (("center", mi.Point3f), ("orientation", mi.Point3f), ("size", mi.Point2f),
                     ("cell_size", mi.Point2f)):  # fmt: skip
        if kw.get(key) is not None and not isinstance(kw[key], cls):
            kw[key] = cls(*(float(x) for x in kw[key]))
    saved = scene.tx_array
    ports = []
    try:
        for pol in PORTS:
            scene.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization=pol)
            v, h, centers = _solve_ports(scene, int(seed), kw)
            ports.append((v, h))
    finally:
        if saved is None:  # a scene without arrays yet (Sionna's setter refuses None)
            scene._tx_array = None
        else:
            scene.tx_array = saved
    p = np.stack([np.stack([ports[0][0], ports[1][0]]), np.stack([ports[0][1], ports[1][1]])])
    if not np.all(np.isfinite(p)) or np.any(p < 0):
        raise FloatingPointError(
            f"XPD map: Sionna returned {int(np.sum(~np.isfinite(p)))} non-finite or negative "
            f"port powers of {p.size}; not returned as a result"
        )
    co, cross = p[0, 0] + p[1, 1], p[0, 1] + p[1, 0]
    return {"ports": p, "co": co, "cross": cross, "xpd_db": xpd_db(co, cross), "lit": co > 0,
            "cell_centers": centers}  # fmt: skip


def xpd_summary(xpd, lit=None) -> dict:
    """Median and quartiles [dB] of per-cell XPD over the lit cells (``+inf`` cells count, as
    the largest values; no interpolation between order statistics, so an infinite quartile stays
    ``+inf``), and how many cells: ``{"n", "n_inf", "q25", "median", "q75"}``."""
    x = np.asarray(xpd, dtype=np.float64)
    m = ~np.isnan(x) if lit is None else (np.asarray(lit, dtype=bool) & ~np.isnan(x))
    v = x[m]
    if v.size == 0:
        return {"n": 0, "n_inf": 0, "q25": math.nan, "median": math.nan, "q75": math.nan}
    q = np.quantile(v, [0.25, 0.5, 0.75], method="inverted_cdf")
    return {"n": int(v.size), "n_inf": int(np.isinf(v).sum()), "q25": float(q[0]),
            "median": float(q[1]), "q75": float(q[2])}  # fmt: skip


def _db(x):
    with np.errstate(divide="ignore"):
        return np.where(x > 0, 10.0 * np.log10(np.where(x > 0, x, 1.0)), -np.inf)


def write_xpd_map(result: dict, out_dir, stem: str, *, title: str = "", tx_xy=None) -> list:
    """``<stem>_xpd_map.csv`` (per cell of the first transmitter: x, y, z [m]; flat and rough
        co- and cross-polar path gain [dB, −inf where none] and XPD [dB, +inf without cross-polar
        power, nan unlit]; rough − flat XPD [dB]; metadata: median and quartiles over the cells lit
    in both) and ``<stem>_xpd_map.png`` (flat XPD, rough XPD,
        rough − flat), atomic writes, from :func:`~emscatter.radio.roughening.compare_rough_flat`
        run with ``xpd_map=True``. Returns the paths written."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import save_figure, write_csv

    xm = result["xpd_map"]
    fl, ro = xm["flat"], xm["rough"]
    both = fl["lit"][0] & ro["lit"][0]  # summaries over the same cells
    c = fl["cell_centers"]
    out = Path(out_dir)
    meta = {"frequency_hz": result["frequency"], "reference": result["reference"],
            "flat_summary": xpd_summary(fl["xpd_db"][0], both),
            "rough_summary": xpd_summary(ro["xpd_db"][0], both),
            **{k: v for k, v in result["settings"].items() if v is not None}}  # fmt: skip
    diff = xm["difference_db"][0]
    cols = [
        c[..., 0],
        c[..., 1],
        c[..., 2],
        _db(fl["co"][0]),
        _db(fl["cross"][0]),
        fl["xpd_db"][0],
        _db(ro["co"][0]),
        _db(ro["cross"][0]),
        ro["xpd_db"][0],
        diff,
    ]
    written = [write_csv(
        out / f"{stem}_xpd_map.csv",
        ["x_m", "y_m", "z_m", "flat_co_db", "flat_cross_db", "flat_xpd_db", "rough_co_db",
         "rough_cross_db", "rough_xpd_db", "rough_minus_flat_xpd_db"],
        [np.asarray(x).ravel() for x in cols], metadata=meta,
        schema="emscatter.radio.compare/xpd-map-1",
    )]  # fmt: skip
    hx = 0.5 * (c[0, 1, 0] - c[0, 0, 0]) if c.shape[1] > 1 else 0.5
    hy = 0.5 * (c[1, 0, 1] - c[0, 0, 1]) if c.shape[0] > 1 else 0.5
    ext = (c[0, 0, 0] - hx, c[0, -1, 0] + hx, c[0, 0, 1] - hy, c[-1, 0, 1] + hy)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    imgs = [np.minimum(x, 60.0) for x in (fl["xpd_db"][0], ro["xpd_db"][0])]  # nan stays nan
    d = diff[np.isfinite(diff)]
    lim = float(np.clip(np.percentile(np.abs(d), 95), 1.0, 40.0)) if d.size else 10.0
    panels = ((imgs[0], f"{result['reference']}: XPD [dB] (capped at 60)", "magma", (0, 60)),
              (imgs[1], "emscatter rough: XPD [dB]", "magma", (0, 60)),
              (np.clip(diff, -60, 60), "rough − flat XPD [dB]", "RdBu_r", (-lim, lim)))  # fmt: skip
    for ax, (img, name, cmap, (vmin, vmax)) in zip(axes, panels, strict=True):
        im = ax.imshow(img, origin="lower", extent=ext, cmap=cmap, vmin=vmin, vmax=vmax)
        if tx_xy is not None:
            ax.plot(*tx_xy, "c*", ms=10)
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("x [m]")
        fig.colorbar(im, ax=ax, shrink=0.8)
    axes[0].set_ylabel("y [m]")
    sf, sr = meta["flat_summary"], meta["rough_summary"]
    fig.suptitle(
        f"{title} {result['frequency'] / 1e9:g} GHz: XPD per cell at z = {c[0, 0, 2]:g} m "
        f"(median flat {sf['median']:.1f} dB, rough {sr['median']:.1f} dB)".strip()
    )
    written.append(save_figure(fig, out / f"{stem}_xpd_map.png"))
    return written


def write_xpd_vs_frequency(rows: list, out_dir, stem: str, *, title: str = "") -> list:
    """``<stem>_xpd_vs_frequency.csv`` and ``.png``: per frequency, the median and quartiles of
    per-cell XPD [dB] flat and rough, over the same cells (``rows``: ``{"frequency_hz",
    "flat": xpd_summary, "rough": xpd_summary}``), atomic writes. Returns the paths written."""
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import save_figure, write_csv

    out = Path(out_dir)
    f = np.array([r["frequency_hz"] for r in rows], dtype=float)
    keys = ("n", "q25", "median", "q75")
    cols = [f / 1e9] + [np.array([r[s][k] for r in rows], dtype=float)
                        for s in ("flat", "rough") for k in keys]  # fmt: skip
    header = ["frequency_ghz"] + [f"{s}_{k}" for s in ("flat", "rough") for k in
                                  ("cells", "q25_db", "median_db", "q75_db")]  # fmt: skip
    written = [write_csv(out / f"{stem}_xpd_vs_frequency.csv", header, cols,
                         schema="emscatter.radio.compare/xpd-frequency-1")]  # fmt: skip
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for s, colour, dx in (("flat", "tab:blue", 0.97), ("rough", "tab:red", 1.03)):
        med = np.array([r[s]["median"] for r in rows])
        lo = np.array([r[s]["q25"] for r in rows])
        hi = np.array([r[s]["q75"] for r in rows])
        cap = 80.0  # +inf quartiles (no cross-polar power) drawn at the top of the axis
        med, lo, hi = (np.minimum(x, cap) for x in (med, lo, hi))
        ax.errorbar(f / 1e9 * dx, med, yerr=[med - lo, hi - med], fmt="o-", color=colour,
                    capsize=4, label=f"{s} walls (median, quartiles)")  # fmt: skip
    ax.set_xscale("log")
    ax.minorticks_off()
    ax.set_xticks(f / 1e9, [f"{x:g}" for x in f / 1e9])
    ax.set_xlabel("frequency [GHz]")
    ax.set_ylabel("XPD per radio-map cell [dB] (cells lit in both)")
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(f"{title} XPD per cell: flat vs emscatter rough".strip(), fontsize=10)
    written.append(save_figure(fig, out / f"{stem}_xpd_vs_frequency.png"))
    return written
