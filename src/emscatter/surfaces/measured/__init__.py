"""The measured roughness of a height map (:mod:`.roughness`) and its n-fold spectra
(:mod:`.nfold`); the maps themselves are read by :mod:`emscatter.surfaces.heightmap`."""

from .roughness import TAILS, BandWarning, MeasuredRoughness, measured_roughness

__all__ = ["MeasuredRoughness", "measured_roughness", "BandWarning", "TAILS"]
