"""Height maps of a roughness whose spectrum is cut off above ``|K| = K_c``: the surfaces of
:func:`~emscatter.solvers.mom3d.bistatic`'s ``spectral_cutoff``.

A correlation whose spectrum decays only as a power of ``K`` (the exponential's
``w ∝ (1 + K²ℓ²)^(−3/2)``, ``K⁻³``) has roughness at every scale: each finer grid samples a
rougher surface (its slope variance grows as ``1/Δx``), and the pulse-basis MFIE on it does
not converge (the energy of a perfect conductor falls with the grid: 0.936 → 0.895 from 8 to
16 points/λ for the exponential kσ = 0.3, kℓ = 3; ``validation/mom3d/exponential_convergence.md``).
A band-limited surface converges instead (the approach of the numerical-Maxwell simulations of
exponential soils, Huang, Tsang, Njoku & Chen 2010, IEEE TGRS, "Backscattering coefficients,
coherent reflectivities and emissivities of randomly rough soil surfaces at L-band …"): the
spectrum is kept below ``K_c`` and zeroed above, so that a fine enough grid resolves every
scale of the surface.

Method: periodic spectral synthesis (Tsang, Kong, Ding & Ao 2001, *Scattering of
Electromagnetic Waves: Numerical Simulations*, ch. 4; the ``"fft-periodic"``
method of :mod:`emscatter.surfaces.generate` without its variance rescaling) of period ``pad``
times the patch per axis, wavenumbers ``K = 2π m / (pad · n Δx)``:
``h(r) = √2 Re Σ_K √(σ² w(K) ΔK²) z_K e^{iK·r}`` with ``z_K`` independent standard complex
normals, ``w(K) = 0`` for ``|K| > K_c`` and at ``K = 0``; the patch is the first ``n × n``
block. The ``z_K`` are drawn over the lattice square ``|K_x|, |K_y| ≤ K_c`` in a fixed order,
independent of the grid: one seed and period give the same continuous surface at every
points per wavelength (sampled, not redrawn: a grid-convergence study compares like with like).
The field is exactly stationary and Gaussian with covariance
``Σ_K σ² w(K) ΔK² cos(K·Δr)``: the target's spectrum below ``K_c`` (sampled at ``ΔK``) and
nothing above. Its variance (:func:`cutoff_variance`, ``σ_c²``) is the target's minus the
removed tail; for the isotropic exponential the continuous value is
``σ_c² = σ² (1 − 1/√(1 + K_c² ℓ²))``. First-order SPM at Bragg wavenumbers below ``K_c`` sees
exactly the target's spectrum.
"""

from __future__ import annotations

import math

import numpy as np

from emscatter.conventions import check_positive, fmt

__all__ = ["check_cutoff", "cutoff_variance", "exponential_cutoff_variance", "truncated_heights"]

#: Periodic synthesis grid per axis, in patch sides (long-wavelength sampling ΔK = 2π/(4L)).
PAD = 4


def check_cutoff(cutoff, spacing: float) -> float | None:
    """``cutoff`` [rad/m] checked: None, or positive and no more than the grid's Nyquist
    wavenumber ``π/spacing`` (else ValueError naming it)."""
    if cutoff is None:
        return None
    kc = check_positive("spectral_cutoff", cutoff, unit="rad/m")
    nyq = math.pi / spacing
    if kc > nyq:
        raise ValueError(
            f"spectral_cutoff={fmt(kc)} rad/m is above the grid's Nyquist wavenumber "
            f"π/Δx = {fmt(nyq)} rad/m (Δx = {fmt(spacing)} m): give a cutoff ≤ π/Δx or a "
            "denser grid"
        )
    return kc


def _modes(roughness, period: float, cutoff: float):
    """The kept lattice modes: integer indices ``(my, mx)`` of ``K = 2π m / period`` over the
    square ``|m| ≤ M`` (fixed order, a function of ``M`` only), and ``σ² w(K) ΔK²`` (zero
    outside ``|K| ≤ K_c`` and at ``K = 0``)."""
    dk = 2 * math.pi / period
    big = int(math.floor(cutoff / dk))
    mv = np.arange(-big, big + 1)
    mx, my = np.meshgrid(mv, mv)
    kx, ky = mx * dk, my * dk
    s = roughness.sigma**2 * roughness.spectrum(kx, ky) * dk * dk
    s[np.hypot(kx, ky) > cutoff] = 0.0
    s[big, big] = 0.0
    return my, mx, s


def cutoff_variance(roughness, n: int, spacing: float, cutoff: float, pad: int = PAD) -> float:
    """Variance [m²] of :func:`truncated_heights`' surfaces (exact: the sum of the kept
    modes ``Σ σ² w(K) ΔK²`` of the period ``pad · n · spacing``)."""
    return float(_modes(roughness, pad * n * spacing, cutoff)[2].sum())


def exponential_cutoff_variance(sigma: float, length: float, cutoff: float) -> float:
    """``σ² (1 − 1/√(1 + K_c² ℓ²))`` [m²]: the variance of the isotropic 2-D exponential
    spectrum ``w = ℓ²/(2π) (1 + K²ℓ²)^(−3/2)`` kept below ``K_c`` (∫₀^{K_c} 2πK w dK)."""
    return sigma**2 * (1.0 - 1.0 / math.sqrt(1.0 + (cutoff * length) ** 2))


def truncated_heights(
    roughness, n: int, spacing: float, cutoff: float, rng: np.random.Generator, pad: int = PAD
) -> np.ndarray:
    """One ``(n, n)`` height map [m] of ``roughness`` (2-D, stationary) with its spectrum
    zeroed above ``cutoff`` [rad/m] (module docstring), drawn from ``rng``."""
    if getattr(roughness, "dimension", None) != 2:
        raise ValueError(
            f"spectral_cutoff needs a 2-D roughness, got dimension="
            f"{getattr(roughness, 'dimension', None)!r}"
        )
    kc = check_cutoff(cutoff, spacing)
    my, mx, s = _modes(roughness, pad * n * spacing, kc)
    z = rng.standard_normal(s.shape) + 1j * rng.standard_normal(s.shape)  # E|z|² = 2
    m = pad * n
    spec = np.zeros((m, m), dtype=complex)
    np.add.at(spec, (my % m, mx % m), np.sqrt(s) * z)  # |m| = m/2 (Nyquist): both alias
    f = np.fft.ifft2(spec) * (m * m)
    return np.ascontiguousarray(f.real[:n, :n])  # Re: variance ½·2·Σ s = Σ s
