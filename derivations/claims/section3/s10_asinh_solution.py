"""S10 (Section 3.3, eq. ``Pequ``): P = Q exp(asinh(M/2)) solves M = Q^T P - P^T Q for
||M||_op < 2.

Erratum: the printed exponent "sinh^-1 M/2" is ambiguous; read as (sinh^-1 M)/2 it fails, read as
sinh^-1(M/2) (the reading that matches the domain ||M/2||_op < 1 of the series) it holds, and on
skew matrices exp(sinh^-1 X) = X + (I + X^2)^(1/2).  The evidence evaluates the displayed formulas
on an eigenvalue (symbolic), with matrices (float64) and near the boundary of the domain in 60
digits.  symrb's own solver of this equation, ``symrb.symmetric.P_from_M``, is checked by M6
(``derivations/methods/p_from_m.py``) against the formulas displayed here.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any

import mpmath as mp
import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import MatFn, OpNorm
from derivations.claims.section3._symmetric import M, P, Q
from derivations.claims.section3.s06_symmetric_to_rigid_body import SYMMETRIC_MOMENTUM
from derivations.registry import Level, claim
from derivations.symbolic import Words, eq, lhs_minus_rhs
from derivations.vocabulary import n

S10 = claim(
    "S10",
    label="Pequ",
    title="$P = Q\\exp(\\sinh^{-1}(M/2))$ solves $M = Q^T P - P^T Q$ for $\\|M\\|_{\\mathrm{op}} "
    "< 2$",
    statement="For [[domain]], the rotation given by the paper's formula for $P$ solves [[M]]. "
    "The power series of $\\sinh^{-1}$, the term-by-term integral of that of "
    "$1/\\sqrt{1 + u^2}$, converges on the skew $u$ of operator norm below 1 and there inverts "
    "$\\sinh$; it still converges on the boundary, as slowly as the scalar series.",
    expected="holds after correction",
    headline="[[corrected]]",
    printed="[[printed]], the exponent read as half of $\\sinh^{-1}M$.",
    corrected="[[corrected]], which on skew matrices is [[closed]].",
    note="The printed exponent $\\sinh^{-1} M/2$ is ambiguous, and read as $\\tfrac12\\sinh^{-1} "
    "M$ it fails. Corrected: $P = Q\\exp(\\sinh^{-1}(M/2))$, the reading that matches the domain "
    "$\\|M/2\\|_{\\mathrm{op}} < 1$ of the series. The slip is notational: read as "
    "$\\sinh^{-1}(M/2)$ the proposition holds; read as $(\\sinh^{-1} M)/2$ it fails even where "
    "the series converges. On skew matrices $\\exp(\\sinh^{-1} X) = X + (I + X^2)^{1/2}$, which "
    "is how `symrb.symmetric.P_from_M` computes it (on the real Schur form). The solution is not unique: "
    "eigen-angles $\\varphi$ and $\\pi - \\varphi$ of $Q^T P$ give the same $M$; this one has "
    "$\\lvert\\varphi\\rvert < \\pi/2$.",
    section="3.3",
    where="Section 3.3, the first proposition: for $\\|M\\|_{\\mathrm{op}} < 2$ the equation $M = "
    "Q^T P - P^T Q$ has the solution $P = Q\\,e^{\\sinh^{-1} M/2}$",
)
DOMAIN = S10.formula("domain", sp.Lt(OpNorm(M), 2))
S10_M = S10.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))
S10.formula("printed", eq(P, Q * MatFn("exp", MatFn("asinh", M) / 2)))
S10.formula("corrected", eq(P, Q * MatFn("exp", MatFn("asinh", M / 2))))
CLOSED = S10.formula("closed", eq(P, Q * (M / 2 + MatFn("sqrt", sp.Identity(n) + M * M / 4))))


def _after_Q(rhs: sp.MatrixExpr) -> sp.MatrixExpr:
    """X for a displayed right side Q X."""
    coeff, mats = rhs.as_coeff_matrices()
    if not mats or mats[0] != Q:
        raise ValueError(f"{rhs} is not Q times a matrix")
    return coeff * sp.MatMul(*mats[1:]).doit() if len(mats) > 2 else coeff * mats[1]


def evaluate(expr: sp.Basic, env: Mapping[str, Any], ops: Mapping[str, Callable[..., Any]]) -> Any:
    """A displayed matrix formula evaluated with concrete matrices: ``ops`` supplies ``mul``,
    ``T``, ``num`` (a SymPy number), ``eye`` and the matrix functions by name."""

    def ev(e: sp.Basic) -> Any:
        if isinstance(e, sp.MatrixSymbol):
            return env[str(e.name)]
        if isinstance(e, sp.Identity):
            return ops["eye"]()
        if isinstance(e, sp.MatMul):
            coeff, mats = e.as_coeff_matrices()
            acc = ev(mats[0])
            for m in mats[1:]:
                acc = ops["mul"](acc, ev(m))
            return ops["num"](coeff) * acc
        if isinstance(e, sp.MatAdd):
            return functools.reduce(lambda x, y: x + y, [ev(a) for a in e.args])
        if isinstance(e, sp.Transpose):
            return ops["T"](ev(e.arg))
        if isinstance(e, sp.MatPow) and e.exp.is_Integer and e.exp > 0:
            base = ev(e.base)
            return functools.reduce(ops["mul"], [base] * int(e.exp))
        if isinstance(e, MatFn):
            return ops[str(e.args[0])](ev(e.args[1]))
        raise TypeError(f"cannot evaluate {type(e).__name__}: {e}")

    return ev(expr)


def _asinh_skew(X: np.ndarray) -> np.ndarray:
    """asinh of a real skew X with ||X||_op <= 1, through the Hermitian matrix iX:
    asinh(iy) = i arcsin(y)."""
    w, V = np.linalg.eigh(1j * X)
    return np.real(V @ np.diag(-1j * np.arcsin(np.clip(w, -1.0, 1.0))) @ V.conj().T)


def _sqrt_sym(S: np.ndarray) -> np.ndarray:
    """The square root of a symmetric positive semidefinite S (symmetric eigen-decomposition)."""
    w, V = np.linalg.eigh((S + S.T) / 2)
    return (V * np.sqrt(np.clip(w, 0.0, None))) @ V.T


def numpy_ops(k: int) -> dict[str, Callable[..., Any]]:
    from scipy.linalg import expm

    return {
        "mul": np.matmul, "T": lambda a: np.swapaxes(a, -1, -2), "num": float,
        "eye": lambda: np.eye(k), "exp": expm, "asinh": _asinh_skew, "sqrt": _sqrt_sym,
    }  # fmt: skip


def _scalar(expr: sp.Basic, x: sp.Symbol) -> sp.Expr:
    """A displayed function of M as a scalar function of x (M -> x, I -> 1): on skew M these
    formulas act on each eigenvalue."""
    ops = {
        "mul": lambda a, b: a * b, "T": lambda a: a, "num": lambda c: c,
        "eye": lambda: sp.Integer(1), "exp": sp.exp, "asinh": sp.asinh, "sqrt": sp.sqrt,
    }  # fmt: skip
    return evaluate(expr, {"M": x}, ops)


def _s10_scalar(form: str) -> sp.Expr:
    x = sp.Symbol("x", real=True)
    inner = _after_Q(S10.formulas[form].rhs)
    if not isinstance(inner, MatFn) or str(inner.args[0]) != "exp":
        raise ValueError(f"the {form} formula is not Q exp(X)")
    X = _scalar(inner.args[1], x)
    gap = sp.exp(X) - sp.exp(-X) - x  # Q^T P - P^T Q - M on the eigenvalue x, P = Q exp(X)
    closed = sp.exp(X) - _scalar(_after_Q(CLOSED.rhs), x)
    total = sp.Integer(0)
    for e in (gap, closed) if form == "corrected" else (gap,):
        if sp.simplify(e.rewrite(sp.log)) != 0:
            total += sp.Integer(1)
    return total


@S10.check(Level.SYMBOLIC_FIXED_N, form="printed")
def s10_printed_scalar() -> sp.Integer:
    r"""On an eigenvalue $x$ of $M$, the displayed printed reading $P = Q \exp(X(x))$ gives $\exp(X)
    - \exp(-X) - x$, the eigenvalue of $Q^T P - P^T Q - M$: does it simplify to 0?"""
    return _s10_scalar("printed")


@S10.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s10_corrected_scalar() -> sp.Integer:
    r"""The same for the corrected reading, and $\exp(X(x))$ equals the displayed closed form $x/2 +
    (1 + x^2/4)^{1/2}$ (identities of analytic functions, simplified for real $x$ after rewriting
    $\operatorname{asinh}$ as a log, so they hold on the imaginary eigenvalues of $M$ too)."""
    return _s10_scalar("corrected")


def _s10_general_n(form: str) -> sp.Integer:
    """Every n, in two steps.  (1) Noncommutative: the displayed M formula with P the displayed
    Q F (F the displayed function of M, a letter) reduces, Q orthogonal, to F - F^T.  (2) F is a
    real power series in the single matrix M, so F^T = F(M^T) = F(-M) (M skew), and power series
    of one matrix form a commutative algebra on which M -> z is a homomorphism: F - F^T - M
    vanishes for every n (with ||M||_op < 2) exactly when F(z) - F(-z) - z does as a function.
    Returns the words left after step (1) other than F, F^T, M, plus 1 if step (2) fails."""
    w = Words(skew=["M"], orthogonal=["Q"])
    F = sp.MatrixSymbol("F", n, n)
    inner = _after_Q(S10.formulas[form].rhs)
    solved = eq(S10_M.lhs, S10_M.rhs.xreplace({P: Q * F}))
    gap = w.reduce(w.of(lhs_minus_rhs(solved)))
    f, fT, m = w("F"), w.T(w("F")), w("M")
    left = sp.expand(
        gap - sp.Add(*[t for t in sp.Add.make_args(gap) if t.free_symbols <= {f, fT, m}])
    )
    z = sp.Symbol("z", real=True)
    Fz = _scalar(inner, z)
    scalar = gap.xreplace({f: Fz, fT: Fz.xreplace({z: -z}), m: z})
    total = sp.Integer(len(sp.Add.make_args(left)) if left != 0 else 0)
    return total + (0 if sp.simplify(sp.expand(scalar).rewrite(sp.log)) == 0 else 1)


@S10.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s10_corrected_general_n() -> sp.Integer:
    r"""Every $n$: $Q^T P - P^T Q - M$ (the displayed $M$ formula, noncommutative $Q$ orthogonal,
    $M$ skew) with $P = Q F$, $F$ the displayed corrected $\exp(\operatorname{asinh}(M/2))$, reduces
    to $F - F^T - M$; $F^T = F(-M)$ for a real power series of skew $M$, and functions of one matrix
    commute, so it vanishes for every $n$ when $\exp(\operatorname{asinh}(z/2))$ minus
    $\exp(\operatorname{asinh}(-z/2))$ is $z$, which SymPy confirms."""
    return _s10_general_n("corrected")


@S10.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s10_printed_general_n() -> sp.Integer:
    r"""The same reduction for the printed reading $F = \exp(\operatorname{asinh}(M)/2)$: $F(z) -
    F(-z) - z$ does not vanish, so the printed formula fails for every $n$ (a nonzero function of
    $M$ is nonzero on some skew $M$ of norm below 2, already for $n = 2$)."""
    return _s10_general_n("printed")


def _s10_equation(form: str) -> float:
    """max |Q^T P - P^T Q - M| (the displayed M formula) for P from the displayed formula."""
    rng = np.random.default_rng(10)
    errs = []
    for k in range(3, 7):
        ops = numpy_ops(k)
        for _ in range(20):
            Mk = ref.random_skew(k, rng)
            Mk *= rng.uniform(0.05, 0.9) / np.linalg.norm(Mk, 2)  # both readings' series converge
            Qk = ref.random_rotation(k, rng)
            Pk = evaluate(S10.formulas[form].rhs, {"Q": Qk, "M": Mk}, ops)
            errs.append(np.abs(evaluate(S10_M.rhs, {"Q": Qk, "P": Pk}, ops) - Mk).max())
    return float(np.max(errs))


@S10.check(Level.FLOAT64, tol=1e-12, form="printed")
def s10_printed_matrix() -> float:
    r"""The displayed printed formula evaluated with matrices ($\operatorname{asinh}$ by the
    Hermitian eigen-decomposition of $iM$, scipy expm) for random skew $M$ with $\|M\|_{\mathrm{op}}
    < 0.9$ and rotations $Q$, $n = 3, \dots, 6$: $\max |Q^T P - P^T Q - M|$."""
    return _s10_equation("printed")


@S10.check(Level.FLOAT64, tol=1e-12, form="corrected")
def s10_corrected_matrix() -> float:
    """The same for the displayed corrected formula."""
    return _s10_equation("corrected")


#: The precision (decimal digits) of the reference near the boundary of the domain.
DPS = 60


@functools.cache
def near_boundary() -> tuple[np.ndarray, list[tuple[float, np.ndarray, Any]], float]:
    """60 digits, n = 4, ||M||_op = 2(1 - delta) for delta = 1e-4, 1e-8, 1e-12: the rotation Q
    (float64), for each delta the triple (delta, M in float64, P from the displayed closed form in
    60-digit arithmetic, square root through mpmath's symmetric eigen-decomposition), and the
    worst residual of that P (Q^T P - P^T Q - M and P^T P - I)."""
    rng = np.random.default_rng(1010)
    Qf, D = ref.random_rotation(4, rng), ref.random_skew(4, rng)
    D = D / np.linalg.norm(D, 2)
    identity, points = [], []
    with mp.workdps(DPS):

        def sqrt_mp(S: Any) -> Any:
            E, V = mp.eigsy(S)
            return V * mp.diag([mp.sqrt(max(e, 0)) for e in E]) * V.T

        ops: dict[str, Callable[..., Any]] = {
            "mul": lambda a, b: a * b, "T": lambda a: a.T, "num": lambda c: mp.mpf(c.p) / c.q,
            "eye": lambda: mp.eye(4), "sqrt": sqrt_mp,
        }  # fmt: skip
        Qm, Rm = mp.qr(mp.matrix(Qf.tolist()))  # orthogonal to 60 digits, not just to rounding
        Qm = Qm * mp.diag([mp.sign(Rm[i, i]) for i in range(4)])
        for delta in (1e-4, 1e-8, 1e-12):
            Mf = 2.0 * (1.0 - delta) * D
            Mm = mp.matrix(Mf.tolist())
            Pm = evaluate(CLOSED.rhs, {"Q": Qm, "M": Mm}, ops)
            gap = evaluate(S10_M.rhs, {"Q": Qm, "P": Pm}, ops) - Mm
            identity += [float(mp.mnorm(gap, 1)), float(mp.mnorm(Pm.T * Pm - mp.eye(4), 1))]
            points.append((delta, Mf, Pm))
    return Qf, points, float(np.max(identity))


@S10.check(Level.MPMATH, tol=1e-50, form="corrected")
def s10_high_precision_identity() -> float:
    r"""60 digits: $P$ from the displayed closed form solves $Q^T P - P^T Q = M$ with $P^T P = I$ at
    $\|M\|_{\mathrm{op}} = 2(1 - \delta)$, $\delta = 10^{-4}, 10^{-8}, 10^{-12}$ ($n = 4$): largest
    residual."""
    return near_boundary()[2]


def _asinh_series(u: np.ndarray, terms: int) -> np.ndarray:
    """The partial sum of the paper's series for sinh^-1 on a matrix: the binomial series of
    1/sqrt(1 + u^2), sum binom(-1/2, k) u^(2k), integrated term by term (u^(2k+1)/(2k+1))."""
    from scipy.special import binom

    u2, power, total = u @ u, u.copy(), np.zeros_like(u)
    for k in range(terms):
        total += binom(-0.5, k) / (2 * k + 1) * power
        power = power @ u2
    return total


def _sinh(a: np.ndarray) -> np.ndarray:
    from scipy.linalg import expm

    return (expm(a) - expm(-a)) / 2


def _skew_of_norm(k: int, norm: float, rng: np.random.Generator) -> np.ndarray:
    u = ref.random_skew(k, rng)
    return u * (norm / np.linalg.norm(u, 2))


@S10.check(Level.FLOAT64, tol=1e-13)
def s10_asinh_series_inside() -> float:
    r"""The paper's series for $\sinh^{-1}$ on $\mathfrak{so}(n)$ inside its domain: for random skew
    $u$ ($n = 3, 4, 5$) with $\|u\|_{\mathrm{op}} = 0.5$ and 0.9, the partial sum of 400 terms
    equals the matrix function $\operatorname{asinh}(u)$ (eigen-decomposition of $iu$,
    $\operatorname{asinh}(iy) = i \arcsin y$) and $\sinh$ of it (scipy's expm) is $u$ again: max
    error."""
    rng = np.random.default_rng(10)
    worst = 0.0
    for k in (3, 4, 5):
        for norm in (0.5, 0.9):
            u = _skew_of_norm(k, norm, rng)
            series = _asinh_series(u, 400)
            worst = max(worst, np.abs(series - _asinh_skew(u)).max())
            worst = max(worst, np.abs(_sinh(series) - u).max())
    return float(worst)


@S10.check(Level.FLOAT64, tol=0.05)
def s10_asinh_series_on_the_boundary() -> float:
    r"""On the boundary $\|u\|_{\mathrm{op}} = 1$ (random skew $u$, $n = 4$) the series still
    converges to $\operatorname{asinh}(u)$, as slowly as the scalar series at $|y| = 1$: the error
    of the partial sums of $K = 100$ and 10,000 terms against the matrix function falls like
    $K^{-1/2}$; $|\text{fitted exponent} + 1/2|$ (inf unless $\sinh$ of the matrix function is $u$
    to 1e-12)."""
    u = _skew_of_norm(4, 1.0, np.random.default_rng(11))
    limit = _asinh_skew(u)
    if np.abs(_sinh(limit) - u).max() > 1e-12:
        return float("inf")
    e100, e10k = (np.abs(_asinh_series(u, K) - limit).max() for K in (100, 10_000))
    return float(abs(np.log(e10k / e100) / np.log(100.0) + 0.5))


_SERIES_TERMS = 8  # odd powers xi, xi^3, ..., xi^15 in the symbolic check


@S10.check(Level.SYMBOLIC_GENERAL_N)
def s10_sinh_is_skew_general_n() -> sp.Integer:
    r"""Every $n$: with $\xi$ a noncommutative skew letter ($\xi^T = -\xi$), the displayed
    definition $(e^\xi - e^{-\xi})/2$, expanded to degree 15, is the odd series $\sum_k
    \xi^{2k+1}/(2k+1)!$ (the even powers cancel), and its transpose is minus itself, so $\sinh$ maps
    $\mathfrak{so}(n)$ to $\mathfrak{so}(n)$; a truncation keeps it degree by degree, so the
    statement holds for the whole series. Replacing $-\xi$ by $\xi^T$ in $e^{-\xi}$ (a non-skew
    letter) leaves a nonzero residual."""
    w = Words(skew=["xi"])
    xi = w("xi")
    exp_series = sum((xi**j / sp.factorial(j) for j in range(2 * _SERIES_TERMS)), sp.Integer(0))
    definition = (exp_series - exp_series.subs(xi, -xi)) / 2
    odd = sum(
        (xi ** (2 * k + 1) / sp.factorial(2 * k + 1) for k in range(_SERIES_TERMS)), sp.Integer(0)
    )
    return w.is_zero(definition - odd) + w.is_zero(w.T(odd) + odd)


@S10.check(Level.FLOAT64, tol=1e-13)
def s10_sinh_and_its_inverse_on_so_n() -> float:
    r"""$\sinh$ and $\sinh^{-1}$ stay in $\mathfrak{so}(n)$: for random skew $\xi$ ($n = 2, \dots,
    6$, $\|\xi\|_{\mathrm{op}} = 0.5, 2, 5$) the displayed $(e^\xi - e^{-\xi})/2$ (scipy's expm) is
    skew and equals its odd power series (80 terms); for random skew $u$ with $\|u\|_{\mathrm{op}} =
    0.5, 0.9$ the paper's series for $\sinh^{-1}$ (400 terms) is skew and $\sinh$ of it is $u$: the
    largest of these errors, relative to the norm of the matrix."""
    from scipy.linalg import expm

    rng = np.random.default_rng(12)
    worst = 0.0
    for k in range(2, 7):
        for norm in (0.5, 2.0, 5.0):
            xi = _skew_of_norm(k, norm, rng)
            S = (expm(xi) - expm(-xi)) / 2
            odd, power = np.zeros_like(xi), xi.copy()
            for j in range(80):
                odd += power / float(sp.factorial(2 * j + 1))
                power = power @ xi @ xi
            scale = np.abs(S).max()
            worst = max(worst, np.abs(S + S.T).max() / scale, np.abs(odd - S).max() / scale)
        for norm in (0.5, 0.9):
            u = _skew_of_norm(k, norm, rng)
            A = _asinh_series(u, 400)
            worst = max(worst, np.abs(A + A.T).max() / norm, np.abs(_sinh(A) - u).max() / norm)
    return float(worst)


# the paper's sentences
S10.sentence(
    r"Recall that $\sinh : \mathfrak{so}(n) \rightarrow \mathfrak{so}(n)$ is defined by $\sinh \xi "
    r"= \left( e^\xi - e^{- \xi} \right) /2$.",
    s10_sinh_is_skew_general_n,
    s10_sinh_and_its_inverse_on_so_n,
)
S10.sentence(
    r"One sees that indeed $\sinh$ takes values in $\mathfrak{so}(n)$ by using, for example, its "
    r"series expansion: $\sinh \xi = \xi + \frac{1}{3!}\xi^3 + \frac{1}{5!} \xi^5 + \ldots.$",
    s10_sinh_is_skew_general_n,
    s10_sinh_and_its_inverse_on_so_n,
)
S10.sentence(
    r"Recall from calculus that the inverse function $\sinh^{-1} (u)$ has a convergent power "
    r"series expansion for $| u | < 1$ that is given by integrating the power series expansion of "
    r"the function $1/ \sqrt{1 + u^2}$ term by term.",
    s10_asinh_series_inside,
    s10_asinh_series_on_the_boundary,
)
S10.sentence(
    r"This power series expansion shows that the map $\sinh : \mathfrak{so}(n) \rightarrow "
    r"\mathfrak{so}(n)$ has an inverse on the set $U = \left\{ u \in \mathfrak{so}(n) \mid \| u "
    r"\|_{\mathrm{op}} < 1 \right\}$.",
    s10_asinh_series_inside,
)
S10.sentence(
    r"We shall denote this inverse by $\sinh^{-1}$, so $\sinh^{-1}: U \rightarrow "
    r"\mathfrak{so}(n)$.",
    s10_sinh_and_its_inverse_on_so_n,
)
S10.sentence(
    r"For $\| M \|_{\mathrm{op}} < 2$, the equation (M_Q_P.eqn) has the solution "
    r"$P=Q\left( e^{\sinh^{-1}M/2}\right)$",
    s10_printed_scalar,
    s10_corrected_scalar,
    s10_printed_matrix,
    s10_corrected_matrix,
    s10_high_precision_identity,
    s10_corrected_general_n,
    s10_printed_general_n,
)
S10.sentence(
    r"Notice that $M=e^{\sinh^{-1}M/2}-e^{-\sinh^{-1}M/2}\,.$",
    s10_printed_scalar,
    s10_corrected_scalar,
    s10_printed_matrix,
    s10_corrected_matrix,
    s10_corrected_general_n,
    s10_printed_general_n,
)
