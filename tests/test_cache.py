"""emscatter.cache: keys, atomic entries, corruption, two processes, size limit, switches."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

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
    assert len(list(fresh_cache.rglob("*.pkl"))) == 1


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
    (path,) = fresh_cache.rglob("*.pkl")
    blob = bytearray(path.read_bytes())
    if damage == "truncate":
        blob = blob[: len(blob) // 2]
    elif damage == "flip":
        blob[-100] ^= 0x01  # one bit inside the array data
    elif damage == "garbage":
        blob = bytearray(b"not a cache entry" * 10)
    else:
        blob = bytearray()
    path.write_bytes(bytes(blob))
    before = cache.stats.corrupt
    c.value = np.arange(1000.0) * 2  # what a recomputation gives (proves it recomputed)
    got = cache.cached("test", "k", c)
    assert c.calls == 2 and cache.stats.corrupt == before + 1
    np.testing.assert_array_equal(got, np.arange(1000.0) * 2)
    # the rewritten entry is sound again
    np.testing.assert_array_equal(cache.cached("test", "k", c), got)
    assert c.calls == 2


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
