"""``emscatter farm brdf``: many BRDF tables at once — serially, on a local dask cluster or
on a running dask scheduler — one ``.npz`` per table in ``--out-dir``.

The tables are the product of the value lists (``--sigma 1e-7 --sigma 2e-7 --material Au
--material Ag --wavelengths-nm 450,550,650 ...``: roughness outermost, then material, then
wavelength set) or the entries of a spec file (``--spec tables.toml``, :mod:`.specs`). Each
table is one :func:`emscatter.brdf.build_tables` spec; the workers write their files
themselves, atomically (``OUT_DIR/<name>.npz``, the folder shared with them), and
``OUT_DIR/manifest.json`` lists every table with its parameters. The files hold the same
tables, bit for bit, whatever the scheduler (tested).

``--scheduler``: none (serial, in this process), ``local`` (a LocalCluster of ``--workers``
processes, ``--threads`` compiled threads each; its dashboard's address is printed) or
``tcp://HOST:PORT`` (a running ``dask scheduler``, reached within ``--connect-timeout``).
Everything is checked before any work: the scheduler's form, each table (surface, material
at every wavelength, method, grid), the file names (two tables never share one) and the
output folder. A tqdm bar counts the tables on stderr when it is a terminal (``--quiet``:
never). The single-table command stays ``emscatter brdf``.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

from ..args import Integer, Number, add_command, reject_unless
from ..brdf import _material, _method_choices, _wavelengths_nm
from ..paths import OutputFolder
from . import specs as _specs

_ADDRESS = re.compile(r"(tcp|tls)://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(\d{1,5})")


def scheduler_address(text: str) -> str:
    """``type=`` of ``--scheduler``: ``local`` or ``tcp://HOST:PORT`` (``tls://`` too)."""
    t = text.strip()
    if t == "local":
        return t
    m = _ADDRESS.fullmatch(t)
    if m is None or not 1 <= int(m[3]) <= 65535:
        raise argparse.ArgumentTypeError(
            f"expected 'local' (a dask LocalCluster here) or a dask scheduler address "
            f"tcp://HOST:PORT (port 1-65535; tls://HOST:PORT too), got {text!r}"
        )
    return t


def register(subparsers) -> None:
    top = add_command(
        subparsers,
        "farm",
        help="many tables at once, serially or on a dask cluster (--scheduler "
        "local|tcp://HOST:PORT): 'emscatter farm brdf' (roughness × material × wavelengths)",
    )
    kinds = top.add_subparsers(dest="farm", required=True, metavar="KIND")
    p = add_command(
        kinds,
        "brdf",
        help="many BRDF tables (roughness × material × wavelengths, or a spec file), one .npz "
        "each in --out-dir",
    )
    p.add_argument("--out-dir", type=OutputFolder(), required=True, metavar="DIR",
                   help="folder of the tables (OUT_DIR/<name>.npz) and manifest.json; created "
                   "when missing; on a cluster, a folder the workers share")  # fmt: skip
    p.add_argument("--spec", type=Path, metavar="FILE",
                   help="a .toml or .json file listing the tables (see the module "
                   "emscatter.cli.farm.specs); the options below are then defaults")  # fmt: skip
    g = p.add_argument_group("tables (each list option repeats: the product is built)")
    g.add_argument("--sigma", type=Number(low=0, unit="m"), action="append", metavar="M",
                   help="rms height [m] (default 1.5e-07)")  # fmt: skip
    g.add_argument("--length", type=Number(low=0, unit="m"), action="append", metavar="M",
                   help="correlation length [m] (default 1e-06)")  # fmt: skip
    g.add_argument("--material", type=_material, action="append",
                   help="material name (Au, Ag, itu:concrete, ...) or permittivity (exp(-iωt), "
                   "Im ≥ 0) or 'pec' (default Au)")  # fmt: skip
    g.add_argument("--wavelengths-nm", type=_wavelengths_nm, action="append",
                   help="one wavelength set [nm]: 'a,b,c' or 'start:stop:count' (default "
                   "450,550,650)")  # fmt: skip
    g.add_argument("--kind", default="gaussian", choices=["gaussian", "exponential", "power-law"],
                   help="correlation function")  # fmt: skip
    g.add_argument("--length-y", type=Number(low=0, unit="m"), metavar="M",
                   help="correlation length along y [m] (default: --length)")  # fmt: skip
    g.add_argument("--hurst", type=Number(low=0, high=1), default=0.5,
                   help="Hurst exponent (power-law kind only)")  # fmt: skip
    g.add_argument("--method", type=str.lower, default="auto", choices=_method_choices(),
                   help="solver, or auto")  # fmt: skip
    g.add_argument("--n-theta", type=Integer(low=2, high=2000), help="θ nodes (default 90)")
    g.add_argument("--n-phi", type=Integer(low=4, high=4000),
                   help="Δφ nodes (default 2 × θ nodes, ≥ 180)")  # fmt: skip
    g.add_argument("--tol", type=Number(low=0, high=1), help="adaptive grid to this error")
    g.add_argument("--polarized", action="store_true", help="also f_r per polarization pair")
    g.add_argument("--float32", action="store_true", help="tables in float32")
    g.add_argument("--anisotropic", action="store_true", help="(θi, φi, θo, φo) tables")
    g.add_argument("--energy", default="rescale", choices=["rescale", "off"],
                   help="energy remedy where the albedo exceeds 1")  # fmt: skip
    g.add_argument("--out-of-range", default="warn", choices=["warn", "raise", "ignore"],
                   help="what to do outside the method's validity")  # fmt: skip
    s = p.add_argument_group("scheduler")
    s.add_argument("--scheduler", type=scheduler_address, metavar="local|tcp://HOST:PORT",
                   help="where the tables are built (default: serially, here)")  # fmt: skip
    s.add_argument(
        "--workers",
        type=Integer(low=1, high=4096),
        help="workers of --scheduler local (default: the CPU count ÷ --threads)",
    )
    s.add_argument("--threads", type=Integer(low=1, high=1024), default=1,
                   help="compiled-kernel threads per table (numba, FFT, BLAS)")  # fmt: skip
    s.add_argument("--batch", type=Integer(low=1, high=100000),
                   help="tables per task (default: about 4 tasks per worker)")  # fmt: skip
    s.add_argument("--connect-timeout", type=Number(low=0, unit="s"), default=10.0,
                   metavar="S", help="how long to try to reach a tcp:// scheduler [s]")  # fmt: skip
    p.add_argument("--skip-existing", action="store_true",
                   help="leave tables whose OUT_DIR/<name>.npz exists (resume a farm)")  # fmt: skip
    p.add_argument("--no-compress", action="store_true",
                   help="write the .npz files uncompressed (faster to write)")  # fmt: skip
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (drawn only when stderr is a terminal)")  # fmt: skip
    p.set_defaults(func=run, _command_name="farm brdf")


def _defaults(a) -> dict:
    """The command line's single-valued table options over the built-in defaults."""
    out = dict(_specs.DEFAULTS)
    for key in ("kind", "length_y", "hurst", "method", "n_theta", "n_phi", "tol", "polarized",
                "float32", "anisotropic", "energy", "out_of_range"):  # fmt: skip
        v = getattr(a, key)
        if v is not None:
            out[key] = v
    return out


def tables_of(a) -> tuple[list[dict], list[str], str]:
    """``(tables, names, source)``: every table checked (nothing computed yet)."""
    defaults = _defaults(a)
    reject_unless(a, a.kind == "power-law" or a.spec is not None, ("--hurst",),
                  "to --kind power-law only")  # fmt: skip
    reject_unless(
        a,
        a.scheduler == "local",
        ("--workers",),
        "with --scheduler local only (a running scheduler has its own workers)",
    )
    reject_unless(a, a.scheduler is not None and a.scheduler != "local", ("--connect-timeout",),
                  "with --scheduler tcp://HOST:PORT only")  # fmt: skip
    if a.spec is not None:
        for opt in _specs.GRID_OPTIONS:
            values = getattr(a, opt.lstrip("-").replace("-", "_"))
            if values and len(values) > 1:
                raise ValueError(
                    f"{opt} is given {len(values)} times with --spec {a.spec}: with a spec file "
                    "the options are defaults for every table and take one value each"
                )
            if values:
                defaults[opt.lstrip("-").replace("-", "_")] = values[0]
        tables = _specs.read_spec_file(a.spec, defaults)
        source = f"--spec {a.spec}"
    else:
        tables = _specs.grid_tables(a, defaults)
        source = "--sigma × --length × --material × --wavelengths-nm:"
    names = _specs.name_tables(tables, source)
    return tables, names, source


def run(a) -> int:
    from ... import parallel
    from ...brdf import build_tables
    from ...brdf.farm import check_spec
    from ...io import write_json

    tables, names, source = tables_of(a)
    farm_specs = [_specs.to_farm_spec(t, n) for t, n in zip(tables, names, strict=True)]
    for i, spec in enumerate(farm_specs):  # every table before the cluster starts
        try:
            check_spec(spec, i)
        except ValueError as exc:
            raise ValueError(f"{source} table[{i}] ({names[i]!r}): {_after_spec(exc)}") from None
    out_dir = a.out_dir
    out_dir.mkdir(parents=True, exist_ok=True)
    todo = [
        j for j, n in enumerate(names)
        if not (a.skip_existing and (out_dir / f"{n}.npz").is_file())
    ]  # fmt: skip
    skipped = len(names) - len(todo)
    t0 = time.perf_counter()
    if todo:
        try:
            executor, close = parallel.open_executor(
                a.scheduler, a.workers, a.threads, timeout=a.connect_timeout
            )
        except (OSError, TimeoutError) as exc:
            raise ValueError(
                f"--scheduler {a.scheduler}: no dask scheduler answered within "
                f"{a.connect_timeout:g} s ({' '.join(str(exc).split())}); start one with "
                "'dask scheduler' (and 'dask worker ADDRESS'), or use --scheduler local"
            ) from None
        try:
            link = parallel.dashboard_link(executor)
            if link and not a.quiet:
                print(f"dask dashboard: {link}", file=sys.stderr)
            try:
                build_tables(
                    [farm_specs[j] for j in todo], client=executor, threads=a.threads,
                    progress=False if a.quiet else None, batch=a.batch, out_dir=out_dir,
                    compress=not a.no_compress,
                )  # fmt: skip
            except RuntimeError as exc:  # a worker's table refused its input: the user's error
                if isinstance(exc.__cause__, ValueError | TypeError):
                    raise ValueError(str(exc).removeprefix("build_tables: ")) from None
                raise
        finally:
            close()
    seconds = time.perf_counter() - t0
    manifest = {
        "command": "emscatter farm brdf",
        "scheduler": a.scheduler or "serial",
        "tables": [_specs.manifest_entry(t, n) for t, n in zip(tables, names, strict=True)],
    }
    write_json(out_dir / "manifest.json", manifest)
    where = a.scheduler or "serially"
    extra = f", {skipped} already there" if skipped else ""
    print(f"wrote {len(todo)} tables to {out_dir} ({where}, {seconds:.1f} s{extra}); "
          f"manifest: {out_dir / 'manifest.json'}")  # fmt: skip
    return 0


def _after_spec(exc: ValueError) -> str:
    """``check_spec``'s message without its ``specs[i] ('name')`` prefix (named here)."""
    return re.sub(r"^specs\[\d+\](?: \('[^']*'\))? ", "", str(exc))


__all__ = ["register", "run", "scheduler_address", "tables_of"]
