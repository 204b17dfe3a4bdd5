r"""Optimality on adjoint orbits, Brockett's double bracket case and learning (paper, Section 3.5):
claims S13-S15.

The control system is :math:`\dot x = [x, u]` on an adjoint orbit of a compact Lie algebra
(:math:`\mathfrak{so}(n)`, :math:`\mathfrak{su}(n)`), the cost :math:`\int \tfrac12\|u\|^2 - V(x)\,dt`
(plus a terminal cost :math:`\sum_a\phi(x^a_T)` in the learning version).  The paper's fixed element
:math:`n` is called :math:`N` here (``n`` is the matrix size).

How the checks work:

* **every n (noncommutative letters).**  Pairings :math:`\langle a,b\rangle = -\tfrac12
  \operatorname{tr}(ab)` of products of :math:`x, p, u, N, \dots` are compared as trace words
  (:class:`~derivations.symbolic.Words`); a derivative is taken along a free direction :math:`d` as
  :math:`\tfrac{d}{d\epsilon}` at :math:`\epsilon = 0`, and a gradient :math:`G` is identified by
  :math:`dF[d] = \langle G, d\rangle` for every :math:`d`.  Only cyclicity of the trace is used, so
  these identities hold for every multiple :math:`B = -c\operatorname{tr}` of the trace form.  A
  potential :math:`V` whose gradient is :math:`V_x` enters through its linearisation
  :math:`\langle V_x, y\rangle` (the first derivative is all Hamilton's equations use).
* **fixed n (coordinates).**  For so(3) with the pairing (in an orthonormal and in a
  non-orthogonal basis) and su(2) with the negative Killing form (computed from the structure
  constants), the maximum principle is written in coordinates with the costate as a covector and
  Hamilton's equations are taken literally.
* **float64.**  Public ``symrb`` functions against independent NumPy formulas, complex-step
  derivatives, Flaschka's Toda equations, central differences of the cost and the exact so(3)
  solution of the double bracket flow.

Emitted (``symrb/_generated/adjoint_orbits.py``): the optimal control (S13), the optimal
Hamiltonian with Brockett's potential (S13, S14), Brockett's potential, the extremal field and the
double bracket field (S14), the state-costate field for a given (shared) control, the closed form
of the one-sample second term and the two-sample bound (S15).  Each kernel is the right side of a
displayed formula.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from derivations import reference as ref
from derivations.registry import Level, claim
from derivations.symbolic import (
    Bracket,
    Pair,
    Words,
    eq,
    explicit,
    hat3,
    residual,
    trace_residual,
)
from derivations.vocabulary import Arg, Kernel, matrix, n

# =============================================================================================
# display objects and their evaluation (private helpers; _Norm and _SampleSum could move to
# derivations.symbolic)


class _Norm(sp.Expr):
    """The norm ||a|| = <a, a>^(1/2) of the pairing (printed with double bars)."""

    is_commutative = True
    is_extended_real = True
    is_extended_nonnegative = True

    def __new__(cls, a: sp.Basic) -> _Norm:
        return super().__new__(cls, a)

    def _latex(self, printer: Any) -> str:
        return rf"\left\|{printer._print(self.args[0])}\right\|"


class _SampleSumMatrix(sp.MatrixExpr):
    """sum over the samples ``index`` of a matrix expression (printed as a sum over the index)."""

    def __new__(cls, expr: sp.MatrixExpr, index: sp.Symbol) -> _SampleSumMatrix:
        return super().__new__(cls, expr, index)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[0].shape

    def _latex(self, printer: Any) -> str:
        return rf"\sum_{{{printer._print(self.args[1])}}} {printer._print(self.args[0])}"


class _SampleSumScalar(sp.Expr):
    """sum over the samples ``index`` of a scalar expression."""

    is_commutative = True

    def __new__(cls, expr: sp.Expr, index: sp.Symbol) -> _SampleSumScalar:
        return super().__new__(cls, expr, index)

    def _latex(self, printer: Any) -> str:
        return rf"\sum_{{{printer._print(self.args[1])}}} {printer._print(self.args[0])}"


def _sample_sum(expr: sp.Basic, index: sp.Symbol) -> sp.Basic:
    if isinstance(expr, sp.MatrixExpr):
        return _SampleSumMatrix(expr, index)
    return _SampleSumScalar(expr, index)


def _of_sample(expr: sp.Basic, index: str, k: int) -> sp.Basic:
    """``expr`` with every matrix letter of sample ``index`` (``x^a``, ``p^a_T``, ...) replaced
    by that of sample ``k`` (``x^1``, ``p^1_T``, ...)."""
    reps = {}
    for m in expr.atoms(sp.MatrixSymbol):
        name = str(m.name)
        if f"^{index}" in name:
            reps[m] = sp.MatrixSymbol(name.replace(f"^{index}", f"^{k}"), *m.shape)
    return expr.xreplace(reps)


def _samples(expr: sp.Basic, count: int) -> sp.Basic:
    """Every sum over samples in ``expr`` written out for samples 1..count."""

    def write_out(s: sp.Basic) -> sp.Basic:
        body, index = s.args
        terms = [_of_sample(body, str(index), k) for k in range(1, count + 1)]
        return sp.MatAdd(*terms) if isinstance(s, sp.MatrixExpr) else sp.Add(*terms)

    return expr.replace(lambda e: isinstance(e, (_SampleSumMatrix, _SampleSumScalar)), write_out)


class _Minus(sp.MatrixExpr):
    """a - b, printed in this order (MatrixExpr arithmetic calls doit(), which expands brackets,
    and the printer sorts the terms of a sum); ``doit`` gives the matrix expression a - b."""

    def __new__(cls, a: sp.MatrixExpr, b: sp.MatrixExpr) -> _Minus:
        return super().__new__(cls, a, b)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[0].shape

    def doit(self, **hints: Any) -> sp.Basic:
        a, b = (e.doit(**hints) for e in self.args)
        return a - b

    def _latex(self, printer: Any) -> str:
        a, b = (printer._print(e) for e in self.args)
        return f"{a} - {b}"


def _minus(a: sp.MatrixExpr, b: sp.MatrixExpr) -> sp.MatrixExpr:
    return _Minus(a, b)


V = sp.Function("V")
PHI = sp.Function("phi")


def _plain(
    expr: sp.Basic,
    potential: Callable[[sp.Basic], sp.Basic] | None = None,
    scale: sp.Expr | int = 1,
) -> sp.Basic:
    """A displayed formula as plain matrix algebra: V(y) -> ``potential(y)``, ||a||^2 and ||a||
    -> pairings, every pairing multiplied by ``scale`` (a form B = -c tr has scale 2c), then
    brackets and pairings expanded (``doit``)."""
    e = expr
    if potential is not None:
        e = e.replace(
            lambda a: isinstance(a, AppliedUndef) and a.func == V, lambda a: potential(a.args[0])
        )
    e = e.replace(
        lambda a: isinstance(a, sp.Pow) and isinstance(a.base, _Norm) and a.exp == 2,
        lambda a: Pair(a.base.args[0], a.base.args[0]),
    )
    e = e.replace(lambda a: isinstance(a, _Norm), lambda a: sp.sqrt(Pair(a.args[0], a.args[0])))
    if scale != 1:
        e = e.xreplace({q: scale * q for q in e.atoms(Pair)})
    return e.doit()


_EPS = sp.Symbol("epsilon")


def _trace_poly(
    expr: sp.Basic, w: Words, potential: Callable[[sp.Basic], sp.Basic] | None = None
) -> sp.Expr:
    """A scalar sum of pairings as the expanded noncommutative polynomial under one trace."""
    e = _plain(expr, potential)
    return sp.Integer(0) if e == 0 else sp.expand(w.trace_argument(e))


def _directional(
    expr: sp.Basic,
    moves: dict[sp.MatrixSymbol, sp.MatrixExpr],
    w: Words,
    potential: Callable[[sp.Basic], sp.Basic] | None = None,
) -> sp.Expr:
    """d/de expr(y + e dy) at e = 0 for the moves {y: dy}, as a trace polynomial (expanded before
    differentiating: SymPy's derivative of a noncommutative power is wrong)."""
    moved = expr.xreplace({y: y + _EPS * dy for y, dy in moves.items()})
    return sp.diff(_trace_poly(moved, w, potential), _EPS).subs(_EPS, 0)


def _pair_poly(a: sp.MatrixExpr, b: sp.MatrixExpr, w: Words) -> sp.Expr:
    return _trace_poly(Pair(a, b), w)


# =============================================================================================
# symbols

x, p, u, N, d = (matrix(s) for s in ("x", "p", "u", "N", "d"))
V_x = matrix("V_x")
XDOT, PDOT = matrix(r"\dot{x}"), matrix(r"\dot{p}")
t, t_f, T = sp.symbols("t t_f T", positive=True)
ARG_X = Arg("x", "(..., n, n)", "state on an adjoint orbit (skew for so(n))")
ARG_P = Arg("p", "(..., n, n)", "costate, identified with the algebra through the pairing")
ARG_N = Arg("N", "(..., n, n)", "the fixed element n of Brockett's potential")
ARG_U = Arg("u", "(..., n, n)", "the control (shared by all samples in the learning version)")


def _linear_potential(y: sp.Basic) -> sp.Basic:
    """The linearisation <V_x, y> of a potential with gradient V_x (first derivatives only)."""
    return Pair(V_x, y)


# =============================================================================================
# S13: the maximum principle on an adjoint orbit

S13 = claim(
    "S13",
    label="orb, var, op",
    title="Maximum principle on adjoint orbits",
    statement="For the control system [[orb]] on an adjoint orbit and the cost [[cost]], with the "
    "pairing and the norm of the negative Killing form ([[killing_so]] on so(n), [[killing_su]] on "
    "su(n)) and $V_x$ the gradient of $V$, the Hamiltonian [[H]] has [[dHdu]] for every $d$, so "
    "[[ustar]] and [[Hstar]], and the extremals solve [[xdot]], [[pdot]].",
    expected="holds",
    section="3.4",
    where="Section 3.4 (Optimality on adjoint orbits and learning), the control system $\\dot x = "
    "[x, u]$, the functional $\\eta(x, u)$ and the theorem on the equations of the maximum "
    "principle, with its proof ($u^* = [p, x]$ and $H^*$)",
    note="Holds as printed provided one bilinear form $B$ is used throughout (pairing, norm and "
    "gradient $V_x$): the checks for general $n$ use only cyclicity of the trace, so they hold "
    "for $B = -c\\operatorname{tr}$ with any $c$, in particular for the pairing "
    "$-\\tfrac12\\operatorname{tr}$ on $\\mathfrak{so}(n)$ and for the negative Killing form, "
    "which is $(n-2)\\operatorname{tr}$ on $\\mathfrak{so}(n)$ and $2n\\operatorname{tr}$ on "
    "$\\mathfrak{su}(n)$. Mixing forms rescales the control: on $\\mathfrak{su}(n)$ with "
    "$\\langle p, \\cdot\\rangle = -\\tfrac12\\operatorname{tr}$ but $\\|u\\|^2 = -\\kappa(u, "
    "u)$, $u^* = [p, x]/(4n)$ ($1/8$ on $\\mathfrak{su}(2)$; see `tests/test_orbits.py`).",
)
_a, _b = matrix("a"), matrix("b")
_kappa = sp.Function("kappa")
KILLING_SO = S13.formula("killing_so", eq(_kappa(_a, _b), (n - 2) * sp.Trace(_a * _b)))
KILLING_SU = S13.formula("killing_su", eq(_kappa(_a, _b), 2 * n * sp.Trace(_a * _b)))
ORB = S13.formula("orb", eq(XDOT, Bracket(x, u)))
COST = S13.formula(
    "cost", eq(sp.Function("eta")(x, u), sp.Integral(_Norm(u) ** 2 / 2 - V(x), (t, 0, t_f)))
)
HAMILTONIAN = S13.formula(
    "H", eq(sp.Function("H")(x, p, u), Pair(p, ORB.rhs) - _Norm(u) ** 2 / 2 + V(x))
)
DHDU = S13.formula(
    "dHdu", eq(Pair(matrix(r"\partial H/\partial u"), d), -Pair(Bracket(x, p), d) - Pair(u, d))
)
USTAR = S13.formula("ustar", eq(matrix("u^*"), Bracket(p, x)))
HSTAR = S13.formula(
    "Hstar", eq(sp.Function("H^*")(x, p), -Pair(x, Bracket(p, Bracket(p, x))) / 2 + V(x))
)
XDOT_EQ = S13.formula("xdot", eq(XDOT, Bracket(x, Bracket(p, x))))
PDOT_EQ = S13.formula("pdot", eq(PDOT, _minus(Bracket(p, Bracket(p, x)), V_x)))

OPTIMAL_CONTROL = Kernel(
    name="optimal_control",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P],
    outputs={"u": USTAR.rhs.doit()},
    doc="The maximiser of H in u: u* = [p, x].\n\n"
    "For samples sharing one control, sum it over the samples: u* = sum_b [p^b, x^b].",
    claims=("S13", "S15"),
)


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_hamiltonian_convention() -> sp.Expr:
    """The displayed H is <p, f> - L for f the right side of the displayed dynamics and L the
    integrand of the displayed cost (the convention under which the maximum principle maximises
    H; trace words, every n)."""
    w = Words()
    (integral,) = COST.rhs.atoms(sp.Integral)
    convention = Pair(p, ORB.rhs) - integral.function
    return trace_residual(_trace_poly(HAMILTONIAN.rhs - convention, w, _linear_potential))


def stationarity(control: sp.MatrixExpr) -> sp.Expr:
    """d/de H(x, p, control + e d) at e = 0 for the displayed H, as a trace polynomial in the
    letters x, p, d (zero for every d exactly when ``control`` is a critical point of H)."""
    moved = HAMILTONIAN.rhs.xreplace({u: control + _EPS * d})
    return sp.diff(_trace_poly(moved, Words(), _linear_potential), _EPS).subs(_EPS, 0)


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_stationary_control() -> sp.Expr:
    """The derivative of the displayed H along a direction d of u is the displayed dH/du, and it
    vanishes at the emitted optimal control for every d (trace words, every n)."""
    w = Words()
    dH = _directional(HAMILTONIAN.rhs, {u: d}, w, _linear_potential)
    r = trace_residual(dH - _trace_poly(DHDU.rhs, w))
    return r + trace_residual(stationarity(OPTIMAL_CONTROL["u"]))


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_optimal_hamiltonian() -> sp.Expr:
    """H at the emitted u* minus the displayed H* (for any V) has no trace words left, and the
    emitted H* kernel equals the displayed H* with Brockett's potential of S14 (every n)."""
    w = Words()
    at_ustar = HAMILTONIAN.rhs.xreplace({u: OPTIMAL_CONTROL["u"]})
    r = trace_residual(_trace_poly(at_ustar - HSTAR.rhs, w, _linear_potential))
    emitted = _trace_poly(ORBIT_HAMILTONIAN["H"], w)
    displayed = _trace_poly(HSTAR.rhs, w, _brockett)
    return r + trace_residual(emitted - displayed)


@S13.check(Level.SYMBOLIC_GENERAL_N)
def s13_hamilton_equations() -> sp.Expr:
    """Hamilton's equations of the displayed H*: dH*/dp [d] equals <xdot, d> and -dH*/dx [d]
    equals <pdot, d> for the displayed xdot and pdot, every direction d (V through its gradient
    V_x; trace words, every n)."""
    w = Words()
    dp = _directional(HSTAR.rhs, {p: d}, w, _linear_potential)
    dx = _directional(HSTAR.rhs, {x: d}, w, _linear_potential)
    r = trace_residual(dp - _pair_poly(XDOT_EQ.rhs, d, w))
    return r + trace_residual(-dx - _pair_poly(PDOT_EQ.rhs, d, w))


# --- fixed n: explicit coordinates --------------------------------------------------------------


def so_basis(k: int) -> list[sp.Matrix]:
    """The basis E_ij = e_i e_j^T - e_j e_i^T (i < j) of so(k)."""
    out = []
    for i, j in itertools.combinations(range(k), 2):
        e = sp.zeros(k, k)
        e[i, j], e[j, i] = 1, -1
        out.append(e)
    return out


def su_basis(k: int) -> list[sp.Matrix]:
    """A basis of su(k): the so(k) basis, i (E_ij + E_ji) for i < j and i (E_jj - E_j+1,j+1)."""
    out = so_basis(k)
    for i, j in itertools.combinations(range(k), 2):
        e = sp.zeros(k, k)
        e[i, j] = e[j, i] = sp.I
        out.append(e)
    for j in range(k - 1):
        e = sp.zeros(k, k)
        e[j, j], e[j + 1, j + 1] = sp.I, -sp.I
        out.append(e)
    return out


def _trace_form(a: sp.Matrix, b: sp.Matrix) -> sp.Expr:
    return sp.expand((a * b).trace())


def killing_form(basis: Sequence[sp.Matrix]) -> sp.Matrix:
    """kappa(e_i, e_j) = tr(ad_e_i ad_e_j) from the structure constants: the coordinates of
    [e_i, e_j] are found with the (non-degenerate) trace form, nothing about kappa is assumed."""
    dim = len(basis)
    gram = sp.Matrix(dim, dim, lambda i, j: _trace_form(basis[i], basis[j]))
    ginv = gram.inv()

    def coords(v: sp.Matrix) -> sp.Matrix:
        return ginv * sp.Matrix([_trace_form(e, v) for e in basis])

    ad = [sp.Matrix.hstack(*[coords(ei * ej - ej * ei) for ej in basis]) for ei in basis]
    return sp.Matrix(dim, dim, lambda i, j: sp.expand((ad[i] * ad[j]).trace()))


@S13.check(Level.SYMBOLIC_FIXED_N)
def s13_killing_forms() -> sp.Expr:
    """kappa(e_i, e_j) from the structure constants equals the displayed (n-2) tr(e_i e_j) on
    so(3), so(4) and 2n tr(e_i e_j) on su(2), su(3), for every pair of basis elements."""
    total = sp.Integer(0)
    for formula, basis in (
        (KILLING_SO, so_basis(3)),
        (KILLING_SO, so_basis(4)),
        (KILLING_SU, su_basis(2)),
        (KILLING_SU, su_basis(3)),
    ):
        shown = formula.rhs.subs(n, basis[0].rows)
        claimed = sp.Matrix([[explicit(shown, {"a": ei, "b": ej}) for ej in basis] for ei in basis])
        total += residual(killing_form(basis) - claimed)
    return total


def _coordinates(basis: Sequence[sp.Matrix], c: sp.Expr, m: sp.Matrix) -> dict[str, sp.Expr]:
    r"""The maximum principle for the displayed H with B = -c tr, written in coordinates.

    x = sum x^k e_k, u = sum u^k e_k, the costate a covector pi_k = B(p, e_k); the potential is
    V(x) = B(x, m)^3 (gradient 3 B(x, m)^2 m).  dH/du = 0 is solved as a linear system, H* is H
    there, and Hamilton's equations xdot^k = dH*/dpi_k, pidot_k = -dH*/dx^k are taken literally.
    Returns residuals: u* minus the emitted optimal control, H* minus the displayed H*, and the
    literal xdot, pdot minus the displayed ones.
    """
    scale = 2 * c
    dim = len(basis)
    zero = sp.zeros(*basis[0].shape)
    gram = sp.Matrix(dim, dim, lambda i, j: -c * _trace_form(basis[i], basis[j]))
    ginv = gram.inv()
    xs = sp.symbols(f"x1:{dim + 1}", real=True)
    pis = sp.symbols(f"pi1:{dim + 1}", real=True)
    us = sp.symbols(f"u1:{dim + 1}", real=True)

    def mat(cs: Sequence[sp.Expr]) -> sp.Matrix:
        return sum((ci * e for ci, e in zip(cs, basis, strict=True)), zero)

    X, P, U = mat(xs), mat(list(ginv * sp.Matrix(pis))), mat(us)
    M = matrix("m")

    def cubic(y: sp.Basic) -> sp.Basic:
        return Pair(y, M) ** 3  # scaled with every other pairing by _plain

    def value(expr: sp.Basic, env: dict[str, Any], potential: Any = cubic) -> Any:
        return explicit(_plain(expr, potential, scale), {**env, "m": m})

    env = {"x": X, "p": P}
    gens = (*xs, *pis)

    def poly(e: sp.Expr) -> sp.Poly:
        return sp.Poly(e, *gens)

    def mismatches(a: sp.Matrix, b: sp.Matrix) -> sp.Integer:
        """The number of entries of a - b that are not the zero polynomial."""
        return sp.Integer(sum(not poly(ai - bi).is_zero for ai, bi in zip(a, b, strict=True)))

    H = sp.Poly(value(HAMILTONIAN.rhs, {**env, "u": U}), *us, *gens)
    A, rhs = sp.linear_eq_to_matrix([H.diff(ui).as_expr() for ui in us], us)
    ustar = mat(list(A.LUsolve(rhs)))
    Hstar = poly(value(HAMILTONIAN.rhs, {**env, "u": ustar}))
    xdot = mat([Hstar.diff(q).as_expr() for q in pis])
    pdot = mat(list(ginv * sp.Matrix([-Hstar.diff(y).as_expr() for y in xs])))
    grad_V = 3 * (-c * _trace_form(X, m)) ** 2 * m
    pdot_shown = explicit(_plain(PDOT_EQ.rhs, None, scale), {**env, "V_x": grad_V})
    return {
        "u": mismatches(ustar, explicit(OPTIMAL_CONTROL["u"], env)),
        "Hstar": sp.Integer(int(not (Hstar - poly(value(HSTAR.rhs, env))).is_zero)),
        "xdot": mismatches(xdot, value(XDOT_EQ.rhs, env)),
        "pdot": mismatches(pdot, pdot_shown),
    }


def killing_factor(basis: Sequence[sp.Matrix]) -> sp.Expr:
    """kappa(e_0, e_0) / tr(e_0 e_0) (the factor c of kappa = c tr, see s13_killing_forms)."""
    return sp.nsimplify(killing_form(basis)[0, 0] / _trace_form(basis[0], basis[0]))


def mixed_form_control_scale() -> sp.Expr:
    """su(2) with the costate paired by -1/2 tr but ||u||^2 = -kappa(u, u): the s with
    u* = s [p, x] (coordinates, dH/du = 0 solved as a linear system; used by the tests and the
    book to show what mixing forms does, not evidence)."""
    basis = su_basis(2)
    c_kill = killing_factor(basis)
    xs, ps, us = (sp.symbols(f"{v}1:4", real=True) for v in ("x", "q", "u"))

    def mat(cs: Sequence[sp.Expr]) -> sp.Matrix:
        return sum((ci * e for ci, e in zip(cs, basis, strict=True)), sp.zeros(2, 2))

    X, P, U = mat(xs), mat(ps), mat(us)
    H = sp.expand(-_trace_form(P, X * U - U * X) / 2 + c_kill * _trace_form(U, U) / 2)
    A, rhs = sp.linear_eq_to_matrix([sp.diff(H, ui) for ui in us], us)
    ustar = mat(list(A.LUsolve(rhs)))
    bracket = P * X - X * P
    k = next(i for i in range(4) if sp.expand(bracket[i]) != 0)
    return sp.simplify(ustar[k] / bracket[k])


def _algebras() -> list[tuple[str, list[sp.Matrix], sp.Expr]]:
    """(name, basis, c): so(3) with the pairing (c = 1/2) in the basis E_ij and in a basis that
    is not orthogonal for it (so the costate covector and the matrix p differ by a non-diagonal
    Gram matrix), and su(2) with the negative Killing form (c from the structure constants)."""
    e = so_basis(3)
    skewed = [e[0], e[0] + e[1], e[2]]
    su2 = su_basis(2)
    return [
        ("so(3), pairing -1/2 tr", e, sp.Rational(1, 2)),
        ("so(3), pairing -1/2 tr, non-orthogonal basis", skewed, sp.Rational(1, 2)),
        ("su(2), negative Killing form", su2, killing_factor(su2)),
    ]


@functools.cache
def coordinate_residuals() -> dict[str, dict[str, sp.Expr]]:
    """For each algebra of :func:`_algebras`: the residuals of :func:`_coordinates` with a fixed
    rational m (a genuine cubic potential)."""
    out = {}
    for name, basis, c in _algebras():
        coeffs = [sp.Rational(3, 2), -1, sp.Rational(1, 3), 2, -sp.Rational(1, 2), 1][: len(basis)]
        m = sum((ci * e for ci, e in zip(coeffs, basis, strict=True)), sp.zeros(*basis[0].shape))
        out[name] = _coordinates(basis, c, m)
    return out


@S13.check(Level.SYMBOLIC_FIXED_N)
def s13_coordinates() -> sp.Expr:
    """In coordinates, with the costate a covector and V(x) = B(x, m)^3: solving dH/du = 0 gives
    the emitted u*, H there is the displayed H*, and the literal Hamilton equations are the
    displayed xdot and pdot with V_x = 3 B(x, m)^2 m (so(3) with the pairing, in an orthonormal
    and in a non-orthogonal basis; su(2) with the negative Killing form)."""
    return sum((sum(r.values()) for r in coordinate_residuals().values()), sp.Integer(0))


@S13.check(Level.FLOAT64, tol=1e-14)
def s13_symrb_hamiltonian() -> float:
    """symrb.orbit_hamiltonian against 1/2 ||[p, x]||^2 - 1/2 ||[x, N]||^2 computed in NumPy
    with ||a||^2 = -1/2 tr(a a), n = 3..6, 20 random skew (x, p, N) each: max difference relative
    to ||p||^2 ||x||^2 + ||x||^2 ||N||^2."""
    import symrb

    rng = np.random.default_rng(13)
    worst = []
    for k in range(3, 7):
        x_, p_, N_ = (np.stack([ref.random_skew(k, rng) for _ in range(20)]) for _ in range(3))
        want = 0.5 * _np_norm2(_np_comm(p_, x_)) - 0.5 * _np_norm2(_np_comm(x_, N_))
        size = _np_norm2(p_) * _np_norm2(x_) + _np_norm2(x_) * _np_norm2(N_)
        worst.append(np.max(np.abs(symrb.orbit_hamiltonian(x_, p_, N_) - want) / size))
    return float(np.max(worst))


def _np_comm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a @ b - b @ a


def _np_pair(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return -0.5 * np.trace(a @ b, axis1=-2, axis2=-1)


def _np_norm2(a: np.ndarray) -> np.ndarray:
    return _np_pair(a, a)


# =============================================================================================
# S14: Brockett's potential, the extremal equations and the Toda lattice

S14 = claim(
    "S14",
    label="opb",
    title="Brockett's potential: extremal equations and the Toda lattice",
    statement="For Brockett's potential [[V]] (the proof uses [[V_rewritten]]) the gradient is "
    "[[V_x]], so the extremals of S13 solve [[opb]]. Toda link (what we check): for $x$ the "
    "product of $i$ and a real symmetric tridiagonal $L$ (diagonal $a_i$, off-diagonal $b_i$) in "
    "su(k), and $N$ the product of $i$ and $D$, $D$ the diagonal matrix of $1,\\dots,k$, the double "
    "bracket flow [[double_bracket]] keeps $L$ tridiagonal and is Flaschka's Toda lattice "
    "[[toda_a]], [[toda_b]] (with $b_0$ and $b_k$ zero), that is [[lax]] with [[toda_B]], the "
    "strictly upper minus the strictly lower part of $L$.",
    expected="holds",
    section="3.4",
    where="Section 3.4, the first corollary (Brockett's potential $V(x) = -\\tfrac12\\|[x, "
    "n]\\|^2$) and the paragraph after it (the link with the Toda lattice)",
    note="Holds as printed (the first line of the printed equations lacks a closing bracket, "
    "$[x,[p,x]$). The sign of $V_x$ is decided by the checks: $V_x = +[N,[N,x]]$ (the opposite "
    "sign fails, see `tests/test_orbits.py`). On real symmetric $L$ the flow $\\dot L = "
    "[L,[L,D]]$ is the Toda flow run backwards in time; the compact form $x = iL$ reverses it.",
)
BROCKETT = S14.formula("V", eq(V(x), -(_Norm(Bracket(x, N)) ** 2) / 2))
BROCKETT_REWRITTEN = S14.formula("V_rewritten", eq(V(x), Pair(x, Bracket(N, Bracket(N, x))) / 2))
BROCKETT_GRADIENT = S14.formula("V_x", eq(V_x, Bracket(N, Bracket(N, x))))
OPB = S14.formula(
    "opb",
    (
        eq(XDOT, Bracket(x, Bracket(p, x))),
        eq(PDOT, _minus(Bracket(p, Bracket(p, x)), Bracket(N, Bracket(N, x)))),
    ),
)
DOUBLE_BRACKET = S14.formula("double_bracket", eq(XDOT, Bracket(x, Bracket(x, N))))


def _brockett(y: sp.Basic) -> sp.Basic:
    """Brockett's potential at y: the right side of the displayed V."""
    return BROCKETT.rhs.xreplace({x: y})


BROCKETT_POTENTIAL = Kernel(
    name="brockett_potential",
    target="adjoint_orbits",
    args=[ARG_X, ARG_N],
    outputs={"V": _plain(BROCKETT.rhs)},
    doc="Brockett's potential V(x) = -1/2 ||[x, N]||^2.\n\n||a||^2 = <a, a> = -1/2 trace(a a).",
    claims=("S14",),
)
ORBIT_HAMILTONIAN = Kernel(
    name="orbit_hamiltonian",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P, ARG_N],
    outputs={"H": _plain(HSTAR.rhs, _brockett)},
    doc="Optimal Hamiltonian H* = -1/2 <x, [p, [p, x]]> + V(x) with Brockett's potential.\n\n"
    "V(x) = -1/2 ||[x, N]||^2, <a, b> = -1/2 trace(a b); H* = 1/2 ||[p, x]||^2 + V(x).",
    claims=("S13", "S14"),
)
ORBIT_EXTREMAL_RHS = Kernel(
    name="orbit_extremal_rhs",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P, ARG_N],
    outputs={"xdot": OPB[0].rhs.doit(), "pdot": OPB[1].rhs.doit()},
    doc="Extremal equations with Brockett's potential (paper, Section 3.4).\n\n"
    "xdot = [x, [p, x]], pdot = [p, [p, x]] - [N, [N, x]].",
    claims=("S14", "S15"),
)
DOUBLE_BRACKET_RHS = Kernel(
    name="double_bracket_rhs",
    target="adjoint_orbits",
    args=[ARG_X, ARG_N],
    outputs={"xdot": DOUBLE_BRACKET.rhs.doit()},
    doc="Double bracket vector field xdot = [x, [x, N]].",
    claims=("S14", "S15"),
)


@S14.check(Level.SYMBOLIC_GENERAL_N)
def s14_potential() -> sp.Expr:
    """The displayed V, its displayed rewriting 1/2 <x, [N, [N, x]]> and the emitted potential
    are the same trace polynomial (every n)."""
    w = Words()
    v = _trace_poly(BROCKETT.rhs, w)
    r = trace_residual(v - _trace_poly(BROCKETT_REWRITTEN.rhs, w))
    return r + trace_residual(v - _trace_poly(BROCKETT_POTENTIAL["V"], w))


@S14.check(Level.SYMBOLIC_GENERAL_N)
def s14_gradient() -> sp.Expr:
    """The derivative of the emitted potential along every d is <V_x, d> with the displayed
    V_x = [N, [N, x]], and S13's displayed pdot with this V_x is the displayed pdot of eq. opb
    (trace words, every n)."""
    w = Words()
    dV = _directional(BROCKETT_POTENTIAL["V"], {x: d}, w)
    r = trace_residual(dV - _pair_poly(BROCKETT_GRADIENT.rhs, d, w))
    s13_pdot = PDOT_EQ.rhs.xreplace({V_x: BROCKETT_GRADIENT.rhs})
    r += trace_residual(_pair_poly(s13_pdot - OPB[1].rhs, d, w))
    return r + trace_residual(_pair_poly(XDOT_EQ.rhs - OPB[0].rhs, d, w))


@S14.check(Level.SYMBOLIC_GENERAL_N)
def s14_emitted_field_is_hamiltonian() -> sp.Expr:
    """The emitted extremal field is Hamilton's equations of the emitted H*: dH*/dp [d] equals
    <xdot, d> and -dH*/dx [d] equals <pdot, d> for every d, and it is the displayed eq. opb
    (trace words, every n)."""
    w = Words()
    H = ORBIT_HAMILTONIAN["H"]
    xdot, pdot = ORBIT_EXTREMAL_RHS["xdot"], ORBIT_EXTREMAL_RHS["pdot"]
    r = trace_residual(_directional(H, {p: d}, w) - _pair_poly(xdot, d, w))
    r += trace_residual(-_directional(H, {x: d}, w) - _pair_poly(pdot, d, w))
    r += trace_residual(_pair_poly(xdot - OPB[0].rhs, d, w))
    return r + trace_residual(_pair_poly(pdot - OPB[1].rhs, d, w))


# --- the Toda lattice --------------------------------------------------------------------------

_ia, _ib = sp.IndexedBase("a"), sp.IndexedBase("b")
_i = sp.Symbol("i", integer=True)
TODA_A = S14.formula("toda_a", eq(sp.Derivative(_ia[_i], t), 2 * (_ib[_i] ** 2 - _ib[_i - 1] ** 2)))
TODA_B = S14.formula("toda_b", eq(sp.Derivative(_ib[_i], t), _ib[_i] * (_ia[_i + 1] - _ia[_i])))
_L, _B, _D = matrix("L"), matrix("B"), matrix("D")
LAX = S14.formula("lax", eq(matrix(r"\dot{L}"), Bracket(_B, _L)))
TODA_BMAT = S14.formula("toda_B", eq(_B, Bracket(_L, _D)))


def toda_residuals(k: int) -> dict[str, sp.Expr]:
    """x = iL, N = iD in su(k), L symbolic real symmetric tridiagonal: the emitted double bracket
    field gives Ldot = x-dot / i; residuals of (tridiagonal) its entries off the band, (toda) its
    band minus the displayed Toda equations, (lax) Ldot minus the displayed [B, L] with the
    displayed B = [L, D], and (B) B minus the strictly upper minus the strictly lower part of L."""
    a = sp.symbols(f"a1:{k + 1}", real=True)
    b = sp.symbols(f"b1:{k}", real=True)
    L = sp.zeros(k, k)
    for i in range(k):
        L[i, i] = a[i]
    for i in range(k - 1):
        L[i, i + 1] = L[i + 1, i] = b[i]
    D = sp.diag(*range(1, k + 1))
    Ldot = sp.expand(explicit(DOUBLE_BRACKET_RHS["xdot"], {"x": sp.I * L, "N": sp.I * D}) / sp.I)
    off = [Ldot[i, j] for i in range(k) for j in range(k) if abs(i - j) > 1]
    values = {_ia[i + 1]: a[i] for i in range(k)} | {_ib[i + 1]: b[i] for i in range(k - 1)}
    values |= {_ib[0]: 0, _ib[k]: 0}
    toda = [Ldot[i - 1, i - 1] - TODA_A.rhs.subs(_i, i).xreplace(values) for i in range(1, k + 1)]
    toda += [Ldot[i - 1, i] - TODA_B.rhs.subs(_i, i).xreplace(values) for i in range(1, k)]
    B = explicit(TODA_BMAT.rhs, {"L": L, "D": D})
    parts = sp.Matrix(k, k, lambda i, j: sp.sign(j - i) * L[i, j])
    return {
        "tridiagonal": residual(sp.Matrix(off)) if off else sp.Integer(0),
        "toda": residual(sp.Matrix(toda)),
        "lax": residual(Ldot - explicit(LAX.rhs, {"B": B, "L": L})),
        "B": residual(B - parts),
    }


@S14.check(Level.SYMBOLIC_FIXED_N)
def s14_toda() -> sp.Expr:
    """x = iL, N = iD, L symbolic real symmetric tridiagonal, k = 3, 4, 5: the emitted double
    bracket field keeps L tridiagonal and equals the displayed Toda equations, the displayed
    [B, L] with the displayed B, and B is the strictly upper minus the strictly lower part of L."""
    return sum((sum(toda_residuals(k).values()) for k in (3, 4, 5)), sp.Integer(0))


@S14.check(Level.FLOAT64, tol=1e-14)
def s14_symrb_potential_and_double_bracket() -> float:
    """symrb.brockett_potential against -1/2 ||[x, N]||^2 in NumPy (n = 3..6) and
    symrb.double_bracket_rhs against hat(xi x (xi x nu)) with numpy.cross (n = 3) and NumPy
    commutators (n = 4..6), 20 random skew pairs each: max difference relative to ||x||^2 ||N||^2
    (potential) and ||x||^2 ||N|| (field)."""
    import symrb

    rng = np.random.default_rng(141)
    worst = []
    for k in range(3, 7):
        x_, N_ = (np.stack([ref.random_skew(k, rng) for _ in range(20)]) for _ in range(2))
        nx, nN = np.sqrt(_np_norm2(x_)), np.sqrt(_np_norm2(N_))
        want_V = -0.5 * _np_norm2(_np_comm(x_, N_))
        worst.append(np.max(np.abs(symrb.brockett_potential(x_, N_) - want_V) / (nx * nN) ** 2))
        if k == 3:
            xi, nu = ref.vee(x_), ref.vee(N_)
            want = ref.hat(np.cross(xi, np.cross(xi, nu)))
        else:
            want = _np_comm(x_, _np_comm(x_, N_))
        err = np.abs(symrb.double_bracket_rhs(x_, N_) - want).max(axis=(-2, -1))
        worst.append(np.max(err / (nx**2 * nN)))
    return float(np.max(worst))


def _complex_step_field(
    x_: np.ndarray, p_: np.ndarray, N_: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Hamilton's equations of the NumPy H* = 1/2 ||[p, x]||^2 - 1/2 ||[x, N]||^2 by complex-step
    derivatives along the orthonormal basis E_ij of so(k): xdot = sum_E dH/dp[E] E,
    pdot = -sum_E dH/dx[E] E (exact to rounding: no cancellation)."""

    def H(xx: np.ndarray, pp: np.ndarray) -> np.ndarray:
        return 0.5 * _np_norm2(_np_comm(pp, xx)) - 0.5 * _np_norm2(_np_comm(xx, N_))

    h = 1e-30
    xdot, pdot = np.zeros_like(x_), np.zeros_like(p_)
    for E in (np.array(e, dtype=float) for e in so_basis(x_.shape[-1])):
        xdot += np.imag(H(x_, p_ + 1j * h * E))[..., None, None] / h * E
        pdot -= np.imag(H(x_ + 1j * h * E, p_))[..., None, None] / h * E
    return xdot, pdot


@S14.check(Level.FLOAT64, tol=1e-13)
def s14_symrb_extremal_field() -> float:
    """symrb.orbit_extremal_rhs against Hamilton's equations of the independent NumPy
    H* = 1/2 ||[p, x]||^2 - 1/2 ||[x, N]||^2, differentiated by the complex step along an
    orthonormal basis of so(n), n = 3..5, 20 random skew (x, p, N) each: max difference relative
    to the largest entry of the reference field."""
    import symrb

    rng = np.random.default_rng(142)
    worst = []
    for k in range(3, 6):
        x_, p_, N_ = (np.stack([ref.random_skew(k, rng) for _ in range(20)]) for _ in range(3))
        want = _complex_step_field(x_, p_, N_)
        got = symrb.orbit_extremal_rhs(x_, p_, N_)
        for g, w_ in zip(got, want, strict=True):
            worst.append(np.max(np.abs(g - w_)) / np.max(np.abs(w_)))
    return float(np.max(worst))


@S14.check(Level.FLOAT64, tol=1e-8)
def s14_toda_flow() -> float:
    """The emitted double bracket field on x = iL, N = iD, integrated as Ldot = -[L, [L, D]]
    (DOP853, rtol 1e-11, k = 5, t in [0, 3]), against Flaschka's Toda equations integrated on
    (a, b): max entry difference.  It calls the generated kernel symrb._generated.adjoint_orbits
    directly because the public symrb.double_bracket_rhs accepts skew x only (L is symmetric)."""
    from scipy.integrate import solve_ivp

    from symrb._generated.adjoint_orbits import double_bracket_rhs

    k = 5
    rng = np.random.default_rng(5)
    a0, b0 = rng.standard_normal(k), rng.uniform(0.3, 1.0, k - 1)
    L0 = np.diag(a0) + np.diag(b0, 1) + np.diag(b0, -1)
    D = np.diag(np.arange(1.0, k + 1))
    ts = np.linspace(0, 3, 31)
    opts = {"t_eval": ts, "method": "DOP853", "rtol": 1e-11, "atol": 1e-12}
    s1 = solve_ivp(
        lambda _t, y: -double_bracket_rhs(y.reshape(k, k), D).ravel(), (0, 3), L0.ravel(), **opts
    )

    def toda(_t: float, y: np.ndarray) -> np.ndarray:
        a, b = y[:k], y[k:]
        bb = np.concatenate([[0.0], b, [0.0]])
        return np.concatenate([2 * (bb[1:] ** 2 - bb[:-1] ** 2), b * (a[1:] - a[:-1])])

    s2 = solve_ivp(toda, (0, 3), np.concatenate([a0, b0]), **opts)
    Ls = s1.y.T.reshape(-1, k, k)
    Lt = np.zeros_like(Ls)
    idx = np.arange(k)
    Lt[:, idx, idx] = s2.y[:k].T
    Lt[:, idx[:-1], idx[1:]] = Lt[:, idx[1:], idx[:-1]] = s2.y[k:].T
    return float(np.max(np.abs(Ls - Lt)))


# =============================================================================================
# S15: the learning version, terminal cost phi(x^a_T) = <x^a_T, N>

_ia_s, _ib_s = sp.Symbol("a"), sp.Symbol("b")
xa, pa, xb, pb = matrix("x^a"), matrix("p^a"), matrix("x^b"), matrix("p^b")
xaT, paT = matrix("x^a_T"), matrix("p^a_T")
XDOT_A, PDOT_A = matrix(r"\dot{x}^a"), matrix(r"\dot{p}^a")
USTAR_M = matrix("u^*")
GRAD_PHI = matrix(r"\partial\phi/\partial x^a_T")
x_T, x_0 = matrix("x_T"), matrix("x_0")
x1T, x2T, x10, x20 = matrix("x^1_T"), matrix("x^2_T"), matrix("x^1_0"), matrix("x^2_0")
_phi_T, _phi_0, _beta = sp.symbols("phi_T phi_0 beta", positive=True)

S15 = claim(
    "S15",
    label="varm, opbm",
    title="Learning version on adjoint orbits: terminal cost and the double bracket flow",
    statement="Samples $x^a$ steered by one shared control, [[orb_m]], with the cost [[cost_m]], "
    "Brockett's potential for each sample and the terminal cost [[phi]].",
    printed="The extremals solve [[opbm_printed]] with [[endpoint_printed]]; then the solution "
    "tends to the double bracket equation [[double_bracket]] and the second term of the costate "
    "equation, [[second_term]], goes to zero.",
    corrected="With the shared control [[shared_control]] the extremals solve [[opbm_corrected]] "
    "with [[endpoint_corrected]]. For one sample the extremal is [[p_one]] on all of $[0,T]$ and "
    "$x$ follows the double bracket flow for every $T$; on so(3) the second term decays as "
    "[[decay]] where [[phase]] ($\\phi_T$ the angle between $x_T$ and $-N$), exponentially at the "
    "rate $\\|x_0\\|\\|N\\|$. For two or more samples the shared control conserves the pairings, "
    "[[invariant]], and on so(3) this gives [[bound]] for every $T$, where [[beta]]: the second "
    "term does not go to zero unless the samples start on one line.",
    expected="holds after correction",
    section="3.4",
    where="Section 3.4, the second corollary (several samples $x^a$ with a terminal cost, $p^a_T "
    "= \\partial\\phi/\\partial x^a_T$) and the last paragraph of the section (with $\\phi(x^a_T) "
    "= \\langle x^a_T, n\\rangle$ the solution is said to tend to the double bracket equation "
    "$\\dot x = [x, [x, n]]$)",
    note="The endpoint sign is wrong, the per-sample control ignores that the samples share $u$, "
    "and for several samples the solution does not tend to the double bracket flow. Corrected: "
    "$p^a_T = -\\partial\\phi/\\partial x^a_T$ and $u^* = \\sum_b [p^b, x^b]$; one sample follows "
    "the double bracket flow for every $T$, several do not. (1) Endpoint sign: with $H = \\langle "
    "p, f\\rangle - L$ (the convention of S13), minimising $\\int L + \\phi(x_T)$ needs $p_T = "
    "-\\partial\\phi/\\partial x_T = -N$; the printed $+\\partial\\phi/\\partial x_T$ makes the "
    "adjoint gradient of the cost wrong (relative error 0.53) and its extremal $p = +N$ drives "
    "$x$ along $\\dot x = -[x,[x,N]]$, maximising $\\langle x_T, N\\rangle$. (2) The samples "
    "share the control, so $u^* = \\sum_b [p^b, x^b]$; the printed per-sample $[p^a, x^a]$ is not "
    "Hamilton's equation of the shared problem (and $x$ in $[p^a,[p^a,x]]$ lacks its index; we "
    "read it as $x^a$). (3) The limit: for one sample the corrected extremal is the double "
    "bracket flow for every $T$ ($p = -N$ exactly) and $\\|[N,[N,x_T]]\\|$ decays like "
    "$e^{-\\|x_0\\| \\|N\\| T}$: on $\\mathfrak{so}(3)$ with $\\|x_0\\| = 0.5$, $\\|N\\| = 1$ it "
    "is 0.499, 0.431, 0.202, 0.029, 5.2e-4 at $T$ = 1, 2, 4, 8, 16 (times $e^{T/2}$ it tends to "
    "$2\\tan(\\phi_0/2)\\|N\\|^2 \\|x_0\\| = 1.557$), and `solve_orbit_bvp` from the guess $p = "
    "0$ reproduces the exact solution to 5e-8 (collocation tolerance 1e-6). For two samples the "
    "shared control rotates both by the same rotation (it conserves $\\langle x^1, x^2\\rangle$ "
    "for every $n$), so on $\\mathfrak{so}(3)$ the angle between the lines of $x^1$ and $x^2$ is "
    "fixed and $\\max_a \\|[N,[N,x^a_T]]\\|$ stays above $\\|N\\|^2 \\min_a \\|x^a_0\\| "
    "\\sin(\\beta/2)$ for every $T$ (sharp: attained by samples of equal norm placed "
    "symmetrically about $N$). On the $\\mathfrak{so}(3)$ example (seed 150) the bound is 1.708 "
    "and the BVP solutions give 2.152, 2.176, 2.176 at $T$ = 2, 4, 8: the second term settles at "
    "a positive value instead of going to zero, and neither sample follows its own double bracket "
    "flow.",
)
ORB_M = S15.formula("orb_m", eq(XDOT_A, Bracket(xa, u)))
PHI_EQ = S15.formula("phi", eq(PHI(xaT), Pair(xaT, N)))
COST_M = S15.formula(
    "cost_m",
    eq(
        sp.Function("eta")(u),
        sp.Integral(_Norm(u) ** 2 / 2 - _sample_sum(V(xa), _ia_s), (t, 0, T))
        + _sample_sum(PHI(xaT), _ia_s),
    ),
)
OPBM_PRINTED = S15.formula(
    "opbm_printed",
    (
        eq(XDOT_A, Bracket(xa, Bracket(pa, xa))),
        eq(PDOT_A, _minus(Bracket(pa, Bracket(pa, xa)), Bracket(N, Bracket(N, xa)))),
    ),
)
ENDPOINT = {
    "printed": S15.formula("endpoint_printed", eq(paT, GRAD_PHI)),
    "corrected": S15.formula("endpoint_corrected", eq(paT, -GRAD_PHI)),
}
S15.formula("double_bracket", DOUBLE_BRACKET)
SECOND_TERM = S15.formula("second_term", Bracket(N, Bracket(N, xa)))
SHARED_CONTROL = S15.formula("shared_control", eq(USTAR_M, _sample_sum(Bracket(pb, xb), _ib_s)))
OPBM_CORRECTED = S15.formula(
    "opbm_corrected",
    (
        eq(XDOT_A, ORB_M.rhs.xreplace({u: USTAR_M})),
        eq(PDOT_A, _minus(Bracket(pa, USTAR_M), SECOND_TERM)),
    ),
)
P_ONE = S15.formula("p_one", eq(p, -N))
DECAY = S15.formula(
    "decay",
    eq(_Norm(Bracket(N, Bracket(N, x_T))), _Norm(N) ** 2 * _Norm(x_0) * sp.sin(_phi_T)),
)
PHASE = S15.formula(
    "phase",
    eq(sp.tan(_phi_T / 2), sp.tan(_phi_0 / 2) * sp.exp(-_Norm(x_0) * _Norm(N) * T)),
)
_x1, _x2 = matrix("x^1"), matrix("x^2")
INVARIANT = S15.formula("invariant", eq(sp.Derivative(Pair(_x1, _x2), t), 0))
BETA = S15.formula("beta", eq(sp.cos(_beta), sp.Abs(Pair(x10, x20)) / (_Norm(x10) * _Norm(x20))))
BOUND = S15.formula(
    "bound",
    sp.Ge(
        sp.Max(_Norm(Bracket(N, Bracket(N, x1T))), _Norm(Bracket(N, Bracket(N, x2T)))),
        _Norm(N) ** 2 * sp.Min(_Norm(x10), _Norm(x20)) * sp.sin(_beta / 2),
    ),
)
# the Hamiltonian of the shared problem (not displayed: H of S13 summed over the samples)
H_SHARED = _sample_sum(Pair(pa, ORB_M.rhs), _ia_s) - _Norm(u) ** 2 / 2 + _sample_sum(V(xa), _ia_s)

ORBIT_RHS_WITH_CONTROL = Kernel(
    name="orbit_rhs_with_control",
    target="adjoint_orbits",
    args=[ARG_X, ARG_P, ARG_U, ARG_N],
    outputs={
        "xdot": OPBM_CORRECTED[0].rhs.xreplace({xa: x, USTAR_M: u}).doit(),
        "pdot": OPBM_CORRECTED[1].rhs.xreplace({xa: x, pa: p, USTAR_M: u}).doit(),
    },
    doc="State and costate fields of one sample for a given control u.\n\n"
    "xdot = [x, u], pdot = [p, u] - [N, [N, x]] (Brockett's potential); with the shared optimal\n"
    "control u = sum_b [p^b, x^b] these are the extremal equations of the learning version.",
    claims=("S15",),
)


def _kernel_of_sample(expr: sp.Basic, k: int, control: sp.MatrixExpr | None = None) -> sp.Basic:
    """A kernel output for sample k: x -> x^k, p -> p^k (and u -> ``control``)."""
    reps = {x: matrix(f"x^{k}"), p: matrix(f"p^{k}")}
    if control is not None:
        reps[u] = control
    return expr.xreplace(reps)


def _emitted_shared_control(count: int) -> sp.MatrixExpr:
    """sum over the samples of the emitted optimal control (how solve_orbit_bvp computes u*)."""
    return sp.MatAdd(*[_kernel_of_sample(OPTIMAL_CONTROL["u"], k) for k in range(1, count + 1)])


def _two_sample_hamilton(form: str) -> sp.Expr:
    """Hamilton's equations of the shared problem with two samples: H* is H_SHARED at the
    displayed shared control; its derivatives in p^1, x^1 along d against the displayed printed
    or corrected equations of sample 1."""
    w = Words()
    ustar = _samples(SHARED_CONTROL.rhs, 2)
    Hstar = _samples(H_SHARED, 2).xreplace({u: ustar})
    eqs = OPBM_PRINTED if form == "printed" else OPBM_CORRECTED
    xdot, pdot = (_of_sample(e.rhs.xreplace({USTAR_M: SHARED_CONTROL.rhs}), "a", 1) for e in eqs)
    xdot, pdot = _samples(xdot, 2), _samples(pdot, 2)
    x1, p1 = matrix("x^1"), matrix("p^1")
    r = trace_residual(_directional(Hstar, {p1: d}, w, _brockett) - _pair_poly(xdot, d, w))
    return r + trace_residual(-_directional(Hstar, {x1: d}, w, _brockett) - _pair_poly(pdot, d, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s15_printed_equations() -> sp.Expr:
    """The displayed printed equations (per-sample control [p^a, x^a]) against Hamilton's
    equations of the shared problem's H* with two samples (trace words, every n): must fail."""
    return _two_sample_hamilton("printed")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_corrected_equations() -> sp.Expr:
    """The displayed corrected equations (shared control) are Hamilton's equations of the
    shared problem's H* = H at the displayed u* with two samples (trace words, every n)."""
    return _two_sample_hamilton("corrected")


def _phi(y: sp.Basic) -> sp.Basic:
    """The displayed terminal cost at y."""
    return PHI_EQ.rhs.xreplace({xaT: y})


def _endpoint_first_variation(form: str) -> sp.Expr:
    """First variation of the displayed cost for one sample along a control variation du, with
    dx_0 = 0 and dxdot = d/de [x + e dx, u + e du].

    With the displayed costate equation (general control u), dL - d/dt <p, dx> = <u - u*, du>
    for L the integrand of the displayed cost and u* the displayed shared control (one sample), so
    that dJ = int <u - u*, du> dt + <p_T, dx_T> + dphi[dx_T].  Returns the trace residual of that
    identity, of dphi[d] = <N, d> for the displayed terminal cost, and of the boundary term
    dphi[dx_T] + <p_T, dx_T> with p_T from the displayed endpoint condition of ``form``.
    """
    w = Words()
    dx, du, dxT = matrix("dx"), matrix("du"), matrix("dx_T")
    x1, p1, x1T = matrix("x^1"), matrix("p^1"), matrix("x^1_T")
    (integral,) = COST_M.rhs.atoms(sp.Integral)
    dL = _directional(_samples(integral.function, 1), {x1: dx, u: du}, w, _brockett)
    pdot = _of_sample(OPBM_CORRECTED[1].rhs.xreplace({USTAR_M: u}), "a", 1)
    dxdot = _of_sample(ORB_M.rhs, "a", 1).xreplace({x1: x1 + _EPS * dx, u: u + _EPS * du})
    d_dt = _pair_poly(pdot, dx, w) + sp.diff(_trace_poly(Pair(p1, dxdot), w), _EPS).subs(_EPS, 0)
    ustar = _samples(SHARED_CONTROL.rhs, 1)
    r = trace_residual(dL - d_dt - _pair_poly(_minus(u, ustar), du, w))
    terminal = (COST_M.rhs - integral).replace(
        lambda e: isinstance(e, AppliedUndef) and e.func == PHI, lambda e: _phi(e.args[0])
    )
    dphi = _directional(_samples(terminal, 1), {x1T: dxT}, w)
    r += trace_residual(dphi - _pair_poly(N, dxT, w))  # the gradient of phi is N
    pT = _of_sample(ENDPOINT[form].rhs.xreplace({GRAD_PHI: N}), "a", 1)
    return r + trace_residual(dphi + _pair_poly(pT, dxT, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def s15_printed_endpoint() -> sp.Expr:
    """First variation of the cost: with the displayed printed endpoint condition the boundary
    term dphi[dx_T] + <p_T, dx_T> does not vanish (trace words, every n): must fail."""
    return _endpoint_first_variation("printed")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_corrected_endpoint() -> sp.Expr:
    """First variation of the displayed cost (one sample, dx_0 = 0): along the linearised state
    and the displayed costate equation dL - d/dt <p, dx> = <u - u*, du>, so
    dJ = int <u - u*, du> dt + dphi[dx_T] + <p_T, dx_T>; with the displayed corrected endpoint
    condition the boundary term vanishes for every dx_T (trace words, every n)."""
    return _endpoint_first_variation("corrected")


@functools.cache
def _cost_and_forward() -> tuple[Any, ...]:
    """so(3), two samples, T = 1, u(t) = u0 + t u1: the directional derivative of the cost along
    du(t) = d0 + t d1 by central differences (h = 1e-4, DOP853 rtol 1e-12) and the forward
    trajectory for the adjoint."""
    from scipy.integrate import solve_ivp

    import symrb
    from symrb._generated.adjoint_orbits import orbit_rhs_with_control

    rng = np.random.default_rng(15)
    k, M = 3, 2
    N_, u0, u1, d0, d1 = (ref.random_skew(k, rng, 0.5) for _ in range(5))
    x0 = np.stack([ref.random_skew(k, rng, 0.5) for _ in range(M)])
    opts = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-13}

    def cost(h: float) -> float:
        def f(tt: float, y: np.ndarray) -> np.ndarray:
            xx = y[:-1].reshape(M, k, k)
            uu = u0 + tt * u1 + h * (d0 + tt * d1)
            dx, _ = orbit_rhs_with_control(xx, xx, uu, N_)
            run = 0.5 * _np_norm2(uu) - np.sum(symrb.brockett_potential(xx, N_))
            return np.concatenate([dx.ravel(), [run]])

        s = solve_ivp(f, (0, 1.0), np.concatenate([x0.ravel(), [0.0]]), **opts)
        xT = s.y[:-1, -1].reshape(M, k, k)
        return float(s.y[-1, -1] + np.sum(_np_pair(xT, N_)))

    fwd = solve_ivp(
        lambda tt, y: orbit_rhs_with_control(
            y.reshape(M, k, k), y.reshape(M, k, k), u0 + tt * u1, N_
        )[0].ravel(),
        (0, 1.0),
        x0.ravel(),
        dense_output=True,
        **opts,
    )
    h = 1e-4
    return (cost(h) - cost(-h)) / (2 * h), fwd, N_, u0, u1, d0, d1


def _endpoint_gradient(form: str) -> float:
    """Relative difference between the adjoint directional derivative of the cost and central
    differences; the adjoint starts from p^a_T of the displayed endpoint condition of ``form``
    (the gradient of phi replaced by N) and integrates the emitted costate field backwards."""
    from scipy.integrate import solve_ivp

    from symrb._generated.adjoint_orbits import optimal_control, orbit_rhs_with_control

    fd, fwd, N_, u0, u1, d0, d1 = _cost_and_forward()
    M, k = 2, 3
    pT_expr = ENDPOINT[form].rhs.xreplace({GRAD_PHI: N})
    pT = np.array(explicit(pT_expr, {"N": sp.Matrix(N_)}), dtype=float)

    def adjoint(tt: float, y: np.ndarray) -> np.ndarray:
        pp = y[:-1].reshape(M, k, k)
        xx = fwd.sol(tt).reshape(M, k, k)
        uu = u0 + tt * u1
        _, dp = orbit_rhs_with_control(xx, pp, uu, N_)
        integrand = _np_pair(uu - optimal_control(xx, pp).sum(axis=0), d0 + tt * d1)
        return np.concatenate([dp.ravel(), [integrand]])

    y_T = np.concatenate([np.broadcast_to(pT, (M, k, k)).ravel(), [0.0]])
    back = solve_ivp(adjoint, (1.0, 0.0), y_T, method="DOP853", rtol=1e-12, atol=1e-13)
    gradient = -back.y[-1, -1]  # integrated from T down to 0
    return abs(gradient - fd) / abs(fd)


@S15.check(Level.FLOAT64, tol=1e-6, form="printed")
def s15_printed_endpoint_gradient() -> float:
    """The adjoint directional derivative of the cost with the printed p_T (so(3), two samples,
    T = 1, Brockett's V from symrb.brockett_potential, emitted state-costate field) against
    central differences of the cost: relative difference (must be large)."""
    return _endpoint_gradient("printed")


@S15.check(Level.FLOAT64, tol=1e-6, form="corrected")
def s15_corrected_endpoint_gradient() -> float:
    """The same with the corrected p_T: the adjoint directional derivative of the cost equals the
    central differences (relative difference)."""
    return _endpoint_gradient("corrected")


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_emitted_shared_field() -> sp.Expr:
    """Two samples: dH/du of the shared problem vanishes at the sum over samples of the emitted
    optimal control for every direction, and the emitted state-costate field at that control is
    the displayed corrected equations (trace words, every n)."""
    w = Words()
    ustar = _emitted_shared_control(2)
    moved = _samples(H_SHARED, 2).xreplace({u: ustar + _EPS * d})
    r = trace_residual(sp.diff(_trace_poly(moved, w, _linear_potential), _EPS).subs(_EPS, 0))
    for k in (1, 2):
        for out, formula in zip(("xdot", "pdot"), OPBM_CORRECTED, strict=True):
            emitted = _kernel_of_sample(ORBIT_RHS_WITH_CONTROL[out], k, ustar)
            want = _samples(
                _of_sample(formula.rhs.xreplace({USTAR_M: SHARED_CONTROL.rhs}), "a", k), 2
            )
            r += trace_residual(_pair_poly(emitted - want, d, w))
    return r


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_one_sample_exact() -> sp.Expr:
    """One sample: at the displayed p = -N the emitted extremal field has pdot = 0 for every x and
    xdot equal to the emitted double bracket field (trace words, every n), so p = -N and the
    double bracket flow solve the boundary value problem for every T."""
    w = Words()
    at = {p: P_ONE.rhs}
    pdot = ORBIT_EXTREMAL_RHS["pdot"].xreplace(at)
    xdot = ORBIT_EXTREMAL_RHS["xdot"].xreplace(at)
    r = trace_residual(_pair_poly(pdot, d, w))
    return r + trace_residual(_pair_poly(xdot - DOUBLE_BRACKET_RHS["xdot"], d, w))


@S15.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def s15_shared_control_invariant() -> sp.Expr:
    """Under one shared control the time derivative of the displayed pairing <x^1, x^2>, along
    the emitted state field of each sample, vanishes for any control and any n (trace words)."""
    w = Words()
    moves = {
        xk: _kernel_of_sample(ORBIT_RHS_WITH_CONTROL["xdot"], k) for k, xk in ((1, _x1), (2, _x2))
    }
    (derivative,) = INVARIANT.lhs.args[:1]
    r = trace_residual(_directional(derivative, moves, w) - _trace_poly(INVARIANT.rhs, w))
    return r


# --- the one-sample decay on so(3) -------------------------------------------------------------

_r, _s, _tau, _tau0 = sp.symbols("r s tau tau_0", positive=True)


def _half_angle(tau: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    """(sin phi, cos phi) from tau = tan(phi / 2)."""
    return 2 * tau / (1 + tau**2), (1 - tau**2) / (1 + tau**2)


def _phase_tau() -> sp.Expr:
    """tan(phi_T / 2) from the displayed phase formula with ||x_0|| = r, ||N|| = s and
    tan(phi_0 / 2) = tau_0."""
    norms = {_Norm(x_0): _r, _Norm(N): _s}
    return PHASE.rhs.xreplace(norms).subs(sp.tan(_phi_0 / 2), _tau0)


def _decay_closed_form() -> sp.Expr:
    """The displayed decay ||N||^2 ||x_0|| sin(phi_T) with sin(phi_T) = 2 tau / (1 + tau^2),
    tau = tan(phi_T / 2) from the displayed phase (||x_0|| = r, ||N|| = s, tan(phi_0 / 2) =
    tau_0)."""
    sin_T, _ = _half_angle(_phase_tau())
    return DECAY.rhs.xreplace({_Norm(x_0): _r, _Norm(N): _s}).subs(sp.sin(_phi_T), sin_T)


ONE_SAMPLE_SECOND_TERM = Kernel(
    name="one_sample_second_term",
    target="adjoint_orbits",
    args=[
        Arg("r", "(...)", "||x_0||, the norm of the sample"),
        Arg("s", "(...)", "||N||"),
        Arg("tau_0", "(...)", "tan(phi_0 / 2), phi_0 the angle of x_0 from -N"),
        Arg("T", "(...)", "the time, >= 0"),
    ],
    outputs={"second_term": _decay_closed_form()},
    doc="||[N, [N, x(T)]]|| along the one-sample extremal on so(3), in closed form.\n\n"
    "The displayed decay ||N||^2 ||x_0|| sin(phi_T), with the displayed phase\n"
    "tan(phi_T / 2) = tan(phi_0 / 2) exp(-||x_0|| ||N|| T): x(T) is the double bracket flow.",
    claims=("S15",),
)


def _rational_residual(values: sp.Matrix | sp.Expr) -> sp.Integer:
    """The number of entries that are not identically zero as rational functions."""
    items = list(values) if isinstance(values, sp.MatrixBase) else [values]
    return sp.Integer(sum(sp.cancel(sp.together(e)) != 0 for e in items))


@S15.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s15_decay_exact_so3() -> sp.Expr:
    """so(3), N = s hat(e3), x = r (sin phi e1 - cos phi e3) written in tau = tan(phi/2): with
    tau(T) from the displayed phase, dtau/dT = -||x_0|| ||N|| tau, dx/dT equals the emitted double
    bracket field, the squared displayed ||[N, [N, x]]|| equals the square of the displayed decay,
    and the decay divided by tau tends to 2 s^2 r as tau tends to 0: it vanishes like
    exp(-||x_0|| ||N|| T) (exact rational functions of tau)."""
    tau_T = _phase_tau()
    rate = sp.simplify(sp.diff(tau_T, T) / tau_T)  # -r s
    sin_t, cos_t = _half_angle(_tau)
    x_tau = hat3([_r * sin_t, 0, -_r * cos_t])
    Nm = hat3([0, 0, _s])
    field = explicit(DOUBLE_BRACKET_RHS["xdot"], {"x": x_tau, "N": Nm})
    r = _rational_residual(sp.diff(x_tau, _tau) * rate * _tau - field)
    env = {"x_T": x_tau, "N": Nm, "x_0": hat3([0, 0, _r])}  # only ||x_0|| = r enters the decay
    lhs = explicit(_plain(DECAY.lhs**2), env)
    rhs_sq = explicit(_plain(DECAY.rhs**2), env).subs(sp.sin(_phi_T), sin_t)
    r += _rational_residual(lhs - rhs_sq)
    decay = _s**2 * _r * sin_t  # the displayed decay: its square is rhs_sq, and it is positive
    r += _rational_residual(decay**2 - rhs_sq)
    limit = sp.cancel(decay / _tau).subs(_tau, 0)
    r += _rational_residual(rate + _r * _s) + _rational_residual(limit - 2 * _s**2 * _r)
    # the emitted closed form is this decay at tau = tau(T) of the displayed phase
    emitted = ONE_SAMPLE_SECOND_TERM["second_term"]
    r += _rational_residual(sp.simplify(emitted - decay.subs(_tau, tau_T)))
    return r


def _exact_so3(x0: np.ndarray, N_: np.ndarray, Ts: np.ndarray) -> np.ndarray:
    """The exact so(3) double bracket flow at the times Ts from x0 (NumPy, from the displayed
    phase): x(T) = r (sin phi_T e - cos phi_T nu/|nu|) in the plane of x0 and N, with e the unit
    vector of x0's component orthogonal to N."""
    xi, nu = ref.vee(x0), ref.vee(N_)
    r, s = np.linalg.norm(xi), np.linalg.norm(nu)
    axis = nu / s
    phi0 = np.arccos(np.clip(-xi @ axis / r, -1.0, 1.0))
    perp = xi + r * np.cos(phi0) * axis
    e = perp / np.linalg.norm(perp)
    tau_fn = sp.lambdify((_r, _s, _tau0, T), _phase_tau(), "numpy")
    tau = tau_fn(r, s, np.tan(phi0 / 2), Ts)
    sin_t, cos_t = 2 * tau / (1 + tau**2), (1 - tau**2) / (1 + tau**2)
    return ref.hat(r * (sin_t[:, None] * e - cos_t[:, None] * axis))


ONE_SAMPLE_HORIZONS = (1.0, 2.0, 4.0, 8.0, 16.0)


def one_sample_data() -> tuple[np.ndarray, np.ndarray]:
    """so(3) data of the one-sample checks: ||N|| = 1, ||x_0|| = 0.5, x_0 at the angle 2 from -N
    (decay rate 0.5)."""
    rng = np.random.default_rng(151)
    q = ref.random_rotation(3, rng)
    nu, e = q[:, 2], q[:, 0]
    xi = 0.5 * (np.sin(2.0) * e - np.cos(2.0) * nu)
    return ref.hat(xi), ref.hat(nu)


@functools.cache
def one_sample_runs() -> dict[float, Any]:
    """solve_orbit_bvp for one sample, from the guess p = 0, at each horizon of
    ONE_SAMPLE_HORIZONS."""
    import symrb

    x0, N_ = one_sample_data()
    return {
        Tk: symrb.solve_orbit_bvp(x0, N_, Tk, p_guess=np.zeros((3, 3)))
        for Tk in ONE_SAMPLE_HORIZONS
    }


def _second_term_norm(x_: np.ndarray, N_: np.ndarray) -> np.ndarray:
    c = _np_comm(N_, _np_comm(N_, x_))
    return np.sqrt(_np_norm2(c))


@S15.check(Level.FLOAT64, tol=1e-6, form="corrected")
def s15_one_sample_bvp() -> float:
    """One sample on so(3), T = 1, 2, 4, 8, 16: symrb.solve_orbit_bvp from the guess p = 0 against
    the exact solution (p = -N, x the double bracket flow in closed form from the displayed
    phase): max of |x_T - exact| / ||x_0||, |p + N| / ||N|| over the mesh and the difference of
    ||[N, [N, x_T]]|| from the emitted closed form (symrb.one_sample_second_term) relative to
    ||N||^2 ||x_0||."""
    import symrb

    x0, N_ = one_sample_data()
    r, s = np.sqrt(_np_norm2(x0)), np.sqrt(_np_norm2(N_))
    xs = _exact_so3(x0, N_, np.array(ONE_SAMPLE_HORIZONS))
    decay = symrb.one_sample_second_term(x0, N_, ONE_SAMPLE_HORIZONS)
    errs = []
    for i, Tk in enumerate(ONE_SAMPLE_HORIZONS):
        res = one_sample_runs()[Tk]
        if not res.success:
            return float("inf")
        xT = res.x[-1, 0]
        errs += [
            np.max(np.abs(xT - xs[i])) / r,
            np.max(np.abs(res.p + N_)) / s,
            abs(_second_term_norm(xT, N_) - decay[i]) / (s**2 * r),
        ]
    return float(np.max(errs))


# --- two samples: the lower bound ---------------------------------------------------------------


@S15.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def s15_bound_so3() -> sp.Expr:
    """so(3), x^a = r_a hat(a_a) with a_1, a_2 at the angles +h and -h from e1 (0 < 2h <= pi/2),
    N = s hat(c), c a unit vector: the displayed cos beta is cos 2h, and the mean over a of the
    squared displayed ||[N, [N, x^a]]|| / (s^2 r_a)^2 minus the squared displayed bound at unit
    norms equals c_2^2 cos 2h + c_3^2 cos^2 h >= 0, so the larger of the two exceeds the bound
    (polynomials in C = cos h, S = sin h and c reduced by C^2 + S^2 = 1 and |c| = 1)."""
    C, S, r1, r2 = sp.symbols("C S r_1 r_2", positive=True)
    c1, c2, c3 = sp.symbols("c1:4", real=True)
    a1, a2 = [C, S, 0], [C, -S, 0]
    env = {
        "x^1_0": r1 * hat3(a1),
        "x^2_0": r2 * hat3(a2),
        "x^1_T": r1 * hat3(a1),
        "x^2_T": r2 * hat3(a2),
        "N": _s * hat3([c1, c2, c3]),
    }

    def reduce(e: sp.Expr) -> sp.Expr:
        """Numerator of e on C^2 + S^2 = 1, |c| = 1 (even powers of S and c3 only)."""
        num, den = sp.fraction(sp.together(e))
        on = {S**2: 1 - C**2, c3**2: 1 - c1**2 - c2**2}
        return sp.expand(sp.expand(num).subs(on)) / sp.expand(sp.expand(den).subs(on))

    cos_2h = C**2 - S**2
    cos_beta = explicit(_plain(BETA.rhs), env)
    r = _rational_residual(reduce(cos_beta**2 - cos_2h**2))  # |.| squared; cos 2h >= 0
    mean = sp.Integer(0)
    for term in BOUND.lhs.args:  # ||[N, [N, x^a_T]]|| for a = 1, 2 (in Max's order)
        rk = r1 if x1T in term.atoms(sp.MatrixSymbol) else r2
        mean += explicit(_plain(term**2), env) / (_s**2 * rk) ** 2 / 2
    unit_norms = {**env, "x^1_0": hat3(a1), "x^2_0": hat3(a2), "N": hat3([c1, c2, c3])}
    bound_unit = explicit(_plain(BOUND.rhs), unit_norms).subs(sp.sin(_beta / 2), S)
    claimed = c2**2 * cos_2h + c3**2 * C**2
    return r + _rational_residual(reduce(mean - bound_unit**2 - claimed))


TWO_SAMPLE_HORIZONS = (2.0, 4.0, 8.0)


def two_sample_data() -> tuple[np.ndarray, np.ndarray]:
    """so(3) data of the two-sample checks: N and two samples x^1_0, x^2_0 (seed 150)."""
    rng = np.random.default_rng(150)
    N_ = ref.random_skew(3, rng, 0.5)
    return np.stack([ref.random_skew(3, rng, 0.5) for _ in range(2)]), N_


_r1, _r2 = sp.symbols("r_1 r_2", positive=True)
_p12 = sp.Symbol("p_12", real=True)


def _bound_closed_form() -> sp.Expr:
    """The displayed bound ||N||^2 min_a ||x^a_0|| sin(beta / 2) with the displayed beta, in the
    norms r_1, r_2, s and the pairing p_12 = <x^1_0, x^2_0>."""
    norms = {_Norm(x10): _r1, _Norm(x20): _r2}
    cos_beta = BETA.rhs.xreplace({**norms, sp.Abs(Pair(x10, x20)): sp.Abs(_p12)})
    return BOUND.rhs.xreplace({**norms, _Norm(N): _s}).subs(_beta, sp.acos(cos_beta))


TWO_SAMPLE_BOUND = Kernel(
    name="two_sample_bound",
    target="adjoint_orbits",
    args=[
        Arg("r_1", "(...)", "||x^1_0||"),
        Arg("r_2", "(...)", "||x^2_0||"),
        Arg("s", "(...)", "||N||"),
        Arg("p_12", "(...)", "<x^1_0, x^2_0>, at most r_1 r_2 in size"),
    ],
    outputs={"bound": _bound_closed_form()},
    doc="The lower bound of the larger second costate term of two samples on so(3).\n\n"
    "||N||^2 min(||x^1_0||, ||x^2_0||) sin(beta / 2), cos beta = |<x^1_0, x^2_0>| /\n"
    "(||x^1_0|| ||x^2_0||): the displayed bound of the corrected statement.",
    claims=("S15",),
)


@functools.cache
def two_sample_runs() -> dict[float, Any]:
    """solve_orbit_bvp for the two samples at each horizon of TWO_SAMPLE_HORIZONS (collocation
    tolerance 1e-5)."""
    import symrb

    X0, N_ = two_sample_data()
    return {Tk: symrb.solve_orbit_bvp(X0, N_, Tk, tol=1e-5) for Tk in TWO_SAMPLE_HORIZONS}


def _numeric(expr: sp.Basic, env: dict[str, np.ndarray]) -> float:
    """A displayed scalar formula evaluated on float64 matrices (explicit on SymPy Floats)."""
    return float(explicit(_plain(expr), {k: sp.Matrix(v.tolist()) for k, v in env.items()}))


@functools.cache
def two_sample_table() -> tuple[dict[str, float], ...]:
    """For each horizon: the displayed max_a ||[N, [N, x^a_T]]|| of the BVP solution, the
    displayed bound, and the drifts of <x^1, x^2> and ||x^a|| relative to their sizes."""
    X0, N_ = two_sample_data()
    env0 = {"x^1_0": X0[0], "x^2_0": X0[1], "N": N_}
    beta = float(np.arccos(_numeric(BETA.rhs, env0)))
    bound = _numeric(BOUND.rhs.subs(_beta, beta), env0)
    rows = []
    for Tk, res in two_sample_runs().items():
        if not res.success:
            rows.append({"T": Tk, "second": float("nan"), "bound": bound, "drift": float("inf")})
            continue
        xT = res.x[-1]
        second = _numeric(BOUND.lhs, {"x^1_T": xT[0], "x^2_T": xT[1], "N": N_})
        size = np.sqrt(_np_norm2(X0))
        drift = [
            abs(_np_pair(xT[0], xT[1]) - _np_pair(X0[0], X0[1])) / (size[0] * size[1]),
            *np.abs(np.sqrt(_np_norm2(xT)) - size) / size,
        ]
        rows.append({"T": Tk, "second": second, "bound": bound, "drift": float(np.max(drift))})
    return tuple(rows)


@S15.check(Level.FLOAT64, tol=1e-3, form="printed")
def s15_two_samples_second_term() -> float:
    """Two samples on so(3) sharing the control, symrb.solve_orbit_bvp at T = 2, 4, 8: the
    smallest over T of the displayed max_a ||[N, [N, x^a_T]]|| relative to its largest possible
    value ||N||^2 max_a ||x^a_0|| (the printed claim: it goes to zero)."""
    X0, N_ = two_sample_data()
    size = _np_norm2(N_) * np.max(np.sqrt(_np_norm2(X0)))
    return float(np.min([row["second"] for row in two_sample_table()]) / size)


@S15.check(Level.FLOAT64, tol=1e-5, form="corrected")
def s15_two_samples_above_bound() -> float:
    """The same solutions stay above the bound and conserve <x^1, x^2> and ||x^a||: max over T of
    the relative shortfall below symrb.two_sample_bound (the emitted kernel) plus the relative
    drift of the invariants, plus the relative difference of that bound (and of the emitted
    expression) from the displayed bound evaluated on the data."""
    import symrb

    rows = two_sample_table()
    second = np.array([row["second"] for row in rows])  # NaN for a failed solve: stays NaN
    displayed = rows[0]["bound"]
    X0, N_ = two_sample_data()
    shipped = float(symrb.two_sample_bound(X0, N_))  # the emitted kernel, through its wrapper
    norms = np.sqrt(_np_norm2(X0))
    emitted = float(TWO_SAMPLE_BOUND["bound"].subs({  # the emitted expression, by SymPy
        _r1: norms[0], _r2: norms[1], _s: np.sqrt(_np_norm2(N_)), _p12: _np_pair(X0[0], X0[1]),
    }))  # fmt: skip
    shortfall = np.maximum(shipped - second, 0.0) / shipped
    agree = max(abs(shipped - displayed), abs(emitted - displayed)) / displayed
    return float(np.max(shortfall + np.array([row["drift"] for row in rows])) + agree)
