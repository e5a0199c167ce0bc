"""How big a table must be, and how big it may be: the default resolution from the lobe width,
and the memory a build needs, estimated before any work.

Resolution from the lobe width
------------------------------
The multilinear interpolant of a lobe of angular rms width ``s`` on nodes of spacing ``h`` errs
by ``≈ (h/s)²`` relative (``h²/8 · |f''/f|``, growing away from the peak). For the specular
lobe of a Gaussian-correlated surface, in the outgoing angle:

* geometric optics (Beckmann slope ``m = 2σ/ℓ``, the total rms slope; the half-vector's slope
  per direction has rms ``m/√2`` and ``θo ≈ 2θh``): ``s_GO = √2 m = 2√2 σ/ℓ``;
* the diffraction (first-order, ``kσ ≪ 1``) lobe ``w(K) ∝ exp(−K²ℓ²/4)``, ``K ≈ k Δθ``:
  ``s_diff = √2/(kℓ)``.

A wave solver's lobe is the wider of the two, ``s = √2/ℓ · max(2σ, 1/k)``, GO's is ``s_GO``;
for anisotropic surfaces the narrower direction (``min(ℓ, ℓ_y)``) counts.

Measured on GO, ``m = 0.05`` (tests/test_brdf_sizing.py; directions whose half-vector has
``D(h) ≥ 1 % D(0)``, θ ≤ 80°, against direct GO evaluation): the median relative error is
``≈ 0.37 (h/s)²`` and the 90th percentile ``≈ 1.6 (h/s)²`` (90 × 180: 2.2 % / 9.6 %;
180 × 360: 0.56 % / 2.4 %). The default grid keeps ``h ≤ 0.1 s`` on both the θ and the Δφ axes
(p90 ≈ 1.6 %, median ≈ 0.4 %), never coarser than 1° (90 × 180) and at most
:data:`MAX_AUTO_THETA` θ nodes; where that cap is too coarse the builder warns with the
predicted error and the resolution that meets the target.

Memory
------
:func:`estimate_bytes` counts the arrays a build holds at its peak: the full grid of every
wavelength (``n_θ² n_φ`` isotropic, ``(n_θ n_φ)²`` anisotropic; four more per-pair grids when
``polarized``) in the storage ``dtype``, filled in place; the energy remedy's two copies of it
and its two float64 direction-pair matrices of anisotropic tables; the solver's workspace on at
most :data:`CHUNK_PAIRS` points at a time.
:func:`memory_limit` is what this process may still allocate: the smallest of the address-space
limit (``RLIMIT_AS``) less what is mapped, the cgroup limit less what is used, and the
available physical memory.
"""

from __future__ import annotations

import math
import os

import numpy as np

__all__ = [
    "CHUNK_PAIRS",
    "MAX_AUTO_THETA",
    "TARGET_STEP",
    "auto_resolution",
    "check_memory",
    "estimate_bytes",
    "format_bytes",
    "lobe_width",
    "memory_limit",
    "predicted_error",
    "TableTooLarge",
]

#: Grid spacing over lobe width the default grid keeps (predicted p90 error ≈ 1.6 %).
TARGET_STEP = 0.1
#: The most θ nodes the default grid takes by itself (256² × 512 × 8 B = 268 MB a wavelength).
MAX_AUTO_THETA = 256
#: Solver points per call while a table is filled (bounds the solver's temporaries): 65536
#: keeps each float64 temporary at 512 kB, reused from the allocator's free lists instead of a
#: fresh zeroed mapping per temporary (2**20: 8 MB each, page-faulted in on every call). A PO
#: 90×180 table: 380–395 ms CPU (2**16) vs 450–750 ms (2**20), GO 40 vs 47–62 ms; the values
#: are the same bit for bit (tests/test_brdf_sizing.py), and two builds side by side no longer
#: contend in the kernel's page zeroing (benchmarks/bench_brdf_farm.py).
CHUNK_PAIRS = 1 << 16
#: Solver workspace per point [bytes] (GO fills measured 230–370 B a point, with margin).
WORKSPACE_PER_POINT = 450
_K_MEDIAN, _K_P90 = 0.37, 1.6  # relative error ≈ K (h/s)² (module docstring)
_BASE = (90, 180)


def lobe_width(rough, wavelengths, solvers) -> float | None:
    """The narrowest specular-lobe rms width [rad] over the wavelengths [m] (module docstring),
    ``solvers`` the solver name per wavelength; None when the roughness has no finite slope
    variance (then only the diffraction width counts) and no length."""
    length = min(rough.length, rough.length_y)
    try:
        sx, sy = rough.mean_square_slope()
        # per-direction ⟨ζ²⟩ = 2σ²/ℓ² → Beckmann m = 2σ/ℓ = √(2⟨ζ²⟩), the narrow direction's
        slope = math.sqrt(2.0 * min(sx, sy))
    except ValueError:  # infinite slope variance (exponential, power law)
        slope = None
    widths = []
    for lam, name in zip(np.atleast_1d(wavelengths), solvers, strict=True):
        k = 2 * math.pi / float(lam)
        go = None if slope is None else math.sqrt(2.0) * slope
        if name == "go":
            if go is not None:
                widths.append(go)
            continue
        diff = math.sqrt(2.0) / (k * length)
        widths.append(diff if go is None else max(go, diff))
    return min(widths) if widths else None


def predicted_error(step: float, width: float) -> tuple[float, float]:
    """``(median, p90)`` relative interpolation error in the lobe for grid spacing ``step``
    and lobe width ``width`` [rad] (the calibration in the module docstring)."""
    r2 = (step / width) ** 2
    return _K_MEDIAN * r2, _K_P90 * r2


def nodes_for(width: float) -> tuple[int, int]:
    """``(n_theta, n_phi)`` with spacing ``TARGET_STEP · width`` on θ ∈ [0, π/2) and Δφ ∈ [0, π]."""
    h = TARGET_STEP * width
    n_t = max(_BASE[0], math.ceil(0.5 * math.pi / h))
    return n_t, max(_BASE[1], 2 * n_t)


def auto_resolution(width: float | None, anisotropic: bool):
    """``(resolution, note)``: the default ``(n_theta, n_phi)`` for lobe ``width`` [rad] and a
    warning text (None when the grid meets the target). Anisotropic tables keep 90 × 180 (their
    size grows as n⁴) and get the note when it is too coarse."""
    if width is None:
        return _BASE, None
    want = nodes_for(width)
    if anisotropic:
        res = _BASE
    else:
        res = (min(want[0], MAX_AUTO_THETA), min(want[1], 2 * MAX_AUTO_THETA))
    if res[0] >= want[0]:
        return res, None
    med, p90 = predicted_error(0.5 * math.pi / res[0], width)
    return res, (
        f"build_table: the specular lobe is {math.degrees(width):.3g}° wide (rms), too narrow "
        f"for the default {res[0]} × {res[1]} grid: predicted interpolation error in the lobe "
        f"{100 * med:.2g} % median, {100 * p90:.2g} % p90 (tolerated: p90 ≈ "
        f"{100 * _K_P90 * TARGET_STEP**2:.2g} %); resolution=({want[0]}, {want[1]}) meets it "
        f"(about {format_bytes(grid_points(*want, anisotropic) * 8)} a wavelength), or pass "
        "resolution= (or theta=/phi=, tol=) to choose"
    )


def grid_points(n_theta: int, n_phi: int, anisotropic: bool) -> int:
    """Node pairs of the full grid (one wavelength)."""
    if anisotropic:
        return (n_theta * n_phi) ** 2
    return n_theta * n_theta * n_phi


def estimate_bytes(
    n_theta: int,
    n_phi: int,
    n_wl: int,
    *,
    anisotropic: bool,
    polarized: bool,
    itemsize: int,
    energy: str = "rescale",
) -> int:
    """Peak bytes of a build (module docstring): the stored grid ``S`` (values, and the four
    polarization pairs), the solver's workspace on one chunk, and for ``energy="rescale"``
    the remedy's two copies of ``S`` plus (anisotropic) its two float64 direction-pair
    matrices."""
    g = grid_points(n_theta, n_phi, anisotropic)
    stored = n_wl * g * itemsize * (5 if polarized else 1)
    work = min(g // 2 + 1, CHUNK_PAIRS) * WORKSPACE_PER_POINT * (3 if polarized else 1)
    remedy = 2 * stored + (2 * g * 8 if anisotropic else 0) if energy == "rescale" else 0
    return int(stored + work + remedy)


def format_bytes(n: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} B"


def _read_int(path: str) -> int | None:
    try:
        with open(path) as fh:
            text = fh.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def _proc_kb(path: str, key: str) -> int | None:
    try:
        with open(path) as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def memory_limit() -> tuple[int | None, str]:
    """``(bytes, where)``: what this process may still allocate, and which limit that is
    (module docstring); ``(None, "unknown")`` where nothing can be read."""
    found = []
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft not in (resource.RLIM_INFINITY, -1):
            used = _proc_kb("/proc/self/status", "VmSize") or 0
            found.append((soft - used, f"the address-space limit (ulimit -v) {format_bytes(soft)}"))
    except (ImportError, OSError, ValueError):
        pass
    cg_max = _read_int("/sys/fs/cgroup/memory.max")
    if cg_max is not None:
        cg_used = _read_int("/sys/fs/cgroup/memory.current") or 0
        found.append((cg_max - cg_used, f"the cgroup memory limit {format_bytes(cg_max)}"))
    avail = _proc_kb("/proc/meminfo", "MemAvailable")
    if avail is not None:
        found.append((avail, "the available physical memory"))
    if not found:
        return None, "unknown"
    n, where = min(found)
    return max(int(n), 0), where


def check_memory(
    n_theta: int,
    n_phi: int,
    n_wl: int,
    *,
    anisotropic: bool,
    polarized: bool,
    dtype,
    energy: str = "rescale",
    limit: int | None = None,
) -> int:
    """The estimate [bytes]; :class:`TableTooLarge` (a ``MemoryError``) naming it, the limit and
    how to reduce it when it exceeds ``limit`` (bytes; None: ``EMSCATTER_MEMORY_LIMIT`` if set,
    else :func:`memory_limit`)."""
    itemsize = np.dtype(dtype).itemsize
    need = estimate_bytes(
        n_theta,
        n_phi,
        n_wl,
        anisotropic=anisotropic,
        polarized=polarized,
        itemsize=itemsize,
        energy=energy,
    )
    where = "memory_limit="
    if limit is None and env_limit() is not None:
        limit, where = env_limit(), "EMSCATTER_MEMORY_LIMIT"
    if limit is None:
        limit, where = memory_limit()
        if limit is None:
            return need
    if need <= limit:
        return need
    kind = "an anisotropic" if anisotropic else "an isotropic"
    hints = []  # (API text, CLI text)
    for res in ((45, 72), (30, 48)) if anisotropic else ((90, 180), (60, 120)):
        if res[0] < n_theta:
            est = format_bytes(
                estimate_bytes(
                    *res,
                    n_wl,
                    anisotropic=anisotropic,
                    polarized=polarized,
                    itemsize=itemsize,
                    energy=energy,
                )
            )
            hints.append(
                (f"resolution={res} ({est})", f"--n-theta {res[0]} --n-phi {res[1]} ({est})")
            )
    if itemsize > 4:
        est = format_bytes(
            estimate_bytes(
                n_theta,
                n_phi,
                n_wl,
                anisotropic=anisotropic,
                polarized=polarized,
                itemsize=4,
                energy=energy,
            )
        )
        hints.append((f"dtype='float32' ({est})", f"--float32 ({est})"))
    if energy == "rescale":
        est = format_bytes(
            estimate_bytes(
                n_theta,
                n_phi,
                n_wl,
                anisotropic=anisotropic,
                polarized=polarized,
                itemsize=min(itemsize, 4),
                energy="off",
            )
        )
        hints.append(
            (f"energy='off' (with float32: {est})", f"--energy off (with --float32: {est})")
        )
    if polarized:
        hints.append(("polarized=False", "no --polarized"))
    if n_wl > 1:
        hints.append(("fewer wavelengths", "fewer --wavelengths-nm"))
    pairs = grid_points(n_theta, n_phi, anisotropic)
    head = (
        f"build_table: {kind} {n_theta} × {n_phi} table at {n_wl} wavelength(s) "
        f"({pairs:.3g} node pairs each, {np.dtype(dtype).name}) needs about "
        f"{format_bytes(need)}, more than the {format_bytes(limit)} this process may "
        f"allocate ({where}); reduce it with "
    )
    raise TableTooLarge(head, [h[0] for h in hints], [h[1] for h in hints], need, limit)


class TableTooLarge(MemoryError):
    """A build whose estimated peak exceeds the limit, raised before any work: ``need`` and
    ``limit`` [bytes], the remedies for the API (``str(exc)``) and for the CLI (:meth:`cli`)."""

    def __init__(self, head: str, api_hints: list, cli_hints: list, need: int, limit: int):
        self.head, self.api_hints, self.cli_hints = head, api_hints, cli_hints
        self.need, self.limit = need, limit
        super().__init__(self._text(api_hints))

    def _text(self, hints) -> str:
        return self.head + ", ".join(hints) + " — nothing was computed"

    def cli(self) -> str:
        """The message with the command line's options."""
        return self._text(self.cli_hints).replace("build_table: ", "", 1)


def env_limit() -> int | None:
    """``EMSCATTER_MEMORY_LIMIT`` [bytes] if set (tests and batch jobs), else None."""
    text = os.environ.get("EMSCATTER_MEMORY_LIMIT")
    if not text:
        return None
    try:
        value = int(float(text))
    except ValueError as exc:
        raise ValueError(f"EMSCATTER_MEMORY_LIMIT must be a number of bytes, got {text!r}") from exc
    if value <= 0:
        raise ValueError(f"EMSCATTER_MEMORY_LIMIT must be positive bytes, got {text!r}")
    return value
