"""The 3-D cells in auto's blend (emscatter.solvers.blend, step 3; issue 20): their errors
interpolated continuously in (θi, log kσ, log kℓ), the layer continuous in every parameter,
absent → the old weights bit for bit, per-angle weights in the API, and the hard rule
(measured.significant_pick) at the cell centres."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import emscatter as em
from emscatter import method_resolution as dispatch
from emscatter.solvers import blend, measured
from emscatter.spectra import ExponentialCorrelation, GaussianCorrelation, PowerLawCorrelation
from synthetic_table_3d import write_table

K = 2 * math.pi
NAMES = ("spm", "go", "po", "iem")


def _eps_of(m: dict):
    return "pec" if m["medium"] == "conductor" else complex(*m["eps"])


def _gaussian_maps() -> list[dict]:
    return [m for m in measured.load_table_3d()["maps"] if m["correlation"] == "gaussian"]


@pytest.fixture
def table(tmp_path, monkeypatch):
    """Point the package's 3-D table at a synthetic Gaussian PEC one (θi 20/40°, kσ 0.1/0.3/1,
    kℓ 3/7), every cell with the same errors / SEs: ``table(errors, se, pair_se)``;
    ``table(None)``: no table (no 3-D cell anywhere)."""

    def use(errors, se=None, pair_se=None):
        path = tmp_path / "m3d.json"
        if errors is None:
            path = tmp_path / "missing.json"
        else:
            write_table(path, errors, se, pair_se)
        monkeypatch.setattr(measured, "TABLE_3D_PATH", path)
        measured.load_table_3d.cache_clear()
        dispatch.clear_cache()
        return path

    yield use
    measured.load_table_3d.cache_clear()
    dispatch.clear_cache()


# ----------------------------------------------------------------------------- interpolation
def test_interpolated_3d_errors_are_the_cells_at_their_centres():
    for m in measured.load_table_3d()["maps"]:
        cls = {"gaussian": GaussianCorrelation, "exponential": ExponentialCorrelation}
        rough_of = cls[m["correlation"]]
        for a, th in enumerate(m["theta_i_deg"]):
            for i, ks in enumerate(m["k_sigma"]):
                for j, kl in enumerate(m["k_l"]):
                    got = measured.interpolated_errors_3d(
                        rough_of(ks / K, kl / K), K, _eps_of(m), math.radians(th)
                    )
                    if got is None:  # a cell not computed: nothing measured there
                        assert all(g[a][i][j] is None for g in m["errors"].values())
                        continue
                    assert got["map"] == m["tag"]
                    for name, cells in m["errors"].items():
                        if cells[a][i][j] is None:
                            assert got["availability"][name][0] == 0.0
                            continue
                        assert got["errors"][name][0] == pytest.approx(cells[a][i][j], abs=1e-12)
                        assert got["availability"][name][0] == pytest.approx(1.0)
                        se = m["se"][name][a][i][j]
                        if se is not None:
                            assert got["se"][name][0] == pytest.approx(se, abs=1e-12)
                    for key, cells in m.get("pair_se", {}).items():
                        x, y = key.split("|")
                        if cells[a][i][j] is not None:
                            assert got["pair_se"][(y, x)][0] == pytest.approx(cells[a][i][j])


def test_interpolated_3d_errors_fade_over_half_a_step_on_every_axis():
    """Half a step beyond the outermost cells (θi: the map's step; a single-value axis: the
    smallest step of that axis over the table's maps) the availability is 0; a quarter step
    beyond, ½; in between two cells the errors are the linear interpolation in that axis."""
    maps = measured.load_table_3d()["maps"]
    for m in _gaussian_maps():
        eps = _eps_of(m)
        ti, ks, kl = (np.asarray(m[k], dtype=float) for k in ("theta_i_deg", "k_sigma", "k_l"))

        def step(key, log, m=m):
            g = [np.asarray(x[key], float) for x in ([m] if len(m[key]) > 1 else maps)]
            return min(float(np.min(np.diff(np.log(x) if log else x))) for x in g if x.size > 1)

        st_t, st_s, st_l = step("theta_i_deg", False), step("k_sigma", True), step("k_l", True)
        rough = GaussianCorrelation(ks[0] / K, kl[0] / K)
        far = np.radians([ti[0] - st_t / 2 * 1.001, ti[-1] + st_t / 2 * 1.001])
        assert measured.interpolated_errors_3d(rough, K, eps, far) is None
        quarter = np.radians([ti[0] - st_t / 4, ti[-1] + st_t / 4])
        got = measured.interpolated_errors_3d(rough, K, eps, quarter)
        assert got["availability"]["iem"] == pytest.approx([0.5, 0.5])
        for axis, grid, stp in (("ks", ks, st_s), ("kl", kl, st_l)):
            for value, avail in ((grid[-1] * math.exp(stp / 4), 0.5),
                                 (grid[-1] * math.exp(stp / 2 * 1.001), None)):  # fmt: skip
                s_, l_ = (value, kl[0]) if axis == "ks" else (ks[0], value)
                r = GaussianCorrelation(s_ / K, l_ / K)
                got = measured.interpolated_errors_3d(r, K, eps, math.radians(ti[0]))
                if avail is None:
                    assert got is None and measured.support_3d(r, K, eps) is None
                else:
                    assert got["availability"]["iem"][0] == pytest.approx(avail)
        if ti.size > 1:  # midway in θi: the mean of the two slices
            mid = math.radians(0.5 * (ti[0] + ti[1]))
            got = measured.interpolated_errors_3d(rough, K, eps, mid)
            cells = m["errors"]["iem"]
            assert got["errors"]["iem"][0] == pytest.approx(0.5 * (cells[0][0][0] + cells[1][0][0]))


@pytest.mark.parametrize(
    ("rough", "eps"),
    [
        (GaussianCorrelation(0.3 / K, 3 / K, dimension=1), "pec"),  # a profile: 1-D maps
        (GaussianCorrelation(0.3 / K, 3 / K), 20.0),  # a dielectric far from the map's ε
        (GaussianCorrelation(0.3 / K, 3 / K, 6 / K), "pec"),  # anisotropic
        (PowerLawCorrelation(0.3 / K, 3 / K, hurst=0.8, dimension=2), "pec"),
        (GaussianCorrelation(0.3 / K, 30 / K), "pec"),  # kℓ beyond the cells
    ],
)
def test_no_3d_layer_where_no_cell_applies(rough, eps):
    assert measured.support_3d(rough, K, eps) is None
    assert measured.interpolated_errors_3d(rough, K, eps, math.radians(30)) is None


@settings(max_examples=80, deadline=None)
@given(
    log_ks=st.floats(math.log10(0.03), math.log10(3.0)),
    log_kl=st.floats(math.log10(1.2), math.log10(15.0)),
    theta=st.floats(0.0, 70.0),
    medium=st.sampled_from(["pec", 4 + 0.5j, 3.0]),
)
def test_the_3d_layer_reaches_no_further_than_the_cells_half_steps(log_ks, log_kl, theta, medium):
    """Where the nearest-cell lookup finds no cell on a two-value axis, nor does the
    interpolation (it may reach further on a single-value axis: module docstring)."""
    rough = GaussianCorrelation(10**log_ks / K, 10**log_kl / K)
    got = measured.interpolated_errors_3d(rough, K, medium, math.radians(theta))
    if (
        got is not None
        and measured.measured_errors_3d(rough, K, medium, math.radians(theta)) is None
    ):
        m = next(x for x in _gaussian_maps() if x["tag"] == got["map"])
        assert min(len(m["theta_i_deg"]), len(m["k_sigma"]), len(m["k_l"])) == 1


# ----------------------------------------------------------------------------- the weights
def _w(rough, eps, theta, monostatic=False) -> np.ndarray:
    w = blend.blend_weights(rough, K, eps=eps, monostatic=monostatic, theta_i=theta)["weights"]
    return np.array([np.broadcast_to(w.get(n, 0.0), np.shape(theta)) for n in NAMES])


@settings(max_examples=80, deadline=None)
@given(
    log_ks=st.floats(math.log10(0.05), math.log10(2.0)),
    log_kl=st.floats(math.log10(1.5), math.log10(12.0)),
    theta=st.floats(5.0, 55.0),
    eps=st.sampled_from(["pec", 4 + 0.5j, 3.0]),
    axis=st.sampled_from([0, 1, 2]),
    monostatic=st.booleans(),
)
def test_weights_are_continuous_in_theta_ks_kl(log_ks, log_kl, theta, eps, axis, monostatic):
    """A step of 1e-7 (relative in kσ, kℓ; in radians in θi) moves no weight by more than 1e-4,
    cell edges, the box's fades and the significance thresholds included: every factor is
    Lipschitz (smoothsteps of the interpolated errors over widths Δ = 0.1 dB and Z = ½ SE,
    SEs ≥ 0.05 dB, errors changing by less than 40 dB per unit log or per radian: slopes
    below 1e3)."""
    ks, kl, ti = 10.0**log_ks, 10.0**log_kl, math.radians(theta)
    sides = []
    for f in (-1e-7, 1e-7):
        s, l_, t = ks, kl, ti
        if axis == 0:
            s = ks * (1 + f)
        elif axis == 1:
            l_ = kl * (1 + f)
        else:
            t = ti + f
        sides.append(_w(GaussianCorrelation(s / K, l_ / K), eps, t, monostatic))
    assert np.all(sides[0] >= 0) and math.isclose(sides[0].sum(), 1.0, rel_tol=1e-12)
    np.testing.assert_allclose(sides[0], sides[1], atol=1e-4)


@pytest.mark.parametrize(
    ("rough", "eps", "theta"),
    [
        (GaussianCorrelation(0.3 / K, 3 / K), "pec", 60.0),  # beyond the θi fade (50°)
        (GaussianCorrelation(0.3 / K, 3 / K), "pec", 5.0),
        (GaussianCorrelation(0.3 / K, 3 / K, 3.3 / K), "pec", 30.0),  # anisotropic
        (GaussianCorrelation(0.3 / K, 3 / K, dimension=1), "pec", 30.0),  # a profile
        (GaussianCorrelation(0.3 / K, 3 / K), 17 + 2j, 30.0),  # no map for this ε
        (GaussianCorrelation(0.3 / K, 40 / K), "pec", 30.0),
        (PowerLawCorrelation(0.3 / K, 3 / K, hurst=0.8, dimension=2), 3.0, 30.0),
    ],
)
@pytest.mark.parametrize("monostatic", [False, True])
def test_without_the_3d_layer_the_weights_are_the_old_ones_bit_for_bit(
    rough, eps, theta, monostatic
):
    old = blend.blend_weights(rough, K, eps=eps, monostatic=monostatic)
    new = blend.blend_weights(rough, K, eps=eps, monostatic=monostatic, theta_i=math.radians(theta))
    assert new == old and "measured_3d" not in new
    arr = blend.blend_weights(
        rough, K, eps=eps, monostatic=monostatic, theta_i=np.radians([theta, theta, theta])
    )
    assert arr == old  # scalars: no angle dependence


def test_an_exponential_surface_is_unchanged_where_no_exponential_map_exists():
    if any(m["correlation"] == "exponential" for m in measured.load_table_3d()["maps"]):
        pytest.skip("the 3-D table has exponential cells")
    rough = ExponentialCorrelation(0.3 / K, 3 / K)
    for eps in ("pec", 4 + 0.5j):
        old = blend.blend_weights(rough, K, eps=eps)
        assert blend.blend_weights(rough, K, eps=eps, theta_i=np.radians([20.0, 40.0])) == old


def test_a_missing_3d_table_gives_the_old_weights_bit_for_bit(table):
    rough = GaussianCorrelation(0.3 / K, 3 / K)
    table(None)
    old = blend.blend_weights(rough, K, eps="pec")
    assert blend.blend_weights(rough, K, eps="pec", theta_i=np.radians([20.0, 30.0])) == old
    assert dispatch.blend_weights(rough, K, eps="pec", theta_i=np.radians(30.0)) == old


def test_no_significant_difference_leaves_the_1d_result(table):
    """Every gap far below 2 combined SEs: the 3-D layer changes nothing."""
    rough = GaussianCorrelation(0.3 / K, 3 / K)  # on SPM's kσ limit: spm/iem by the criteria
    table({"spm": 3.0, "iem": 2.0, "po": 2.5, "go": 9.0}, {n: 3.0 for n in NAMES})
    old = blend.blend_weights(rough, K, eps="pec")
    new = blend.blend_weights(rough, K, eps="pec", theta_i=math.radians(30))
    assert "measured_3d" in new
    assert new["weights"] == pytest.approx(old["weights"], abs=1e-12)


def test_a_significant_difference_moves_the_weight_and_fades_with_theta(table):
    """spm 3 dB off, the IEM 0.5 dB, significantly (gap 2.5 dB, paired SE 0.2 dB): where the
    criteria give SPM (kσ = 0.1), the IEM takes it inside the θi box (10°–50°), half of it a
    quarter step (5°) beyond 40°, none beyond 50°."""
    rough = GaussianCorrelation(0.1 / K, 3 / K)
    table({"spm": 3.0, "iem": 0.5}, {"spm": 0.3, "iem": 0.3}, {"spm|iem": 0.2})
    assert blend.blend_weights(rough, K, eps="pec")["weights"] == {"spm": 1.0}
    got = blend.blend_weights(rough, K, eps="pec", theta_i=np.radians([30.0, 45.0, 55.0]))
    assert got["weights"]["iem"] == pytest.approx([1.0, 0.5, 0.0])
    assert got["weights"]["spm"] == pytest.approx([0.0, 0.5, 1.0])


@pytest.mark.parametrize("monostatic", [False, True])
def test_scalar_and_array_theta_agree_per_angle(monostatic):
    rough = GaussianCorrelation(0.3 / K, 5 / K)
    ti = np.radians(np.array([[8.0, 15.0, 25.0], [33.0, 44.0, 52.0]]))
    arr = blend.blend_weights(rough, K, eps="pec", monostatic=monostatic, theta_i=ti)
    assert {np.shape(w) for w in arr["weights"].values()} == {ti.shape}
    total = sum(arr["weights"].values())
    np.testing.assert_allclose(total, 1.0, rtol=1e-12)
    for idx in np.ndindex(ti.shape):
        one = blend.blend_weights(rough, K, eps="pec", monostatic=monostatic, theta_i=ti[idx])
        for n in NAMES:
            assert one["weights"].get(n, 0.0) == pytest.approx(
                float(arr["weights"].get(n, np.zeros(ti.shape))[idx]), abs=1e-12
            )
    res = em.backscatter(rough, "pec", wavelength=1.0, theta_i=ti, out_of_range="ignore")
    for idx in np.ndindex(ti.shape):
        one = em.backscatter(rough, "pec", wavelength=1.0, theta_i=ti[idx], out_of_range="ignore")
        np.testing.assert_allclose(res.sigma0[(..., *idx)], one.sigma0, rtol=1e-9)


def test_the_api_reports_per_angle_weights_and_runs_their_union(table):
    """SPM alone by the criteria (kσ = 0.1), the cells measure the IEM significantly better:
    the IEM at 30°, SPM outside the θi box; both run, each σ⁰ weighted per angle."""
    table({"spm": 3.0, "iem": 0.5}, {"spm": 0.3, "iem": 0.3}, {"spm|iem": 0.2})
    rough = GaussianCorrelation(0.1 / K, 3 / K)
    ti = np.radians([5.0, 30.0, 45.0, 60.0])
    res = em.backscatter(rough, "pec", wavelength=1.0, theta_i=ti, out_of_range="ignore")
    weights = res.info["blend"]["weights"]
    assert set(res.method.split("+")) == set(weights) == set(res.info["by_method"])
    assert weights["iem"] == pytest.approx([0.0, 1.0, 0.5, 0.0])
    for w in weights.values():
        assert np.shape(w) == ti.shape
    np.testing.assert_allclose(sum(weights.values()), 1.0, rtol=1e-12)
    # at 5° and 60° (outside 10°–50°) the 1-D blend
    old = blend.blend_weights(rough, K, eps="pec", monostatic=True)["weights"]
    for n in weights:
        assert weights[n][[0, 3]] == pytest.approx([old.get(n, 0.0)] * 2, abs=1e-12)
    parts = {n: em.backscatter(rough, "pec", wavelength=1.0, theta_i=ti, method=n,
                               out_of_range="ignore").sigma0 for n in weights}  # fmt: skip
    co = sum(weights[n] * parts[n][[0, 1], [0, 1]] for n in weights)
    np.testing.assert_allclose(res.sigma0[[0, 1], [0, 1]], co, rtol=1e-9)


# ----------------------------------------------------------------------------- the hard rule
def _saturated(meas: dict, f: str, names) -> bool:
    """Every factor of the 3-D rule for the criteria's ``f`` at a cell at least its width
    from its threshold (the blend's factors are then 0 or 1: module docstring)."""
    e = meas["errors"]
    d, z_w = blend.MEASURED_WIDTH_DB, blend.SIGNIFICANCE_WIDTH
    values = [e[n] for n in names if math.isfinite(e.get(n, math.nan))]
    if any(abs(x - measured.TOL_DB) < d for x in values):
        return False
    for n in names:
        if n == f or not math.isfinite(e.get(n, math.nan)):
            continue
        gap = e[f] - e[n]
        z = abs(gap) / measured.combined_se(meas, f, n)
        if abs(z - measured.SIGNIFICANCE) < z_w or abs(abs(gap) - measured.TOL_DB) < d:
            return False
    return True


def test_at_the_cell_centres_the_blend_follows_significant_pick():
    """At each 3-D cell centre where the criteria's weight is on one method f and every factor
    is saturated: the method significant_pick puts before f is the heaviest weight; where it
    puts none, the 3-D layer leaves the 1-D weights — except that a method the cell measures
    significantly worse than f gives its 1-D weight back to f (rank_methods' veto)."""
    tested = 0
    for m in _gaussian_maps():
        eps = _eps_of(m)
        for th in m["theta_i_deg"]:
            for ks in m["k_sigma"]:
                for kl in m["k_l"]:
                    rough, ti = GaussianCorrelation(ks / K, kl / K), math.radians(th)
                    cell = measured.measured_errors_3d(rough, K, eps, ti)
                    if cell is None:
                        continue
                    for mono in (False, True):
                        order = blend.auto_order(eps, monostatic=mono)
                        old = blend.blend_weights(rough, K, eps=eps, monostatic=mono)
                        crit = old["criteria"]
                        f = next(iter(crit))
                        if len(crit) != 1 or not _saturated(cell, f, order):
                            continue
                        new = blend.blend_weights(rough, K, eps=eps, monostatic=mono, theta_i=ti)
                        pick = measured.significant_pick(cell, f, order)
                        vetoed = [p for p in order if measured.significant_pick(cell, p, [f]) == f]
                        heaviest = max(new["weights"], key=new["weights"].get)
                        if pick is not None:
                            assert heaviest == pick
                        elif not vetoed:
                            assert new["weights"] == pytest.approx(old["weights"], abs=1e-9)
                        else:  # the vetoed methods' 1-D weight goes back to f
                            was = max(old["weights"], key=old["weights"].get)
                            assert heaviest == (f if was in vetoed else was)
                            for p in vetoed:
                                assert new["weights"].get(p, 0.0) <= old["weights"].get(p, 0.0)
                        tested += 1
    assert tested >= 4


# ----------------------------------------------------------------------------- σ⁰ continuity
def _db(x):
    return 10 * np.log10(x)


def _lobe(*curves):
    """The angles where every curve (dB, ``(pol, angle)``) is within :data:`LOBE_DB` of its
    peak: the lobe that the properties' jump test reads too (``tests/test_properties.py``,
    1e-2 of the peak). Beyond it the methods differ by tens of dB (a Gaussian spectrum's
    tail against the IEM's higher orders), and any continuous weight moves σ⁰ there by a
    fraction of the larger one."""
    return np.logical_and.reduce([c >= c.max(axis=-1, keepdims=True) - LOBE_DB for c in curves])


def _jumps(samples, eps, ti):
    """Auto's backscatter co-pol [dB] change between neighbouring roughness samples over the
    lobe (:func:`_lobe`), and the bound the law gives it less MAX_JUMP_DB: the largest change
    of its methods' own σ⁰ there (a convex combination with fixed weights moves no more than
    its parts; MAX_JUMP_DB is the weights' share)."""
    runs = []
    for rough in samples:
        res = em.backscatter(rough, eps, wavelength=1.0, theta_i=ti, out_of_range="ignore")
        names = set(res.method.split("+"))
        runs.append((rough, res.sigma0[[0, 1], [0, 1]], names))
    for (r0, a, n0), (r1, b, n1) in zip(runs[:-1], runs[1:], strict=True):
        lobe = _lobe(_db(a), _db(b))
        own = 0.0
        for n in n0 | n1:
            s0, s1 = (em.backscatter(r, eps, wavelength=1.0, theta_i=ti, method=n,
                                     out_of_range="ignore").sigma0[[0, 1], [0, 1]]
                      for r in (r0, r1))  # fmt: skip
            own = max(own, float(np.max(np.abs(_db(s1) - _db(s0))[lobe])))
        yield float(np.max(np.abs(_db(b) - _db(a))[lobe])), own


#: Largest σ⁰ change [dB] the weights may add between neighbouring samples (issue 20's 0.5 dB).
MAX_JUMP_DB = 0.5
#: The lobe [dB below the peak] over which the changes are read (:func:`_lobe`).
LOBE_DB = 20.0


@pytest.mark.parametrize(
    ("axis", "lo", "hi", "other", "eps"),
    [
        ("k_sigma", 0.07, 1.5, 3.0, "pec"),  # across the box in kσ: SPM → IEM by the cells
        ("k_sigma", 0.07, 1.5, 7.0, "pec"),
        ("k_sigma", 0.07, 1.5, 3.2, 3.0),  # the dielectric map (ε = 3 within its range)
        ("k_l", 1.5, 11.0, 0.3, "pec"),
        ("k_l", 1.5, 5.5, 0.3, 4 + 0.5j),  # the single kℓ = 3 of the dielectric map: its fade
    ],
)
def test_auto_sigma0_moves_little_between_samples_one_percent_apart(axis, lo, hi, other, eps):
    ti = np.radians(np.arange(5.0, 56.0, 5.0))
    values = lo * 1.01 ** np.arange(int(math.log(hi / lo) / math.log(1.01)) + 1)
    samples = [
        GaussianCorrelation(v / K, other / K) if axis == "k_sigma"
        else GaussianCorrelation(other / K, v / K)
        for v in values
    ]  # fmt: skip
    for jump, own in _jumps(samples, eps, ti):
        assert jump <= own + MAX_JUMP_DB


@pytest.mark.parametrize(("ks", "kl", "eps"), [(0.3, 3.0, "pec"), (0.3, 7.0, "pec"),
                                               (0.3, 3.0, 4 + 0.5j)])  # fmt: skip
def test_auto_sigma0_moves_little_between_angles_half_a_degree_apart(ks, kl, eps):
    """Across the θi fades (10°, 50°) and between the slices: the weights' share of the
    change between angles 0.5° apart is at most MAX_JUMP_DB over the lobe (the methods' own
    change aside: a convex combination with fixed weights moves no more than its parts)."""
    rough = GaussianCorrelation(ks / K, kl / K)
    ti = np.radians(np.arange(5.0, 55.01, 0.5))
    res = em.backscatter(rough, eps, wavelength=1.0, theta_i=ti, out_of_range="ignore")
    auto = _db(res.sigma0[[0, 1], [0, 1]])
    lobe = _lobe(auto)
    lobe = lobe[:, 1:] & lobe[:, :-1]  # (pol, neighbouring pair)
    assert lobe.sum() >= 10
    own = np.zeros(lobe.shape)
    for n in res.info["blend"]["weights"]:
        s = em.backscatter(rough, eps, wavelength=1.0, theta_i=ti, method=n, out_of_range="ignore")
        own = np.maximum(own, np.abs(np.diff(_db(s.sigma0[[0, 1], [0, 1]]), axis=1)))
    jump = np.abs(np.diff(auto, axis=1))
    assert np.all(jump[lobe] <= own[lobe] + MAX_JUMP_DB)


def test_the_api_cache_keys_on_theta_only_where_the_3d_layer_applies():
    """Outside the 3-D layer the roughness-only entry answers whatever the angles (the same
    scalar weights); inside, each set of angles has its entry (arrays, fresh each call)."""
    dispatch.clear_cache()
    out = GaussianCorrelation(0.3 / K, 40 / K)  # beyond the cells' kℓ
    a = dispatch.blend_weights(out, K, eps="pec", theta_i=np.radians([20.0, 30.0]))
    b = dispatch.blend_weights(out, K, eps="pec", theta_i=np.radians(35.0))
    assert a == b == dispatch.blend_weights(out, K, eps="pec")
    inside = GaussianCorrelation(0.3 / K, 3 / K)
    ti = np.radians([5.0, 30.0])
    first = dispatch.blend_weights(inside, K, eps="pec", theta_i=ti)
    again = dispatch.blend_weights(inside, K, eps="pec", theta_i=ti)
    assert first["weights"] is not again["weights"]
    for n, w in first["weights"].items():
        np.testing.assert_array_equal(w, again["weights"][n])
        assert np.shape(w) == ti.shape
    plain = dispatch.blend_weights(inside, K, eps="pec", theta_i=np.radians([5.0, 60.0]))
    assert plain == dispatch.blend_weights(inside, K, eps="pec")  # both angles outside 10°–50°
