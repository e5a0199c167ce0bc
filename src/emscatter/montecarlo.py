"""Monte Carlo over surface realizations, on any :class:`concurrent.futures.Executor`.

:func:`run` calls ``func(rng)`` once per realization, each with its own
:class:`numpy.random.Generator` seeded from ``np.random.SeedSequence(seed).spawn(n)[i]``,
and returns the mean and the standard error of what ``func`` returns (an array, a number,
or a dict of them). Realization ``i`` always gets the same seed, and the realizations are
grouped into fixed chunks whose statistics are merged in chunk order (Chan, Golub & LeVeque
1983 pairwise update), so the numbers are the same, bit for bit, serially, on a thread or
process pool, or on a dask.distributed cluster (``client.get_executor()``)::

    from dask.distributed import Client, LocalCluster
    with LocalCluster(n_workers=2) as cluster, Client(cluster) as client:
        res = run(func, 64, seed=1, executor=client.get_executor())

``func`` must be picklable for process pools and distributed clusters (a module-level
function or an instance of a module-level class).
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .progress import task

__all__ = ["MonteCarloResult", "run", "realization_seeds"]


@dataclass(frozen=True)
class MonteCarloResult:
    """Statistics over ``n`` realizations.

    ``mean`` and ``std_error`` (``std / √n``, sample standard deviation with ``n − 1``) have
    the structure ``func`` returned: an array, or a dict of arrays. ``std`` is the sample
    standard deviation. ``entropy`` reproduces the seeds: ``run(..., seed=entropy)``.
    """

    mean: object
    std_error: object
    std: object
    n: int
    entropy: int | tuple
    chunk: int
    info: dict = field(default_factory=dict)


def realization_seeds(seed, n: int) -> tuple[np.random.SeedSequence, list[np.random.SeedSequence]]:
    """``(root, children)``: ``np.random.SeedSequence(seed).spawn(n)``."""
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    return root, root.spawn(n)


def _as_dict(value) -> tuple[dict[str, np.ndarray], bool]:
    if isinstance(value, dict):
        return {k: np.asarray(v, dtype=float) for k, v in value.items()}, True
    return {"": np.asarray(value, dtype=float)}, False


def _run_chunk(func: Callable, seeds: list[np.random.SeedSequence], start: int):
    """Realizations ``start, start+1, ...`` with their seeds: ``(n, mean, M2, is_dict)``
    (Welford's running update, in realization order)."""
    n = 0
    mean: dict[str, np.ndarray] = {}
    m2: dict[str, np.ndarray] = {}
    is_dict = False
    for i, ss in enumerate(seeds):
        try:
            value = func(np.random.default_rng(ss))
        except Exception as exc:
            raise RuntimeError(f"realization {start + i} failed: {exc!r}") from exc
        d, is_dict = _as_dict(value)
        n += 1
        if n == 1:
            mean = {k: v.copy() for k, v in d.items()}
            m2 = {k: np.zeros_like(v) for k, v in d.items()}
            continue
        if d.keys() != mean.keys():
            raise ValueError(
                f"realization {start + i} returned keys {sorted(d)}, expected {sorted(mean)}"
            )
        for k, v in d.items():
            if v.shape != mean[k].shape:
                raise ValueError(
                    f"realization {start + i} returned shape {v.shape} for {k!r}, "
                    f"expected {mean[k].shape}"
                )
            delta = v - mean[k]
            mean[k] = mean[k] + delta / n
            m2[k] = m2[k] + delta * (v - mean[k])
    return n, mean, m2, is_dict


def _merge(a, b):
    """Chan et al. (1983) pairwise merge of ``(n, mean, M2)``."""
    na, ma, sa = a
    nb, mb, sb = b
    n = na + nb
    mean, m2 = {}, {}
    for k in ma:
        delta = mb[k] - ma[k]
        mean[k] = ma[k] + delta * (nb / n)
        m2[k] = sa[k] + sb[k] + delta * delta * (na * nb / n)
    return n, mean, m2


def run(
    func: Callable[[np.random.Generator], object],
    n_realizations: int,
    *,
    seed=None,
    executor: cf.Executor | None = None,
    progress: bool | None = None,
    chunk: int | None = None,
    desc: str = "realizations",
) -> MonteCarloResult:
    """Mean and standard error of ``func(rng)`` over ``n_realizations`` realizations.

    Parameters
    ----------
    func : callable taking a :class:`numpy.random.Generator`, returning a number, an array
        or a dict of arrays (same shapes every time). Must be finite.
    n_realizations : number of realizations, ≥ 2 (a standard error needs two).
    seed : ``int``, ``SeedSequence`` or ``None`` (fresh entropy, recorded in the result).
    executor : any :class:`concurrent.futures.Executor` (thread/process pool, dask's
        ``client.get_executor()``); ``None`` runs serially in this process.
    progress : a tqdm bar over the realizations on stderr, advanced per chunk: ``None`` (auto)
        when stderr is a terminal and the run lasts past 2 s, ``True`` always, ``False``
        never (:mod:`emscatter.progress`).
    chunk : realizations per task; default ``ceil(n/32)``. It depends on ``n`` only, so the
        same seed gives the same numbers on every executor.
    """
    if isinstance(n_realizations, bool) or not isinstance(n_realizations, numbers.Integral):
        raise TypeError(f"n_realizations must be an integer, got {n_realizations!r}")
    n_realizations = int(n_realizations)
    if n_realizations < 2:
        raise ValueError(f"n_realizations must be >= 2, got {n_realizations}")
    if chunk is None:
        chunk = max(1, math.ceil(n_realizations / 32))
    if isinstance(chunk, bool) or not isinstance(chunk, numbers.Integral) or chunk < 1:
        raise ValueError(f"chunk must be a positive integer, got {chunk!r}")
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise TypeError(
            f"executor must be a concurrent.futures.Executor (with .submit), got {executor!r}"
        )
    if not callable(func):
        raise TypeError(f"func must be callable, got {func!r}")
    root, seeds = realization_seeds(seed, n_realizations)
    starts = list(range(0, n_realizations, chunk))
    parts: list = [None] * len(starts)

    with task(desc, n_realizations, progress, unit="realization") as bar:
        if executor is None:
            for j, s in enumerate(starts):
                parts[j] = _run_chunk(func, seeds[s : s + chunk], s)
                bar.update(parts[j][0])
        else:
            futures = {
                executor.submit(_run_chunk, func, seeds[s : s + chunk], s): j
                for j, s in enumerate(starts)
            }
            try:
                for fut in cf.as_completed(futures):
                    j = futures[fut]
                    parts[j] = fut.result()
                    bar.update(parts[j][0])
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    is_dict = parts[0][3]
    acc = parts[0][:3]
    for p in parts[1:]:
        acc = _merge(acc, p[:3])
    n, mean, m2 = acc
    std = {k: np.sqrt(v / (n - 1)) for k, v in m2.items()}
    se = {k: v / math.sqrt(n) for k, v in std.items()}
    for k, v in mean.items():
        if not np.all(np.isfinite(v)):
            raise ValueError(f"func returned non-finite values (key {k!r})")

    def shape(d):
        return d if is_dict else d[""]

    return MonteCarloResult(
        mean=shape(mean),
        std_error=shape(se),
        std=shape(std),
        n=n,
        entropy=root.entropy,
        chunk=chunk,
        info={"executor": type(executor).__name__ if executor is not None else "serial"},
    )
