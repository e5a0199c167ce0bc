"""A wall as a slab with rough faces: coherent reflection and transmission (NumPy reference).

Sionna RT models a wall as one surface with a thickness ``d`` and uses the single-layer slab of
ITU-R P.2040-3 (eqs. 43–44; ``exp(+jωt)``). In emscatter's ``exp(−iωt)`` it reads, with the
flat-interface Fresnel coefficient ``r`` (:mod:`emscatter.fresnel`) and ``q = k d √(ε − sin²θ)``::

    R = r (1 − e^{2iq}) / (1 − r² e^{2iq})            T = (1 − r²) e^{iq} / (1 − r² e^{2iq})

That is the ray sum of a slab whose front face reflects ``r`` from outside and ``r′ = −r``
from inside, transmits ``t t′ = 1 − r²`` per crossing pair, and whose back face is the same
interface: ``R = r + t t′ r′ e^{2iq} / (1 − r′² e^{2iq})``, ``T = t t′ e^{iq} / (1 − r′² e^{2iq})``.

Rough faces (both faces carry the same roughness statistics — a wall modelled as one surface is
hit from either side, and each side is "the front" for the rays that hit it):

* the wave reflected outside the front face is emscatter's coherent reflection
  ``r_coh`` (:func:`emscatter.coherent.coherent_amplitude`: the chosen solver's coherent
  power with its mean-field phase);
* each crossing of a rough face keeps the Kirchhoff mean field
  ``χ_t = exp(−σ²(k₁z − k₂z)²/2)`` (``t t′ → (1 − r²) χ_t²``);
* each internal reflection at a rough face keeps ``χ_i = exp(−2σ² k₂z²)`` with the vertical
  wavenumber inside, ``k₂z = k √(ε − sin²θ)`` (``r′ → −r χ_i``).

``k₁z = k cosθ``. With complex ``k₂z`` (loss) these Gaussian averages can exceed 1 in magnitude
where ``Re(k²) < 0`` of their argument; a passive mean field cannot grow, so the real part of the
exponent is clipped at 0 there (only the phase is kept). The power that leaves the coherent
field is scattered diffusely: the diffuse *reflection* from the front face is emscatter's σ⁰ of
the half-space (the material's lobe); diffuse *transmission* and diffuse light from the back face
are not modelled here (nor in Sionna's material model): the radio material's
``transmission="diffuse"`` adds them from :mod:`emscatter.radio.slab_diffuse`.

``thickness=None`` is a half-space (a thick or lossy wall, the ground): ``R = r_coh``,
``T = 0``. With σ = 0 and ``front = r`` everything reduces exactly to the ITU formulas above
(tested against Sionna's own ``itu_coefficients_single_layer_slab``).
"""

from __future__ import annotations

import numpy as np

from ..fresnel import fresnel_cos

__all__ = ["gaussian_mean_field", "slab_coefficients"]


def gaussian_mean_field(q2, sigma: float):
    """``⟨e^{iqh}⟩ = exp(−q²σ²/2)`` for Gaussian heights of rms ``sigma`` [m] and a complex
    ``q²`` [rad²/m²], with the real part of the exponent clipped at 0 (module docstring)."""
    q2 = np.asarray(q2, dtype=complex)
    expo = -0.5 * sigma * sigma * q2
    return np.exp(np.minimum(expo.real, 0.0) + 1j * expo.imag)


def slab_coefficients(eps, cos_theta, k: float, thickness, *, sigma: float = 0.0, front=None):
    """Coherent ``(R_h, R_v, T_h, T_v)`` of a slab (module docstring), ``exp(−iωt)``.

    Parameters
    ----------
    eps : relative permittivity (``Im ε ≥ 0``).
    cos_theta : incidence cosine(s) ∈ [0, 1].
    k : free-space wavenumber [rad/m].
    thickness : slab thickness [m], or ``None`` for a half-space.
    sigma : rms height of both faces [m] (0: flat).
    front : ``(2, ...)`` complex coherent reflection of the front face from outside (h, v);
        default: the flat Fresnel coefficients.
    """
    c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
    eps = complex(eps)
    rh, rv = fresnel_cos(eps, c)
    r0 = np.stack([rh, rv])
    r1 = r0 if front is None else np.asarray(front, dtype=complex)
    if thickness is None:
        zero = np.zeros_like(r1)
        return r1[0], r1[1], zero[0], zero[1]
    root = np.sqrt(eps - (1.0 - c * c) + 0j)
    root = np.where(root.imag < 0, -root, root)
    k1z, k2z = k * c, k * root
    chi_t = gaussian_mean_field((k1z - k2z) ** 2, sigma)
    chi_i = gaussian_mean_field(4.0 * k2z * k2z, sigma)  # exp(−2σ²k₂z²)
    r_in = -r0 * chi_i
    ph = np.exp(1j * k * thickness * root)
    den = 1.0 - r_in * r_in * ph * ph
    tt = (1.0 - r0 * r0) * chi_t * chi_t
    big_r = r1 + tt * r_in * ph * ph / den
    big_t = tt * ph / den
    return big_r[0], big_r[1], big_t[0], big_t[1]
