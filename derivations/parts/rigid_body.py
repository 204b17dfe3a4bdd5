r"""The classical n-dimensional rigid body (paper, Section 3.1): claims S1-S4.

Derived here:

* S1: the pairing :math:`-\tfrac12\operatorname{tr}(\hat u\hat v) = u\cdot v` and :math:`\hat u v = u\times v`;
* S2: :math:`J` is symmetric for the pairing, :math:`\langle\Omega, J\Omega\rangle =
  \sum_{i<j}(\lambda_i+\lambda_j)\Omega_{ij}^2` (positive iff all :math:`\lambda_i+\lambda_j>0`),
  for n = 3 the moments :math:`I_1=\lambda_2+\lambda_3` (cyclic) and Euler's equations;
* S3: :math:`\dot M=[M,\Omega]` is the Euler-Poincare equation of :math:`l(\Omega)=\tfrac12\langle
  \Omega,J\Omega\rangle`: :math:`\delta l/\delta\Omega = J\Omega` and
  :math:`\operatorname{ad}^*_\Omega\mu = [\mu,\Omega]` for this pairing;
* S4: Manakov's Lax pair with parameter, for every n with noncommutative symbols, and the
  conservation and involution of the coefficients of :math:`\operatorname{tr}(M+\lambda\Lambda^2)^k`.

Emitted (``symrb/_generated/rigid_body.py``): the rigid body vector field, the kinetic energy, the
Casimir traces, Manakov's integrals (general n, matrix level) and Euler's equations for n = 3
(component level, through CSE).
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

from derivations.codegen import Arg, Kernel, aux, n
from derivations.registry import Claim, Evidence, Level
from derivations.symbolic import (
    comm,
    diag_matrix,
    hat3,
    pair,
    residual,
    skew_gradient,
    skew_matrix,
    sym_vector,
    trace_words,
    vee3,
)

# ---------------------------------------------------------------------------------------------
# S1: pairing and hat map


def s1_pairing_is_dot() -> sp.Expr:
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    return residual(pair(hat3(u), hat3(v)) - u.dot(v))


def s1_hat_is_cross() -> sp.Expr:
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    return residual(hat3(u) * v - u.cross(v))


# ---------------------------------------------------------------------------------------------
# S2: rigid body equations, J symmetric positive definite, n = 3 moments


def _J(Om: sp.Matrix, L: sp.Matrix) -> sp.Matrix:
    return L * Om + Om * L


def s2_J_symmetric(nn: int = 4) -> sp.Expr:
    L = diag_matrix("lam", nn, positive=False)
    a, b = skew_matrix("a", nn), skew_matrix("b", nn)
    return residual(pair(_J(a, L), b) - pair(a, _J(b, L)))


def s2_J_quadratic_form(nn: int = 4) -> sp.Expr:
    """<Om, J Om> = sum_{i<j} (lam_i + lam_j) Om_ij^2: positive definite iff all lam_i+lam_j > 0."""
    L = diag_matrix("lam", nn, positive=False)
    Om = skew_matrix("w", nn)
    form = sum(
        ((L[i, i] + L[j, j]) * Om[i, j] ** 2 for i, j in itertools.combinations(range(nn), 2)),
        sp.Integer(0),
    )
    return residual(pair(Om, _J(Om, L)) - form)


def s2_moments_n3() -> sp.Expr:
    """For n = 3: 1/2 <Om, J Om> = 1/2 sum I_i w_i^2 with I_1 = lam2 + lam3 (cyclic)."""
    L = diag_matrix("lam", 3, positive=False)
    w = sym_vector("w", 3)
    l1, l2, l3 = L[0, 0], L[1, 1], L[2, 2]
    moments = [l2 + l3, l3 + l1, l1 + l2]
    kinetic = sum((Ii * wi**2 for Ii, wi in zip(moments, w, strict=True)), sp.Integer(0)) / 2
    return residual(pair(hat3(w), _J(hat3(w), L)) / 2 - kinetic)


def s2_euler_equations_n3() -> sp.Expr:
    """For n = 3, M = J(hat w) = hat(I w) and vee([M, Om]) = (I w) x w: Euler's equations."""
    L = diag_matrix("lam", 3, positive=False)
    w = sym_vector("w", 3)
    l1, l2, l3 = L[0, 0], L[1, 1], L[2, 2]
    Iw = sp.Matrix([(l2 + l3) * w[0], (l3 + l1) * w[1], (l1 + l2) * w[2]])
    Om = hat3(w)
    M = _J(Om, L)
    return residual(M - hat3(Iw)) + residual(vee3(comm(M, Om)) - Iw.cross(w))


def s2_flow_preserves_skew_and_SO() -> float:
    """float64: the generated vector field keeps M skew and Q in SO(n) along a trajectory (n=5)."""
    from scipy.integrate import solve_ivp

    from symrb._generated.rigid_body import rigid_body_rhs

    rng = np.random.default_rng(1)
    nn = 5
    lam = np.sort(rng.uniform(0.5, 2.0, nn))
    a = rng.standard_normal((nn, nn))
    M0 = a - a.T
    Q0 = np.linalg.qr(rng.standard_normal((nn, nn)))[0]
    Q0 = Q0 * np.sign(np.linalg.det(Q0))

    def f(_t, y):
        Q, M = y[: nn * nn].reshape(nn, nn), y[nn * nn :].reshape(nn, nn)
        dQ, dM = rigid_body_rhs(Q, M, lam)
        return np.concatenate([dQ.ravel(), dM.ravel()])

    sol = solve_ivp(f, (0, 5), np.concatenate([Q0.ravel(), M0.ravel()]), rtol=1e-12, atol=1e-12)
    Q, M = sol.y[: nn * nn, -1].reshape(nn, nn), sol.y[nn * nn :, -1].reshape(nn, nn)
    return float(max(np.abs(M + M.T).max(), np.abs(Q.T @ Q - np.eye(nn)).max()))


# ---------------------------------------------------------------------------------------------
# S3: Euler-Poincare


def s3_variational_derivative(nn: int = 4) -> sp.Expr:
    """d/de l(Om + e eta)|_0 = <J Om, eta>: the functional derivative of l is M = J(Om)."""
    L = diag_matrix("lam", nn, positive=False)
    Om, eta = skew_matrix("w", nn), skew_matrix("e", nn)
    eps = sp.Symbol("epsilon")
    lag = pair(Om + eps * eta, _J(Om + eps * eta, L)) / 2
    return residual(sp.diff(lag, eps).subs(eps, 0) - pair(_J(Om, L), eta))


def s3_coadjoint(nn: int = 4) -> sp.Expr:
    """<mu, [xi, eta]> = <[mu, xi], eta>: ad*_xi mu = [mu, xi], so EP reads Mdot = [M, Om]."""
    mu, xi, eta = skew_matrix("m", nn), skew_matrix("x", nn), skew_matrix("e", nn)
    return residual(pair(mu, comm(xi, eta)) - pair(comm(mu, xi), eta))


# ---------------------------------------------------------------------------------------------
# S4: Manakov's Lax pair with parameter


def s4_lax_pair_general_n() -> sp.Expr:
    """With L (= Lambda) and Om noncommutative and M = L Om + Om L (any n):
    d/dt (M + l L^2) - [M + l L^2, Om + l L] = 0, where d/dt M = [M, Om] and L is constant."""
    L, Om = sp.symbols("L Omega", commutative=False)
    lam = sp.Symbol("lambda")
    M = L * Om + Om * L
    Mdot = M * Om - Om * M
    lhs = Mdot  # d/dt (M + lambda L^2) with L constant
    rhs = (M + lam * L**2) * (Om + lam * L) - (Om + lam * L) * (M + lam * L**2)
    return sp.Integer(0) if sp.expand(lhs - rhs) == 0 else sp.Integer(1)


def manakov_words(kmax: int = 5) -> list[tuple[int, int, dict[tuple[str, ...], sp.Expr]]]:
    """Non-trivial coefficients of lambda^j in trace((M + lambda A)^k), A = Lambda^2, 2 <= k <= kmax.

    Words with an odd number of M's vanish (M skew, A symmetric), j = k is the constant
    trace(A^k).  Returns (k, j, {word: integer coefficient}).
    """
    lam = sp.Symbol("lambda")
    out = []
    for k in range(2, kmax + 1):
        coeffs = trace_words({"M": sp.Integer(1), "A": lam}, k, lam, {"M": -1, "A": 1})
        for j, words in coeffs.items():
            if j == k:
                continue
            out.append((k, j, words))
    return out


def _manakov_explicit(nn: int, kmax: int) -> tuple[sp.Matrix, sp.Matrix, list[sp.Expr]]:
    M = skew_matrix("m", nn)
    L = diag_matrix("lam", nn)
    A = L * L
    mats = {"M": M, "A": A}
    integrals = []
    for _k, _j, words in manakov_words(kmax):
        total = sp.Integer(0)
        for word, c in words.items():
            prod = sp.eye(nn)
            for letter in word:
                prod = prod * mats[letter]
            total += c * prod.trace()
        integrals.append(sp.expand(total))
    return M, L, integrals


def s4_integrals_conserved(nn: int = 4, kmax: int = 4) -> sp.Expr:
    """d/dt F(M) = <grad F, [M, J^-1 M]> = 0 for every Manakov integral F (symbolic, fixed n)."""
    M, L, integrals = _manakov_explicit(nn, kmax)
    Om = sp.Matrix(nn, nn, lambda i, j: M[i, j] / (L[i, i] + L[j, j]) if i != j else 0)
    Mdot = comm(M, Om)
    total = sp.Integer(0)
    for F in integrals:
        total += residual(sp.together(pair(skew_gradient(F, M), Mdot)))
    return total


def s4_integrals_in_involution(nn: int = 4, kmax: int = 4) -> sp.Expr:
    """Lie-Poisson brackets {F, G}(M) = -<M, [grad F, grad G]> of the Manakov integrals vanish."""
    M, _L, integrals = _manakov_explicit(nn, kmax)
    grads = [skew_gradient(F, M) for F in integrals]
    total = sp.Integer(0)
    for a, b in itertools.combinations(range(len(grads)), 2):
        total += residual(pair(M, comm(grads[a], grads[b])))
    return total


def s4_trajectory_drift() -> float:
    """float64: relative drift of Manakov's integrals over t in [0, 20] (n = 4, rtol = 1e-12)."""
    from scipy.integrate import solve_ivp

    from symrb._generated.rigid_body import manakov_integrals, rigid_body_rhs

    rng = np.random.default_rng(4)
    nn = 4
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    a = rng.standard_normal((nn, nn))
    M0 = a - a.T

    def f(_t, y):
        M = y.reshape(nn, nn)
        return rigid_body_rhs(np.eye(nn), M, lam)[1].ravel()

    sol = solve_ivp(f, (0, 20), M0.ravel(), method="DOP853", rtol=1e-12, atol=1e-12)
    Ms = sol.y.T.reshape(-1, nn, nn)
    vals = manakov_integrals(Ms, lam)
    scale = np.abs(vals[0]) + 1e-300
    return float(np.max(np.abs(vals - vals[0]) / scale))


# ---------------------------------------------------------------------------------------------

CLAIMS = [
    Claim(
        id="S1",
        label="killing.eqn",
        title="Pairing on so(n) agrees with the dot product of R^3",
        statement=r"$\langle\xi,\eta\rangle=-\tfrac12\operatorname{tr}(\xi\eta)$; for $n=3$, "
        r"$\langle\hat u,\hat v\rangle = u\cdot v$ where $\hat u v = u\times v$.",
        expected="holds",
        section="3.1",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "-1/2 tr(hat u hat v) - u.v expands to 0 (n = 3)",
                s1_pairing_is_dot,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N, "hat(u) v - u x v expands to 0 (n = 3)", s1_hat_is_cross
            ),
        ),
    ),
    Claim(
        id="S2",
        label="rbl",
        title="Rigid body equations; J symmetric positive definite; n = 3 moments",
        statement=r"$\dot Q=Q\Omega$, $\dot M=[M,\Omega]$, $M=J(\Omega)=\Lambda\Omega+\Omega\Lambda$; "
        r"$J$ is symmetric for the pairing and positive definite when $\Lambda_i+\Lambda_j>0$; "
        r"for $n=3$, $I_1=\Lambda_2+\Lambda_3$ and cyclic.",
        expected="holds",
        section="3.1",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "<J a, b> = <a, J b> for symbolic skew a, b (n = 4)",
                s2_J_symmetric,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "<Om, J Om> = sum_{i<j} (lam_i + lam_j) Om_ij^2 (n = 4)",
                s2_J_quadratic_form,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "1/2 <Om, J Om> = 1/2 sum I_i w_i^2, I_1 = lam2 + lam3 (n = 3)",
                s2_moments_n3,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "J(hat w) = hat(I w) and vee[M, Om] = (I w) x w: Euler's equations (n = 3)",
                s2_euler_equations_n3,
            ),
            Evidence(
                Level.FLOAT64,
                "generated field keeps M skew and Q orthogonal, t in [0, 5], n = 5",
                s2_flow_preserves_skew_and_SO,
                tol=1e-9,
            ),
        ),
    ),
    Claim(
        id="S3",
        label="RBLag_group.eqn",
        title="Mdot = [M, Omega] is Euler-Poincare for l(Omega) = 1/2 <Omega, J Omega>",
        statement=r"$\delta l/\delta\Omega = J(\Omega)=M$ and $\operatorname{ad}^*_\Omega M=[M,\Omega]$ "
        r"for $\langle\cdot,\cdot\rangle=-\tfrac12\operatorname{tr}$, so "
        r"$\tfrac{d}{dt}\tfrac{\delta l}{\delta\Omega}=\operatorname{ad}^*_\Omega\tfrac{\delta l}{\delta\Omega}$ "
        r"reads $\dot M=[M,\Omega]$.",
        expected="holds",
        section="3.1",
        evidence=(
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "d/de l(Om + e eta) at 0 equals <J Om, eta> (n = 4)",
                s3_variational_derivative,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N, "<mu, [xi, eta]> = <[mu, xi], eta> (n = 4)", s3_coadjoint
            ),
        ),
    ),
    Claim(
        id="S4",
        label="lambda_eqn",
        title="Manakov's Lax equation with parameter and its integrals",
        statement=r"$\tfrac{d}{dt}(M+\lambda\Lambda^2)=[M+\lambda\Lambda^2,\Omega+\lambda\Lambda]$; the "
        r"coefficients of $\lambda$ in $\operatorname{tr}(M+\lambda\Lambda^2)^k$ are conserved and in involution.",
        expected="holds",
        section="3.1",
        evidence=(
            Evidence(
                Level.SYMBOLIC_GENERAL_N,
                "noncommutative L, Om, M = L Om + Om L: Mdot - [M + l L^2, Om + l L] expands to 0",
                s4_lax_pair_general_n,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "d/dt of every coefficient of tr(M + l Lam^2)^k, k <= 4, vanishes on the flow (n = 4)",
                s4_integrals_conserved,
            ),
            Evidence(
                Level.SYMBOLIC_FIXED_N,
                "Lie-Poisson brackets of those coefficients vanish pairwise (n = 4)",
                s4_integrals_in_involution,
            ),
            Evidence(
                Level.FLOAT64,
                "relative drift of generated manakov_integrals along a DOP853 trajectory (n = 4, t <= 20)",
                s4_trajectory_drift,
                tol=1e-8,
            ),
        ),
    ),
]


# ---------------------------------------------------------------------------------------------
# code emission


def _word_to_matexpr(word: tuple[str, ...], mats: dict[str, sp.MatrixExpr]) -> sp.MatrixExpr:
    return sp.MatMul(*[mats[x] for x in word])


def emit() -> tuple[str, list[Kernel]]:
    Q = sp.MatrixSymbol("Q", n, n)
    M = sp.MatrixSymbol("M", n, n)
    W, Lam2 = aux("W"), aux("Lam2")
    Omega = sp.HadamardProduct(W, M)  # J^{-1}(M)
    Om = sp.MatrixSymbol("Omega", n, n)
    arg_Q = Arg("Q", "(..., n, n)", "attitude, in SO(n)")
    arg_M = Arg("M", "(..., n, n)", "body angular momentum, skew")
    arg_lam = Arg("lam", "(..., n)", "diagonal of Lambda, lam_i + lam_j > 0")

    kernels = [
        Kernel(
            name="rigid_body_rhs",
            args=[arg_Q, arg_M, arg_lam],
            intermediates={"Omega": Omega},
            outputs={"Qdot": Q * Om, "Mdot": M * Om - Om * M},
            doc=r"Rigid body vector field (paper, eq. rbl): Omega = J^{-1}(M), Qdot = Q Omega, "
            r"Mdot = [M, Omega].",
        ),
        Kernel(
            name="kinetic_energy",
            args=[arg_M, arg_lam],
            outputs={"E": -sp.Rational(1, 4) * sp.Trace(sp.HadamardProduct(W, M) * M)},
            doc=r"Kinetic energy 1/2 <J^{-1} M, M> = -1/4 trace(J^{-1}(M) M).",
        ),
        Kernel(
            name="casimir_traces",
            args=[arg_M],
            outputs={f"tr_M{k}": sp.Trace(sp.MatPow(M, k)) for k in (2, 4, 6)},
            stack=True,
            doc=r"Casimirs of so(n): trace(M^2), trace(M^4), trace(M^6) (odd powers vanish).",
        ),
    ]
    mats = {"M": M, "A": Lam2}
    integrals = {}
    lines = []
    for k, j, words in manakov_words(5):
        expr = sp.Add(*[c * sp.Trace(_word_to_matexpr(w, mats)) for w, c in words.items()])
        integrals[f"k{k}_j{j}"] = expr
        desc = " + ".join(f"{c} tr({''.join(w)})" for w, c in words.items())
        lines.append(f"    k={k}, lambda^{j}: {desc}")
    kernels.append(
        Kernel(
            name="manakov_integrals",
            args=[arg_M, arg_lam],
            outputs=integrals,
            stack=True,
            doc="Manakov's integrals: the non-trivial coefficients of lambda^j in "
            "trace((M + lambda Lambda^2)^k), 2 <= k <= 5, with A = Lambda^2, in this order:\n"
            + "\n".join(lines),
        )
    )
    # Euler's equations for n = 3 in components, through CSE
    m = sym_vector("m", 3)
    lam = sym_vector("l", 3)
    L = sp.diag(*lam)
    Mh = hat3(m)
    Omh = sp.Matrix(3, 3, lambda i, j: Mh[i, j] / (L[i, i] + L[j, j]) if i != j else 0)
    mdot = vee3(comm(Mh, Omh))
    kernels.append(
        Kernel(
            name="euler_rhs_so3",
            args=[
                Arg("m", "(..., 3)", "body angular momentum vector, M = hat(m)"),
                Arg("lam", "(..., 3)", "diagonal of Lambda"),
            ],
            outputs={f"mdot{i + 1}": sp.simplify(mdot[i]) for i in range(3)},
            stack=True,
            components={"m": m, "lam": lam},
            doc="Euler's equations for n = 3: mdot = m x omega with omega_i = m_i / I_i, "
            "I_1 = lam_2 + lam_3 (cyclic).",
        )
    )
    return "rigid_body", kernels
