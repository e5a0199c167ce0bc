"""emscatter.cache: keys, atomic non-executable entries bound to their key, corruption, planted and
swapped entries, private folder, settings checked up front, two processes, size limit, switches."""

from __future__ import annotations

import contextlib
import math
import os
import subprocess
import sys
import textwrap
import time
import warnings

import numpy as np
import pytest

from emscatter import cache
from emscatter.spectra import GaussianCorrelation


@pytest.fixture(autouse=True)
def fresh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("EMSCATTER_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("EMSCATTER_CACHE", "1")
    monkeypatch.delenv("EMSCATTER_CACHE_MAX_MB", raising=False)
    cache.set_enabled(None)
    yield tmp_path / "cache"
    cache.set_enabled(None)


class Counter:
    def __init__(self, value):
        self.calls = 0
        self.value = value

    def __call__(self):
        self.calls += 1
        return self.value


def test_second_call_is_read_from_disk_and_returns_a_fresh_copy(fresh_cache):
    value = {"e": np.linspace(0, 1, 7), "n": 3, "label": "x"}
    c = Counter(value)
    key = {"surface": GaussianCorrelation(0.01, 0.1), "eps": 17 + 2j, "theta": np.arange(3.0)}
    a = cache.cached("test", key, c)
    b = cache.cached("test", key, c)
    assert c.calls == 1
    np.testing.assert_array_equal(b["e"], value["e"])
    assert b["n"] == 3 and b["label"] == "x"
    b["e"][0] = 99.0  # a hit is a new object: changing it does not change the cache
    assert cache.cached("test", key, c)["e"][0] == 0.0
    assert a is value
    assert len(list(fresh_cache.rglob("*.npz"))) == 1


def test_keys_tell_apart_every_input_bit_and_type():
    g = GaussianCorrelation(0.01, 0.1)
    base = cache.key_of("ns", {"s": g, "x": 0.1})
    assert cache.key_of("ns", {"x": 0.1, "s": GaussianCorrelation(0.01, 0.1)}) == base
    assert cache.key_of("ns", {"s": g, "x": np.nextafter(0.1, 1)}) != base
    assert cache.key_of("ns", {"s": GaussianCorrelation(0.01, 0.1, dimension=1), "x": 0.1}) != base
    assert cache.key_of("other", {"s": g, "x": 0.1}) != base
    a = np.arange(6.0)
    assert cache.key_of("ns", a) != cache.key_of("ns", a.reshape(2, 3))
    assert cache.key_of("ns", a) != cache.key_of("ns", a.astype(np.float32))
    assert cache.key_of("ns", 1) != cache.key_of("ns", 1.0) != cache.key_of("ns", True)
    assert cache.key_of("ns", (1, 2)) != cache.key_of("ns", [1, 2])
    with pytest.raises(TypeError, match="cannot build a cache key from object"):
        cache.key_of("ns", {"x": object()})
    with pytest.raises(ValueError, match="namespace"):
        cache.key_of("../etc", 1)


def test_a_code_change_starts_a_fresh_cache(monkeypatch):
    key = cache.key_of("ns", 1)
    monkeypatch.setattr(cache, "_FINGERPRINT", "another source tree")
    assert cache.key_of("ns", 1) != key


@pytest.mark.parametrize("damage", ["truncate", "flip", "garbage", "empty"])
def test_a_corrupted_entry_is_recomputed_never_returned(fresh_cache, damage):
    c = Counter(np.arange(1000.0))
    cache.cached("test", "k", c)
    (path,) = fresh_cache.rglob("*.npz")
    blob = bytearray(path.read_bytes())
    if damage == "truncate":
        blob = blob[: len(blob) // 2]
    elif damage == "flip":
        at = blob.index(np.arange(1000.0).tobytes()) + 4000
        blob[at] ^= 0x01  # one bit inside the array data
    elif damage == "garbage":
        blob = bytearray(b"not a cache entry" * 10)
    else:
        blob = bytearray()
    path.write_bytes(bytes(blob))
    before = cache.stats.corrupt
    c.value = np.arange(1000.0) * 2  # what a recomputation gives (proves it recomputed)
    with pytest.warns(cache.CacheWarning, match="rejected the entry .*recomputing it"):
        got = cache.cached("test", "k", c)
    assert c.calls == 2 and cache.stats.corrupt == before + 1
    np.testing.assert_array_equal(got, np.arange(1000.0) * 2)
    # the rewritten entry is sound again
    np.testing.assert_array_equal(cache.cached("test", "k", c), got)
    assert c.calls == 2


def test_values_keep_their_types_and_bits(fresh_cache):
    value = (
        np.array([1 + 2j, np.nan - 0j]),
        {"n": 3, "big": 2**70, "x": -0.0, "nan": float("nan"), "z": 1e-300 - 2.5j, "ok": True,
         "none": None, "s": "λ", "raw": b"\x00\xff", "i64": np.int64(-7), "f32": np.float32(0.1),
         "nested": [np.zeros((2, 0)), ("a", [1.5])], "rec": np.zeros(2, "i4,f8")},
    )  # fmt: skip
    c = Counter(value)
    cache.cached("test", "types", c)
    got = cache.cached("test", "types", c)
    assert c.calls == 1 and type(got) is tuple
    np.testing.assert_array_equal(got[0], value[0])
    d = got[1]
    assert d["n"] == 3 and type(d["n"]) is int and d["big"] == 2**70
    assert math.copysign(1.0, d["x"]) == -1.0 and math.isnan(d["nan"])
    assert d["z"] == 1e-300 - 2.5j and d["ok"] is True and d["none"] is None
    assert d["s"] == "λ" and d["raw"] == b"\x00\xff"
    assert type(d["i64"]) is np.int64 and d["i64"] == -7
    assert type(d["f32"]) is np.float32 and d["f32"] == np.float32(0.1)
    assert d["nested"][0].shape == (2, 0) and d["nested"][1] == ("a", [1.5])
    assert d["rec"].dtype == np.dtype("i4,f8")
    # the entry is a plain .npz: numpy reads it without pickles
    (path,) = fresh_cache.rglob("*.npz")
    with np.load(path, allow_pickle=False) as data:
        assert {"header", "mac"} <= set(data.files)
        assert not any(data[k].dtype.hasobject for k in data.files)


@pytest.mark.parametrize(
    "value", [np.array([object()]), object(), {1: "int key"}, np.ma.masked_array([1.0])]
)
def test_a_value_the_format_cannot_hold_is_computed_not_stored(fresh_cache, value):
    before = cache.stats.unusable
    c = Counter(value)
    assert cache.cached("test", "odd", c) is value
    assert cache.cached("test", "odd", c) is value
    assert c.calls == 2 and cache.stats.unusable == before + 2
    assert not list(fresh_cache.rglob("*.npz"))


def test_an_entry_copied_over_another_keys_path_is_refused(fresh_cache):
    """The issue's case: σ = 0.03 numbers must not come back for a σ = 0.02 run."""
    k02 = {"surface": GaussianCorrelation(0.02, 0.5), "eps": 17 + 2j}
    k03 = {"surface": GaussianCorrelation(0.03, 0.5), "eps": 17 + 2j}
    cache.cached("emissivity", k03, lambda: np.full(4, 0.03))
    c = Counter(np.full(4, 0.02))
    cache.cached("emissivity", k02, c)
    p02 = next(fresh_cache.rglob(f"{cache.key_of('emissivity', k02)}.npz"))
    p03 = next(fresh_cache.rglob(f"{cache.key_of('emissivity', k03)}.npz"))
    p02.write_bytes(p03.read_bytes())  # the swap: a sound entry (valid MAC) at the wrong path
    before = cache.stats.mismatched
    with pytest.warns(cache.CacheWarning, match="not of 'emissivity'.*another key's path"):
        got = cache.cached("emissivity", k02, c)
    assert c.calls == 2 and cache.stats.mismatched == before + 1
    np.testing.assert_array_equal(got, np.full(4, 0.02))
    np.testing.assert_array_equal(cache.cached("emissivity", k02, c), np.full(4, 0.02))
    assert c.calls == 2  # rewritten under its own key


class _Exploit:
    """Unpickling this runs code: it writes the file ``marker``."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (exec, (f"with open({self.marker!r}, 'w') as f: f.write('code ran')",))


@pytest.mark.parametrize("where", ["legacy pkl path", "npz path", "object array", "data, no MAC"])
def test_a_planted_entry_with_a_valid_checksum_is_refused_and_not_executed(
    fresh_cache, tmp_path, where
):
    import hashlib
    import pickle

    marker = tmp_path / "pwned"
    payload = pickle.dumps(_Exploit(marker))
    pickle.loads(payload)  # the payload does run code when unpickled ...
    assert marker.exists()
    marker.unlink()
    c = Counter(np.arange(3.0))
    cache.cached("test", "k", c)  # creates the folder, its secret and the real entry
    (path,) = fresh_cache.rglob("*.npz")
    if where == "legacy pkl path":  # the former format: magic + SHA-256(payload) + pickle
        path.with_suffix(".pkl").write_bytes(
            b"EMSCACHE1\n" + hashlib.sha256(payload).digest() + payload
        )
        path.unlink()
    elif where == "npz path":
        path.write_bytes(b"EMSCACHE1\n" + hashlib.sha256(payload).digest() + payload)
    else:  # a well-formed entry for this very key, with an array member the planter chose
        key = cache.key_of("test", "k")
        if where == "object array":
            arrays = [np.array([_Exploit(marker)], dtype=object)]
            secret = (fresh_cache / ".secret").read_bytes()  # even with the secret's MAC
        else:
            arrays = [np.full(3, 1e300)]  # wrong numbers, checksummed but not with the secret
            secret = b"\0" * 32
        header = cache._header("test", key, {"array": 0})
        # an object array has no bytes to sign: the planter signs the header (with the secret)
        mac = cache._mac(secret, header, [] if arrays[0].dtype.hasobject else arrays)
        with open(path, "wb") as fh:
            np.savez(fh, header=np.array(header.decode()), mac=np.array(mac), a0=arrays[0])
    why = {"npz path": r"not an \.npz archive \(it starts with b'EMSC'\)",
           "object array": "Object arrays cannot be loaded when allow_pickle=False",
           "data, no MAC": "its MAC does not match"}.get(where)  # fmt: skip
    with pytest.warns(cache.CacheWarning, match=why) if why else _no_warning():
        got = cache.cached("test", "k", c)
    assert not marker.exists()  # ... but reading the cache never did
    assert c.calls == 2
    np.testing.assert_array_equal(got, np.arange(3.0))
    if where == "legacy pkl path":
        assert cache.clear() == 2  # the new entry and the never-read legacy pickle


@contextlib.contextmanager
def _no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


@pytest.mark.parametrize(("mode", "who"), [(0o770, "the group"), (0o707, "others"),
                                           (0o777, "the group and others")])  # fmt: skip
def test_a_folder_others_can_write_to_is_refused_before_computing(fresh_cache, mode, who):
    fresh_cache.mkdir()
    os.chmod(fresh_cache, mode)
    c = Counter(1.0)
    with pytest.raises(
        cache.CacheSecurityError, match=rf"{who} can write to it \(mode 0{mode:o}\).*chmod 700"
    ) as err:
        cache.cached("test", "k", c)
    assert "EMSCATTER_CACHE_DIR" in str(err.value) and str(fresh_cache) in str(err.value)
    assert c.calls == 0 and list(fresh_cache.iterdir()) == []
    os.chmod(fresh_cache, 0o700)  # the fix the message gives
    assert cache.cached("test", "k", c) == 1.0 and c.calls == 1


def test_a_new_folder_and_its_secret_are_private(fresh_cache):
    cache.cached("test", "k", lambda: 1)
    assert fresh_cache.stat().st_mode & 0o777 == 0o700
    secret = fresh_cache / ".secret"
    assert secret.stat().st_mode & 0o777 == 0o600 and secret.stat().st_size == 32
    os.chmod(secret, 0o644)
    with pytest.raises(cache.CacheSecurityError, match="secret .*mode is 0644, not 0600"):
        cache.cached("test", "k", lambda: 1)


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="needs chown")
def test_a_folder_owned_by_someone_else_is_refused(fresh_cache):
    fresh_cache.mkdir(mode=0o700)
    os.chown(fresh_cache, 54321, -1)
    with pytest.raises(cache.CacheSecurityError, match="belongs to uid 54321, not to you"):
        cache.cached("test", "k", lambda: 1)


@pytest.mark.parametrize(
    ("var", "value", "allowed"),
    [
        ("EMSCATTER_CACHE_MAX_MB", "abc", "positive finite number of MiB"),
        ("EMSCATTER_CACHE_MAX_MB", "-3", "positive finite number of MiB"),
        ("EMSCATTER_CACHE_MAX_MB", "0", "positive finite number of MiB"),
        ("EMSCATTER_CACHE_MAX_MB", "nan", "positive finite number of MiB"),
        ("EMSCATTER_CACHE_MAX_MB", "inf", "positive finite number of MiB"),
        ("EMSCATTER_CACHE", "maybe", "one of"),
        ("EMSCATTER_CACHE_DIR", "relative/cache", "absolute folder path"),
    ],
)
@pytest.mark.parametrize("state", ["cold", "warm"])
def test_bad_settings_fail_up_front_warm_or_cold(
    fresh_cache, monkeypatch, var, value, allowed, state
):
    c = Counter(np.ones(3))
    if state == "warm":
        cache.cached("test", "k", c)
    monkeypatch.setenv(var, value)
    with pytest.raises(ValueError, match=rf"{var} must be .*{allowed}.*got '{value}'"):
        cache.cached("test", "k", c)
    assert c.calls == (1 if state == "warm" else 0)  # nothing computed with bad settings
    with pytest.raises(ValueError, match=var):
        cache.settings()


def test_switches_env_api_and_context(fresh_cache, monkeypatch):
    c = Counter(5)
    monkeypatch.setenv("EMSCATTER_CACHE", "off")
    assert not cache.enabled()
    cache.cached("test", "k", c)
    cache.cached("test", "k", c)
    assert c.calls == 2 and not fresh_cache.exists()
    monkeypatch.setenv("EMSCATTER_CACHE", "1")
    cache.set_enabled(False)
    cache.cached("test", "k", c)
    assert c.calls == 3 and not fresh_cache.exists()
    cache.set_enabled(None)
    cache.cached("test", "k", c)
    with cache.disabled():
        cache.cached("test", "k", c)
    assert c.calls == 5
    cache.cached("test", "k", c)
    assert c.calls == 5  # on again after the context
    with pytest.raises(TypeError, match="set_enabled"):
        cache.set_enabled("yes")


def test_size_limit_evicts_least_recently_used(fresh_cache, monkeypatch):
    monkeypatch.setenv("EMSCATTER_CACHE_MAX_MB", str(2.5 * 0.8))  # room for two 0.8 MiB entries
    big = np.zeros(100_000)  # 0.8 MB
    for name in "abc":
        cache.cached("test", name, lambda: big)
        if name == "a":
            continue
        if name == "b":  # touch "a" so "b" is the least recently used when "c" arrives
            time.sleep(0.02)
            c = Counter(big)
            cache.cached("test", "a", c)
            assert c.calls == 0
            time.sleep(0.02)
    assert cache.size_bytes() <= 2.5 * 0.8 * 2**20
    c = Counter(big)
    cache.cached("test", "b", c)
    assert c.calls == 1  # b was evicted
    monkeypatch.setenv("EMSCATTER_CACHE_MAX_MB", "-3")
    with pytest.raises(ValueError, match="EMSCATTER_CACHE_MAX_MB"):
        cache.evict()
    assert cache.clear() >= 1 and cache.size_bytes() == 0


def test_two_processes_filling_the_same_entry(fresh_cache, tmp_path):
    """Both get the value; it is computed once (the second waits on the entry's lock and
    reads the first one's result); the entry is sound."""
    log = tmp_path / "computed.log"
    script = textwrap.dedent(
        f"""
        import os, time, numpy as np
        from emscatter import cache
        def compute():
            with open({str(log)!r}, "a") as fh:
                fh.write(f"{{os.getpid()}}\\n")
            time.sleep(1.0)
            return np.arange(50_000.0)
        v = cache.cached("race", {{"k": 1}}, compute)
        assert np.array_equal(v, np.arange(50_000.0))
        print("ok")
        """
    )
    env = {**os.environ, "EMSCATTER_CACHE_DIR": str(fresh_cache), "EMSCATTER_CACHE": "1"}
    procs = [
        subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE, text=True)
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=60)[0] for p in procs]
    assert [p.returncode for p in procs] == [0, 0] and all("ok" in o for o in outs)
    assert len(log.read_text().split()) == 1
    c = Counter(None)
    np.testing.assert_array_equal(cache.cached("race", {"k": 1}, c), np.arange(50_000.0))
    assert c.calls == 0
    assert not list(fresh_cache.rglob("*.tmp"))  # no temporary file left behind


def test_cached_step_replays_the_files_a_step_wrote(tmp_path):
    calls = []

    def produce(folder):
        calls.append(folder)
        (folder / "sub").mkdir()
        (folder / "sub" / "a.csv").write_text("x,y\n1,2\n")
        (folder / "b.png").write_bytes(b"\x89PNG fake")
        return {"rows": 1}

    v1, f1 = cache.cached_step("steps", {"step": "t"}, tmp_path / "one", produce)
    v2, f2 = cache.cached_step("steps", {"step": "t"}, tmp_path / "two", produce)
    assert len(calls) == 1 and v1 == v2 == {"rows": 1}
    assert sorted(p.relative_to(tmp_path / "two") for p in f2) == sorted(
        p.relative_to(tmp_path / "one") for p in f1
    )
    assert (tmp_path / "two" / "sub" / "a.csv").read_text() == "x,y\n1,2\n"
    assert (tmp_path / "two" / "b.png").read_bytes() == b"\x89PNG fake"


def test_emissivity_is_served_from_the_cache_unchanged():
    import emscatter as em

    kw = dict(wavelength=1.0, theta_i=np.radians([10.0, 50.0]), method="spm")
    rough = GaussianCorrelation(0.02, 0.5)
    hits = cache.stats.hits
    e1 = em.emissivity(rough, 17 + 2j, **kw)
    e2 = em.emissivity(rough, 17 + 2j, **kw)
    assert cache.stats.hits == hits + 1
    np.testing.assert_array_equal(e1.emissivity, e2.emissivity)
    np.testing.assert_array_equal(e1.error, e2.error)
    e3 = em.emissivity(rough, 17 + 2.001j, **kw)  # another input: computed, not served
    assert cache.stats.hits == hits + 1 and not np.array_equal(e3.emissivity, e1.emissivity)


def test_an_unusable_folder_or_value_never_stops_the_computation(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("EMSCATTER_CACHE_DIR", str(blocker / "cache"))  # cannot be created
    c = Counter(7)
    assert cache.cached("test", "k", c) == 7 and cache.cached("test", "k", c) == 7
    assert c.calls == 2
    monkeypatch.setenv("EMSCATTER_CACHE_DIR", str(tmp_path / "ok"))
    before = cache.stats.unusable
    assert cache.cached("test", "lambda", lambda: lambda: 1)() == 1  # does not pickle
    assert cache.stats.unusable == before + 1
