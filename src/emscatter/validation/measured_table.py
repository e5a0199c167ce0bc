"""The measured-error table that ``method="auto"`` reads (:mod:`emscatter.solvers.measured`),
written from the validity maps' rows."""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..io import atomic_path
from .maps import AUTO_TO_MAP, MapConfig, tag_of

__all__ = ["measured_maps", "write_measured"]


def _medium(cfg: MapConfig) -> str:
    from ..solvers.measured import medium_class

    return medium_class(cfg.eps)


def measured_maps(maps: list[tuple[MapConfig, list[dict]]]) -> list[dict]:
    """Per map: grid, correlation, medium class and, per candidate of ``auto``, the σ⁰ error
    [dB] per cell, the larger of h and v (None where a polarization was not measured)."""
    out = []
    for cfg, rows in maps:
        ks, kl = list(cfg.k_sigma), list(cfg.k_l)
        errors = {}
        for name, row in AUTO_TO_MAP.items():
            z = [[None] * len(kl) for _ in ks]
            got: dict = {}
            for r in rows:
                if r["method"] == row:
                    got.setdefault((r["k_sigma"], r["k_l"]), []).append(float(r["error_dB"]))
            for (a, b), v in got.items():
                if len(v) == 2 and all(math.isfinite(x) for x in v):
                    z[ks.index(a)][kl.index(b)] = round(max(v), 3)
            errors[name] = z
        out.append(
            {
                "tag": tag_of(cfg),
                "correlation": cfg.correlation,
                "medium": _medium(cfg),
                "eps": str(cfg.eps),
                "theta_i_deg": cfg.theta_i_deg,
                "k_sigma": ks,
                "k_l": kl,
                "errors": errors,
            }
        )
    return out


def write_measured(maps: list[tuple[MapConfig, list[dict]]], path=None) -> Path:
    """Write the table (default: the one the package reads) atomically; clears the loader's
    cache so the new table is used at once."""
    from ..solvers import measured

    path = Path(path) if path else measured.TABLE_PATH
    doc = {
        "about": "σ⁰ error [dB] vs the 1-D method of moments (larger of h, v) per map cell; "
        "written by emscatter.validation.measured_table.write_measured from "
        "validation/validity_maps (README there)",
        "maps": measured_maps(maps),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(_dumps(doc))
    measured.load_table.cache_clear()
    return path


def _dumps(doc: dict) -> str:
    """JSON with one grid row per line (small, diffable)."""
    lines = ["{", f' "about": {json.dumps(doc["about"], ensure_ascii=False)},', ' "maps": [']
    for i, m in enumerate(doc["maps"]):
        head = {k: v for k, v in m.items() if k != "errors"}
        lines.append("  {" + json.dumps(head, ensure_ascii=False)[1:-1] + ', "errors": {')
        names = list(m["errors"])
        for a, name in enumerate(names):
            rows = ",\n".join("    " + json.dumps(r) for r in m["errors"][name])
            comma = "," if a < len(names) - 1 else ""
            lines.append(f'   "{name}": [\n{rows}\n   ]{comma}')
        lines.append("  }}" + ("," if i < len(doc["maps"]) - 1 else ""))
    lines += [" ]", "}"]
    return "\n".join(lines) + "\n"
