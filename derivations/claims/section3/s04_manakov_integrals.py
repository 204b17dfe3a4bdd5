"""S4 (Section 3.1, eq. ``lambda_eqn``): Manakov's Lax equation with parameter and its integrals.

With M = J(Omega) and Mdot = [M, Omega] (S2), d/dt(M + lambda Lambda^2) = [M + lambda Lambda^2,
Omega + lambda Lambda] for every n, and the coefficients of the powers of lambda in
tr((M + lambda Lambda^2)^k) are conserved and in involution for the Lie-Poisson bracket.

Emitted to ``symrb/_generated/rigid_body.py``: ``manakov_integrals`` (derived by expanding the
displayed trace in noncommutative letters) and ``casimir_traces`` (its lambda^0 coefficients).
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section2._matrix_formulas import Mk, Mk1, Omk
from derivations.claims.section2.d10_moser_veselov import MV_MOMENTUM, MV_TRANSPORT
from derivations.claims.section3 import _semisimple as su3
from derivations.claims.section3._inertia import ARG_LAM, lam_symbols
from derivations.claims.section3.s02_rigid_body_equations import (
    ARG_M,
    J_DEF,
    MDOT,
    RIGID_BODY_RHS,
    M,
    Om,
)
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Pair,
    Words,
    eq,
    explicit,
    residual,
    skew_gradient,
    skew_matrix,
    trace_words,
)
from derivations.vocabulary import Kernel, Lam, matrix

_xi, _eta = matrix("xi"), matrix("eta")

S4 = claim(
    "S4",
    label="lambda_eqn",
    title="Manakov's Lax equation with parameter and its integrals",
    statement="[[lax]]; the coefficients of the powers of $\\lambda$ in [[generating]] are "
    "conserved along the rigid body flow and are in involution for the Lie-Poisson bracket. At a "
    "generic point they are as many independent functions as complete integrability on a generic "
    "coadjoint orbit needs: half the orbit's dimension besides the Casimirs. Moser and Veselov's "
    "discrete rigid body has the corresponding Lax form with parameter, [[discrete_lax]], with "
    "$M_k$ and $M_{k+1}$ given by mv2 and mv3 (D10), so the discrete flow conserves the same "
    "integrals.",
    expected="holds",
    section="3.1",
    where="Section 3.1, the last displayed equation: Manakov's Lax equation with parameter, "
    "$\\frac{d}{dt}(M + \\lambda\\Lambda^2) = [M + \\lambda\\Lambda^2, \\Omega + "
    "\\lambda\\Lambda]$, and the integrals after it",
    note="Words with an odd number of $M$'s vanish ($M$ skew, $\\Lambda^2$ symmetric) and the top "
    "power of $\\lambda$ is the constant $\\operatorname{tr}(\\Lambda^{2k})$, so the non-trivial "
    "integrals for $2 \\le k \\le 5$ are six; the $\\lambda^0$ coefficients "
    "$\\operatorname{tr}(M^k)$ are the Casimirs.",
)
_lp = sp.Symbol("lambda")
_k = sp.Symbol("k", integer=True, positive=True)
LAX_MATRIX = M + _lp * Lam**2
LAX = S4.formula(
    "lax",
    eq(sp.Derivative(LAX_MATRIX, sp.Symbol("t")), Bracket(LAX_MATRIX, Om + _lp * Lam)),
)
GENERATING = S4.formula("generating", sp.Trace(sp.MatPow(LAX_MATRIX, _k)))
_U_LAX = Omk - _lp * Lam
DISCRETE_LAX = S4.formula(
    "discrete_lax", eq((Mk1 + _lp * Lam**2) * _U_LAX, _U_LAX * (Mk + _lp * Lam**2))
)


def _letters_of_lax() -> dict[str, tuple[sp.Expr, sp.MatrixExpr]]:
    """The summands of the Lax matrix as {letter: (coefficient, matrix)}: M and Lambda^2."""
    out = {}
    for term in GENERATING.arg.base.args:
        coeff, mat = term.as_coeff_mmul() if isinstance(term, sp.MatMul) else (sp.Integer(1), term)
        out["M" if mat == M else "A"] = (coeff, mat)
    return out


def manakov_words(kmax: int) -> list[tuple[int, int, dict[tuple[str, ...], sp.Expr]]]:
    """The non-trivial coefficients of lambda^j in the displayed tr((M + lambda Lambda^2)^k),
    2 <= k <= kmax, as {trace word: integer coefficient} (words up to rotation and reversal)."""
    letters = _letters_of_lax()
    out = []
    for k in range(2, kmax + 1):
        coeffs = trace_words(
            {name: c for name, (c, _m) in letters.items()}, k, _lp, {"M": -1, "A": 1}
        )
        out += [(k, j, words) for j, words in coeffs.items() if j != k]
    return out


def _word_trace(word: tuple[str, ...]) -> sp.Expr:
    mats = {name: m for name, (_c, m) in _letters_of_lax().items()}
    return sp.Trace(sp.MatMul(*[mats[x] for x in word]))


_MANAKOV = manakov_words(5)
MANAKOV_INTEGRALS = Kernel(
    name="manakov_integrals",
    target="rigid_body",
    args=[ARG_M, ARG_LAM],
    outputs={
        f"k{k}_j{j}": sp.Add(*[c * _word_trace(w) for w, c in words.items()])
        for k, j, words in _MANAKOV
    },
    doc="Manakov's integrals of the rigid body.\n\n"
    "The non-trivial coefficients of lambda^j in trace((M + lambda Lambda^2)^k), 2 <= k <= 5\n"
    "(A = Lambda^2), in this order:\n\n"
    + "\n".join(
        f"- k={k}, lambda^{j}: " + " + ".join(f"{c} tr({''.join(w)})" for w, c in words.items())
        for k, j, words in _MANAKOV
    ),
    claims=("S4",),
    stack=True,
)
CASIMIR_TRACES = Kernel(
    name="casimir_traces",
    target="rigid_body",
    args=[ARG_M],
    outputs={
        f"tr_M{k}": sp.Add(*[c * _word_trace(w) for w, c in words.items()])
        for k, j, words in manakov_words(6)
        if j == 0 and k % 2 == 0
    },
    doc="Casimirs of so(n): trace(M^2), trace(M^4), trace(M^6).\n\n"
    "The lambda^0 coefficients of trace((M + lambda Lambda^2)^k); odd powers vanish.",
    claims=("S4",),
    stack=True,
)


@S4.check(Level.SYMBOLIC_GENERAL_N)
def s4_lax_pair_general_n() -> sp.Expr:
    r"""With $\Lambda$ and $\Omega$ noncommutative, $M$ the displayed $J(\Omega)$ and $\dot M$ the
    displayed $[M, \Omega]$: $\dot M$ minus the right side of the displayed Lax equation expands to
    0 (any $n$)."""
    w = Words(symmetric=["Lambda"])
    Mdot = w.of(MDOT.rhs.xreplace({M: J_DEF.rhs}))  # Lambda is constant: d/dt lhs = Mdot
    rhs = w.of(LAX.rhs.xreplace({M: J_DEF.rhs}))
    return w.is_zero(Mdot - rhs)


def _degree(name: str) -> int:
    return int(name[1]) if name.startswith("k") else int(name[4:])


def _integrals(max_degree: int, lam: list[sp.Expr], Ms: sp.Matrix) -> list[sp.Expr]:
    """The emitted Manakov integrals of degree <= max_degree, on an explicit M (the Casimirs of
    these degrees are among them: (k, j) = (2, 0), (4, 0))."""
    return [
        sp.expand(explicit(MANAKOV_INTEGRALS[name], {"M": Ms}, lam))
        for name in MANAKOV_INTEGRALS.outputs
        if _degree(name) <= max_degree
    ]


def conservation(lam: list[sp.Expr], Ms: sp.Matrix, max_degree: int) -> sp.Expr:
    k = Ms.rows
    Mdot = explicit(RIGID_BODY_RHS["Mdot"], {"Q": sp.eye(k), "M": Ms}, lam)
    total = sp.Integer(0)
    for F in _integrals(max_degree, lam, Ms):
        G = skew_gradient(F, Ms)
        total += residual(sp.together(explicit(Pair(M, Om), {"M": G, "Omega": Mdot})))
    return total


@S4.check(Level.SYMBOLIC_FIXED_N)
def s4_integrals_conserved() -> sp.Expr:
    r"""$\frac{d}{dt} F = \langle \nabla F, \dot M\rangle$ vanishes identically for the emitted
    integrals of degree at most 4, with $\dot M$ from the emitted rigid body field (symbolic $M$ and
    $\Lambda$, $n = 4$)."""
    lam, Ms = lam_symbols(4), skew_matrix("m", 4)
    return conservation(lam, Ms, 4)


def _derivative_at_zero(values: list[sp.Rational]) -> sp.Rational:
    """p'(0) of the polynomial p of degree < len(values) with p(i) = values[i], i = 0, 1, ...
    (exact Lagrange interpolation)."""
    e = sp.Symbol("e")
    return sp.diff(sp.interpolate(list(enumerate(values)), e), e).subs(e, 0)


@S4.check(Level.EXACT_RATIONAL)
def s4_integrals_conserved_exact() -> sp.Expr:
    r"""The same for every emitted integral and Casimir (degrees up to 6): $\frac{d}{de} F(M + e\dot
    M)$ at $e = 0$, by exact interpolation of $F$ at $e = 0, \dots, 6$, vanishes at 3 random
    rational $(M, \Lambda)$, $n = 4$ and 5."""
    rng = np.random.default_rng(44)
    total = sp.Integer(0)
    for k in (4, 5):
        for _ in range(3):
            lam = [sp.Rational(int(x), 7) for x in rng.integers(3, 20, k)]
            A = sp.Matrix(k, k, lambda i, j: sp.Rational(int(rng.integers(-9, 10)), 5))
            Ms = A - A.T
            Mdot = explicit(RIGID_BODY_RHS["Mdot"], {"Q": sp.eye(k), "M": Ms}, lam)
            for kernel in (MANAKOV_INTEGRALS, CASIMIR_TRACES):
                for name in kernel.outputs:
                    vals = [explicit(kernel[name], {"M": Ms + e * Mdot}, lam) for e in range(7)]
                    total += residual(_derivative_at_zero(vals))
    return total


@S4.check(Level.SYMBOLIC_FIXED_N)
def s4_integrals_in_involution() -> sp.Expr:
    r"""Lie-Poisson brackets $\{F, G\}(M) = -\langle M, [\nabla F, \nabla G]\rangle$ of the emitted
    Manakov integrals of degree at most 4 vanish pairwise (symbolic, $n = 4$)."""
    lam, Ms = lam_symbols(4), skew_matrix("m", 4)
    grads = [skew_gradient(F, Ms) for F in _integrals(4, lam, Ms)]
    total = sp.Integer(0)
    for a, b in itertools.combinations(range(len(grads)), 2):
        bracket = explicit(Pair(M, Bracket(_xi, _eta)), {"M": Ms, "xi": grads[a], "eta": grads[b]})
        total += residual(bracket)
    return total


@S4.check(Level.SYMBOLIC_FIXED_N)
def s4_coefficients_by_expansion() -> sp.Expr:
    r"""Another route to the same integrals: expand the displayed trace with explicit symbolic $3
    \times 3$ matrices as a polynomial in $\lambda$; its coefficients equal the emitted Manakov
    integrals and Casimirs ($n = 3$)."""
    lam, Ms = lam_symbols(3), skew_matrix("m", 3)
    base = explicit(GENERATING.arg.base, {"M": Ms, "lambda": _lp}, lam)
    total = sp.Integer(0)
    coeff_cache: dict[int, sp.Poly] = {}
    for kernel in (MANAKOV_INTEGRALS, CASIMIR_TRACES):
        for name in kernel.outputs:
            k, j = (int(name[1]), int(name[4])) if name.startswith("k") else (int(name[4:]), 0)
            if k not in coeff_cache:
                coeff_cache[k] = sp.Poly(sp.expand((base**k).trace()), _lp)
            want = coeff_cache[k].coeff_monomial(_lp**j)
            total += residual(sp.expand(explicit(kernel[name], {"M": Ms}, lam)) - want)
    return total


@S4.check(Level.FLOAT64, tol=1e-10)
def s4_symrb_integrals_pointwise() -> float:
    r"""symrb.manakov_integrals and symrb.casimir_traces against coefficients of a polynomial fit of
    $\operatorname{tr}((M + t\Lambda^2)^k)$ over $t$ (plain NumPy), $n = 4, 5$, 10 random $M$ each:
    max relative difference."""
    import symrb

    rng = np.random.default_rng(5)
    worst = 0.0
    order = [(int(nm[1]), int(nm[4])) for nm in MANAKOV_INTEGRALS.outputs]
    for k in (4, 5):
        lam = rng.uniform(0.5, 1.5, k)
        A = np.diag(lam**2)
        for _ in range(10):
            m = ref.random_skew(k, rng, 0.5)
            ts = np.linspace(-1.0, 1.0, 9)
            fits = {}
            for p in range(2, 7):
                vals = [np.trace(np.linalg.matrix_power(m + t * A, p)) for t in ts]
                fits[p] = np.polynomial.polynomial.polyfit(ts, vals, p)
            got = symrb.manakov_integrals(m, lam)
            want = np.array([fits[p][j] for p, j in order])
            cas = symrb.casimir_traces(m)
            want_c = np.array([fits[p][0] for p in (2, 4, 6)])
            scale = max(np.abs(want).max(), np.abs(want_c).max())
            worst = max(worst, float(np.abs(got - want).max() / scale))
            worst = max(worst, float(np.abs(cas - want_c).max() / scale))
    return worst


@S4.check(Level.FLOAT64, tol=1e-9)
def s4_conserved_on_reference_flow() -> float:
    """symrb.manakov_integrals along a trajectory of the reference rigid body field ($J^{-1}$ by a
    linear solve; DOP853, rtol 1e-12, $n = 4$, $t$ in $[0, 20]$): max drift relative to the values.
    """
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(6)
    k = 4
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    M0 = ref.random_skew(k, rng, 0.5)
    sol = solve_ivp(
        lambda _t, y: ref.rigid_body_field(np.eye(k), y.reshape(k, k), lam)[1].ravel(),
        (0, 20), M0.ravel(), method="DOP853", rtol=1e-12, atol=1e-12,
    )  # fmt: skip
    vals = symrb.manakov_integrals(sol.y.T.reshape(-1, k, k), lam)
    return float(np.max(np.abs(vals - vals[0]) / np.abs(vals[0])))


def _so_basis(k: int) -> list[np.ndarray]:
    """The basis E_ij - E_ji (i < j) of so(k)."""
    out = []
    for i, j in itertools.combinations(range(k), 2):
        E = np.zeros((k, k))
        E[i, j], E[j, i] = 1.0, -1.0
        out.append(E)
    return out


def _integral_gradients(k: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """At a random skew M and random Lambda (n = k): the gradients, in the basis of so(k), of every
    non-constant lambda-coefficient of the displayed tr((M + lambda Lambda^2)^p), p = 2..k (from
    the derivative p tr(X^(p-1) E) at p + 1 values of lambda and the Vandermonde solve), and of
    the Casimirs among them (the lambda^0 coefficients)."""
    lam_v, M_v = rng.uniform(0.5, 2.0, k), ref.random_skew(k, rng)
    lam_s, M_s = sp.symbols(f"l0:{k}"), sp.MatrixSymbol("M", k, k)
    lax = sp.lambdify([M_s, lam_s, _lp], explicit(LAX_MATRIX, {"M": sp.Matrix(M_s)}, lam_s))
    basis, rows, casimirs = _so_basis(k), [], []
    for p in range(2, k + 1):
        nodes = np.arange(1.0, p + 2)
        grads = []
        for node in nodes:
            Xp = np.linalg.matrix_power(np.array(lax(M_v, lam_v, node), dtype=float), p - 1)
            grads.append([p * np.trace(Xp @ E) for E in basis])
        coeffs = np.linalg.solve(np.vander(nodes, p + 1, increasing=True), np.array(grads))
        rows += list(coeffs[:p])  # the lambda^p coefficient is the constant tr(Lambda^(2p))
        casimirs.append(coeffs[0])
    return np.array(rows), np.array(casimirs)


def _rank(A: np.ndarray) -> tuple[int, bool]:
    """Numerical rank, and whether the singular values have a clear gap there (the kept ones
    above 1e-8 of the largest, the dropped ones below 1e-11)."""
    s = np.linalg.svd(A, compute_uv=False) / np.linalg.norm(A, 2)
    r = int((s > 1e-9).sum())
    return r, bool(s[r - 1] > 1e-8 and (r == len(s) or s[r] < 1e-11))


@S4.check(Level.FLOAT64)
def s4_number_of_independent_integrals() -> sp.Integer:
    r"""The paper's 'right number of integrals', counted: for $n = 3, \dots, 6$ at a random point,
    the rank of the gradients of all coefficients of the displayed generating trace is $m + r$ and
    that of the Casimirs $r$, with $r = \lfloor n/2 \rfloor$ the rank of $\mathfrak{so}(n)$ and $2m
    = n(n-1)/2 - r$ the dimension of a generic coadjoint orbit (2, 4, 6, 9 in all;
    Mishchenko-Fomenko). The number of $n$ for which a rank differs or the singular values show no
    clear gap."""
    rng = np.random.default_rng(4)
    bad = 0
    for k in range(3, 7):
        r = k // 2
        m = (k * (k - 1) // 2 - r) // 2
        (all_rank, gap_a), (cas_rank, gap_c) = (_rank(A) for A in _integral_gradients(k, rng))
        bad += int(all_rank != m + r or cas_rank != r or not (gap_a and gap_c))
    return sp.Integer(bad)


@S4.check(Level.SYMBOLIC_GENERAL_N)
def s4_discrete_lax_pair() -> sp.Expr:
    r"""Moser and Veselov's Lax form with parameter of the discrete rigid body: the displayed
    $(M_{k+1} + \lambda\Lambda^2)(\Omega_k - \lambda\Lambda)$ equals $(\Omega_k -
    \lambda\Lambda)(M_k + \lambda\Lambda^2)$ with $M_k$ the emitted mv2 momentum and $M_{k+1}$ the
    emitted mv3 transport of it, $\Omega_k$ orthogonal and $\Lambda$ symmetric (noncommutative,
    every $n$): left minus right reduces to 0 (so $\operatorname{tr}((M_k + \lambda\Lambda^2)^p)$
    does not depend on $k$)."""
    w = Words(symmetric=["Lambda"], orthogonal=["Omega"])
    Mk_v = MV_MOMENTUM["M"]
    env = {Mk: Mk_v, Mk1: MV_TRANSPORT["M_next"].xreplace({M: Mk_v}), Omk: Om}
    return w.is_zero(w.of(DISCRETE_LAX.lhs.xreplace(env)) - w.of(DISCRETE_LAX.rhs.xreplace(env)))


@S4.check(Level.FLOAT64, tol=1e-12)
def s4_discrete_flow_conserves_the_integrals() -> float:
    r"""The Moser-Veselov map conserves the integrals, as its Lax form says: symrb.engine.mv_flow
    ($n = 5$, random $\Lambda$ and $M_0$ with $|M_0| = 1$, $h = 0.05$, 1000 steps) against the
    emitted Manakov integrals (symrb.rigid_body.manakov_integrals): max over the six integrals of
    the drift relative to the integral's size."""
    import symrb

    rng = np.random.default_rng(41)
    lam = rng.uniform(0.5, 2.0, 5)
    M0 = ref.random_skew(5, rng)
    M0 /= np.linalg.norm(M0)
    sol = symrb.engine.mv_flow(ref.random_rotation(5, rng), M0, lam, 0.05, 1000, save_every=20)
    F = symrb.rigid_body.manakov_integrals(sol.y.M, lam)
    return float((np.abs(F - F[0]).max(axis=0) / np.abs(F[0])).max())


@S4.check(Level.SYMBOLIC_FIXED_N)
def s4_generalized_rigid_body_su3() -> sp.Integer:
    r"""Beyond $\mathrm{SO}(n)$, the paper's 'any semisimple Lie group', on $\mathfrak{su}(3)$
    (Mishchenko-Fomenko): with $a = i \operatorname{diag}(1, 3, -4)$, $b = i \operatorname{diag}(2,
    -1, 1/2)$ and $\Omega$ from $[a, \Omega] = [b, M]$ off the diagonal (0 on it), $\dot M = [M,
    \Omega]$ is the Lax equation with parameter $\frac{d}{dt}(M + \lambda a) = [M + \lambda a,
    \Omega + \lambda b]$ and the Lie-Poisson flow of $H = \frac12 \langle M, \Omega\rangle$ ($\nabla
    H = \Omega$); the non-constant $\lambda$-coefficients of $\operatorname{tr}((M + \lambda a)^p)$,
    $p = 2, 3$, and $H$ are conserved and pairwise in involution (symbolic $M$, 8 coordinates); at a
    rational point their gradients have rank $5 = (\dim + \mathrm{rank})/2$, the Casimirs' rank 2: 3
    integrals for the generic 6-dimensional orbits. The number of these that fail."""
    m = sp.symbols("m1:9", real=True)
    a, b = [sp.I * v for v in (1, 3, -4)], [sp.I * v for v in (2, -1, sp.Rational(1, 2))]
    A, B, M_ = sp.diag(*a), sp.diag(*b), su3.element(m)
    Om_ = su3.sectional_omega(M_, a, b)
    lam = sp.Symbol("lambda")
    Mdot = M_ * Om_ - Om_ * M_
    lax = Mdot - ((M_ + lam * A) * (Om_ + lam * B) - (Om_ + lam * B) * (M_ + lam * A))
    every, casimirs = su3.shifted_integrals(M_, A, m)
    H = su3.pairing(M_, Om_) / 2
    grads = [su3.gradient(F, m) for F in [*every, H]]
    bad = residual(lax) + residual(grads[-1] - Om_)
    bad += sum(int(not su3.poly_pairing(g, Mdot, m).is_zero) for g in grads)
    for gF, gG in itertools.combinations(grads, 2):
        bad += int(not su3.lie_poisson(M_, gF, gG, m).is_zero)
    rng = np.random.default_rng(43)
    point = {x: sp.Rational(int(rng.integers(-9, 10)), int(rng.integers(1, 7))) for x in m}
    rank_all, rank_cas = (
        sp.Matrix([[sp.diff(F, x).xreplace(point) for x in m] for F in Fs]).rank()
        for Fs in (every, casimirs)
    )
    return sp.Integer(bad + int(rank_all != 5) + int(rank_cas != 2))


# the paper's sentences
S4.sentence(
    r"We note that the dynamic rigid body equations on $\operatorname{SO}(n)$ and indeed on any "
    r"semisimple Lie group are integrable ([MiFo1976]).",
    s4_generalized_rigid_body_su3,
    s4_integrals_conserved,
    s4_integrals_in_involution,
    s4_number_of_independent_integrals,
)
S4.sentence(
    r"A key observation in this regard, due to Manakov, was that one could write the generalized "
    r"rigid body equations as Lax equations with parameter: $\frac{d}{dt}(M+\lambda \Lambda^2)= "
    r"[M+\lambda \Lambda^2,\Omega+\lambda \Lambda],$ where $M=J(\Omega)=\Lambda\Omega +\Omega "
    r"\Lambda$, as in §2.",
    s4_lax_pair_general_n,
)
S4.sentence(
    r"The nontrivial coefficients of $\lambda$ in the traces of the powers of $M+\lambda "
    r"\Lambda^2$ then yield the right number of independent integrals in involution to prove "
    r"integrability of the flow on a generic adjoint orbit of $\operatorname{SO}(n)$ (identified "
    r"with the corresponding coadjoint orbit).",
    s4_integrals_conserved,
    s4_integrals_conserved_exact,
    s4_integrals_in_involution,
    s4_coefficients_by_expansion,
    s4_symrb_integrals_pointwise,
    s4_conserved_on_reference_flow,
    s4_number_of_independent_integrals,
)
S4.sentence(
    r"Useful references are [Bogayavlenski1994] and [FeKo1995].)",
    kind="prose",
    reason="a citation",
)
S4.sentence(
    r"[MoVe1991] show that there is a corresponding formulation of the discrete rigid body "
    r"equations with parameter.",
    s4_discrete_lax_pair,
    s4_discrete_flow_conserves_the_integrals,
)
