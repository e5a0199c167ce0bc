"""How a cache entry is stored (:mod:`emscatter.cache`): the value tree written as JSON +
arrays (no pickle: nothing read can run code), the private folder and its per-folder
secret (mode 0600), and the HMAC-SHA256 that binds an entry to its key."""

from __future__ import annotations

import contextlib
import hashlib
import hmac
import os
import stat
import struct
import tempfile
from pathlib import Path

import numpy as np

_SECRET = ".secret"  # the per-folder secret file
_SECRET_BYTES = 32


class CacheWarning(UserWarning):
    """A cache entry was rejected (damaged, unauthenticated, or another key's) and recomputed."""


class CacheSecurityError(RuntimeError):
    """The cache folder or its secret could be written or read by someone else."""


# ----------------------------------------------------------------------------- values
_VALUE_TYPES = (
    "None, bool, int, float, complex, str, bytes, numpy arrays and scalars (not of object "
    "dtype), and tuples, lists and dicts with str keys of these"
)


def _pack(obj, arrays: list[np.ndarray]):
    """The JSON node of ``obj``; its arrays are appended to ``arrays`` (TypeError if a part
    of ``obj`` has no exact, non-executable representation)."""
    if obj is None:
        return None
    if isinstance(obj, np.generic):  # before float/int: np.float64 is a float subclass
        if obj.dtype.hasobject:
            raise TypeError("cache values cannot hold numpy object scalars")
        arrays.append(np.asarray(obj))
        return {"scalar": len(arrays) - 1}
    if type(obj) is bool:
        return {"bool": obj}
    if type(obj) is int:
        return {"int": str(obj)}
    if type(obj) is float:
        return {"float": obj.hex()}
    if type(obj) is complex:
        return {"complex": [obj.real.hex(), obj.imag.hex()]}
    if type(obj) is str:
        return {"str": obj}
    if type(obj) in (bytes, bytearray):
        arrays.append(np.frombuffer(bytes(obj), dtype=np.uint8))
        return {"bytes": len(arrays) - 1}
    if type(obj) is np.ndarray:
        if obj.dtype.hasobject:
            raise TypeError("cache values cannot hold object arrays")
        arrays.append(obj)
        return {"array": len(arrays) - 1}
    if type(obj) in (tuple, list):
        return {type(obj).__name__: [_pack(v, arrays) for v in obj]}
    if type(obj) is dict:
        if not all(type(k) is str for k in obj):
            raise TypeError("cache values can hold dicts with str keys only")
        return {"dict": [[k, _pack(v, arrays)] for k, v in obj.items()]}
    raise TypeError(f"cannot store a {type(obj).__name__} in the cache (storable: {_VALUE_TYPES})")


class _Rejected(Exception):
    """An entry that must not be returned; ``str`` says why."""


class _Mismatch(_Rejected):
    """A sound entry, but of another key."""


def _unpack(node, arrays: list[np.ndarray]):
    """Inverse of :func:`_pack`; :class:`_Rejected` for anything it would not have written."""
    if node is None:
        return None
    if not (isinstance(node, dict) and len(node) == 1):
        raise _Rejected(f"malformed value node {str(node)[:60]!r}")
    ((tag, v),) = node.items()
    if tag in ("scalar", "bytes", "array"):
        if type(v) is not int or not 0 <= v < len(arrays):
            raise _Rejected(f"value node {tag} points at no array ({v!r})")
        a = arrays[v]
        if tag == "scalar":
            if a.ndim != 0:
                raise _Rejected("a numpy scalar stored as a non-scalar array")
            return a[()]
        if tag == "bytes":
            if a.dtype != np.uint8 or a.ndim != 1:
                raise _Rejected("bytes stored as something else than a 1-D uint8 array")
            return a.tobytes()
        return a
    if tag == "bool" and type(v) is bool:
        return v
    if tag == "int" and type(v) is str:
        return int(v)
    if tag == "float" and type(v) is str:
        return float.fromhex(v)
    if tag == "complex" and type(v) is list and len(v) == 2:
        return complex(float.fromhex(v[0]), float.fromhex(v[1]))
    if tag == "str" and type(v) is str:
        return v
    if tag in ("tuple", "list") and type(v) is list:
        items = [_unpack(x, arrays) for x in v]
        return tuple(items) if tag == "tuple" else items
    if tag == "dict" and type(v) is list:
        out = {}
        for kv in v:
            if not (type(kv) is list and len(kv) == 2 and type(kv[0]) is str):
                raise _Rejected("malformed dict item")
            out[kv[0]] = _unpack(kv[1], arrays)
        return out
    raise _Rejected(f"unknown value node {tag!r}")


# ----------------------------------------------------------------------------- folder, secret
def _private_mkdir(path: Path) -> None:
    with contextlib.suppress(FileExistsError):
        path.mkdir(mode=0o700)


def _check_private(path: Path, st: os.stat_result, what: str) -> None:
    """:class:`CacheSecurityError` unless ``path`` is the user's own and others cannot write."""
    if not hasattr(os, "getuid"):  # pragma: no cover - non-POSIX: no owner/mode bits to check
        return
    fix = (
        f"make it private with `chmod 700 {path}` (or `chown` it to yourself), or set "
        "EMSCATTER_CACHE_DIR to a folder only you can write (EMSCATTER_CACHE=0 turns the "
        "cache off)"
    )
    uid = os.getuid()
    if st.st_uid != uid:
        raise CacheSecurityError(
            f"refusing the result cache {what} {str(path)!r}: it belongs to uid {st.st_uid}, "
            f"not to you (uid {uid}), who could plant entries this process would read; {fix}"
        )
    if st.st_mode & 0o022:
        who = " and ".join(
            name for bit, name in ((0o020, "the group"), (0o002, "others")) if st.st_mode & bit
        )
        raise CacheSecurityError(
            f"refusing the result cache {what} {str(path)!r}: {who} can write to it (mode "
            f"{stat.S_IMODE(st.st_mode):04o}), so anyone there could plant entries this "
            f"process would read; {fix}"
        )


def _ensure_root(root: Path) -> Path:
    """Create the cache folder (mode 0700) if needed and check it is private."""
    if not root.exists():
        root.parent.mkdir(parents=True, exist_ok=True)
        _private_mkdir(root)
    st = root.stat()
    if not stat.S_ISDIR(st.st_mode):
        raise NotADirectoryError(f"{root} is not a folder")
    _check_private(root, st, "folder")
    return root


def _secret(root: Path) -> bytes:
    """The folder's HMAC secret (created, mode 0600, on first use)."""
    path = root / _SECRET
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        fd_tmp, tmp = tempfile.mkstemp(prefix=".secret.", suffix=".tmp", dir=root)  # 0600
        try:
            with os.fdopen(fd_tmp, "wb") as fh:
                fh.write(os.urandom(_SECRET_BYTES))
                fh.flush()
                os.fsync(fh.fileno())
            with contextlib.suppress(FileExistsError):  # another process made one first
                os.link(tmp, path)  # atomic and never replaces an existing secret
        finally:
            os.unlink(tmp)
        fd = os.open(path, flags)
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        secret = fh.read(_SECRET_BYTES + 1)
    if hasattr(os, "getuid"):
        problem = None
        if st.st_uid != os.getuid():
            problem = f"it belongs to uid {st.st_uid}, not to you (uid {os.getuid()})"
        elif st.st_mode & 0o077:
            problem = f"its mode is {stat.S_IMODE(st.st_mode):04o}, not 0600"
        if problem:
            raise CacheSecurityError(
                f"refusing the result cache secret {str(path)!r}: {problem}; delete it (a new "
                "one is made, the entries signed with it are recomputed) and make its folder "
                f"private (`chmod 700 {root}`)"
            )
    if not stat.S_ISREG(st.st_mode) or len(secret) != _SECRET_BYTES:
        raise CacheSecurityError(
            f"refusing the result cache secret {str(path)!r}: not a {_SECRET_BYTES}-byte file; "
            "delete it (a new one is made)"
        )
    return secret


def _mac(secret: bytes, header: bytes, arrays: list[np.ndarray]) -> str:
    h = hmac.new(secret, digestmod=hashlib.sha256)
    h.update(struct.pack("<Q", len(header)) + header)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape};".encode())
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()
