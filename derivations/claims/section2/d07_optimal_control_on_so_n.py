r"""D7: the discrete symmetric rigid body from optimal control on SO(n) (paper, Section 2.1).

Where: Section 2.1, the first definition (mvoptprobm: minimise :math:`\sum_k\operatorname{tr}
(\Lambda U_k)` subject to :math:`Q_{k+1} = Q_kU_k`) and the first theorem (discrbopteqns, Ukdef:
:math:`P_{k+1} = P_kU_k` and :math:`U_k\Lambda - \Lambda U_k^T = Q_k^TP_k - P_k^TQ_k`), with its
proof (discrbeq, discham, symequation, equ_final_th_2.7).

Recorded outcome: holds after correction.  The necessary conditions and the sign change hold as
printed for every :math:`n` (noncommutative symbols); the dynamics carry a frozen index, the
multiplier is :math:`n\times n`, the costate in :math:`SO(n)` is a choice, the sign change
multiplies the determinant by :math:`(-1)^n`, and the discrete rigid body (:math:`U_k` on the
branch through the identity, which symrb follows) is the global maximiser of the cost, while the
global minimiser has every :math:`U_k` on another branch (:mod:`._so_extremals`).

Emitted (``symrb/_generated/discrete_rigid_body.py``): ``jd``, the left side :math:`J_D(U)` of
the equation for :math:`U_k`.  Evidence independent of symrb: symbolic and exact computations and
the enumeration of :mod:`._jd_solutions`; symrb's ``symmetric_flow`` against the 50-digit run of
:mod:`._reference_run` and against the stationarity of the displayed cost.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section2._jd_solutions import _all_jd_solutions, _on_branch
from derivations.claims.section2._matrix_formulas import (
    _LAM3,
    _N,
    ARG_LAM,
    M0,
    P0,
    Q0,
    Pk,
    Pk1,
    Qk,
    Qk1,
    U,
    Uk,
    _cayley_rational,
    _k,
    _lam,
    _MatrixFunction,
    _numeric,
)
from derivations.claims.section2._reference_run import _H, _STEPS, _mp_run
from derivations.claims.section2._so_extremals import (
    _continued_to,
    _global_optimum,
    _margin,
    _rot,
    _states,
)
from derivations.registry import Level, claim
from derivations.symbolic import (
    Words,
    eq,
    explicit,
    general_matrix,
    lhs_minus_rhs,
    residual,
    skew_matrix,
)
from derivations.vocabulary import Arg, Kernel, Lam, matrix, n

D7 = claim(
    "D7",
    label="mvoptprobm, discrbeq, discrbopteqns, Ukdef, discham, symequation, equ_final_th_2.7",
    title="Discrete symmetric rigid body from optimal control on $\\mathrm{SO}(n)$",
    statement="Minimising [[cost]] subject to [[dynamics]] with $Q_0$ and $Q_N$ given: with the "
    "Hamiltonian [[hamiltonian]], whose critical points in $U$ on $SO(n)$ satisfy [[critical]] "
    "(from [[lagrangian]], [[dlagrangian]]), one gets the stationarity equation of the proof [[symequation]], the costate "
    "equation [[costate]], the proof's last equation [[final]], and after the sign change of $P$ the "
    "theorem's equations [[discrbopteqns]] with [[Ukdef]].  The proof uses the Moser-Veselov "
    "form of the cost, [[mv_functional]].",
    printed="The dynamics of the problem read [[dynamics_printed]]; the multiplier $\\Sigma$ is an $N\\times N$ "
    "matrix; $P_k$ in $SO(n)$ is the discrete covector of the maximum principle (the theorem's "
    "$P_k$ is minus the covector of the proof, so both would be in $SO(n)$: [[flip_printed]]); "
    "$U_k$ in $SO(n)$ is defined by the theorem's equation for $U_k$ (one solution), and the "
    "discrete rigid body so defined solves the minimisation problem.",
    corrected="The dynamics are [[dynamics]]; $\\Sigma$ is $n\\times n$ (the size of $U^TU-I$); the "
    "costate is a covector of $\\mathfrak{gl}(n)$, fixed only up to adding $Q_k$ times a symmetric "
    "matrix, so $SO(n)$ is a choice (an invariant set): [[P0_gl]] and [[P0_SO]] give the same "
    "extremal; the sign change gives [[flip_det]], so for odd $n$ at most one of $P_k$ and "
    "$-P_k$ is in $SO(n)$; the equation for $U_k$ has several solutions in $SO(n)$ (two for $n=2$, four for "
    "$n=3$ and small momenta), and the theorem's equations hold at every extremal, the minimiser "
    "and the maximiser alike.  The discrete rigid body, the solution on the branch through the "
    "identity (all eigenvalues of $U_k\\Lambda$ in the open right half-plane; unique, and existing "
    "only up to a fold, D10) that symrb's flows follow, is the global maximiser of the cost (the "
    "minimiser of minus the cost) in every case computed ($n=3$; $N$ from 2 to 4; $Q_0^TQ_N$ a "
    "turn by less than $\\pi$, and half-turns for $N=3$); the global minimiser has for every "
    "$U_k$ an eigenvalue of $U_k\\Lambda$ in the open left half-plane, each $U_k$ on the continuation "
    "of the half-turn about the axis of the smallest $\\lambda_i$ for $Q_N$ near $Q_0$.",
    note="The dynamics carry a frozen index, the multiplier $\\Sigma$ is said to be $N \\times "
    "N$, the theorem leaves the choice of $P_k$ and of the solution $U_k$ unstated, and the "
    "discrete rigid body it leads to (the solution on the branch through the identity) is the "
    "maximiser of the cost, not its minimiser. "
    "Corrected: $Q_{r+1} = Q_r U_r$, $\\Sigma$ is $n \\times n$, $P_k \\in \\mathrm{SO}(n)$ is a "
    "choice of costate, and the discrete rigid body (every $U_k$ on the branch through the "
    "identity) is the global maximiser of $\\sum_k \\operatorname{tr}(\\Lambda U_k)$ (the "
    "minimiser of minus it) for $Q_N$ near $Q_0$, while the global minimiser is the extremal "
    "with every $U_k$ off that branch. The "
    "necessary conditions (the stationarity equation of the proof, the costate equation, the "
    "equation for $U_k$ before the sign change, and the sign change itself) hold as printed, for "
    "every $n$. With the frozen index the proof's identity $\\sum_k \\operatorname{tr}(\\Lambda "
    "U_k) = \\sum_k \\operatorname{tr}(Q_k \\Lambda Q_{k+1}^T)$ fails; the multiplier has the "
    "size $n$ of the matrices, not the number $N$ of steps; the costate of the maximum principle "
    "is a $\\mathfrak{gl}(n)$ covector, defined up to $Q_k S_k$ with $S_k$ symmetric (the right "
    "side of the equation for $U_k$ does not see $S_k$), so '$P_k \\in \\mathrm{SO}(n)$' is a "
    "choice of representative that exists when $\\|M\\|_{\\mathrm{op}} < 2$ (S9, S10) and is kept "
    "by the equations; $P \\mapsto -P$ changes $\\det P$ by $(-1)^n$; and the equation for $U_k$ "
    "does not define $U_k$ without naming the branch: for $n = 3$ near $M = 0$ it has four "
    "solutions in $\\mathrm{SO}(3)$, $I$ and the half-turns about the principal axes continued. "
    "Both global optima satisfy the theorem's equations, so the equations alone cannot tell them "
    "apart; the branch does.  Computed for $n = 3$, $\\Lambda = \\mathrm{diag}(0.7, 1.1, 1.6)$ "
    "and $N = 2, 3, 4$ (multi-start BFGS over $\\mathrm{SO}(3)^{N-1}$, polished to an "
    "extremal; for $N = 2$ 16 axes at turns from 2 to 3.13 and 6 other targets, for $N = 3$ 36 targets (10 "
    "half-turns), for $N = 4$ 6 targets): "
    "the maximiser has every eigenvalue of $U_k\\Lambda$ in the right half-plane whenever "
    "$Q_0^T Q_N$ is a turn by less than $\\pi$ (for $N = 2$ the least real part tends to 0, the "
    "fold, as the turn tends to $\\pi$, and at a half-turn the maximisers form a continuum, most "
    "of them off the branch); the minimiser has for every $U_k$ an eigenvalue of $U_k\\Lambda$ in "
    "the left half-plane (at $Q_N = Q_0$ "
    "and even $N$ every $U_k$ is the half-turn about the axis of $\\lambda_1$), and symrb's "
    "flow started from its $Q_0$ and $M_0$ leaves it.",
    expected="holds after correction",
    headline="[[dynamics]]; the discrete rigid body maximises [[cost]]",
    section="2.1",
    where="Section 2.1 (The discrete symmetric rigid body), the first definition (minimise "
    "$\\sum_k \\operatorname{tr}(\\Lambda U_k)$ subject to $Q_{k+1} = Q_k U_k$) and the first "
    "theorem (the equations $Q_{k+1} = Q_k U_k$, $P_{k+1} = P_k U_k$ with $U_k \\Lambda - "
    "\\Lambda U_k^T = Q_k^T P_k - P_k^T Q_k$), with its proof",
)


# the kernel: J_D, the left side of the theorem's equation for U_k

JD = Kernel(
    name="jd",
    target="discrete_rigid_body",
    args=[
        Arg("U", "(..., n, n)", "a square matrix (in SO(n) for the discrete rigid body)"),
        ARG_LAM,
    ],
    outputs={"JD": U * Lam - Lam * U.T},
    doc="The discrete inertia operator J_D(U) = U Lambda - Lambda U^T (paper, Section 2.1).\n\n"
    "Its derivative at the identity is J(Omega) = Omega Lambda + Lambda Omega (claim D8).",
    claims=("D7", "D8", "D10", "D12"),
)


_A, _Sig, _dU = matrix("A"), matrix("Sigma"), matrix(r"\delta U")
_Ur, _Qr, _Qr1 = matrix("U_r"), matrix("Q_r"), matrix("Q_{r+1}")
COST = D7.formula("cost", sp.Sum(sp.Trace(Lam * Uk), (_k, 0, _N - 1)))
DYNAMICS = D7.formula("dynamics", eq(_Qr1, _Qr * _Ur))
DYNAMICS_PRINTED = D7.formula("dynamics_printed", eq(_Qr1, Qk * _Ur))
MV_FUNCTIONAL = D7.formula(
    "mv_functional",
    eq(COST, sp.Sum(sp.Trace(Qk * Lam * Qk1.T), (_k, 0, _N - 1))),
)
HAMILTONIAN = D7.formula(
    "hamiltonian",
    eq(sp.Function("H")(Pk1, Qk, Uk), sp.Trace((Pk1.T * Qk - Lam) * Uk)),
)
CRITICAL = D7.formula("critical", eq(_A * U, U.T * _A.T))
CONSTRAINT = U.T * U - sp.Identity(n)
LAGRANGIAN = D7.formula(
    "lagrangian",
    eq(sp.Function(r"\tilde{V}")(U), sp.Trace(_A * U) + sp.Trace(_Sig * CONSTRAINT) / 2),
)
DLAGRANGIAN = D7.formula(
    "dlagrangian",
    eq(sp.Function(r"\delta\tilde{V}")(_dU), sp.Trace(_A * _dU + _Sig * U.T * _dU)),
)
SYMEQUATION = D7.formula(
    "symequation", eq(Uk * Lam - Lam * Uk.T, -Qk.T * Pk1 * Uk.T + Uk * Pk1.T * Qk)
)
COSTATE = D7.formula("costate", eq(Pk, Pk1 * Uk.T))
STATE = eq(Qk1, Qk * Uk)
DISCRBOPTEQNS = D7.formula("discrbopteqns", (STATE, eq(Pk1, Pk * Uk)))
FINAL = D7.formula("final", eq(Uk * Lam - Lam * Uk.T, Pk.T * Qk - Qk.T * Pk))
UKDEF = D7.formula("Ukdef", eq(JD.outputs["JD"].xreplace({U: Uk}), Qk.T * Pk - Pk.T * Qk))
P0_GL = D7.formula("P0_gl", eq(P0, Q0 * M0 / 2))
P0_SO = D7.formula("P0_SO", eq(P0, Q0 * _MatrixFunction("exp", _MatrixFunction("asinh", M0 / 2))))
FLIP_PRINTED = D7.formula("flip_printed", eq(sp.Determinant(-Pk), sp.Determinant(Pk)))
FLIP_DET = D7.formula("flip_det", eq(sp.Determinant(-Pk), (-1) ** n * sp.Determinant(Pk)))


@D7.check(Level.SYMBOLIC_FIXED_N)
def d7_critical_points() -> sp.Expr:
    r"""Along $U(I + e\xi)$, $\xi$ skew, $\frac{d}{de}\,\operatorname{tr}(AU(I + e\xi))$ at 0 equals
    $-\sum_{i<j} \xi_{ij} D_{ij}$ with $D = AU - U^T A^T$ the displayed critical-point condition
    (lhs - rhs): the derivative vanishes for every skew $\xi$ exactly when it holds (general $A$ and
    $U$, $n = 3$)."""
    A3, U3, xi = general_matrix("a", 3), general_matrix("u", 3), skew_matrix("x", 3)
    eps = sp.Symbol("epsilon")
    f = (A3 * U3 * (sp.eye(3) + eps * xi)).trace()
    D = explicit(lhs_minus_rhs(CRITICAL), {"A": A3, "U": U3})
    form = sum((xi[i, j] * D[i, j] for i, j in itertools.combinations(range(3), 2)), sp.Integer(0))
    return residual(sp.diff(f, eps).subs(eps, 0) + form)


@D7.check(Level.SYMBOLIC_FIXED_N)
def d7_multiplier_derivative() -> sp.Expr:
    r"""The proof's derivative: $\frac{d}{de}$ of the displayed $\tilde V(U + e\,dU)$ at 0, with a
    symmetric $n \times n$ $\Sigma$, equals the displayed $\operatorname{tr}(A\,dU + \Sigma U^T dU)$
    (general $A$, $U$, $dU$, $n = 3$)."""
    A3, U3, dU = general_matrix("a", 3), general_matrix("u", 3), general_matrix("d", 3)
    Sig = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"s{min(i, j) + 1}{max(i, j) + 1}", real=True))
    eps = sp.Symbol("epsilon")
    V = explicit(LAGRANGIAN.rhs, {"A": A3, "U": U3 + eps * dU, "Sigma": Sig})
    dV = explicit(DLAGRANGIAN.rhs, {"A": A3, "U": U3, "Sigma": Sig, r"\delta U": dU})
    return residual(sp.diff(V, eps).subs(eps, 0) - dV)


def _multiplier_mismatch(size: int) -> int:
    """|entries of a symmetric size x size Sigma - independent constraints in U^T U = I| (n = 3)."""
    U3 = _cayley_rational([1, -2, 3], 5)  # a rational rotation
    dU = general_matrix("d", 3)
    g = explicit(CONSTRAINT, {"U": U3 + dU})
    at_U = {x: 0 for x in dU}
    jac = sp.Matrix([[sp.diff(e, d).subs(at_U) for d in dU] for e in g])
    return abs(size * (size + 1) // 2 - jac.rank())


@D7.check(Level.EXACT_RATIONAL, form="corrected")
def d7_multiplier_n_by_n() -> int:
    r"""Lagrange multipliers: one per independent scalar constraint. The constraint $U^T U - I$ of
    the displayed $\tilde V$ has rank-6 derivative at a rational rotation ($n = 3$, exact); a
    symmetric $n \times n$ $\Sigma$ has 6 entries: mismatch $|6 - 6|$."""
    return _multiplier_mismatch(3)


@D7.check(Level.EXACT_RATIONAL, form="printed")
def d7_multiplier_N_by_N() -> int:
    r"""The same count with the printed $N \times N$ $\Sigma$ ($N = 4$ steps, $n = 3$): 10
    multipliers for 6 independent constraints."""
    return _multiplier_mismatch(4)


@D7.check(Level.SYMBOLIC_GENERAL_N)
def d7_symequation() -> sp.Expr:
    r"""With $A = P_{k+1}^T Q_k - \Lambda$ from the displayed $H$ and $U_k$ orthogonal, the
    displayed critical condition (lhs - rhs) multiplied by $U_k$ on the left and by $U_k^T$ on the
    right, plus the displayed symequation (lhs - rhs), reduces to 0 (noncommutative symbols, every
    $n$)."""
    w = Words(symmetric=["Lambda"], orthogonal=["U_k"])
    _c, factors = HAMILTONIAN.rhs.arg.as_coeff_matrices()  # H = tr(A U_k)
    if factors[-1] != Uk:  # pragma: no cover - the displayed H is fixed above
        raise ValueError("the displayed H is not tr(A U_k)")
    A_k = sp.MatMul(*factors[:-1])
    crit = w.of(lhs_minus_rhs(CRITICAL).xreplace({_A: A_k, U: Uk}))
    u = w("U_k")
    return w.is_zero(u * crit * w.T(u) + w.of(lhs_minus_rhs(SYMEQUATION)))


@D7.check(Level.SYMBOLIC_FIXED_N)
def d7_costate_gradients() -> sp.Expr:
    r"""The gradients of the displayed $H$: $\partial H/\partial Q_k$ is the displayed costate right
    side $P_{k+1} U_k^T$ and $\partial H/\partial P_{k+1}$ is $Q_k U_k$ (entrywise, general
    matrices, $n = 3$)."""
    lam = _lam(3)
    Qx, Px, Ux = general_matrix("q", 3), general_matrix("p", 3), general_matrix("u", 3)
    env = {"Q_k": Qx, "P_{k+1}": Px, "U_k": Ux}
    Hx = explicit(HAMILTONIAN.rhs, env, lam)
    gQ = sp.Matrix(3, 3, lambda i, j: sp.diff(Hx, Qx[i, j]))
    gP = sp.Matrix(3, 3, lambda i, j: sp.diff(Hx, Px[i, j]))
    return residual(gQ - explicit(COSTATE.rhs, env)) + residual(gP - explicit(STATE.rhs, env))


@D7.check(Level.SYMBOLIC_GENERAL_N)
def d7_final_and_flip() -> sp.Expr:
    r"""With $P_{k+1} = P_k U_k$ ($U_k$ orthogonal) the displayed symequation's right side is the
    displayed equ_final_th_2.7 right side, and $P \mapsto -P$ turns that into the right side of the
    displayed Ukdef (noncommutative symbols, every $n$)."""
    w = Words(orthogonal=["U_k"])
    step = {Pk1: Pk * Uk}
    r = w.is_zero(w.of(SYMEQUATION.rhs.xreplace(step)) - w.of(FINAL.rhs))
    flipped = FINAL.rhs.xreplace({Pk: -Pk})
    return r + w.is_zero(w.of(flipped) - w.of(UKDEF.rhs))


def _mv_functional_gap(dynamics: sp.Eq) -> sp.Expr:
    """|sum tr(Lambda U_k) - sum tr(Q_k Lambda Q_{k+1}^T)| for Q_{r+1} from ``dynamics``."""
    lam = [sp.Rational(7, 10), sp.Rational(11, 10), sp.Rational(8, 5)]
    controls = [_cayley_rational(e, 7) for e in ([1, 2, -1], [-3, 1, 2], [2, -2, 1])]
    Qs = [_cayley_rational([1, -1, 3], 4)]
    for r, Ur in enumerate(controls):
        Qs.append(explicit(dynamics.rhs, {"Q_r": Qs[r], "Q_k": Qs[0], "U_r": Ur}))  # k frozen: 0
    left = sum(explicit(COST.function, {"U_k": Ur}, lam) for Ur in controls)
    right = sum(
        explicit(MV_FUNCTIONAL.rhs.function, {"Q_k": Qs[r], "Q_{k+1}": Qs[r + 1]}, lam)
        for r in range(len(controls))
    )
    return sp.Abs(left - right)


@D7.check(Level.EXACT_RATIONAL, form="corrected")
def d7_mv_functional_corrected() -> sp.Expr:
    r"""The proof's identity (displayed sums) along the corrected dynamics $Q_{r+1} = Q_r U_r$ with
    three exact rational rotations $U_r$ ($n = 3$): $|\mathrm{left} - \mathrm{right}|$."""
    return _mv_functional_gap(DYNAMICS)


@D7.check(Level.EXACT_RATIONAL, form="printed")
def d7_mv_functional_printed() -> sp.Expr:
    """The same identity along the printed dynamics $Q_{r+1} = Q_k U_r$ ($k$ frozen at 0)."""
    return _mv_functional_gap(DYNAMICS_PRINTED)


def _costate_gap(P0_formula: sp.Eq) -> float:
    """Run the theorem's equations (symrb.symmetric_flow) from P_0 given by the formula; the
    largest of the Q_k error against the 50-digit reference and the distance of P_k from SO(n)."""
    import symrb

    run = _mp_run()
    P0x = _numeric(P0_formula.rhs, {"Q_0": run["Q0"], "M_0": run["M0"]})
    # the theorem's map (h = 1) for Lambda/h is the reference's map at step h
    sol = symrb.symmetric_flow(run["Q0"], P0x, _LAM3 / _H, 1.0, _STEPS)
    Qs, Ps = sol.y.Q, sol.y.P
    dq = np.abs(Qs - run["Qf"]).max()
    off = np.abs(np.swapaxes(Ps, -1, -2) @ Ps - np.eye(3)).max()
    return float(np.max([dq, off, np.abs(np.linalg.det(Ps) - 1.0).max()]))


@D7.check(Level.FLOAT64, tol=1e-13, form="corrected")
def d7_costate_in_SO_is_a_choice() -> float:
    r"""The costate $P_0 = Q_0 \exp(\operatorname{asinh}(M_0/2))$ (displayed; in $\mathrm{SO}(3)$)
    run through symrb.symmetric_flow for 12 steps gives the $Q_k$ of the 50-digit reference started
    from $P_0 = Q_0 M_0/2$, and every $P_k$ stays in $\mathrm{SO}(3)$: largest of $\max|Q_k -
    Q_k^{\mathrm{ref}}|$, $\max|P_k^T P_k - I|$, $\max|\det P_k - 1|$ ($h = 0.1$,
    $\|M_0\|_{\mathrm{op}} = 1.66$)."""
    return _costate_gap(P0_SO)


@D7.check(Level.FLOAT64, tol=1e-13, form="printed")
def d7_costate_in_SO_printed() -> float:
    r"""The same residual for the costate $P_0 = Q_0 M_0/2$ of the same extremal (displayed): it
    gives the same $Q_k$, but $P_k$ is not in $\mathrm{SO}(3)$."""
    return _costate_gap(P0_GL)


def _flip_gap(relation: sp.Eq) -> sp.Expr:
    """Residual of det(-P) against ``relation`` for general symbolic P, n = 2 and n = 3."""
    total = sp.Integer(0)
    for k in (2, 3):
        Px = general_matrix("p", k)
        value = explicit(lhs_minus_rhs(relation), {"P_k": Px, "n": k})
        total += residual(value.doit())
    return total


@D7.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d7_flip_determinant() -> sp.Expr:
    r"""The displayed $\det(-P) = (-1)^n \det(P)$ for a general symbolic $P$, $n = 2$ and $n = 3$."""
    return _flip_gap(FLIP_DET)


@D7.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d7_flip_determinant_printed() -> sp.Expr:
    r"""The same residual for $\det(-P) = \det(P)$, which keeping $-P$ in $\mathrm{SO}(n)$ needs: it
    fails for $n = 3$."""
    return _flip_gap(FLIP_PRINTED)


def _ukdef_count_n2(on_branch: bool) -> sp.Expr:
    """|number of solutions U in SO(2) of J_D(U) = M - 1| (exact: every element of SO(2) is
    [[c, -s], [s, c]] with c^2 + s^2 = 1; lam = (7/10, 19/10), M_21 = 3/5); with ``on_branch``
    only those whose U Lambda has both eigenvalues in the open right half-plane."""
    lam = [sp.Rational(7, 10), sp.Rational(19, 10)]
    c, s = sp.symbols("c s", real=True)
    Ux = sp.Matrix([[c, -s], [s, c]])
    Mx = sp.Matrix([[0, -sp.Rational(3, 5)], [sp.Rational(3, 5), 0]])
    eqs = [*(explicit(JD["JD"], {"U": Ux}, lam) - Mx), c**2 + s**2 - 1]
    sols = [Ux.subs(sol) for sol in sp.solve(eqs, [c, s], dict=True)]
    if on_branch:
        sols = [u for u in sols if all(sp.re(ev) > 0 for ev in (u * sp.diag(*lam)).eigenvals())]
    return sp.Abs(len(sols) - 1)


@D7.check(Level.EXACT_RATIONAL, form="corrected")
def d7_ukdef_branch_n2() -> sp.Expr:
    r"""$n = 2$, exact: the solutions in $\mathrm{SO}(2)$ of the emitted $J_D(U) = M$ (a rational
    point) that lie on the branch through $I$: $|\mathrm{count} - 1|$."""
    return _ukdef_count_n2(on_branch=True)


@D7.check(Level.EXACT_RATIONAL, form="printed")
def d7_ukdef_unique_n2() -> sp.Expr:
    r"""The same count over all of $\mathrm{SO}(2)$: the rotations by $\theta$ and $\pi - \theta$
    both solve it."""
    return _ukdef_count_n2(on_branch=False)


def _ukdef_count_n3(on_branch: bool) -> float:
    """|number of solutions in SO(3) of J_D(U) = M - 1|, M = hat(0.3, -0.2, 0.4), from the
    invariant subspaces of the Hamiltonian matrix (every solution in O(3))."""
    M3 = ref.hat(np.array([0.3, -0.2, 0.4]))
    sols = [x for x in _all_jd_solutions(M3, _LAM3) if np.linalg.det(x) > 0]
    if on_branch:
        sols = [x for x in sols if _on_branch(x, _LAM3)]
    return float(abs(len(sols) - 1))


@D7.check(Level.FLOAT64, form="corrected")
def d7_ukdef_branch_n3() -> float:
    r"""$n = 3$: all solutions in $\mathrm{O}(3)$ of $U\Lambda - \Lambda U^T = M$ (reference $J_D$
    residual and orthogonality at rounding), found from the $n$-dimensional invariant subspaces of
    the Riccati equation's Hamiltonian matrix; those in $\mathrm{SO}(3)$ on the branch through $I$:
    $|\mathrm{count} - 1|$."""
    return _ukdef_count_n3(on_branch=True)


@D7.check(Level.FLOAT64, form="printed")
def d7_ukdef_unique_n3() -> float:
    r"""The same count over all of $\mathrm{SO}(3)$: four solutions (the continuations of $I$ and of
    the three half-turns about the principal axes)."""
    return _ukdef_count_n3(on_branch=False)


@D7.check(Level.FLOAT64, tol=1e-13)
def d7_symrb_flow_is_extremal() -> float:
    r"""symrb.symmetric_flow ($h = 1$, $n = 4$, 8 steps) from a random $P_0$ in $\mathfrak{gl}(4)$
    gives controls $U_k = Q_k^T Q_{k+1}$ at which the displayed cost is stationary for fixed $Q_0$,
    $Q_N$: its derivative along $Q_k(I + e\xi)$, every interior $k$ and basis $\xi$ of
    $\mathfrak{so}(4)$, is $\operatorname{tr}(\Lambda U_{k-1} \xi) - \operatorname{tr}(\Lambda \xi
    U_k)$ (summands of the displayed cost); largest absolute value."""
    import symrb

    rng = np.random.default_rng(71)
    lam = np.array([1.6, 1.9, 2.3, 2.7])
    Q0x = ref.random_rotation(4, rng)
    Qs = symrb.symmetric_flow(Q0x, 0.2 * rng.standard_normal((4, 4)), lam, 1.0, 8).y.Q
    Us = np.swapaxes(Qs[:-1], -1, -2) @ Qs[1:]
    worst = []
    for k in range(1, len(Qs) - 1):
        for i, j in itertools.combinations(range(4), 2):
            xi = np.zeros((4, 4))
            xi[i, j], xi[j, i] = 1.0, -1.0
            d = _numeric(COST.function, {"U_k": Us[k - 1] @ xi}, lam)
            d -= _numeric(COST.function, {"U_k": xi @ Us[k]}, lam)
            worst.append(abs(d))
    return float(np.max(worst))


_TARGET = np.array([1.0, -0.6, 0.8])  # rotation vector of Q_0^T Q_N: a turn by 1.41 rad


def _optimum(sign: int) -> tuple[np.ndarray, float, float]:
    """The global minimiser (``sign`` = 1) or maximiser (-1) of the displayed cost over SO(3)^3
    with Q_0 (a random rotation) and Q_N = Q_0 exp(hat(_TARGET)) given (plain NumPy/SciPy, see
    :mod:`._so_extremals`): its controls, the largest residual of the displayed Ukdef along the
    displayed discrbopteqns from P_0 = Q_0 M_0/2 with M_0 = J_D(U_0), and the largest distance of
    symrb.symmetric_flow's Q_k (h = 1, from that Q_0, P_0) from the optimum's Q_k."""
    import symrb

    Q0x = ref.random_rotation(3, np.random.default_rng(70))
    Us = _global_optimum(_LAM3, _rot(_TARGET), 3, sign)
    Qs = _states(Us, Q0x)
    Ps = [_numeric(P0_GL.rhs, {"Q_0": Q0x, "M_0": ref.J_D(Us[0], _LAM3)})]
    for Ux in Us:
        Ps.append(_numeric(DISCRBOPTEQNS[1].rhs, {"P_k": Ps[-1], "U_k": Ux}))
    ukdef = lhs_minus_rhs(UKDEF)
    theorem = max(
        float(np.abs(_numeric(ukdef, {"U_k": u, "Q_k": q, "P_k": p}, _LAM3)).max())
        for u, q, p in zip(Us, Qs, Ps, strict=False)
    )
    flow = symrb.symmetric_flow(Q0x, Ps[0], _LAM3, 1.0, len(Us)).y.Q
    gap = float(np.abs(flow - Qs).max()) if flow.shape == Qs.shape else np.inf
    return Us, theorem, gap


def _is_discrete_rigid_body(sign: int) -> float:
    """Largest of: the optimum's Ukdef residual, its distance from symrb's flow, how far the
    least real part of the eigenvalues of U_k Lambda is below 0 (off the branch through I), and
    the number of U_k that do not continue to I along J_D(V) = tM_k, t from 1 to 0."""
    Us, theorem, gap = _optimum(sign)
    below = max(0.0, -min(_margin(u, _LAM3) for u in Us))
    elsewhere = sum(_continued_to(u, _LAM3) != "I" for u in Us)
    return max(theorem, gap, below, float(elsewhere))


@D7.check(Level.FLOAT64, tol=1e-12, form="corrected")
def d7_maximiser_is_discrete_rigid_body() -> float:
    r"""The global maximiser of the displayed cost (best of 12 BFGS runs over rotation vectors,
    polished to an extremal; $n = 3$, $N = 3$, $Q_0^T Q_N$ a turn by 1.41 rad) solves the theorem's
    equations with its costate, every $U_k \Lambda$ has its eigenvalues in the open right
    half-plane, each $U_k$ continues to $I$ along $J_D(V) = tM_k$ ($t$ from 1 to 0), and
    symrb.symmetric_flow started from its $Q_0$ and $M_0 = J_D(U_0)$ reproduces its $Q_k$: the
    largest of the Ukdef residual, $\max|Q_k - Q_k^{\mathrm{symrb}}|$, the negative part of $\min
    \operatorname{Re} \operatorname{eig}$ and the number of $U_k$ that continue elsewhere."""
    return _is_discrete_rigid_body(-1)


@D7.check(Level.FLOAT64, tol=1e-12, form="printed")
def d7_minimiser_is_discrete_rigid_body() -> float:
    r"""The same residual for the global minimiser, which the problem as printed asks for and the
    theorem's $U_k$ is read as: it solves the theorem's equations, but symrb's flow from its data
    leaves it and its $U_k \Lambda$ have eigenvalues in the left half-plane."""
    return _is_discrete_rigid_body(1)


@D7.check(Level.FLOAT64, tol=1e-12, form="corrected")
def d7_minimiser_branch() -> float:
    r"""The global minimiser of the same problem solves the theorem's equations with its costate,
    and each of its $U_k$ is off the branch through $I$ and continues (Newton along $J_D(V) = tM_k$,
    $t$ from 1 to 0) to the half-turn about the axis of the smallest $\lambda_i$ ($\lambda_1 =
    0.7$): the largest of the Ukdef residual, the largest over $k$ of $\max(0, \min
    \operatorname{Re} \operatorname{eig}(U_k \Lambda))$ and the number of $U_k$ that continue
    elsewhere."""
    Us, theorem, _gap = _optimum(1)
    above = max(0.0, max(_margin(u, _LAM3) for u in Us))
    elsewhere = sum(_continued_to(u, _LAM3) != "R1" for u in Us)
    return max(theorem, above, float(elsewhere))


# the paper's sentences (the definition, the theorem, the remark after it and the proof)

D7.sentence(
    r"We now derive the discrete symmetric rigid body equations by considering discrete optimal "
    r"control on the special orthogonal group.",
    kind="prose",
    reason="announces the definition and theorem",
)
D7.sentence(
    r"Let $\Lambda$ be a positive definite diagonal matrix.",
    d7_ukdef_branch_n3,
    d7_symrb_flow_is_extremal,
)
D7.sentence(
    r"Let $\overline{Q}_0, \overline{Q}_N\in \operatorname{SO}(n)$ be given and fixed.",
    d7_symrb_flow_is_extremal,
)
D7.sentence(
    r"Let $\hat{V}(U_0, \ldots, U_{N-1}):=\sum_{k=0}^{N-1} \operatorname{trace}(\Lambda U_{k}), "
    r"\quad U_k \in \operatorname{SO}(n).$",
    d7_mv_functional_corrected,
    d7_symrb_flow_is_extremal,
)
D7.sentence(
    r"Define the optimal control problem $\mathop{\rm min}_{U_k\in\operatorname{SO}(n)}"
    r"\hat{V}(U_0,\ldots, U_{N-1})= \mathop{\rm min}_{U_k\in\operatorname{SO}(n)} "
    r"\sum_{k=0}^{N-1}\operatorname{trace}(\Lambda U_{k})$ subject to dynamics and initial and "
    r"final data $Q_{r+1}=Q_kU_{r}, \qquad Q_0=\overline{Q}_0, \qquad Q_N =\overline{Q}_N$ for "
    r"$Q_r, U_r\in \operatorname{SO}(n)$, $r=0,1, \ldots, N-1$.",
    d7_mv_functional_corrected,
    d7_mv_functional_printed,
    d7_symrb_flow_is_extremal,
    d7_maximiser_is_discrete_rigid_body,
    d7_minimiser_is_discrete_rigid_body,
    d7_minimiser_branch,
)
D7.sentence(
    r"Theorem. A solution of the optimal control problem in Definition (mvoptprobm) satisfies "
    r"the optimal evolution equations $Q_{k+1} = Q_kU_{k}\,, \qquad P_{k+1} = P_kU_{k}\,, \qquad "
    r"k=0, \ldots, N-1,$ where $P_k\in \operatorname{SO}(n)$ is the discrete covector in the "
    r"discrete maximum principle and $U_{k} \in \operatorname{SO}(n)$ is defined by "
    r"$U_{k}\Lambda - \Lambda U^T_{k}=Q_k^TP_k-P_k^TQ_k\,.$",
    d7_costate_gradients,
    d7_final_and_flip,
    d7_symrb_flow_is_extremal,
    d7_costate_in_SO_is_a_choice,
    d7_costate_in_SO_printed,
    d7_ukdef_branch_n2,
    d7_ukdef_unique_n2,
    d7_ukdef_branch_n3,
    d7_ukdef_unique_n3,
    d7_maximiser_is_discrete_rigid_body,
    d7_minimiser_is_discrete_rigid_body,
    d7_minimiser_branch,
)
D7.sentence(
    r"Equation (Ukdef) can be solved for $U_k$ under certain circumstances, as discussed in "
    r"[MoVe1991] and [CaLe2001]; we discuss this issue further below.",
    d7_ukdef_branch_n2,
    d7_ukdef_branch_n3,
    d7_minimiser_is_discrete_rigid_body,
    d7_minimiser_branch,
)
D7.sentence(
    r"Proof. Applying Proposition (gendiscprop), we get "
    r"$H(P_{k+1},Q_k,U_{k})=\operatorname{trace}(P_{k+1}^TQ_kU_{k}) "
    r"-\operatorname{trace}(\Lambda U_{k}) =\operatorname{trace}\left((P^T_{k+1}Q_k-\Lambda)"
    r"U_{k}\right)\,.$",
    d7_costate_gradients,
    d7_symequation,
)
D7.sentence(
    r"Note that $\hat{V}(U_0, \ldots, U_{N-1})= \sum_{k=0}^{N-1}\operatorname{trace}(\Lambda "
    r"U_{k})= \sum_{k=0}^{N-1}\operatorname{trace}(U^T_{k} \Lambda)=\sum_{k=0}^{N-1}"
    r"\operatorname{trace}(Q_k\Lambda Q_{k+1}^T)$ is the Moser-Veselov functional [MoVe1991] "
    r"and that this functional is linear in the controls.",
    d7_mv_functional_corrected,
    d7_mv_functional_printed,
)
D7.sentence(
    r"We need to find the critical points of $H(P_{k+1},Q_k,U_{k})$ where $U_k^TU_k=I$ since "
    r"$U_k\in \operatorname{SO}(n)$.",
    d7_critical_points,
)
D7.sentence(
    r"Thus, we need to minimize a functional of the form $\operatorname{trace}(AU)$, $A$ fixed, "
    r"subject to $U^TU=I$.",
    d7_critical_points,
)
D7.sentence(
    r"Set $\tilde{V}(U):=\operatorname{trace}(AU)+\tfrac{1}{2} \operatorname{trace}\left(\Sigma "
    r"(U^TU-I)\right)\,,$ where $U \in \operatorname{SO}(n)$ and $\Sigma=\Sigma^T$ is a "
    r"$N \times N$ matrix of Lagrange multipliers.",
    d7_multiplier_derivative,
    d7_multiplier_n_by_n,
    d7_multiplier_N_by_N,
)
D7.sentence(
    r"Then $\delta\tilde{V}(U) \cdot \delta U= \operatorname{trace}(A\delta U+\Sigma U^T\delta "
    r"U)=0$ implies $A+\Sigma U^T=0$ where $U^TU=I$.",
    d7_multiplier_derivative,
    d7_critical_points,
)
D7.sentence(r"Hence $\Sigma=-AU$.", d7_critical_points)
D7.sentence(
    r"But since $\Sigma=\Sigma^T$ the extrema of our optimization problem are obtained when "
    r"$AU=U^TA^T$.",
    d7_critical_points,
)
D7.sentence(
    r"Applying this observation to our case (see (discham)), we have $\nabla_{U_k}H = 0$ when "
    r"$\left(P_{k+1}^TQ_k-\Lambda\right)U_{k} =U^T_{k}\left(Q_k^TP_{k+1}-\Lambda\right)\,,$ that "
    r"is, $U^T_{k}\Lambda-\Lambda U_{k}= U^T_{k}Q^T_kP_{k+1}-P^T_{k+1}Q_kU_{k}$ or, "
    r"equivalently, $U_{k}\Lambda-\Lambda U^T_{k}=-Q^T_kP_{k+1}U^T_{k}+ U_{k}P^T_{k+1}Q_k\,.$",
    d7_symequation,
    d7_critical_points,
)
D7.sentence(
    r"Also, by (eq8.3), $P_k=\nabla_{Q_k}H=\left(U_{k}P^T_{k+1}\right)^T=P_{k+1}U^T_{k}\,, "
    r"\qquad Q_{k+1} = \nabla_{P_{k+1}}H = Q_kU_k\,.$",
    d7_costate_gradients,
)
D7.sentence(r"Hence we obtain equations (discrbopteqns).", d7_costate_gradients)
D7.sentence(
    r"Combining (discrbopteqns) with (symequation) we get "
    r"$U_{k}\Lambda-\Lambda U^T_{k}=P_k^TQ_k-Q_k^TP_k$",
    d7_final_and_flip,
)
D7.sentence(
    r"Now replace $P_k$ by $-P_k$ and $P_{k+1}$ by $-P_{k+1}$; thus (discrbopteqns) remains "
    r"unchanged but (equ_final_th_2.7) is transformed to (Ukdef) which yields the stated result.",
    d7_final_and_flip,
    d7_flip_determinant,
    d7_flip_determinant_printed,
)
