r"""S5 (Section 3.2, eqs. ``rboptcontprob``, ``optr``, ``eqnr``, ``srb1``): the maximum principle for
the smooth rigid body control problem.

Minimising 1/4 int <U, J(U)> dt subject to Qdot = Q U gives extremals Qdot = Q U, Pdot = P U with
U = J^-1(Q^T P - P^T Q).  Erratum: the printed Hamiltonian
:math:`\langle P,QU\rangle + \tfrac14\langle U,J(U)\rangle` is convex in :math:`U` (no
maximum); the maximum principle uses :math:`-\tfrac14\langle U,J(U)\rangle`, maximised at the
printed control, with the pairing :math:`\tfrac12\operatorname{tr}(A^TB)` on
:math:`\mathfrak{gl}(n)`.

Emitted to ``symrb/_generated/symmetric_rigid_body.py``: ``symmetric_rigid_body_rhs`` (the
extremal field; S6, S7, S11 and S12 read it from here).  S8 reuses the maximiser and the
gradients in the pairing defined here.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.claims.section3._display import GlPair
from derivations.claims.section3._exact import count_nonzero
from derivations.claims.section3._inertia import ARG_LAM, lam_symbols
from derivations.claims.section3._symmetric import ARG_P, ARG_Q, MOMENTUM, P, Pdot, Q, Qdot, U
from derivations.registry import Level, claim
from derivations.symbolic import (
    Pair,
    Words,
    eq,
    explicit,
    general_matrix,
    skew_matrix,
    trace_words_of,
)
from derivations.vocabulary import Jinv, Kernel, Lam, W, matrix

S5 = claim(
    "S5",
    label="rboptcontprob, optr, eqnr, srb1",
    title="Maximum principle for the smooth rigid body control problem",
    statement="The extremals of the problem of minimising [[cost]] over $U\\in\\mathfrak{so}(n)$ "
    "subject to [[eqnr]] with $Q(0)$ and $Q(T)$ given satisfy [[srb1]] with [[optimal_U]], where "
    "$P\\in\\mathfrak{gl}(n)$ is the costate of the maximum principle.",
    expected="holds after correction",
    headline="[[H_corrected]]",
    printed="The Hamiltonian [[H_printed]], maximised with respect to $U$, gives [[optimal_U]].",
    corrected="With the costate paired with $\\dot Q$ by [[pairing]] on $\\mathfrak{gl}(n)$ "
    "(which extends the pairing of S1 on $\\mathfrak{so}(n)$), the Hamiltonian [[H_corrected]] "
    "is maximised at [[optimal_U]], and the extremals follow [[costate]].",
    note="The printed Hamiltonian has the cost with a plus sign and is maximised, but it is "
    "convex in $U$, so it has no maximum. Corrected: $H = \\langle P, QU\\rangle - "
    "\\tfrac14\\langle U, J(U)\\rangle$, with $P$ paired with $\\dot Q$ by "
    "$\\tfrac12\\operatorname{tr}(P^T \\dot Q)$, is maximised exactly at the printed $U$. The "
    "printed $H$ has the Hessian $+\\tfrac12\\operatorname{diag}(\\Lambda_i + \\Lambda_j)$ in $U$ "
    "and its stationary point is $U = -J^{-1}(Q^T P - P^T Q)$. The maximum principle with the "
    "normal multiplier $-1$ on the running cost gives the corrected $H$. The printed factor of "
    "$U$ fixes the pairing of $P$ with $\\dot Q$ as $\\tfrac12\\operatorname{tr}(P^T \\dot Q)$ "
    "(with $c\\operatorname{tr}(P^T QU)$ the maximiser is $2c\\,J^{-1}(\\cdots)$). The costate "
    "equations do not depend on the sign.",
    section="3.2",
    where="Section 3.2 (Smooth optimal control and the symmetric rigid body equations), the first "
    "definition (minimise $\\tfrac14\\int_0^T \\langle U, J(U)\\rangle\\,dt$ subject to $\\dot Q "
    "= QU$), the first proposition ($U = J^{-1}(Q^T P - P^T Q)$) and the remark after it (the "
    "Hamiltonian)",
)
_A, _B = matrix("A"), matrix("B")
PAIRING = S5.formula("pairing", eq(GlPair(_A, _B), sp.Trace(_A.T * _B) / 2))
COST = Pair(U, Lam * U + U * Lam) / 4  # the running cost, in the pairing of S1 on so(n)
_t, _T = sp.symbols("t T", positive=True)
S5.formula("cost", sp.Integral(COST, (_t, 0, _T)))
EQNR = S5.formula("eqnr", eq(Qdot, Q * U))
SRB1 = S5.formula("srb1", (EQNR, eq(Pdot, P * U)))
OPTIMAL_U = S5.formula("optimal_U", eq(U, Jinv(MOMENTUM)))
#: The symbols H, Q, P of the displayed Hamiltonian and costate equations (S8 and S12 use them).
H_SYM = sp.Symbol("H")
H_PRINTED = S5.formula("H_printed", eq(H_SYM, GlPair(P, Q * U) + COST))
H_CORRECTED = S5.formula("H_corrected", eq(H_SYM, GlPair(P, Q * U) - COST))
Q_SYM, P_SYM = sp.symbols("Q P")
_Hf = sp.Function("H")(Q_SYM, P_SYM)
COSTATE = S5.formula(
    "costate", (eq(Qdot, sp.Derivative(_Hf, P_SYM)), eq(Pdot, -sp.Derivative(_Hf, Q_SYM)))
)

SYMMETRIC_RIGID_BODY_RHS = Kernel(
    name="symmetric_rigid_body_rhs",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_P, ARG_LAM],
    outputs={"Qdot": Q * Jinv(MOMENTUM), "Pdot": P * Jinv(MOMENTUM)},
    doc="Symmetric rigid body field (paper, Section 3.2).\n\n"
    "Qdot = Q U, Pdot = P U, U = J^{-1}(Q^T P - P^T Q), J^{-1}(X)_ij = X_ij / (lam_i + lam_j).",
    claims=("S5", "S6", "S7", "S11", "S12"),
)


def unfold(expr: sp.Basic) -> sp.Basic:
    """Replace every displayed pairing <a, b> by the right side of the displayed definition."""
    return expr.replace(
        lambda e: isinstance(e, GlPair),
        lambda e: PAIRING.rhs.xreplace({_A: e.args[0], _B: e.args[1]}),
    )


def _elementary(k: int, i: int, j: int) -> sp.Matrix:
    E = sp.zeros(k, k)
    E[i, j] = 1
    return E


def gl_gradient(F: sp.Expr, X: sp.Matrix) -> sp.Matrix:
    """The G with <G, dX> = dF for the displayed pairing (its Gram matrix on the elementary
    matrices, so no coefficient is assumed); X has independent entries."""
    k = X.rows
    basis = [_elementary(k, i, j) for i in range(k) for j in range(k)]
    gram = sp.Matrix(
        len(basis), len(basis), lambda a, b: explicit(PAIRING.rhs, {"A": basis[a], "B": basis[b]})
    )
    dF = sp.Matrix([sp.diff(F, X[i, j]) for i in range(k) for j in range(k)])
    return sp.Matrix(k, k, list(gram.solve(dF)))


def derivative_rule(relation: sp.Eq) -> tuple[sp.Expr, sp.Symbol]:
    """``Xdot = c dH/dY`` as (c, Y)."""
    c, d = relation.rhs.as_coeff_Mul()
    if not isinstance(d, sp.Derivative) or d.expr != _Hf or len(d.variables) != 1:
        raise ValueError(f"{relation} is not a multiple of a partial derivative of H")
    return c, d.variables[0]


def maximiser(H: sp.Expr, Ux: sp.Matrix, lam: Sequence[sp.Expr]) -> tuple[sp.Matrix, sp.Integer]:
    """The stationary point of H in the skew U (entries u_ij, i < j), and the number of ways it
    fails to be a maximum for every lam with lam_i + lam_j > 0: the Hessian must be diagonal with
    entries -c (lam_i + lam_j), c > 0 a number."""
    k = Ux.rows
    pairs = list(itertools.combinations(range(k), 2))
    us = [Ux[i, j] for i, j in pairs]
    hess = sp.hessian(H, us)
    bad = 0
    for a, b in itertools.product(range(len(us)), repeat=2):
        if a != b:
            bad += sp.expand(hess[a, b]) != 0
            continue
        i, j = pairs[a]
        c = sp.cancel(hess[a, a] / (lam[i] + lam[j]))
        bad += not (c.is_number and c < 0)
    sol = sp.solve([sp.diff(H, u) for u in us], us, dict=True)
    if len(sol) != 1:
        raise ValueError("dH/dU = 0 has no unique solution")
    return Ux.xreplace(sol[0]), sp.Integer(bad)


def _setting(form: str) -> tuple[list[sp.Symbol], dict[str, sp.Matrix], sp.Expr]:
    """n = 3 with general Q, P, skew U and symbolic Lambda: lam, the matrices by name and the
    displayed Hamiltonian ``H_<form>`` (form ``printed`` or ``corrected``) evaluated there."""
    lam = lam_symbols(3)
    env = {"Q": general_matrix("q", 3), "P": general_matrix("p", 3), "U": skew_matrix("u", 3)}
    return lam, env, sp.expand(explicit(unfold(S5.formulas[f"H_{form}"].rhs), env, lam))


def stationary_control(form: str) -> tuple[sp.Matrix, sp.Matrix, sp.Integer]:
    """For the displayed Hamiltonian ``H_<form>`` (see :func:`_setting`): its stationary point in
    U, the displayed optimal control J^-1(Q^T P - P^T Q), and the number of ways the stationary
    point fails to be a maximum."""
    lam, env, Hx = _setting(form)
    Ustar, not_max = maximiser(Hx, env["U"], lam)
    return Ustar, explicit(OPTIMAL_U.rhs, env, lam), not_max


def _s5_extremals(form: str) -> sp.Integer:
    lam, env, Hx = _setting(form)
    Qx, Px, Ux = env["Q"], env["P"], env["U"]
    Ustar, shown, not_max = stationary_control(form)
    total = not_max + count_nonzero(Ustar - shown)
    # the emitted field is the displayed (Qdot, Pdot) = (QU, PU) at the maximiser ...
    at_max = {"Q": Qx, "P": Px, "U": Ustar}
    for out, rel in zip(("Qdot", "Pdot"), SRB1, strict=True):
        kernel = explicit(SYMMETRIC_RIGID_BODY_RHS[out], env, lam)
        total += count_nonzero(kernel - explicit(rel.rhs, at_max, lam))
        # ... and Hamilton's costate equations of H, gradients in the displayed pairing
        c, var = derivative_rule(COSTATE[0 if out == "Qdot" else 1])
        grad = gl_gradient(Hx, Px if var == P_SYM else Qx).xreplace(
            {u: v for u, v in zip(Ux, Ustar, strict=True) if u != 0}
        )
        total += count_nonzero(kernel - c * grad)
    return total


@S5.check(Level.SYMBOLIC_FIXED_N, form="printed")
def s5_printed_hamiltonian() -> sp.Integer:
    r"""The printed Hamiltonian (pairing as displayed, general $Q$, $P$, skew $U$, symbolic
    $\Lambda$, $n = 3$): is it maximised, at the displayed $U$, and is the emitted field $(QU, PU)$
    with $\dot Q = \partial H/\partial P$, $\dot P = -\partial H/\partial Q$ there? Residual: the
    number of entries or conditions that fail (the printed $H$ is convex in $U$, its stationary
    point is $-J^{-1}(Q^T P - P^T Q)$)."""
    return _s5_extremals("printed")


@S5.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s5_corrected_hamiltonian() -> sp.Integer:
    r"""The same for the corrected Hamiltonian: its Hessian in $U$ is negative definite ($-c
    (\lambda_i + \lambda_j)$, $c > 0$), its maximiser is the displayed $U = J^{-1}(Q^T P - P^T Q)$,
    and the emitted symmetric rigid body field equals $(QU, PU)$ and the displayed costate equations
    (gradients in the displayed pairing, solved from its Gram matrix) at that $U$."""
    return _s5_extremals("corrected")


@S5.check(Level.FLOAT64, tol=1e-9)
def s5_first_variation() -> float:
    r"""Extremals are critical points: along a trajectory of
    symrb.symmetric.symmetric_rigid_body_rhs ($n = 4$, $P$ in $\mathfrak{gl}(n)$, $t$ in $[0, 2]$,
    DOP853 rtol 1e-13), the first variation of the cost in a control direction $dU$, $\int \frac12
    \langle J U, dU\rangle\, dt$ with $J$ from the reference, equals $\langle P_T, dQ_T\rangle$ in
    the displayed pairing, $dQ$ from the tangent-linear equation $d\dot Q = dQ\, U + Q\, dU$, $dQ(0)
    = 0$. Relative difference (it vanishes only when $J U = Q^T P - P^T Q$ along the flow)."""
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(5)
    k, T = 4, 2.0
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    Q0, P0 = ref.random_rotation(k, rng), rng.standard_normal((k, k))
    V0, V1 = ref.random_skew(k, rng), ref.random_skew(k, rng)
    size = k * k

    def field(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        Qy, Py = y[:size].reshape(k, k), y[size : 2 * size].reshape(k, k)
        dQ, dP = symrb.symmetric.symmetric_rigid_body_rhs(Qy, Py, lam)
        return dQ, dP, np.linalg.solve(Qy, dQ)  # U = Q^{-1} Qdot

    def f(t: float, y: np.ndarray) -> np.ndarray:
        dQ, dP, Uy = field(y)
        var = y[2 * size :].reshape(k, k)
        return np.concatenate(
            [dQ.ravel(), dP.ravel(), (var @ Uy + y[:size].reshape(k, k) @ (V0 + t * V1)).ravel()]
        )

    y0 = np.concatenate([Q0.ravel(), P0.ravel(), np.zeros(size)])
    sol = solve_ivp(f, (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
    nodes, weights = np.polynomial.legendre.leggauss(60)
    lhs = 0.0
    for x, wt in zip(nodes, weights, strict=True):
        t = T * (x + 1) / 2
        Ut = field(sol.sol(t))[2]
        lhs += T * wt / 2 * 0.5 * float(ref.pairing(ref.J(Ut, lam), V0 + t * V1))
    PT, dQT = sol.y[size : 2 * size, -1].reshape(k, k), sol.y[2 * size :, -1].reshape(k, k)
    rhs = float(explicit(PAIRING.rhs, {"A": sp.Matrix(PT), "B": sp.Matrix(dQT)}))
    return abs(lhs - rhs) / abs(rhs)


# ---------------------------------------------------------------------------------------------
# every n: noncommutative letters, derivatives along a direction, traces compared as words

_t_dir = sp.Symbol("t")


def _traced(expr: sp.Expr, w: Words) -> sp.Expr:
    """A scalar built from the displayed pairings and traces as the polynomial X with value
    tr(X): the gl(n) pairing by its displayed definition, the so(n) pairing <a, b> =
    -tr(a b)/2 of S1."""
    e = unfold(expr).replace(
        lambda x: isinstance(x, Pair), lambda x: -sp.Trace(x.args[0] * x.args[1]) / 2
    )
    return w.trace_argument(e)


def _trace_gap(a: sp.Expr, b: sp.Expr, w: Words) -> int:
    """Trace words left in tr(a) - tr(b), written as tr(d + d^T)/2 (a trace equals that of its
    transpose, which brings skew and symmetric letters to one form): 0 when tr(a) = tr(b)."""
    d = sp.expand(a - b)
    return len(trace_words_of(d + w.T(d)))


def _along(X: sp.Expr, var: sp.Symbol, dvar: sp.Symbol, w: Words, order: int = 1) -> sp.Expr:
    """d^order/dt^order of the polynomial X with var -> var + t dvar (and its transpose letter
    with it), at t = 0."""
    moved = {var: var + _t_dir * dvar, w.T(var): w.T(var) + _t_dir * w.T(dvar)}
    if w.T(var) == -var:  # a skew letter has no transpose letter of its own
        moved = {var: var + _t_dir * dvar}
    return sp.diff(sp.expand(X.xreplace(moved)), _t_dir, order).xreplace({_t_dir: 0})


def _s5_general_n(form: str) -> sp.Integer:
    """Every n, noncommutative Q, P (general), U, dU (skew), Lambda (symmetric): trace words by
    which the displayed H_<form> fails (1) dH = <X - J(U), dU>/2 along skew dU, X the argument
    of the displayed U = J^-1(X) (so dH = 0 exactly there, J invertible), (2) d^2H =
    -<dU, J(dU)>/2 (negative definite by S2), (3) the displayed costate equations: dH along dP
    and dQ equal the displayed pairing with Qdot/c and Pdot/c of the displayed srb1."""
    w = Words(symmetric=["Lambda"], skew=["U", "dU"])
    q, p, u, du, lam = w.letters("Q P U dU Lambda")
    H = _traced(S5.formulas[f"H_{form}"].rhs, w)
    # the displayed U = J^-1(X) is W o X (vocabulary.Jinv), which solves J(U) = X
    (mom,) = (w.of(a) for a in OPTIMAL_U.rhs.args if a != W)
    J = lambda x: lam * x + x * lam  # noqa: E731 - the displayed J of S2
    pair = lambda a, b: -a * b / 2  # noqa: E731 - <a, b> = -tr(a b)/2, as a trace argument
    total = _trace_gap(_along(H, u, du, w), pair(mom - J(u), du) / 2, w)
    total += _trace_gap(_along(H, u, du, w, 2), -pair(du, J(du)) / 2, w)
    for rel, costate in zip(SRB1, COSTATE, strict=True):
        c, var = derivative_rule(costate)
        X, dX = (p, w("dP")) if var == P_SYM else (q, w("dQ"))
        rhs = w.of(rel.rhs)
        shown = _traced(GlPair(_A, _B), w).xreplace({w("A"): rhs / c, w("B"): dX})
        shown = shown.xreplace({w.T(w("A")): w.T(rhs) / c})
        total += _trace_gap(_along(H, X, dX, w), shown, w)
    return sp.Integer(total)


@S5.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s5_corrected_general_n() -> sp.Integer:
    r"""Every $n$ (noncommutative $Q$, $P$, skew $U$, symmetric $\Lambda$, derivatives along a
    direction, traces compared as words): the corrected Hamiltonian has $dH = \langle M - J(U),
    dU\rangle/2$ along skew $dU$, zero exactly at the displayed $U = J^{-1}(Q^T P - P^T Q)$, second
    derivative $-\langle dU, J(dU)\rangle/2$ (a maximum where $J$ is positive definite, S2), and its
    gradients in $P$ and $Q$ in the displayed pairing give the displayed $\dot Q = Q U$, $\dot P = P
    U$ through the displayed costate equations."""
    return _s5_general_n("corrected")


@S5.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s5_printed_general_n() -> sp.Integer:
    r"""The same for the printed Hamiltonian: $dH = \langle M + J(U), dU\rangle/2$ and $d^2 H =
    +\langle dU, J(dU)\rangle/2$, so it is convex in $U$ for every $n$ and its stationary point is
    $-J^{-1}(M)$, not the displayed $U$ (trace words left)."""
    return _s5_general_n("printed")


# the paper's sentences
S5.sentence(
    r"Now we briefly review, see [BlCr1996] and [BlBrCr1997], two results which link the theory "
    r"of optimal control with the rigid body equations.",
    kind="prose",
    reason="announces the two propositions that follow, with citations",
)
S5.sentence(
    r"Let $T >0$, $Q_0, Q_T \in \operatorname{SO}(n)$ be given and fixed.",
    s5_first_variation,
)
S5.sentence(
    r"Let the rigid body optimal control problem be given by $\min_{U\in \mathfrak{so}(n)} "
    r"\frac{1}{4}\int_0^T \langle U,J(U)\rangle dt$ subject to the constraint on $U$ that there "
    r"be a curve $Q(t) \in \operatorname{SO}(n)$ such that $\dot Q=QU\qquad Q(0)=Q_0,\qquad "
    r"Q(T)=Q_T.$",
    s5_first_variation,
)
S5.sentence(
    r"The rigid body optimal control problem has optimal evolution equations $\dot{Q}=QU\qquad "
    r"\dot{P}=PU$ where $P$ is the costate vector given by the maximum principle.",
    s5_corrected_hamiltonian,
    s5_first_variation,
    s5_corrected_general_n,
)
S5.sentence(
    r"The optimal controls in this case are given by $U=J^{-1}(Q^TP-P^TQ).$",
    s5_printed_hamiltonian,
    s5_corrected_hamiltonian,
    s5_first_variation,
    s5_corrected_general_n,
    s5_printed_general_n,
)
S5.sentence(
    r"The proof (see [BlCr1996]) simply involves, as in the discrete analysis above, writing the "
    r"Hamiltonian of the maximum principle as $H= \left\langle P,QU \right\rangle +\frac{1}{4} "
    r"\left\langle U,J(U) \right\rangle,$ where the costate vector $P$ is a multiplier "
    r"enforcing the dynamics, and then maximizing with respect to $U$ in the standard fashion "
    r"(see, for example, Brockett [1973]).",
    s5_printed_hamiltonian,
    s5_corrected_hamiltonian,
    s5_corrected_general_n,
    s5_printed_general_n,
)
S5.sentence(
    r"We refer to the equations (srb1) as the symmetric representation of the rigid body "
    r"equations.",
    kind="prose",
    reason="names the equations",
)
S5.sentence(
    r"We can now recover the classical rigid body equations:",
    kind="prose",
    reason="announces the next proposition (S6)",
)
