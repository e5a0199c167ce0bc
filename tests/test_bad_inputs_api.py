"""Bad API input (issue 23): each message names the parameter, the value and what is allowed;
the writers name the file the user asked for (never the temporary file beside it) and leave
nothing behind; build_table warns once per cause at the caller's line.

``/proc`` and ``/sys`` stand for folders that take no new file even for root; those cases need
Linux. The BRDF tables here are small (a few θ nodes): the checks are about messages.
"""

import math
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import emscatter as em
from emscatter import io, materials
from emscatter.brdf import build_table
from emscatter.solvers.select import ValidityError, ValidityWarning

LINUX = sys.platform.startswith("linux") and Path("/proc/self").exists()
needs_linux = pytest.mark.skipif(not LINUX, reason="uses /proc and /sys as unwritable folders")
ROUGH = em.GaussianCorrelation(sigma=0.01, length=0.5)
GOLD = em.GaussianCorrelation(0.15e-6, 1e-6)  # the README's BRDF surface


def _message(exc_type, fn, *args, **kw) -> str:
    with pytest.raises(exc_type) as info:
        fn(*args, **kw)
    return str(info.value)


def _has(msg: str, *fragments: str) -> None:
    for frag in fragments:
        assert frag in msg, (frag, msg)


# ----------------------------------------------------------------------------- eps as a string
@pytest.mark.parametrize(
    "text, number",
    [("17+2j", "(17+2j)"), ("17+2i", "(17+2j)"), (" (4+0.5j) ", "(4+0.5j)"), ("2.25", "2.25")],
)
def test_a_number_in_quotes_says_pass_a_complex_number(text, number):
    msg = _message(TypeError, em.backscatter, ROUGH, text, frequency=1e9, theta_i=0.3)
    _has(msg, f"eps={text!r}", "is a string", "pass a complex number", f"eps={number}")
    assert "concrete" in msg and "wet_ground" not in msg  # not the 90 names


@pytest.mark.parametrize(
    "name, close", [("concrte", "'concrete'"), ("glas", "'glass'"), ("PEC_", "'pec'")]
)
def test_an_unknown_material_gets_close_names_not_all_of_them(name, close):
    msg = _message(ValueError, materials.as_material, name)
    _has(msg, f"unknown material {name!r}", f"did you mean {close}", "ITU-R P.2040", "'pec'")
    assert len(msg) < 400 and "medium_dry_ground" not in msg, msg


def test_an_unknown_material_without_close_names_says_what_is_allowed():
    msg = _message(
        ValueError, em.bistatic, ROUGH, "gold", wavelength=1.0, theta_i=0.2, theta_s=0.2, phi_s=0.0
    )
    _has(msg, "unknown material 'gold'", "complex number", "available_itu()", "'Au'")
    assert "did you mean" not in msg


# ----------------------------------------------------------------------------- frequencies
@pytest.mark.parametrize("f", [28.0, 5.4, 3.5e3])
def test_itu_material_at_hz_hints_ghz(f):
    msg = _message(materials.OutOfBandError, materials.itu("concrete").eps, frequency=f)
    _has(msg, "'concrete'", f"got {materials.core.format_frequency(f)}")
    _has(msg, f"did you mean {f:g} GHz", "1 GHz–100 GHz", "extrapolate=True")


def test_a_band_error_above_1_mhz_has_no_ghz_hint():
    msg = _message(materials.OutOfBandError, materials.itu("concrete").eps, frequency=500e6)
    _has(msg, "got 500 MHz", "1 GHz–100 GHz")
    assert "did you mean" not in msg


def test_mitsuba_metal_at_hz_hints_ghz():
    try:
        gold = materials.metal("Au")
    except (ModuleNotFoundError, FileNotFoundError):
        pytest.skip("Mitsuba's ior data are not installed")
    msg = _message(materials.OutOfBandError, gold.eps, frequency=28)
    _has(msg, "'Au'", "got 28 Hz", "did you mean 28 GHz", "nm")


def test_the_api_at_28_hz_warns_with_the_ghz_hint():
    with pytest.warns(em.conventions.PlausibilityWarning, match="did you mean 28 GHz"):
        em.backscatter(ROUGH, 4.0, frequency=28.0, theta_i=0.3, method="spm")


# ----------------------------------------------------------------------------- Drude
@pytest.mark.parametrize(
    "args, name, shown, exc",
    [
        ((4e7, -1e14), "collision_rate", "-1e+14", ValueError),
        ((4e7, 0), "collision_rate", "got 0", ValueError),
        ((4e7, 0.0), "collision_rate", "got 0", ValueError),
        ((-4e7, 1e14), "conductivity", "-4e+07", ValueError),
        ((0, 1e14), "conductivity", "got 0", ValueError),
        ((math.nan, 1e14), "conductivity", "nan", TypeError),
        ((4e7, math.inf), "collision_rate", "inf", TypeError),
        (("4e7", 1e14), "conductivity", "'4e7'", TypeError),
        ((4e7, True), "collision_rate", "True", TypeError),
    ],
)
def test_drude_from_conductivity_names_the_parameter(args, name, shown, exc):
    msg = _message(exc, materials.Drude.from_conductivity, *args)
    _has(msg, name, shown, "> 0")
    assert "math domain" not in msg
    other = {"conductivity": "collision_rate", "collision_rate": "conductivity"}[name]
    assert "plasma_angular_frequency" not in msg and other not in msg


def test_drude_from_conductivity_takes_numpy_numbers():
    d = materials.Drude.from_conductivity(np.float64(4e7), np.int64(10**14))
    # ωp² = σ0 γ / ε0 (Ashcroft & Mermin 1976, ch. 1): the DC limit gives σ0 back.
    eps0 = 8.8541878128e-12
    assert d.plasma_angular_frequency**2 * eps0 / d.collision_rate == pytest.approx(4e7, rel=1e-9)


# ----------------------------------------------------------------------------- writers
def test_write_csv_under_a_file_names_the_target(tmp_path):
    (tmp_path / "afile").write_text("x")
    target = tmp_path / "afile" / "x.csv"
    with pytest.raises(io.OutputPathError) as info:
        io.write_csv(target, ["a"], [np.array([1.0])])
    _has(str(info.value), str(target), "is a file, not a folder", "choose another folder")
    assert isinstance(info.value, ValueError) and isinstance(info.value, OSError)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_write_json_onto_a_folder_names_it(tmp_path):
    msg = _message(io.OutputPathError, io.write_json, tmp_path, {"a": 1})
    _has(msg, str(tmp_path), "it is a folder", "give a file name inside it")


@needs_linux
@pytest.mark.parametrize(
    "write, target",
    [
        (lambda p: io.write_json(p, {"a": 1}), "/proc/emscatter-x.json"),
        (lambda p: io.write_csv(p, ["a"], [[1.0]]), "/proc/nonexistent/x.csv"),
        (lambda p: io.write_json(p, {}), "/sys/emscatter-x.json"),
    ],
)
def test_unwritable_folder_names_the_target_not_the_temporary(write, target):
    with pytest.raises(io.OutputPathError) as info:
        write(target)
    msg = str(info.value)
    _has(msg, repr(target), "does not take new files", "choose another folder")
    assert f".{Path(target).name}." not in msg  # the temporary file's name


@needs_linux
def test_save_figure_into_an_unwritable_folder_names_the_target():
    import matplotlib.pyplot as plt

    fig = plt.figure()
    try:
        msg = _message(io.OutputPathError, io.save_figure, fig, "/sys/emscatter-x.png")
    finally:
        plt.close(fig)
    _has(msg, "'/sys/emscatter-x.png'", "does not take new files")
    assert ".emscatter-x.png." not in msg


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root writes into 0o555 folders"
)
def test_read_only_folder_names_the_target(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        msg = _message(io.OutputPathError, io.write_json, ro / "x.json", {})
    finally:
        ro.chmod(0o755)
    _has(msg, str(ro / "x.json"), "not writable")
    assert ".x.json." not in msg


@pytest.mark.parametrize(
    "path, suffixes, fragment",
    [
        ("x.txt", (".csv",), "unknown extension '.txt'; use one of .csv"),
        ("x", (".json",), "unknown extension '(none)'"),
        ("", (), "the path is empty"),
    ],
)
def test_check_output_names_the_path_and_what_is_allowed(path, suffixes, fragment, tmp_path):
    msg = _message(io.OutputPathError, io.check_output, path, suffixes)
    _has(msg, f"cannot write {path!r}", fragment)


def test_output_problem_leaves_nothing_behind(tmp_path):
    assert io.output_problem(tmp_path / "a" / "b" / "x.csv", (".csv",)) is None
    assert io.output_problem(tmp_path / "out", folder=True) is None
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- BRDF tables
@pytest.fixture(scope="module")
def small_table():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        return build_table(GOLD, 2.25, [550e-9], method="go", resolution=(6, 8))


@pytest.mark.parametrize(
    "kwargs, name, shown",
    [
        ({"theta_i": math.nan}, "theta_i", "nan"),
        ({"theta_i": [0.1, math.inf]}, "theta_i", "inf"),
        ({"theta_i": 0.2, "phi_i": math.nan}, "phi_i", "nan"),
    ],
)
def test_coherent_reflectance_rejects_non_finite_angles(small_table, kwargs, name, shown):
    msg = _message(ValueError, small_table.coherent_reflectance, **kwargs)
    _has(msg, name, shown, "must be finite angles [rad]")


def test_evaluate_angles_names_the_non_finite_angle(small_table):
    msg = _message(ValueError, small_table.evaluate_angles, 0.1, 0.0, math.nan, 0.0)
    _has(msg, "theta_o", "nan", "must be finite angles [rad]", "1 of 1 values")


@pytest.mark.parametrize(
    "policy, fragments",
    [
        ("nan", ["out_of_range='nan'", "'warn'", "'raise'", "'ignore'"]),
        ("maybe", ["out_of_range", "'maybe'", "'warn'", "'raise'", "'ignore'"]),
    ],
)
def test_build_table_policies_name_the_ones_it_takes(policy, fragments):
    msg = _message(ValueError, build_table, GOLD, "Au", [550e-9], out_of_range=policy)
    _has(msg, *fragments)


def test_build_table_raise_names_the_wavelength():
    msg = _message(
        ValidityError,
        build_table,
        GOLD,
        2.25,
        [650e-9],
        method="go",
        resolution=(6, 8),
        out_of_range="raise",
    )
    _has(msg, "λ = 650 nm", "method 'go'", "stationary_phase", "out_of_range='warn'")


def test_build_table_warns_once_per_cause_at_the_callers_line():
    """The README's GO table (Au, 450/550/650 nm) on a small grid: one warning per failed check
    (not one per solver call), at this file's line, naming λ and θ, advising only policies that
    build_table takes (before: 4 to ~130 warnings from brdf/build.py advising 'nan')."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        line = sys._getframe().f_lineno + 1
        t = build_table(GOLD, 2.25, [450e-9, 550e-9, 650e-9], method="go", resolution=(12, 16))
    valid = [w for w in caught if issubclass(w.category, ValidityWarning)]
    texts = [str(w.message) for w in valid]
    checks = [m.split("validity (", 1)[1].split(")", 1)[0] for m in texts]
    assert len(checks) == len(set(checks)) >= 2, texts  # once per cause
    assert "stationary_phase_angle" in checks
    for w in valid:
        assert w.filename == __file__ and w.lineno == line, (w.filename, w.lineno)
        _has(str(w.message), "method 'go'", "λ = ", "nm", "out_of_range='raise'", "'ignore'")
        assert "'nan'" not in str(w.message)
    angle = texts[checks.index("stationary_phase_angle")]
    _has(angle, "λ = 450 nm for θi ∈", "λ = 550 nm for θi ∈", "λ = 650 nm for θi ∈", "θ nodes")
    # the metadata keeps what was warned about
    assert any("stationary_phase_angle" in r for r in t.metadata["per_wavelength"][0]["reasons"])


def test_build_table_ignore_is_silent_but_records():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t = build_table(GOLD, 2.25, [650e-9], method="go", resolution=(6, 8), out_of_range="ignore")
    assert not [w for w in caught if issubclass(w.category, ValidityWarning)]
    assert t.metadata["per_wavelength"][0]["reasons"]
    assert not t.metadata["per_wavelength"][0]["valid"]


def test_output_path_error_survives_pickling():
    """Raised in a worker process, it must reach the parent with its message intact."""
    import pickle

    err = pickle.loads(pickle.dumps(io.OutputPathError("/x/y.csv", "it is a folder")))
    assert str(err) == "cannot write '/x/y.csv': it is a folder" and isinstance(err, ValueError)
