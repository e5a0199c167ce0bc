"""Textured (anisotropic) radio materials in Sionna RT (CPU, LLVM), run in a fresh interpreter
(tests/radio_worker.py, check ``textured_plate``): a 20 m concrete plate at 28 GHz, 60°,
σ = 1 mm, ℓx = 30 mm, ℓy = 12 mm (PO tables)."""

from __future__ import annotations

import importlib.util
import math

import pytest

if importlib.util.find_spec("sionna") is None:
    pytest.skip("Sionna RT is not installed", allow_module_level=True)

from test_radio_sionna import _ok, _run  # noqa: E402


def _db(a, b):
    return 10.0 * math.log10(a / b)


def test_textured_plate_laws():
    r = _ok(_run("textured_plate"), "textured_plate")
    assert r["method"] == "po"
    # diffuse power vs the radar-equation quadrature of the anisotropic σ⁰ (as the isotropic
    # plate check: 0.2 dB, here widened by 3 Monte Carlo standard errors)
    noise = 10.0 * math.log10(1.0 + 3.0 * r["diffuse"]["noise_vv"])
    for pair in ("VV", "HH", "HV"):
        d = _db(r["diffuse"][pair], r["diffuse_prediction"][pair])
        assert abs(d) <= 0.2 + noise, (pair, d)
    # texture turned by 90° (direction y) with ℓx, ℓy swapped = the same surface
    for pair in ("VV", "HH", "HV", "VH"):
        assert abs(_db(r["diffuse_rotated"][pair], r["diffuse"][pair])) <= 0.01, pair
    # specular = image × Fresnel × Kirchhoff coherent factor (σ only)
    for pair in ("VV", "HH"):
        assert abs(_db(r["specular"][pair], r["specular_prediction"][pair])) <= 0.01, pair
    # ℓx = ℓy through the textured path (direction z: the plate's normal, the degenerate rule)
    # = the isotropic material, diffuse and specular
    for pair in ("VV", "HH", "HV", "VH"):
        for kind in ("", "_specular"):
            a, b = r["iso_textured" + kind][pair], r["iso_plain" + kind][pair]
            if b > 1e-30:
                assert abs(a / b - 1.0) <= 1e-5, (kind, pair, a, b)
    errors = r["errors"]
    assert "texture_direction" in errors["no_direction"] and "ℓx" in errors["no_direction"]
    assert "flat surface" in errors["flat"]
    assert "(0, 0, 0)" in errors["zero"]
