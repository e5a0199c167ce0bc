import numpy as np

from emscatter import GaussianCorrelation
from emscatter.brdf import build_table

t = build_table(GaussianCorrelation(0.15e-6, 1e-6), "Au", [450e-9, 550e-9, 650e-9],
                method="go")                 # 90 × 90 × 180 (θi, θo, Δφ) per wavelength
theta_i = np.radians(30.0)
wi = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])   # renderer frame: away from the surface
wo = np.array([-np.sin(theta_i), 0.0, np.cos(theta_i)])  # the mirror direction (φo = φi + π)
t.evaluate(wi, wo, wavelength=550e-9)        # f_r [1/sr] at direction arrays (..., 3), interpolated
t.coherent_reflectance(theta_i)              # the specular delta lobe, kept apart
t.albedo().total                             # coherent + incoherent, ≤ 1 everywhere
