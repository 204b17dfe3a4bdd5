"""S12 (Section 3.3, eqs. ``gln_symp``, ``ourHam``): the Hamiltonian form of the symmetric rigid
body on gl(n) x gl(n).

With the symplectic form 1/2 tr(eta_2^T xi_1 - eta_1^T xi_2) and the Hamiltonian
H = -1/8 tr(J^-1(M) M), Hamilton's equations are the symmetric rigid body equations, SO(n) x SO(n)
is invariant, and H = 1/4 <J^-1(M), M> is half the kinetic energy.

Emitted to ``symrb/_generated/symmetric_rigid_body.py``: ``gl_hamiltonian``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import SymplecticForm
from derivations.claims.section3._exact import count_nonzero
from derivations.claims.section3._inertia import ARG_LAM, lam_symbols
from derivations.claims.section3._symmetric import ARG_P, ARG_Q, MOMENTUM, M, P, Q
from derivations.claims.section3._words import ddt, jinv_letters
from derivations.claims.section3.s02_rigid_body_equations import J_explicit
from derivations.claims.section3.s05_maximum_principle import H_SYM, SYMMETRIC_RIGID_BODY_RHS
from derivations.registry import Level, claim
from derivations.symbolic import (
    Pair,
    Words,
    eq,
    explicit,
    general_matrix,
    hat3,
    pair,
    trace_residual,
    vee3,
)
from derivations.vocabulary import Jinv, Kernel, matrix

S12 = claim(
    "S12",
    label="gln_symp, ourHam",
    title="Hamiltonian form of the symmetric rigid body on $\\mathfrak{gl}(n) \\times "
    "\\mathfrak{gl}(n)$",
    statement="On $\\mathfrak{gl}(n)\\times\\mathfrak{gl}(n)$ with the symplectic form [[form]] "
    "and the Hamiltonian [[H]], Hamilton's equations [[hamilton]] for every $v$ are "
    "[[equations]], the symmetric rigid body equations; $SO(n)\\times SO(n)$ is invariant, and "
    "[[quarter]] with [[M]].",
    expected="holds",
    section="3.3",
    where="Section 3.3, the paragraph 'The Hamiltonian form of the symmetric rigid body "
    "equations': the third proposition (the symplectic form on $\\mathfrak{gl}(n) \\times "
    "\\mathfrak{gl}(n)$ and the Hamiltonian $H(\\xi, \\eta)$) and the remark $H = "
    "\\tfrac14\\langle J^{-1}M, M\\rangle$ after it",
    note="With the convention $\\Omega(X_H, \\cdot) = dH$ the equations are exactly the symmetric "
    "rigid body equations (the factor $\\tfrac12$ of the form and the $\\tfrac18$ of $H$ match); "
    "the opposite convention reverses time. $H$ is half the kinetic energy $\\tfrac12\\langle "
    "J^{-1}M, M\\rangle$, consistent with the cost $\\tfrac14\\langle U, J(U)\\rangle$ of S5. The "
    "symplectic form and $H$ are the paper's definitions: what is checked is what follows from "
    "them.",
)
_xi, _eta = matrix("xi"), matrix("eta")
_x1, _y1, _x2, _y2 = (matrix(s) for s in ("xi_1", "eta_1", "xi_2", "eta_2"))
FORM = S12.formula(
    "form", eq(SymplecticForm(_x1, _y1, _x2, _y2), sp.Trace(_y2.T * _x1 - _y1.T * _x2) / 2)
)
_XH, _v = sp.symbols("X_H v")
HAMILTON = S12.formula("hamilton", eq(sp.Function("Omega")(_XH, _v), sp.Function("dH")(_v)))

GL_HAMILTONIAN = Kernel(
    name="gl_hamiltonian",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_P, ARG_LAM],
    outputs={"H": -sp.Trace(Jinv(MOMENTUM) * MOMENTUM) / 8},
    doc="The Hamiltonian on gl(n) x gl(n) (paper, Section 3.3).\n\n"
    "H = -1/8 trace(J^{-1}(M) M) = 1/4 <J^{-1}(M), M>, M = Q^T P - P^T Q: half the kinetic\n"
    "energy of the rigid body with momentum M.",
    claims=("S12",),
)
_rename = {Q: _xi, P: _eta}
S12.formula("H", eq(H_SYM, GL_HAMILTONIAN.outputs["H"].xreplace(_rename)))
S12.formula(
    "equations",
    tuple(
        eq(matrix(d), SYMMETRIC_RIGID_BODY_RHS.outputs[o].xreplace(_rename))
        for d, o in (("xidot", "Qdot"), ("etadot", "Pdot"))
    ),
)
QUARTER = S12.formula("quarter", eq(H_SYM, Pair(Jinv(M), M) / 4))
S12.formula("M", eq(M, MOMENTUM.xreplace(_rename)))


def form_matrix(k: int) -> sp.Matrix:
    """The matrix of the displayed symplectic form on gl(k) x gl(k), coordinates (xi_11, xi_12,
    ..., eta_kk): entry (a, b) is the form on the a-th and b-th elementary pairs."""
    N = 2 * k * k
    basis = [_unflatten(k, [int(i == a) for i in range(N)]) for a in range(N)]
    return sp.Matrix(
        N, N,
        lambda a, b: explicit(FORM.rhs, {"xi_1": basis[a][0], "eta_1": basis[a][1],
                                         "xi_2": basis[b][0], "eta_2": basis[b][1]}),
    )  # fmt: skip


def _unflatten(k: int, vec: Sequence[sp.Expr]) -> tuple[sp.Matrix, sp.Matrix]:
    return sp.Matrix(k, k, list(vec[: k * k])), sp.Matrix(k, k, list(vec[k * k :]))


def hamilton_equations(k: int, convention: sp.Expr) -> tuple[sp.Matrix, ...]:
    """Solve Omega(X_H, v) = convention dH(v) for every v, with the displayed form and the emitted
    Hamiltonian (symbolic entries x_ij, y_ij and Lambda, n = k).  Returns (xidot, etadot) and the
    emitted symmetric rigid body field (Qdot, Pdot) at (Q, P) = (xi, eta)."""
    X, Y, lam = general_matrix("x", k), general_matrix("y", k), lam_symbols(k)
    coords = list(X) + list(Y)
    env = {"Q": X, "P": Y}
    H = explicit(GL_HAMILTONIAN["H"], env, lam)
    grad = sp.Matrix([sp.diff(H, c) for c in coords])
    # Omega(Z, v) = Z^T F v = convention dH(v) for every v:  F^T Z = convention grad H
    # (F is a matrix of numbers: invert it rather than eliminate with a symbolic right side)
    Xdot, Ydot = _unflatten(k, list(form_matrix(k).T.inv() * (convention * grad)))
    field = [explicit(SYMMETRIC_RIGID_BODY_RHS[o], env, lam) for o in ("Qdot", "Pdot")]
    return Xdot, Ydot, field[0], field[1]


@S12.check(Level.SYMBOLIC_FIXED_N)
def s12_hamilton_equations() -> sp.Integer:
    r"""Hamilton's equations from the displayed form (its Gram matrix on the elementary matrices, no
    coefficient assumed), the displayed convention and the emitted Hamiltonian, solved for $X_H$,
    against the emitted symmetric rigid body field (symbolic entries and $\Lambda$, $n = 3$):
    entries that differ."""
    convention, dH = HAMILTON.rhs.as_coeff_Mul()
    if dH.func.__name__ != "dH":
        raise ValueError("the convention is not a multiple of dH")
    Xdot, Ydot, Qdot_k, Pdot_k = hamilton_equations(3, convention)
    return count_nonzero(list(Xdot - Qdot_k) + list(Ydot - Pdot_k))


@S12.check(Level.SYMBOLIC_GENERAL_N)
def s12_SO_invariant_general_n() -> sp.Integer:
    r"""Noncommutative $Q$, $P$ (any $n$), emitted field with $J^{-1}(M)$ a skew letter $U$:
    $\frac{d}{dt}(Q^T Q - I)$ equals $[Q^T Q - I, U]$, a linear homogeneous equation, so $Q^T Q = I$
    is invariant; likewise for $P$."""
    w = Words(skew=["U"])
    rates = {
        o[0]: w.of(jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, {"U": Jinv(MOMENTUM)}))
        for o in ("Qdot", "Pdot")
    }
    Uw = w("U")
    total = sp.Integer(0)
    for name in ("Q", "P"):
        X = w(name)
        G = w.T(X) * X - 1
        total += w.is_zero(ddt(w, G, rates) - (G * Uw - Uw * G))
    return total


@S12.check(Level.SYMBOLIC_GENERAL_N)
def s12_quarter_energy_general_n() -> sp.Integer:
    r"""The emitted Hamiltonian minus the displayed $\frac14 \langle J^{-1}(M), M\rangle$ (pairing
    $-\frac12 \operatorname{tr}$), with $J^{-1}(M)$ a letter, as trace words in noncommutative $Q$,
    $P$ (any $n$): no word remains."""
    w = Words()
    letters = {"V": Jinv(MOMENTUM)}
    emitted = jinv_letters(GL_HAMILTONIAN["H"], w, letters)
    quarter = jinv_letters(QUARTER.rhs.xreplace({M: MOMENTUM}).doit(), w, letters)
    return trace_residual(w.trace_argument(emitted) - w.trace_argument(quarter))


@S12.check(Level.FLOAT64, tol=1e-13)
def s12_symrb_pointwise() -> float:
    r"""symrb.symmetric.gl_hamiltonian against $\frac14 \langle J^{-1}(M), M\rangle$ and
    symrb.symmetric.symmetric_rigid_body_rhs against the reference field, $J^{-1}$ by the reference
    linear solve, $M = Q^T P - P^T Q$ in NumPy, $n = 2, \dots, 6$, batches of 20 random ($Q$ in
    $\mathrm{SO}(n)$, $P$ in $\mathfrak{gl}(n)$): max difference relative to the reference values'
    size."""
    import symrb

    rng = np.random.default_rng(12)
    errs = []
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        Qs = np.stack([ref.random_rotation(k, rng) for _ in range(20)])
        Ps = rng.standard_normal((20, k, k))
        Ms = np.swapaxes(Qs, -1, -2) @ Ps - np.swapaxes(Ps, -1, -2) @ Qs
        want_H = 0.25 * ref.pairing(ref.J_inv(Ms, lam), Ms)
        errs.append(
            np.abs(symrb.symmetric.gl_hamiltonian(Qs, Ps, lam) - want_H).max() / want_H.max()
        )
        for got, want in zip(
            symrb.symmetric.symmetric_rigid_body_rhs(Qs, Ps, lam),
            ref.symmetric_field(Qs, Ps, lam),
            strict=True,
        ):
            errs.append(np.abs(got - want).max() / np.abs(want).max())
    return float(np.max(errs))


def _cayley_chart(q: sp.Matrix, d: sp.Matrix) -> tuple[tuple[sp.Matrix, sp.Matrix], list]:
    """Q = (I - X)^-1 (I + X), X = hat(q)/2, and the columns a_k = vee(Q^T dQ/dq_k) of the map
    qdot -> omega, each as (value at q, derivative along d) (exact, n = 3)."""
    eye = sp.eye(3)
    X0, X1 = hat3(q) / 2, hat3(d) / 2
    R0 = (eye - X0).inv()
    R1 = R0 * X1 * R0
    Q0, Q1 = R0 * (eye + X0), R1 * (eye + X0) + R0 * X1
    cols = []
    for k in range(3):
        E = hat3(sp.eye(3)[:, k]) / 2
        D0, D1 = R0 * E * (eye + Q0), R1 * E * (eye + Q0) + R0 * E * Q1
        cols.append((vee3(Q0.T * D0), vee3(Q1.T * D0 + Q0.T * D1)))
    return (Q0, Q1), cols


def _gram(A: sp.Matrix, B: sp.Matrix, lam: list[sp.Expr]) -> sp.Matrix:
    """<hat(a_k), J hat(b_m)> for the columns of A and B (pairing of S1, displayed J)."""
    return sp.Matrix(3, 3, lambda k, m: pair(hat3(A[:, k]), J_explicit(hat3(B[:, m]), lam)))


def _canonical_rates(q: sp.Matrix, p: sp.Matrix, lam: list[sp.Expr]) -> sp.Matrix:
    """In the Cayley chart of SO(3) with canonical momenta p, the Legendre transform of the
    Lagrangian 1/2 <Omega, J Omega> gives H = 1/2 p^T G^-1 p; returns the residuals of Qdot =
    Q Omega and Mdot = [M, Omega] along Hamilton's equations qdot = dH/dp, pdot = -dH/dq, with
    Omega = hat(A G^-1 p) and M = J(Omega) (derivatives by first-order dual numbers)."""
    parts = []
    for j in range(3):
        (Q0, Q1), cols = _cayley_chart(q, sp.eye(3)[:, j])
        A0 = sp.Matrix.hstack(*[c[0] for c in cols])
        A1 = sp.Matrix.hstack(*[c[1] for c in cols])
        G0 = _gram(A0, A0, lam)
        G1 = _gram(A1, A0, lam) + _gram(A0, A1, lam)
        Gi0 = G0.inv()
        Gi1 = -Gi0 * G1 * Gi0
        parts.append((Q0, Q1, A0, A1, Gi0, Gi1))
    Q0, _, A0, _, Gi0, _ = parts[0]
    qdot = Gi0 * p
    pdot = sp.Matrix([-(p.T * part[5] * p)[0] / 2 for part in parts])
    Om = hat3(A0 * Gi0 * p)
    M = J_explicit(Om, lam)
    Mdot = J_explicit(hat3(A0 * Gi0 * pdot), lam)
    Qdot = sp.zeros(3, 3)
    for j, (_, Q1, _, A1, _, Gi1) in enumerate(parts):
        Mdot += qdot[j] * J_explicit(hat3(A1 * Gi0 * p + A0 * Gi1 * p), lam)
        Qdot += qdot[j] * Q1
    return sp.Matrix.vstack(Qdot - Q0 * Om, Mdot - (M * Om - Om * M))


def _rational(rng: np.random.Generator) -> sp.Rational:
    return sp.Rational(int(rng.integers(-9, 10)), int(rng.integers(1, 7)))


@S12.check(Level.EXACT_RATIONAL)
def s12_classical_canonical() -> sp.Integer:
    r"""The classical rigid body is Hamiltonian on $T^*\mathrm{SO}(n)$ for the canonical symplectic
    structure ($n = 3$, in a chart): with $Q = (I - X)^{-1} (I + X)$, $X = \hat q/2$, canonical
    momenta $p$ conjugate to $q$ and $H(q, p)$ the Legendre transform of $\frac12 \langle \Omega,
    J\Omega\rangle$ (pairing of S1, displayed $J$), Hamilton's equations $\dot q = \partial
    H/\partial p$, $\dot p = -\partial H/\partial q$ give $\dot Q = Q\Omega$ and $\dot M = [M,
    \Omega]$ with $M = J(\Omega)$, at 3 random rational $(q, p)$ and rational $\Lambda$ (exact). The
    number of entries that are not 0."""
    rng = np.random.default_rng(12)
    lam = [sp.Rational(5, 10), sp.Rational(8, 10), sp.Rational(14, 10)]
    bad = 0
    for _ in range(3):
        q, p = (sp.Matrix(3, 1, lambda i, _: _rational(rng)) for _ in range(2))
        bad += sum(1 for e in _canonical_rates(q, p, lam) if e != 0)
    return sp.Integer(bad)


# the paper's sentences
S12.sentence(
    r"Recall that the classical rigid body equations are Hamiltonian on $T^*\operatorname{SO}(n)$ "
    r"with respect to the canonical symplectic structure on the cotangent bundle of "
    r"$\operatorname{SO}(n)$.",
    s12_classical_canonical,
)
S12.sentence(
    r"The following result gives the corresponding theorem for the symmetric case.",
    kind="prose",
    reason="announces the proposition",
)
S12.sentence(
    r"The proof is given in [BlCrMaRa2002]",
    kind="prose",
    reason="a citation",
)
S12.sentence(
    r"Consider the Hamiltonian system on the symplectic vector space $\mathfrak{gl}(n) \times "
    r"\mathfrak{gl}(n)$ with the symplectic structure $\Omega_{\mathfrak{gl}(n)} (\xi_1, \eta_1, "
    r"\xi_2, \eta_2 ) = \frac{1}{2} \operatorname{trace} ( \eta_2^T \xi_1 - \eta_1^T \xi_2 )$ "
    r"where $(\xi_i,\eta_i)\,,i=1,2$ are elements of $\mathfrak{gl}(n) \times \mathfrak{gl}(n)$ "
    r"and Hamiltonian $H ( \xi, \eta ) = - \frac{1}{8} \operatorname{trace} \left[ \left( "
    r"J^{-1}(\xi^T \eta -\eta^T \xi ) \right) \left( \xi^T\eta - \eta^T \xi \right) \right] .$",
    s12_hamilton_equations,
    s12_symrb_pointwise,
)
S12.sentence(
    r"The corresponding Hamiltonian system leaves $\operatorname{SO}(n) \times "
    r"\operatorname{SO}(n)$ invariant and induces on it, the flow of the symmetric representation "
    r"of the rigid body system.",
    s12_hamilton_equations,
    s12_SO_invariant_general_n,
    s12_symrb_pointwise,
)
S12.sentence(
    r"Note that the above Hamiltonian is equivalent to the standard rigid body Hamiltonian $H="
    r"\frac{1}{4} \left\langle J^{-1}M,M\right\rangle$, as in [Ratiu1980].",
    s12_quarter_energy_general_n,
    s12_symrb_pointwise,
)
