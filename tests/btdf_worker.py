"""Mitsuba evaluations for tests/test_go_transmission.py in a fresh interpreter (Dr.Jit
variants are per process): ``python tests/btdf_worker.py < JSON`` (standard input) with
``{"variant", "bsdf": dict, "wi": [[x, y, z], ...] (towards the light), "wo": [...] (towards
the viewer), "wavelength" [nm, optional]}`` prints ``{"eval": [...]}`` as JSON on its last
line: ``bsdf.eval`` (radiance transport: ``f · |cosθ|`` of the light direction), channel 0, or
in a ``*_polarized`` variant the 4×4 Mueller matrix per pair (Mitsuba's Stokes frames). A
vectorized (``llvm_*``) variant evaluates all pairs at once; a ``scalar_*`` one pair by pair
(unpolarized only).
"""

from __future__ import annotations

import json
import sys

import numpy as np


def main(arg: str) -> None:
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    bsdf = mi.load_dict(args["bsdf"])
    wi = np.asarray(args["wi"], dtype=float)
    wo = np.asarray(args["wo"], dtype=float)
    ctx = mi.BSDFContext()
    if mi.variant().startswith("scalar"):
        vals = []
        for a, b in zip(wi, wo, strict=True):
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*b)  # Mitsuba's si.wi: towards the viewer
            vals.append(float(np.ravel(np.array(bsdf.eval(ctx, si, mi.Vector3f(*a))))[0]))
    else:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(mi.Float(c) for c in wo.T))
        if "spectral" in mi.variant():
            si.wavelengths = mi.UnpolarizedSpectrum(float(args.get("wavelength", 550.0)))
        val = bsdf.eval(ctx, si, mi.Vector3f(*(mi.Float(c) for c in wi.T)))
        if "polarized" in mi.variant():  # (4, 4, wavelengths, n) → (n, 4, 4), first λ
            vals = np.moveaxis(np.array(val, dtype=float)[:, :, 0, :], -1, 0).tolist()
        else:
            vals = np.array(val[0], dtype=float).tolist()
    print(json.dumps({"eval": vals}))


if __name__ == "__main__":
    main(sys.stdin.read())
