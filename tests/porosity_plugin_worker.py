"""Mitsuba side of tests/test_brdf_porosity.py in a fresh interpreter (Dr.Jit variants are per
process): ``python tests/porosity_plugin_worker.py`` loads the plugin ``"emscatter"`` with the
porosity parameters (transform applied at load time) and with the table transformed beforehand
in Python, evaluates both on the same direction pairs, and prints JSON on its last line:
``{"max_rel": ..., "max_rel_base": ...}`` (porous vs pre-transformed; porous vs the base table).
"""

from __future__ import annotations

import json

import numpy as np


def main() -> None:
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    from emscatter.brdf import porosity as P
    from emscatter.brdf.analytic import blinn_phong, table_from_function
    from emscatter.render import mitsuba as em_mi

    base = table_from_function(
        lambda wi, wo, wl: blinn_phong(wi, wo, 20.0, ks=0.5), [550e-9], resolution=(18, 36)
    )
    params = {"porosity": 0.35, "diffuse_albedo": 0.4, "wetness": 0.5, "pore_shape": 3.0}
    pre = P.wet(base, 0.35, 0.5, kd=0.4, pore_shape=3.0)
    rng = np.random.default_rng(1)
    n = 256
    th = rng.uniform(0.05, 1.3, (2, n))
    ph = rng.uniform(0, 2 * np.pi, (2, n))
    d = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)

    def evaluate(bsdf_dict):
        bsdf = mi.load_dict(bsdf_dict)
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(mi.Float(c) for c in d[1].T))
        val = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*(mi.Float(c) for c in d[0].T)))
        return np.array(val)[0]

    key = em_mi.register_table(base)
    porous = evaluate({"type": "emscatter", "table": key, **params})
    ref = evaluate({"type": "emscatter", "table": em_mi.register_table(pre)})
    plain = evaluate({"type": "emscatter", "table": key})
    print(
        json.dumps(
            {
                "max_rel": float(np.max(np.abs(porous - ref)) / np.max(ref)),
                "max_rel_base": float(np.max(np.abs(porous - plain)) / np.max(plain)),
            }
        )
    )


if __name__ == "__main__":
    main()
