"""The ``"emscatter"`` Mitsuba plugin in polarized variants: a Mueller table as a pBSDF.

In ``*_polarized`` variants (``scalar_spectral_polarized``, ``llvm_ad_spectral_polarized``,
``*_rgb_polarized``, ``*_mono_polarized``) the plugin takes a
:class:`~emscatter.brdf.mueller.MuellerTable` (:func:`~emscatter.brdf.mueller.build_mueller_table`,
GO or first-order SPM) registered with :func:`emscatter.render.mitsuba.register_table`, and
``eval`` returns the 4 × 4 Mueller matrix times cosθ of the light direction, in Mitsuba's Stokes
frames, as Mitsuba's own ``roughconductor`` does (``src/bsdfs/roughconductor.cpp``):

* the light arrives along ``−L`` and leaves along ``V``: in radiance transport (the default)
  ``L`` is Mitsuba's ``wo`` and ``V`` is ``si.wi``, in importance transport the other way
  round. ``L`` is the table's incident direction ``wi`` (renderer convention, pointing away from
  the surface) and ``V`` its ``wo``: a Mueller table is *not* symmetric under ``wi ↔ wo`` (its
  reciprocity is ``M(V, L) = Q Mᵀ(L, V) Q``), so the roles are never mixed.
* every one of the 16 elements is interpolated multilinearly on the table's own (θi, θo, Δφ)
  nodes (the same interpolant as :meth:`~emscatter.brdf.table.BrdfTable.evaluate`, so ``M₀₀``
  is the unpolarized plugin's value), with the isotropic mirror ``M → D M D``,
  ``D = diag(1, 1, −1, −1)``, for ``Δφ = φV − φL ∈ (π, 2π)`` (:mod:`emscatter.brdf.export_pbsdf`);
  spectral variants interpolate linearly between the table's wavelengths, RGB ones use its sRGB
  weights per element (linear, so the Mueller algebra is kept).
* frames (:func:`emscatter.brdf.mueller.to_mitsuba`): emscatter's h/v frames, ``ĥ = ẑ × k̂``
  normalized, are made right-handed with Mitsuba's sign of V (``D_MITSUBA``), then rotated onto
  ``mi.mueller.stokes_basis`` of ``−L`` and ``V`` by ``mi.mueller.rotate_mueller_basis``.
* ``pdf`` and ``sample`` are the unpolarized plugin's (importance sampling of ``M₀₀ cosθ``);
  a sample's weight is the Mueller matrix over its pdf.

* the coherent (delta) lobe (SPM tables; ``coherent`` true, the default): its Mueller matrix
  :attr:`~emscatter.brdf.mueller.MuellerTable.coherent` (the table's h/v coherent powers with
  the mean field's phase, :func:`~emscatter.brdf.mueller.coherent_amplitudes`), interpolated
  linearly in θi, brought into Mitsuba's frames as the glossy part; Mitsuba's ``conductor``
  uses the same frames (``s`` axis ``n × k̂``, ``src/bsdfs/conductor.cpp``). It is sampled
  with the unpolarized plugin's delta probability; a delta sample's weight is that matrix
  over the probability.

* anisotropic Mueller tables (θi, φi, θo, φo): multilinear on the table's own nodes with φi
  and φo periodic, as the unpolarized plugin (no mirror fold: the azimuths are absolute).

Not supported here (clear errors): plain :class:`BrdfTable`
objects (no phase between polarizations: build a Mueller table with ``method="go"`` or
``"spm"``), a delta lobe without its Mueller matrix (a MuellerTable built by hand with
``coherent=None``: pass ``coherent=False`` or rebuild it with ``build_mueller_table``).
"""

from __future__ import annotations

import numpy as np

from ..brdf.colour import RGB_LUMINANCE, spectrum_to_rgb_weights
from ..brdf.mueller import D_MITSUBA, MuellerTable

__all__ = ["mueller_channels", "coherent_channels", "polarized_class"]


def _channel_mix(t, m: np.ndarray, channels: str) -> np.ndarray:
    """``m`` ``(..., n_wl, E)`` → plugin channels ``(..., C, E)``."""
    if channels == "spectral":
        return m
    w = spectrum_to_rgb_weights(t.wavelengths)  # (3, n_wl)
    if channels == "mono":
        w = RGB_LUMINANCE[None, :] @ w
    return np.einsum("cw,...we->...ce", w, m)


def coherent_channels(mt: MuellerTable, channels: str) -> np.ndarray | None:
    """The delta lobe's Mueller matrices as the plugin gathers them: float32 ``(n_ti, C, 16)``
    [-] in emscatter's h/v frames at the mirror pair of each θi node; None without a delta
    lobe. ``M₀₀`` is the unpolarized plugin's ``R_coh`` (same channels, clipped to [0, 1])."""
    if mt.coherent is None:
        return None
    c = np.asarray(mt.coherent, float)  # (n_wl, 4, 4, n_ti)
    c = np.moveaxis(c.reshape(c.shape[0], 16, -1), (0, 1), (-2, -1))  # (n_ti, n_wl, 16)
    out = _channel_mix(mt.table, c, channels).copy()
    out[..., 0] = np.clip(out[..., 0], 0.0, 1.0)
    if not np.all(np.isfinite(out)):
        raise ValueError("the Mueller table's coherent part holds NaN/inf; nothing to render")
    return np.ascontiguousarray(out, dtype=np.float32)


def mueller_channels(mt: MuellerTable, channels: str) -> np.ndarray:
    """The Mueller table as the plugin gathers it: float32 ``(n_ti, n_to, n_pd, C, 16)``
    [1/sr] in emscatter's h/v frames, ``C`` the table's wavelengths (``"spectral"``), linear
    sRGB (``"rgb"``) or luminance (``"mono"``); ``M₀₀`` clipped at 0 as the unpolarized plugin."""
    if not isinstance(mt, MuellerTable):
        raise TypeError(
            "the emscatter plugin in a polarized Mitsuba variant needs a MuellerTable "
            "(emscatter.brdf.mueller.build_mueller_table with method='go' or 'spm'), got "
            f"{type(mt).__name__}; a plain BrdfTable keeps no phase between polarizations"
        )
    t = mt.table
    m = np.asarray(mt.mueller, float)  # (n_wl, 4, 4, *grid)
    m = np.moveaxis(m.reshape(m.shape[0], 16, *m.shape[3:]), (0, 1), (-2, -1))
    if not t.isotropic:  # (n_ti, n_pi, n_to, n_po) → the plugin's (n_pi, n_ti, n_to, n_po + 1)
        m = np.moveaxis(m, 1, 0)
        m = np.concatenate([m, m[:, :, :, :1]], axis=3)  # φo periodic: φ₀ repeated at 2π
    out = _channel_mix(t, m, channels).copy()
    out[..., 0] = np.clip(out[..., 0], 0.0, None)
    if not np.all(np.isfinite(out)):
        raise ValueError("the Mueller table holds NaN/inf; nothing to render")
    return np.ascontiguousarray(out, dtype=np.float32)


def polarized_class(mi, base, position, elevation, prepared_mueller):
    """The polarized BSDF class: ``base`` (the unpolarized plugin class of this variant, which
    keeps the table's s0 for sampling) with Mueller ``eval`` and ``sample``.
    ``prepared_mueller(key)`` → ``(flat Mueller array, n_channels, wavelengths [nm] or None,
    coherent channels or None)`` (:func:`mueller_channels`, :func:`coherent_channels`)."""
    import drjit as dr

    glossy = mi.BSDFFlags.GlossyReflection
    delta = mi.BSDFFlags.DeltaReflection
    radiance = mi.TransportMode.Radiance
    n_spec = len(mi.UnpolarizedSpectrum(0.0))
    d_sign = np.diag(D_MITSUBA)
    mirror_sign = [1.0, 1.0, -1.0, -1.0]

    def h_axis(k):
        """emscatter's ĥ = ẑ × k̂ / |ẑ × k̂| (x̂ at the pole: a measure-zero choice)."""
        h = mi.Vector3f(-k.y, k.x, 0.0)
        n2 = dr.square(h.x) + dr.square(h.y)
        return dr.select(n2 > 1e-14, h * dr.rsqrt(dr.maximum(n2, 1e-30)), mi.Vector3f(1, 0, 0))

    class EmscatterPolarizedBSDF(base):
        def __init__(self, props):
            base.__init__(self, props)
            flat, n_ch, lam, coh = prepared_mueller(str(self._key))
            self._mflat = mi.Float(flat.ravel())
            self._mch = n_ch
            self._mlam = lam
            if self._use_delta:
                if coh is None:
                    raise ValueError(
                        f"emscatter plugin, table {self._key!r}: the table has a coherent "
                        "(delta) lobe but no Mueller matrix for it (MuellerTable.coherent is "
                        "None: anisotropic tables, or a table not built by "
                        "emscatter.brdf.mueller.build_mueller_table); pass coherent=False "
                        "(drops R_coh) or render unpolarized"
                    )
                self._cflat = mi.Float(coh.ravel())

        def _coherent_mueller(self, si, light, view, active):
            """The delta lobe's Mueller matrix (a reflectance) in Mitsuba's frames of
            ``−light`` → ``view`` (the mirror pair), linear in θi between the nodes."""
            ax = self._data.theta_i
            x = position(elevation(light), ax)
            i0 = dr.minimum(mi.UInt32(x), max(ax.size - 2, 0))
            i1 = dr.minimum(i0 + 1, ax.size - 1)
            t = x - mi.Float(i0)
            corners = [(i0, 1.0 - t), (i1, t)]
            return self._assemble(self._cflat, corners, si, light, view, active, False)

        def _assemble(self, flat, corners, si, light, view, active, mirror):
            """Gather the 16 elements at ``corners`` (node index, weight) and the channel
            picks, to Mitsuba's handedness and sign of V, rotated onto Mitsuba's bases."""
            picks = self._channel_picks(si)
            stride = self._mch * 16
            m = dr.zeros(mi.Spectrum)
            mirrored = (light.x * view.y - light.y * view.x) < 0  # Δφ = φV − φL ∈ (π, 2π)
            for e in range(16):
                r, c = divmod(e, 4)
                slots = []
                for pick in picks:
                    acc = mi.Float(0.0)
                    for idx, w in corners:
                        for ch, wc in pick:
                            g = dr.gather(mi.Float, flat, idx * stride + ch * 16 + e, active)
                            acc += (w * wc) * g
                    slots.append(acc)
                val = (
                    mi.UnpolarizedSpectrum(*slots)
                    if n_spec > 1
                    else mi.UnpolarizedSpectrum(slots[0])
                )
                sign = d_sign[r] * d_sign[c]  # to Mitsuba's handedness and sign of V
                if mirror and mirror_sign[r] * mirror_sign[c] < 0:
                    val = dr.select(mirrored, -val, val)
                m[r, c] = val * float(sign)
            k_in = -light
            return mi.mueller.rotate_mueller_basis(
                m, k_in, h_axis(k_in), mi.mueller.stokes_basis(k_in),
                view, h_axis(view), mi.mueller.stokes_basis(view),
            )  # fmt: skip

        def _channel_picks(self, si):
            """Per spectrum slot: ``[(channel, weight), ...]`` (two table wavelengths around
            each sampled one in spectral variants; the slot's own channel otherwise)."""
            c = self._mch
            if self._mlam is None or c == 1:
                return [[(mi.UInt32(min(j, c - 1)), 1.0)] for j in range(n_spec)]
            lam = self._mlam
            wl = si.wavelengths
            x = mi.UnpolarizedSpectrum(0.0)
            for k in range(c - 1):
                x += dr.clip((wl - lam[k]) / (lam[k + 1] - lam[k]), 0.0, 1.0)
            picks = []
            for j in range(n_spec):
                k0 = dr.minimum(mi.UInt32(x[j]), c - 2)
                t = x[j] - mi.Float(k0)
                picks.append([(k0, 1.0 - t), (k0 + 1, t)])
            return picks

        def _mueller(self, si, light, view, active):
            """The Mueller BRDF (no cosine) in Mitsuba's frames of ``−light`` → ``view``."""
            corners = self._corners(self._coords(light, view))
            mirror = self._data.isotropic  # Δφ ∈ (π, 2π) folded onto the table's [0, π]
            return self._assemble(self._mflat, corners, si, light, view, active, mirror)

        def _light_view(self, ctx, si, wo):
            if ctx.mode == radiance:
                return wo, si.wi
            return si.wi, wo

        def eval(self, ctx, si, wo, active=True):
            cos_o = mi.Frame3f.cos_theta(wo)
            active = active & (mi.Frame3f.cos_theta(si.wi) > 0) & (cos_o > 0)
            if not ctx.is_enabled(glossy, 0):
                return dr.zeros(mi.Spectrum)
            light, view = self._light_view(ctx, si, wo)
            val = self._mueller(si, light, view, active) * cos_o
            return dr.select(active, val, dr.zeros(mi.Spectrum))

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            active = active & (mi.Frame3f.cos_theta(wi) > 0)
            bs = dr.zeros(mi.BSDFSample3f)
            has_g = ctx.is_enabled(glossy, 0)
            has_d = self._use_delta and ctx.is_enabled(delta, 1)
            if not (has_g or has_d):
                return bs, dr.zeros(mi.Spectrum)
            p_d = self._delta_probability(ctx, si, active)  # 0 without a delta lobe
            pick_d = active & (sample1 < p_d)
            pick_g = active & ~pick_d
            xi = dr.clip((sample1 - p_d) / dr.maximum(1.0 - p_d, 1e-30), 0.0, 1.0)
            wo_g, pdf_g, ok_g = self._sample_glossy_pdf(ctx, si, xi, sample2, pick_g)
            wo_d = mi.Vector3f(-wi.x, -wi.y, wi.z)
            wo = dr.select(pick_d, wo_d, wo_g)
            light, view = self._light_view(ctx, si, wo)
            val = self._mueller(si, light, view, ok_g) * (
                mi.Frame3f.cos_theta(wo_g) / dr.maximum(pdf_g, 1e-30)
            )
            if self._use_delta:  # delta: the mirror direction, weight M_coh / P(delta)
                m_d = self._coherent_mueller(si, light, view, pick_d)
                val = dr.select(pick_d, m_d * (1.0 / dr.maximum(p_d, 1e-12)), val)
            bs.wo = wo
            bs.pdf = dr.select(pick_d, p_d, pdf_g)
            bs.eta = 1.0
            bs.sampled_type = dr.select(pick_d, mi.UInt32(+delta), mi.UInt32(+glossy))
            bs.sampled_component = dr.select(pick_d, mi.UInt32(1), mi.UInt32(0))
            return bs, dr.select(pick_d | ok_g, val, dr.zeros(mi.Spectrum))

        def to_string(self):
            return base.to_string(self).replace("EmscatterBSDF[", "EmscatterPolarizedBSDF[")

    return EmscatterPolarizedBSDF
