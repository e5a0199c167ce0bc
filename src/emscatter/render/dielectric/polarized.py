"""The ``"emscatter_dielectric"`` plugin in ``*_polarized`` Mitsuba variants: Mueller matrices
for reflection on both sides and for transmission, in Mitsuba's Stokes frames.

Tables: ``reflection`` (and ``inner``) as :class:`~emscatter.brdf.mueller.MuellerTable`
(``build_mueller_table(..., method="go")``), the BTDF built with
``build_btdf_table(..., polarized=True)``. Sampling, pdf and ``M₀₀`` are the unpolarized
plugin's (:mod:`.plugin`); ``eval`` returns ``M · |cosθ_wo|`` (times the same radiance
factors), a sample's weight is that matrix over the pdf.

Frames — those of Mitsuba's ``dielectric`` / ``roughdielectric`` polarized code
(``src/bsdfs/dielectric.cpp``, ``roughdielectric.cpp``): light arrives along ``−L`` and
leaves along ``V`` (radiance transport: ``L`` = ``wo``, ``V`` = ``si.wi``; importance
transport the other way round); the matrix maps Stokes vectors in
``mi.mueller.stokes_basis(−L)`` to ``mi.mueller.stokes_basis(V)``.

* outside reflection: the polarized ``"emscatter"`` plugin (:mod:`.polarized`) as it is.
* transmission, light from outside (``L`` above, ``V`` below): the table's Mueller BTDF
  (emscatter's h/v bases, ``ĥ = ẑ × k̂``), multilinear on its nodes (``Δφ ∈ (π, 2π)`` mirrored:
  ``P M P``, ``P = diag(1, 1, −1, −1)``), made right-handed with Mitsuba's sign of V
  (``D_MITSUBA``) and rotated onto the Stokes bases (:meth:`BtdfTable.evaluate_mueller` with
  ``frame="mitsuba"`` is the NumPy twin). An
  :class:`~emscatter.brdf.btdf_aniso.AnisotropicBtdfTable` (``polarized=True``): its 16
  entries multilinear in ``(θi, φi, θt, Δφ)`` (:class:`.aniso.AnisoBtdfLookup`; ``Δφ`` is
  stored on the full turn, the fold of ``φi`` into ``[0, π/2]`` by the mirror ``φi → π − φi``
  gives ``P M P``), then the same signs and rotations (the h/v bases are those of the
  directions in the local frame, tangent ``+x`` along ``ℓx``;
  :meth:`AnisotropicBtdfTable.evaluate_mueller` with ``frame="mitsuba"`` is the NumPy twin).
  Reflection: isotropic or anisotropic ``MuellerTable`` objects (the ``"emscatter"`` plugin).
* transmission, light from inside (``L`` below, ``V`` above): reciprocity of the reverse path
  (Saxon 1955; the scattering dyadic transposes, ``S(k_s, k_i) = Sᵀ(−k_i, −k_s)``, with the
  same physical polarization vectors). With ``M_f`` the table matrix of the forward path
  ``−V → L`` in Stokes bases ``x_a = stokes_basis(−V)``, ``x_b = stokes_basis(L)``, the
  reverse path ``−L → V`` has ``M_r = Q M_fᵀ Q``, ``Q = diag(1, 1, −1, 1)`` (``Mueller(Jᵀ) =
  diag(1,1,1,−1) Mᵀ diag(1,1,1,−1)`` in :func:`~emscatter.brdf.mueller.jones_to_mueller`'s
  convention, times ``diag(1,1,−1,−1)`` for reversing each basis' second vector to stay
  right-handed; checked against Mitsuba's smooth ``dielectric``), in bases with x axes
  ``x_b`` (incident) and ``x_a`` (outgoing), then rotated onto ``stokes_basis(−L)``,
  ``stokes_basis(V)``.
* inside reflection: the ``inner`` plugin at the directions mirrored through the surface
  (``z → −z``, as the unpolarized plugin). A mirror maps a right-handed basis ``(x, y)`` to the
  left-handed ``(Px, Py)``; flipping ``y`` back gives ``D M D``, ``D = diag(1, 1, −1, −1)``,
  in bases with x axes ``P·stokes_basis(mirrored k)``, rotated onto Mitsuba's bases.

* delta lobes (:mod:`.delta`): Mitsuba's polarized ``dielectric`` — the Fresnel
  Mueller matrices (``mi.mueller.specular_reflection`` / ``specular_transmission`` at the
  light's cosine, mean ``η``) rotated from the s/p frames onto the Stokes bases — times the
  table's coherent part over the Fresnel power, so ``M₀₀`` is the unpolarized plugin's.

Spectral variants interpolate every element linearly between the table's wavelengths (the
unpolarized plugin's rule); RGB ones use the table's sRGB weights per element.
"""

from __future__ import annotations

import math

import numpy as np

from ...brdf.btdf_aniso import AnisotropicBtdfTable
from ...brdf.btdf_table import BtdfTable
from ...brdf.mueller import D_MITSUBA
from ..polarized import _channel_mix
from .aniso import AnisoBtdfLookup, aniso_mueller_channels

__all__ = ["btdf_mueller_channels", "polarized_dielectric_class"]


def btdf_mueller_channels(bt: BtdfTable, channels: str) -> np.ndarray:
    """The Mueller BTDF as the plugin samples it: float32 ``(n_ti, n_tt, n_pd, C·16)``
    [1/sr] in emscatter's h/v bases, channel-major (``C`` as :func:`.polarized.mueller_channels`),
    ``M₀₀`` clipped at 0 as the unpolarized plugin."""
    if not isinstance(bt, BtdfTable) or bt.mueller is None:
        raise ValueError(
            "the emscatter_dielectric plugin in a polarized Mitsuba variant needs a BTDF "
            "table with Mueller matrices (build_btdf_table(..., polarized=True)); this one "
            "has none"
        )
    m = np.asarray(bt.mueller, float)  # (n_wl, 4, 4, ti, tt, pd)
    m = np.moveaxis(m.reshape(m.shape[0], 16, *m.shape[3:]), (0, 1), (-2, -1))
    out = _channel_mix(bt, m, channels).copy()  # (ti, tt, pd, C, 16)
    out[..., 0] = np.clip(out[..., 0], 0.0, None)
    if not np.all(np.isfinite(out)):
        raise ValueError("the BTDF table's Mueller part holds NaN/inf; nothing to render")
    return np.ascontiguousarray(out.reshape(*out.shape[:3], -1), dtype=np.float32)


def polarized_dielectric_class(mi, base, coord, theta, sets):
    """The polarized dielectric class: ``base`` (the unpolarized dielectric class of this
    variant: sampling, pdf, lobe choice) with Mueller ``eval`` and ``sample`` weights.
    ``coord``/``theta``: the base's texture coordinate and polar angle helpers; ``sets``: the
    registry of :func:`.plugin.register_dielectric`."""
    import drjit as dr

    from ..mitsuba import channels_of_variant

    channels = channels_of_variant(mi.variant())
    f = mi.BSDFFlags
    radiance = mi.TransportMode.Radiance
    d_sign = np.diag(D_MITSUBA)
    mirror_sign = [1.0, 1.0, -1.0, -1.0]
    sb = mi.mueller.stokes_basis

    def h_axis(k):
        h = mi.Vector3f(-k.y, k.x, 0.0)
        n2 = dr.square(h.x) + dr.square(h.y)
        return dr.select(n2 > 1e-14, h * dr.rsqrt(dr.maximum(n2, 1e-30)), mi.Vector3f(1, 0, 0))

    def flip(w):
        return mi.Vector3f(w.x, w.y, -w.z)

    def scaled(m, diag):
        """``diag · m · diag`` for a ±1 diagonal (a Python list)."""
        out = dr.zeros(mi.Spectrum)
        for r in range(4):
            for c in range(4):
                out[r, c] = m[r, c] * float(diag[r] * diag[c])
        return out

    def transposed(m):
        out = dr.zeros(mi.Spectrum)
        for r in range(4):
            for c in range(4):
                out[r, c] = m[c, r]
        return out

    class DielectricPolarizedBSDF(base):
        def __init__(self, props):
            base.__init__(self, props)
            s = sets[str(props.get("tables", ""))]
            if not s["polarized_tables"]:
                raise ValueError(
                    "emscatter_dielectric plugin in a polarized variant: reflection (and "
                    "inner) must be MuellerTables (emscatter.brdf.mueller.build_mueller_table "
                    "with method='go'), got plain BrdfTables (no phase between polarizations)"
                )
            bt = s["transmission"]
            self._maniso = None
            if isinstance(bt, AnisotropicBtdfTable):  # 4-D: explicit gathers (.aniso)
                flat = aniso_mueller_channels(bt, lambda m: _channel_mix(bt, m, channels))
                self._mch = flat.shape[-1] // 16
                self._maniso = AnisoBtdfLookup(mi, bt, vals=flat)
                return
            flat = btdf_mueller_channels(bt, channels)
            self._mch = flat.shape[-1] // 16
            self._mtex = mi.Texture3f(
                mi.TensorXf(flat),
                use_accel=False,
                filter_mode=dr.FilterMode.Linear,
                wrap_mode=dr.WrapMode.Clamp,
            )

        def _uspec(self, chans, si):
            """One element's channels → UnpolarizedSpectrum (the base's spectral rule)."""
            return self._spec(chans, si, mi.UnpolarizedSpectrum)

        def _mt(self, a, b, active, si):
            """Mueller BTDF (no cosine) of light from above along ``−a`` to ``b`` below, in
            Mitsuba's bases of ``−a`` and ``b``."""
            if self._maniso is not None:  # φi folded by a mirror: P M P (module docstring)
                vals, mirrored = self._maniso.lookup(a, b, active)
            else:
                ti, tt = theta(a.z), theta(b.z)
                dphi = dr.abs(dr.atan2(b.y, b.x) - dr.atan2(a.y, a.x))
                dphi = dr.select(dphi > math.pi, 2 * math.pi - dphi, dphi)
                ax = self._ax
                pos = mi.Point3f(coord(dphi, ax[2]), coord(tt, ax[1]), coord(ti, ax[0]))
                vals = self._mtex.eval(pos, active)
                mirrored = (a.x * b.y - a.y * b.x) < 0  # Δφ = φb − φa ∈ (π, 2π)
            m = dr.zeros(mi.Spectrum)
            c = self._mch
            for e in range(16):
                r, col = divmod(e, 4)
                val = self._uspec([vals[k * 16 + e] for k in range(c)], si)
                if mirror_sign[r] * mirror_sign[col] < 0:
                    val = dr.select(mirrored, -val, val)
                m[r, col] = val * float(d_sign[r] * d_sign[col])
            k_in = -a
            return mi.mueller.rotate_mueller_basis(
                m, k_in, h_axis(k_in), sb(k_in), b, h_axis(b), sb(b)
            )

        def _eval_t(self, ctx, si, wo, active):
            if ctx.mode == radiance:
                light, view = wo, si.wi
            else:
                light, view = si.wi, wo
            from_out = light.z > 0
            m_fwd = self._mt(light, view, active & from_out, si)
            # light from inside: reciprocity of the forward path −V → L (module docstring)
            m_f = self._mt(view, light, active & ~from_out, si)
            m_r = scaled(transposed(m_f), [1.0, 1.0, -1.0, 1.0])
            m_r = mi.mueller.rotate_mueller_basis(
                m_r, -light, sb(light), sb(-light), view, sb(-view), sb(view)
            )
            m = dr.select(from_out, m_fwd, m_r)
            out = si.wi.z > 0
            rad = ctx.mode == radiance
            inv = self._inv_eps(si, mi.UnpolarizedSpectrum)  # per sampled λ when spectral
            scale = dr.select(out, inv if rad else 1.0, 1.0 if rad else inv)
            if isinstance(inv, float):
                return m * (dr.abs(wo.z) * scale)
            return m * mi.Spectrum(dr.abs(wo.z) * scale)  # M · diag(s(λ)): each entry × s(λ)

        def _inner_mueller(self, m, ctx, si, wo):
            """The inner plugin's matrix (mirrored directions) in Mitsuba's true bases."""
            if ctx.mode == radiance:
                light, view = wo, si.wi
            else:
                light, view = si.wi, wo
            k_in, k_out = -light, view
            m = scaled(m, [1.0, 1.0, -1.0, -1.0])
            return mi.mueller.rotate_mueller_basis(
                m, k_in, flip(sb(flip(k_in))), sb(k_in), k_out, flip(sb(flip(k_out))), sb(k_out)
            )

        def eval(self, ctx, si, wo, active=True):
            v = si.wi
            active = active & (v.z != 0) & (wo.z != 0)
            reflect = v.z * wo.z > 0
            res = dr.zeros(mi.Spectrum)
            if ctx.is_enabled(f.GlossyReflection, 0):
                m = active & reflect & (v.z > 0)
                res = dr.select(m, self._refl.eval(ctx, si, wo, m), res)
            if ctx.is_enabled(f.GlossyTransmission, 1):
                m = active & ~reflect
                res = dr.select(m, self._eval_t(ctx, si, wo, m), res)
            if self._inner is not None and ctx.is_enabled(f.GlossyReflection, 2):
                m = active & reflect & (v.z < 0)
                val = self._inner.eval(ctx, self._inner_si(si), flip(wo), m)
                res = dr.select(m, self._inner_mueller(val, ctx, si, wo), res)
            return res

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs, weight = base.sample(self, ctx, si, sample1, sample2, active)
            if self._inner is not None:  # the base weighs the inner lobe in mirrored bases
                inner = (bs.sampled_component == 2) & (bs.pdf > 0)
                fixed = self._inner_mueller(weight, ctx, si, bs.wo)
                weight = dr.select(inner, fixed, weight)
            return bs, weight

        def _delta_weight(self, ctx, si, wo, is_r, active):
            """A delta sample's Mueller matrix: Mitsuba's ``dielectric`` (Fresnel matrices
            at the light's cosine, its Stokes frames ⟂ the plane of incidence) scaled by the
            table's coherent part over the Fresnel power (``R_coh/R_F``, ``T_coh/T_F``: s0
            is the unpolarized plugin's; the radiance scale is in the coherent part)."""
            coh = self._delta_coh(ctx, si, wo, is_r, active, mi.UnpolarizedSpectrum)
            light, view = (wo, si.wi) if ctx.mode == radiance else (si.wi, wo)
            m_r = mi.mueller.specular_reflection(light.z, mi.Complex2f(self._eta, 0.0))
            m_t = mi.mueller.specular_transmission(light.z, mi.Float(self._eta))
            m4 = dr.select(is_r, m_r, m_t)  # Matrix4f (the mean η, as the refraction)
            ratio = coh / dr.maximum(m4[0, 0], 1e-12)
            m = dr.zeros(mi.Spectrum)
            for r in range(4):
                for c in range(4):
                    m[r, c] = ratio * m4[r, c]
            n = mi.Vector3f(0, 0, 1)
            s_in, s_out = dr.cross(n, -light), dr.cross(n, view)
            normal = dr.all(s_in == 0)
            s_in = dr.select(normal, mi.Vector3f(1, 0, 0), dr.normalize(s_in))
            s_out = dr.select(normal, mi.Vector3f(1, 0, 0), dr.normalize(s_out))
            m = mi.mueller.rotate_mueller_basis(m, -light, s_in, sb(-light), view, s_out, sb(view))
            return m

        def to_string(self):
            return base.to_string(self).replace("EmscatterDielectricBSDF[", "Polarized[")

    return DielectricPolarizedBSDF
