"""S2 (Section 3.1, eq. ``rbl``): the rigid body equations, the inertia operator J and the moments
of inertia for n = 3.

The paper's rigid body is Qdot = Q Omega, Mdot = [M, Omega] with M = J(Omega) = Lambda Omega +
Omega Lambda; J is symmetric for the pairing of S1 and positive definite when lam_i + lam_j > 0,
and for n = 3 the moments are I_1 = lam_2 + lam_3 (cyclic).  The equations are definitions: what
is checked is that the emitted field computes Omega = J^-1(M) and returns exactly these right-hand
sides, that Euler's equations emitted for n = 3 are its components, and that symrb's field, its
inertia operators and its flow agree with independent references.

Emitted to ``symrb/_generated/rigid_body.py``: ``rigid_body_rhs`` and ``euler_rhs_so3`` (derived
from the matrix field at M = hat(m)).  S3 and S4 read J, Mdot and the field from here.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._inertia import ARG_LAM, lam_symbols
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Pair,
    Words,
    eq,
    explicit,
    hat3,
    lhs_minus_rhs,
    residual,
    skew_matrix,
    sym_vector,
    trace_words_of,
    vee3,
)
from derivations.vocabulary import Arg, Jinv, Kernel, Lam, matrix, n

Q, M, Om = matrix("Q"), matrix("M"), matrix("Omega")
ARG_Q = Arg("Q", "(..., n, n)", "attitude, in SO(n)")
ARG_M = Arg("M", "(..., n, n)", "body angular momentum, skew")


S2 = claim(
    "S2",
    label="rbl",
    title="Rigid body equations; $J$ symmetric positive definite; moments of inertia for $n = 3$",
    statement="[[Qdot]], [[Mdot]], [[J]]; $J$ is symmetric for the pairing, [[J_symmetric]], and "
    "positive definite when [[positive]] for every pair of distinct indices $i$, $j$; for $n=3$, "
    "[[moment]] and cyclic.",
    expected="holds",
    section="3.1",
    where="Section 3.1, the rigid body equations $\\dot Q = Q\\Omega$, $\\dot M = [M, \\Omega]$ "
    "and the paragraph after them ($M = J(\\Omega) = \\Lambda\\Omega + \\Omega\\Lambda$, "
    "$\\Lambda_i + \\Lambda_j > 0$, $I_1 = \\Lambda_2 + \\Lambda_3$)",
    note="The equations are the definitions of the flow; what is checked is that the emitted "
    "field computes $\\Omega$ with $J(\\Omega) = M$ and returns exactly these right-hand sides, "
    "and that symrb's field and its flow agree with independent references (an $n^2 \\times n^2$ "
    "linear solve for $J^{-1}$, and the Jacobi elliptic solution for $n = 3$).",
)
QDOT = S2.formula("Qdot", eq(matrix("Qdot"), Q * Om))
MDOT = S2.formula("Mdot", eq(matrix("Mdot"), Bracket(M, Om)))
J_DEF = S2.formula("J", eq(M, Lam * Om + Om * Lam))
_a, _b = matrix("a"), matrix("b")
S2.formula(
    "J_symmetric",
    eq(Pair(J_DEF.rhs.xreplace({Om: _a}), _b), Pair(_a, J_DEF.rhs.xreplace({Om: _b}))),
)
_li, _lj = sp.symbols("Lambda_i Lambda_j", real=True)
POSITIVE = S2.formula("positive", sp.Gt(_li + _lj, 0))
_I1, _l1, _l2, _l3 = sp.symbols("I_1 Lambda_1 Lambda_2 Lambda_3", real=True)
MOMENT = S2.formula("moment", eq(_I1, _l2 + _l3))


def _moments(lam: Sequence[sp.Expr]) -> list[sp.Expr]:
    """The displayed I_1 and its cyclic permutations I_2, I_3 at the diagonal ``lam`` (n = 3)."""
    return [
        MOMENT.rhs.subs({_l1: lam[c[0]], _l2: lam[c[1]], _l3: lam[c[2]]}, simultaneous=True)
        for c in ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    ]


RIGID_BODY_RHS = Kernel(
    name="rigid_body_rhs",
    target="rigid_body",
    args=[ARG_Q, ARG_M, ARG_LAM],
    outputs={"Qdot": Q * Jinv(M), "Mdot": M * Jinv(M) - Jinv(M) * M},
    doc="Rigid body vector field (paper, Section 3.1).\n\n"
    "Qdot = Q Omega, Mdot = [M, Omega], Omega = J^{-1}(M), J^{-1}(M)_ij = M_ij / (lam_i + lam_j).",
    claims=("S2",),
)


def J_explicit(X: sp.Matrix, lam: list[sp.Expr]) -> sp.Matrix:
    """The right side of the displayed definition of J, on an explicit matrix."""
    return explicit(J_DEF.rhs, {"Omega": X}, lam)


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_emitted_field() -> sp.Expr:
    r"""The emitted field at $Q = I$: its $\Omega = \dot Q$ satisfies the displayed $J(\Omega) = M$,
    and its $\dot M$ equals the displayed $[M, \Omega]$ (symbolic skew $M$, $n = 4$)."""
    lam, Ms = lam_symbols(4), skew_matrix("m", 4)
    env = {"Q": sp.eye(4), "M": Ms}
    Omega = explicit(RIGID_BODY_RHS["Qdot"], env, lam)
    Mdot = explicit(RIGID_BODY_RHS["Mdot"], env, lam)
    r = residual(sp.simplify(J_explicit(Omega, lam) - Ms))
    r += residual(sp.simplify(Mdot - explicit(MDOT.rhs, {"M": Ms, "Omega": Omega})))
    # and Qdot is Q Omega for a general Q (the displayed first equation)
    Qs = sp.Matrix(4, 4, lambda i, j: sp.Symbol(f"q{i}{j}"))
    Qdot = explicit(RIGID_BODY_RHS["Qdot"], {"Q": Qs, "M": Ms}, lam)
    return r + residual(sp.simplify(Qdot - explicit(QDOT.rhs, {"Q": Qs, "Omega": Omega})))


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_J_symmetric() -> sp.Expr:
    r"""The displayed symmetry $\langle J a, b\rangle = \langle a, J b\rangle$ for symbolic skew
    $a$, $b$ ($n = 4$)."""
    lam, a, b = lam_symbols(4), skew_matrix("a", 4), skew_matrix("b", 4)
    eq = S2.formulas["J_symmetric"]
    return residual(explicit(lhs_minus_rhs(eq), {"a": a, "b": b}, lam))


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_J_positive() -> sp.Expr:
    r"""$\langle \Omega, J\Omega\rangle = \sum_{i<j} c_{ij} \Omega_{ij}^2$ with $c_{ij}$ the left
    side of the displayed positivity condition at $(\lambda_i, \lambda_j)$: positive definite
    exactly when it holds ($n = 4$)."""
    lam, Omega = lam_symbols(4), skew_matrix("w", 4)
    form = sum(
        (
            POSITIVE.lhs.subs({_li: lam[i], _lj: lam[j]}) * Omega[i, j] ** 2
            for i, j in itertools.combinations(range(4), 2)
        ),
        sp.Integer(0),
    )
    quad = explicit(Pair(Om, J_DEF.rhs), {"Omega": Omega}, lam)
    return residual(quad - form)


def _pair_trace(e: sp.Basic) -> sp.Basic:
    """The displayed pairings <a, b> as -tr(a b)/2 (the pairing of S1)."""
    return e.replace(lambda x: isinstance(x, Pair), lambda x: -sp.Trace(x.args[0] * x.args[1]) / 2)


@S2.check(Level.SYMBOLIC_GENERAL_N)
def s2_J_symmetric_general_n() -> sp.Expr:
    r"""Every $n$: the displayed $\langle J a, b\rangle - \langle a, J b\rangle$, with $a$, $b$ and
    the symmetric $\Lambda$ noncommutative, is a sum of traces that cancels up to cyclic rotation
    (trace words left)."""
    w = Words(symmetric=["Lambda"])
    return sp.Integer(len(trace_words_of(w.trace_argument(
        _pair_trace(lhs_minus_rhs(S2.formulas["J_symmetric"]))))))  # fmt: skip


@S2.check(Level.SYMBOLIC_GENERAL_N)
def s2_J_positive_general_n() -> sp.Expr:
    r"""Every $n$, with symbolic indices: $\langle \Omega, J\Omega\rangle$ (the displayed $J$,
    $\Lambda = \operatorname{diag}(\lambda)$) is the double sum over $0 \le i, k \le n - 1$ of
    SymPy's entries of the matrix product, whose summand, with $\Omega_{ki} = -\Omega_{ik}$ (skew),
    is $\frac12 c_{ik} \Omega_{ik}^2$ with $c_{ik}$ the left side of the displayed positivity
    condition at $(\lambda_i, \lambda_k)$: positive definite when it holds for $i \ne k$
    ($\Omega_{ii} = 0$). Residual: 1 if the summands differ."""
    lv = sp.MatrixSymbol("lambda", n, 1)
    i = sp.Symbol("i", integer=True)
    quad = _pair_trace(Pair(Om, J_DEF.rhs))  # -tr(Om J(Om))/2
    coeff, tr = quad.as_coeff_Mul()
    entry = tr.arg.xreplace({Lam: sp.DiagMatrix(lv)})[i, i]  # Sum over k of the (i, i) entry
    (k,) = entry.variables

    def in_range(e: sp.Piecewise) -> sp.Expr:  # the inner sums' range conditions hold for i, k
        (value, cond), rest = e.args[0], e.args[1:]
        if not any(cond == sp.And(v >= 0, v <= n - 1) for v in (i, k)) or rest[0][0] != 0:
            raise ValueError(f"unexpected condition {cond}")
        return value

    summand = entry.function.replace(lambda e: isinstance(e, sp.Sum), lambda e: e.doit())
    summand = coeff * summand.replace(lambda e: isinstance(e, sp.Piecewise), in_range)
    summand = summand.xreplace({Om[k, i]: -Om[i, k]})
    c = POSITIVE.lhs.xreplace({_li: lv[i, 0], _lj: lv[k, 0]})
    return residual(sp.expand(summand - c * Om[i, k] ** 2 / 2))


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_moments_n3() -> sp.Expr:
    r"""For $n = 3$: $\frac12 \langle \Omega, J\Omega\rangle = \frac12 \sum_i I_i \omega_i^2$ with
    the displayed $I_1$ and its cyclic permutations."""
    lam, w = lam_symbols(3), sym_vector("w", 3)
    moments = _moments(lam)
    kinetic = sum((Ii * wi**2 for Ii, wi in zip(moments, w, strict=True)), sp.Integer(0)) / 2
    quad = explicit(Pair(Om, J_DEF.rhs), {"Omega": hat3(w)}, lam)
    return residual(quad / 2 - kinetic)


# Euler's equations for n = 3 in components, derived from the emitted matrix field
_m3, _l3v = sym_vector("m", 3), sym_vector("l", 3)
_MDOT3 = explicit(RIGID_BODY_RHS.outputs["Mdot"], {"Q": sp.eye(3), "M": hat3(_m3)}, list(_l3v))
EULER_RHS_SO3 = Kernel(
    name="euler_rhs_so3",
    target="rigid_body",
    args=[
        Arg("m", "(..., 3)", "body angular momentum vector, M = hat(m)"),
        Arg("lam", "(..., 3)", "diagonal of Lambda"),
    ],
    outputs={f"mdot{i + 1}": sp.factor(vee3(_MDOT3)[i]) for i in range(3)},
    doc="Euler's equations for n = 3.\n\n"
    "mdot = m x omega, omega_i = m_i / I_i, I_1 = lam_2 + lam_3 (cyclic): the components of the\n"
    "rigid body field at M = hat(m).",
    claims=("S2",),
    stack=True,
    components={"m": _m3, "lam": _l3v},
)


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_euler_n3() -> sp.Expr:
    r"""The emitted Euler kernel equals $m \times \omega$ with $\omega_i = m_i / I_i$ and the
    displayed moments $I_1 = \lambda_2 + \lambda_3$ (cyclic) (symbolic, $n = 3$)."""
    m, lam = _m3, list(_l3v)
    moments = _moments(lam)
    omega = sp.Matrix([m[i] / moments[i] for i in range(3)])
    target = m.cross(omega)
    return residual(sp.Matrix([EULER_RHS_SO3[f"mdot{i + 1}"] - target[i] for i in range(3)]))


@S2.check(Level.FLOAT64, tol=1e-13)
def s2_symrb_field_pointwise() -> float:
    r"""symrb.rigid_body.rigid_body_rhs against the reference field with $J^{-1}$ from an $n^2
    \times n^2$ linear solve, $n = 2, \dots, 6$, batches of 20 random $(Q, M, \lambda)$: max
    relative difference."""
    import symrb

    rng = np.random.default_rng(2)
    worst = 0.0
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        Qs = np.stack([ref.random_rotation(k, rng) for _ in range(20)])
        Ms = np.stack([ref.random_skew(k, rng) for _ in range(20)])
        got = symrb.rigid_body.rigid_body_rhs(Qs, Ms, lam)
        want = ref.rigid_body_field(Qs, Ms, lam)
        # reference size of the terms: |Omega| <= |M| / (2 min lam), |Mdot| <= 2 |M| |Omega|
        size = np.abs(Ms).max() / lam.min()
        scale = np.array([size, np.abs(Ms).max() * size])
        err = [np.abs(g - w).max() / s for g, w, s in zip(got, want, scale, strict=True)]
        worst = float(np.max([worst, *err]))
    return worst


@S2.check(Level.FLOAT64, tol=1e-14)
def s2_symrb_inertia_operators() -> float:
    r"""symrb.J and symrb.J_inv against the reference operators (explicit diagonal matrices, and an
    $n^2 \times n^2$ linear solve), $n = 2, \dots, 6$, 20 random skew matrices each: max relative
    difference."""
    import symrb

    rng = np.random.default_rng(21)
    worst = []
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        X = np.stack([ref.random_skew(k, rng) for _ in range(20)])
        JX = ref.J(X, lam)
        worst.append(np.abs(symrb.J(X, lam) - JX).max() / np.abs(JX).max())
        worst.append(
            np.abs(symrb.J_inv(X, lam) - ref.J_inv(X, lam)).max() / np.abs(X).max() * lam.min()
        )
    return float(np.max(worst))


@S2.check(Level.FLOAT64, tol=1e-9)
def s2_flow_against_elliptic() -> float:
    r"""symrb.integrate(RigidBody) ($n = 3$, DOP853, rtol 1e-12) against the Jacobi elliptic
    solution of Euler's equations at 41 times in $[0, 20]$: $\max |M \text{ error}| / |M|$."""
    import symrb

    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia  # I_1 = lam_2 + lam_3 (cyclic)
    t = np.linspace(0.0, 20.0, 41)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    sol = symrb.integrate(
        symrb.RigidBody, (0.0, 20.0), {"Q": np.eye(3), "M": ref.hat(m[0])}, lam=lam,
        rtol=1e-12, atol=1e-12, t_eval=t,
    )  # fmt: skip
    return float(np.abs(ref.vee(sol.y.M) - m).max() / np.linalg.norm(m[0]))


@S2.check(Level.FLOAT64, tol=1e-13)
def s2_symrb_euler_pointwise() -> float:
    r"""symrb.rigid_body.euler_rhs_so3 against numpy.cross($m$, $m / I$) with $I$ from symrb's
    convention checked above ($I_1 = \lambda_2 + \lambda_3$), 50 random points: max relative
    difference."""
    import symrb

    rng = np.random.default_rng(3)
    m = rng.standard_normal((50, 3))
    lam = rng.uniform(0.3, 2.0, (50, 3))
    inertia = lam.sum(axis=-1, keepdims=True) - lam
    want = np.cross(m, m / inertia)
    return float(np.abs(symrb.rigid_body.euler_rhs_so3(m, lam) - want).max() / np.abs(want).max())


# the paper's sentences
S2.sentence(
    r"Firstly we review the classical rigid body equations in $n$ dimensions for completeness.",
    kind="prose",
    reason="announces the review that follows",
)
S2.sentence(
    r"Further details may be found in [BlCrMaRa2002].",
    kind="prose",
    reason="a citation",
)
S2.sentence(
    r"We recall from [Manakov1976] and [Ratiu1980] that the left invariant generalized rigid body "
    r"equations on $\operatorname{SO}(n)$ may be written as $\dot Q = Q\Omega ; \qquad \dot M = "
    r"[M,\Omega]\,,$ where $Q\in \operatorname{SO}(n)$ denotes the configuration space variable "
    r"(the attitude of the body), $\Omega=Q^{-1}\dot{Q} \in \mathfrak{so}(n)$ is the body angular "
    r"velocity, and $M:=J(\Omega)=\Lambda\Omega +\Omega\Lambda \in \mathfrak{so}(n)$ is the "
    r"body angular momentum.",
    s2_emitted_field,
    s2_symrb_field_pointwise,
    s2_symrb_inertia_operators,
    s2_flow_against_elliptic,
)
S2.sentence(
    r"Here $J: \mathfrak{so}(n) \rightarrow \mathfrak{so}(n)$ is the symmetric (with respect to "
    r"the inner product (killing.eqn)), positive definite, and hence invertible, operator defined "
    r"by $J(\Omega)=\Lambda\Omega +\Omega\Lambda ,$ where $\Lambda$ is a diagonal matrix "
    r"satisfying $\Lambda_i + \Lambda_j >0$ for all $i \neq j$.",
    s2_J_symmetric,
    s2_J_positive,
    s2_symrb_inertia_operators,
    s2_J_symmetric_general_n,
    s2_J_positive_general_n,
)
S2.sentence(
    r"For $n=3$ the elements of $\Lambda_i$ are related to the standard diagonal moment of "
    r"inertia tensor $I$ by $I_1 = \Lambda_2 + \Lambda_3$, $I_2 = \Lambda_3 + \Lambda_1$, "
    r"$I_3 = \Lambda_1 + \Lambda_2$.",
    s2_moments_n3,
    s2_euler_n3,
    s2_symrb_euler_pointwise,
    s2_flow_against_elliptic,
)
