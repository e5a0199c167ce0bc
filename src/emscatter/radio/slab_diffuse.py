"""Diffuse transmission through a rough slab and its energy budget per incidence (NumPy).

A wall of thickness ``d`` [m] and permittivity ``ε`` (``exp(−iωt)``, ``Im ε ≥ 0``) whose two
faces carry the same isotropic roughness. Per incidence ``θi`` from air and incident
polarization ``p`` (h, v) the incident power splits into::

    R_coh + R_diff + T_coh + T_diff + A (+ L) = 1

* ``R_coh, T_coh`` — the coherent slab of :mod:`emscatter.radio.slab` (``|R|², |T|²``; with
  σ = 0 exactly ITU-R P.2040-3 eqs. 43–44, i.e. Sionna RT's slab).
* ``R_diff`` — power scattered diffusely back into the incidence side: the front face's
  diffuse reflection plus the diffuse light that leaves the slab through the front face after
  crossing it; ``T_diff`` — diffuse power leaving through the back face.
* ``A`` — power absorbed in the slab, summed crossing by crossing (below), not taken as the
  remainder; ``L`` — power lost by the faces' single-scattering model (shadowed facets: the
  deficit ``1 − R − T`` of Walter et al. 2007, documented in
  :mod:`emscatter.solvers.kirchhoff.transmission.go`). With ``conserve=True`` (default) each
  face's diffuse rows are scaled to ``R + T = 1`` (the deficit returned to the lobes in
  proportion, recorded as ``face_deficit``), so ``L = 0``.

Face models (``face=``, :data:`~emscatter.radio.slab_faces.FACES`). ``"go"``: geometric
optics, Walter, Marschner, Li & Torrance, EGSR 2007 (eqs. 16, 21, 23, 25, 27) for transmission
(:func:`~emscatter.solvers.kirchhoff.transmission.go.bistatic_transmission`) and
emscatter's GO reflection (:func:`emscatter.solvers.kirchhoff.go.bistatic`), both with the real
part of ``ε`` (a low-loss face; the loss acts in the bulk). From inside, a face is
the interface to air with ``ε_rel = 1/Re ε`` (total internal reflection included). GO holds
only for ``(2kσ)² ≥ 10`` and ``kℓ ≥ 6`` (:func:`emscatter.solvers.kirchhoff.go.check_validity`);
there the Kirchhoff mean field is ``< e⁻⁵`` and the coherent terms are negligible (taken off
the incident power at the entrance, ``keep`` below). ``"spm"``, ``"po"``, ``"iem"``: the
small and medium roughness of common walls (the 28 GHz brick wall, kσ = 0.47), where the
coherent slab keeps most of the power; :mod:`emscatter.radio.slab_faces` builds their kernels
from the solvers' transmitted and reflected σ⁰ (complex ε from air) and feeds the transport
below with what the coherent field loses at each face, so nothing is counted twice.
``"auto"`` (default) takes GO where it holds (this GO path, bit for bit), else the first of SPM,
PO, IEM whose validity holds. Outside the chosen model's validity
:func:`diffuse_transmission` refuses (``out_of_range="raise"``, the default) or carries on
(``"warn"``/``"ignore"``, the result then only indicative).

Transport inside (radiative, incoherent): the diffuse power inside is tracked per internal
direction cosine ``μ`` (Gauss–Legendre nodes on (0, 1)), azimuth-integrated (exact for the
power fluxes of isotropic faces: only the azimuthal mean of a redistribution kernel moves
hemispherical power) and unpolarized after the first face (the mean of the two incident
polarizations; the first face is polarization-resolved). One crossing of the slab keeps::

    a(μ) = exp(−2 d Im k₂z),    k₂z = k √(ε − Re ε (1 − μ²))      (≈ exp(−2αd/cosθt))

with ``k`` the free-space wavenumber: the vertical wavenumber of an internal wave whose
transverse wavenumber is ``k √Re ε sinθt``. With ``x₀`` the power per node after the front
face and ``P = diag(a) K_r`` (``K_r`` the internal-reflection kernel), crossing ``n`` carries
``x_n = x₀ Pⁿ``; even crossings end on the back face (``T_diff``), odd ones on the front face
(``R_diff``): ``T = x₀ (I − P²)⁻¹ diag(a) t_out``, ``R_int = x₀ P (I − P²)⁻¹ diag(a) t_out``,
``A = x₀ (I − P)⁻¹ (1 − a)`` (``t_out`` the per-node escape fraction).

With ``n_modes > 0`` the azimuthal Fourier modes of both escaping lobes are kept: the
transmitted one (:meth:`DiffuseTransmission.transmitted_lobe`) and the internal light that leaves
through the front face (the odd crossings, :meth:`DiffuseTransmission.internal_reflection_lobe`,
powers ``r_lobe``); the radio material's ``transmission="diffuse"`` tables read both
(:mod:`emscatter.radio.transmission_tables`).

The flat limit (``surface=None`` or σ = 0): ``R_diff = T_diff = 0``, ``T_coh, R_coh`` the ITU
slab, ``A = 1 − R_coh − T_coh`` (Poynting's theorem for the slab).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..conventions import wavenumber
from ..fresnel import fresnel_cos
from ..spectra import check_roughness
from .medium import check_thickness
from .slab import gaussian_mean_field, slab_coefficients
from .slab_faces import check_face, choose_face, rough_face_budget
from .tables import RadioValidityWarning, check_policy

__all__ = ["DiffuseTransmission", "diffuse_transmission", "face_kernels"]


@dataclass(frozen=True)
class DiffuseTransmission:
    """Per-incidence power budget of a rough slab (module docstring). Arrays are ``(2, n)``
    over ``(pol_i, theta)`` [-] (fractions of the incident power); angles [rad]."""

    theta: np.ndarray
    frequency: float
    eps: complex
    thickness: float
    r_coh: np.ndarray
    r_diff: np.ndarray
    t_coh: np.ndarray
    t_diff: np.ndarray
    absorbed: np.ndarray
    lost: np.ndarray
    flat: bool
    valid: bool
    reasons: list = field(default_factory=list)
    face_deficit: np.ndarray | None = None  # (2, n) external-face 1 − R − T before scaling
    t_lobe: np.ndarray | None = None  # (2, n, n_mu) T_diff per air cosine node (sum = t_diff)
    mu_nodes: np.ndarray | None = None  # air-side cosine nodes of t_lobe
    mu_weights: np.ndarray | None = None
    t_modes: np.ndarray | None = None  # (2, n, n_mu, M + 1) azimuthal modes of t_lobe
    r_lobe: np.ndarray | None = None  # (2, n, n_mu) internal diffuse light out of the front face
    r_modes: np.ndarray | None = None  # (2, n, n_mu, M + 1) azimuthal modes of r_lobe
    face: str = "go"  # the face model used (``face=`` of diffuse_transmission, resolved)
    source_scale: np.ndarray | None = None  # (2, n) SPM/PO/IEM faces (radio.slab_faces)

    def transmitted_lobe(self, phi) -> np.ndarray:
        """Diffusely transmitted power per unit solid angle [1/sr], ``(2, n, n_mu, n_phi)``
        over ``(pol_i, θi, μ node, φ)``, at azimuths ``phi`` [rad] from the plane of incidence
        (``φ = 0``: forward): ``Σ_m (2 − δ_m0) T_m cos(mφ) / (2π w_j)``; its integral over
        the back hemisphere is ``t_diff`` (needs ``n_modes > 0``)."""
        return self._lobe(self.t_modes, phi)

    def internal_reflection_lobe(self, phi) -> np.ndarray:
        """The part of ``r_diff`` that crossed the slab and left through the front face (not
        the front face's own diffuse reflection), per unit solid angle [1/sr], as
        :meth:`transmitted_lobe` (``φ = 0``: the specular side); integral: ``r_lobe`` summed."""
        return self._lobe(self.r_modes, phi)

    def _lobe(self, modes, phi):
        if modes is None:
            raise ValueError("no azimuthal modes: call diffuse_transmission(..., n_modes=M > 0)")
        ph = np.atleast_1d(np.asarray(phi, dtype=float))
        m = np.arange(modes.shape[-1])
        basis = np.where(m == 0, 1.0, 2.0)[:, None] * np.cos(m[:, None] * ph[None, :])
        lobe = modes @ basis / (2.0 * math.pi)
        return lobe / self.mu_weights[None, None, :, None]

    @property
    def total(self) -> np.ndarray:
        """``R_coh + R_diff + T_coh + T_diff + A + L`` (2, n): 1 within the quadrature error."""
        return self.r_coh + self.r_diff + self.t_coh + self.t_diff + self.absorbed + self.lost


def _gauss01(n: int):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _gauss01_split(n: int, cut: float):
    """Gauss–Legendre nodes on (0, cut) and (cut, 1), ``n`` in all in proportion to the lengths
    (at least 2 each): the inside faces' coherent refraction has a kink at the critical
    cosine ``cut`` (total internal reflection beyond), which one rule converges on slowly."""
    n1 = min(max(int(round(n * cut)), 2), n - 2)
    x1, w1 = _gauss01(n1)
    x2, w2 = _gauss01(n - n1)
    mu = np.concatenate([cut * x1, cut + (1 - cut) * x2])
    return mu, np.concatenate([cut * w1, (1 - cut) * w2])


def face_kernels(rough, eps_rel: float, k: float, cos_in, mu, w_mu, n_phi: int, n_modes=0):
    """GO kernels of one face for incidence cosines ``cos_in``, per azimuthal Fourier mode.

    Returns ``(K_r, K_t)`` of shape ``(n_modes + 1, 2, n_in, n_mu)`` [-]: mode ``m`` of the
    power per unit incident power of polarization ``p`` scattered into the reflected
    (transmitted) cosine node ``j``, summed over the scattered polarizations:
    ``K_m[p, i, j] = w_j ∫₀^{2π} Σ_q σ⁰_qp(θi, θj, φ) cos(mφ) / (4π cosθi) dφ`` (Walter et al.
    2007 eq. 21 for transmission; emscatter GO for reflection); ``m = 0`` is the power into
    node ``j``. Kernels of isotropic faces depend on ``φ`` only through the azimuth difference,
    so a chain of faces multiplies its modes (the convolution theorem). ``eps_rel`` is real.
    """
    from ..solvers.kirchhoff import go
    from ..solvers.kirchhoff.transmission.go import bistatic_transmission

    xp, wp = np.polynomial.legendre.leggauss(n_phi)
    phi = 0.5 * math.pi * (xp + 1.0)  # (0, π): isotropic lobes are mirror-symmetric in φ
    wphi = 0.5 * math.pi * wp  # ×2 for (π, 2π) below
    cosm = np.cos(np.arange(n_modes + 1)[:, None] * phi[None, :]) * wphi  # (M + 1, n_phi)
    ti = np.arccos(np.clip(cos_in, 0.0, 1.0))[:, None, None]
    tj = np.arccos(mu)[None, :, None]
    ph = phi[None, None, :]
    out = []
    for kind in ("r", "t"):
        if kind == "r":
            s = go.bistatic(rough, eps_rel, k, ti, tj, ph, coherent=False)
        else:
            s = bistatic_transmission(rough, eps_rel, k, ti, tj, ph)
        sig = s.sigma0.sum(axis=0)  # (p, i, j, φ): summed over scattered polarizations
        ker = 2.0 * np.einsum("pijf,mf->mpij", sig, cosm)
        ker = ker / (4.0 * math.pi * np.cos(ti[..., 0])) * w_mu
        out.append(ker)
    return out[0], out[1]


def _check_eps(eps) -> complex:
    try:
        e = complex(eps)
    except (TypeError, ValueError):
        raise ValueError(f"eps must be a complex permittivity, got {eps!r}") from None
    if not (np.isfinite(e.real) and np.isfinite(e.imag)) or e.imag < 0 or e.real <= 1.0:
        raise ValueError(
            f"eps must be finite with Re ε > 1 and Im ε ≥ 0 (exp(−iωt)), got eps = {e!r}"
        )
    return e


def diffuse_transmission(
    surface,
    eps,
    frequency: float,
    thickness: float,
    *,
    theta=None,
    n_mu: int = 48,
    n_phi: int = 48,
    conserve: bool = True,
    out_of_range: str = "raise",
    n_modes: int = 0,
    face: str = "auto",
) -> DiffuseTransmission:
    """Power budget of a rough slab per incidence (module docstring).

    Parameters
    ----------
    surface : isotropic 2-D roughness (:mod:`emscatter.spectra`, both faces), or ``None``
        (flat).
    eps : relative permittivity of the wall (``Im ε ≥ 0``, ``Re ε > 1``).
    frequency : [Hz].
    thickness : slab thickness [m] (> 0).
    theta : incidence angles [rad] in [0, π/2) (default 0°…80° every 5°).
    n_mu, n_phi : Gauss–Legendre nodes in cosθ (each hemisphere) and in φ ∈ (0, π).
    conserve : scale each face's diffuse rows to ``R + T = 1`` (``L = 0``).
    out_of_range : ``"raise"`` (default), ``"warn"`` or ``"ignore"`` outside GO's validity.
    n_modes : azimuthal Fourier modes of the transmitted lobe to keep (0: the azimuth-integrated
        budget only; ``< n_phi``), for :meth:`DiffuseTransmission.transmitted_lobe`.
    face : the faces' model, one of :data:`~emscatter.radio.slab_faces.FACES`: ``"auto"``
        (default: GO where it holds — the GO path unchanged, bit for bit — else the first valid
        of SPM, PO, IEM), ``"go"``, ``"spm"``, ``"po"``, ``"iem"``
        (:mod:`emscatter.radio.slab_faces`); ``out_of_range`` applies the chosen model's
        validity.
    """
    face = check_face(face)
    e = _check_eps(eps)
    f = float(frequency)
    if not (np.isfinite(f) and f > 0):
        raise ValueError(f"frequency must be a positive number of Hz, got {frequency!r}")
    d = check_thickness(thickness)
    if d is None:
        raise ValueError("thickness=None is a half-space: it transmits nothing; give d > 0 [m]")
    check_policy(out_of_range)
    for name, n in (("n_mu", n_mu), ("n_phi", n_phi)):
        if not isinstance(n, (int, np.integer)) or n < 4:
            raise ValueError(f"{name} must be an integer ≥ 4, got {n!r}")
    if not isinstance(n_modes, (int, np.integer)) or not 0 <= n_modes < n_phi:
        raise ValueError(f"n_modes must be an integer in [0, n_phi = {n_phi}), got {n_modes!r}")
    th = np.radians(np.arange(0.0, 81.0, 5.0)) if theta is None else np.atleast_1d(theta)
    th = np.asarray(th, dtype=float)
    if th.ndim != 1 or not np.all(np.isfinite(th)) or np.any((th < 0) | (th >= math.pi / 2)):
        raise ValueError(f"theta must be angles in [0, π/2) rad, got {theta!r}")
    k = wavenumber(frequency=f)
    c = np.cos(th)
    sigma = 0.0 if surface is None else float(check_roughness(surface).sigma)
    flat = sigma == 0.0
    rough = None if flat else check_roughness(surface)
    if not flat and (rough.dimension != 2 or not getattr(rough, "is_isotropic", True)):
        raise ValueError(f"surface must be isotropic 2-D roughness, got {rough.describe()}")
    # front face's coherent reflection: Fresnel × the Kirchhoff mean field exp(−2k²σ²cos²θ)
    front = np.stack(fresnel_cos(e, c)) * gaussian_mean_field(4.0 * (k * c) ** 2, sigma)
    rh, rv, th_, tv = slab_coefficients(e, c, k, d, sigma=sigma, front=front)
    r_coh = np.abs(np.stack([rh, rv])) ** 2
    t_coh = np.abs(np.stack([th_, tv])) ** 2
    zero = np.zeros_like(r_coh)
    if flat:
        a = 1.0 - r_coh - t_coh
        return DiffuseTransmission(th, f, e, d, r_coh, zero, t_coh, zero, a, zero, True, True)
    asked = face
    face, rep = choose_face(face, rough, k, e)
    if not rep["valid"]:
        if asked == "auto":
            msg = (
                f"diffuse slab transmission (face='auto'): at {f / 1e9:g} GHz "
                f"{rough.describe()} is outside the validity of every face model "
                f"({'; '.join(rep['reasons'])}); out_of_range='warn' computes GO anyway, or "
                "name a model with face="
            )
        elif face == "go":
            from ..solvers.kirchhoff import go

            gr = go.check_validity(rough, k)
            msg = (
                f"diffuse slab transmission needs geometric optics ((2kσ)² ≥ 10, kℓ ≥ 6) for "
                f"face='go'; at {f / 1e9:g} GHz {rough.describe()} has kσ = "
                f"{gr['k_sigma']:.3g}, kℓ = {gr['k_l']:.3g} ({'; '.join(rep['reasons'])}). "
                "face='auto' takes SPM, PO or the IEM where one of them holds "
                "(out_of_range='warn' computes GO anyway)"
            )
        else:
            msg = (
                f"diffuse slab transmission with face={face!r} at {f / 1e9:g} GHz: "
                f"{rough.describe()} is outside that model's validity "
                f"({'; '.join(rep['reasons'])}); out_of_range='warn' computes anyway"
            )
        if out_of_range == "raise":
            raise ValueError(msg)
        if out_of_range == "warn":
            warnings.warn(msg, RadioValidityWarning, stacklevel=2)
    if face != "go":
        mu, wmu = _gauss01(n_mu)  # air side; inside: split at the critical cosine
        inner = _gauss01_split(n_mu, math.sqrt(1.0 - 1.0 / e.real))
        parts = rough_face_budget(face, rough, e, k, d, c, (mu, wmu), inner, n_phi, n_modes,
                                  conserve, r_coh, t_coh)  # fmt: skip
        out = DiffuseTransmission(
            th, f, e, d, r_coh, t_coh=t_coh, flat=False, valid=rep["valid"],
            reasons=list(rep["reasons"]), mu_nodes=mu, mu_weights=wmu, face=face, **parts,
        )  # fmt: skip
        if not np.all(np.isfinite(out.total)):
            raise ValueError(
                "diffuse slab transmission produced NaN/inf (please report the inputs)"
            )
        return out
    mu, wmu = _gauss01(n_mu)
    er = e.real
    # front face from air: polarization-resolved, at the incidence angles
    kr0m, kt0m = face_kernels(rough, er, k, c, mu, wmu, n_phi, n_modes)
    # a face from inside: unpolarized (mean over incident polarizations), on the nodes
    kr1m, kt1m = face_kernels(rough, 1.0 / er, k, mu, mu, wmu, n_phi, n_modes)
    kr1m, kt1m = kr1m.mean(axis=1), kt1m.mean(axis=1)
    kr0, kt0, kr1, kt1 = kr0m[0], kt0m[0], kr1m[0], kt1m[0]
    def0 = 1.0 - kr0.sum(-1) - kt0.sum(-1)  # (2, n)
    def1 = 1.0 - kr1.sum(-1) - kt1.sum(-1)  # (n_mu,)
    if conserve:
        s0 = 1.0 / (1.0 - def0)
        kr0, kt0 = kr0 * s0[..., None], kt0 * s0[..., None]
        s1 = 1.0 / (1.0 - def1)
        kr1, kt1 = kr1 * s1[:, None], kt1 * s1[:, None]
        kt0m, kr1m, kt1m = kt0m * s0[..., None], kr1m * s1[:, None], kt1m * s1[:, None]
    loss0 = np.zeros_like(def0) if conserve else def0
    loss1 = np.zeros_like(def1) if conserve else def1
    k2z = k * np.sqrt(e - er * (1.0 - mu * mu) + 0j)
    att = np.exp(-2.0 * d * np.abs(k2z.imag))  # one crossing, per internal node
    p = att[:, None] * kr1  # P = diag(a) K_r
    eye = np.eye(n_mu)
    inv2 = np.linalg.inv(eye - p @ p)
    t_out = att[:, None] * kt1  # (n_mu, n_mu): arriving at a face, leaving into air node j
    x0 = kt0  # (2, n, n_mu)
    t_lobe = x0 @ inv2 @ t_out
    r_int = x0 @ p @ inv2 @ t_out
    absorbed = x0 @ np.linalg.solve(eye - p, 1.0 - att)
    lost = loss0 + x0 @ np.linalg.solve(eye - p, att * loss1)
    # the coherent fields are removed from the incident power before the faces act
    # (negligible where GO holds: their share is reported in r_coh, t_coh)
    keep = np.clip(1.0 - r_coh - t_coh, 0.0, 1.0)
    t_lobe = t_lobe * keep[..., None]
    modes = r_modes = None
    if n_modes:  # the same chain per azimuthal mode (the power fluxes above are mode 0)
        pm = att[None, :, None] * kr1m
        tm = att[None, :, None] * kt1m
        inv2m = np.linalg.inv(eye[None] - pm @ pm)  # (M + 1, n_mu, n_mu)
        modes = np.einsum("mpij,mjk->pikm", kt0m, inv2m @ tm) * keep[..., None, None]
        r_modes = np.einsum("mpij,mjk->pikm", kt0m, pm @ inv2m @ tm) * keep[..., None, None]
    r_diff = (kr0.sum(-1) + r_int.sum(-1)) * keep
    out = DiffuseTransmission(
        th, f, e, d, r_coh, r_diff, t_coh, t_lobe.sum(-1), absorbed * keep, lost * keep,
        False, bool(rep["valid"]), list(rep["reasons"]), def0, t_lobe, mu, wmu, modes,
        r_int * keep[..., None], r_modes,
    )  # fmt: skip
    if not np.all(np.isfinite(out.total)):
        raise ValueError("diffuse slab transmission produced NaN/inf (please report the inputs)")
    return out
