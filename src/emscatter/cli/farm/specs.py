"""The tables of ``emscatter farm brdf``: from the command line's value lists (the product
roughness × material × wavelength set) or from a spec file, checked before any work.

A spec file is JSON or TOML (by its extension). Its top-level keys are defaults for every
table, and ``table`` (TOML ``[[table]]``; JSON ``"table": [...]``, or the file is a JSON list)
lists the tables; each table's keys override the defaults::

    method = "go"                 # defaults for every table
    wavelengths_nm = [450, 550, 650]
    n_theta = 45

    [[table]]
    name = "gold-smooth"          # the file: OUT_DIR/gold-smooth.npz (default: from the fields)
    material = "Au"
    sigma = 0.1e-6                # [m]
    length = 1e-6                 # [m]

The keys are the single-table command's options (``emscatter brdf``) with ``_`` for ``-``:
:data:`FIELDS`. Options given on the command line are defaults below the file's own. Units:
metres for ``sigma``, ``length``, ``length_y``; nanometres for ``wavelengths_nm`` (a list or
``"start:stop:count"``). Every value goes through the same check as the option of that name;
an error names the file, the table, the key, the value and what is allowed.
"""

from __future__ import annotations

import argparse
import itertools
import json
import re
from pathlib import Path

from ..args import Integer, Number, fmt
from ..brdf import _material, _method_choices, _wavelengths_nm

__all__ = ["FIELDS", "GRID_OPTIONS", "read_spec_file", "grid_tables", "to_farm_spec", "DEFAULTS"]

_CHOICES = {
    "kind": ("gaussian", "exponential", "power-law"),
    "energy": ("rescale", "off"),
    "out_of_range": ("warn", "raise", "ignore"),
}
_FLAGS = ("polarized", "float32", "anisotropic")
_TYPES = {
    "sigma": Number(low=0, unit="m"),
    "length": Number(low=0, unit="m"),
    "length_y": Number(low=0, unit="m"),
    "hurst": Number(low=0, high=1),
    "n_theta": Integer(low=2, high=2000),
    "n_phi": Integer(low=4, high=4000),
    "tol": Number(low=0, high=1),
}
#: Every key a table (or the spec file's defaults) may have.
FIELDS = ("name", "kind", "sigma", "length", "length_y", "hurst", "material", "wavelengths_nm",
          "method", "n_theta", "n_phi", "tol", *_FLAGS, "energy", "out_of_range")  # fmt: skip
#: The built-in defaults (those of ``emscatter brdf``).
DEFAULTS = {"kind": "gaussian", "sigma": 0.15e-6, "length": 1.0e-6, "hurst": 0.5,
            "material": "Au", "wavelengths_nm": "450,550,650", "method": "auto",
            "energy": "rescale", "out_of_range": "warn"}  # fmt: skip
#: Options that take several values on the command line (their product is the farm).
GRID_OPTIONS = ("--sigma", "--length", "--material", "--wavelengths-nm")
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,199}")


def _check_value(key: str, value, where: str):
    """``value`` of ``key`` as the option of that name would take it; ValueError naming
    ``where``, the key, the value and what is allowed."""
    try:
        if key == "name":
            if not isinstance(value, str) or not _NAME.fullmatch(value):
                raise argparse.ArgumentTypeError(
                    "must be a file name: letters, digits and . _ + - (starting with a letter "
                    "or digit, at most 200 characters)"
                )
            return value
        if key in _FLAGS:
            if not isinstance(value, bool):
                raise argparse.ArgumentTypeError("must be true or false")
            return value
        if key in _CHOICES or key == "method":
            allowed = _CHOICES.get(key) or tuple(_method_choices())
            if not isinstance(value, str) or value.lower() not in allowed:
                raise argparse.ArgumentTypeError(f"must be one of {list(allowed)}")
            return value.lower()
        if key == "material":
            if isinstance(value, bool) or not isinstance(value, str | int | float):
                raise argparse.ArgumentTypeError(
                    "must be a material name (Au, itu:concrete) or a permittivity (2.25, '4+0.3j')"
                )
            return _material(str(value))
        if key == "wavelengths_nm":
            if isinstance(value, list | tuple):
                if not value or not all(
                    isinstance(v, int | float) and not isinstance(v, bool) for v in value
                ):
                    raise argparse.ArgumentTypeError("must be a list of numbers [nm]")
                value = ",".join(repr(float(v)) for v in value)
            if not isinstance(value, str):
                raise argparse.ArgumentTypeError("must be a list [nm] or 'start:stop:count'")
            return _wavelengths_nm(value)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise argparse.ArgumentTypeError("must be a number")
        if key in ("n_theta", "n_phi") and not float(value).is_integer():
            raise argparse.ArgumentTypeError("must be an integer")
        return _TYPES[key](str(int(value) if key in ("n_theta", "n_phi") else value))
    except argparse.ArgumentTypeError as exc:
        raise ValueError(f"{where} key {key!r} = {value!r}: {exc}") from None


def _load(path: Path):
    suffix = path.suffix.lower()
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"--spec {str(path)!r}: cannot read it ({exc.strerror or exc})") from None
    try:
        if suffix == ".json":
            return json.loads(text)
        if suffix == ".toml":
            import tomllib

            return tomllib.loads(text)
    except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError, TOMLDecodeError
        raise ValueError(f"--spec {str(path)!r}: not valid {suffix[1:].upper()}: {exc}") from None
    raise ValueError(
        f"--spec {str(path)!r}: unknown extension {suffix or '(none)'!r}; use .json or .toml"
    )


def read_spec_file(path, defaults: dict) -> list[dict]:
    """The tables of the spec file ``path`` (module docstring), each a dict of checked
    values over ``defaults`` (the command line's and the built-in ones)."""
    path = Path(path)
    data = _load(path)
    if isinstance(data, list):
        data = {"table": data}
    if not isinstance(data, dict):
        raise ValueError(f"--spec {str(path)!r}: expected a table list or an object with 'table'")
    tables = data.get("table")
    if not isinstance(tables, list) or not tables:
        raise ValueError(
            f"--spec {str(path)!r}: no tables; list them under 'table' (TOML [[table]], JSON "
            '"table": [{...}, ...]), each with keys from ' + ", ".join(FIELDS)
        )
    common = _fields({k: v for k, v in data.items() if k != "table"}, f"--spec {path} defaults")
    if "name" in common:
        raise ValueError(f"--spec {str(path)!r} defaults: 'name' belongs to one table, not all")
    out = []
    for i, entry in enumerate(tables):
        where = f"--spec {path} table[{i}]"
        if not isinstance(entry, dict):
            raise ValueError(f"{where}: expected a table of keys, got {entry!r:.60}")
        out.append({**defaults, **common, **_fields(entry, where)})
    return out


def _fields(entry: dict, where: str) -> dict:
    unknown = sorted(set(entry) - set(FIELDS))
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; allowed: {', '.join(FIELDS)}")
    return {k: _check_value(k, v, where) for k, v in entry.items()}


def grid_tables(a, defaults: dict) -> list[dict]:
    """The product roughness (σ × ℓ, outermost) × material × wavelength set of the command
    line's lists; a value given twice is an error (it would be one table twice)."""
    lists = {}
    for opt, key in (("--sigma", "sigma"), ("--length", "length"), ("--material", "material"),
                     ("--wavelengths-nm", "wavelengths_nm")):  # fmt: skip
        values = getattr(a, key) or [defaults[key]]
        seen = {}
        for v in values:
            k = _label(v)
            if k in seen:
                raise ValueError(f"{opt} {k} is given twice; each value makes its own tables")
            seen[k] = v
        lists[key] = values
    out = []
    for s, ell, m, w in itertools.product(*lists.values()):
        out.append({**defaults, "sigma": s, "length": ell, "material": m, "wavelengths_nm": w})
    return out


def _label(v) -> str:
    if isinstance(v, complex):
        return f"eps{fmt(v.real)}" + (f"+{fmt(v.imag)}j" if v.imag else "")
    if hasattr(v, "__len__") and not isinstance(v, str):
        return ",".join(fmt(float(x)) for x in v)
    if isinstance(v, float):
        return fmt(v)
    return str(v)


def default_name(t: dict, several_wavelength_sets: bool) -> str:
    """``Au-sigma1.5e-07-len1e-06`` (+ ``-nm450-550-650`` where several sets): a file name."""
    mat = re.sub(r"[^A-Za-z0-9.+-]", "_", _label(t["material"])).strip("_") or "eps"
    name = f"{mat}-sigma{fmt(t['sigma'])}-len{fmt(t['length'])}"
    if several_wavelength_sets:
        name += "-nm" + _label(t["wavelengths_nm"]).replace(",", "-")
    return name


def name_tables(tables: list[dict], source: str) -> list[str]:
    """Every table's file name (given or :func:`default_name`), refused when two coincide."""
    several = len({_label(t["wavelengths_nm"]) for t in tables}) > 1
    names, seen = [], {}
    for i, t in enumerate(tables):
        name = t.get("name") or default_name(t, several)
        if name in seen:
            raise ValueError(
                f"{source} table[{i}] name {name!r} repeats table[{seen[name]}]'s: every table "
                "needs its own name (its file OUT_DIR/<name>.npz)"
            )
        seen[name] = i
        names.append(name)
    return names


def to_farm_spec(t: dict, name: str) -> dict:
    """The :func:`emscatter.brdf.build_tables` spec of one checked table."""
    import numpy as np

    from ...spectra import roughness

    params = {"sigma": t["sigma"], "length": t["length"], "dimension": 2}
    if t.get("length_y") is not None:
        params["length_y"] = t["length_y"]
    if t["kind"] == "power-law":
        params["hurst"] = t["hurst"]
    resolution = None
    if t.get("tol") is not None and (t.get("n_theta") or t.get("n_phi")):
        raise ValueError(
            f"table {name!r}: n_theta/n_phi apply to a fixed grid only; tol refines the grid by "
            "itself (drop one of them)"
        )
    if t.get("n_theta") is not None or t.get("n_phi") is not None:
        n_theta = t.get("n_theta") or 90
        resolution = (n_theta, t.get("n_phi") or max(180, 2 * n_theta))
    wl = t["wavelengths_nm"]
    if isinstance(wl, str):
        wl = _wavelengths_nm(wl)
    return {
        "name": name,
        "surface": roughness(t["kind"], **params),
        "material": t["material"],
        "wavelengths": np.asarray(wl, float) * 1e-9,
        "method": t["method"],
        "resolution": resolution,
        "tol": t.get("tol"),
        "anisotropic": True if t.get("anisotropic") else None,
        "polarized": bool(t.get("polarized")),
        "energy": t["energy"],
        "out_of_range": t["out_of_range"],
        "dtype": "float32" if t.get("float32") else "float64",
    }


def manifest_entry(t: dict, name: str) -> dict:
    """What the manifest records of one table (JSON: numbers, strings, lists)."""
    out = {"name": name, "file": f"{name}.npz"}
    for key in FIELDS[1:]:
        v = t.get(key)
        if v is None or (key == "hurst" and t.get("kind") != "power-law"):
            continue
        if key == "wavelengths_nm":
            v = [float(x) for x in (_wavelengths_nm(v) if isinstance(v, str) else v)]
        elif isinstance(v, complex):  # as the option reads it back: "2.25", "4+0.3j"
            v = fmt(v.real) + (f"+{fmt(v.imag)}j" if v.imag else "")
        elif key == "material":
            v = str(v)
        out[key] = v
    return out
