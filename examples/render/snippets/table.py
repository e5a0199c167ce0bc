import numpy as np

from emscatter import GaussianCorrelation
from emscatter.brdf import build_table
from emscatter.brdf.export_npz import write_npz

# GO over gold, Beckmann m = 2σ/ℓ = 0.3: the default grid, 90 × 90 × 180 (θi, θo, Δφ)
t = build_table(GaussianCorrelation(0.15e-6, 1e-6), "Au", [450e-9, 550e-9, 650e-9], method="go")
theta_i = np.radians(30.0)
wi = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])  # renderer frame: away from the surface
wo = np.array([-np.sin(theta_i), 0.0, np.cos(theta_i)])  # the mirror direction, φo = φi + π
f = t.evaluate(wi, wo, wavelength=550e-9)  # f_r [1/sr] at direction arrays (..., 3)
r_coh = t.coherent_reflectance(theta_i)  # the specular delta lobe, kept apart
albedo = t.albedo().total  # coherent + incoherent, ≤ 1 everywhere
write_npz(t, "gold.npz")  # the table and its metadata, read back by read_npz
