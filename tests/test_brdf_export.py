"""Exports: MERL .binary (round trip exact, clear errors, atomic) and .npz (full metadata)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from emscatter.brdf import build_table, frames
from emscatter.brdf import export_merl as merl
from emscatter.brdf.export_npz import read_npz, write_npz
from emscatter.io import _jsonable
from emscatter.spectra import GaussianCorrelation

WL = [0.45e-6, 0.55e-6, 0.65e-6]


@pytest.fixture(scope="module")
def table():
    rough = GaussianCorrelation(0.15e-6, 1.0e-6)  # m = 0.3
    return build_table(rough, "Au", WL, method="go", resolution=(30, 37), out_of_range="ignore")


@pytest.fixture(scope="module")
def merl_file(table, tmp_path_factory):
    return merl.write_merl(table, tmp_path_factory.mktemp("merl") / "gold.binary")


def test_merl_bins_are_self_consistent():
    wi, wo = merl.merl_bin_directions()
    sub = (slice(None, None, 3),) * 3
    ih, idd, ip = merl.merl_indices(wi[sub], wo[sub])
    grid = np.meshgrid(*(np.arange(n)[::3] for n in merl.MERL_SHAPE), indexing="ij")
    for got, want in zip((ih, idd, ip), grid, strict=True):
        np.testing.assert_array_equal(got, want)
    # the half vector of every bin's pair is at the bin's θh, in the x–z plane (φh = 0)
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    th = ((np.arange(90) + 0.5) / 90) ** 2 * (math.pi / 2)
    np.testing.assert_allclose(np.arccos(h[:, 0, 0, 2]), th, atol=1e-12)


def test_merl_round_trip(table, merl_file, tmp_path):
    path = merl_file
    assert path.stat().st_size == 12 + 8 * 3 * 90 * 90 * 180
    m = merl.read_merl(path)
    wi, wo = merl.merl_bin_directions()
    want = table.evaluate(wi, wo, wavelength=np.array(WL[::-1]))  # R, G, B
    raw = want / merl.MERL_SCALES[:, None, None, None]
    np.testing.assert_array_equal(m.raw, raw)  # the stored bins, bit for bit
    np.testing.assert_allclose(m.values, want, rtol=1e-15)
    # rewriting what was read reproduces the file exactly
    again = merl.write_merl_raw(m.raw, tmp_path / "again.binary")
    assert again.read_bytes() == path.read_bytes()
    # the reference lookup at the bin centres returns the bins; between them, the table
    np.testing.assert_allclose(
        m.evaluate(wi[::7, ::7, ::9], wo[::7, ::7, ::9]), want[:, ::7, ::7, ::9], rtol=1e-15
    )
    rng = np.random.default_rng(0)
    wi = frames.directions(rng.uniform(0, 1.2, 4000), rng.uniform(0, 6.3, 4000))
    wo = frames.directions(rng.uniform(0, 1.2, 4000), rng.uniform(0, 6.3, 4000))
    ref = table.evaluate(wi, wo, wavelength=WL[2])
    got = m.evaluate(wi, wo)[0]
    sig = ref > 0.05 * ref.max()
    rel = np.abs(got - ref)[sig] / ref[sig]
    assert np.median(rel) < 0.05  # MERL's nearest-bin lookup vs the table's interpolant


def test_merl_errors(table, merl_file, tmp_path):
    data = merl_file.read_bytes()
    (tmp_path / "short.binary").write_bytes(data[:1000])
    (tmp_path / "tiny.binary").write_bytes(data[:5])
    (tmp_path / "long.binary").write_bytes(data + b"\0" * 8)
    foreign = np.array([64, 64, 64], "<i4").tobytes() + data[12:]
    (tmp_path / "foreign.binary").write_bytes(foreign)
    for name, match in (
        ("short", "truncated"),
        ("tiny", "header"),
        ("long", "longer"),
        ("foreign", "dimensions"),
    ):
        with pytest.raises(merl.MerlFormatError, match=match):
            merl.read_merl(tmp_path / f"{name}.binary")
    with pytest.raises(FileNotFoundError, match="no such"):
        merl.read_merl(tmp_path / "missing.binary")
    two = table.replace(
        wavelengths=table.wavelengths[:2],
        values=table.values[:2],
        coherent=table.coherent[:2],
        coherent_polarized=table.coherent_polarized[:, :2],
    )
    with pytest.raises(ValueError, match="channel_wavelengths"):
        merl.write_merl(two, tmp_path / "x.binary")
    with pytest.raises(ValueError, match="three wavelengths"):
        merl.write_merl(two, tmp_path / "x.binary", channel_wavelengths=[0.55e-6, 0.5e-6])


def test_interrupted_export_leaves_nothing(table, tmp_path, monkeypatch):
    target = tmp_path / "out.binary"

    def fail_halfway(fh, raw):
        fh.write(b"\0" * 4096)
        raise OSError("disk full (injected)")

    monkeypatch.setattr(merl, "_write_payload", fail_halfway)
    monkeypatch.setattr(merl, "_channel_values", lambda *a: np.zeros((3, *merl.MERL_SHAPE)))
    with pytest.raises(OSError, match="injected"):
        merl.write_merl(table, target)
    assert list(tmp_path.iterdir()) == []
    # an existing file survives a failed overwrite untouched
    target.write_bytes(b"previous")
    with pytest.raises(OSError, match="injected"):
        merl.write_merl(table, target)
    assert target.read_bytes() == b"previous" and len(list(tmp_path.iterdir())) == 1


def test_npz_round_trip_keeps_everything(tmp_path):
    rough = GaussianCorrelation(0.02e-6, 0.3e-6)
    t = build_table(
        rough,
        4 + 0.3j,
        [0.5e-6, 0.6e-6],
        method="spm",
        resolution=(8, 9),
        polarized=True,
        out_of_range="ignore",
    )
    back = read_npz(write_npz(t, tmp_path / "t.npz"))
    for name in (
        "wavelengths",
        "theta_i",
        "theta_o",
        "phi_d",
        "values",
        "coherent",
        "coherent_polarized",
        "polarized",
    ):
        np.testing.assert_array_equal(getattr(back, name), getattr(t, name))
    assert back.metadata == json.loads(json.dumps(t.metadata, default=_jsonable))
    assert back.metadata["solver"] == "spm" and back.metadata["units"]["values"] == "1/sr"
    assert "remedy_applied" in back.metadata["energy"]
    assert back.metadata["material"]["type"] == "Constant"
    wi = frames.directions(0.3, 0.0)
    np.testing.assert_array_equal(back.evaluate(wi, wi), t.evaluate(wi, wi))


def test_npz_errors(tmp_path):
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match="not a readable"):
        read_npz(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", a=np.ones(3))
    with pytest.raises(ValueError, match="not an emscatter BRDF"):
        read_npz(tmp_path / "other.npz")
    with pytest.raises(ValueError, match=".npz"):
        write_npz(_tiny(), tmp_path / "t.bin")


def _tiny():
    from emscatter.brdf import BrdfTable
    from emscatter.brdf.build import default_phi_d, default_theta

    th = default_theta(3)
    return BrdfTable(
        wavelengths=[5e-7],
        theta_i=th,
        theta_o=th,
        phi_d=default_phi_d(3),
        values=np.ones((1, 3, 3, 3)),
    )
