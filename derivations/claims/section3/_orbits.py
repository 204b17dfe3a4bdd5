"""Adjoint orbits (Section 3.4, claims S13-S15): symbols, kernel arguments and the trace-word
tools shared by the claims.

The control system is :math:`\\dot x = [x, u]` on an adjoint orbit of a compact Lie algebra
(:math:`\\mathfrak{so}(n)`, :math:`\\mathfrak{su}(n)`), the cost :math:`\\int \tfrac12\\|u\\|^2 - V(x)\\,dt`
(plus a terminal cost :math:`\\sum_a\\phi(x^a_T)` in the learning version).  The paper's fixed element
:math:`n` is called :math:`N` here (``n`` is the matrix size).

How the checks work:

* **every n (noncommutative letters).**  Pairings :math:`\\langle a,b\rangle = -\tfrac12
  \\operatorname{tr}(ab)` of products of :math:`x, p, u, N, \\dots` are compared as trace words
  (:class:`~derivations.symbolic.Words`); a derivative is taken along a free direction :math:`d` as
  :math:`\tfrac{d}{d\\epsilon}` at :math:`\\epsilon = 0`, and a gradient :math:`G` is identified by
  :math:`dF[d] = \\langle G, d\rangle` for every :math:`d`.  Only cyclicity of the trace is used, so
  these identities hold for every multiple :math:`B = -c\\operatorname{tr}` of the trace form.  A
  potential :math:`V` whose gradient is :math:`V_x` enters through its linearisation
  :math:`\\langle V_x, y\rangle` (the first derivative is all Hamilton's equations use).
* **fixed n (coordinates).**  For so(3) with the pairing (in an orthonormal and in a
  non-orthogonal basis) and su(2) with the negative Killing form (computed from the structure
  constants), the maximum principle is written in coordinates with the costate as a covector and
  Hamilton's equations are taken literally.
* **float64.**  Public ``symrb`` functions against independent NumPy formulas, complex-step
  derivatives, Flaschka's Toda equations, central differences of the cost and the exact so(3)
  solution of the double bracket flow.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from derivations.claims.section3._display import _Norm, _SampleSumMatrix, _SampleSumScalar
from derivations.symbolic import Bracket, Pair, Words
from derivations.vocabulary import Arg, matrix

x, p, u, N, d = (matrix(s) for s in ("x", "p", "u", "N", "d"))
V_x = matrix("V_x")
XDOT, PDOT = matrix(r"\dot{x}"), matrix(r"\dot{p}")
t, t_f, T = sp.symbols("t t_f T", positive=True)
ARG_X = Arg("x", "(..., n, n)", "state on an adjoint orbit (skew for so(n))")
ARG_P = Arg("p", "(..., n, n)", "costate, identified with the algebra through the pairing")
ARG_N = Arg("N", "(..., n, n)", "the fixed element n of Brockett's potential")
ARG_U = Arg("u", "(..., n, n)", "the control (shared by all samples in the learning version)")


def linear_potential(y: sp.Basic) -> sp.Basic:
    """The linearisation <V_x, y> of a potential with gradient V_x (first derivatives only)."""
    return Pair(V_x, y)


def brockett(y: sp.Basic) -> sp.Basic:
    """Brockett's potential -1/2 ||[y, N]||^2 at y: the right side of S14's displayed V (S13's
    optimal Hamiltonian kernel and S15's cost use it too)."""
    return -(_Norm(Bracket(y, N)) ** 2) / 2


V = sp.Function("V")
PHI = sp.Function("phi")


def plain(
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


EPS = sp.Symbol("epsilon")


def trace_poly(
    expr: sp.Basic, w: Words, potential: Callable[[sp.Basic], sp.Basic] | None = None
) -> sp.Expr:
    """A scalar sum of pairings as the expanded noncommutative polynomial under one trace."""
    e = plain(expr, potential)
    return sp.Integer(0) if e == 0 else sp.expand(w.trace_argument(e))


def directional(
    expr: sp.Basic,
    moves: dict[sp.MatrixSymbol, sp.MatrixExpr],
    w: Words,
    potential: Callable[[sp.Basic], sp.Basic] | None = None,
) -> sp.Expr:
    """d/de expr(y + e dy) at e = 0 for the moves {y: dy}, as a trace polynomial (expanded before
    differentiating: SymPy's derivative of a noncommutative power is wrong)."""
    moved = expr.xreplace({y: y + EPS * dy for y, dy in moves.items()})
    return sp.diff(trace_poly(moved, w, potential), EPS).subs(EPS, 0)


def pair_poly(a: sp.MatrixExpr, b: sp.MatrixExpr, w: Words) -> sp.Expr:
    return trace_poly(Pair(a, b), w)


def of_sample(expr: sp.Basic, index: str, k: int) -> sp.Basic:
    """``expr`` with every matrix letter of sample ``index`` (``x^a``, ``p^a_T``, ...) replaced
    by that of sample ``k`` (``x^1``, ``p^1_T``, ...)."""
    reps = {}
    for m in expr.atoms(sp.MatrixSymbol):
        name = str(m.name)
        if f"^{index}" in name:
            reps[m] = sp.MatrixSymbol(name.replace(f"^{index}", f"^{k}"), *m.shape)
    return expr.xreplace(reps)


def samples(expr: sp.Basic, count: int) -> sp.Basic:
    """Every sum over samples in ``expr`` written out for samples 1..count."""

    def write_out(s: sp.Basic) -> sp.Basic:
        body, index = s.args
        terms = [of_sample(body, str(index), k) for k in range(1, count + 1)]
        return sp.MatAdd(*terms) if isinstance(s, sp.MatrixExpr) else sp.Add(*terms)

    return expr.replace(lambda e: isinstance(e, (_SampleSumMatrix, _SampleSumScalar)), write_out)


def np_comm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a @ b - b @ a


def np_pair(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return -0.5 * np.trace(a @ b, axis1=-2, axis2=-1)


def np_norm2(a: np.ndarray) -> np.ndarray:
    return np_pair(a, a)


def so_basis(k: int) -> list[sp.Matrix]:
    """The basis E_ij = e_i e_j^T - e_j e_i^T (i < j) of so(k)."""
    out = []
    for i, j in itertools.combinations(range(k), 2):
        e = sp.zeros(k, k)
        e[i, j], e[j, i] = 1, -1
        out.append(e)
    return out
