r"""M3: the preprocessed Moser-Veselov method of Hairer and Vilmart (symrb's own; not the paper's).

The Moser-Veselov map of a body with inertia :math:`I` is, to every order in :math:`h`, the flow
of a body with the same invariant curves run at a changed speed.  Hairer and Vilmart (J. Phys. A
39, 13225-13235, 2006) give inertias :math:`\tilde I(h, m)` for which one Moser-Veselov step of
:math:`\tilde I` is the step :math:`h` of the flow of :math:`I` to order :math:`p = 4, 6, 8, 10`
(momentum and attitude)::

    1/I~_i = c(h, m)/I_i + d(h, m),  c = 1 + sum_{k>=1} C_k,  d = sum_{k>=1} D_k,
    C_k = sum_{j=0}^{k} c_kj A^(k-j) E^j,  A = h^2 |m|^2 / 2,  E = h^2 sum_i m_i^2 / (2 I_i),

(order 2k + 2 keeps C_1..C_k, D_1..D_k).  The coefficients c_kj, d_kj are rational functions of
I_1, I_2, I_3 printed in that paper (and its authors' Fortran code DMV10); they are typed here
once, in their notation's symmetric functions.

Emitted (``symrb/_generated/discrete_rigid_body.py``): ``mv3_preprocessing_coefficients`` and
``mv3_preprocessed_lam``.  Evidence: :func:`m3_preprocessed_local_error` computes the Taylor series
of one emitted step with exact rationals and compares it with the exact flow's
(:func:`derivations.reference.rigid_body_taylor`), so a wrong coefficient lowers the order there;
the observed order of ``symrb.engine.mv_flow(order=p)`` against the elliptic solution.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.methods.cayley_step import (
    _CH,
    _CL,
    _CM,
    _CQ,
    _CS,
    _LARGS,
    _MARGS,
    _SCALAR3,
    MV3_CAYLEY_S_NEWTON,
    MV3_CAYLEY_STEP,
    _cayley3_inertia,
)
from derivations.registry import Level, claim
from derivations.vocabulary import Arg, Kernel

M3 = claim(
    "M3",
    label="",
    title="The preprocessed Moser-Veselov method (Hairer and Vilmart 2006)",
    statement="With the modified inertia of Hairer and Vilmart, one Moser-Veselov step is the "
    "step $h$ of the rigid body flow to order $p$ for $p$ in 4, 6, 8 and 10 (order 2 without "
    "preprocessing): the exact Taylor coefficients of one emitted step agree with the flow's up "
    "to $h^p$ and not beyond, and the observed order against the elliptic solution is $p$.",
    expected="holds",
    section="symrb",
    where="symrb.engine.mv_flow(order=p), n = 3: the kernels mv3_preprocessing_coefficients "
    "and mv3_preprocessed_lam",
)


_HI = sp.symbols("I1:4", positive=True)
_HA, _HE = sp.symbols("A E", real=True)


def _hv_coefficients() -> tuple[list[list[sp.Expr]], list[list[sp.Expr]]]:
    """(c, d): c[k-1][j], d[k-1][j] the coefficients of A^(k-j) E^j in C_k, D_k, k = 1..4."""
    I1, I2, I3 = _HI
    cyc = ((I1, I2, I3), (I2, I3, I1), (I3, I1, I2))
    X = {q: sum(1 / a**q for a in _HI) for q in (1, 2, 3, 4)}  # sums of 1/I^q
    S = {q: sum(a**q for a in _HI) for q in (1, 2, 3, 4)}  # sums of I^q
    V = I1 * I2 * I3

    def P(a: int, b: int) -> sp.Expr:  # sum over i of (I_j^a + I_k^a)/I_i^b
        return sum((j**a + k**a) / i**b for i, j, k in cyc)

    R = sp.Rational
    c = [
        [S[1] / (6 * V), -X[1] / 3],
        [(S[2] / V - X[1]) / (30 * V), (1 - P(1, 1)) / (30 * V), (3 * S[1] / V + 2 * X[2]) / 60],
        [
            (4 * V + 17 * S[3] - 15 * V * P(1, 1)) / (2520 * V**3),
            (9 * S[1] + 10 * V * X[2] - 6 * P(2, 1)) / (420 * V**2),
            ((6 * P(1, 2) - 100 * X[1]) * V + 53 * S[2]) / (2520 * V**2),
            (15 - V * X[3] - 2 * P(1, 1)) / (630 * V),
        ],
        [
            (62 * S[4] - 94 * V * P(2, 1) + 66 * V**2 * X[2] + 81 * V * S[1]) / (45360 * V**4),
            (-77 * P(3, 1) + 75 * V * P(1, 2) + 214 * S[2] - 240 * V * X[1]) / (22680 * V**3),
            (26 * V * P(2, 2) + 55 * S[3] + 204 * V - 50 * V**2 * X[3] - 59 * V * P(1, 1))
            / (7560 * V**3),
            (137 * V * X[2] - V * P(1, 3) + 3 * S[1] - 69 * P(2, 1)) / (11340 * V**2),
            (2 * V**2 * X[4] + 5 * V * P(1, 2) - 171 * V * X[1] + 159 * S[2]) / (45360 * V**2),
        ],
    ]
    d = [
        [-R(1, 3) / V, S[1] / (6 * V)],
        [-S[1] / V**2 / 60, X[1] / V / 10 - S[2] / V**2 / 60, -(9 + P(1, 1)) / V / 60],
        [
            (34 * V * X[1] - 19 * S[2]) / (2520 * V**3),
            (S[3] + 2 * V * P(1, 1) - 85 * V) / (1260 * V**3),
            (47 * S[1] + 13 * P(2, 1) - 38 * V * X[2]) / (2520 * V**2),
            (9 * V * X[1] + V * P(1, 2) - 11 * S[2]) / (1260 * V**2),
        ],
        [
            (60 * P(1, 1) * V - 61 * S[3] - 247 * V) / (45360 * V**4),
            (54 * V * S[1] - S[4] + 218 * V * P(2, 1) - 426 * V**2 * X[2]) / (45360 * V**4),
            (125 * V * X[1] - 5 * P(3, 1) - 130 * S[2] + 4 * V * P(1, 2)) / (7560 * V**3),
            (67 * S[3] - 735 * V - 15 * V * P(2, 2) + 87 * V * P(1, 1) + 34 * V**2 * X[3])
            / (22680 * V**3),
            (165 * S[1] - V * P(1, 3) - 9 * P(2, 1) - 145 * V * X[2]) / (45360 * V**2),
        ],
    ]
    return c, d


_HV_C, _HV_D = _hv_coefficients()
_HV_ORDERS = (4, 6, 8, 10)
# the coefficient arguments of the evaluation kernel: c_kj, d_kj (k = 1..4, j = 0..k)
_HV_CS = [[sp.Symbol(f"c{k + 1}{j}", real=True) for j in range(k + 2)] for k in range(4)]
_HV_DS = [[sp.Symbol(f"d{k + 1}{j}", real=True) for j in range(k + 2)] for k in range(4)]
_HV_CINERTIA = _cayley3_inertia(_CL)


def _hv_modified_lam(h: sp.Expr, m: sp.Matrix, lam: sp.Matrix, cs: Any, ds: Any) -> list[Any]:
    """Lambda~ of the modified inertia: I~_i = 1/(c/I_i + d), lam~_i = (I~_j + I~_k - I~_i)/2."""
    inertia = _cayley3_inertia(lam)
    A = h**2 * m.dot(m) / 2
    E = h**2 * sum(m[i] ** 2 / inertia[i] for i in range(3)) / 2
    cc = 1 + sum(cs[k][j] * A ** (k + 1 - j) * E**j for k in range(4) for j in range(k + 2))
    dd = sum(ds[k][j] * A ** (k + 1 - j) * E**j for k in range(4) for j in range(k + 2))
    mod = [1 / (cc / inertia[i] + dd) for i in range(3)]
    return [(mod[(i + 1) % 3] + mod[(i + 2) % 3] - mod[i]) / 2 for i in range(3)]


_HV_SUBS = dict(zip(_HI, _HV_CINERTIA, strict=True))
MV3_PREPROCESSING_COEFFICIENTS = Kernel(
    name="mv3_preprocessing_coefficients",
    target="discrete_rigid_body",
    args=_LARGS,
    outputs={
        str(sym): expr.xreplace(_HV_SUBS)
        for row_s, row_e in zip(_HV_CS + _HV_DS, _HV_C + _HV_D, strict=True)
        for sym, expr in zip(row_s, row_e, strict=True)
    },
    doc="The constants of the preprocessed Moser-Veselov method (Hairer and Vilmart 2006), n = 3.\n\n"
    "c_kj, d_kj (k = 1..4, j = 0..k), rational functions of the inertia I_1 = l2 + l3 (cyclic):\n"
    "the coefficients of A^(k-j) E^j in the h^(2k) terms of c and d, 1/I~_i = c/I_i + d\n"
    "(mv3_preprocessed_lam).  Order 2k + 2 uses k = 1..k and zeros for the rest.",
    claims=("M3",),
    convert=False,
)
MV3_PREPROCESSED_LAM = Kernel(
    name="mv3_preprocessed_lam",
    target="discrete_rigid_body",
    args=[Arg("h", _SCALAR3, "the step")]
    + _MARGS
    + _LARGS
    + [
        Arg(str(sym), _SCALAR3, f"preprocessing constant {sym} (mv3_preprocessing_coefficients)")
        for row in _HV_CS + _HV_DS
        for sym in row
    ],  # fmt: skip
    outputs={
        f"l{i + 1}_mod": e for i, e in enumerate(_hv_modified_lam(_CH, _CM, _CL, _HV_CS, _HV_DS))
    },
    doc="The modified Lambda of one preprocessed Moser-Veselov step, n = 3.\n\n"
    "A = h^2 |m|^2 / 2, E = h^2 sum m_i^2/(2 I_i), c = 1 + sum c_kj A^(k-j) E^j,\n"
    "d = sum d_kj A^(k-j) E^j, I~_i = 1/(c/I_i + d), l~_i = (I~_j + I~_k - I~_i)/2.  One\n"
    "mv3_cayley_step with l~ is the step h of the flow of Lambda to order 2k + 2 (Hairer and\n"
    "Vilmart 2006).  Arguments may be floats or arrays of one broadcast shape.",
    claims=("M3",),
    convert=False,
)


def _hv_constants(order: int, lam: sp.Matrix) -> dict[sp.Symbol, Any]:
    """The constants of ``order`` at lam from the emitted coefficient kernel (zeros above it)."""
    keep = order // 2 - 1
    vals = dict(zip(_CL, lam, strict=True))
    out: dict[sp.Symbol, Any] = {}
    for k in range(4):
        for sym in _HV_CS[k] + _HV_DS[k]:
            expr = MV3_PREPROCESSING_COEFFICIENTS[str(sym)]
            out[sym] = sp.nsimplify(expr.xreplace(vals)) if k < keep else sp.Integer(0)
    return out


@M3.check(Level.EXACT_RATIONAL)
def m3_preprocessed_local_error() -> sp.Expr:
    r"""$n = 3$, exact rationals ($\lambda = (7/10, 11/10, 8/5)$, $m = (3/5, -1/2, 4/5)$, $Q = I$):
    one emitted step (mv3_cayley_step at the root $s$ of the scalar form, found by Newton steps of
    mv3_cayley_s_newton on series) with the modified $\Lambda$ of mv3_preprocessed_lam and
    mv3_preprocessing_coefficients, as a power series in $h$, against the Taylor series of the exact
    flow (reference.rigid_body_taylor, Picard iteration of $m' = m \times \omega$, $Q' = Q
    \hat\omega$): for orders 2 (no preprocessing), 4, 6, 8 and 10 the coefficients of $h^1, \dots,
    h^p$ of $m$ and $Q$ agree and that of $h^{p+1}$ in $m$ does not. Returns the sum of absolute
    coefficient differences up to $h^p$ plus one per order whose $h^{p+1}$ term vanishes."""
    lam = sp.Matrix([sp.Rational(7, 10), sp.Rational(11, 10), sp.Rational(8, 5)])
    m0 = [sp.Rational(3, 5), sp.Rational(-1, 2), sp.Rational(4, 5)]
    N = 12  # coefficients of h^0..h^11
    total = Fraction(0)
    inertia = [Fraction(str(e)) for e in _cayley3_inertia(lam)]
    m_ex, Q_ex = ref.rigid_body_taylor(inertia, [Fraction(str(e)) for e in m0], N)
    h = ref.Series.var(N)
    base = {_CH: h} | {_CM[i]: m0[i] for i in range(3)}
    base |= {_CQ[i, j]: int(i == j) for i in range(3) for j in range(3)}
    for order in (2,) + _HV_ORDERS:
        if order == 2:
            lam_mod = [ref.Series.const(Fraction(str(e)), N) for e in lam]
        else:
            vals = base | {_CL[i]: lam[i] for i in range(3)} | _hv_constants(order, lam)
            lam_mod = [ref.series_eval(MV3_PREPROCESSED_LAM[f"l{i + 1}_mod"], vals, N)
                       for i in range(3)]  # fmt: skip
        vals = base | {_CL[i]: lam_mod[i] for i in range(3)}
        s = ref.Series.const(0, N)
        for _ in range(5):  # Newton on series: each step doubles the correct orders
            s = ref.series_eval(MV3_CAYLEY_S_NEWTON["s_next"], vals | {_CS: s}, N)
        vals[_CS] = s
        m1 = [ref.series_eval(_CM[i] + MV3_CAYLEY_STEP[f"dm{i + 1}"], vals, N) for i in range(3)]
        Q1 = [[ref.series_eval(_CQ[i, j] + MV3_CAYLEY_STEP[f"dq{i + 1}{j + 1}"], vals, N)
               for j in range(3)] for i in range(3)]  # fmt: skip
        for i in range(3):
            total += sum(
                abs(a - b)
                for a, b in zip(m1[i].c[: order + 1], m_ex[i].c[: order + 1], strict=True)
            )
            for j in range(3):
                got, want = Q1[i][j].c[: order + 1], Q_ex[i][j].c[: order + 1]
                total += sum(abs(a - b) for a, b in zip(got, want, strict=True))
        if all(m1[i].c[order + 1] == m_ex[i].c[order + 1] for i in range(3)):
            total += 1  # the order is higher than stated: the check could not tell a change
    return sp.Rational(total.numerator, total.denominator)


@M3.check(Level.FLOAT64, tol=0.25)
def m3_preprocessed_order_against_elliptic() -> float:
    r"""symrb.engine.mv_flow(order=p) (NumPy path), the preprocessed method, $n = 3$, against the
    Jacobi elliptic solution of Euler's equations (reference.euler_elliptic) at $T = 4$: the error
    in $M$ at steps $h$ and $h/2$ gives the observed order $\log_2(e(h)/e(h/2))$; largest
    $|\mathrm{observed} - p|$ over $p = 2, 4, 6, 8, 10$ (steps chosen so both errors are far above
    rounding)."""
    from symrb import engine

    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia  # I_1 = lam_2 + lam_3 (cyclic)
    T = 4.0
    m = ref.euler_elliptic(inertia, 1.6, 2.2, np.array([0.0, T]))
    M0 = ref.hat(m[0])

    def error(order: int, h: float) -> float:
        k = round(T / h)
        sol = engine.mv_flow(np.eye(3), M0, lam, T / k, k, save_every=k, order=order,
                             method="numpy")  # fmt: skip
        return float(np.abs(ref.vee(sol.y.M[-1]) - m[-1]).max())

    gaps = []
    for order, h in ((2, 0.05), (4, 0.1), (6, 0.2), (8, 0.25), (10, 0.25)):
        observed = np.log2(error(order, h) / error(order, h / 2))
        gaps.append(abs(observed - order))
    return float(max(gaps))
