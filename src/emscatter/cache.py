"""On-disk result cache for expensive pure computations (emissivity quadratures, SPM's
second-order coherent reflectivity, BRDF/radio tables, Monte Carlo runs, the demo's steps).

    from emscatter import cache
    value = cache.cached("emissivity", {"surface": rough, "eps": eps, ...}, compute)

* **Key**: SHA-256 of a canonical encoding of the inputs (numbers by their exact bits, arrays
  by dtype, shape and bytes, dataclasses such as a ``Roughness`` by type and fields), the
  namespace, the package version and a fingerprint of the package's source files (any code
  change starts a fresh cache; no stale result survives an edit). Unsupported input types are
  a ``TypeError`` naming the type — never a silent ``repr``.
* **Entry**: ``<dir>/<namespace>/<key[:2]>/<key>.pkl`` = magic + SHA-256 of the payload +
  payload (pickle). A short, truncated or altered entry fails the check, is deleted and
  recomputed — never returned.
* **Writes are atomic** (temporary file in the same folder, then :func:`os.replace`), and a
  per-entry lock (``fcntl.flock``) makes a second process that wants the same entry wait for
  the first and read its result instead of computing it again.
* **Size limit** ``EMSCATTER_CACHE_MAX_MB`` (default 1024): after each write the least
  recently used entries (a hit refreshes an entry's time) are removed until the total fits.
* **Never in the way**: an unusable folder (read-only, full disk) or a value that does not
  pickle means the value is computed and returned, not stored (``stats.unusable``).
* **Switches**: ``EMSCATTER_CACHE=0`` (or ``off``/``false``/``no``) or :func:`set_enabled`
  (``False``) / ``with cache.disabled():`` turn it off; ``EMSCATTER_CACHE_DIR`` moves it
  (default ``~/.cache/emscatter/results``, created with mode 0700: entries are pickles, so the
  folder must be writable only by its user).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import math
import os
import pickle
import struct
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

__all__ = [
    "cached",
    "key_of",
    "cache_dir",
    "enabled",
    "set_enabled",
    "disabled",
    "clear",
    "size_bytes",
    "evict",
    "stats",
    "CacheStats",
    "cached_step",
]

T = TypeVar("T")
_MAGIC = b"EMSCACHE1\n"
_DIGEST = 32
_OFF = {"0", "off", "false", "no"}
_override: bool | None = None


@dataclasses.dataclass
class CacheStats:
    """Counters of this process: hits, misses, writes, corrupt entries found, evictions,
    keys that could not be encoded, and times the folder could not be used (computed anyway)."""

    hits: int = 0
    misses: int = 0
    writes: int = 0
    corrupt: int = 0
    evicted: int = 0
    uncacheable: int = 0
    unusable: int = 0


stats = CacheStats()


# ----------------------------------------------------------------------------- switches
def enabled() -> bool:
    """Whether :func:`cached` uses the disk (``set_enabled`` wins over ``EMSCATTER_CACHE``)."""
    if _override is not None:
        return _override
    return os.environ.get("EMSCATTER_CACHE", "1").strip().lower() not in _OFF


def set_enabled(flag: bool | None) -> None:
    """Turn the cache on (True) or off (False) for this process; None: back to the env var."""
    global _override
    if flag is not None and not isinstance(flag, bool):
        raise TypeError(f"set_enabled takes True, False or None, got {flag!r}")
    _override = flag


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """``with cache.disabled(): ...`` — compute everything inside, read and write nothing."""
    global _override
    old = _override
    _override = False
    try:
        yield
    finally:
        _override = old


def cache_dir() -> Path:
    """The cache folder (``EMSCATTER_CACHE_DIR`` or ``~/.cache/emscatter/results``)."""
    env = os.environ.get("EMSCATTER_CACHE_DIR")
    if env:
        return Path(env)
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "emscatter" / "results"


def _max_bytes() -> int:
    raw = os.environ.get("EMSCATTER_CACHE_MAX_MB", "1024")
    try:
        mb = float(raw)
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and mb > 0):
        raise ValueError(f"EMSCATTER_CACHE_MAX_MB must be a positive number of MiB, got {raw!r}")
    return int(mb * 2**20)


# ----------------------------------------------------------------------------- keys
_FINGERPRINT: str | None = None


def _source_fingerprint() -> str:
    """Hash of (path, size, mtime) of every module of the package, once per process."""
    global _FINGERPRINT
    if _FINGERPRINT is None:
        from ._version import __version__

        root = Path(__file__).resolve().parent
        h = hashlib.sha256(__version__.encode())
        for p in sorted(root.rglob("*.py")):
            st = p.stat()
            h.update(f"{p.relative_to(root)}:{st.st_size}:{st.st_mtime_ns};".encode())
        _FINGERPRINT = h.hexdigest()
    return _FINGERPRINT


def _encode(obj, h) -> None:
    """Feed a canonical, type-tagged encoding of ``obj`` into the hash ``h``."""
    if obj is None or isinstance(obj, bool):
        h.update(f"<{obj!r}>".encode())
    elif isinstance(obj, int | np.integer):
        h.update(b"i" + str(int(obj)).encode() + b";")
    elif isinstance(obj, float | np.floating):
        h.update(b"f" + struct.pack("<d", float(obj)))
    elif isinstance(obj, complex | np.complexfloating):
        h.update(b"c" + struct.pack("<dd", obj.real, obj.imag))
    elif isinstance(obj, str):
        b = obj.encode()
        h.update(b"s" + str(len(b)).encode() + b":" + b)
    elif isinstance(obj, bytes):
        h.update(b"b" + str(len(obj)).encode() + b":" + obj)
    elif isinstance(obj, np.ndarray):
        if obj.dtype == object:
            raise TypeError("cache keys cannot hold object arrays")
        a = np.ascontiguousarray(obj)
        h.update(f"a{a.dtype.str}{a.shape};".encode())
        h.update(a.tobytes())
    elif isinstance(obj, list | tuple):
        h.update(f"{type(obj).__name__[0]}{len(obj)}[".encode())
        for item in obj:
            _encode(item, h)
        h.update(b"]")
    elif isinstance(obj, Mapping):
        items = sorted(obj.items(), key=lambda kv: str(kv[0]))
        h.update(f"d{len(items)}{{".encode())
        for k, v in items:
            _encode(str(k), h)
            _encode(v, h)
        h.update(b"}")
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        t = type(obj)
        _encode(f"{t.__module__}.{t.__qualname__}", h)
        _encode({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}, h)
    elif hasattr(obj, "cache_key") and callable(obj.cache_key):
        t = type(obj)
        _encode(f"{t.__module__}.{t.__qualname__}", h)
        _encode(obj.cache_key(), h)
    else:
        raise TypeError(
            f"cannot build a cache key from {type(obj).__name__} (supported: numbers, str, "
            "bytes, numpy arrays, lists/tuples/dicts of these, dataclasses, objects with a "
            "cache_key() method)"
        )


def key_of(namespace: str, key: Any) -> str:
    """The hex SHA-256 that names the entry of ``key`` in ``namespace``."""
    if not isinstance(namespace, str) or not namespace.replace("-", "").replace("_", "").isalnum():
        raise ValueError(
            f"namespace must be a short name of letters, digits, - or _, got {namespace!r}"
        )
    h = hashlib.sha256()
    _encode((namespace, _source_fingerprint(), key), h)
    return h.hexdigest()


# ----------------------------------------------------------------------------- entries
def _entry_path(namespace: str, key: str) -> Path:
    return cache_dir() / namespace / key[:2] / f"{key}.pkl"


def _read(path: Path):
    """(True, value) for a sound entry, (False, None) when missing; a bad entry is deleted."""
    try:
        blob = path.read_bytes()
    except FileNotFoundError:
        return False, None
    head = len(_MAGIC) + _DIGEST
    ok = len(blob) > head and blob.startswith(_MAGIC)
    if ok:
        payload = blob[head:]
        ok = hashlib.sha256(payload).digest() == blob[len(_MAGIC) : head]
    if ok:
        try:
            value = pickle.loads(payload)
        except Exception:  # noqa: BLE001 — an unreadable entry is recomputed, never returned
            ok = False
    if not ok:
        stats.corrupt += 1
        path.unlink(missing_ok=True)
        return False, None
    with contextlib.suppress(OSError):
        os.utime(path)  # LRU: a hit refreshes the entry
    return True, value


def _write(path: Path, value) -> None:
    payload = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(_MAGIC + hashlib.sha256(payload).digest() + payload)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    stats.writes += 1


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """Exclusive per-entry lock across processes (no-op where fcntl is missing)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - non-POSIX
        yield
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path.with_suffix(".lock"), "a+b") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _ensure_root() -> Path:
    root = cache_dir()
    if not root.exists():
        root.mkdir(parents=True, exist_ok=True)
        with contextlib.suppress(OSError):
            os.chmod(root, 0o700)
    return root


def cached(namespace: str, key: Any, compute: Callable[[], T]) -> T:
    """``compute()``'s value, from the disk when an entry for ``key`` exists.

    ``namespace``: what is cached (``"emissivity"``, ``"brdf-table"``, ...); ``key``: every
    input the result depends on (see :func:`key_of`); ``compute``: a pure function of them.
    With the cache off, this is ``compute()``. The value must pickle. A key that cannot be
    encoded (e.g. an executor among the options) is not an error: the value is computed and
    not stored (``stats.uncacheable`` counts it)."""
    if not enabled():
        return compute()
    try:
        digest = key_of(namespace, key)
    except TypeError:
        stats.uncacheable += 1
        return compute()
    path = _entry_path(namespace, digest)
    try:
        _ensure_root()
        found, value = _read(path)
    except OSError:  # an unusable cache folder never stops a computation
        stats.unusable += 1
        return compute()
    if found:
        stats.hits += 1
        return value
    try:
        lock = _locked(path)
        lock.__enter__()
    except OSError:
        stats.unusable += 1
        return compute()
    try:
        found, value = _read(path)  # another process may have filled it while we waited
        if found:
            stats.hits += 1
            return value
        stats.misses += 1
        value = compute()
        try:
            _write(path, value)
        except (OSError, pickle.PicklingError, TypeError, AttributeError):
            stats.unusable += 1  # full disk, read-only folder, unpicklable value: not stored
            return value
    finally:
        lock.__exit__(None, None, None)
    try:
        evict()
    except OSError:
        pass
    return value


# ----------------------------------------------------------------------------- housekeeping
def _entries() -> list[tuple[float, int, Path]]:
    out = []
    root = cache_dir()
    if not root.exists():
        return out
    for p in root.rglob("*.pkl"):
        with contextlib.suppress(FileNotFoundError):
            st = p.stat()
            out.append((st.st_mtime, st.st_size, p))
    return out


def size_bytes() -> int:
    """Total size of the entries [bytes]."""
    return sum(s for _, s, _ in _entries())


def evict(max_bytes: int | None = None) -> int:
    """Remove least recently used entries until the total is ≤ ``max_bytes`` (default
    ``EMSCATTER_CACHE_MAX_MB``); returns the number removed."""
    limit = _max_bytes() if max_bytes is None else int(max_bytes)
    entries = sorted(_entries())
    total = sum(s for _, s, _ in entries)
    removed = 0
    for _, size, p in entries:
        if total <= limit:
            break
        with contextlib.suppress(FileNotFoundError):
            p.unlink()
            p.with_suffix(".lock").unlink(missing_ok=True)
            removed += 1
        total -= size
    stats.evicted += removed
    return removed


def clear(namespace: str | None = None) -> int:
    """Delete every entry (of ``namespace`` if given); returns the number deleted."""
    n = 0
    for _, _, p in _entries():
        if namespace is None or p.parent.parent.name == namespace:
            p.unlink(missing_ok=True)
            p.with_suffix(".lock").unlink(missing_ok=True)
            n += 1
    return n


def cached_step(
    namespace: str, key: Any, out, produce: Callable[[Path], T]
) -> tuple[T, list[Path]]:
    """A step that writes files: ``produce(folder)`` writes them under ``folder`` and returns a
    value. Run (on a miss) in a temporary folder; the value and every file's bytes are cached;
    then the files are written atomically under ``out`` at the same relative paths. Returns
    ``(value, paths under out)``. Paths inside the value are not translated: return data, not
    paths, from ``produce``."""
    from .io import atomic_path

    def run() -> tuple[T, dict[str, bytes]]:
        with tempfile.TemporaryDirectory(prefix="emscatter-step-") as tmp:
            value = produce(Path(tmp))
            files = {
                str(p.relative_to(tmp)): p.read_bytes()
                for p in sorted(Path(tmp).rglob("*"))
                if p.is_file()
            }
        return value, files

    value, files = cached(namespace, key, run)
    written = []
    for rel, blob in files.items():
        dest = Path(out) / rel
        with atomic_path(dest) as tmp_path:
            tmp_path.write_bytes(blob)
        written.append(dest)
    return value, written


def timed(namespace: str, key: Any, compute: Callable[[], T]) -> tuple[T, float, bool]:
    """``(value, seconds, hit)``: :func:`cached` with its wall time and whether it hit."""
    before = stats.hits
    t0 = time.perf_counter()
    value = cached(namespace, key, compute)
    return value, time.perf_counter() - t0, stats.hits > before
