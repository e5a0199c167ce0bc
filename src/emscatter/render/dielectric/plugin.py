"""A rough dielectric interface from emscatter tables as a Mitsuba 3 BSDF: reflection on both
sides and transmission through it (plugin ``"emscatter_dielectric"``).

Usage, after ``mi.set_variant(...)`` with an RGB, mono or spectral LLVM variant
(``llvm_ad_rgb`` and ``llvm_ad_spectral`` tested; ``*_polarized`` variants with Mueller tables:
:mod:`.polarized`)::

    from emscatter.render import dielectric as em_d
    bsdf = mi.load_dict(em_d.bsdf_dict(reflection=brdf, transmission=btdf, inner=brdf_in))

``reflection``: the :class:`~emscatter.brdf.table.BrdfTable` of the outside (``ε``),
``transmission``: the :class:`~emscatter.brdf.btdf_table.BtdfTable` of light from outside
(or an :class:`~emscatter.brdf.btdf_aniso.AnisotropicBtdfTable`, :mod:`.aniso`: scalar, RGB,
mono, spectral and, with its Mueller part, polarized variants; ``reflection``/``inner`` may
then be anisotropic BRDF tables),
``inner`` (optional): the BRDF of the inside (``1/ε``: internal reflection, total internal
reflection included; without it nothing is reflected inside). The reflection lobes are the
``"emscatter"`` plugin (:mod:`.mitsuba`) of each table; this plugin adds the transmission lobe
and picks between them. A separate plugin rather than a third lobe in ``"emscatter"``: the
reflection plugin stays one-sided like Mitsuba's ``measured``, and a dielectric needs three
tables that belong together.

Conventions — those of Mitsuba's ``roughdielectric`` (``src/bsdfs/roughdielectric.cpp``):
``si.wi`` towards the viewer, ``wo`` towards the light, ``eval`` returns ``f · |cosθ_wo|``. The
table holds the radiance BTDF ``f_t(l → v)`` for light ``l`` above and viewer ``v`` below
(Walter et al. 2007, eq. 21, the ``η²`` radiance compression included). By the reciprocity
of the BTDF, ``f(l → v)/η_v² = f(v → l)/η_l²`` (Veach 1997, §5.2), so in radiance mode

* viewer inside, light outside: ``f_table(l, v)``;
* viewer outside, light inside: ``f_table(v, l) / ε`` (``roughdielectric``'s ``inv_eta²``);

in importance mode (adjoint transport) without the ``1/ε``, and the inside case carries
``1/ε`` instead. Components: 0 glossy reflection (outside), 1 glossy transmission, 2 glossy
reflection inside (when ``inner`` is given); flags front and back side, non-symmetric.

Coherent (delta) lobes (``coherent``, bool, default true; PO/SPM tables, :mod:`.delta`):
the reflection table's ``R_coh`` (mirror), the BTDF's ``T_coh`` (Snell direction, Mitsuba's
``dielectric`` radiance scale ``1/ε`` outside, ``ε`` inside), the inner table's ``R_coh``
and, from inside, ``T_coh`` at the Snell-mapped outside angle; components after the glossy
ones: ``DeltaReflection`` (outside), ``DeltaTransmission``, ``DeltaReflection`` (inside, with
an inner coherent part). Chosen by energy against the glossy lobes; ``coherent=false`` (or GO
tables, which have none) renders the glossy lobes only, exactly as before the delta lobes
(the reflection lobes are ``"emscatter"`` plugins with ``coherent=false``: the delta parts
are this plugin's).

Sampling (:mod:`.sampling`): reflection vs transmission by their albedos at the viewer's θ
(outside: ``R`` of the reflection table, ``T`` of the BTDF table, both exact integrals of the
interpolants; inside: ``R_in`` of ``inner`` and ``1 − R_in``), the reflection lobes by the
``"emscatter"`` plugin's sampler, the transmission by Beckmann microfacet normals refracted
(Walter et al. 2007, eqs. 17, 28, 40: ``p(wo) = D(m) cosθm |wo·m| η_o² / (η_i v·m + η_o
wo·m)²``) with the table's slope variance (``α² = 2s``); ``pdf`` is that density exactly, times
the lobe probability. Tables with a coherent transmission (PO/SPM) draw half the normals from a
wide Beckmann lobe (α = 0.5, a defensive mixture; the pdf is the mixture's): an SPM lobe is the
roughness spectrum at the Bragg wavenumbers, far wider than its slopes (kσ = 0.13, ℓ = 1 µm: α
= 0.023 sampled 6 % of the glossy transmission at normal incidence, the mixture all of it).
Anisotropic tables sample their anisotropic Beckmann lobe (``αx = √(2 s_x)``, ``αy = √(2
s_y)``, tangent ``+x`` along ``ℓx``; the plugin parameter ``lobe_sampling="isotropic"`` keeps
``α = √(s_x + s_y)``, :mod:`.sampling`).

Spectral variants: the BTDF is kept per table wavelength (one texture channel each) and
interpolated linearly to the sampled wavelengths, flat beyond the table's range — the
``"emscatter"`` plugin's spectral rule (:mod:`.mitsuba`), which the two reflection lobes use.
The ``1/ε`` radiance factor is taken per sampled wavelength (``1/ε`` of the table's
wavelengths by the same hat functions), so a dispersive glass is exact at every table
wavelength (N-BK7 over 400–700 nm: 1.3 % error at 400 nm with the mean ``ε``, the table's
interpolation error with this rule; ``tests/test_render_dielectric_dispersive.py``). The
sampling's refraction frame (Walter's normals refracted at ``η``) takes the mean ``ε``: its
``pdf`` is that density exactly, so this costs variance, not bias. RGB and mono variants use
the mean ``ε`` throughout (one index per path); ``*_spectral_polarized`` takes ``1/ε`` per
wavelength as here (:mod:`.polarized`). The lobe probabilities weigh the
wavelengths by their luminance.
"""

from __future__ import annotations

import itertools
import math
import sys

import numpy as np

from ...brdf.btdf_aniso import AnisotropicBtdfTable
from ...brdf.btdf_table import BtdfTable
from ...brdf.colour import RGB_LUMINANCE, spectrum_to_rgb_weights
from ...brdf.mueller import MuellerTable
from ...brdf.table import BrdfTable
from .. import mitsuba as em_mi
from ..plugin_data import Axis
from .aniso import AnisoBtdfLookup, check_axes, reduce_albedo
from .delta import delta_data, refract
from .sampling import (
    LOBE_SAMPLING,
    RefractionSampler,
    inner_transmission_choice,
    transmission_choice,
)

__all__ = ["PLUGIN_NAME", "bsdf_dict", "register", "register_dielectric"]

PLUGIN_NAME = "emscatter_dielectric"
_SETS: dict[str, dict] = {}
_CLASSES: dict[str, type] = {}
_COUNTER = itertools.count()


def _s0(t):
    """The unpolarized table of a MuellerTable (its ``M₀₀``), other objects as they are."""
    return t.table if isinstance(t, MuellerTable) else t


def register_dielectric(reflection, transmission, inner=None, key: str | None = None) -> str:
    """Register the tables of one interface (module docstring); returns the key for
    ``{"type": "emscatter_dielectric", "tables": key}``. ``reflection`` and ``inner`` may be
    :class:`~emscatter.brdf.mueller.MuellerTable` objects (needed in polarized variants,
    :mod:`.polarized`; their ``M₀₀`` elsewhere). With a Mitsuba variant set it
    also registers the plugin (:func:`register`), as :func:`.mitsuba.register_table`."""
    refl_obj, inner_obj = reflection, inner
    reflection, inner = _s0(reflection), _s0(inner)
    aniso = isinstance(transmission, AnisotropicBtdfTable)
    kind = "a" if aniso else "an isotropic"  # an anisotropic BTDF: either BRDF kind (.aniso)
    if not isinstance(reflection, BrdfTable) or not (aniso or reflection.isotropic):
        raise TypeError(f"reflection must be {kind} BrdfTable, got {type(reflection).__name__}")
    if not isinstance(transmission, (BtdfTable, AnisotropicBtdfTable)):
        raise TypeError(
            "transmission must be a BtdfTable or an AnisotropicBtdfTable, got "
            f"{type(transmission).__name__}"
        )
    if inner is not None and (not isinstance(inner, BrdfTable) or not (aniso or inner.isotropic)):
        raise TypeError(f"inner must be None or {kind} BrdfTable, got {type(inner).__name__}")
    for name, t in (("reflection", reflection), ("inner", inner)):
        if t is not None and not np.allclose(t.wavelengths, transmission.wavelengths, rtol=1e-9):
            raise ValueError(
                f"{name} and transmission tables must share their wavelengths, got "
                f"{t.wavelengths.tolist()} and {transmission.wavelengths.tolist()} m"
            )
    if aniso:
        check_axes(transmission)
    for name, ax in zip(("theta_i", "theta_t", "phi_d"), _grid_axes(transmission), strict=True):
        if not Axis.of(ax).uniform:
            raise ValueError(f"the plugin needs uniform BTDF axes; {name} is not uniform")
    slope = transmission.metadata.get("slope_variance")
    if slope is None:
        raise ValueError(
            "the BTDF table has no metadata['slope_variance'] (build_btdf_table sets it)"
        )
    key = f"emscatter-dielectric-{next(_COUNTER)}" if key is None else str(key)
    _SETS[key] = {
        "reflection": em_mi.register_table(refl_obj),
        "inner": None if inner is None else em_mi.register_table(inner_obj),
        "polarized_tables": isinstance(refl_obj, MuellerTable)
        and (inner is None or isinstance(inner_obj, MuellerTable)),
        "transmission": transmission,
        "r_albedo": reduce_albedo(reflection.albedo().incoherent),  # the delta lobes: .delta
        "r_in_albedo": None if inner is None else reduce_albedo(inner.albedo().incoherent),
        "reflection_table": reflection,
        "inner_table": inner,
        "theta_r": reflection.theta_i,
        "theta_in": None if inner is None else inner.theta_i,
    }
    mi = sys.modules.get("mitsuba")  # as register_table: loads as written with a variant set
    if mi is not None and mi.variant() is not None:
        register()
    return key


def _grid_axes(bt) -> tuple[np.ndarray, ...]:
    """``(θi, θt, Δφ)`` nodes of either BTDF table kind."""
    return (bt.theta_i, bt.theta_t, bt.phi_d)


def register(name: str = PLUGIN_NAME) -> None:
    """Register the plugin (and ``"emscatter"``) for the current Mitsuba variant."""
    mi = em_mi._mitsuba()
    em_mi.register()
    variant = mi.variant()
    if variant not in _CLASSES:
        _CLASSES[variant] = _bsdf_class(mi)
        mi.register_bsdf(name, lambda props: _CLASSES[variant](props))


def bsdf_dict(
    reflection, transmission, inner=None, *, coherent: bool = True, lobe_sampling: str = "auto"
) -> dict:
    """A ``mi.load_dict`` entry (registers the plugin and the tables); ``coherent``: render the
    tables' coherent (delta) parts (module docstring); ``lobe_sampling``: ``"auto"`` (an
    anisotropic BTDF samples its anisotropic Beckmann lobe) or ``"isotropic"``
    (:mod:`.sampling`)."""
    if not isinstance(coherent, bool):
        raise ValueError(f"coherent must be True or False, got {coherent!r}")
    if lobe_sampling not in LOBE_SAMPLING:
        raise ValueError(
            f"lobe_sampling must be one of {', '.join(map(repr, LOBE_SAMPLING))}, "
            f"got {lobe_sampling!r}"
        )
    register()
    key = register_dielectric(reflection, transmission, inner)
    out = {"type": PLUGIN_NAME, "tables": key, "coherent": coherent}
    return out if lobe_sampling == "auto" else {**out, "lobe_sampling": lobe_sampling}


def _channels(wavelengths, channels: str) -> np.ndarray:
    if channels == "spectral":  # one channel per table wavelength
        return np.eye(np.size(wavelengths))
    rgb = spectrum_to_rgb_weights(wavelengths)
    return RGB_LUMINANCE[None, :] @ rgb if channels == "mono" else rgb


def _bsdf_class(mi):
    import drjit as dr

    channels = em_mi.channels_of_variant(mi.variant())
    f = mi.BSDFFlags
    sides = f.FrontSide | f.BackSide | f.NonSymmetric
    refl, trans = f.GlossyReflection | sides, f.GlossyTransmission | sides
    d_refl = f.DeltaReflection | f.FrontSide | f.BackSide  # as Mitsuba's ``dielectric``
    d_trans = f.DeltaTransmission | sides

    def tex(cls, a):
        return cls(
            mi.TensorXf(np.ascontiguousarray(a, dtype=np.float32)),
            use_accel=False,
            filter_mode=dr.FilterMode.Linear,
            wrap_mode=dr.WrapMode.Clamp,
        )

    def coord(x, axis: Axis):
        pos = dr.clip((x - axis.start) * (1.0 / axis.step), 0.0, axis.size - 1.0)
        return (pos + 0.5) * (1.0 / axis.size)

    def theta(z):
        return dr.acos(dr.clip(dr.abs(z), 0.0, 1.0))

    def flip(w):
        return mi.Vector3f(w.x, w.y, -w.z)

    class DielectricBSDF(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            key = str(props.get("tables", ""))
            if key not in _SETS:
                raise ValueError(
                    f"emscatter_dielectric plugin: 'tables' must be a key from "
                    f"register_dielectric, got {key!r}"
                )
            s = _SETS[key]
            bt: BtdfTable = s["transmission"]
            mat = _channels(bt.wavelengths, channels)
            self._c = mat.shape[0]
            lam = [float(x) * 1e9 for x in bt.wavelengths]
            self._lam, self._inv = lam, [1.0 / (b - a) for a, b in itertools.pairwise(lam)]
            self._aniso = None
            if isinstance(bt, AnisotropicBtdfTable):  # 4-D: explicit gathers (.aniso)
                self._aniso = AnisoBtdfLookup(mi, bt, mat)  # polarized: also .polarized
            else:
                vals = np.clip(np.moveaxis(np.asarray(bt.values, float), 0, -1) @ mat.T, 0, None)
                self._tex = tex(mi.Texture3f, vals)
            self._ax = [Axis.of(a) for a in _grid_axes(bt)]
            self._eps = float(np.mean(bt.eps))
            self._inv_eps_k = [float(x) for x in 1.0 / np.asarray(bt.eps, dtype=float)]
            self._eta = math.sqrt(self._eps)
            lobe = str(props.get("lobe_sampling", "auto"))  # .sampling.LOBE_SAMPLING
            self._sampler = RefractionSampler(mi, bt, self._eta, lobe)  # the refracted normals
            self._alpha = self._sampler.alpha
            lum = RGB_LUMINANCE @ spectrum_to_rgb_weights(bt.wavelengths)
            p_t = transmission_choice(bt, s["theta_r"], s["r_albedo"], lum)
            self._pt_out = tex(mi.Texture1f, p_t[:, None])
            self._ax_pt = Axis.of(bt.theta_i)
            glossy_only = {"type": "emscatter", "coherent": False}  # deltas: below
            self._refl = mi.load_dict({**glossy_only, "table": s["reflection"]})
            self._inner = None
            if s["inner"] is not None:
                self._inner = mi.load_dict({**glossy_only, "table": s["inner"]})
                p_in = inner_transmission_choice(s["r_in_albedo"], lum)
                self._pt_in = tex(mi.Texture1f, p_in[:, None])
                self._ax_in = Axis.of(s["theta_in"])
            comps = [refl, trans] + ([refl] if self._inner is not None else [])
            self._dd = None
            if bool(props.get("coherent", True)) and self._aniso is None:  # GO: none
                tabs = (s["reflection_table"], bt, s["inner_table"])
                self._dd = delta_data(*tabs, mat, lum, self._eta)
            flags = refl | trans
            if self._dd is not None:  # components 3, 4 (dielectric's 0, 1), 5 (inside)
                d = self._dd
                self._k_dr = len(comps)
                comps = comps + [d_refl, d_trans] + ([d_refl] if d.r_in is not None else [])
                self._tex_r = tex(mi.Texture1f, d.r_out)
                self._tex_tc = tex(mi.Texture1f, d.t_out)
                self._tex_ri = None if d.r_in is None else tex(mi.Texture1f, d.r_in)
                self._tex_po = tex(mi.Texture1f, d.p_out)
                self._tex_pi = tex(mi.Texture1f, d.p_in)
                flags = flags | d_refl | d_trans
            self.m_components = comps
            self.m_flags = flags

        def _spec(self, chans, si, kind=None):
            """Channels → ``kind`` (default ``mi.Spectrum``; the polarized class asks for
            ``mi.UnpolarizedSpectrum``): RGB as is, spectral by hat functions in λ."""
            kind = mi.Spectrum if kind is None else kind
            if channels == "rgb":
                return kind(chans[0], chans[1], chans[2])
            if channels != "spectral":
                return kind(chans[0])
            lam, inv, wl = self._lam, self._inv, si.wavelengths
            if len(lam) == 1:
                return kind(chans[0])
            acc = kind(0.0)
            for k in range(len(lam)):  # hat functions in λ (wavelengths, not angles)
                up = (wl - lam[k - 1]) * inv[k - 1] if k > 0 else None
                down = (lam[k + 1] - wl) * inv[k] if k < len(lam) - 1 else None
                w = up if down is None else (down if up is None else dr.minimum(up, down))
                acc += dr.clip(w, 0.0, 1.0) * chans[k]
            return acc

        def _inv_eps(self, si, kind=None):
            """``1/ε`` at the sampled wavelengths (spectral: hat functions over the table's
            wavelengths, as ``_spec``); the mean ``ε``'s otherwise."""
            if channels != "spectral":
                return 1.0 / self._eps
            return self._spec(self._inv_eps_k, si, kind)

        def _ft(self, a, b, active, si):
            """Table BTDF f_t(a → b), ``a`` above, ``b`` below (no cosine)."""
            if self._aniso is not None:
                return self._spec(self._aniso(a, b, active), si)
            ti, tt = theta(a.z), theta(b.z)
            dphi = dr.abs(dr.atan2(b.y, b.x) - dr.atan2(a.y, a.x))
            dphi = dr.select(dphi > math.pi, 2 * math.pi - dphi, dphi)
            ax = self._ax
            pos = mi.Point3f(coord(dphi, ax[2]), coord(tt, ax[1]), coord(ti, ax[0]))
            return self._spec(self._tex.eval(pos, active), si)

        def _p_t(self, v, active):
            """Probability of sampling transmission for the viewer ``v``."""
            out = v.z > 0
            p_out = self._pt_out.eval(mi.Point1f(coord(theta(v.z), self._ax_pt)), active)[0]
            if self._inner is None:
                return dr.select(out, p_out, 1.0)
            p_in = self._pt_in.eval(mi.Point1f(coord(theta(v.z), self._ax_in)), active)[0]
            return dr.select(out, p_out, p_in)

        def _inner_si(self, si):
            s2 = mi.SurfaceInteraction3f(si)
            s2.wi = flip(si.wi)
            return s2

        def _eval_t(self, ctx, si, wo, active):
            v = si.wi
            out = v.z > 0
            a = dr.select(out, v, wo)  # the direction above
            b = dr.select(out, wo, v)
            val = self._ft(a, b, active, si) * dr.abs(wo.z)
            radiance = ctx.mode == mi.TransportMode.Radiance
            inv = self._inv_eps(si)
            scale = dr.select(out, inv if radiance else 1.0, 1.0 if radiance else inv)
            return val * scale

        def eval(self, ctx, si, wo, active=True):
            v = si.wi
            active = active & (v.z != 0) & (wo.z != 0)
            reflect = v.z * wo.z > 0
            res = mi.Spectrum(0.0)
            if ctx.is_enabled(f.GlossyReflection, 0):
                m = active & reflect & (v.z > 0)
                res = dr.select(m, self._refl.eval(ctx, si, wo, m), res)
            if ctx.is_enabled(f.GlossyTransmission, 1):
                m = active & ~reflect
                res = dr.select(m, self._eval_t(ctx, si, wo, m), res)
            if self._inner is not None and ctx.is_enabled(f.GlossyReflection, 2):
                m = active & reflect & (v.z < 0)
                res = dr.select(m, self._inner.eval(ctx, self._inner_si(si), flip(wo), m), res)
            return res

        def _pdf_t(self, v, wo, active):
            """The refracted lobe's density (:class:`.sampling.RefractionSampler`)."""
            return self._sampler.pdf(v, wo, active)

        def _pdf_glossy(self, ctx, si, wo, active=True):
            v = si.wi
            active = active & (v.z != 0) & (wo.z != 0)
            reflect = v.z * wo.z > 0
            p_t = self._p_t(v, active)
            has_r0 = ctx.is_enabled(f.GlossyReflection, 0)
            has_t = ctx.is_enabled(f.GlossyTransmission, 1)
            p_t = p_t if (has_r0 and has_t) else (1.0 if has_t else 0.0)
            res = mi.Float(0.0)
            if has_r0:
                m = active & reflect & (v.z > 0)
                res = dr.select(m, (1.0 - p_t) * self._refl.pdf(ctx, si, wo, m), res)
            if has_t:
                m = active & ~reflect
                res = dr.select(m, p_t * self._pdf_t(v, wo, m), res)
            if self._inner is not None and ctx.is_enabled(f.GlossyReflection, 2):
                m = active & reflect & (v.z < 0)
                p_in = self._inner.pdf(ctx, self._inner_si(si), flip(wo), m)
                res = dr.select(m, (1.0 - p_t) * p_in, res)
            return res

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def _sample_t(self, v, u):
            """A refracted direction (:class:`.sampling.RefractionSampler`)."""
            return self._sampler.sample(v, u)

        def _sample_glossy(self, ctx, si, sample1, sample2, active=True):
            v = si.wi
            active = active & (v.z != 0)
            has_r0 = ctx.is_enabled(f.GlossyReflection, 0)
            has_t = ctx.is_enabled(f.GlossyTransmission, 1)
            p_t = self._p_t(v, active)
            p_t = p_t if (has_r0 and has_t) else (1.0 if has_t else 0.0)
            pick_t = active & (sample1 < p_t)
            pick_r = active & ~pick_t
            xi = dr.clip((sample1 - p_t) / dr.maximum(1.0 - p_t, 1e-30), 0.0, 1.0)
            bs, w = self._refl.sample(ctx, si, xi, sample2, pick_r & (v.z > 0))
            bs_r, w_r = bs, w / dr.maximum(1.0 - p_t, 1e-30)
            bs_r.pdf = bs.pdf * (1.0 - p_t)
            if self._inner is not None:
                s2 = self._inner_si(si)
                bi, wi_ = self._inner.sample(ctx, s2, xi, sample2, pick_r & (v.z < 0))
                bi.wo = flip(bi.wo)
                inside = v.z < 0
                bs_r.wo = dr.select(inside, bi.wo, bs_r.wo)
                bs_r.pdf = dr.select(inside, bi.pdf * (1.0 - p_t), bs_r.pdf)
                w_r = dr.select(inside, wi_ / dr.maximum(1.0 - p_t, 1e-30), w_r)
                bs_r.sampled_component = dr.select(inside, mi.UInt32(2), mi.UInt32(0))
            wo_t, ok_t, eta = self._sample_t(v, sample2)
            ok_t = pick_t & ok_t & (wo_t.z * v.z < 0)
            pdf_t = p_t * self._pdf_t(v, wo_t, ok_t)
            ok_t = ok_t & (pdf_t > 0)
            w_t = self._eval_t(ctx, si, wo_t, ok_t) / dr.maximum(pdf_t, 1e-30)
            out = dr.zeros(mi.BSDFSample3f)
            out.wo = dr.select(pick_t, wo_t, bs_r.wo)
            out.pdf = dr.select(pick_t, pdf_t, bs_r.pdf)
            out.eta = dr.select(pick_t, eta, 1.0)
            out.sampled_type = dr.select(
                pick_t, mi.UInt32(+f.GlossyTransmission), mi.UInt32(+f.GlossyReflection)
            )
            out.sampled_component = dr.select(pick_t, mi.UInt32(1), bs_r.sampled_component)
            weight = dr.select(pick_t, w_t, w_r)
            valid_r = pick_r & (bs_r.pdf > 0) & (bs_r.wo.z * v.z > 0)
            valid = dr.select(pick_t, ok_t, valid_r)
            if self._inner is None:
                valid = valid & (pick_t | (v.z > 0))
            out.pdf = dr.select(valid, out.pdf, 0.0)
            return out, dr.select(valid, weight, mi.Spectrum(0.0))

        # ------------------------------------------------ delta lobes (.delta)
        def _p_delta(self, ctx, v, active):
            """``(P_δ, P(reflection | δ))`` at the viewer ``v`` for the enabled components."""
            k = self._k_dr
            g = ctx.is_enabled(f.GlossyReflection, 0) or ctx.is_enabled(f.GlossyTransmission, 1)
            g = g or (self._inner is not None and ctx.is_enabled(f.GlossyReflection, 2))
            dt = ctx.is_enabled(f.DeltaTransmission, k + 1)
            out = v.z > 0
            pd, pr = [], []
            for has_r, tex_p, axis in (
                (ctx.is_enabled(f.DeltaReflection, k), self._tex_po, self._dd.ax_po),
                (self._tex_ri is not None and ctx.is_enabled(f.DeltaReflection, k + 2),
                 self._tex_pi, self._dd.ax_pi),
            ):  # fmt: skip
                p = tex_p.eval(mi.Point1f(coord(theta(v.z), axis)), active)
                p_d = p[0] if g else mi.Float(1.0)
                p_r = p[1] if (has_r and dt) else mi.Float(1.0 if has_r else 0.0)
                pd.append(p_d if (has_r or dt) else mi.Float(0.0))
                pr.append(p_r)
            return dr.select(out, pd[0], pd[1]), dr.select(out, pr[0], pr[1])

        def _delta_coh(self, ctx, si, wo, is_r, active, kind=None):
            """The coherent part of a delta sample ``wo`` (the radiance scale included):
            ``R_coh`` (``is_r``) or ``T_coh``, as ``kind`` (default ``mi.Spectrum``)."""
            v = si.wi
            out = v.z > 0
            d = self._dd

            def look(t, axis, z, m):
                return self._spec(t.eval(mi.Point1f(coord(theta(z), axis)), m), si, kind)

            f_r = mi.fresnel(v.z, self._eta)[0]  # ratios × Fresnel (.delta)
            r = look(self._tex_r, d.ax_r, v.z, active & is_r & out)
            if self._tex_ri is not None:
                r = dr.select(out, r, look(self._tex_ri, d.ax_ri, v.z, active & is_r & ~out))
            r = r * f_r
            t = look(self._tex_tc, d.ax_t, dr.select(out, v.z, wo.z), active & ~is_r)
            t = t * (1.0 - f_r)
            if ctx.mode == mi.TransportMode.Radiance:  # dielectric's η_ti²
                inv = self._inv_eps(si, kind)
                t = t * dr.select(out, inv, 1.0 / inv)
            return dr.select(is_r, r, t)

        def _delta_weight(self, ctx, si, wo, is_r, active):
            return self._delta_coh(ctx, si, wo, is_r, active)

        def pdf(self, ctx, si, wo, active=True):
            p = self._pdf_glossy(ctx, si, wo, active)
            if self._dd is None:
                return p
            return p * (1.0 - self._p_delta(ctx, si.wi, active)[0])

        def sample(self, ctx, si, sample1, sample2, active=True):
            if self._dd is None:
                return self._sample_glossy(ctx, si, sample1, sample2, active)
            v = si.wi
            active = active & (v.z != 0)
            p_d, p_r = self._p_delta(ctx, v, active)
            pick_d = active & (sample1 < p_d)
            xi = dr.clip((sample1 - p_d) / dr.maximum(1.0 - p_d, 1e-30), 0.0, 1.0)
            bs, w = self._sample_glossy(ctx, si, xi, sample2, active & ~pick_d)
            bs.pdf = bs.pdf * (1.0 - p_d)
            w = w / dr.maximum(1.0 - p_d, 1e-30)
            is_r = sample1 < p_d * p_r
            out = v.z > 0
            wo_t, ok_t, eta_it = refract(mi, dr, v, self._eta)
            wo_d = dr.select(is_r, mi.Vector3f(-v.x, -v.y, v.z), wo_t)
            prob = p_d * dr.select(is_r, p_r, 1.0 - p_r)
            ok_d = pick_d & (is_r | ok_t) & (prob > 0)
            w_d = self._delta_weight(ctx, si, wo_d, is_r, ok_d) / dr.maximum(prob, 1e-30)
            k = self._k_dr
            bs.wo = dr.select(pick_d, wo_d, bs.wo)
            bs.pdf = dr.select(pick_d, dr.select(ok_d, prob, 0.0), bs.pdf)
            bs.eta = dr.select(pick_d, dr.select(is_r, 1.0, eta_it), bs.eta)
            t_d = dr.select(is_r, mi.UInt32(+f.DeltaReflection), mi.UInt32(+f.DeltaTransmission))
            bs.sampled_type = dr.select(pick_d, t_d, bs.sampled_type)
            c_d = dr.select(is_r, dr.select(out, mi.UInt32(k), mi.UInt32(k + 2)), k + 1)
            bs.sampled_component = dr.select(pick_d, c_d, bs.sampled_component)
            w = dr.select(pick_d, dr.select(ok_d, w_d, dr.zeros(mi.Spectrum)), w)
            return bs, w

        def traverse(self, callback):
            pass

        def to_string(self):
            ax, ay = self._sampler.alpha_xy
            a = f"αx = {ax:.4g}, αy = {ay:.4g}" if self._sampler.anisotropic else ""
            return (
                f"EmscatterDielectricBSDF[η = {self._eta:.6g}, {a or f'α = {self._alpha:.4g}'}, "
                f"delta lobes={self._dd is not None}]"
            )

    if "polarized" in mi.variant():
        from .polarized import polarized_dielectric_class

        return polarized_dielectric_class(mi, DielectricBSDF, coord, theta, _SETS)
    return DielectricBSDF
