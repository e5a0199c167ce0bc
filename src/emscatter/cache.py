"""On-disk result cache for expensive pure computations: the emissivity quadratures of
:func:`emscatter.emissivity` (and of a Monte Carlo or method-of-moments solver when it runs with
a fixed ``seed``), SPM's second-order coherent reflectivity, and the steps of
``emscatter demo``. BRDF and radio tables are *not* cached.

    from emscatter import cache
    value = cache.cached("emissivity", {"surface": rough, "eps": eps, ...}, compute)

* **Key**: SHA-256 of a canonical encoding of the inputs (numbers by their exact bits, arrays
  by dtype, shape and bytes, dataclasses such as a ``Roughness`` by type and fields), the
  namespace, the package version and a fingerprint of the package's source files (any code
  change starts a fresh cache; no stale result survives an edit). Unsupported input types are
  a ``TypeError`` naming the type — never a silent ``repr``.
* **Entry**: ``<dir>/<namespace>/<key[:2]>/<key>.npz``, an uncompressed ``numpy.savez``
  archive read with ``allow_pickle=False``: a JSON ``header`` (format, version, namespace, the
  full key, and the value as a tree of tagged nodes — ``None``, bool, int, float and complex by
  their exact bits, str, bytes, numpy arrays and scalars, tuples, lists, dicts with str keys),
  one array member per array/bytes/numpy scalar of the value, and ``mac``, an HMAC-SHA256 of
  the header and every array under the folder's secret. Nothing read from the cache is
  executed: there is no pickle anywhere (object arrays are refused on write and on read), so a
  planted file can at worst be data, and a file without the secret's MAC is refused.
  Values of other types are computed and returned, not stored (``stats.unusable``).
* **Rejected entries** — short, truncated, altered, foreign, of another format, failing the
  MAC, or written for another key (an entry copied over another key's path) — are deleted,
  recomputed and never returned; each rejection is a :class:`CacheWarning` saying why
  (``stats.corrupt``, or ``stats.mismatched`` for another key's entry).
* **Secret**: ``<dir>/.secret``, 32 random bytes created with mode 0600 on first use; one not
  owned by the user, readable by others or of the wrong size is a :class:`CacheSecurityError`.
* **Folder**: created with mode 0700. A cache folder that the group or others can write to, or
  that another user owns, is refused (:class:`CacheSecurityError`, raised before any
  computing) with the reason and the fix (``chmod 700 <dir>``, or ``EMSCATTER_CACHE_DIR`` set
  to a private folder, or ``EMSCATTER_CACHE=0``): whoever can write there could plant entries.
* **Writes are atomic** (temporary file in the same folder, then :func:`os.replace`), and a
  per-entry lock (``fcntl.flock``) makes a second process that wants the same entry wait for
  the first and read its result instead of computing it again.
* **Size limit** ``EMSCATTER_CACHE_MAX_MB`` (default 1024): after each write the least
  recently used entries (a hit refreshes an entry's time) are removed until the total fits.
  Entries of the former pickle format (``*.pkl``) are never read; they count towards the
  limit and :func:`clear`/:func:`evict` remove them.
* **Settings, checked up front** on every :func:`cached` call, before any computing, whether
  the entry exists or not (a ``ValueError`` naming the variable, its value and what is
  allowed): ``EMSCATTER_CACHE`` — ``1``/``on``/``true``/``yes`` or ``0``/``off``/``false``/
  ``no`` (unset or empty: on); :func:`set_enabled` (``False``) / ``with cache.disabled():``
  win over it; ``EMSCATTER_CACHE_DIR`` — an absolute folder path (``~`` expanded; default
  ``$XDG_CACHE_HOME/emscatter/results`` when ``XDG_CACHE_HOME`` is absolute, else
  ``~/.cache/emscatter/results``); ``EMSCATTER_CACHE_MAX_MB`` — a positive finite number of
  MiB.
* **Never in the way**: a folder that cannot be used (cannot be created, read-only, full disk)
  means the value is computed and returned, not stored (``stats.unusable``). Only an unsafe
  folder or secret and invalid settings are errors.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import hmac
import json
import math
import os
import struct
import tempfile
import time
import warnings
import zipfile
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from .cache_entries import (
    CacheSecurityError,
    CacheWarning,
    _ensure_root,
    _mac,
    _Mismatch,
    _pack,
    _private_mkdir,
    _Rejected,
    _secret,
    _unpack,
)

__all__ = [
    "cached",
    "key_of",
    "cache_dir",
    "settings",
    "Settings",
    "enabled",
    "set_enabled",
    "disabled",
    "clear",
    "size_bytes",
    "evict",
    "stats",
    "CacheStats",
    "CacheWarning",
    "CacheSecurityError",
    "cached_step",
]

T = TypeVar("T")
_FORMAT = "emscatter-cache"
_FORMAT_VERSION = 2
_SUFFIX = ".npz"
_LEGACY = ".pkl"  # the former pickle entries: never read, only counted and removed
_ON = {"1", "on", "true", "yes"}
_OFF = {"0", "off", "false", "no"}
_override: bool | None = None


@dataclasses.dataclass
class CacheStats:
    """Counters of this process: hits, misses, writes, corrupt entries found, entries of
    another key found at a key's path, evictions, keys that could not be encoded, and times
    the folder could not be used or a value could not be stored (computed anyway)."""

    hits: int = 0
    misses: int = 0
    writes: int = 0
    corrupt: int = 0
    mismatched: int = 0
    evicted: int = 0
    uncacheable: int = 0
    unusable: int = 0


stats = CacheStats()


# ----------------------------------------------------------------------------- settings
@dataclasses.dataclass(frozen=True)
class Settings:
    """The validated cache settings: on/off, folder (None when off and not set), size limit
    [bytes]."""

    enabled: bool
    root: Path | None
    max_bytes: int


def _env_enabled() -> bool:
    raw = os.environ.get("EMSCATTER_CACHE")
    if raw is None or not raw.strip():
        return True
    value = raw.strip().lower()
    if value in _ON:
        return True
    if value in _OFF:
        return False
    raise ValueError(
        f"EMSCATTER_CACHE must be one of {sorted(_ON)} (cache on) or {sorted(_OFF)} (cache "
        f"off), got {raw!r}"
    )


def _env_root() -> Path:
    raw = os.environ.get("EMSCATTER_CACHE_DIR")
    if raw is None or raw == "":
        xdg = os.environ.get("XDG_CACHE_HOME") or ""
        try:
            home = Path.home()
        except (KeyError, RuntimeError):
            raise ValueError(
                "no home folder for the default result cache: set EMSCATTER_CACHE_DIR to an "
                "absolute folder path (or EMSCATTER_CACHE=0)"
            ) from None
        base = Path(xdg) if xdg and Path(xdg).is_absolute() else home / ".cache"
        return base / "emscatter" / "results"
    if "\0" in raw or not raw.strip():
        raise ValueError(f"EMSCATTER_CACHE_DIR must be an absolute folder path, got {raw!r}")
    path = Path(raw).expanduser()
    if not path.is_absolute():
        raise ValueError(
            f"EMSCATTER_CACHE_DIR must be an absolute folder path (or start with ~), got "
            f"{raw!r}: a relative one would change with the working directory"
        )
    return path


def _env_max_bytes() -> int:
    raw = os.environ.get("EMSCATTER_CACHE_MAX_MB")
    if raw is None:
        return 1024 * 2**20
    try:
        mb = float(raw)
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and mb > 0):
        raise ValueError(
            f"EMSCATTER_CACHE_MAX_MB must be a positive finite number of MiB (e.g. 1024), "
            f"got {raw!r}"
        )
    return int(mb * 2**20)


def settings() -> Settings:
    """Read and check every cache setting (``ValueError`` naming the variable, its value and
    what is allowed). :func:`cached` calls it first, so bad settings fail before any work."""
    on = _env_enabled()  # checked even when set_enabled/disabled() overrides it
    on = on if _override is None else _override
    max_bytes = _env_max_bytes()
    # the default folder needs a home folder: looked up only when the cache is used
    root = _env_root() if on or os.environ.get("EMSCATTER_CACHE_DIR") else None
    return Settings(enabled=on, root=root, max_bytes=max_bytes)


def enabled() -> bool:
    """Whether :func:`cached` uses the disk (``set_enabled`` wins over ``EMSCATTER_CACHE``)."""
    on = _env_enabled()
    return on if _override is None else _override


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
    return _env_root()


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
def _entry_path(root: Path, namespace: str, key: str) -> Path:
    return root / namespace / key[:2] / f"{key}{_SUFFIX}"


def _header(namespace: str, key: str, tree) -> bytes:
    from ._version import __version__

    head = {"format": _FORMAT, "format_version": _FORMAT_VERSION, "namespace": namespace,
            "key": key, "emscatter": __version__, "value": tree}  # fmt: skip
    return json.dumps(head, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()


def _load(fh, namespace: str, key: str, secret: bytes):
    """The value of the entry open in ``fh``; :class:`_Rejected` saying why it is refused."""
    start = fh.read(4)
    if start != b"PK\x03\x04":  # a pickle (the former format) or any other file
        raise _Rejected(f"not an .npz archive (it starts with {start!r})")
    fh.seek(0)
    data = np.load(fh, allow_pickle=False)  # never unpickles: object members raise
    if not isinstance(data, np.lib.npyio.NpzFile):
        raise _Rejected("a bare .npy array, not a cache entry")
    with data:
        names = set(data.files)
        if not {"header", "mac"} <= names:
            raise _Rejected("no header or mac member")
        n = len(names) - 2
        if names != {"header", "mac", *(f"a{i}" for i in range(n))}:
            raise _Rejected(f"unexpected members {sorted(names)[:8]}")
        head_arr, mac_arr = data["header"], data["mac"]
        if head_arr.dtype.kind != "U" or head_arr.ndim != 0 or mac_arr.dtype.kind != "U":
            raise _Rejected("header or mac is not text")
        header = str(head_arr).encode()
        arrays = [data[f"a{i}"] for i in range(n)]
    if not hmac.compare_digest(str(mac_arr), _mac(secret, header, arrays)):
        raise _Rejected(
            "its MAC does not match (damaged, or not written with this folder's secret)"
        )
    head = json.loads(header)
    if head.get("format") != _FORMAT or head.get("format_version") != _FORMAT_VERSION:
        raise _Rejected(f"format {head.get('format')!r} v{head.get('format_version')!r}")
    if head.get("namespace") != namespace or head.get("key") != key:
        raise _Mismatch(
            f"it holds the entry of {head.get('namespace')!r}/{str(head.get('key'))[:16]}…, "
            f"not of {namespace!r}/{key[:16]}… (copied or moved over another key's path)"
        )
    return _unpack(head["value"], arrays)


def _read(path: Path, namespace: str, key: str, secret: bytes):
    """(True, value) for a sound entry of this key, (False, None) when missing; a rejected
    entry is deleted, counted and warned about."""
    try:
        fh = open(path, "rb")
    except FileNotFoundError:
        return False, None
    with fh:
        try:
            value = _load(fh, namespace, key, secret)
            reason = None
        except _Mismatch as exc:
            reason, counter = str(exc), "mismatched"
        except _Rejected as exc:
            reason, counter = str(exc), "corrupt"
        except (OSError, EOFError, zipfile.BadZipFile) as exc:
            reason, counter = f"unreadable ({type(exc).__name__}: {exc})", "corrupt"
        except Exception as exc:  # noqa: BLE001 — any damage: recomputed, never returned
            reason, counter = f"damaged ({type(exc).__name__}: {exc})", "corrupt"
    if reason is not None:
        setattr(stats, counter, getattr(stats, counter) + 1)
        path.unlink(missing_ok=True)
        warnings.warn(
            f"emscatter cache: rejected the entry {str(path)!r}: {reason}; recomputing it",
            CacheWarning,
            stacklevel=3,
        )
        return False, None
    with contextlib.suppress(OSError):
        os.utime(path)  # LRU: a hit refreshes the entry
    return True, value


def _write(path: Path, namespace: str, key: str, secret: bytes, value) -> None:
    arrays: list[np.ndarray] = []
    tree = _pack(value, arrays)  # TypeError before anything touches the disk
    header = _header(namespace, key, tree)
    members = {f"a{i}": a for i, a in enumerate(arrays)}
    mac = _mac(secret, header, arrays)
    _private_mkdir(path.parent.parent)
    _private_mkdir(path.parent)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, header=np.array(header.decode()), mac=np.array(mac), **members)
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
    _private_mkdir(path.parent.parent)
    _private_mkdir(path.parent)
    with open(path.with_suffix(".lock"), "a+b") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def cached(namespace: str, key: Any, compute: Callable[[], T]) -> T:
    """``compute()``'s value, from the disk when a sound entry for ``key`` exists.

    ``namespace``: what is cached (``"emissivity"``, ``"spm2-coherent"``, ...); ``key``: every
    input the result depends on (see :func:`key_of`); ``compute``: a pure function of them.
    Settings are checked first (``ValueError``), and an unsafe folder is refused
    (:class:`CacheSecurityError`), both before ``compute`` runs. With the cache off, this is
    ``compute()``. A key that cannot be encoded (e.g. an executor among the options) is not an
    error: the value is computed and not stored (``stats.uncacheable``); nor is a value of a
    type the entry format cannot hold (``stats.unusable``; see the module docstring)."""
    conf = settings()
    if not conf.enabled:
        return compute()
    try:
        digest = key_of(namespace, key)
    except TypeError:
        stats.uncacheable += 1
        return compute()
    path = _entry_path(conf.root, namespace, digest)
    try:
        _ensure_root(conf.root)
        secret = _secret(conf.root)
        found, value = _read(path, namespace, digest, secret)
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
        found, value = _read(path, namespace, digest, secret)  # filled while we waited?
        if found:
            stats.hits += 1
            return value
        stats.misses += 1
        value = compute()
        try:
            _write(path, namespace, digest, secret, value)
        except (OSError, TypeError):
            stats.unusable += 1  # full disk, read-only folder, unstorable value: not stored
            return value
    finally:
        lock.__exit__(None, None, None)
    with contextlib.suppress(OSError):
        evict(conf.max_bytes)
    return value


# ----------------------------------------------------------------------------- housekeeping
def _entries() -> list[tuple[float, int, Path]]:
    out = []
    root = cache_dir()
    if not root.exists():
        return out
    for pattern in (f"*/*/*{_SUFFIX}", f"*/*/*{_LEGACY}"):
        for p in root.glob(pattern):
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
    if max_bytes is None:
        limit = _env_max_bytes()
    elif (
        isinstance(max_bytes, bool) or not isinstance(max_bytes, int | np.integer) or max_bytes < 0
    ):
        raise ValueError(f"max_bytes must be an integer >= 0 [bytes], got {max_bytes!r}")
    else:
        limit = int(max_bytes)
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
