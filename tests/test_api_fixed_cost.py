"""The API's fixed cost per call (issue 22): the shortcuts keep results bit-identical — the
API's σ⁰ and coherent reflectivity are the solver's own, ``Scattering._of`` builds the same
object as the constructor, the lazy coherent part is computed once on first read (and by
pickling), and a one-angle ``check_angle`` keeps every check of the general path."""

import math
import pickle

import numpy as np
import pytest

import emscatter as em
from emscatter import solvers
from emscatter.conventions import check_angle
from emscatter.scattering import Scattering

FREQ, EPS = 5.3e9, 15 + 2j
K = 2 * math.pi * FREQ / 299792458.0
FUNG92 = dict(complementary="fung92", fresnel="incident", first_order="model", shadowing=False)


@pytest.mark.parametrize("theta", [0.3, [0.3], np.radians(np.linspace(0.5, 70.0, 10))])
@pytest.mark.parametrize("opts", [{}, FUNG92])
def test_api_backscatter_is_the_solvers_result(theta, opts):
    rough = em.ExponentialCorrelation(1.0 / K, 0.03)
    res = em.backscatter(rough, EPS, frequency=FREQ, theta_i=theta, method="iem",
                         out_of_range="ignore", **opts)  # fmt: skip
    th = np.asarray(theta, dtype=float)
    ref = solvers.get("iem").bistatic(rough, EPS, K, th, th, np.asarray(math.pi), 0.0, **opts)
    assert np.array_equal(res.sigma0, ref.sigma0)
    assert not res.coherent_computed  # lazy until read ...
    assert np.array_equal(res.coherent, ref.coherent)  # ... then the solver's own
    assert res.coherent_computed and res.method == "iem"
    assert res.info["validity"]["valid"] in (True, False)


def _fields(coherent):
    z = np.zeros(3)
    return dict(sigma0=np.ones((2, 2, 3)), coherent=coherent, method="x", theta_i=z,
                theta_s=z, phi_s=z, phi_i=z, k=1.0, dimension=2, info={"a": 1})  # fmt: skip


def test_scattering_of_is_the_constructor():
    a, b = Scattering(**_fields(np.ones((2, 3)))), Scattering._of(**_fields(np.ones((2, 3))))
    assert type(a) is type(b) and a.__dict__.keys() == b.__dict__.keys()
    for name in a.__dict__:
        assert np.array_equal(getattr(a, name), getattr(b, name))
    with pytest.raises(TypeError, match="needs exactly the fields"):
        Scattering._of(sigma0=np.ones((2, 2, 1)))
    with pytest.raises(AttributeError):  # still frozen
        b.method = "y"


def test_lazy_coherent_once_and_through_pickle():
    calls = []

    def coherent():
        calls.append(1)
        return np.full((2, 3), 0.25)

    for build in (Scattering, Scattering._of):
        calls.clear()
        s = build(**_fields(coherent))
        assert not s.coherent_computed and calls == []
        assert np.array_equal(s.coherent, np.full((2, 3), 0.25))
        assert s.coherent is s.coherent and calls == [1]  # computed once, kept
        t = pickle.loads(pickle.dumps(build(**_fields(coherent))))  # pickling computes it
        assert t.coherent_computed and np.array_equal(t.coherent, s.coherent)


def test_one_angle_check_keeps_every_check():
    v = np.array([0.4])
    out = check_angle("theta_i", v)
    assert np.array_equal(out, v) and out is not v and out.dtype == float
    assert check_angle("theta_i", np.array(0.2)).shape == ()
    cases = [([np.nan], "must be finite"), ([2.0], "must be in"), ([-0.1], "must be in"),
             ([np.inf], "must be finite")]  # fmt: skip
    for bad, match in cases:
        with pytest.raises(ValueError, match=f"theta_i {match}"):
            check_angle("theta_i", np.array(bad))
