r"""The classical n-dimensional rigid body (paper, Section 3.1): claims S1-S4.

Emitted to ``symrb/_generated/rigid_body.py``: the rigid body vector field (S2), Euler's equations
for n = 3 (S2, derived from the matrix field), the kinetic energy (S3), Manakov's integrals and the
Casimir traces (S4, derived by expanding :math:`\operatorname{tr}(M+\lambda\Lambda^2)^k`).  Each
kernel is one object: the evidence below evaluates it and the printer prints it.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Cross,
    Pair,
    Words,
    eq,
    explicit,
    hat3,
    lhs_minus_rhs,
    residual,
    skew_gradient,
    skew_matrix,
    sym_vector,
    trace_residual,
    trace_words,
    vee3,
)
from derivations.vocabulary import Arg, Jinv, Kernel, Lam, matrix, vector

Q, M, Om = matrix("Q"), matrix("M"), matrix("Omega")
ARG_Q = Arg("Q", "(..., n, n)", "attitude, in SO(n)")
ARG_M = Arg("M", "(..., n, n)", "body angular momentum, skew")
ARG_LAM = Arg("lam", "(..., n)", "diagonal of Lambda, lam_i + lam_j > 0")
_LAMS = sp.symbols("lam1:5", real=True)


def _lam(k: int) -> list[sp.Symbol]:
    return list(sp.symbols(f"lam1:{k + 1}", real=True))


# =============================================================================================
# S1: pairing and hat map

S1 = claim(
    "S1",
    label="killing.eqn",
    title="Pairing on $\\mathfrak{so}(n)$ agrees with the dot product of $\\mathbb{R}^3$",
    statement="[[pairing]]; for $n=3$, [[pair_is_dot]] where [[hat]].",
    expected="holds",
    section="3.1",
    where="Section 3.1 (Classical $n$-dimensional rigid body equations), the first displayed "
    "equation, $\\langle \\xi, \\eta\\rangle = -\\tfrac12 \\operatorname{tr}(\\xi\\eta)$, and the "
    "hat map $\\hat u v = u \\times v$ after it",
    note="The pairing and the hat map are definitions; what is checked is that they agree with "
    "the dot and cross products of $\\mathbb{R}^3$, and that symrb's `hat` and `pairing` "
    "implement them.",
)
_xi, _eta = matrix("xi"), matrix("eta")
_u, _v = vector("u"), vector("v")
PAIRING = S1.formula("pairing", eq(Pair(_xi, _eta), -sp.Trace(_xi * _eta) / 2))
HAT = S1.formula("hat", eq(matrix("uhat") * _v, Cross(_u, _v)))
S1.formula("pair_is_dot", eq(Pair(matrix("uhat"), matrix("vhat")), _u.T * _v))


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_pairing_is_dot() -> sp.Expr:
    """The pairing's right side on hat(u), hat(v) minus u.v expands to 0 (n = 3)."""
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    value = explicit(PAIRING.rhs, {"xi": hat3(u), "eta": hat3(v)})
    return residual(value - u.dot(v))


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_hat_is_cross() -> sp.Expr:
    """The hat matrix used throughout satisfies the defining relation hat(u) v = u x v (n = 3)."""
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    return residual(explicit(lhs_minus_rhs(HAT), {"uhat": hat3(u), "v": v, "u": u}))


@S1.check(Level.FLOAT64, tol=1e-14)
def s1_symrb_hat_and_pairing() -> float:
    """symrb.hat(u) v against numpy.cross(u, v) and symrb.pairing(hat u, hat v) against u.v
    (relative, 50 random pairs)."""
    import symrb

    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, 50, 3))
    e1 = np.abs(np.einsum("...ij,...j->...i", symrb.hat(u), v) - np.cross(u, v)).max()
    e2 = np.abs(symrb.pairing(symrb.hat(u), symrb.hat(v)) - np.einsum("...i,...i", u, v)).max()
    return float(max(e1, e2) / np.abs(u).max() / np.abs(v).max())


# =============================================================================================
# S2: rigid body equations, J, n = 3 moments

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

RIGID_BODY_RHS = Kernel(
    name="rigid_body_rhs",
    target="rigid_body",
    args=[ARG_Q, ARG_M, ARG_LAM],
    outputs={"Qdot": Q * Jinv(M), "Mdot": M * Jinv(M) - Jinv(M) * M},
    doc="Rigid body vector field (paper, Section 3.1).\n\n"
    "Qdot = Q Omega, Mdot = [M, Omega], Omega = J^{-1}(M), J^{-1}(M)_ij = M_ij / (lam_i + lam_j).",
    claims=("S2",),
)


def _J_explicit(X: sp.Matrix, lam: list[sp.Expr]) -> sp.Matrix:
    """The right side of the displayed definition of J, on an explicit matrix."""
    return explicit(J_DEF.rhs, {"Omega": X}, lam)


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_emitted_field() -> sp.Expr:
    """The emitted field at Q = I: its Omega = Qdot satisfies the displayed J(Omega) = M, and its
    Mdot equals the displayed [M, Omega] (symbolic skew M, n = 4)."""
    lam, Ms = _lam(4), skew_matrix("m", 4)
    env = {"Q": sp.eye(4), "M": Ms}
    Omega = explicit(RIGID_BODY_RHS["Qdot"], env, lam)
    Mdot = explicit(RIGID_BODY_RHS["Mdot"], env, lam)
    r = residual(sp.simplify(_J_explicit(Omega, lam) - Ms))
    r += residual(sp.simplify(Mdot - explicit(MDOT.rhs, {"M": Ms, "Omega": Omega})))
    # and Qdot is Q Omega for a general Q (the displayed first equation)
    Qs = sp.Matrix(4, 4, lambda i, j: sp.Symbol(f"q{i}{j}"))
    Qdot = explicit(RIGID_BODY_RHS["Qdot"], {"Q": Qs, "M": Ms}, lam)
    return r + residual(sp.simplify(Qdot - explicit(QDOT.rhs, {"Q": Qs, "Omega": Omega})))


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_J_symmetric() -> sp.Expr:
    """The displayed symmetry <J a, b> = <a, J b> for symbolic skew a, b (n = 4)."""
    lam, a, b = _lam(4), skew_matrix("a", 4), skew_matrix("b", 4)
    eq = S2.formulas["J_symmetric"]
    return residual(explicit(lhs_minus_rhs(eq), {"a": a, "b": b}, lam))


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_J_positive() -> sp.Expr:
    """<Om, J Om> = sum_{i<j} c_ij Om_ij^2 with c_ij the left side of the displayed positivity
    condition at (lam_i, lam_j): positive definite exactly when it holds (n = 4)."""
    lam, Omega = _lam(4), skew_matrix("w", 4)
    form = sum(
        (
            POSITIVE.lhs.subs({_li: lam[i], _lj: lam[j]}) * Omega[i, j] ** 2
            for i, j in itertools.combinations(range(4), 2)
        ),
        sp.Integer(0),
    )
    quad = explicit(Pair(Om, J_DEF.rhs), {"Omega": Omega}, lam)
    return residual(quad - form)


@S2.check(Level.SYMBOLIC_FIXED_N)
def s2_moments_n3() -> sp.Expr:
    """For n = 3: 1/2 <Om, J Om> = 1/2 sum I_i w_i^2 with the displayed I_1 and its cyclic
    permutations."""
    lam, w = _lam(3), sym_vector("w", 3)
    moments = [
        MOMENT.rhs.subs({_l1: lam[c[0]], _l2: lam[c[1]], _l3: lam[c[2]]}, simultaneous=True)
        for c in ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    ]
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
    """The emitted Euler kernel equals m x omega with omega_i = m_i / I_i and the displayed
    moments I_1 = lam_2 + lam_3 (cyclic) (symbolic, n = 3)."""
    m, lam = _m3, list(_l3v)
    moments = [
        MOMENT.rhs.subs({_l1: lam[c[0]], _l2: lam[c[1]], _l3: lam[c[2]]}, simultaneous=True)
        for c in ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    ]
    omega = sp.Matrix([m[i] / moments[i] for i in range(3)])
    target = m.cross(omega)
    return residual(sp.Matrix([EULER_RHS_SO3[f"mdot{i + 1}"] - target[i] for i in range(3)]))


@S2.check(Level.FLOAT64, tol=1e-13)
def s2_symrb_field_pointwise() -> float:
    """symrb.rigid_body_rhs against the reference field with J^-1 from an n^2 x n^2 linear solve,
    n = 2..6, batches of 20 random (Q, M, lam): max relative difference."""
    import symrb

    rng = np.random.default_rng(2)
    worst = 0.0
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        Qs = np.stack([ref.random_rotation(k, rng) for _ in range(20)])
        Ms = np.stack([ref.random_skew(k, rng) for _ in range(20)])
        got = symrb.rigid_body_rhs(Qs, Ms, lam)
        want = ref.rigid_body_field(Qs, Ms, lam)
        # reference size of the terms: |Omega| <= |M| / (2 min lam), |Mdot| <= 2 |M| |Omega|
        size = np.abs(Ms).max() / lam.min()
        scale = np.array([size, np.abs(Ms).max() * size])
        err = [np.abs(g - w).max() / s for g, w, s in zip(got, want, scale, strict=True)]
        worst = float(np.max([worst, *err]))
    return worst


@S2.check(Level.FLOAT64, tol=1e-14)
def s2_symrb_inertia_operators() -> float:
    """symrb.J and symrb.J_inv against the reference operators (explicit diagonal matrices, and
    an n^2 x n^2 linear solve), n = 2..6, 20 random skew matrices each: max relative difference."""
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
    """symrb.integrate(RigidBody) (n = 3, DOP853, rtol 1e-12) against the Jacobi elliptic solution
    of Euler's equations at 41 times in [0, 20]: max |M error| / |M|."""
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


@S2.check(Level.FLOAT64, tol=1e-12)
def s2_exact_against_elliptic() -> float:
    """symrb.exact.rigid_body_exact (n = 3) against the Landau-Lifshitz Jacobi elliptic solution
    (reference.euler_elliptic) at 201 times in [0, 200], with the principal axes in the three
    cyclic orders of lam (the body momentum circles the largest axis), as one call for all times
    (the array route) and one call per six of them (one body and at most 8 times: the float
    route): max |M error| / |M|."""
    from symrb.exact import rigid_body_exact

    inertia = np.array([1.0, 1.7, 2.6])
    t = np.linspace(0.0, 200.0, 201)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    worst = 0.0
    for shift in range(3):  # a cyclic relabelling of the axes is a rotation: same dynamics
        I_s, m_s = np.roll(inertia, shift), np.roll(m, shift, axis=-1)
        lam = 0.5 * I_s.sum() - I_s  # I_1 = lam_2 + lam_3 (cyclic)
        Q0 = ref.random_rotation(3, np.random.default_rng(shift))
        sol = rigid_body_exact(Q0, ref.hat(m_s[0]), lam, t)
        err = np.abs(ref.vee(sol.y.M) - m_s).max() / np.linalg.norm(m_s[0])
        worst = max(worst, float(err))
        for part in np.array_split(np.arange(len(t)), 34):
            one = rigid_body_exact(Q0, ref.hat(m_s[0]), lam, t[part])
            err = np.abs(ref.vee(one.y.M) - m_s[part]).max() / np.linalg.norm(m_s[0])
            worst = max(worst, float(err))
    return worst


# the 6 random bodies of the next check, and the special cases it adds
_EXACT_SPECIAL = [
    ([0.0, 0.0, 1.3], [0.7, 1.1, 1.6]),  # a steady rotation about a principal axis
    ([0.5, 1.0, 1.5], [0.8, 0.8, 1.5]),  # a symmetric body
    ([0.7, 0.3, -1.1], [-0.2, 1.1, 1.6]),  # lam_1 < 0 with J positive definite
]


@S2.check(Level.FLOAT64, tol=1e-10)
def s2_exact_against_flow() -> float:
    """symrb.exact.rigid_body_exact against symrb.integrate(RigidBody) (DOP853, rtol = atol =
    1e-13) at 11 times in [0, 60], for 6 random bodies (|m| = 1; the momentum circles the largest
    axis for some, the smallest for others) plus a steady rotation, a symmetric body and a body
    with lam_1 < 0, all in one call (the array route) and each body alone at the last three
    times (one body: the float route, except the steady rotation): max |Q error| and
    |M error| / |M|."""
    import symrb
    from symrb.exact import rigid_body_exact

    rng = np.random.default_rng(17)
    lam = rng.uniform(0.4, 2.0, (6, 3))
    m = rng.standard_normal((6, 3))
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    lam = np.concatenate([lam, [c[1] for c in _EXACT_SPECIAL]])
    m = np.concatenate([m, [c[0] for c in _EXACT_SPECIAL]])
    Q0 = np.stack([ref.random_rotation(3, rng) for _ in range(len(m))])
    M0 = ref.hat(m)
    t = np.linspace(0.0, 60.0, 11)
    sol = rigid_body_exact(Q0, M0, lam, t)
    inertia = lam.sum(axis=-1, keepdims=True) - lam
    circled = np.take_along_axis(inertia, np.maximum(sol.axis, 0)[:, None], -1)[:, 0]
    if not (np.any(circled == inertia.max(-1)) and np.any(circled == inertia.min(-1))):
        return np.inf  # both elliptic cases must be exercised
    flow = symrb.integrate(
        symrb.RigidBody, (0.0, 60.0), {"Q": Q0, "M": M0}, lam=lam, rtol=1e-13, atol=1e-13,
        t_eval=t,
    )  # fmt: skip
    eQ = np.abs(sol.y.Q - flow.y.Q).max()
    eM = (np.abs(sol.y.M - flow.y.M).max(axis=(0, -2, -1)) / np.abs(M0).max(axis=(-2, -1))).max()
    for b in range(len(m)):
        one = rigid_body_exact(Q0[b], M0[b], lam[b], t[-3:])
        eQ = max(eQ, np.abs(one.y.Q - flow.y.Q[-3:, b]).max())
        eM = max(eM, np.abs(one.y.M - flow.y.M[-3:, b]).max() / np.abs(M0[b]).max())
    return float(max(eQ, eM))


def _mp_rigid_body(inertia: np.ndarray, Q0: np.ndarray, m0: np.ndarray, T: float, dps: int):
    """Q(T), m(T) of Qdot = Q hat(omega), mdot = m x omega, omega_i = m_i / I_i by mpmath's
    Taylor-series solver (mpmath.odefun) in ``dps`` digits."""
    import mpmath

    with mpmath.workdps(dps):
        inv = [1 / mpmath.mpf(float(x)) for x in inertia]

        def field(_t, y):
            m = y[9:]
            w = [m[i] * inv[i] for i in range(3)]
            W = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
            Qd = [sum(y[3 * i + k] * W[k][j] for k in range(3)) for i in range(3) for j in range(3)]
            md = [m[1] * w[2] - m[2] * w[1], m[2] * w[0] - m[0] * w[2], m[0] * w[1] - m[1] * w[0]]
            return Qd + md

        y0 = [mpmath.mpf(float(x)) for x in np.concatenate([np.ravel(Q0), m0])]
        yT = mpmath.odefun(field, 0, y0)(T)
        out = np.array([float(x) for x in yT])
    return out[:9].reshape(3, 3), out[9:]


@S2.check(Level.MPMATH, tol=1e-13)
def s2_exact_against_mpmath_ode() -> float:
    """symrb.exact.rigid_body_exact at t = 4 against a 20-digit Taylor integration of the rigid
    body (mpmath.odefun on Qdot = Q hat(omega), mdot = m x omega), for a body whose momentum
    circles its largest axis and one whose momentum circles its smallest: max |Q error| and
    |m error| / |m|."""
    from symrb.exact import rigid_body_exact

    worst = 0.0
    rng = np.random.default_rng(5)
    for lam, m0 in (([0.7, 1.1, 1.6], [0.5, 1.0, 1.5]), ([0.7, 1.1, 1.6], [1.5, 1.0, 0.5])):
        lam_a, m0_a = np.array(lam), np.array(m0)
        inertia = lam_a.sum() - lam_a
        Q0 = ref.random_rotation(3, rng)
        QT, mT = _mp_rigid_body(inertia, Q0, m0_a, 4.0, 20)
        sol = rigid_body_exact(Q0, ref.hat(m0_a), lam_a, [4.0])
        eQ = np.abs(sol.y.Q[0] - QT).max()
        eM = np.abs(ref.vee(sol.y.M[0]) - mT).max() / np.linalg.norm(m0_a)
        worst = max(worst, float(eQ), float(eM))
    return worst


@S2.check(Level.FLOAT64, tol=1e-13)
def s2_symrb_euler_pointwise() -> float:
    """symrb.euler_rhs_so3 against numpy.cross(m, m / I) with I from symrb's convention checked
    above (I_1 = lam_2 + lam_3), 50 random points: max relative difference."""
    import symrb

    rng = np.random.default_rng(3)
    m = rng.standard_normal((50, 3))
    lam = rng.uniform(0.3, 2.0, (50, 3))
    inertia = lam.sum(axis=-1, keepdims=True) - lam
    want = np.cross(m, m / inertia)
    return float(np.abs(symrb.euler_rhs_so3(m, lam) - want).max() / np.abs(want).max())


# =============================================================================================
# S3: Euler-Poincare and the kinetic energy

S3 = claim(
    "S3",
    label="RBLag_group.eqn",
    title="$\\dot M = [M, \\Omega]$ is Euler-Poincaré for $l(\\Omega) = \\tfrac12\\langle "
    "\\Omega, J(\\Omega)\\rangle$",
    statement="For [[lagrangian]] the variational derivative is [[derivative]] and "
    "[[coadjoint]], so the Euler-Poincare equation reads [[euler_poincare]].",
    expected="holds",
    section="3.1",
    where="Section 3.1, the paragraph after the rigid body equations: the Euler-Poincaré "
    "equations of $l(\\Omega) = \\tfrac12\\langle \\Omega, J(\\Omega)\\rangle$ and the Lagrangian "
    "$L(g, \\dot g)$ on $T\\,\\mathrm{SO}(n)$",
    note="The Lagrangian is the paper's definition; the kinetic energy kernel is that Lagrangian "
    "evaluated at $\\Omega = J^{-1}(M)$, which the evidence checks.",
)
_eta3 = matrix("eta")
_ell = sp.Function("l")
LAGRANGIAN = S3.formula("lagrangian", eq(_ell(Om), Pair(Om, J_DEF.rhs) / 2))
S3.formula("derivative", eq(matrix("delta_l/delta_Omega"), J_DEF.rhs))
_mu, _xi3 = matrix("mu"), matrix("xi")
COADJOINT = S3.formula(
    "coadjoint", eq(Pair(_mu, Bracket(_xi3, _eta3)), Pair(Bracket(_mu, _xi3), _eta3))
)
EULER_POINCARE = S3.formula("euler_poincare", eq(matrix("Mdot"), Bracket(M, Om)))

KINETIC_ENERGY = Kernel(
    name="kinetic_energy",
    target="rigid_body",
    args=[ARG_M, ARG_LAM],
    outputs={"E": Pair(Jinv(M), M).doit() / 2},
    doc="Kinetic energy 1/2 <J^{-1}(M), M>.\n\n"
    "The Lagrangian l(Omega) = 1/2 <Omega, J Omega> at Omega = J^{-1}(M), with the pairing\n"
    "<a, b> = -1/2 trace(a b).",
    claims=("S3",),
)


@S3.check(Level.SYMBOLIC_FIXED_N)
def s3_variational_derivative() -> sp.Expr:
    """d/de l(Om + e eta) at e = 0 equals <J Om, eta> for the displayed l (n = 4)."""
    lam, Omega, eta = _lam(4), skew_matrix("w", 4), skew_matrix("e", 4)
    eps = sp.Symbol("epsilon")
    lag = explicit(LAGRANGIAN.rhs, {"Omega": Omega + eps * eta}, lam)
    return residual(
        sp.diff(lag, eps).subs(eps, 0)
        - explicit(Pair(J_DEF.rhs, _eta3), {"Omega": Omega, "eta": eta}, lam)
    )


@S3.check(Level.SYMBOLIC_GENERAL_N)
def s3_coadjoint() -> sp.Expr:
    """The displayed <mu, [xi, eta]> = <[mu, xi], eta> holds as trace words for every n, and with
    it <M, [Om, eta]> = <[M, Om], eta>: ad*_Om M is the right side of the displayed Euler-Poincare
    equation (noncommutative symbols)."""
    w = Words()
    r = trace_residual(w.trace_argument(lhs_minus_rhs(COADJOINT).doit()))
    ad_star = Pair(M, Bracket(Om, _eta3)) - Pair(EULER_POINCARE.rhs, _eta3)
    return r + trace_residual(w.trace_argument(ad_star.doit()))


@S3.check(Level.SYMBOLIC_FIXED_N)
def s3_kinetic_energy_kernel() -> sp.Expr:
    """The emitted kinetic energy at M = J(Om) equals the displayed l(Om) (symbolic skew Om,
    n = 4)."""
    lam, Omega = _lam(4), skew_matrix("w", 4)
    Mx = _J_explicit(Omega, lam)
    E = explicit(KINETIC_ENERGY["E"], {"M": Mx}, lam)
    return residual(sp.simplify(E - explicit(LAGRANGIAN.rhs, {"Omega": Omega}, lam)))


@S3.check(Level.FLOAT64, tol=1e-13)
def s3_symrb_kinetic_energy() -> float:
    """symrb.kinetic_energy(M) against 1/2 <Om, J Om> with Om from the reference linear solve,
    n = 2..6, 20 random M each: max relative difference."""
    import symrb

    rng = np.random.default_rng(4)
    worst = 0.0
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        Ms = np.stack([ref.random_skew(k, rng) for _ in range(20)])
        Omega = ref.J_inv(Ms, lam)
        want = 0.5 * ref.pairing(Omega, ref.J(Omega, lam))
        worst = max(worst, float(np.abs(symrb.kinetic_energy(Ms, lam) - want).max() / want.max()))
    return worst


# =============================================================================================
# S4: Manakov's Lax pair with parameter and its integrals

S4 = claim(
    "S4",
    label="lambda_eqn",
    title="Manakov's Lax equation with parameter and its integrals",
    statement="[[lax]]; the coefficients of the powers of $\\lambda$ in [[generating]] are "
    "conserved along the rigid body flow and are in involution for the Lie-Poisson bracket.",
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
    """With Lambda and Om noncommutative, M the displayed J(Om) and Mdot the displayed [M, Om]:
    Mdot minus the right side of the displayed Lax equation expands to 0 (any n)."""
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


def _conservation(lam: list[sp.Expr], Ms: sp.Matrix, max_degree: int) -> sp.Expr:
    k = Ms.rows
    Mdot = explicit(RIGID_BODY_RHS["Mdot"], {"Q": sp.eye(k), "M": Ms}, lam)
    total = sp.Integer(0)
    for F in _integrals(max_degree, lam, Ms):
        G = skew_gradient(F, Ms)
        total += residual(sp.together(explicit(Pair(M, Om), {"M": G, "Omega": Mdot})))
    return total


@S4.check(Level.SYMBOLIC_FIXED_N)
def s4_integrals_conserved() -> sp.Expr:
    """d/dt F = <grad F, Mdot> vanishes identically for the emitted integrals of degree <= 4,
    with Mdot from the emitted rigid body field (symbolic M and Lambda, n = 4)."""
    lam, Ms = _lam(4), skew_matrix("m", 4)
    return _conservation(lam, Ms, 4)


def _derivative_at_zero(values: list[sp.Rational]) -> sp.Rational:
    """p'(0) of the polynomial p of degree < len(values) with p(i) = values[i], i = 0, 1, ...
    (exact Lagrange interpolation)."""
    e = sp.Symbol("e")
    return sp.diff(sp.interpolate(list(enumerate(values)), e), e).subs(e, 0)


@S4.check(Level.EXACT_RATIONAL)
def s4_integrals_conserved_exact() -> sp.Expr:
    """The same for every emitted integral and Casimir (degrees up to 6): d/de F(M + e Mdot) at
    e = 0, by exact interpolation of F at e = 0..6, vanishes at 3 random rational (M, Lambda),
    n = 4 and 5."""
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
    """Lie-Poisson brackets {F, G}(M) = -<M, [grad F, grad G]> of the emitted Manakov integrals
    of degree <= 4 vanish pairwise (symbolic, n = 4)."""
    lam, Ms = _lam(4), skew_matrix("m", 4)
    grads = [skew_gradient(F, Ms) for F in _integrals(4, lam, Ms)]
    total = sp.Integer(0)
    for a, b in itertools.combinations(range(len(grads)), 2):
        bracket = explicit(
            Pair(M, Bracket(_xi3, _eta3)), {"M": Ms, "xi": grads[a], "eta": grads[b]}
        )
        total += residual(bracket)
    return total


@S4.check(Level.SYMBOLIC_FIXED_N)
def s4_coefficients_by_expansion() -> sp.Expr:
    """Another route to the same integrals: expand the displayed trace with explicit symbolic
    3 x 3 matrices as a polynomial in lambda; its coefficients equal the emitted Manakov integrals
    and Casimirs (n = 3)."""
    lam, Ms = _lam(3), skew_matrix("m", 3)
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
    """symrb.manakov_integrals and symrb.casimir_traces against coefficients of a polynomial fit
    of tr((M + t Lambda^2)^k) over t (plain NumPy), n = 4, 5, 10 random M each: max relative
    difference."""
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
    """symrb.manakov_integrals along a trajectory of the reference rigid body field (J^-1 by a
    linear solve; DOP853, rtol 1e-12, n = 4, t in [0, 20]): max drift relative to the values."""
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
