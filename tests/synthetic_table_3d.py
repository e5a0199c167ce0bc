"""A synthetic 3-D measured-error table (the schema of solvers/data/measured_errors_3d.json)
for the tests of the 3-D lookup and of auto's blend: one Gaussian PEC map, every cell with the
same errors / SEs / pair SEs."""

from __future__ import annotations

import json

import numpy as np

NAMES = ("spm", "go", "po", "iem")


def write_table(path, errors, se=None, pair_se=None, *, theta=(20.0, 40.0),
                ks=(0.1, 0.3, 1.0), kl=(3.0, 7.0)):  # fmt: skip
    """Write the table to ``path`` and return it: ``errors``/``se`` {method: dB or None},
    ``pair_se`` {"a|b": dB}, on the grid ``theta`` [deg] × ``ks`` × ``kl``."""
    shape = (len(theta), len(ks), len(kl))

    def grid(v):
        return np.full(shape, v, dtype=object).tolist()

    doc = {"maps": [{
        "tag": "synthetic", "correlation": "gaussian", "medium": "conductor",
        "theta_i_deg": list(theta), "k_sigma": list(ks), "k_l": list(kl),
        "realizations": grid(16),
        "errors": {n: grid(errors.get(n)) for n in NAMES},
        "se": {n: grid((se or {}).get(n)) for n in NAMES},
        "pair_se": {p: grid(v) for p, v in (pair_se or {}).items()},
    }]}  # fmt: skip
    path.write_text(json.dumps(doc))
    return path
