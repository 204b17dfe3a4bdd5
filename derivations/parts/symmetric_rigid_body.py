r"""Smooth optimal control and the symmetric rigid body (paper, Sections 3.2-3.3): claims S5-S12.

Emitted to ``symrb/_generated/symmetric_rigid_body.py``: the momentum map
:math:`M = Q^TP - P^TQ` (S6), the symmetric rigid body field (S5, S6, S12), the McLachlan-Scovel
field (S7), the state and costate fields for a given control (S8) and the Hamiltonian on
:math:`\mathfrak{gl}(n)\times\mathfrak{gl}(n)` (S12).  Each kernel is one object: the evidence
below evaluates it (explicit matrices for fixed n, noncommutative words for every n) and the
printer prints it.

What was found (details in the claims' notes):

* S5: the printed Hamiltonian :math:`\langle P,QU\rangle + \tfrac14\langle U,J(U)\rangle` is convex
  in :math:`U` (no maximum); the maximum principle uses :math:`-\tfrac14\langle U,J(U)\rangle`,
  maximised at the printed control, with the pairing :math:`\tfrac12\operatorname{tr}(A^TB)` on
  :math:`\mathfrak{gl}(n)`.
* S7: for a costate :math:`B` with :math:`Q^TB` skew the extremal control is
  :math:`J^{-1}(2Q^TB)`, so (rbnlms) holds for :math:`2B` (equivalently for
  :math:`P - QP^TQ`), not for the costate itself.
* S8: the endpoint condition is :math:`P^a_T = -2\,\partial\phi/\partial Q^a_T` (minus the gradient
  in the pairing above), not :math:`+\partial\phi/\partial Q^a_T`.
* S10: the exponent of (Pequ) must be read :math:`\sinh^{-1}(M/2)`.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from derivations import reference as ref
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Pair,
    Words,
    eq,
    explicit,
    general_matrix,
    letters_of,
    skew_matrix,
    trace_residual,
)
from derivations.vocabulary import Arg, Jinv, Kernel, Lam, W, matrix, n

Q, P, B, U = matrix("Q"), matrix("P"), matrix("B"), matrix("U")
M, Om = matrix("M"), matrix("Omega")
Qdot, Pdot, Bdot, Mdot = matrix("Qdot"), matrix("Pdot"), matrix("Bdot"), matrix("Mdot")
ARG_Q = Arg("Q", "(..., n, n)", "configuration (SO(n) is invariant; any square matrix accepted)")
ARG_P = Arg("P", "(..., n, n)", "costate")
ARG_B = Arg("B", "(..., n, n)", "McLachlan-Scovel costate, Q^T B skew")
ARG_U = Arg("U", "(..., n, n)", "control, skew")
ARG_LAM = Arg("lam", "(..., n)", "diagonal of Lambda, lam_i + lam_j > 0")

#: The momentum map of the symmetric representation; every kernel below is built on this object.
MOMENTUM = Q.T * P - P.T * Q


def _lam(k: int) -> list[sp.Symbol]:
    return list(sp.symbols(f"lam1:{k + 1}", real=True))


# =============================================================================================
# private helpers: display objects and noncommutative tools (candidates for derivations.symbolic)


class GlPair(sp.Expr):
    """The pairing of two matrices on gl(n), shown with angle brackets; its meaning is the
    registered formula S5 ``pairing`` (see :func:`_unfold`)."""

    is_commutative = True

    def __new__(cls, a: sp.Basic, b: sp.Basic) -> GlPair:
        return super().__new__(cls, a, b)

    def _latex(self, printer: Any) -> str:
        a, b = self.args
        return rf"\left\langle {printer._print(a)}, {printer._print(b)}\right\rangle"


class OpNorm(sp.Expr):
    """The operator norm of a matrix (a display object; the evidence computes it with NumPy)."""

    is_commutative = True
    is_real = True

    def __new__(cls, a: sp.Basic) -> OpNorm:
        return super().__new__(cls, a)

    def _latex(self, printer: Any) -> str:
        return rf"\left\|{printer._print(self.args[0])}\right\|_{{\rm op}}"


class MatFn(sp.MatrixExpr):
    """A named matrix function (``exp``, ``asinh``, ``sqrt``) of a matrix expression, for display;
    :func:`_evaluate` evaluates it."""

    _LATEX = {
        "exp": r"e^{{{}}}",
        "asinh": r"\sinh^{{-1}}\left({}\right)",
        "sqrt": r"\left({}\right)^{{1/2}}",
    }

    def __new__(cls, name: str | sp.Symbol, arg: sp.MatrixExpr) -> MatFn:
        return super().__new__(cls, sp.Symbol(name) if isinstance(name, str) else name, arg)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[1].shape

    def _latex(self, printer: Any) -> str:
        return self._LATEX[str(self.args[0])].format(printer._print(self.args[1]))


class Ddt(sp.MatrixExpr):
    """d/dt of a matrix expression (display; :func:`_ddt` computes it along a vector field)."""

    def __new__(cls, arg: sp.MatrixExpr) -> Ddt:
        return super().__new__(cls, arg)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[0].shape

    def _latex(self, printer: Any) -> str:
        return rf"\frac{{d}}{{dt}}\left({printer._print(self.args[0])}\right)"


class SymplecticForm(sp.Expr):
    """Omega_gl((xi1, eta1), (xi2, eta2)) (display of the left side of the printed form)."""

    is_commutative = True

    def __new__(cls, *args: sp.Basic) -> SymplecticForm:
        return super().__new__(cls, *args)

    def _latex(self, printer: Any) -> str:
        x1, y1, x2, y2 = (printer._print(a) for a in self.args)
        return rf"\Omega_{{\mathfrak{{gl}}(n)}}\left(({x1},{y1}),({x2},{y2})\right)"


def _reduce(
    w: Words, expr: sp.Expr, rules: Mapping[tuple[sp.Symbol, sp.Symbol], sp.Expr]
) -> sp.Expr:
    """Apply the rewriting ``rules`` (a pair of adjacent letters -> a polynomial) and the
    orthogonality of ``w`` until nothing changes."""
    current = w.reduce(expr)
    for _ in range(50):
        total = sp.Integer(0)
        for term in sp.Add.make_args(sp.expand(current)):
            c, word = letters_of(term)
            for i in range(len(word) - 1):
                if (word[i], word[i + 1]) in rules:
                    repl = rules[(word[i], word[i + 1])]
                    term = c * sp.Mul(*word[:i]) * repl * sp.Mul(*word[i + 2 :])
                    break
            total += term
        new = w.reduce(total)
        if new == current:
            return new
        current = new
    raise RuntimeError("rewriting did not terminate")


def _rule(w: Words, relation: sp.Eq) -> dict[tuple[sp.Symbol, sp.Symbol], sp.Expr]:
    """A displayed relation ``X Y = poly`` (its left side one word of two letters) as a rule."""
    c, word = letters_of(sp.expand(w.of(relation.lhs.doit())))
    if len(word) != 2:
        raise ValueError(f"relation {relation} is not a rule on a pair of letters")
    return {(word[0], word[1]): sp.expand(w.of(relation.rhs.doit()) / c)}


def _ratio(x: sp.Expr, t: sp.Expr) -> sp.Expr | None:
    """The scalar c with x = c t for noncommutative polynomials, or None."""
    x, t = sp.expand(x), sp.expand(t)
    if t == 0:
        return None
    lead = sp.Add.make_args(t)[0]
    coeff_t, word = letters_of(lead)
    coeff_x = sum(
        (cx for cx, wx in map(letters_of, sp.Add.make_args(x)) if wx == word),
        sp.Integer(0),
    )
    c = sp.nsimplify(coeff_x / coeff_t)
    return c if sp.expand(x - c * t) == 0 else None


def _jinv_argument(node: sp.Basic) -> sp.MatrixExpr | None:
    """X for a node J^{-1}(X) (a Hadamard product with W), else None."""
    if not (isinstance(node, sp.HadamardProduct) and W in node.args):
        return None
    others = [a for a in node.args if a != W]
    return others[0] if len(others) == 1 else sp.HadamardProduct(*others)


def _jinv_letters(
    expr: sp.Basic,
    w: Words,
    letters: Mapping[str, sp.MatrixExpr],
    rules: Mapping[tuple[sp.Symbol, sp.Symbol], sp.Expr] | None = None,
) -> sp.Basic:
    """Replace every ``J^{-1}(X)`` in ``expr`` by ``c L`` when X reduces (``rules``,
    orthogonality) to c times the argument of ``letters[L] = J^{-1}(Y)``: J^{-1} is linear, so
    this is exact.  Raises when some J^{-1} argument is no multiple of those."""
    rules = rules or {}
    reduced = {}
    for name, jinv in letters.items():
        arg = _jinv_argument(jinv)
        if arg is None:
            raise ValueError(f"{jinv} is not J^-1 of a matrix")
        reduced[name] = _reduce(w, w.of(arg), rules)
    mapping = {}
    for node in sp.preorder_traversal(expr):
        arg = _jinv_argument(node)
        if arg is None:
            continue
        x = _reduce(w, w.of(arg), rules)
        for name, t in reduced.items():
            c = _ratio(x, t)
            if c is not None:
                mapping[node] = c * matrix(name)
                break
        else:
            raise ValueError(f"J^-1 of {arg} is no multiple of {list(letters)}")
    return expr.xreplace(mapping)


def _ddt(w: Words, poly: sp.Expr, rates: Mapping[str, sp.Expr]) -> sp.Expr:
    """d/dt of a noncommutative polynomial by the product rule; ``rates`` gives the derivative of
    each letter by name (transposes follow: d/dt X^T = (d/dt X)^T)."""
    table: dict[sp.Symbol, sp.Expr] = {}
    for name, rate in rates.items():
        x = w(name)
        table[x] = rate
        xt = w.T(x)
        if xt != x and xt != -x:
            table[xt] = w.T(rate)
    total = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(poly)):
        c, word = letters_of(term)
        for i, x in enumerate(word):
            if x in table:
                total += c * sp.Mul(*word[:i]) * table[x] * sp.Mul(*word[i + 1 :])
    return sp.expand(total)


def _count_nonzero(values: Sequence[sp.Expr] | sp.Matrix) -> sp.Integer:
    """How many of the rational functions ``values`` are not identically zero.

    An entry that is non-zero at a random rational point (exact arithmetic) is non-zero; the
    others are decided by ``sp.cancel``."""
    rng = np.random.default_rng(0)
    count = 0
    for v in values:
        e = sp.expand(v)
        if e == 0:
            continue
        point = {
            s: sp.Rational(int(rng.integers(1, 97)), int(rng.integers(1, 89)))
            for s in e.free_symbols
        }
        at = e.xreplace(point)
        if at.is_finite and at != 0:
            count += 1
        elif sp.cancel(sp.together(e)) != 0:
            count += 1
    return sp.Integer(count)


def _elementary(k: int, i: int, j: int) -> sp.Matrix:
    E = sp.zeros(k, k)
    E[i, j] = 1
    return E


# =============================================================================================
# S5: the maximum principle for the smooth problem

S5 = claim(
    "S5",
    label="rboptcontprob, optr, eqnr, srb1",
    title="Maximum principle for the smooth rigid body control problem",
    statement="The extremals of the problem of minimising [[cost]] over $U\\in\\mathfrak{so}(n)$ "
    "subject to [[eqnr]] with $Q(0)$ and $Q(T)$ given satisfy [[srb1]] with [[optimal_U]], where "
    "$P\\in\\mathfrak{gl}(n)$ is the costate of the maximum principle.",
    expected="holds after correction",
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
_H = sp.Symbol("H")
H_PRINTED = S5.formula("H_printed", eq(_H, GlPair(P, Q * U) + COST))
H_CORRECTED = S5.formula("H_corrected", eq(_H, GlPair(P, Q * U) - COST))
_Qs, _Ps = sp.symbols("Q P")
_Hf = sp.Function("H")(_Qs, _Ps)
COSTATE = S5.formula(
    "costate", (eq(Qdot, sp.Derivative(_Hf, _Ps)), eq(Pdot, -sp.Derivative(_Hf, _Qs)))
)

SYMMETRIC_MOMENTUM = Kernel(
    name="symmetric_momentum",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_P],
    outputs={"M": MOMENTUM},
    doc="The body momentum of the symmetric representation, M = Q^T P - P^T Q.\n\n"
    "Skew for any square Q, P; on the symmetric rigid body flow it follows the rigid body\n"
    "equations (paper, Proposition SRBtoRB).",
    claims=("S6", "S9", "S11"),
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


def _unfold(expr: sp.Basic) -> sp.Basic:
    """Replace every displayed pairing <a, b> by the right side of the displayed definition."""
    return expr.replace(
        lambda e: isinstance(e, GlPair),
        lambda e: PAIRING.rhs.xreplace({_A: e.args[0], _B: e.args[1]}),
    )


def _gl_gradient(F: sp.Expr, X: sp.Matrix) -> sp.Matrix:
    """The G with <G, dX> = dF for the displayed pairing (its Gram matrix on the elementary
    matrices, so no coefficient is assumed); X has independent entries."""
    k = X.rows
    basis = [_elementary(k, i, j) for i in range(k) for j in range(k)]
    gram = sp.Matrix(
        len(basis), len(basis), lambda a, b: explicit(PAIRING.rhs, {"A": basis[a], "B": basis[b]})
    )
    dF = sp.Matrix([sp.diff(F, X[i, j]) for i in range(k) for j in range(k)])
    return sp.Matrix(k, k, list(gram.solve(dF)))


def _derivative_rule(relation: sp.Eq) -> tuple[sp.Expr, sp.Symbol]:
    """``Xdot = c dH/dY`` as (c, Y)."""
    c, d = relation.rhs.as_coeff_Mul()
    if not isinstance(d, sp.Derivative) or d.expr != _Hf or len(d.variables) != 1:
        raise ValueError(f"{relation} is not a multiple of a partial derivative of H")
    return c, d.variables[0]


def _maximiser(H: sp.Expr, Ux: sp.Matrix, lam: Sequence[sp.Expr]) -> tuple[sp.Matrix, sp.Integer]:
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


def stationary_control(form: str) -> tuple[sp.Matrix, sp.Matrix, sp.Integer]:
    """For the displayed Hamiltonian ``H_<form>`` (form ``printed`` or ``corrected``; n = 3,
    general Q, P, symbolic Lambda): its stationary point in U, the displayed optimal control
    J^-1(Q^T P - P^T Q), and the number of ways the stationary point fails to be a maximum."""
    lam, Qx, Px, Ux = _lam(3), general_matrix("q", 3), general_matrix("p", 3), skew_matrix("u", 3)
    env = {"Q": Qx, "P": Px, "U": Ux}
    Hx = sp.expand(explicit(_unfold(S5.formulas[f"H_{form}"].rhs), env, lam))
    Ustar, not_max = _maximiser(Hx, Ux, lam)
    return Ustar, explicit(OPTIMAL_U.rhs, env, lam), not_max


def _s5_extremals(form: str) -> sp.Integer:
    lam, Qx, Px, Ux = _lam(3), general_matrix("q", 3), general_matrix("p", 3), skew_matrix("u", 3)
    env = {"Q": Qx, "P": Px, "U": Ux}
    Hx = sp.expand(explicit(_unfold(S5.formulas[f"H_{form}"].rhs), env, lam))
    Ustar, shown, not_max = stationary_control(form)
    total = not_max + _count_nonzero(Ustar - shown)
    # the emitted field is the displayed (Qdot, Pdot) = (QU, PU) at the maximiser ...
    at_max = {"Q": Qx, "P": Px, "U": Ustar}
    for out, rel in zip(("Qdot", "Pdot"), SRB1, strict=True):
        kernel = explicit(SYMMETRIC_RIGID_BODY_RHS[out], env, lam)
        total += _count_nonzero(kernel - explicit(rel.rhs, at_max, lam))
        # ... and Hamilton's costate equations of H, gradients in the displayed pairing
        c, var = _derivative_rule(COSTATE[0 if out == "Qdot" else 1])
        grad = _gl_gradient(Hx, Px if var == _Ps else Qx).xreplace(
            {u: v for u, v in zip(Ux, Ustar, strict=True) if u != 0}
        )
        total += _count_nonzero(kernel - c * grad)
    return total


@S5.check(Level.SYMBOLIC_FIXED_N, form="printed")
def s5_printed_hamiltonian() -> sp.Integer:
    """The printed Hamiltonian (pairing as displayed, general Q, P, skew U, symbolic Lambda,
    n = 3): is it maximised, at the displayed U, and is the emitted field (QU, PU) with
    Qdot = dH/dP, Pdot = -dH/dQ there?  Residual: the number of entries or conditions that
    fail (the printed H is convex in U, its stationary point is -J^-1(Q^T P - P^T Q))."""
    return _s5_extremals("printed")


@S5.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s5_corrected_hamiltonian() -> sp.Integer:
    """The same for the corrected Hamiltonian: its Hessian in U is negative definite
    (-c (lam_i + lam_j), c > 0), its maximiser is the displayed U = J^-1(Q^T P - P^T Q), and the
    emitted symmetric rigid body field equals (QU, PU) and the displayed costate equations
    (gradients in the displayed pairing, solved from its Gram matrix) at that U."""
    return _s5_extremals("corrected")


@S5.check(Level.FLOAT64, tol=1e-9)
def s5_first_variation() -> float:
    """Extremals are critical points: along a trajectory of symrb.symmetric_rigid_body_rhs
    (n = 4, P in gl(n), t in [0, 2], DOP853 rtol 1e-13), the first variation of the cost in a
    control direction dU, int 1/2 <J U, dU> dt with J from the reference, equals <P_T, dQ_T> in
    the displayed pairing, dQ from the tangent-linear equation dQdot = dQ U + Q dU, dQ(0) = 0.
    Relative difference (it vanishes only when J U = Q^T P - P^T Q along the flow)."""
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
        dQ, dP = symrb.symmetric_rigid_body_rhs(Qy, Py, lam)
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


# =============================================================================================
# S6: from the symmetric representation to the rigid body

S6 = claim(
    "S6",
    label="SRBtoRB.prop",
    title="$(Q, M = Q^T P - P^T Q)$ solves the rigid body equations",
    statement="If $(Q, P)$ solves [[srb1]] with [[U]], then $Q$ and [[M]] satisfy the rigid body "
    "equations [[rbl]] with [[Omega]].",
    expected="holds",
    section="3.2",
    where="Section 3.2, the second proposition: if $(Q, P)$ solves the symmetric equations, $(Q, "
    "M)$ solves the rigid body equations (with its one-line proof)",
    note="Only $U^T = -U$ is used; $Q^T Q = I$ is not needed, so the statement holds on all of "
    "$\\mathfrak{gl}(n) \\times \\mathfrak{gl}(n)$.",
)
S6.formula("srb1", SRB1)
S6.formula("U", OPTIMAL_U)
S6_M = S6.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))
RBL = S6.formula("rbl", (eq(Qdot, Q * Om), eq(Mdot, Bracket(M, Om))))
OMEGA = S6.formula("Omega", eq(Om, Jinv(M)))


@S6.check(Level.SYMBOLIC_GENERAL_N)
def s6_rigid_body_general_n() -> sp.Integer:
    """Noncommutative Q, P (any n): with the emitted field, every J^-1 in it is the displayed
    Omega = J^-1(M) of the emitted M (J^-1 is linear), Qdot equals the displayed Q Omega, and
    d/dt M (product rule) equals the displayed [M, Omega], using only Omega^T = -Omega."""
    w = Words(skew=["Omega"])
    Mk = SYMMETRIC_MOMENTUM["M"]
    target = {"Omega": OMEGA.rhs.xreplace({M: Mk})}
    rates = {
        out[0]: w.of(_jinv_letters(SYMMETRIC_RIGID_BODY_RHS[out], w, target))
        for out in ("Qdot", "Pdot")
    }
    env = {M: Mk}
    total = w.is_zero(rates["Q"] - w.of(RBL[0].rhs))
    return total + w.is_zero(_ddt(w, w.of(Mk), rates) - w.of(RBL[1].rhs.xreplace(env)))


@S6.check(Level.SYMBOLIC_GENERAL_N)
def s6_momentum_skew() -> sp.Integer:
    """The emitted M = Q^T P - P^T Q is skew for noncommutative Q, P (any n): M + M^T reduces
    to 0."""
    w = Words()
    Mw = w.of(SYMMETRIC_MOMENTUM["M"])
    return w.is_zero(Mw + w.T(Mw))


def _costate_for(Q0: np.ndarray, M0: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A costate in gl(n) with Q0^T P0 - P0^T Q0 = M0 (Q0 orthogonal): Q0 (M0/2 + S), S a random
    symmetric matrix (which does not change M)."""
    S = rng.standard_normal(M0.shape)
    return Q0 @ (M0 / 2 + S + S.T)


@S6.check(Level.FLOAT64, tol=1e-9)
def s6_flow_against_elliptic() -> float:
    """symrb.integrate(SymmetricRigidBody) (n = 3, DOP853, rtol 1e-12) from Q0 in SO(3) and a
    costate in gl(3) with M(0) = hat(m0): its M(t) = Q^T P - P^T Q against the Jacobi elliptic
    solution of Euler's equations at 41 times in [0, 20]: max |M error| / |m0|."""
    import symrb

    rng = np.random.default_rng(61)
    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia  # I_1 = lam_2 + lam_3 (cyclic)
    t = np.linspace(0.0, 20.0, 41)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    Q0 = ref.random_rotation(3, rng)
    P0 = _costate_for(Q0, ref.hat(m[0]), rng)
    sol = symrb.integrate(
        symrb.SymmetricRigidBody, (0.0, 20.0), {"Q": Q0, "P": P0}, lam=lam,
        rtol=1e-12, atol=1e-12, t_eval=t,
    )  # fmt: skip
    return float(np.abs(ref.vee(sol.y.M) - m).max() / np.linalg.norm(m[0]))


@S6.check(Level.FLOAT64, tol=1e-9)
def s6_flow_against_reference_rigid_body() -> float:
    """symrb.integrate(SymmetricRigidBody) (n = 4, rtol 1e-12) against the reference rigid body
    field (J^-1 by a linear solve) integrated by solve_ivp from (Q0, M0), at 11 times in [0, 5]:
    max difference of Q and of M = Q^T P - P^T Q, relative to |M0|."""
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(62)
    k = 4
    lam = np.array([0.6, 0.9, 1.3, 1.9])
    Q0, M0 = ref.random_rotation(k, rng), ref.random_skew(k, rng, 0.4)
    P0 = _costate_for(Q0, M0, rng)
    ts = np.linspace(0.0, 5.0, 11)
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12, t_eval=ts)

    def field(_t: float, y: np.ndarray) -> np.ndarray:
        dQ, dM = ref.rigid_body_field(y[: k * k].reshape(k, k), y[k * k :].reshape(k, k), lam)
        return np.concatenate([dQ.ravel(), dM.ravel()])

    want = solve_ivp(field, (0.0, 5.0), np.concatenate([Q0.ravel(), M0.ravel()]), **kw)
    got = symrb.integrate(symrb.SymmetricRigidBody, (0.0, 5.0), {"Q": Q0, "P": P0}, lam=lam, **kw)
    Qw, Mw = (want.y[i * k * k : (i + 1) * k * k].T.reshape(-1, k, k) for i in range(2))
    err = np.max([np.abs(got.y.Q - Qw).max(), np.abs(got.y.M - Mw).max()])
    return float(err / np.abs(M0).max())


# =============================================================================================
# S7: the McLachlan-Scovel equations

S7 = claim(
    "S7",
    label="rbnlms",
    title="A costate $B$ with $Q^T B$ skew: the McLachlan-Scovel equations",
    statement="For a costate $B$ with [[skew]], the extremal equations of S5 become [[rbnlms]]; "
    "these equations leave the set where $Q^TB$ is skew invariant, and on it $Q^TB$ follows the "
    "rigid body equations (the McLachlan-Scovel equations).",
    expected="holds after correction",
    printed="The extremal equations for a costate $B$ with [[skew]] are [[rbnlms]].",
    corrected="The extremal equations for a costate $B$ with [[skew]] are [[extremal_B]]: "
    "the McLachlan-Scovel equations hold for the rescaled costate [[rescaled]], which on this set is "
    "[[remark]], the map the paper's commented-out remark names.",
    note="Read for the costate itself, the printed McLachlan-Scovel equations run the extremal "
    "flow at half speed. Corrected: the extremals are $\\dot Q = QJ^{-1}(2Q^T B)$, $\\dot B = "
    "BJ^{-1}(2Q^T B)$, so the printed equations hold for the rescaled costate $B' = 2B$. With "
    "$Q^T B$ skew, $Q^T B - B^T Q = 2Q^T B$, so the control of S5 is $U = J^{-1}(2Q^T B)$; on "
    "this set $B' = 2B$ equals $B - QB^T Q$. That map, $B' = P - QP^T Q$, takes every solution of "
    "the symmetric rigid body equations with $Q$ orthogonal to a solution of the McLachlan-Scovel "
    "equations with $Q^T B' = M$ (the paper's commented-out remark). The invariance of the set "
    "where $Q^T B$ is skew holds for any $U$: $S = Q^T B + B^T Q$ obeys $\\dot S = U^T S + SU$.",
    section="3.2",
    where="Section 3.2, the paragraph after the proof of the second proposition: the "
    "McLachlan-Scovel equations $\\dot Q = QJ^{-1}(Q^T B)$, $\\dot B = BJ^{-1}(Q^T B)$ for a "
    "costate $B$ with $Q^T B$ skew",
)
SKEW_B = S7.formula("skew", eq(sp.Transpose(Q.T * B), -Q.T * B))
MCLACHLAN_SCOVEL_RHS = Kernel(
    name="mclachlan_scovel_rhs",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_B, ARG_LAM],
    outputs={"Qdot": Q * Jinv(Q.T * B), "Bdot": B * Jinv(Q.T * B)},
    doc="McLachlan-Scovel field (paper, Section 3.2).\n\n"
    "Qdot = Q U, Bdot = B U, U = J^{-1}(Q^T B), for Q^T B skew.",
    claims=("S7",),
)
RBNLMS = S7.formula(
    "rbnlms",
    tuple(eq(d, MCLACHLAN_SCOVEL_RHS.outputs[o]) for d, o in ((Qdot, "Qdot"), (Bdot, "Bdot"))),
)
EXTREMAL_B = S7.formula(
    "extremal_B", (eq(Qdot, Q * Jinv(2 * Q.T * B)), eq(Bdot, B * Jinv(2 * Q.T * B)))
)
_Bs = matrix("B'")
RESCALED = S7.formula("rescaled", eq(_Bs, 2 * B))
REMARK = S7.formula("remark", eq(_Bs, B - Q * B.T * Q))


def _s7_extremals(form: str) -> sp.Integer:
    w = Words()
    rules = _rule(w, SKEW_B)
    target = {"V": Jinv(Q.T * B)}
    shown = S7.formulas["rbnlms" if form == "printed" else "extremal_B"]
    total = sp.Integer(0)
    for out, rel in zip(("Qdot", "Pdot"), shown, strict=True):
        field = SYMMETRIC_RIGID_BODY_RHS[out].xreplace({P: B})  # S5's extremals, costate B
        lhs = _reduce(w, w.of(_jinv_letters(field, w, target, rules)), rules)
        rhs = _reduce(w, w.of(_jinv_letters(rel.rhs, w, target, rules)), rules)
        total += w.is_zero(lhs - rhs)
    return total


@S7.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s7_printed_extremals() -> sp.Integer:
    """The emitted S5 extremal field (QU, BU), U = J^-1(Q^T B - B^T Q), for a costate B with the
    displayed skewness (a rewriting rule B^T Q -> -Q^T B) against the printed (rbnlms), any n
    (noncommutative Q, B; J^-1 linear): number of equations that differ."""
    return _s7_extremals("printed")


@S7.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s7_corrected_extremals() -> sp.Integer:
    """The same field against the corrected equations with U = J^-1(2 Q^T B), any n."""
    return _s7_extremals("corrected")


@S7.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s7_remark_maps_symmetric_flow() -> sp.Integer:
    """Noncommutative Q (orthogonal), P, any n: for B from the displayed remark, Q^T B is the
    momentum, so the emitted McLachlan-Scovel field at (Q, B) has the U of the emitted symmetric
    field; d/dt B along the symmetric field (product rule) equals its Bdot, and its Qdot equals
    the symmetric Qdot.  And on the displayed skew set (B^T Q -> -Q^T B) the remark equals the
    displayed rescaling 2B."""
    w = Words(orthogonal=["Q"], skew=["U"])
    target = {"U": Jinv(MOMENTUM)}
    sym = {o: w.of(_jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, target)) for o in ("Qdot", "Pdot")}
    Bp = REMARK.rhs.xreplace({B: P})  # the remark applied to the symmetric costate P
    ms = {
        o: _reduce(w, w.of(_jinv_letters(MCLACHLAN_SCOVEL_RHS[o].xreplace({B: Bp}), w, target)), {})
        for o in ("Qdot", "Bdot")
    }
    dB = _ddt(w, w.of(Bp), {"Q": sym["Qdot"], "P": sym["Pdot"]})
    total = w.is_zero(ms["Qdot"] - sym["Qdot"]) + w.is_zero(ms["Bdot"] - dB)
    rules = _rule(w, SKEW_B)
    return total + w.is_zero(_reduce(w, w.of(REMARK.rhs) - w.of(RESCALED.rhs), rules))


@S7.check(Level.SYMBOLIC_GENERAL_N)
def s7_skew_set_invariant() -> sp.Integer:
    """Noncommutative Q, B, any n: along the emitted McLachlan-Scovel field (Qdot = QU,
    Bdot = BU with one U, not assumed skew), S = Q^T B + B^T Q obeys the linear equation
    Sdot = U^T S + S U, so S(0) = 0 gives S = 0."""
    w = Words()
    rates = {
        o[0]: w.of(_jinv_letters(MCLACHLAN_SCOVEL_RHS[o], w, {"U": Jinv(Q.T * B)}))
        for o in ("Qdot", "Bdot")
    }
    S = w.of(Q.T * B + B.T * Q)
    Uw = w("U")
    return w.is_zero(_ddt(w, S, rates) - (w.T(Uw) * S + S * Uw))


@S7.check(Level.FLOAT64, tol=1e-9)
def s7_flow_against_elliptic() -> float:
    """symrb.integrate(McLachlanScovel) (n = 3, DOP853, rtol 1e-12) from Q0 in SO(3),
    B0 = Q0 hat(m0): its M = Q^T B against the Jacobi elliptic solution of Euler's equations at
    41 times in [0, 20]: max |M error| / |m0| (a factor in U changes the speed)."""
    import symrb

    rng = np.random.default_rng(71)
    inertia = np.array([1.0, 1.7, 2.6])
    lam = 0.5 * inertia.sum() - inertia
    t = np.linspace(0.0, 20.0, 41)
    m = ref.euler_elliptic(inertia, 0.8, 1.1, t)
    Q0 = ref.random_rotation(3, rng)
    sol = symrb.integrate(
        symrb.McLachlanScovel, (0.0, 20.0), {"Q": Q0, "B": Q0 @ ref.hat(m[0])}, lam=lam,
        rtol=1e-12, atol=1e-12, t_eval=t,
    )  # fmt: skip
    return float(np.abs(ref.vee(sol.y.M) - m).max() / np.linalg.norm(m[0]))


# =============================================================================================
# S8: the learning version

S8 = claim(
    "S8",
    label="rboptcontprobm, optrm, eqnrm",
    title="Learning version: shared control, per-sample costates, endpoint condition",
    statement="For the samples [[eqnrm]] sharing one control, with the cost of S5 plus "
    "$\\sum_a\\phi(Q^a_T)$, the extremals satisfy [[costates]] with [[control]], the maximiser "
    "of [[H]], and an endpoint condition on $P^a_T$.",
    expected="holds after correction",
    printed="[[endpoint_printed]] (with the printed $U$).",
    corrected="[[endpoint_corrected]], where $\\partial\\phi/\\partial Q$ is the matrix of "
    "entrywise partial derivatives: minus the gradient in the pairing of S5.",
    note="The endpoint condition $P^a_T = \\partial\\phi/\\partial Q^a_T$ has the wrong sign and "
    "factor for the printed control. Corrected: $P^a_T = -2\\,\\partial\\phi/\\partial Q^a_T$, "
    "minus the gradient of $\\phi$ in the pairing of S5. With the running cost entering the "
    "maximum principle with multiplier $-1$ (so that $U$ is the printed $+J^{-1}(\\cdots)$, see "
    "S5), transversality gives $P_T = -\\nabla\\phi$, and the gradient in the pairing "
    "$\\tfrac12\\operatorname{tr}(A^T B)$ is twice the entrywise derivative. Checked against a "
    "forward tangent-linear derivative of the cost: with the corrected endpoint the reduced "
    "gradient is $\\tfrac12 J(U - \\sum_a J^{-1}(M^a))$ and vanishes exactly at the printed $U$; "
    "with the printed one it does not match. Equivalently the printed sign is right after $P "
    "\\mapsto -P$, $U \\mapsto -J^{-1}(\\cdots)$.",
    section="3.2",
    where="Section 3.2, the second definition (several samples $Q^a$ and a terminal cost "
    "$\\phi$), the third proposition ($U = \\sum_a J^{-1}((Q^a)^T P^a - (P^a)^T Q^a)$) and the "
    "endpoint condition after it, $P^a_T = \\partial\\phi/\\partial Q^a_T$",
)
_a, _m = sp.symbols("a m", integer=True, positive=True)
Qa, Pa = matrix("Q^a"), matrix("P^a")
EQNRM = S8.formula("eqnrm", eq(matrix("Qdot^a"), Qa * U))
COSTATES = S8.formula("costates", (EQNRM, eq(matrix("Pdot^a"), Pa * U)))
CONTROL = S8.formula("control", eq(U, sp.Sum(Jinv(Qa.T * Pa - Pa.T * Qa), (_a, 1, _m))))
S8_H = S8.formula("H", eq(_H, sp.Sum(GlPair(Pa, Qa * U), (_a, 1, _m)) - COST))
_phi = sp.Function("phi")
_QT, _PT = sp.symbols("Q^a_T P^a_T")
S8.formula("endpoint_printed", eq(_PT, sp.Derivative(_phi(_QT), _QT)))
S8.formula("endpoint_corrected", eq(_PT, -2 * sp.Derivative(_phi(_QT), _QT)))

CONTROL_RHS = Kernel(
    name="control_rhs",
    target="symmetric_rigid_body",
    args=[ARG_Q, ARG_P, ARG_U],
    outputs={"Qdot": Q * U, "Pdot": P * U},
    doc="State and costate fields for a given control U: Qdot = Q U, Pdot = P U.\n\n"
    "The learning version (paper, Section 3.2), one sample per batch entry.",
    claims=("S8",),
)


def _samples(expr: sp.Basic, count: int) -> sp.Basic:
    """A displayed sum over the samples a = 1..m written out for m = count, with Q^a, P^a
    renamed Q1, P1, Q2, ..."""

    def expand_sum(s: sp.Sum) -> sp.Basic:
        return sp.Add(
            *[
                s.function.xreplace({Qa: matrix(f"Q{i}"), Pa: matrix(f"P{i}")})
                for i in range(1, count + 1)
            ]
        )

    return expr.replace(lambda e: isinstance(e, sp.Sum), expand_sum)


@S8.check(Level.SYMBOLIC_FIXED_N)
def s8_two_samples() -> sp.Integer:
    """Two samples, n = 3, general Q^a, P^a, skew U, symbolic Lambda: the displayed Hamiltonian
    (pairing of S5) is maximised (Hessian -c (lam_i + lam_j)) at the displayed control
    U = sum_a J^-1(...); for every sample the emitted control field equals the displayed
    (Q^a U, P^a U) and the costate equations Qdot^a = dH/dP^a, Pdot^a = -dH/dQ^a of S5."""
    lam, Ux = _lam(3), skew_matrix("u", 3)
    env: dict[str, sp.Matrix] = {"U": Ux}
    for i in (1, 2):
        env[f"Q{i}"], env[f"P{i}"] = general_matrix(f"q{i}", 3), general_matrix(f"p{i}", 3)
    Hx = sp.expand(explicit(_unfold(_samples(S8_H.rhs, 2)), env, lam))
    Ustar, total = _maximiser(Hx, Ux, lam)
    total += _count_nonzero(Ustar - explicit(_samples(CONTROL.rhs, 2), env, lam))
    for i in (1, 2):
        Qi, Pi = env[f"Q{i}"], env[f"P{i}"]
        one = {"Q": Qi, "P": Pi, "U": Ux, "Q^a": Qi, "P^a": Pi}
        for out, rel, costate in zip(("Qdot", "Pdot"), COSTATES, COSTATE, strict=True):
            kernel = explicit(CONTROL_RHS[out], one, lam)
            total += _count_nonzero(kernel - explicit(rel.rhs, one, lam))
            c, var = _derivative_rule(costate)
            total += _count_nonzero(kernel - c * _gl_gradient(Hx, Pi if var == _Ps else Qi))
    return total


@S8.check(Level.FLOAT64, tol=1e-13)
def s8_symrb_multi_sample() -> float:
    """symrb.multi_sample_control against sum_a J^-1((Q^a)^T P^a - (P^a)^T Q^a) with J^-1 from the
    reference linear solve, and symrb.multi_sample_rhs against (Q^a U, P^a U), for m = 1, 2, 5
    samples, n = 3, 4, batches of 3: max difference relative to the size of the reference U."""
    import symrb

    rng = np.random.default_rng(81)
    errs = []
    for k in (3, 4):
        lam = rng.uniform(0.3, 2.0, k)
        for count in (1, 2, 5):
            Qs = np.stack([[ref.random_rotation(k, rng) for _ in range(count)] for _ in range(3)])
            Ps = rng.standard_normal((3, count, k, k))
            moments = np.swapaxes(Qs, -1, -2) @ Ps - np.swapaxes(Ps, -1, -2) @ Qs
            want = ref.J_inv(moments, lam).sum(axis=1)
            size = np.abs(want).max()
            errs.append(np.abs(symrb.multi_sample_control(Qs, Ps, lam) - want).max() / size)
            dQ, dP = symrb.multi_sample_rhs(Qs, Ps, lam)
            errs.append(np.abs(dQ - Qs @ want[:, None]).max() / size)
            errs.append(np.abs(dP - Ps @ want[:, None]).max() / size / np.abs(Ps).max())
    return float(np.max(errs))


def endpoint_mismatch(coefficient: float) -> float:
    """Relative mismatch of two computations of the derivative of the learning cost
    int_0^1 1/4 <U, JU> dt + sum_a phi(Q^a_1), phi(Q) = 1/2 |Q - R|_F^2 (two samples, n = 3,
    controls linear in t) in a direction dU: forward with the tangent-linear equation, and by the
    maximum principle as int 1/2 <J(U - symrb.multi_sample_control(Q, P)), dU> dt with P
    integrated backward from P^a_1 = coefficient * dphi/dQ^a_1 (entrywise derivative Q - R).
    Zero only for the coefficient -2."""
    from scipy.integrate import solve_ivp

    import symrb

    rng = np.random.default_rng(8)
    k, count = 3, 2
    lam = np.array([0.7, 1.1, 1.6])
    U0, U1, V0, V1 = (ref.random_skew(k, rng, 0.7) for _ in range(4))
    R = ref.random_rotation(k, rng)
    Q0 = np.stack([ref.random_rotation(k, rng) for _ in range(count)])
    size = count * k * k

    def fwd(t: float, y: np.ndarray) -> np.ndarray:
        Qy, dQ = y[:size].reshape(count, k, k), y[size:].reshape(count, k, k)
        Ut, dUt = U0 + t * U1, V0 + t * V1
        return np.concatenate([(Qy @ Ut).ravel(), (dQ @ Ut + Qy @ dUt).ravel()])

    kw = dict(method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
    a = solve_ivp(fwd, (0, 1), np.concatenate([Q0.ravel(), np.zeros(size)]), **kw)
    Q1, dQ1 = a.y[:size, -1].reshape(count, k, k), a.y[size:, -1].reshape(count, k, k)
    nodes, weights = np.polynomial.legendre.leggauss(40)
    ts, ws = (nodes + 1) / 2, weights / 2
    # forward: d/de of int 1/4 <U, JU> + sum_a phi(Q^a_1), phi(Q) = 1/2 |Q - R|_F^2
    d_forward = sum(
        wt * 0.5 * float(ref.pairing(ref.J(U0 + t * U1, lam), V0 + t * V1))
        for t, wt in zip(ts, ws, strict=True)
    )
    d_forward += float(np.sum((Q1 - R) * dQ1))
    # backward: P from the displayed endpoint condition, dphi/dQ = Q - R entrywise
    P1 = coefficient * (Q1 - R)
    b = solve_ivp(
        lambda t, y: (y.reshape(count, k, k) @ (U0 + t * U1)).ravel(), (1, 0), P1.ravel(), **kw
    )
    # reduced gradient of the maximum principle: 1/2 <J(U - sum_a J^-1(M^a)), dU>
    d_adjoint = 0.0
    for t, wt in zip(ts, ws, strict=True):
        Qt = a.sol(t)[:size].reshape(count, k, k)
        Pt = b.sol(t).reshape(count, k, k)
        gap = U0 + t * U1 - symrb.multi_sample_control(Qt, Pt, lam)
        d_adjoint += wt * 0.5 * float(ref.pairing(ref.J(gap, lam), V0 + t * V1))
    return abs(d_forward - d_adjoint) / abs(d_forward)


def _endpoint_mismatch(form: str) -> float:
    coeff, deriv = S8.formulas[f"endpoint_{form}"].rhs.as_coeff_Mul()
    if not (isinstance(deriv, sp.Derivative) and deriv.variables == (_QT,)):
        raise ValueError("the endpoint condition is not a multiple of d phi / d Q^a_T")
    return endpoint_mismatch(float(coeff))


@S8.check(Level.FLOAT64, tol=1e-8, form="printed")
def s8_printed_endpoint() -> float:
    """The derivative of the learning cost (two samples, n = 3, phi = 1/2 |Q - R|_F^2, controls
    linear in t) in a direction dU, forward (tangent-linear dQ) against the adjoint form
    int 1/2 <J(U - symrb.multi_sample_control(Q, P)), dU> dt with P integrated backward from the
    printed endpoint condition (its coefficient read from the displayed formula): relative
    mismatch."""
    return _endpoint_mismatch("printed")


@S8.check(Level.FLOAT64, tol=1e-8, form="corrected")
def s8_corrected_endpoint() -> float:
    """The same with P integrated backward from the displayed corrected endpoint condition."""
    return _endpoint_mismatch("corrected")


# =============================================================================================
# S9: ||M||_op <= 2 is necessary for P in SO(n)


S9 = claim(
    "S9",
    label="M_Q_P.eqn, CandS.definition",
    title="$\\|M\\|_{\\mathrm{op}} \\le 2$ is necessary for $M = Q^T P - P^T Q$ with $P$ in "
    "$\\mathrm{SO}(n)$",
    statement="If $Q, P\\in SO(n)$ and [[M]], then [[bound]], and the bound is attained. With "
    "$A$ the orthogonal matrix $Q^TP$, [[identity]]. For $P\\in\\mathfrak{gl}(n)$ there is no "
    "bound: [[gl]] solves the equation for every skew $M$.",
    expected="holds",
    section="3.3",
    where="Section 3.3 (Local equivalence of classical rigid body and symmetric rigid body "
    "equations), the paragraph before the definition of $C$ and $S$ (the necessary condition "
    "$\\|M\\|_{\\mathrm{op}} \\le 2$), and that definition",
    note="The paper's argument uses $\\|P\\|_{\\mathrm{op}} \\le 1$, so $P$ is in "
    "$\\mathrm{SO}(n)$ (or $\\mathrm{O}(n)$). For a costate $P$ in $\\mathfrak{gl}(n)$, as in S5, "
    "there is no bound. With $A = Q^T P$ orthogonal the identity gives $\\|Mx\\|^2 = 4\\|x\\|^2 - "
    "\\|(A + A^T)x\\|^2$, so $\\|M\\|_{\\mathrm{op}} = 2$ exactly when $A + A^T$ is singular ($A$ "
    "has eigenvalues $\\pm i$).",
)
S9_M = S9.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))
BOUND = S9.formula("bound", sp.Le(OpNorm(M), 2))
_Ao = matrix("A")
IDENTITY = S9.formula("identity", eq(M.T * M + (_Ao + _Ao.T).T * (_Ao + _Ao.T), 4 * sp.Identity(n)))
GL_SOLUTION = S9.formula("gl", eq(P, Q * M / 2))


@S9.check(Level.SYMBOLIC_GENERAL_N)
def s9_identity_general_n() -> sp.Integer:
    """Noncommutative orthogonal Q, P (any n): the displayed identity with M the emitted
    momentum and A = Q^T P reduces to 0, and its constant is the square of the displayed bound
    (so |Mx|^2 <= bound^2 |x|^2)."""
    w = Words(orthogonal=["Q", "P"])
    env = {M: SYMMETRIC_MOMENTUM["M"], _Ao: Q.T * P}
    lhs, rhs = (w.of(side.xreplace(env)) for side in (IDENTITY.lhs, IDENTITY.rhs))
    return w.is_zero(lhs - rhs) + sp.Integer(sp.expand(rhs - BOUND.rhs**2) != 0)


@S9.check(Level.SYMBOLIC_GENERAL_N)
def s9_no_bound_on_gl() -> sp.Integer:
    """Noncommutative orthogonal Q and skew M (any n): the emitted momentum at the displayed
    P = Q M / 2 reduces to M, whatever the size of M."""
    w = Words(orthogonal=["Q"], skew=["M"])
    return w.is_zero(w.of(SYMMETRIC_MOMENTUM["M"].xreplace({P: GL_SOLUTION.rhs})) - w("M"))


@S9.check(Level.FLOAT64, tol=1e-12)
def s9_sampled_bound() -> float:
    """symrb.symmetric_momentum of 3000 random pairs of reference rotations (n = 2..7): by how
    much its largest operator norm exceeds the displayed bound (0 when it does not)."""
    import symrb

    rng = np.random.default_rng(9)
    norms = []
    for k in range(2, 8):
        Qs = np.stack([ref.random_rotation(k, rng) for _ in range(500)])
        Ps = np.stack([ref.random_rotation(k, rng) for _ in range(500)])
        norms.append(np.linalg.norm(symrb.symmetric_momentum(Qs, Ps), 2, axis=(-2, -1)).max())
    return float(np.max([0.0, np.max(norms) - float(BOUND.rhs)]))


@S9.check(Level.FLOAT64, tol=1e-13)
def s9_bound_attained() -> float:
    """The bound is attained: for Q^T P an orthogonal matrix with a rotation by pi/2 in some
    plane (random Q, random rotation on the complement, n = 3..6), the operator norm of
    symrb.symmetric_momentum(Q, P) minus the displayed bound, in absolute value."""
    from scipy.linalg import block_diag

    import symrb

    rng = np.random.default_rng(90)
    errs = []
    for k in range(3, 7):
        rest = ref.random_rotation(k - 2, rng) if k > 3 else np.eye(1)
        V = ref.random_rotation(k, rng)
        A = V @ block_diag(np.array([[0.0, -1.0], [1.0, 0.0]]), rest) @ V.T
        Qk = ref.random_rotation(k, rng)
        errs.append(np.linalg.norm(symrb.symmetric_momentum(Qk, Qk @ A), 2) - float(BOUND.rhs))
    return float(np.max(np.abs(errs)))


# =============================================================================================
# S10: P = Q exp(asinh(M/2))

S10 = claim(
    "S10",
    label="Pequ",
    title="$P = Q\\exp(\\sinh^{-1}(M/2))$ solves $M = Q^T P - P^T Q$ for $\\|M\\|_{\\mathrm{op}} "
    "< 2$",
    statement="For [[domain]], the rotation given by the paper's formula for $P$ solves [[M]].",
    expected="holds after correction",
    printed="[[printed]], the exponent read as half of $\\sinh^{-1}M$.",
    corrected="[[corrected]], which on skew matrices is [[closed]].",
    note="The printed exponent $\\sinh^{-1} M/2$ is ambiguous, and read as $\\tfrac12\\sinh^{-1} "
    "M$ it fails. Corrected: $P = Q\\exp(\\sinh^{-1}(M/2))$, the reading that matches the domain "
    "$\\|M/2\\|_{\\mathrm{op}} < 1$ of the series. The slip is notational: read as "
    "$\\sinh^{-1}(M/2)$ the proposition holds; read as $(\\sinh^{-1} M)/2$ it fails even where "
    "the series converges. On skew matrices $\\exp(\\sinh^{-1} X) = X + (I + X^2)^{1/2}$, which "
    "is how `symrb.P_from_M` computes it (on the real Schur form). The solution is not unique: "
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


def _evaluate(expr: sp.Basic, env: Mapping[str, Any], ops: Mapping[str, Callable[..., Any]]) -> Any:
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


def _numpy_ops(k: int) -> dict[str, Callable[..., Any]]:
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
    return _evaluate(expr, {"M": x}, ops)


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
    """On an eigenvalue x of M, the displayed printed reading P = Q exp(X(x)) gives
    exp(X) - exp(-X) - x, the eigenvalue of Q^T P - P^T Q - M: does it simplify to 0?"""
    return _s10_scalar("printed")


@S10.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s10_corrected_scalar() -> sp.Integer:
    """The same for the corrected reading, and exp(X(x)) equals the displayed closed form
    x/2 + (1 + x^2/4)^(1/2) (identities of analytic functions, simplified for real x after
    rewriting asinh as a log, so they hold on the imaginary eigenvalues of M too)."""
    return _s10_scalar("corrected")


def _s10_equation(form: str) -> float:
    """max |Q^T P - P^T Q - M| (the displayed M formula) for P from the displayed formula."""
    rng = np.random.default_rng(10)
    errs = []
    for k in range(3, 7):
        ops = _numpy_ops(k)
        for _ in range(20):
            Mk = ref.random_skew(k, rng)
            Mk *= rng.uniform(0.05, 0.9) / np.linalg.norm(Mk, 2)  # both readings' series converge
            Qk = ref.random_rotation(k, rng)
            Pk = _evaluate(S10.formulas[form].rhs, {"Q": Qk, "M": Mk}, ops)
            errs.append(np.abs(_evaluate(S10_M.rhs, {"Q": Qk, "P": Pk}, ops) - Mk).max())
    return float(np.max(errs))


@S10.check(Level.FLOAT64, tol=1e-12, form="printed")
def s10_printed_matrix() -> float:
    """The displayed printed formula evaluated with matrices (asinh by the Hermitian
    eigen-decomposition of iM, scipy expm) for random skew M with ||M||_op < 0.9 and rotations
    Q, n = 3..6: max |Q^T P - P^T Q - M|."""
    return _s10_equation("printed")


@S10.check(Level.FLOAT64, tol=1e-12, form="corrected")
def s10_corrected_matrix() -> float:
    """The same for the displayed corrected formula."""
    return _s10_equation("corrected")


@S10.check(Level.FLOAT64, tol=1e-11, form="corrected")
def s10_symrb_P_from_M() -> float:
    """symrb.P_from_M (real Schur form) against the displayed corrected formula (Hermitian
    eigen-decomposition and expm) and the displayed closed form (symmetric eigen-decomposition),
    n = 3..6, ||M||_op from 0.1 to 0.995 times the displayed domain bound: max difference."""
    import symrb

    rng = np.random.default_rng(11)
    errs = []
    for k in range(3, 7):
        ops = _numpy_ops(k)
        for r in np.linspace(0.1, 0.995 * float(DOMAIN.rhs), 12):
            Mk = ref.random_skew(k, rng)
            Mk *= r / np.linalg.norm(Mk, 2)
            Qk = ref.random_rotation(k, rng)
            got = symrb.P_from_M(Qk, Mk)
            for formula in (S10.formulas["corrected"], CLOSED):
                errs.append(np.abs(got - _evaluate(formula.rhs, {"Q": Qk, "M": Mk}, ops)).max())
    return float(np.max(errs))


@functools.cache
def _s10_near_boundary(dps: int = 60) -> tuple[float, float]:
    """60 digits, n = 4, ||M||_op = 2(1 - delta) for delta = 1e-4, 1e-8, 1e-12: the worst residual
    of the displayed closed form (Q^T P - P^T Q - M and P^T P - I, 60-digit arithmetic, square
    root through mpmath's symmetric eigen-decomposition) and the worst error of symrb.P_from_M
    against it in units of eps / sqrt(delta) (the conditioning of asinh near the boundary)."""
    import mpmath as mp

    import symrb

    rng = np.random.default_rng(1010)
    Qf, D = ref.random_rotation(4, rng), ref.random_skew(4, rng)
    D = D / np.linalg.norm(D, 2)
    identity, ratio = [], []
    with mp.workdps(dps):

        def sqrt_mp(S: Any) -> Any:
            E, V = mp.eigsy(S)
            return V * mp.diag([mp.sqrt(max(e, 0)) for e in E]) * V.T

        ops = {
            "mul": lambda a, b: a * b, "T": lambda a: a.T, "num": lambda c: mp.mpf(c.p) / c.q,
            "eye": lambda: mp.eye(4), "sqrt": sqrt_mp,
        }  # fmt: skip
        Qm, Rm = mp.qr(mp.matrix(Qf.tolist()))  # orthogonal to 60 digits, not just to rounding
        Qm = Qm * mp.diag([mp.sign(Rm[i, i]) for i in range(4)])
        for delta in (1e-4, 1e-8, 1e-12):
            Mf = 2.0 * (1.0 - delta) * D
            Mm = mp.matrix(Mf.tolist())
            Pm = _evaluate(CLOSED.rhs, {"Q": Qm, "M": Mm}, ops)
            gap = _evaluate(S10_M.rhs, {"Q": Qm, "P": Pm}, ops) - Mm
            identity += [float(mp.mnorm(gap, 1)), float(mp.mnorm(Pm.T * Pm - mp.eye(4), 1))]
            err = float(mp.mnorm(mp.matrix(symrb.P_from_M(Qf, Mf).tolist()) - Pm, 1))
            ratio.append(err * np.sqrt(delta) / np.finfo(float).eps)
    return float(np.max(identity)), float(np.max(ratio))


@S10.check(Level.MPMATH, tol=1e-50, form="corrected")
def s10_high_precision_identity() -> float:
    """60 digits: P from the displayed closed form solves Q^T P - P^T Q = M with P^T P = I at
    ||M||_op = 2(1 - delta), delta = 1e-4, 1e-8, 1e-12 (n = 4): largest residual."""
    return _s10_near_boundary()[0]


@S10.check(Level.MPMATH, tol=10.0, form="corrected")
def s10_float64_conditioning() -> float:
    """symrb.P_from_M against that 60-digit P: error in units of eps/sqrt(delta), the
    conditioning of asinh at the boundary."""
    return _s10_near_boundary()[1]


# =============================================================================================
# S11: the operator norm is a Casimir

S11 = claim(
    "S11",
    label="invariance of C and S",
    title="$\\|M\\|_{\\mathrm{op}}$ is a Casimir; $C$ and $S$ are invariant",
    statement="Along the symmetric rigid body flow, [[spatial]] with [[M]]; as $Q$ stays "
    "orthogonal (S12), $M(t)$ is orthogonally conjugate to $M(0)$, so its operator norm is "
    "constant and the sets $C$ (norm equal to 2) and $S$ (norm below 2) are invariant.",
    expected="holds",
    section="3.3",
    where="Section 3.3, the second proposition ($C$ and $S$ are invariant under the rigid body "
    "equations) and its proof (the operator norm is a Casimir)",
    note="The paper argues with the coadjoint action; the check is the equivalent statement that "
    "the spatial momentum $QMQ^T$ is constant. Only $U^T = -U$ is used.",
)
SPATIAL = S11.formula("spatial", eq(Ddt(Q * M * Q.T), sp.ZeroMatrix(n, n)))
S11.formula("M", eq(M, SYMMETRIC_MOMENTUM.outputs["M"]))


@S11.check(Level.SYMBOLIC_GENERAL_N)
def s11_spatial_momentum_general_n() -> sp.Integer:
    """Noncommutative Q, P (any n): d/dt of the displayed Q M Q^T, with M the emitted momentum
    and (Qdot, Pdot) the emitted field (J^-1(M) a skew letter), reduces to the displayed 0."""
    w = Words(skew=["U"])
    Mk = SYMMETRIC_MOMENTUM["M"]
    rates = {
        o[0]: w.of(_jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, {"U": Jinv(Mk)}))
        for o in ("Qdot", "Pdot")
    }
    spatial = w.of(SPATIAL.lhs.args[0].xreplace({M: Mk}))
    return w.is_zero(_ddt(w, spatial, rates) - w.of(SPATIAL.rhs))


# =============================================================================================
# S12: the Hamiltonian form on gl(n) x gl(n)

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
S12.formula("H", eq(_H, GL_HAMILTONIAN.outputs["H"].xreplace(_rename)))
S12.formula(
    "equations",
    tuple(
        eq(matrix(d), SYMMETRIC_RIGID_BODY_RHS.outputs[o].xreplace(_rename))
        for d, o in (("xidot", "Qdot"), ("etadot", "Pdot"))
    ),
)
QUARTER = S12.formula("quarter", eq(_H, Pair(Jinv(M), M) / 4))
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
    X, Y, lam = general_matrix("x", k), general_matrix("y", k), _lam(k)
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
    """Hamilton's equations from the displayed form (its Gram matrix on the elementary matrices,
    no coefficient assumed), the displayed convention and the emitted Hamiltonian, solved for
    X_H, against the emitted symmetric rigid body field (symbolic entries and Lambda, n = 3):
    entries that differ."""
    convention, dH = HAMILTON.rhs.as_coeff_Mul()
    if dH.func.__name__ != "dH":
        raise ValueError("the convention is not a multiple of dH")
    Xdot, Ydot, Qdot_k, Pdot_k = hamilton_equations(3, convention)
    return _count_nonzero(list(Xdot - Qdot_k) + list(Ydot - Pdot_k))


@S12.check(Level.SYMBOLIC_GENERAL_N)
def s12_SO_invariant_general_n() -> sp.Integer:
    """Noncommutative Q, P (any n), emitted field with J^-1(M) a skew letter U: d/dt(Q^T Q - I)
    equals [Q^T Q - I, U], a linear homogeneous equation, so Q^T Q = I is invariant; likewise
    for P."""
    w = Words(skew=["U"])
    rates = {
        o[0]: w.of(_jinv_letters(SYMMETRIC_RIGID_BODY_RHS[o], w, {"U": Jinv(MOMENTUM)}))
        for o in ("Qdot", "Pdot")
    }
    Uw = w("U")
    total = sp.Integer(0)
    for name in ("Q", "P"):
        X = w(name)
        G = w.T(X) * X - 1
        total += w.is_zero(_ddt(w, G, rates) - (G * Uw - Uw * G))
    return total


@S12.check(Level.SYMBOLIC_GENERAL_N)
def s12_quarter_energy_general_n() -> sp.Integer:
    """The emitted Hamiltonian minus the displayed 1/4 <J^-1(M), M> (pairing -1/2 tr), with
    J^-1(M) a letter, as trace words in noncommutative Q, P (any n): no word remains."""
    w = Words()
    letters = {"V": Jinv(MOMENTUM)}
    emitted = _jinv_letters(GL_HAMILTONIAN["H"], w, letters)
    quarter = _jinv_letters(QUARTER.rhs.xreplace({M: MOMENTUM}).doit(), w, letters)
    return trace_residual(w.trace_argument(emitted) - w.trace_argument(quarter))


@S12.check(Level.FLOAT64, tol=1e-13)
def s12_symrb_pointwise() -> float:
    """symrb.gl_hamiltonian against 1/4 <J^-1(M), M> and symrb.symmetric_rigid_body_rhs against
    the reference field, J^-1 by the reference linear solve, M = Q^T P - P^T Q in NumPy, n = 2..6,
    batches of 20 random (Q in SO(n), P in gl(n)): max difference relative to the reference
    values' size."""
    import symrb

    rng = np.random.default_rng(12)
    errs = []
    for k in range(2, 7):
        lam = rng.uniform(0.3, 2.0, k)
        Qs = np.stack([ref.random_rotation(k, rng) for _ in range(20)])
        Ps = rng.standard_normal((20, k, k))
        Ms = np.swapaxes(Qs, -1, -2) @ Ps - np.swapaxes(Ps, -1, -2) @ Qs
        want_H = 0.25 * ref.pairing(ref.J_inv(Ms, lam), Ms)
        errs.append(np.abs(symrb.gl_hamiltonian(Qs, Ps, lam) - want_H).max() / want_H.max())
        for got, want in zip(
            symrb.symmetric_rigid_body_rhs(Qs, Ps, lam),
            ref.symmetric_field(Qs, Ps, lam),
            strict=True,
        ):
            errs.append(np.abs(got - want).max() / np.abs(want).max())
    return float(np.max(errs))
