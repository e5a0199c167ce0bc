"""Filling a large table in pieces: index chunks of the reciprocal half of a direction grid,
and one solver report from the reports of the chunks (:mod:`.build` calls the solver on at
most :data:`.sizing.CHUNK_PAIRS` points at a time, so its temporaries stay bounded).
"""

from __future__ import annotations

import re

import numpy as np

__all__ = ["merge_info", "slim", "upper_pairs"]


def slim(info: dict) -> dict:
    """A solver info without its per-point arrays (``angle_valid``, ``angle_excess``, …: 9 B a
    point, which over the chunks of a 1e8-pair table would add up to a gigabyte); the
    reports' texts and flags are kept."""

    def small(v):
        return not (isinstance(v, np.ndarray) and v.size > 64)

    out = {k: v for k, v in info.items() if small(v)}
    if isinstance(out.get("validity"), dict):
        out["validity"] = {k: v for k, v in out["validity"].items() if small(v)}
    return out


def upper_pairs(nd: int, step: int):
    """``(a, b)`` index chunks of the pairs ``a ≤ b < nd`` (row-major, as ``np.triu_indices``),
    whole rows of about ``step`` pairs at a time (the full index arrays would be 16 B a pair)."""
    lo = 0
    while lo < nd:
        counts = nd - np.arange(lo, nd)
        hi = lo + max(1, int(np.searchsorted(np.cumsum(counts), step, side="right")))
        rows = np.arange(lo, min(hi, nd))
        n = nd - rows
        a = np.repeat(rows, n)
        start = np.cumsum(n) - n
        b = np.arange(a.size) - np.repeat(start, n) + a
        yield a, b
        lo = rows[-1] + 1


def merge_info(infos, theta=None):
    """One solver info from the chunks': valid only if every chunk is; reasons once each, a
    check failing per angle in several chunks as one text (θi range over all, counts summed,
    the worst chunk's requirement; with ``theta`` [rad], the grid's θ nodes, the counts are
    of distinct nodes, as one call over the whole grid reports them)."""
    if len(infos) == 1:
        return infos[0]
    out = dict(infos[0])
    reps = [i.get("validity", {}) for i in infos]
    val = dict(reps[0])
    val["valid"] = all(r.get("valid", True) for r in reps)
    val["reasons"] = list(dict.fromkeys(x for r in reps for x in r.get("reasons", [])))
    by_check: dict[str, list] = {}
    for text in dict.fromkeys(x for r in reps for x in r.get("angle_reasons", [])):
        m = _CHUNK_REASON.match(text)
        by_check.setdefault(m["check"] if m else text, []).append((text, m))
    merged = []
    for check, items in by_check.items():
        if len(items) == 1 or any(m is None for _, m in items):
            merged.extend(t for t, _ in items)
            continue
        lo = min(float(m["lo"] or m["lo1"]) for _, m in items)
        hi = max(float(m["hi"] or m["lo1"]) for _, m in items)
        span = f"θi = {lo:.4g}°" if lo == hi else f"θi ∈ [{lo:.4g}°, {hi:.4g}°]"
        n, tot = sum(int(m["n"]) for _, m in items), sum(int(m["m"]) for _, m in items)
        if theta is not None:  # the solver counts distinct θi nodes; chunks share them
            deg = np.degrees(np.asarray(theta))
            tol = 5e-4 * np.maximum(1.0, np.abs(deg))  # the texts' 4 significant digits
            n, tot = int(np.sum((deg >= lo - tol) & (deg <= hi + tol))), int(deg.size)
        worst = max(items, key=lambda it: float(_RATIO.search(it[1]["why"] + "(×0)")[1]))
        merged.append(f"{check}: fails for {span} ({n} of {tot} angles); {worst[1]['why']}")
    val["angle_reasons"] = merged
    out["validity"] = val
    return out


_CHUNK_REASON = re.compile(
    r"^(?P<check>[^:]+): fails for θi (?:= (?P<lo1>[-0-9.e+]+)°|∈ \[(?P<lo>[-0-9.e+]+)°, "
    r"(?P<hi>[-0-9.e+]+)°\]) \((?P<n>\d+) of (?P<m>\d+) angles\); (?P<why>.*)$"
)
_RATIO = re.compile(r"\(×([0-9.]+(?:e[-+]?[0-9]+)?)\)")
