"""Mitsuba evaluations for tests/test_brdf_pbsdf.py in a fresh interpreter (Dr.Jit variants are
per process): ``python tests/pbsdf_worker.py JSON`` with ``{"variant", "bsdfs": {name: dict},
"wi": [[x, y, z], ...] (towards the light), "wo": [...] (towards the viewer), "wavelength"
[nm]}`` prints ``{name: [eval, ...]}`` as JSON on its last line: each ``eval`` is the 4×4
Mueller matrix (polarized variants) or the scalar s0 (others) of ``bsdf.eval`` (it includes
cosθ of the light direction), radiance transport.
"""

from __future__ import annotations

import json
import sys

import numpy as np


def main(arg: str) -> None:
    import mitsuba as mi

    args = json.loads(arg)
    mi.set_variant(args["variant"])
    polarized = "polarized" in args["variant"]
    out = {}
    for name, spec in args["bsdfs"].items():
        bsdf = mi.load_dict(spec)
        vals = []
        for wi, wo in zip(args["wi"], args["wo"], strict=True):
            si = mi.SurfaceInteraction3f()
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.n = mi.Vector3f(0, 0, 1)
            si.wi = mi.Vector3f(wo)  # Mitsuba's si.wi: towards the viewer
            si.wavelengths = [float(args["wavelength"])] * 4
            a = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wi)))
            if polarized:
                vals.append((a if a.ndim == 2 else a[..., 0]).tolist())
            else:
                vals.append(float(np.ravel(a)[0]))
        out[name] = vals
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1])
