"""Method of moments for a perfectly conducting or dielectric 2-D rough surface (the 3-D
problem): one realization (:func:`solve_realization`; dielectrics in :mod:`.dielectric_model`)
and the Monte Carlo σ⁰ (:func:`bistatic`).

The formulation (MFIE, pulse bases, point matching, analytic ``J/2`` self term) is in
:mod:`.operator`, the tapered incident wave and its power in :mod:`.incident`, the far field and
the hemisphere quadrature in :mod:`.farfield`. Monte Carlo estimators over ``n``
realizations of the far-field amplitude ``A = p̂_s·F`` (:mod:`.farfield`):

* incoherent σ⁰ from the sample variance ``n/(n−1) (⟨|A|²⟩ − |⟨A⟩|²)``;
* coherent power from the unbiased ``(n |⟨A⟩|² − ⟨|A|²⟩)/(n−1)``, integrated over the upper
  hemisphere (the specular lobe of a finite beam has a width ~ ``2/(k g cosθi)``), summed over
  the scattered polarizations: the coherent reflectivity per incident polarization;
* per realization, the energy ratio ``∫ Σ_p dP/dΩ dΩ / P_inc`` (1 for a perfect conductor:
  the check of every solution, in ``info["energy"]``); for a dielectric ``R + T``
  (reflected plus transmitted power, 1 when lossless; NaN for a lossy medium, whose
  reflectivity per realization is ``info["reflectivity"]``).

A perfect conductor is solved on the dense matrix up to :data:`SMCG_MIN_NODES` nodes (8λ × 8λ
at 8 points/λ) and by the sparse-matrix/canonical-grid product of :mod:`.smcg` above
(``accel=`` chooses); dielectrics densely up to
:data:`~.dielectric_model.DIELECTRIC_SMCG_MIN_NODES` nodes and by the dielectric SMCG
product of :mod:`.dielectric_smcg` (both media's kernels) above. Not registered in
:mod:`emscatter.solvers` yet; call it as ``emscatter.solvers.mom3d.bistatic``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from emscatter.conventions import check_angle, check_finite, check_positive, fmt
from emscatter.fresnel import check_eps, is_pec
from emscatter.parallel import check_client, check_n_workers, check_threads
from emscatter.progress import task
from emscatter.scattering import Scattering
from emscatter.solvers.mom3d.dielectric_model import (
    DIELECTRIC_NEAR_RADIUS,
    dielectric_accel,
    solve_dielectric_realization,
)
from emscatter.solvers.mom3d.farfield import amplitudes, hemisphere
from emscatter.solvers.mom3d.incident import tapered_beam
from emscatter.solvers.mom3d.montecarlo import MEMORY_OVERHEAD, run_realizations, stack_results
from emscatter.solvers.mom3d.operator import assemble, make_patch, rhs, solve
from emscatter.solvers.mom3d.smcg import (
    MAX_PTP_OVER_RD,  # noqa: F401  (kept public here)
    resolve_near_radius,
    smcg_operator,
)
from emscatter.solvers.mom3d.truncated import check_cutoff, cutoff_variance, truncated_heights

__all__ = ["bistatic", "matrix_bytes", "solve_realization"]

#: Largest dense matrix :func:`bistatic` assembles unless told otherwise [bytes].
MAX_MATRIX_BYTES = 2 * 2**30
#: Below this many points per wavelength the pulse-basis MFIE is not trusted.
MIN_PPW = 6.0
#: ``accel="auto"`` takes the SMCG product (:mod:`.smcg`) above this many nodes, dense below.
SMCG_MIN_NODES = 4096
#: Default strong-pair radius of SMCG [wavelengths] (Tsang et al.'s r_d) and Taylor order.
NEAR_RADIUS = 2.5
TAYLOR_ORDER = 3
ACCELS = ("auto", "dense", "smcg")


def matrix_bytes(n_nodes: int, dtype=np.complex128) -> int:
    """Bytes of the dense ``(2N, 2N)`` MFIE matrix for ``n_nodes`` nodes."""
    return (2 * n_nodes) ** 2 * np.dtype(dtype).itemsize


def smcg_bytes(n_nodes: int, near_radius_cells: float) -> int:
    """Estimated bytes of the SMCG strong matrix (complex64 + int32 per nonzero, four
    ``π r_d²`` blocks per node) for ``n_nodes`` nodes and ``r_d`` in grid cells."""
    return int(4 * n_nodes * math.pi * near_radius_cells**2 * 12)


def _accel_for(accel, n_nodes: int, pec: bool) -> str:
    if accel not in ACCELS:
        raise ValueError(f"accel must be one of {ACCELS}, got {accel!r}")
    if not pec:
        return dielectric_accel(accel, n_nodes)
    if accel == "auto":
        return "smcg" if n_nodes > SMCG_MIN_NODES else "dense"
    return accel


def dielectric_smcg_bytes(n_nodes: int, near_radius_cells: float) -> int:
    """Estimated bytes of the dielectric SMCG strong matrix (16 ``π r_d²`` blocks per node,
    complex64 + int32 per nonzero) for ``n_nodes`` nodes and ``r_d`` in grid cells, plus the
    kernel spectra and FFT work arrays of the far part (≈ 214 complex arrays of ``4N``)."""
    return int(16 * n_nodes * math.pi * near_radius_cells**2 * 12 + 214 * 4 * n_nodes * 16)


def _near_radius(near_radius, heights: np.ndarray, k: float, default: float = NEAR_RADIUS) -> float:
    """``r_d`` [m] from ``near_radius`` [λ] (:func:`.smcg.resolve_near_radius`, default
    :data:`NEAR_RADIUS`)."""
    return resolve_near_radius(near_radius, heights, k, default)


def _dtype_for(n_nodes: int):
    """complex128 up to 2048 nodes (64 MiB … 268 MB), complex64 above (half the memory; GMRES
    tolerances of 1e-5 are far above its rounding)."""
    return np.complex128 if n_nodes <= 2048 else np.complex64


def solve_realization(
    heights,
    spacing: float,
    k: float,
    theta_i: float,
    theta_s,
    phi_s,
    phi_i: float = 0.0,
    *,
    taper_g: float | None = None,
    polarizations: tuple[str, ...] = ("h", "v"),
    n_mu: int | None = None,
    tol: float = 1e-5,
    max_iter: int = 300,
    dtype=None,
    accel: str = "auto",
    near_radius: float | None = None,
    taylor_order: int = TAYLOR_ORDER,
) -> dict:
    """Solve the MFIE on one ``(ny, nx)`` height map [m] with square ``spacing`` [m].

    Returns a dict: ``amplitude`` ``(2, P, D)`` (scattered pol × incident pol × direction, the
    directions ``theta_s, phi_s`` flattened), ``hemisphere`` (the same on the quadrature of
    :func:`~emscatter.solvers.mom3d.farfield.hemisphere`, with ``weights``), ``power`` the
    incident power [m²], ``beam`` (:class:`~.incident.TaperedBeam`), ``current`` ``(P, N, 3)``
    the density ``u = sJ`` on ``points`` ``(N, 3)``, ``energy`` ``(P,)`` the
    scattered-to-incident power ratio,
    ``iterations``, ``residual``, ``seconds`` and the sizes.

    ``accel``: ``"dense"`` (the full matrix, :func:`.operator.assemble`), ``"smcg"`` (the
    sparse-matrix/canonical-grid product of :mod:`.smcg`: pairs closer than ``near_radius``
    [wavelengths, default 2.5, enlarged to 1.25 × the peak-to-valley height] exact and sparse,
    the rest by a Taylor series of order ``taylor_order`` in ``Z²`` and FFTs) or ``"auto"``
    (SMCG above :data:`SMCG_MIN_NODES` nodes). ``matrix_bytes`` is then the sparse matrix
    plus kernel spectra; ``nonzeros`` its entries.
    """
    t0 = time.perf_counter()
    h = np.asarray(heights, dtype=float)
    patch = make_patch(h, spacing, spacing)
    ny, nx = patch.shape
    half_x, half_y = (nx - 1) / 2 * spacing, (ny - 1) / 2 * spacing
    g = taper_g if taper_g is not None else min(nx, ny) * spacing / 4.0
    beam = tapered_beam(k, theta_i, phi_i, g, math.hypot(half_x, half_y))
    points = patch.points
    mode = _accel_for(accel, patch.n, True)
    dt = dtype if dtype is not None else _dtype_for(patch.n)
    extra = {"accel": mode}
    if mode == "smcg":
        rd = _near_radius(near_radius, h, k)
        sdt = np.complex64 if dtype is None else dtype
        mat = smcg_operator(patch, k, near_radius=rd, taylor_order=taylor_order, dtype=sdt)
        nbytes = mat.nbytes
        extra.update(near_radius=rd * k / (2 * math.pi), taylor_order=taylor_order)
        extra["nonzeros"] = mat.strong.nnz
    else:
        mat = assemble(patch, k, dtype=dt)
        nbytes = matrix_bytes(patch.n, dt)
    t_assemble = time.perf_counter() - t0
    b = [rhs(patch, beam.fields(points, p)[1]) for p in polarizations]
    sol = solve(mat, patch, b, tol=tol, max_iter=max_iter)
    del mat
    t_solve = time.perf_counter() - t0 - t_assemble
    u = np.stack(sol.u)  # (P, N, 3)
    area = spacing * spacing
    amp = amplitudes(points, area, k, u, theta_s, phi_s)
    if n_mu is None:  # resolve the beam's lobes: ~4 nodes per 2π/L in k⊥
        n_mu = max(24, int(math.ceil(2.0 * k * max(nx, ny) * spacing / math.pi)))
    th, ph, wt = hemisphere(n_mu)
    hemi = amplitudes(points, area, k, u, th, ph)
    scale = k * k / (16.0 * math.pi**2) / beam.power
    energy = scale * np.einsum("spd,d->p", np.abs(hemi) ** 2, wt)
    if not np.all(np.isfinite(energy)):
        raise FloatingPointError("mom3d: the scattered power is not finite (NaN or inf)")
    return {
        "amplitude": amp,
        "hemisphere": hemi,
        "weights": wt,
        "power": beam.power,
        "beam": beam,
        "current": u,
        "points": points,
        "energy": energy,
        "iterations": sol.iterations,
        "residual": sol.residual,
        "seconds": {"assemble": t_assemble, "solve": t_solve, "total": time.perf_counter() - t0},
        "unknowns": 2 * patch.n,
        "taper_g": g,
        "n_mu": n_mu,
        "matrix_bytes": nbytes,
        **extra,
    }


#: What one realization sends back from a worker (small arrays and scalars).
RESULT_KEYS = (
    "amplitude", "hemisphere", "weights", "energy", "iterations", "power", "unknowns",
    "matrix_bytes", "taper_g", "reflectivity",
)  # fmt: skip


def _realization(job: dict, ss: np.random.SeedSequence) -> dict:
    """One realization of ``job`` (the checked arguments of ``bistatic``) from the seed
    ``ss``: the surface, its solve and the entries of :data:`RESULT_KEYS` plus ``seconds``
    (module-level: the task of :func:`.montecarlo.run_realizations` on any executor)."""
    from emscatter.surfaces.generate import generate_surface

    n_side, spacing, k, eps = job["n_side"], job["spacing"], job["k"], job["eps"]
    gen = np.random.default_rng(ss)
    if job.get("cutoff") is None:
        heights = generate_surface(job["roughness"], (n_side, n_side), spacing, rng=gen).heights
    else:
        heights = truncated_heights(job["roughness"], n_side, spacing, job["cutoff"], gen)
    args = (job["theta_i"], job["theta_s"], job["phi_s"], job["phi_i"])
    if is_pec(eps):
        out = solve_realization(heights, spacing, k, *args, **job["options"], **job["fast"])
        out["reflectivity"] = np.ones(2)
    else:
        out = solve_dielectric_realization(heights, spacing, k, eps, *args,
                                           **job["options"], **job["fast"])  # fmt: skip
        out["energy"] = out["reflectivity"] + out["transmissivity"]
    res = {key: out[key] for key in RESULT_KEYS}
    res["seconds"] = out["seconds"]["total"]
    return res


def _check(roughness, eps, k, theta_i, length, ppw, realizations, max_bytes, accel="dense",
           near_radius=None):  # fmt: skip
    eps = check_eps(eps)
    if not is_pec(eps):
        if np.ndim(eps) != 0:
            raise ValueError(f"mom3d needs one scalar eps, got an array of shape {np.shape(eps)}")
        eps = complex(eps)
        if abs(eps - 1.0) < 1e-9:
            raise ValueError(f"eps={eps!r} is air: there is no interface to scatter from")
    if getattr(roughness, "dimension", None) != 2:
        raise ValueError(
            "mom3d needs a 2-D surface roughness (dimension=2), got "
            f"dimension={getattr(roughness, 'dimension', None)!r}"
        )
    k = check_positive("k", k, unit="rad/m")
    ti = float(check_angle("theta_i", theta_i, high=math.radians(80.0)))
    if not isinstance(realizations, int) or isinstance(realizations, bool) or realizations < 2:
        raise ValueError(
            f"realizations must be an int ≥ 2 (coherent and incoherent parts need two), "
            f"got {realizations!r}"
        )
    ppw = check_positive("points_per_wavelength", ppw)
    if ppw < MIN_PPW:
        raise ValueError(f"points_per_wavelength must be ≥ {MIN_PPW:g}, got {fmt(ppw)}")
    # dielectrics: points per wavelength in the denser medium (λ / Re √ε), Tsang's denser grid
    lam = 2 * math.pi / k / (1.0 if is_pec(eps) else max(1.0, np.sqrt(eps).real))
    lam0 = 2 * math.pi / k
    length = 8.0 * lam0 if length is None else check_positive("length", length, unit="m")
    n_side = int(math.ceil(length / lam * ppw))
    mode = _accel_for(accel, n_side * n_side, is_pec(eps))
    need = matrix_bytes(n_side * n_side, _dtype_for(n_side * n_side))
    what = "dense matrix"
    if mode == "smcg":
        rd_cells = (near_radius or NEAR_RADIUS) * ppw
        need, what = smcg_bytes(n_side * n_side, rd_cells), "SMCG sparse matrix"
    if not is_pec(eps):
        need, what = (4 * n_side * n_side) ** 2 * 16, "dense matrix"
        if mode == "smcg":
            rd_cells = (near_radius or DIELECTRIC_NEAR_RADIUS) * lam0 / lam * ppw
            need = dielectric_smcg_bytes(n_side * n_side, rd_cells)
            what = "dielectric SMCG sparse matrix"
    if need > max_bytes:
        raise ValueError(
            f"length={fmt(length)} m at points_per_wavelength={fmt(ppw)} needs "
            f"{n_side}² nodes and a {need / 2**30:.3g} GiB {what}, over "
            f"max_matrix_bytes={max_bytes / 2**30:.3g} GiB: use a smaller patch or raise it"
        )
    return eps, k, ti, length, n_side, lam, mode, need


def bistatic(
    roughness,
    eps,
    k: float,
    theta_i: float,
    theta_s,
    phi_s=0.0,
    phi_i: float = 0.0,
    *,
    realizations: int = 8,
    seed=0,
    length: float | None = None,
    points_per_wavelength: float = 8.0,
    taper_g: float | None = None,
    tol: float = 1e-5,
    max_iter: int = 300,
    max_matrix_bytes: int = MAX_MATRIX_BYTES,
    progress: bool | None = None,
    accel: str = "auto",
    near_radius: float | None = None,
    taylor_order: int = TAYLOR_ORDER,
    spectral_cutoff: float | None = None,
    client=None,
    threads: int | None = 1,
    n_workers: int | None = None,
) -> Scattering:
    """Monte Carlo MoM σ⁰ per unit area of a perfectly conducting 2-D rough surface.

    Parameters
    ----------
    roughness : a 2-D :class:`~emscatter.spectra.Roughness` (Gaussian, exponential, …).
    eps : ``"pec"`` (MFIE, :mod:`.operator`) or a complex scalar with ``Im ε ≥ 0`` below air
        (Müller's equations, :mod:`.dielectric`; four unknowns per node).
    k : free-space wavenumber [rad/m].
    theta_i : incidence angle [rad], scalar, ``[0°, 80°]``; ``phi_i`` its azimuth [rad].
    theta_s, phi_s : scattering directions [rad], broadcast together.
    realizations : surfaces (≥ 2), each from ``SeedSequence(seed).spawn``; reproducible.
    length : side of the square patch [m] (default 8λ).
    points_per_wavelength : nodes per λ along each axis (default 8, at least 6); for a
        dielectric per wavelength inside it, ``λ / Re √ε`` (the denser grid it needs).
    taper_g : taper radius [m] (default ``length/4``).
    tol, max_iter : GMRES relative residual and iteration cap (an unconverged solve raises).
    max_matrix_bytes : refuse patches whose dense (or SMCG sparse) matrix exceeds this
        (default 2 GiB).
    progress : a tqdm bar over the realizations on stderr (seconds and energy of the last one
        beside it): ``None`` (auto) on a terminal past 2 s, ``True`` always, ``False`` never.
    accel, near_radius, taylor_order : ``"dense"``, ``"smcg"`` (strong pairs within
        ``near_radius`` free-space wavelengths sparse, the rest by FFT: :mod:`.smcg` for a
        perfect conductor, :mod:`.dielectric_smcg` for a dielectric, default radius 2.5 λ and
        :data:`~.dielectric_model.DIELECTRIC_NEAR_RADIUS` respectively) or ``"auto"`` (SMCG
        above :data:`SMCG_MIN_NODES` nodes for PEC,
        :data:`~.dielectric_model.DIELECTRIC_SMCG_MIN_NODES` for a dielectric); see
        :func:`solve_realization` and
        :func:`~.dielectric_model.solve_dielectric_realization`.
    spectral_cutoff : None (default: the surfaces of
        :func:`~emscatter.surfaces.generate.generate_surface`, exact circulant embedding) or
        ``K_c`` [rad/m], at most the grid's Nyquist ``π/Δx``: each surface band-limited to
        ``|K| ≤ K_c`` by periodic spectral synthesis (:mod:`.truncated`), variance
        ``info["surface_variance"]`` = the target's minus the removed tail (for a spectrum
        that decays as a power, the exponential's, so that the MFIE converges with the grid).
    client : where the realizations run (:mod:`.montecarlo`): None (serially, here),
        ``"local"`` (a dask LocalCluster of ``n_workers`` single-threaded processes, closed at
        the end), a scheduler address ``"tcp://host:port"``, a dask.distributed ``Client`` or
        any :class:`concurrent.futures.Executor`. Realization ``j`` draws its surface from
        ``seeds[j]`` whatever the worker, so the result is bit-identical to the serial run.
        Each worker holds one realization's matrix at a time: ``info["bytes_per_worker"]``.
    threads : compiled threads (BLAS, scipy.fft, numba) per worker (default 1); None: no cap.
        Ignored serially (``client=None`` uses this process's defaults).
    n_workers : workers of ``client="local"`` (default: CPU count ÷ ``threads``, no more
        than the free memory holds at ``bytes_per_worker`` each).

    Returns
    -------
    :class:`~emscatter.scattering.Scattering` with ``sigma0[pol_s, pol_i]`` (incoherent),
    ``coherent`` per incident pol, ``method="mom3d"``, and in ``info``: ``energy``
    ``(realizations, 2)``, ``incoherent_reflectivity`` ``(2,)``, iterations, seconds per
    realization, unknowns, matrix bytes, ``bytes_per_worker`` (matrix plus GMRES working
    memory of one realization [bytes]), ``sigma0_std`` (standard error of σ⁰),
    ``sigma0_samples`` ``(realizations, 2, 2, …)`` (each realization's incoherent σ⁰,
    ``n/(n−1)·|A − ⟨A⟩|²`` scaled; their mean is σ⁰ — pool directions on them, then take the
    standard error over realizations).
    """
    eps, k, ti, length, n_side, lam, mode, need = _check(
        roughness, eps, k, theta_i, length, points_per_wavelength, realizations,
        max_matrix_bytes, accel, near_radius,
    )  # fmt: skip
    pi_ = float(check_finite("phi_i", phi_i))
    ts = check_angle("theta_s", theta_s)
    ps = check_finite("phi_s", phi_s)
    ts_b, ps_b = np.broadcast_arrays(ts, ps)
    shape = ts_b.shape
    threads = check_threads(threads)
    n_workers = check_n_workers(n_workers)
    check_client(client)
    spacing = lam / points_per_wavelength
    cutoff = check_cutoff(spectral_cutoff, spacing)
    seeds = np.random.SeedSequence(seed).spawn(realizations)  # realization j: seeds[j]
    job = {
        "roughness": roughness, "n_side": n_side, "spacing": spacing, "k": k, "eps": eps,
        "theta_i": ti, "theta_s": ts_b.ravel(), "phi_s": ps_b.ravel(), "phi_i": pi_,
        "options": {"taper_g": taper_g, "tol": tol, "max_iter": max_iter},
        "fast": {"accel": mode, "near_radius": near_radius, "taylor_order": taylor_order},
        "cutoff": cutoff,
    }  # fmt: skip
    with task("mom3d realizations", realizations, progress, unit="realization") as bar:
        results = run_realizations(_realization, job, seeds, client=client, threads=threads,
                                   n_workers=n_workers, bar=bar, bytes_per_worker=need)  # fmt: skip
    out = stack_results(results)
    n = realizations
    a = out["amplitude"]  # (n, 2, 2, D)
    scale = k * k / (16.0 * math.pi**2) / out["power"]
    var = n / (n - 1) * (np.mean(np.abs(a) ** 2, axis=0) - np.abs(a.mean(axis=0)) ** 2)
    sig = 4.0 * math.pi * math.cos(ti) * scale * var
    sig_se = 4.0 * math.pi * math.cos(ti) * scale * np.std(np.abs(a) ** 2, axis=0) / math.sqrt(n)
    # per realization n/(n−1)|A − ⟨A⟩|²: their mean is σ⁰ (pool directions, then take the SE)
    samples = 4.0 * math.pi * math.cos(ti) * scale * n / (n - 1) * np.abs(a - a.mean(axis=0)) ** 2
    hm = out["hemisphere"]
    p_tot = np.mean(np.abs(hm) ** 2, axis=0)
    p_coh = (n * np.abs(hm.mean(axis=0)) ** 2 - p_tot) / (n - 1)
    wt = out["weights"]
    r_coh = scale * np.einsum("spd,d->p", p_coh, wt)
    r_tot = scale * np.einsum("spd,d->p", p_tot, wt)
    sigma0 = sig.reshape(2, 2, *shape)
    if not np.all(np.isfinite(sigma0)):
        raise FloatingPointError("mom3d: σ⁰ is not finite")
    coherent = np.broadcast_to(
        np.clip(r_coh, 0.0, None)[(...,) + (None,) * len(shape)], (2, *shape)
    )
    return Scattering(
        sigma0=sigma0,
        coherent=np.array(coherent),
        method="mom3d",
        theta_i=np.broadcast_to(ti, shape).copy(),
        theta_s=np.array(ts_b, dtype=float),
        phi_s=np.array(ps_b, dtype=float),
        phi_i=np.broadcast_to(pi_, shape).copy(),
        k=k,
        dimension=2,
        info={
            "energy": out["energy"],
            "reflectivity": out["reflectivity"],
            "incoherent_reflectivity": r_tot - r_coh,
            "sigma0_std": sig_se.reshape(2, 2, *shape),
            "sigma0_samples": samples.reshape(n, 2, 2, *shape),
            "iterations": out["iterations"],
            "seconds_per_realization": out["seconds"],
            "unknowns": out["unknowns"],
            "matrix_bytes": out["matrix_bytes"],
            "length": length,
            "points_per_wavelength": points_per_wavelength,
            "taper_g": out["taper_g"],
            "realizations": n,
            "accel": mode,
            "spectral_cutoff": cutoff,
            "surface_variance": (
                roughness.sigma**2
                if cutoff is None
                else cutoff_variance(roughness, n_side, spacing, cutoff)
            ),
            "bytes_per_worker": int(need * MEMORY_OVERHEAD),
        },
    )
