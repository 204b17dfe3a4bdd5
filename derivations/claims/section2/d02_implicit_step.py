r"""D2: the implicit costate step needs the mixed derivative of the reduced Hamiltonian.

Where: Section 2, the remark after the proof of the first proposition: the costate equation is
implicit in :math:`p_{k+1}`, and the paper asks for the matrix
:math:`\partial^2H/\partial y_i\partial x_j` to be invertible.

Recorded outcome: holds after correction.  :math:`u^*` depends on :math:`y = p_{k+1}`, so the
Jacobian of the step is the mixed derivative of :math:`H^*` (envelope theorem), not that of
:math:`H` at fixed :math:`u`.  Evidence: two scalar examples (one exact, one with undefined
:math:`a, b, V`) compare the determinant of each displayed matrix with that of the true Jacobian of
the displayed step, computed by SymPy (independent of symrb); and for every :math:`n` and
:math:`m` the same comparison in matrix symbols.

Every n: the statement is about an arbitrary smooth :math:`f, g`, whose derivatives have no
index-free form.  What makes it all-n is that the Jacobian of the step and the mixed derivative of
:math:`H^*` at a point depend on :math:`f, g` only through their Taylor polynomials of order two
there (chain rule, and :math:`\partial u^*/\partial y = -H_{uu}^{-1}H_{uy}` by the implicit
function theorem).  :math:`H` is linear in :math:`y`, so those polynomials are exactly
:math:`f = Ax + Bu`, :math:`g = \tfrac12 x^TPx + x^TSu + \tfrac12 u^TRu` (linear terms change
no second derivative) with free matrix symbols :math:`A, B, P, S, R` of sizes :math:`n\times n`,
:math:`n\times m`, ... (:math:`P, R` symmetric, :math:`R = g_{uu}` invertible); the check is done
on those.  An equality constraint :math:`h(u) = 0` is the same computation with :math:`u` replaced
by :math:`(u, \sigma)`: :math:`\hat H` is stationary in both, and :math:`h` depends on neither
:math:`x` nor :math:`y`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp

from derivations.claims.section2._general_n import Alphabet, quadratic_problem
from derivations.claims.section2._hamiltonians import (
    _H,
    H_DEF,
    REDUCED,
    _Hstar,
    _us,
    _ustar,
    _with_hamiltonians,
    _xs,
    _y,
)
from derivations.claims.section2._indexed import _define, _grad, _nonzero, _value
from derivations.registry import Level, claim
from derivations.symbolic import eq

D2 = claim(
    "D2",
    label="remark after gendiscprop",
    title="The implicit step needs an invertible mixed second derivative",
    statement="With [[H]], the costate equation is an implicit step [[step]] for the unknown $y$ "
    "(the costate "
    "$p_{k+1}$) given $p_k$ and the state $x$; computing $y$ needs the Jacobian of its right side "
    "in $y$ to be invertible.",
    printed="Invertibility of [[printed_matrix]] at every $(y, x, u)$, with $u$ held fixed, lets "
    "one compute $p_{k+1}$.",
    corrected="The Jacobian of the step is the mixed derivative of the reduced Hamiltonian "
    "[[reduced]] (envelope theorem), [[step_jacobian]], so the implicit function theorem needs "
    "that matrix invertible; it equals the printed matrix only when $u^*$ does not depend on $y$.",
    expected="holds after correction",
    headline="[[step_jacobian]] invertible",
    section="2",
    where="Section 2, the paragraph after the proof of the first proposition: the step is "
    "implicit in $p_{k+1}$ and needs the matrix $\\partial^2 H/\\partial y_i\\,\\partial x_j$ "
    "invertible",
    note="Invertibility of the printed matrix $\\partial^2 H/\\partial y\\,\\partial x$ at fixed "
    "$u$ does not make the step solvable for $p_{k+1}$. Corrected: the step needs the mixed "
    "derivative of the reduced Hamiltonian $H^*(y, x) = \\hat H(y, x, u^*(y, x), \\sigma(y, x))$ "
    "invertible. $u^*_k$ depends on $p_{k+1}$, so the Jacobian of the step picks up "
    "$H_{xu}\\,\\partial u^*/\\partial y$. Exact counterexample: $f = x + u$, $g = (u + x)^2/2 "
    "\\ge 0$ has $\\partial^2 H/\\partial y\\,\\partial x = 1$ everywhere, yet $u^* = y - x$ and "
    "$p_k = 0$ for every $p_{k+1}$: the step does not determine $p_{k+1}$. The index order ($y_i "
    "x_j$ or $x_i y_j$) is a transpose and does not matter for invertibility. For every $n$ and "
    "$m$ (matrix symbols for the second derivatives): the step's Jacobian is $H_{xy} - H_{xu}"
    "H_{uu}^{-1}H_{uy}$, the mixed derivative of $H^*$, and the printed matrix misses the second "
    "term.",
)
D2.formula("H", H_DEF)
STEP = D2.formula(
    "step",
    eq(sp.Symbol("p_k"), sp.Subs(sp.Derivative(_H(_y, _xs, _us), _xs), _us, _ustar(_y, _xs))),
)
PRINTED_MATRIX = D2.formula("printed_matrix", sp.Derivative(_H(_y, _xs, _us), _y, _xs))
D2.formula("reduced", REDUCED)
STEP_JACOBIAN = D2.formula(
    "step_jacobian",
    eq(sp.Symbol(r"\partial p_{k}/\partial y"), sp.Derivative(_Hstar(_y, _xs), _y, _xs)),
)


def _scalar_problem(
    f: Callable[..., Any], g: Callable[..., Any]
) -> tuple[dict[str, Any], dict[Any, Any]]:
    """Functions H, Hhat, u*, H* of a scalar unconstrained problem (n = m = 1) defined by the
    displayed formulas, u* solved from dH/du = 0, and symbolic values for y, x."""
    Y, X, U = sp.symbols("Y X U", real=True)
    fn = _with_hamiltonians({"f": f, "g": g, "h": lambda u: sp.S.Zero})
    dHdu = _value(sp.Derivative(_H(_y, _xs, _us), _us), {"y": Y, "x": X, "u": U}, fn)
    (ustar,) = sp.solve(dHdu, U)
    fn["u^*"] = lambda y, x: ustar.xreplace({Y: y, X: x})
    fn[r"\sigma"] = lambda y, x: sp.S.Zero
    fn["H^*"] = _define(REDUCED, fn)
    return fn, {"y": Y, "x": X}


def _d2_examples() -> list[tuple[Callable[..., Any], Callable[..., Any]]]:
    xx = sp.Symbol("x_")
    a, b, V = (sp.Lambda(xx, sp.Function(c)(xx)) for c in "abV")
    return [
        (lambda x, u: x + u, lambda x, u: (u + x) ** 2 / 2),
        (lambda x, u: a(x) + b(x) * u, lambda x, u: u**2 / 2 + V(x)),
    ]


def _d2_defect(named: sp.Basic) -> sp.Expr:
    """For f = x + u, g = (u + x)^2/2 and for f = a(x) + b(x) u, g = u^2/2 + V(x) (a, b, V
    undefined; n = m = 1): the number of examples in which the determinant of the named matrix
    (at u = u*(y, x)) differs from that of the true Jacobian in y of the displayed step."""
    total = sp.Integer(0)
    for f, g in _d2_examples():
        fn, values = _scalar_problem(f, g)
        jac = sp.Matrix([sp.diff(_value(STEP.rhs, values, fn), values["y"])])
        at = {**values, "u": fn["u^*"](values["y"], values["x"])}
        total += _nonzero(sp.Matrix([_value(named, at, fn)]).det() - jac.det())
    return total


@D2.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d2_printed_matrix() -> sp.Expr:
    r"""The printed matrix $\partial^2 H/\partial y\,\partial x$ at $u = u^*$ against the true
    Jacobian of the step in $y$: in $f = x + u$, $g = (u + x)^2/2$ the printed matrix is 1 while the
    step's Jacobian is 0 ($p_k = 0$ for every $y$); in $f = a(x) + b(x) u$, $g = u^2/2 + V(x)$ they
    differ by $b b' y$ (count of examples)."""
    return _d2_defect(PRINTED_MATRIX)


@D2.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d2_reduced_matrix() -> sp.Expr:
    """The same comparison with the displayed right side of the corrected step Jacobian, the mixed
    derivative of $H^*$ built from the displayed reduced Hamiltonian: equal in both examples."""
    return _d2_defect(STEP_JACOBIAN.rhs)


def _d2_general_n() -> tuple[sp.MatrixExpr, dict[str, sp.MatrixExpr], Alphabet, sp.Expr]:
    """On :func:`._general_n.quadratic_problem`: the Jacobian in y of the displayed step, the
    displayed matrices (the printed one at u = u*), the alphabet and the number of words of dH/du
    at u* (zero: u* is the stationary point)."""
    fn, sym, w = quadratic_problem()
    at = {"y": sym["y"], "x": sym["x"]}
    frozen = {**at, "u": fn["u^*"](sym["y"], sym["x"])}
    stationary = w.is_zero(w.nc(_value(sp.Derivative(_H(_y, _xs, _us), _us), frozen, fn)))
    jac = _grad(_value(STEP.rhs, at, fn), sym["y"])
    shown = {
        "corrected": _value(STEP_JACOBIAN.rhs, at, fn),
        "printed": _value(PRINTED_MATRIX, frozen, fn),
    }
    return jac, shown, w, stationary


@D2.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def d2_reduced_matrix_general_n() -> sp.Expr:
    r"""Every $n$ and $m$: $f = A x + B u$, $g = \frac12 x^T P x + x^T S u + \frac12 u^T R u$ with
    matrix symbols (the second-order Taylor polynomials of any problem at a point, which is all the
    Jacobians involve), $u^* = R^{-1} (B^T y - S^T x)$ checked to make $\partial H/\partial u$
    vanish: the Jacobian in $y$ of the displayed step (SymPy's matrix calculus), $A^T - S R^{-1}
    B^T$, equals the transpose (the index order) of the displayed mixed derivative of the displayed
    $H^*$ (words left after cancelling $R R^{-1}$)."""
    jac, shown, w, stationary = _d2_general_n()
    return stationary + w.is_zero(w.nc(jac - shown["corrected"].T))


@D2.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def d2_printed_matrix_general_n() -> sp.Expr:
    r"""The same problem: the printed $\partial^2 H/\partial y\,\partial x$ at fixed $u$ ($A$, or
    $A^T$ in the other index order) differs from the step's Jacobian by the word $S R^{-1} B^T$,
    i.e. $H_{xu} H_{uu}^{-1} H_{uy}$, for every $n$ and $m$ (fewest words left over both index
    orders)."""
    jac, shown, w, _stationary = _d2_general_n()
    return sp.Min(*(w.is_zero(w.nc(jac - m)) for m in (shown["printed"], shown["printed"].T)))


# the paper's sentences (the remark after the proof of the first proposition)

D2.sentence(
    r"Note that for the algorithm described by equation (eq8.3) to make sense we need to able to "
    r"compute $p_{k+1}$ from the given implicit form.",
    d2_printed_matrix,
    d2_reduced_matrix,
    d2_reduced_matrix_general_n,
    d2_printed_matrix_general_n,
)
D2.sentence(
    r"This follows if the $n \times n$ matrix with entries "
    r"$\frac{\partial ^2 H}{\partial y_i \partial x_j} (y,x,u)$ for $i,j = 1, \ldots, n,$ is "
    r"invertible at every $(y,x,u) \in \mathbb{R}^n \times \mathbb{R}^n \times \mathbb{R}^m$.",
    d2_printed_matrix,
    d2_reduced_matrix,
    d2_reduced_matrix_general_n,
    d2_printed_matrix_general_n,
)
D2.sentence(
    r"We need such a condition to be satisfied for any given algorithm.",
    kind="prose",
    reason="a general remark on implicit algorithms; the condition itself is the sentence above",
)
