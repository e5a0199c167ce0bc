"""Branch-free ``exp``, ``sin``/``cos`` and ``erfcx`` for compiled loops.

numba lowers ``math.exp``/``math.sin`` to scalar libm calls, and one scalar call in a loop body
stops LLVM from vectorizing the whole loop (numpy's own float64 ``sin``/``cos`` are scalar too:
~55 M/s here, the bottleneck of the numpy path). These are written in plain arithmetic and
selects so the loops they are inlined into compile to AVX2/AVX-512 code.

Accuracy (tested against numpy/scipy in tests/test_kernels.py, ≤ 4 ulp on the ranges used):

* ``exp(x)``: Cody–Waite reduction ``x = n ln2 + r`` (``ln2`` split in a 32-bit head and a
  tail, so ``n·ln2_hi`` is exact), Taylor series of ``e^r`` to ``r¹³`` (``|r| ≤ ln2/2``: the
  truncation is < 1e-17 relative), ``2ⁿ`` by placing the exponent bits; 0 below −745.2,
  inf above 709.78.
* ``sin``/``cos``: reduction by ``π/2`` in three 33-bit pieces (``n·p_k`` exact for
  ``|n| < 2²⁰``, i.e. ``|x| < 1.6e6`` — callers fall back to numpy beyond ``MAX_TRIG_ARG``),
  Taylor series to ``r¹⁷`` / ``r¹⁸`` on ``|r| ≤ π/4`` (truncation < 1e-19); ``cos`` near 1
  adds back the rounding of ``1 − r²/2``, so ``sin θ`` near ``π/2`` matches libm's to the last
  bit in > 99.9 % of cases (``cos θ = √(1 − sin²θ)`` downstream is then the same too).
* ``erfcx(a) = e^{a²} erfc(a)`` on ``[0, ERFCX_HI]``: a Chebyshev series (degree
  ``ERFCX_DEGREE``) of ``(1 + 2a) erfcx(a)`` in ``t = (a − 2)/(a + 2)`` fitted to scipy's
  ``erfcx`` once at import; its maximum relative error is measured then
  (``ERFCX_MAX_REL_ERR``, ~1e-15).
"""

from __future__ import annotations

import math
from decimal import Decimal, getcontext

import numpy as np

from ._runtime import inline

# ----------------------------------------------------------------------------- constants
getcontext().prec = 60
_PI = Decimal("3.14159265358979323846264338327950288419716939937510582097494459")


def _split(value: Decimal, bits: int, parts: int) -> list[float]:
    """``value`` as a sum of ``parts`` doubles, each but the last with ``bits`` leading bits."""
    out, rest = [], value
    for i in range(parts):
        v = float(rest)
        if i < parts - 1:
            m, e = math.frexp(v)
            v = math.ldexp(math.floor(math.ldexp(m, bits)), e - bits)
        out.append(v)
        rest = rest - Decimal(v)
    return out


PIO2_1, PIO2_2, PIO2_3 = _split(_PI / 2, 33, 3)
INV_PIO2 = float(2 / _PI)
LN2_HI, LN2_LO = _split(Decimal(2).ln(), 32, 2)
INV_LN2 = float(1 / Decimal(2).ln())
MAX_TRIG_ARG = 1.0e6  # |x| up to which the π/2 reduction is exact (|n| < 2^20)
EXP_LO, EXP_HI = -745.2, 709.78


# Taylor coefficients 1/j! (exp), (−1)^j/(2j+1)! (sin), (−1)^j/(2j)! (cos)
_E = [1.0 / math.factorial(j) for j in range(14)]
_S = [(-1) ** j / math.factorial(2 * j + 1) for j in range(9)]
_C = [(-1) ** j / math.factorial(2 * j) for j in range(10)]
E0, E1, E2, E3, E4, E5, E6, E7, E8, E9, E10, E11, E12, E13 = _E
S1, S3, S5, S7, S9, S11, S13, S15, S17 = _S
C0, C2, C4, C6, C8, C10, C12, C14, C16, C18 = _C


# ----------------------------------------------------------------------------- exp
@inline
def _pow2(m):
    """``2^m`` for integer ``−1022 ≤ m ≤ 1023``, by placing the biased exponent."""
    return np.int64((m + 1023) << 52).view(np.float64)


@inline
def vexp(x):
    """``e^x`` for any float ``x``."""
    xc = min(max(x, EXP_LO), EXP_HI)
    n = math.floor(xc * INV_LN2 + 0.5)
    r = (xc - n * LN2_HI) - n * LN2_LO
    # Estrin's scheme (short dependency chains; the loops using it are latency-bound)
    r2 = r * r
    r4 = r2 * r2
    lo = ((E0 + E1 * r) + (E2 + E3 * r) * r2) + ((E4 + E5 * r) + (E6 + E7 * r) * r2) * r4
    hi = ((E8 + E9 * r) + (E10 + E11 * r) * r2) + (E12 + E13 * r) * r4
    p = lo + hi * (r4 * r4)
    ni = int(n)
    # multiplying by 2^m is exact in the normal range: scale in two steps so n = 1024 does
    # not overflow and the subnormal range (n < −1021) rounds once
    low = ni < -1021
    m = ni + 54 if low else ni - 1
    scale = 5.551115123125783e-17 if low else 2.0  # 2^-54 or 2
    val = (p * _pow2(m)) * scale
    if x < EXP_LO:
        val = 0.0
    if x > EXP_HI:
        val = math.inf
    return val


# ----------------------------------------------------------------------------- sin / cos
@inline
def _sin_poly(r):
    z = r * r
    p = S17
    p = p * z + S15
    p = p * z + S13
    p = p * z + S11
    p = p * z + S9
    p = p * z + S7
    p = p * z + S5
    p = p * z + S3
    return r + r * z * p


@inline
def _cos_poly(r):
    z = r * r
    p = C18
    p = p * z + C16
    p = p * z + C14
    p = p * z + C12
    p = p * z + C10
    p = p * z + C8
    p = p * z + C6
    p = p * z + C4
    # 1 − z/2 rounded once, its rounding error added back (cos near 1 to < 1 ulp)
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + z * z * p)


@inline
def _reduce(x):
    n = math.floor(x * INV_PIO2 + 0.5)
    r = ((x - n * PIO2_1) - n * PIO2_2) - n * PIO2_3
    q = int(n) & 3
    return r, q


@inline
def vsin(x):
    """``sin x`` for ``|x| ≤ MAX_TRIG_ARG``."""
    r, q = _reduce(x)
    s = _sin_poly(r)
    c = _cos_poly(r)
    v = s if (q & 1) == 0 else c
    return -v if q >= 2 else v


@inline
def vsin_q1(x):
    """``sin x`` for ``0 ≤ x ≤ π/2`` (incidence and scattering angles): :func:`vsin`'s
    arithmetic without the quadrant bookkeeping of the other three quadrants."""
    n = math.floor(x * INV_PIO2 + 0.5)  # 0 or 1
    r = ((x - n * PIO2_1) - n * PIO2_2) - n * PIO2_3
    return _sin_poly(r) if n < 0.5 else _cos_poly(r)


@inline
def vcos(x):
    """``cos x`` for ``|x| ≤ MAX_TRIG_ARG``."""
    r, q = _reduce(x)
    s = _sin_poly(r)
    c = _cos_poly(r)
    v = c if (q & 1) == 0 else s
    return -v if (q == 1 or q == 2) else v


# ----------------------------------------------------------------------------- erfcx
ERFCX_HI = 6.0
ERFCX_DEGREE = 20  # verfcx is unrolled for this degree
_ERFCX_K = 2.0  # t = (a − K)/(a + K) maps [0, ∞) onto [−1, 1) (Shepherd & Laframboise 1981)
_ERFCX_T1 = (ERFCX_HI - _ERFCX_K) / (ERFCX_HI + _ERFCX_K)


def _erfcx_fit() -> tuple[np.ndarray, float]:
    """Chebyshev coefficients in ``u ∈ [−1, 1]`` (affine in ``t``) of ``(1 + 2a) erfcx(a)``
    on ``a ∈ [0, ERFCX_HI]``, fitted to scipy's ``erfcx`` on 200 Chebyshev nodes, and the
    measured maximum relative error on a fine grid."""
    from scipy import special

    cheb = np.polynomial.chebyshev
    j = np.arange(200)
    u = np.cos(math.pi * (j + 0.5) / 200)
    t = -1.0 + 0.5 * (u + 1.0) * (_ERFCX_T1 + 1.0)
    a = _ERFCX_K * (1.0 + t) / (1.0 - t)
    coef = cheb.chebfit(u, (1.0 + 2.0 * a) * special.erfcx(a), ERFCX_DEGREE)
    x = np.linspace(0.0, ERFCX_HI, 100_001)
    tt = (x - _ERFCX_K) / (x + _ERFCX_K)
    approx = cheb.chebval(2.0 * (tt + 1.0) / (_ERFCX_T1 + 1.0) - 1.0, coef) / (1.0 + 2.0 * x)
    return coef, float(np.max(np.abs(approx / special.erfcx(x) - 1.0)))


#: :func:`_erfcx_fit`'s coefficients, frozen (bit-exact hex): importing scipy.special and
#: fitting cost ~0.3 s of a fresh process's first SPM call (issue 22); tests/test_cold_start.py
#: refits and compares.
_ERFCX_HEX = (
    "0x1.32442f0f2a8b8p+0", "0x1.5117cae7afc67p-4", "-0x1.78e38c9958ae9p-4",
    "0x1.57bcbe48b69e5p-6", "-0x1.58c5b24b32316p-10", "-0x1.ed60f1001dd15p-13",
    "0x1.94bfe9cf48419p-16", "0x1.4b341a057946cp-18", "-0x1.096010adb596fp-22",
    "-0x1.0d1b95c5c26fap-23", "-0x1.7c31d2f70e7b6p-28", "0x1.548acacdf23e1p-29",
    "0x1.e5cbe09aebf19p-32", "-0x1.e3446137c93b8p-38", "-0x1.d22e434b35803p-37",
    "-0x1.0946f73771556p-39", "0x1.57d922362bee0p-44", "0x1.3e65abf972c7ep-44",
    "0x1.80ab13d07079ep-47", "-0x1.f861d05e70376p-53", "-0x1.c3c8efe72064ep-52",
)  # fmt: skip
ERFCX_COEF = np.array([float.fromhex(h) for h in _ERFCX_HEX])
ERFCX_MAX_REL_ERR = 1.2212453270876722e-15  # the fit's, on 100001 points of [0, ERFCX_HI]
# module constants: numba freezes them into the compiled code (no table look-ups)
(
    _X0,
    _X1,
    _X2,
    _X3,
    _X4,
    _X5,
    _X6,
    _X7,
    _X8,
    _X9,
    _X10,
    _X11,
    _X12,
    _X13,
    _X14,
    _X15,
    _X16,
    _X17,
    _X18,
    _X19,
    _X20,
) = (float(c) for c in ERFCX_COEF)
_U_SCALE = 2.0 / (_ERFCX_T1 + 1.0)


@inline
def verfcx(a):
    """``e^{a²} erfc(a)`` for ``0 ≤ a ≤ ERFCX_HI`` (see :func:`verfcx_parts`)."""
    p, d = verfcx_parts(a)
    return p / d


@inline
def verfcx_parts(a):
    """``(p, d)`` with ``erfcx(a) = p / d``, ``d = 1 + 2a``, for ``0 ≤ a ≤ ERFCX_HI``:
    unrolled Clenshaw sum, branch-free and without table look-ups so the loop it sits in
    vectorizes (callers fold the division into their own)."""
    t = (a - _ERFCX_K) / (a + _ERFCX_K)
    u = (t + 1.0) * _U_SCALE - 1.0
    u2 = 2.0 * u
    b1 = 0.0
    b2 = 0.0
    b0 = _X20 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X19 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X18 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X17 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X16 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X15 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X14 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X13 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X12 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X11 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X10 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X9 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X8 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X7 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X6 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X5 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X4 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X3 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X2 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    b0 = _X1 + u2 * b1 - b2
    b2 = b1
    b1 = b0
    return _X0 + u * b1 - b2, 1.0 + 2.0 * a
