"""Kirchhoff transmission through a rough dielectric interface (the BTDF side of the solvers).

:mod:`.go`: geometric optics, the microfacet BTDF of Walter, Marschner, Li & Torrance (EGSR
2007) with GO's Beckmann slopes and Smith shadowing (``bistatic_transmission``).
:mod:`.po`: physical optics (Kirchhoff, tangent plane with the local Fresnel transmission),
the coherent transmissivity and the incoherent σ⁰_t for Gaussian, exponential and power-law
spectra.
"""
