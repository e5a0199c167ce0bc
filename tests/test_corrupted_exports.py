"""Every export reader rejects a damaged file, naming the file and what is wrong (issue 23).

For each reader (MERL ``.binary``, RGL ``.bsdf``, ``.npz``): 64 bytes flipped at random places
after the header (the issue's case: ``read_merl`` returned values up to 1.8e127, ``read_rgl``
2.2e24), a truncated file, and foreign files (a PNG, a text file, another reader's format).
The sound file is read first each time, so every rejection is of the damage alone.
"""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from emscatter.brdf import build_table
from emscatter.brdf import export_merl as merl
from emscatter.brdf.export_npz import read_npz, write_npz
from emscatter.brdf.export_rgl import RglFormatError, read_rgl, write_rgl
from emscatter.spectra import GaussianCorrelation

WL = [0.45e-6, 0.55e-6, 0.65e-6]
PNG = b"\x89PNG\r\n\x1a\n" + b"\0\0\0\rIHDR" + bytes(range(256)) * 4
TEXT = b"theta_i,theta_o,value\n0.1,0.2,0.3\n" * 50


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """One sound file per format, from one small gold GO table (σ/ℓ = 0.15)."""
    d = tmp_path_factory.mktemp("exports")
    rough = GaussianCorrelation(0.15e-6, 1.0e-6)
    table = build_table(rough, "Au", WL, method="go", resolution=(12, 13), out_of_range="ignore")
    return {
        "merl": merl.write_merl(table, d / "t.binary"),
        "rgl": write_rgl(d / "t.bsdf", table, channels="spectral", n_theta_i=4, n_samples=8),
        "npz": write_npz(table, d / "t.npz"),
        "npz-raw": write_npz(table, d / "raw.npz", compress=False),
    }


READERS = {
    "merl": (merl.read_merl, merl.MerlFormatError, 12),
    "rgl": (read_rgl, RglFormatError, 64),  # past the magic and the first field names
    "npz": (read_npz, ValueError, 0),
    "npz-raw": (read_npz, ValueError, 0),
}


def _flip(blob: bytes, seed: int, start: int, n: int = 64) -> bytes:
    rng = np.random.default_rng(seed)
    out = bytearray(blob)
    at = rng.choice(np.arange(start, len(blob)), size=n, replace=False)
    for i, x in zip(at, rng.integers(1, 256, size=n), strict=True):
        out[i] ^= int(x)  # never 0: every chosen byte changes
    return bytes(out)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("fmt", list(READERS))
def test_flipped_bytes_are_rejected(files, tmp_path, fmt, seed):
    read, error, start = READERS[fmt]
    good = files[fmt]
    read(good)  # the sound file reads
    bad = tmp_path / f"flipped{good.suffix}"
    bad.write_bytes(_flip(good.read_bytes(), seed, start))
    with pytest.raises(error) as err:
        read(bad)
    msg = str(err.value)
    assert str(bad) in msg
    assert any(
        w in msg for w in ("damaged", "truncated", "not a", "longer than", "unknown type")
    ), msg


def test_merl_flips_that_made_1e127_name_what_is_wrong(files, tmp_path):
    """The issue's symptom: a flipped exponent byte read as a huge f_r."""
    blob = bytearray(files["merl"].read_bytes())
    raw = np.frombuffer(bytes(blob[12:]), "<f8")
    i = int(np.argmax(raw > 0))  # a lit bin
    blob[12 + 8 * i + 7] ^= 0x1A  # its exponent: the value grows by 2^416
    bad = tmp_path / "huge.binary"
    bad.write_bytes(bytes(blob))
    with pytest.raises(merl.MerlFormatError, match=r"exceed 1e\+07 1/sr.*largest [0-9.]+e\+1"):
        merl.read_merl(bad)
    blob[12 + 8 * i + 7] ^= 0x1A ^ 0x80  # the sign instead
    bad.write_bytes(bytes(blob))
    with pytest.raises(merl.MerlFormatError, match=r"1 values are negative.*channel R"):
        merl.read_merl(bad)
    assert merl.read_merl(bad, allow_negative=True).raw.min() < 0  # the database's markers
    blob[12 + 8 * i : 12 + 8 * i + 8] = np.array([np.nan]).tobytes()
    bad.write_bytes(bytes(blob))
    with pytest.raises(merl.MerlFormatError, match=r"1 values are NaN or inf"):
        merl.read_merl(bad)


def test_rgl_damaged_values_name_the_field(files, tmp_path):
    from emscatter.brdf.export_rgl import _write_tensor_file, read_tensor_file

    f = read_tensor_file(files["rgl"])
    cases = {
        "spectra": ("spectra", lambda a: a.__setitem__((0, 1, 0, 2, 3), -0.5), "negative"),
        "huge": ("spectra", lambda a: a.__setitem__((0, 1, 0, 2, 3), 2.2e24), "albedo"),
        "vndf": ("vndf", lambda a: a.__setitem__((0, 0, 1, 1), -1.0), "'vndf' has negative"),
        "empty": ("luminance", lambda a: a.__setitem__((0, 2), 0.0), "empty slice"),
        "sigma": ("sigma", lambda a: a.__setitem__((0, 0), 0.0), "'sigma' must be > 0"),
        "theta": ("theta_i", lambda a: a.__setitem__(1, 3.0), "theta_i must rise"),
        "jacobian": ("jacobian", lambda a: a.__setitem__(0, 7), "'jacobian' must be 0 or 1"),
    }
    for label, (name, damage, match) in cases.items():
        g = {k: v.copy() for k, v in f.items()}
        damage(g[name])
        path = tmp_path / f"{label}.bsdf"
        _write_tensor_file(path, g)
        with pytest.raises(RglFormatError, match=match) as err:
            read_rgl(path)
        assert str(path) in str(err.value) and "is damaged" in str(err.value)
    raw = files["rgl"].read_bytes()
    (tmp_path / "long.bsdf").write_bytes(raw + b"\0" * 64)
    with pytest.raises(RglFormatError, match="longer than its fields"):
        read_rgl(tmp_path / "long.bsdf")


def test_npz_checksum_catches_an_edit_with_a_valid_zip(files, tmp_path):
    """An uncompressed member changed in place, its zip CRC-32 recomputed: only the SHA-256
    can tell."""
    blob = bytearray(files["npz-raw"].read_bytes())
    t = read_npz(files["npz-raw"])
    vals = np.ascontiguousarray(t.values).tobytes()
    at = blob.index(vals[:64])
    new = (np.frombuffer(vals, float) * 1.001).tobytes()  # plausible, wrong numbers
    blob[at : at + len(new)] = new
    import zipfile

    with zipfile.ZipFile(files["npz-raw"]) as z:
        info = z.getinfo("values.npy")
        member = z.read("values.npy")
    member = member.replace(vals, new)
    crc = zlib.crc32(member).to_bytes(4, "little")
    # patch the CRC in the local header (offset 14) and in the central directory
    old_crc = info.CRC.to_bytes(4, "little")
    blob = blob.replace(old_crc, crc)
    bad = tmp_path / "edited.npz"
    bad.write_bytes(bytes(blob))
    with zipfile.ZipFile(bad) as z:
        assert z.testzip() is None  # a valid zip archive
    with pytest.raises(ValueError, match="SHA-256 checksum does not match") as err:
        read_npz(bad)
    assert str(bad) in str(err.value)


@pytest.mark.parametrize("fmt", list(READERS))
@pytest.mark.parametrize("keep", [0.5, 0.999, 100])
def test_truncated_files_are_rejected(files, tmp_path, fmt, keep):
    read, error, _ = READERS[fmt]
    blob = files[fmt].read_bytes()
    n = int(len(blob) * keep) if keep < 1 else keep
    bad = tmp_path / f"short{files[fmt].suffix}"
    bad.write_bytes(blob[:n])
    with pytest.raises(error, match="truncated|shorter|not a readable|damaged") as err:
        read(bad)
    assert str(bad) in str(err.value)


@pytest.mark.parametrize("fmt", list(READERS))
@pytest.mark.parametrize("foreign", ["png", "text", "other", "empty"])
def test_foreign_files_are_rejected(files, tmp_path, fmt, foreign):
    read, error, _ = READERS[fmt]
    other = {"merl": "rgl", "rgl": "npz", "npz": "merl", "npz-raw": "rgl"}[fmt]
    blob = {
        "png": PNG,
        "text": TEXT,
        "other": files[other].read_bytes(),
        "empty": b"",
    }[foreign]
    bad = tmp_path / f"foreign{files[fmt].suffix}"
    bad.write_bytes(blob)
    want = {
        "merl": "not a MERL BRDF|longer than a MERL BRDF",
        "rgl": "not a Mitsuba tensor file",
        "npz": "not a readable .npz file",
        "npz-raw": "not a readable .npz file",
    }[fmt]
    with pytest.raises(error, match=want) as err:
        read(bad)
    assert str(bad) in str(err.value)
