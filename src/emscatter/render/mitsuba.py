"""An emscatter BRDF table as a Mitsuba 3 BSDF (plugin ``"emscatter"``), delta lobe included.

Usage, after ``mi.set_variant(...)`` with an LLVM variant (tested here; the CUDA ones are not,
and a scalar one would call Python once per ray)::

    import mitsuba as mi
    from emscatter.render import mitsuba as em_mi
    mi.set_variant("llvm_ad_spectral")
    bsdf = mi.load_dict(em_mi.bsdf_dict(table))       # registers the plugin and the table
    # or in a scene dict / XML (register_table registers the plugin for the current variant):
    #     {"type": "emscatter", "table": em_mi.register_table(table)}
    #     <bsdf type="emscatter"><string name="table" value="KEY"/></bsdf>

Scene-dict / XML parameters: ``table`` (a key from :func:`register_table`), ``coherent``
(bool, default true: include the coherent delta lobe), ``sampling_resolution`` (int, 64), and
the seed's ch. 4 porosity applied to the table at load time (:mod:`emscatter.brdf.porosity`,
:func:`~emscatter.brdf.porosity.from_plugin_params`): ``porosity``, ``pore_shape``,
``pore_slope``, ``diffuse_albedo``, ``specular_albedo``, ``wetness``, ``pollution_time``,
``pollution_fill_time``, ``pollution_albedo`` (floats).

What it does (numpy preparation in :mod:`emscatter.render.plugin_data`):

* ``eval``: ``f_r cosθo`` with ``f_r`` from a Dr.Jit ``Texture3f`` with linear filtering over the
  table's own (θi, θo, Δφ) nodes — the same multilinear interpolant as
  :meth:`BrdfTable.evaluate`; non-uniform axes (adaptive ``tol=`` grids) are located by a
  binary search over their nodes, so nothing is resampled; spectral variants interpolate
  linearly between the table's wavelengths (constant beyond them); RGB variants use the
  table's sRGB conversion.
* ``sample`` / ``pdf``: a piecewise-constant marginal/conditional distribution of half-vectors
  (alias tables, :mod:`emscatter.render.sampling`; a mixture of the neighbouring incidence
  nodes' distributions between them) built from ``f_r cosθo``; the pdf is exactly that of the
  samples drawn, and ``sample`` returns ``pdf(wo)`` itself (same code path: equal bitwise; 0,
  with weight 0, below the horizon).
* the coherent part ``R_coh(θi, λ)`` is a second component of the same BSDF
  (``DeltaReflection``, component 1; the glossy table is component 0), sampled with probability
  ``R_coh / (R_coh + albedo)`` — a ``blendbsdf`` of a delta and a glossy lobe is biased.

One-sided like Mitsuba's ``measured``: black from below (wrap it in ``twosided`` if needed).
Polarized variants (``*_polarized``) take a :class:`~emscatter.brdf.mueller.MuellerTable` and
return Mueller matrices in Mitsuba's Stokes frames (:mod:`emscatter.render.polarized`); a
MuellerTable in an unpolarized variant renders its ``M₀₀`` (the unpolarized table).
Dr.Jit variants are per process: render in a process
that does not also run Sionna RT.
"""

from __future__ import annotations

import itertools
import math
import sys
import weakref

import numpy as np

from ..brdf.mueller import MuellerTable
from .mitsuba_sampling import glossy_sampling
from .plugin_data import Axis, PluginData, prepare

__all__ = [
    "PLUGIN_NAME",
    "bsdf_dict",
    "channels_of_variant",
    "register",
    "register_table",
    "unregister_table",
]

PLUGIN_NAME = "emscatter"
_TABLES: dict[str, object] = {}
_PREPARED: dict[tuple, PluginData] = {}
_CLASSES: dict[str, type] = {}
_REGISTERED: set[tuple[str, str]] = set()
_COUNTER = itertools.count()


def _mitsuba():
    try:
        import mitsuba as mi
    except ImportError as exc:  # pragma: no cover - mitsuba is installed with emscatter[render]
        raise ImportError(
            "the Mitsuba plugin needs mitsuba (pip install 'emscatter[render]')"
        ) from exc
    if mi.variant() is None:
        raise RuntimeError("set a Mitsuba variant first, e.g. mitsuba.set_variant('llvm_ad_rgb')")
    return mi


def channels_of_variant(variant: str) -> str:
    """``"spectral"``, ``"rgb"`` or ``"mono"`` for a Mitsuba variant name (``*_polarized``:
    the colour representation under the Mueller matrices)."""
    name = variant.removesuffix("_polarized")
    for kind in ("spectral", "rgb", "mono"):
        if name.endswith(kind):
            return kind
    raise ValueError(f"unknown Mitsuba variant {variant!r}")


def register_table(table, key: str | None = None) -> str:
    """Make ``table`` (BrdfTable or BrdfFunction) available to scenes as ``{"table": key}``
    (in this process; the registry keeps a reference until :func:`unregister_table`).

    With a Mitsuba variant set it also registers the plugin for that variant (:func:`register`),
    so ``{"type": "emscatter", "table": register_table(t)}`` loads as written; a variant set
    later needs :func:`register` (or :func:`bsdf_dict`) once in it."""
    if not (
        isinstance(table, MuellerTable)
        or hasattr(table, "evaluate")
        or callable(getattr(table, "_fr", None))
    ):
        raise TypeError(
            f"table must be a BrdfTable, BrdfFunction or MuellerTable, got {type(table).__name__}"
        )
    if key is None:
        key = f"emscatter-table-{next(_COUNTER)}"
    if not isinstance(key, str) or not key:
        raise ValueError(f"key must be a non-empty string, got {key!r}")
    if _TABLES.get(key) is not table:
        _TABLES[key] = table
        for k in [k for k in _PREPARED if k[0] == key]:
            del _PREPARED[k]
    mi = sys.modules.get("mitsuba")  # only where the user already imported Mitsuba
    if mi is not None and mi.variant() is not None:
        register()
    return key


def unregister_table(key: str) -> None:
    """Drop a registered table and its prepared lookups (scenes already loaded keep theirs)."""
    if key not in _TABLES:
        raise ValueError(f"no table registered as {key!r}")
    del _TABLES[key]
    for k in [k for k in _PREPARED if k[0] == key]:
        del _PREPARED[k]


def register(name: str = PLUGIN_NAME) -> None:
    """Register the plugin under ``name`` for the current Mitsuba variant (idempotent)."""
    mi = _mitsuba()
    variant = mi.variant()
    if (variant, name) in _REGISTERED:
        return
    cls = _bsdf_class(mi)
    mi.register_bsdf(name, lambda props: cls(props))
    _REGISTERED.add((variant, name))


def bsdf_dict(table, *, coherent: bool = True, sampling_resolution: int = 64) -> dict:
    """A ``mi.load_dict`` entry for ``table`` (registers the plugin and the table)."""
    register()
    key = _key_of(table)
    return {
        "type": PLUGIN_NAME,
        "table": key,
        "coherent": bool(coherent),
        "sampling_resolution": int(sampling_resolution),
    }


_KEYS = weakref.WeakKeyDictionary()


def _key_of(table) -> str:
    try:
        key = _KEYS.get(table)
    except TypeError:
        key = None
    if key is None or _TABLES.get(key) is not table:
        key = register_table(table)
        try:
            _KEYS[table] = key
        except TypeError:
            pass
    return key


def _prepared(key: str, channels: str, resolution: int) -> PluginData:
    if key not in _TABLES:
        known = ", ".join(sorted(_TABLES)) or "none"
        raise ValueError(
            f"emscatter plugin: no table registered as {key!r} (registered: {known}); call "
            "emscatter.render.mitsuba.register_table(table) in this process first"
        )
    cache_key = (key, channels, resolution)
    if cache_key not in _PREPARED:
        t = _TABLES[key]
        t = t.table if isinstance(t, MuellerTable) else t  # s0: the unpolarized table
        _PREPARED[cache_key] = prepare(t, channels, sampling_resolution=resolution)
    return _PREPARED[cache_key]


def _porous_key(key: str, props) -> str:
    """``key``, or the key of its porous transform when the porosity parameters are given."""
    from ..brdf.porosity import PLUGIN_PARAMS, from_plugin_params

    params = {n: float(props.get(n)) for n in PLUGIN_PARAMS if n in props}
    if not params or key not in _TABLES:
        return key
    derived = f"{key}|porosity{sorted(params.items())}"
    if derived not in _TABLES:
        _TABLES[derived] = from_plugin_params(_TABLES[key], params)
    return derived


def _prepared_mueller(key: str, channels: str):
    """``(flat Mueller array, n_channels, wavelengths [nm] or None, coherent channels or
    None)`` for the polarized class (the delta lobe's matrices passed with the glossy ones)."""
    from .polarized import coherent_channels, mueller_channels

    cache_key = (key, channels, "mueller")
    if cache_key not in _PREPARED:
        t = _TABLES[key]
        arr = mueller_channels(t, channels)
        lam = None if channels != "spectral" else [float(x) * 1e9 for x in t.table.wavelengths]
        _PREPARED[cache_key] = (arr, arr.shape[-2], lam, coherent_channels(t, channels))
    return _PREPARED[cache_key]


def _bsdf_class(mi):
    variant = mi.variant()
    if variant in _CLASSES:
        return _CLASSES[variant]
    import drjit as dr

    channels = channels_of_variant(variant)
    linear, clamp = dr.FilterMode.Linear, dr.WrapMode.Clamp
    glossy = mi.BSDFFlags.GlossyReflection
    delta = mi.BSDFFlags.DeltaReflection
    front = mi.BSDFFlags.FrontSide

    def texture(cls, array):
        return cls(mi.TensorXf(array), use_accel=False, filter_mode=linear, wrap_mode=clamp)

    nodes_of: dict[tuple, object] = {}  # Dr.Jit copies of non-uniform axes, per axis

    def dr_nodes(axis, periodic):
        key = (axis.points, periodic)
        if key not in nodes_of:
            pts = list(axis.points)
            nodes_of[key] = mi.Float(pts + [pts[0] + 2 * math.pi] if periodic else pts)
        return nodes_of[key]

    def position(x, axis):
        """Fractional node index of angle ``x`` on a clamped axis, in ``[0, size − 1]``:
        the uniform formula, or a binary search over non-uniform nodes (same multilinear
        interpolant as :meth:`BrdfTable.evaluate`)."""
        n = axis.size
        if n == 1:
            return mi.Float(0.0)
        if axis.uniform:
            return dr.clip((x - axis.start) * (1.0 / axis.step), 0.0, n - 1.0)
        nodes = dr_nodes(axis, False)
        xc = dr.clip(x, axis.points[0], axis.points[-1])
        i1 = dr.binary_search(1, n - 1, lambda i: dr.gather(mi.Float, nodes, i) <= xc)
        i0 = i1 - 1
        a0, a1 = dr.gather(mi.Float, nodes, i0), dr.gather(mi.Float, nodes, i1)
        return mi.Float(i0) + dr.clip((xc - a0) / (a1 - a0), 0.0, 1.0)

    def periodic_position(x, axis):
        """``(i0, t)`` of azimuth ``x`` ∈ [0, 2π) on a periodic axis: interval ``i0`` (from
        node ``i0`` to ``i0 + 1``, node ``size`` being node 0 at +2π) and the weight of its
        upper end."""
        n = axis.size
        if axis.uniform:  # start 0, step 2π/n (plugin_data makes other axes non-uniform)
            a = x * (1.0 / axis.step)
            a0f = dr.floor(a)
            return dr.minimum(mi.UInt32(a0f), n - 1), dr.clip(a - a0f, 0.0, 1.0)
        nodes = dr_nodes(axis, True)
        xw = dr.select(x < axis.points[0], x + 2 * math.pi, x)
        i1 = dr.binary_search(1, n, lambda i: dr.gather(mi.Float, nodes, i) <= xw)
        i0 = i1 - 1
        a0, a1 = dr.gather(mi.Float, nodes, i0), dr.gather(mi.Float, nodes, i1)
        return i0, dr.clip((xw - a0) / (a1 - a0), 0.0, 1.0)

    def coord(x, axis):
        """Texture coordinate of angle ``x`` (texel centres at the nodes)."""
        return (position(x, axis) + 0.5) * (1.0 / axis.size)

    def elevation(w):
        """θ [rad], accurate near the pole (as Mitsuba's ``measured``)."""
        return 2.0 * dr.safe_asin(
            0.5 * dr.sqrt(dr.square(w.x) + dr.square(w.y) + dr.square(w.z - 1))
        )

    sampler = glossy_sampling(mi, dr, position, elevation)

    class EmscatterBSDF(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            if "table" not in props:
                raise ValueError(
                    "emscatter plugin: give 'table' (a key from "
                    "emscatter.render.mitsuba.register_table)"
                )
            res = props.get("sampling_resolution", 64)
            self._key = _porous_key(str(props.get("table")), props)
            data = _prepared(str(self._key), channels, int(res))
            self._data = data
            self._use_delta = bool(props.get("coherent", True)) and data.has_coherent
            # Dr.Jit texture (linear filtering) for isotropic tables with ≤ 4 channels; explicit
            # multilinear gathers for anisotropic (4-D) and many-wavelength spectral tables
            self._gather_spectral = data.channels == "spectral" and data.n_channels > 4
            if data.isotropic and not self._gather_spectral:
                self._tex = texture(mi.Texture3f, data.values)
            else:
                self._flat = mi.Float(data.values.ravel())
            if data.isotropic:
                self._coh = texture(mi.Texture1f, data.coherent)
                self._pdelta = texture(mi.Texture1f, data.delta_probability[:, None])
            else:
                # rows φi, periodic: the first row repeated at 2π closes the circle
                def periodic(a):
                    return np.concatenate([a, a[:1]], axis=0)

                self._coh = texture(mi.Texture2f, periodic(data.coherent))
                self._pdelta = texture(mi.Texture2f, periodic(data.delta_probability[..., None]))
            smp = data.sampler
            self._n = smp.resolution
            self._s_theta = Axis.of(smp.theta_i)
            self._s_phi = (
                None if smp.phi_i is None else (smp.phi_i.size, 2 * math.pi / smp.phi_i.size)
            )
            self._dens = mi.Float(smp.density.ravel())
            self._mprob = mi.Float(smp.marginal_prob.ravel())
            self._malias = mi.UInt32(smp.marginal_alias.ravel().astype(np.uint32))
            self._cprob = mi.Float(smp.conditional_prob.ravel())
            self._calias = mi.UInt32(smp.conditional_alias.ravel().astype(np.uint32))
            if data.channels == "spectral":
                lam = [float(x) for x in data.wavelengths_nm]
                self._lam = lam
                self._inv = [1.0 / (b - a) for a, b in itertools.pairwise(lam)]
            comps = [glossy | front]
            if self._use_delta:
                comps.append(delta | front)
            self.m_components = comps
            flags = comps[0]
            for c in comps[1:]:
                flags = flags | c
            self.m_flags = flags

        # ---------------------------------------------------------------- lookups
        def _to_spectrum(self, chans, si):
            if channels == "rgb":
                return mi.Spectrum(chans[0], chans[1], chans[2])
            if channels == "mono":
                return mi.Spectrum(chans[0])
            lam, inv = self._lam, self._inv
            wl = si.wavelengths
            acc = mi.Spectrum(0.0)
            n = len(lam)
            for k in range(n):  # hat functions: linear between table wavelengths, flat beyond
                if n == 1:
                    w = 1.0
                elif k == 0:
                    w = dr.clip((lam[1] - wl) * inv[0], 0.0, 1.0)
                elif k == n - 1:
                    w = dr.clip((wl - lam[k - 1]) * inv[k - 1], 0.0, 1.0)
                else:
                    w = dr.clip(
                        dr.minimum((wl - lam[k - 1]) * inv[k - 1], (lam[k + 1] - wl) * inv[k]),
                        0.0,
                        1.0,
                    )
                acc += w * chans[k]
            return acc

        def _azimuth(self, w):
            phi = dr.atan2(w.y, w.x)
            return dr.select(phi < 0, phi + 2 * math.pi, phi)  # [0, 2π)

        def _coords(self, wi, wo):
            """Per grid axis ``(i0, i1, t)``: neighbouring nodes and the weight of ``i1``, with
            ``wi`` as the table's incident direction and ``wo`` the outgoing one: (θi, θo, Δφ)
            for isotropic tables, (φi, θi, θo, φo) otherwise (the layout of ``_corners``)."""
            d = self._data
            ti, to = elevation(wi), elevation(wo)

            def clamped(x, axis):
                x = position(x, axis)
                i0 = dr.minimum(mi.UInt32(x), max(axis.size - 2, 0))
                return i0, dr.minimum(i0 + 1, axis.size - 1), x - mi.Float(i0)

            if d.isotropic:
                dphi = dr.abs(dr.atan2(wo.y, wo.x) - dr.atan2(wi.y, wi.x))
                dphi = dr.select(dphi > math.pi, 2 * math.pi - dphi, dphi)
                return [clamped(ti, d.theta_i), clamped(to, d.theta_o), clamped(dphi, d.phi)]
            a0, ta = periodic_position(self._azimuth(wi), d.phi_i)
            b0, tb = periodic_position(self._azimuth(wo), d.phi)  # φo: repeated column at 2π
            return [
                (a0, (a0 + 1) % d.phi_i.size, ta),
                clamped(ti, d.theta_i),
                clamped(to, d.theta_o),
                (b0, b0 + 1, tb),
            ]

        def _corners(self, coords):
            """Flat texel indices (in texels) and weights of the multilinear interpolant."""
            shape = self._data.values.shape[:-1]
            if not self._data.isotropic:  # (φi·θi rows, θo, φo + 1)
                shape = (self._data.phi_i.size, self._data.theta_i.size, *shape[1:])
            strides = [int(np.prod(shape[k + 1 :])) for k in range(len(shape))]
            out = [(mi.UInt32(0), mi.Float(1.0))]
            for (i0, i1, t), stride in zip(coords, strides, strict=True):
                out = [
                    (idx + node * stride, w * wt)
                    for idx, w in out
                    for node, wt in ((i0, 1.0 - t), (i1, t))
                ]
            return out

        def _brdf(self, si, wo, active):
            """f_r (no cosine) as a Spectrum."""
            d = self._data
            if self._gather_spectral:
                return self._brdf_spectral(si, wo, active)
            if d.isotropic:
                wi = si.wi
                ti, to = elevation(wi), elevation(wo)
                dphi = dr.abs(dr.atan2(wo.y, wo.x) - dr.atan2(wi.y, wi.x))
                dphi = dr.select(dphi > math.pi, 2 * math.pi - dphi, dphi)
                pos = mi.Point3f(coord(dphi, d.phi), coord(to, d.theta_o), coord(ti, d.theta_i))
                return self._to_spectrum(self._tex.eval(pos, active), si)
            corners = self._corners(self._coords(si.wi, wo))
            c = d.n_channels
            chans = []
            for k in range(c):
                acc = mi.Float(0.0)
                for idx, w in corners:
                    acc += w * dr.gather(mi.Float, self._flat, idx * c + k, active)
                chans.append(acc)
            return self._to_spectrum(chans, si)

        def _brdf_spectral(self, si, wo, active):
            """Spectral tables with many wavelengths: per sampled wavelength, only the two
            table wavelengths around it are interpolated (2 gathers per grid corner)."""
            corners = self._corners(self._coords(si.wi, wo))
            c = self._data.n_channels
            lam, inv = self._lam, self._inv
            wl = si.wavelengths
            x = mi.Spectrum(0.0)  # fractional channel index, clamped to [0, c − 1]
            for k in range(c - 1):
                x += dr.clip((wl - lam[k]) * inv[k], 0.0, 1.0)
            out = []
            for j in range(len(wl)):
                k0 = dr.minimum(mi.UInt32(x[j]), c - 2)
                t = x[j] - mi.Float(k0)
                v0 = mi.Float(0.0)
                v1 = mi.Float(0.0)
                for idx, w in corners:
                    base = idx * c + k0
                    v0 += w * dr.gather(mi.Float, self._flat, base, active)
                    v1 += w * dr.gather(mi.Float, self._flat, base + 1, active)
                out.append(dr.lerp(v0, v1, t))
            return mi.Spectrum(*out)

        def _incident_lookup(self, tex, si, active):
            d = self._data
            ti = elevation(si.wi)
            if d.isotropic:
                return tex.eval(mi.Point1f(coord(ti, d.theta_i)), active)
            a0, ta = periodic_position(self._azimuth(si.wi), d.phi_i)
            pos = mi.Point2f(
                coord(ti, d.theta_i), (mi.Float(a0) + ta + 0.5) * (1.0 / (d.phi_i.size + 1))
            )
            return tex.eval(pos, active)

        def _delta_probability(self, ctx, si, active):
            has_g = ctx.is_enabled(glossy, 0)
            has_d = self._use_delta and ctx.is_enabled(delta, 1)
            if has_g and has_d:
                return self._incident_lookup(self._pdelta, si, active)[0]
            return mi.Float(1.0 if has_d else 0.0)

        # the glossy lobe's sampling (.mitsuba_sampling): nanobind classes take one base
        _slices = sampler.slices
        _density = sampler.density
        _pick = sampler.pick
        _cell = sampler.cell
        _glossy_pdf = sampler.glossy_pdf
        _sample_glossy = sampler.sample_glossy
        _sample_glossy_pdf = sampler.sample_glossy_pdf

        # ---------------------------------------------------------------- BSDF interface
        def eval(self, ctx, si, wo, active=True):
            cos_o = mi.Frame3f.cos_theta(wo)
            active = active & (mi.Frame3f.cos_theta(si.wi) > 0) & (cos_o > 0)
            if not ctx.is_enabled(glossy, 0):
                return mi.Spectrum(0.0)
            val = self._brdf(si, wo, active) * cos_o
            return dr.select(active, val, mi.Spectrum(0.0))

        def pdf(self, ctx, si, wo, active=True):
            active = active & (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
            if not ctx.is_enabled(glossy, 0):
                return mi.Float(0.0)
            p_d = self._delta_probability(ctx, si, active)
            return (1.0 - p_d) * self._glossy_pdf(si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            active = active & (mi.Frame3f.cos_theta(wi) > 0)
            bs = dr.zeros(mi.BSDFSample3f)
            has_g = ctx.is_enabled(glossy, 0)
            has_d = self._use_delta and ctx.is_enabled(delta, 1)
            if not (has_g or has_d):
                return bs, mi.Spectrum(0.0)
            p_d = self._delta_probability(ctx, si, active)
            pick_d = active & (sample1 < p_d)
            pick_g = active & ~pick_d
            xi = dr.clip((sample1 - p_d) / dr.maximum(1.0 - p_d, 1e-30), 0.0, 1.0)
            wo_g, pdf_g, ok_g = self._sample_glossy_pdf(ctx, si, xi, sample2, pick_g)
            f_g = self._brdf(si, wo_g, ok_g) * mi.Frame3f.cos_theta(wo_g)
            w_g = f_g / dr.select(ok_g, pdf_g, 1.0)
            # delta: the mirror direction with weight R_coh / P(delta)
            wo_d = mi.Vector3f(-wi.x, -wi.y, wi.z)
            if self._use_delta:
                r_coh = self._to_spectrum(self._incident_lookup(self._coh, si, pick_d), si)
                w_d = r_coh / dr.maximum(p_d, 1e-12)
            else:
                w_d = mi.Spectrum(0.0)
            bs.wo = dr.select(pick_d, wo_d, wo_g)
            bs.pdf = dr.select(pick_d, p_d, pdf_g)
            bs.eta = 1.0
            bs.sampled_type = dr.select(pick_d, mi.UInt32(+delta), mi.UInt32(+glossy))
            bs.sampled_component = dr.select(pick_d, mi.UInt32(1), mi.UInt32(0))
            valid = pick_d | ok_g
            weight = dr.select(pick_d, w_d, w_g)
            return bs, dr.select(valid, weight, mi.Spectrum(0.0))

        def traverse(self, callback):
            pass

        def to_string(self):
            d = self._data
            grid = "×".join(str(s) for s in d.values.shape[:-1])
            kind = "isotropic" if d.isotropic else "anisotropic"
            return (
                f"EmscatterBSDF[table={self._key!r}, {kind} "
                f"{grid} nodes, {d.n_channels} {d.channels} channels, delta lobe={self._use_delta}]"
            )

    cls = EmscatterBSDF
    if "polarized" in variant:
        from .polarized import polarized_class

        cls = polarized_class(
            mi, EmscatterBSDF, position, elevation, lambda key: _prepared_mueller(key, channels)
        )
    _CLASSES[variant] = cls
    return cls
