"""What the ``"emscatter_dielectric"`` plugin (:mod:`.plugin`) samples: the reflect/refract
choice probabilities and the refracted lobe's microfacet normals, with its exact pdf.

Reflection vs transmission by their albedos at the viewer's θ (outside: ``R`` of the
reflection table, ``T`` of the BTDF table, both exact integrals of the interpolants; inside:
``R_in`` of ``inner`` and ``1 − R_in``, at least 2 % transmission): :func:`transmission_choice`.

The transmission by Beckmann microfacet normals refracted (Walter et al. 2007, eqs. 17, 28,
40: ``p(wo) = D(m) cosθm |wo·m| η_o² / (η_i v·m + η_o wo·m)²``) with the table's slope
variance (``α² = 2s``): :class:`RefractionSampler`, whose ``pdf`` is that density exactly.
Tables with a coherent transmission (PO/SPM) draw half the normals from a wide Beckmann lobe
(α = :data:`ALPHA_WIDE`, a defensive mixture; the pdf is the mixture's).

Anisotropic tables (:class:`~emscatter.brdf.btdf_aniso.AnisotropicBtdfTable` with ``s_x ≠
s_y``) draw their normals from the anisotropic Beckmann distribution of their slopes, ``αx =
√(2 s_x)`` along the local ``+x`` (the shading frame's tangent, the table's ``ℓx`` direction,
:mod:`.aniso`), ``αy = √(2 s_y)`` along ``+y`` — Mitsuba's anisotropic ``roughdielectric``
with ``alpha_u = αx``, ``alpha_v = αy`` (Walter et al. 2007 eq. 25's anisotropic form, Heitz
2014 eq. 87): the slopes ``(p_x, p_y) = −(m_x, m_y)/m_z`` are Gaussian with variances ``(s_x,
s_y)``, drawn by Box–Muller, ``p = (αx r cos 2πu₂, αy r sin 2πu₂)``, ``r = √(−ln(1 − u₁))``,
with the density ``D(m) = exp(−p_x²/αx² − p_y²/αy²) / (π αx αy cos⁴θm)``. The isotropic
``α = √(s_x + s_y)`` wastes samples on such a lobe (``ℓy = 4ℓx``: the weights' variance
``tests/test_render_dielectric_sampling.py`` reports). ``lobe_sampling="isotropic"`` keeps the
isotropic lobe for every table (the sampler before anisotropic tables had their own).

The anisotropic lobe's ``pdf`` is zero where the microfacet and the macro-surface disagree on
a direction's side (``(v·m) v_z ≤ 0`` or ``(wo·m) wo_z ≤ 0``: Smith's ``χ⁺``, where ``f = 0``;
Mitsuba's ``roughdielectric`` filters the same), so a sample there is invalid rather than of
weight 0 and ``pdf`` is the density of the samples that carry weight (Mitsuba's χ² test,
which drops zero-weight samples, needs this near grazing transmission). The isotropic lobe
keeps its pdf bit for bit (it reports ``pdf > 0`` with weight 0 there; renders are the same).
"""

from __future__ import annotations

import math

import numpy as np

from ...brdf.btdf_aniso import AnisotropicBtdfTable
from .aniso import reduce_albedo

__all__ = [
    "ALPHA_WIDE",
    "LOBE_SAMPLING",
    "RefractionSampler",
    "inner_transmission_choice",
    "transmission_choice",
]

ALPHA_WIDE = 0.5  # Beckmann α of the defensive transmission sampler (PO/SPM tables)
LOBE_SAMPLING = ("auto", "isotropic")  # the plugin's ``lobe_sampling`` values


def transmission_choice(bt, theta_r, r_albedo, lum) -> np.ndarray:
    """Probability of sampling transmission from outside at the BTDF's ``θi`` nodes: ``T/(T +
    R)`` with the luminance-weighted albedos (``r_albedo``: ``(n_wl, n_θr)`` on ``theta_r``)."""
    aniso = isinstance(bt, AnisotropicBtdfTable)
    t_alb = lum @ (
        reduce_albedo(bt.albedo()) if aniso else bt.incoherent_albedo()
    )  # what the lobe holds (PO: no delta lobe)
    r_alb = np.interp(bt.theta_i, theta_r, lum @ r_albedo)
    return t_alb / np.maximum(t_alb + r_alb, 1e-12)


def inner_transmission_choice(r_in_albedo, lum) -> np.ndarray:
    """Probability of sampling transmission from inside: ``1 − R_in``, in ``[0.02, 1]``."""
    r_in = np.clip(lum @ r_in_albedo, 0.0, 1.0)
    return np.clip(1.0 - r_in, 0.02, 1.0)


class RefractionSampler:
    """Refracted directions through Beckmann microfacet normals and their pdf in Dr.Jit
    (module docstring). ``bt``: the BTDF table (its ``metadata["slope_variance"]`` and
    coherent part), ``eta``: the mean refractive index used for the refraction frame,
    ``lobe_sampling``: ``"auto"`` (anisotropic tables: their anisotropic lobe) or
    ``"isotropic"`` (:data:`LOBE_SAMPLING`, module docstring)."""

    def __init__(self, mi, bt, eta: float, lobe_sampling: str = "auto"):
        if lobe_sampling not in LOBE_SAMPLING:
            raise ValueError(
                f"lobe_sampling must be one of {', '.join(map(repr, LOBE_SAMPLING))}, "
                f"got {lobe_sampling!r}"
            )
        self._mi = mi
        self.eta = float(eta)
        sx, sy = (float(x) for x in bt.metadata["slope_variance"])
        if not (sx > 0 and sy > 0 and math.isfinite(sx + sy)):
            raise ValueError(
                f"the BTDF table's metadata['slope_variance'] must be two positive finite "
                f"numbers (s_x, s_y), got {(sx, sy)}"
            )
        self.alpha = math.sqrt(sx + sy)  # Beckmann α² = 2s (isotropic: s = (sx + sy)/2)
        self.anisotropic = (
            isinstance(bt, AnisotropicBtdfTable) and sx != sy and lobe_sampling == "auto"
        )
        self.alpha_xy = (math.sqrt(2 * sx), math.sqrt(2 * sy))  # along +x (ℓx), +y
        # PO/SPM tables (a coherent part): their glossy lobe is wider than the slopes say
        # (SPM: the roughness spectrum at the Bragg wavenumbers), so half the refracted
        # normals come from a wide Beckmann lobe (defensive mixture; GO tables: none)
        coh = getattr(bt, "coherent", None)
        has_coh = coh is not None and bool(np.any(coh > 0))
        self.q_wide = 0.5 if has_coh and self.alpha < ALPHA_WIDE else 0.0

    def pdf(self, v, wo, active):
        """Walter et al. 2007 eq. 17 × the Beckmann normal density (module docstring)."""
        import drjit as dr

        out = v.z > 0
        n_i = dr.select(out, 1.0, self.eta)
        n_o = dr.select(out, self.eta, 1.0)
        m = dr.normalize(-(n_i * v + n_o * wo))
        m = dr.mulsign(m, m.z)
        vm, om = dr.dot(v, m), dr.dot(wo, m)
        ok = active & (vm * om < 0) & (m.z > 1e-7)
        if self.anisotropic:  # micro- and macro-surface agree on the sides: else f = 0
            ok = ok & (vm * v.z > 0) & (om * wo.z > 0)  # (Smith's χ⁺; roughdielectric's)
        c2 = dr.square(m.z)
        if self.anisotropic:  # D(m) of the slopes p = −(m_x, m_y)/m_z (module docstring)
            ax, ay = self.alpha_xy
            e = (dr.square(m.x) * (1 / ax**2) + dr.square(m.y) * (1 / ay**2)) / c2
            d = dr.exp(-e) / (math.pi * ax * ay * dr.square(c2))
        else:
            a2 = self.alpha**2
            d = dr.exp(-(1.0 - c2) / (c2 * a2)) / (math.pi * a2 * dr.square(c2))
        if self.q_wide:  # the defensive wide normals (``__init__``)
            q, w2 = self.q_wide, ALPHA_WIDE**2
            d_w = dr.exp(-(1.0 - c2) / (c2 * w2)) / (math.pi * w2 * dr.square(c2))
            d = (1.0 - q) * d + q * d_w
        jac = dr.square(n_o) * dr.abs(om) / dr.maximum(dr.square(n_i * vm + n_o * om), 1e-30)
        return dr.select(ok, d * m.z * jac, 0.0)

    def sample(self, v, u):
        """A refracted direction through a Beckmann normal (Walter et al. 2007 eq. 28):
        ``(wo, ok, η_o/η_i)``."""
        import drjit as dr

        mi = self._mi
        if self.anisotropic:
            return self._refract(v, self._aniso_normal(u))
        a2 = self.alpha**2
        if self.q_wide:  # the defensive wide normals with probability q
            q = self.q_wide
            wide = u.x < q
            u = mi.Point2f(dr.select(wide, u.x / q, (u.x - q) / (1.0 - q)), u.y)
            a2 = dr.select(wide, ALPHA_WIDE**2, a2)
        tan2 = -a2 * dr.log(dr.maximum(1.0 - u.x, 1e-30))
        c = dr.rsqrt(1.0 + tan2)
        s = dr.sqrt(dr.maximum(1.0 - c * c, 0.0))
        sp, cp = dr.sincos(2 * math.pi * u.y)
        m = mi.Vector3f(cp * s, sp * s, c)
        return self._refract(v, m)

    def _aniso_normal(self, u):
        """An anisotropic Beckmann normal by Box–Muller in slope space (module docstring),
        the wide isotropic lobe with probability ``q_wide``."""
        import drjit as dr

        mi = self._mi
        ax, ay = self.alpha_xy
        if self.q_wide:
            q = self.q_wide
            wide = u.x < q
            u = mi.Point2f(dr.select(wide, u.x / q, (u.x - q) / (1.0 - q)), u.y)
            ax = dr.select(wide, ALPHA_WIDE, ax)
            ay = dr.select(wide, ALPHA_WIDE, ay)
        r = dr.sqrt(-dr.log(dr.maximum(1.0 - u.x, 1e-30)))
        sp, cp = dr.sincos(2 * math.pi * u.y)
        return dr.normalize(mi.Vector3f(ax * r * cp, ay * r * sp, 1.0))

    def _refract(self, v, m):
        """``v`` refracted through the normal ``m``: ``(wo, ok, η_o/η_i)``."""
        import drjit as dr

        out = v.z > 0
        eta = dr.select(out, self.eta, 1.0 / self.eta)  # n_o / n_i
        vm = dr.dot(v, m)
        k = 1.0 - (1.0 - vm * vm) / (eta * eta)
        ok = (k > 0) & (vm * v.z > 0)
        wo = m * (vm / eta - dr.mulsign(dr.sqrt(dr.maximum(k, 0.0)), vm)) - v / eta
        return dr.normalize(wo), ok, eta
