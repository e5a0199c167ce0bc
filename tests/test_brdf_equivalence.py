"""The seed's chapter-3 roughness equivalences (section 3.2), reproduced with the stated
criterion (emscatter.brdf.equivalence.FIT_CRITERION)."""

from __future__ import annotations

import numpy as np
import pytest

from emscatter.brdf.analytic import equivalence as E


def test_slope_from_surface():
    # eq. 3.1: m = 2σ/T (the seed's worked example prints 0.32 for σ = 0.2, T = 0.8, but
    # 2·0.2/0.8 = 0.5; its figures then use m = 0.32)
    assert E.rms_slope_from_surface(0.2, 0.8) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="sigma"):
        E.rms_slope_from_surface(-1.0, 1.0)


def test_seed_chapter3_values():
    # seed §3.2.2: Beckmann m = 0.32 ↔ Phong n = 4 (Fig. 3.4) ↔ Blinn n_B = 17 (Fig. 3.6)
    phong = E.phong_from_beckmann(0.32)
    assert round(phong.value) == 4 and phong.error < 0.005
    blinn = E.blinn_from_beckmann(0.32)
    assert blinn.value == pytest.approx(17, abs=0.2)
    # Phong n = 1 ↔ m_max ≈ 0.51 (Fig. 3.5)
    assert E.beckmann_from_phong(1).value == pytest.approx(0.51, abs=0.01)
    # Blinn n_B = 4 ↔ m ≈ 0.54 (Fig. 3.7), "clearly not a good approximation"
    b4 = E.beckmann_from_blinn(4)
    assert b4.value == pytest.approx(0.54, abs=0.03) and b4.error > 10 * phong.error
    # inverses agree
    assert E.beckmann_from_phong(phong.value).value == pytest.approx(0.32, rel=1e-3)


def test_ward_ashikhmin():
    # seed Figs. 3.8–3.9: Ward (0.1, 0.8); two different AS pairs fit, hence a fixed ratio
    fixed = E.ashikhmin_from_ward(0.1, 0.8)
    nu, nv = fixed.value
    assert nu / nv == pytest.approx(64.0)
    free = E.ashikhmin_from_ward(0.1, 0.8, ratio=None)
    assert free.value[0] > 150 and free.value[1] < 3 and free.error <= fixed.error
    # the seed's (n_u, n_v) = (10, 187) is this fit with u along y; it is worse than ours
    g, p = np.meshgrid(E._GAMMA[::4], E._PHI, indexing="ij")
    ref = E.ward_shape(g, p, 0.1, 0.8)
    seed_err = E.fit_error(ref, E.ashikhmin_shape(g, p, 187, 10))
    assert free.error < fixed.error < seed_err


def test_seed_section_makes_the_fit_non_unique():
    """Seed §3.2.2: 'la solution trouvée n'est pas unique' — on the φ = π/4 section every pair
    with n_u + n_v = 2N fits equally well; both printed pairs (Figs. 3.8, 3.9) are within 2 %
    of that line and fit the section to rms < 2e-3, while on the full (γ, φ) grid they differ
    by ×1.7 (0.12 and 0.21) — only a 1D comparison makes them both fits."""
    sec = E.ward_section_exponent(0.1, 0.8)
    # Ward on the diagonal is a Beckmann lobe with 1/m² = (1/m_x² + 1/m_y²)/2
    m45 = (0.5 * (1 / 0.1**2 + 1 / 0.8**2)) ** -0.5
    assert sec.value == pytest.approx(E.blinn_from_beckmann(m45).value, rel=1e-6)
    assert sec.value == pytest.approx(98.85, rel=1e-3)
    g = E._GAMMA
    ref = E.ward_shape(g, E.SEED_SECTION_PHI, 0.1, 0.8)
    for nu, nv in ((10, 187), (187, 10), (100, 100), (175.7, 22.0)):
        assert E.fit_error(ref, E.ashikhmin_shape(g, E.SEED_SECTION_PHI, nu, nv)) < 2e-3
    full = [E.ward_ashikhmin_grid_error(0.1, 0.8, *p) for p in ((187, 10), (100, 100))]
    assert full[1] > 1.5 * full[0] > 0.15
    # a section off the diagonal separates u and v: (187, 10) and (10, 187) differ there
    r0 = E.ward_shape(g, 0.3, 0.1, 0.8)
    e1 = E.fit_error(r0, E.ashikhmin_shape(g, 0.3, 187, 10))
    e2 = E.fit_error(r0, E.ashikhmin_shape(g, 0.3, 10, 187))
    assert e2 > 10 * e1
    with pytest.raises(ValueError, match="phi"):
        E.ward_section_exponent(0.1, 0.8, phi=float("nan"))


def test_seed_criterion_isotropic_limit():
    """m_x = m_y: Ward is Beckmann at every φ, the seed's criterion gives n_u = n_v = the Blinn
    exponent of that m (the isotropic equivalence, seed: m = 0.32 → n_B = 17)."""
    eq = E.ashikhmin_from_ward(0.32, 0.32, ratio="seed")
    nb = E.blinn_from_beckmann(0.32)
    assert eq.value == pytest.approx((nb.value, nb.value), rel=1e-6)
    assert eq.error == pytest.approx(nb.error, rel=1e-6)
