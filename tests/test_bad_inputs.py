"""Bad input, read by a person: every case names the parameter, the value and what is allowed,
in plain numbers (no numpy reprs), degrees where degrees were given — and never a traceback.

API cases call the public functions; CLI cases run ``emscatter.cli.main`` in-process (it returns
the exit status) and a few through a real subprocess.
"""

import math
import re
import subprocess
import sys

import numpy as np
import pytest

import emscatter as em
from emscatter.cli import main
from emscatter.conventions import ConventionError, PlausibilityWarning
from emscatter.solvers.select import ValidityError

ROUGH = em.GaussianCorrelation(sigma=0.01, length=0.5)
NUMPY_REPR = re.compile(r"np\.(float|int|complex|bool)|array\(")

# ----------------------------------------------------------------------------- API
BISTATIC = dict(surface=ROUGH, eps=4.0, wavelength=1.0, theta_i=0.2, theta_s=0.3, phi_s=0.0)


def _bistatic(**override):
    kw = {**BISTATIC, **override}
    return em.bistatic(kw.pop("surface"), kw.pop("eps"), **kw)


def _emissivity(**override):
    kw = dict(surface=ROUGH, eps=4.0, wavelength=1.0, theta_i=0.2, method="spm")
    kw.update(override)
    return em.emissivity(kw.pop("surface"), kw.pop("eps"), **kw)


def _result():
    return em.bistatic(ROUGH, 4.0, wavelength=1.0, theta_i=0.2, theta_s=0.3, phi_s=0.0)


API = [
    # (id, call, exception, [fragments that must all appear in the message])
    (
        "theta_i<0",
        lambda: _bistatic(theta_i=-0.1),
        ValueError,
        ["theta_i must be in [0, 1.5708] rad ([0°, 90°])", "got -0.1 rad (-5.73°)"],
    ),
    (
        "theta_i>90",
        lambda: _bistatic(theta_i=math.radians(91)),
        ValueError,
        ["theta_i must be in", "(91°)"],
    ),
    (
        "theta_i nan",
        lambda: _bistatic(theta_i=math.nan),
        ValueError,
        ["theta_i must be finite, got nan"],
    ),
    ("theta_i bool", lambda: _bistatic(theta_i=True), TypeError, ["theta_i", "booleans"]),
    ("theta_i text", lambda: _bistatic(theta_i="45"), TypeError, ["theta_i must be a number"]),
    ("theta_i complex", lambda: _bistatic(theta_i=0.1 + 1j), TypeError, ["theta_i must be real"]),
    (
        "theta_s>90",
        lambda: _bistatic(theta_s=math.radians(91)),
        ValueError,
        ["theta_s must be in", "91°"],
    ),
    (
        "theta_s nan in array",
        lambda: _bistatic(theta_s=np.array([0.1, np.nan])),
        ValueError,
        ["theta_s must be finite, got nan in array of shape (2,)"],
    ),
    ("phi_s inf", lambda: _bistatic(phi_s=math.inf), ValueError, ["phi_s must be finite, got inf"]),
    ("phi_i nan", lambda: _bistatic(phi_i=math.nan), ValueError, ["phi_i must be finite, got nan"]),
    (
        "eps Im<0",
        lambda: _bistatic(eps=17 - 2j),
        ConventionError,
        ["eps = (17-2j) has Im(eps) < 0", "exp(-i omega t)", "numpy.conj"],
    ),
    (
        "eps unknown name",
        lambda: _bistatic(eps="metal-ish"),
        ValueError,
        ["unknown material 'metal-ish'", "'pec'", "concrete"],
    ),
    (
        "eps True",
        lambda: _bistatic(eps=True),
        TypeError,
        ["eps must be a complex permittivity", "True"],
    ),
    ("eps 0", lambda: _bistatic(eps=0), ValueError, ["eps must be nonzero, got 0"]),
    ("eps nan", lambda: _bistatic(eps=complex(math.nan, 0)), ValueError, ["eps must be finite"]),
    ("eps None", lambda: _bistatic(eps=None), TypeError, ["eps must be", "None"]),
    (
        "eps object array",
        lambda: _bistatic(eps=np.array([1, None], dtype=object)),
        TypeError,
        ["eps must be a number or array of numbers"],
    ),
    (
        "no frequency",
        lambda: _bistatic(wavelength=None),
        ValueError,
        ["give exactly one of frequency [Hz] or wavelength [m]", "frequency=None, wavelength=None"],
    ),
    (
        "both frequency and wavelength",
        lambda: _bistatic(frequency=1e9),
        ValueError,
        ["give exactly one of frequency [Hz] or wavelength [m]", "frequency=1e+09, wavelength=1"],
    ),
    (
        "wavelength<0",
        lambda: _bistatic(wavelength=-1.0),
        ValueError,
        ["wavelength must be > 0 [m], got -1"],
    ),
    (
        "wavelength 0",
        lambda: _bistatic(wavelength=0.0),
        ValueError,
        ["wavelength must be > 0 [m], got 0"],
    ),
    (
        "frequency 0",
        lambda: _bistatic(wavelength=None, frequency=0),
        ValueError,
        ["frequency must be > 0 [Hz], got 0"],
    ),
    (
        "frequency<0",
        lambda: _bistatic(wavelength=None, frequency=-1e9),
        ValueError,
        ["frequency must be > 0 [Hz], got -1e+09"],
    ),
    (
        "frequency nan",
        lambda: _bistatic(wavelength=None, frequency=math.nan),
        ValueError,
        ["frequency must be finite, got nan"],
    ),
    (
        "frequency bool",
        lambda: _bistatic(wavelength=None, frequency=True),
        TypeError,
        ["frequency must be a number [Hz]", "True"],
    ),
    (
        "frequency text",
        lambda: _bistatic(wavelength=None, frequency="1e9"),
        TypeError,
        ["frequency must be a number or array of numbers"],
    ),
    (
        "frequency array with 0",
        lambda: _bistatic(wavelength=None, frequency=np.array([1e9, 0])),
        ValueError,
        ["frequency must be > 0 [Hz], got 0"],
    ),
    (
        "method unknown",
        lambda: _bistatic(method="ipm"),
        ValueError,
        ["method must be one of", "'auto'", "'spm'", "got 'ipm'"],
    ),
    (
        "method not text",
        lambda: _bistatic(method=3),
        ValueError,
        ["method must be 'auto' or one of", "got 3"],
    ),
    (
        "out_of_range",
        lambda: _bistatic(out_of_range="maybe"),
        ValueError,
        ["out_of_range must be one of", "'warn'", "'nan'", "got 'maybe'"],
    ),
    (
        "angles do not broadcast",
        lambda: _bistatic(theta_i=np.zeros(3), theta_s=np.zeros(4)),
        ValueError,
        ["do not broadcast", "theta_i(3,)", "theta_s(4,)"],
    ),
    (
        "band does not broadcast",
        lambda: _bistatic(wavelength=None, frequency=np.array([1e9, 2e9]), theta_i=np.zeros(3)),
        ValueError,
        ["do not broadcast", "theta_i(3,)", "frequency(2,)"],
    ),
    (
        "fBm surface",
        lambda: _bistatic(surface=em.FractionalBrownian(0.5)),
        TypeError,
        ["surface must be a roughness description", "FractionalBrownian"],
    ),
    (
        "surface text",
        lambda: _bistatic(surface="gaussian"),
        TypeError,
        ["surface must be a roughness description", "got str"],
    ),
    (
        "unknown solver option",
        lambda: _bistatic(method="go", foo=1),
        ValueError,
        ["option foo=1 does not apply: method 'go', which takes", "'shadowing'"],
    ),
    (
        "auto option that does not apply",
        lambda: _bistatic(shadowing=True),
        ValueError,
        ["shadowing", "picked 'spm'"],
    ),
    ("tol 0", lambda: _emissivity(tol=0), ValueError, ["tol must be a number in (0, 1)", "got 0"]),
    (
        "tol 2",
        lambda: _emissivity(tol=2.0),
        ValueError,
        ["tol must be a number in (0, 1)", "got 2.0"],
    ),
    (
        "tol bool",
        lambda: _emissivity(tol=True),
        ValueError,
        ["tol must be a number in (0, 1)", "True"],
    ),
    (
        "tol nan",
        lambda: _emissivity(tol=math.nan),
        ValueError,
        ["tol must be a number in (0, 1)", "nan"],
    ),
    (
        "emissivity theta_i",
        lambda: _emissivity(theta_i=2.0),
        ValueError,
        ["theta_i must be in", "(114.6°)"],
    ),
    ("emissivity phi_i", lambda: _emissivity(phi_i=np.inf), ValueError, ["phi_i must be finite"]),
    (
        "pol pair",
        lambda: _result().pol("hx"),
        ValueError,
        ["pol must be one of hh, hv, vh, vv", "got 'hx'"],
    ),
    (
        "coherent_pol x",
        lambda: _result().coherent_pol("x"),
        ValueError,
        ["pol must be 'h' (or 'TE') or 'v' (or 'TM'), case-insensitive, got 'x'"],
    ),
    ("coherent_pol 3", lambda: _result().coherent_pol(3), ValueError, ["pol must be 'h'", "got 3"]),
    (
        "emissivity pol",
        lambda: _emissivity().pol("hh"),
        ValueError,
        ["pol must be 'h'", "got 'hh'"],
    ),
    (
        "material out of band",
        lambda: _emissivity(eps="Au", method="auto", wavelength=0.01),
        ValueError,
        ["material 'Au'", "298.8–885.6 nm", "got 29.9792 GHz (λ = 0.01 m)"],
    ),
    (
        "sigma<0",
        lambda: em.GaussianCorrelation(-1.0, 1.0),
        ValueError,
        ["sigma must be > 0 [m], got -1"],
    ),
    (
        "length 0",
        lambda: em.ExponentialCorrelation(0.1, 0.0),
        ValueError,
        ["length must be > 0 [m], got 0"],
    ),
    (
        "sigma text",
        lambda: em.GaussianCorrelation("a", 1.0),
        TypeError,
        ["sigma must be a real number", "'a'"],
    ),
    (
        "raise policy",
        lambda: _emissivity(
            surface=em.GaussianCorrelation(0.2 / (2 * math.pi), 1 / (2 * math.pi)),
            eps="pec",
            theta_i=np.radians([10.0, 89.0]),
            out_of_range="raise",
        ),
        ValidityError,
        ["method 'spm' at θi = 89°", "energy not conserved"],
    ),
]


@pytest.mark.parametrize("call, exc, fragments", [c[1:] for c in API], ids=[c[0] for c in API])
def test_api_bad_input_is_named(call, exc, fragments):
    with pytest.raises(exc) as info:
        call()
    msg = str(info.value)
    for frag in fragments:
        assert frag in msg, (frag, msg)
    assert not NUMPY_REPR.search(msg), msg


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        (dict(frequency=5.4), "did you mean 5.4 GHz = 5.4e+09 Hz?"),
        (dict(wavelength=5000.0), "wavelength = 5000 m is above 1 km; did you mean GHz?"),
    ],
    ids=["frequency 5.4 (GHz meant)", "wavelength 5 km"],
)
def test_implausible_units_warn_with_a_hint(kwargs, fragment):
    with pytest.warns(PlausibilityWarning, match=re.escape(fragment)):
        em.backscatter(
            em.GaussianCorrelation(0.01, 0.5),
            4.0,
            theta_i=0.2,
            method="spm",
            out_of_range="ignore",
            **kwargs,
        )


def test_polarization_names_are_case_insensitive():
    r = _result()
    np.testing.assert_array_equal(r.coherent_pol("H"), r.coherent_pol("te"))
    np.testing.assert_array_equal(r.coherent_pol("TM"), r.coherent_pol("v"))
    np.testing.assert_array_equal(r.pol("HV"), r.hv)


# ----------------------------------------------------------------------------- CLI
CLI = [
    # (argv, fragments of the one-line error)
    (["curves", "--sigma", "-1"], ["argument --sigma: must be > 0 m, got -1"]),
    (["curves", "--sigma", "0"], ["argument --sigma: must be > 0 m, got 0"]),
    (["curves", "--sigma", "abc"], ["argument --sigma: expected a number, got 'abc'"]),
    (["curves", "--length", "0"], ["argument --length: must be > 0 m"]),
    (["curves", "--length-y", "-2"], ["argument --length-y: must be > 0 m, got -2"]),
    (["curves", "--frequency", "0"], ["argument --frequency: must be in [1e+06, 3e+16] Hz, got 0"]),
    (
        ["curves", "--frequency", "-1e9"],
        ["argument --frequency: must be in [1e+06, 3e+16] Hz, got -1e9"],
    ),
    (["curves", "--frequency", "5.4"], ["got 5.4; did you mean 5.4 GHz = 5.4e+09 Hz?"]),
    (
        ["curves", "--frequency", "nan"],
        ["argument --frequency: must be a finite number, got 'nan'"],
    ),
    (["curves", "--wavelength", "0"], ["argument --wavelength: must be in [1e-08, 1000] m, got 0"]),
    (
        ["curves", "--wavelength", "-1"],
        ["argument --wavelength: must be in [1e-08, 1000] m, got -1"],
    ),
    (["curves", "--wavelength", "5000"], ["got 5000; did you mean GHz?", "--frequency"]),
    (
        ["curves", "--frequency", "1e9", "--wavelength", "1"],
        ["argument --wavelength: not allowed with argument --frequency"],
    ),
    (
        ["curves", "--eps", "seventeen"],
        ["argument --eps: expected a complex permittivity like 17+2j"],
    ),
    (
        ["curves", "--eps", "17-2j"],
        ["argument --eps: permittivity '17-2j' has Im < 0", "give 17+2j"],
    ),
    (["curves", "--eps", "0"], ["argument --eps: permittivity must be nonzero"]),
    (["curves", "--eps", "gold"], ["argument --eps:", "unknown material 'gold'", "'Au'"]),
    (["curves", "--eps", "Au", "--wavelength", "1"], ["material 'Au'", "298.8–885.6 nm"]),
    (
        ["curves", "--theta-i-deg", "10:40"],
        [
            "argument --theta-i-deg: must be 'a', 'a,b,c' or 'start:stop:count' in degrees, "
            "got '10:40'"
        ],
    ),
    (["curves", "--theta-i-deg", "10:40:0"], ["range '10:40:0': the count must be ≥ 1, got 0"]),
    (
        ["curves", "--theta-i-deg", "95"],
        ["argument --theta-i-deg: must be in [0, 90] degrees, got 95"],
    ),
    (
        ["curves", "--theta-i-deg", "-5"],
        ["argument --theta-i-deg: must be in [0, 90] degrees, got -5"],
    ),
    (["curves", "--theta-i-deg", "ten"], ["argument --theta-i-deg: must be 'a', 'a,b,c'"]),
    (
        ["curves", "--theta-s-deg", "0:100:5"],
        ["--theta-s-deg: must be in [0, 90] degrees, got 100"],
    ),
    (["curves", "--phi-s-deg", "400"], ["argument --phi-s-deg: must be in [-360, 360], got 400"]),
    (
        ["curves", "--quantity", "emissivity", "--theta-s-deg", "3"],
        ["--theta-s-deg applies to --quantity bistatic only"],
    ),
    (
        ["curves", "--quantity", "backscatter", "--phi-s-deg", "3"],
        ["--phi-s-deg applies to --quantity bistatic only"],
    ),
    (["curves", "--tol", "1e-3"], ["--tol applies to --quantity emissivity only"]),
    (
        ["curves", "--quantity", "emissivity", "--tol", "0"],
        ["argument --tol: must be in (0, 1), got 0"],
    ),
    (["curves", "--hurst", "0.3"], ["--hurst applies to --kind power-law only"]),
    (
        ["curves", "--kind", "power-law", "--hurst", "1.5"],
        ["argument --hurst: must be in (0, 1), got 1.5"],
    ),
    (["curves", "--profile", "--length-y", "2"], ["--length-y applies to 2-D surfaces only"]),
    (
        ["curves", "--method", "ipm"],
        ["argument --method: invalid choice: 'ipm'", "'auto'", "'spm'"],
    ),
    (["curves", "--out-of-range", "maybe"], ["argument --out-of-range: invalid choice: 'maybe'"]),
    (["curves", "--quantity", "brdf"], ["argument --quantity: invalid choice: 'brdf'"]),
    (["curves", "--kind", "fractal"], ["argument --kind: invalid choice: 'fractal'"]),
    (["curves", "--frequency"], ["argument --frequency: expected one argument"]),
    (["curves", "--sigm", "0.1"], ["unrecognized arguments: --sigm"]),
    (
        ["curves", "--method", "go", "--out-of-range", "raise"],
        ["method 'go' used outside its validity"],
    ),
    (["surface", "--size", "0"], ["argument --size: must be in [8, 16384], got 0"]),
    (["surface", "--size", "3.5"], ["argument --size: expected an integer, got '3.5'"]),
    (["surface", "--spacing", "0"], ["argument --spacing: must be > 0 m, got 0"]),
    (["surface", "--hurst", "1.5"], ["argument --hurst: must be in (0, 1), got 1.5"]),
    (["surface", "--seed", "-1"], ["argument --seed: must be ≥ 0, got -1"]),
    (
        ["surface", "--kind", "gaussian", "--sigma", "-3"],
        ["argument --sigma: must be > 0 m, got -3"],
    ),
    (["nosuchcommand"], ["invalid choice: 'nosuchcommand'", "'curves'"]),
    ([], ["the following arguments are required: COMMAND"]),
]


@pytest.mark.parametrize("argv, fragments", CLI, ids=[" ".join(c[0]) or "(none)" for c in CLI])
def test_cli_bad_input_is_one_line_naming_the_option(argv, fragments, capsys):
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2, err
    for frag in fragments:
        assert frag in err, (frag, err)
    assert "Traceback" not in err and not NUMPY_REPR.search(err)
    errors = [line for line in err.splitlines() if ": error: " in line]
    assert len(errors) == 1, err


def _path_cases(tmp_path):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    folder = tmp_path / "folder"
    folder.mkdir()
    return [
        (["curves", "--csv", str(a_file / "sub" / "x.csv")], ["is a file, not a folder"]),
        (["curves", "--png", str(tmp_path / "x.txt")], ["unknown extension '.txt'", ".png"]),
        (["curves", "--png", str(folder)], ["it is a folder; give a file name inside it"]),
        (["curves", "--json", str(a_file / "x.json")], ["is a file, not a folder"]),
        (["demo", "--out", str(a_file)], ["it is an existing file, not a folder"]),
        (["validate", "--out", str(a_file)], ["it is an existing file, not a folder"]),
        (["surface", "--png", str(a_file / "s.png")], ["is a file, not a folder"]),
        (["curves", "--from", str(tmp_path / "missing.json")], ["no such file"]),
        (["curves", "--from", str(a_file)], ["not written by 'emscatter curves'"]),
    ]


def test_cli_output_and_input_path_problems_are_one_line(tmp_path, capsys):
    for argv, fragments in _path_cases(tmp_path):
        rc = main(argv)
        err = capsys.readouterr().err
        assert rc == 2, (argv, err)
        assert str(tmp_path) in err, (argv, err)
        for frag in fragments:
            assert frag in err, (argv, frag, err)
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file", "folder"]  # nothing written


def test_cli_from_rejects_other_inputs(tmp_path, capsys):
    out = tmp_path / "e.json"
    assert (
        main(["curves", "--quantity", "backscatter", "--theta-i-deg", "20", "--json", str(out)])
        == 0
    )
    capsys.readouterr()
    assert main(["curves", "--from", str(out), "--sigma", "0.1"]) == 2
    assert "only --png, --csv, --json may be given with it, got --sigma" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["curves", "--frequency", "-1e9"], "argument --frequency: must be in"),
        (["curves", "--theta-i-deg", "10:40"], "'start:stop:count'"),
        (["nosuchcommand"], "invalid choice"),
    ],
)
def test_cli_errors_through_a_real_process(argv, fragment):
    out = subprocess.run(
        [sys.executable, "-m", "emscatter", *argv], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 2 and fragment in out.stderr
    assert "Traceback" not in out.stderr and len(out.stderr.strip().splitlines()) == 1
