r"""D3: the linearised extremal equations (paper, Section 2, corollary C:8.3).

Where: Section 2, the corollary after the first proposition: the differentials :math:`dp_k` and
:math:`dx_{k+1}` as linear functions of :math:`dx_k` and :math:`dp_{k+1}`.

Recorded outcome: holds after correction.  The second derivatives are those of the reduced
Hamiltonian :math:`H^*`, not of :math:`\hat H` at frozen :math:`u^*`, and the two lines use the
transposed mixed matrices.  Evidence: a symbolic family (:math:`f = a(x) + Bu`) and a nonlinear
float64 family (:mod:`._nonlinear_family`, solved with SciPy) against the Jacobians of the true
maps; independent of symrb.  For every :math:`n` and :math:`m`: the same comparison on the
quadratic problem of :func:`._general_n.quadratic_problem` in matrix symbols (second-order Taylor
polynomials with free blocks, which is all a linearisation at a point involves; see D2's module
for why this covers every smooth problem).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import sympy as sp

from derivations.claims.section2._general_n import quadratic_problem
from derivations.claims.section2._hamiltonians import (
    _H,
    REDUCED,
    _Hstar,
    _us,
    _with_hamiltonians,
    _xs,
    _y,
)
from derivations.claims.section2._indexed import _define, _dot, _grad, _nonzero, _value, _vec
from derivations.claims.section2._nonlinear_family import NonlinearFamily
from derivations.claims.section2.d02_implicit_step import STEP
from derivations.registry import Level, claim
from derivations.symbolic import eq, explicit, lhs_minus_rhs
from derivations.vocabulary import matrix, vector

D3 = claim(
    "D3",
    label="C:8.3",
    title="Linearised extremal equations",
    statement="The corollary after the discrete maximum principle: differentiating the extremal equations gives the differentials "
    "$dp_k$ and $dx_{k+1}$ as linear functions of $dx_k$ and $dp_{k+1}$.",
    printed="[[printed]], with second derivatives of $\\hat H$ at $(p_{k+1}, x_k, u^*_k)$.",
    corrected="[[corrected]] with the second derivatives of the reduced Hamiltonian [[reduced]]; "
    "the entry $(i, j)$ of $H^*_{xy}$ is the derivative in $x_i$ and $y_j$.",
    expected="holds after correction",
    headline="[[corrected]]",
    section="2",
    where="Section 2, the corollary (its only one): the differentials $dp_k$ and $dx_{k+1}$ of "
    "the extremal equations",
    note="The printed second derivatives are those of $\\hat H$ at frozen $u^*_k$, and both lines "
    "use the same mixed matrix. Corrected: the second derivatives are those of the reduced "
    "Hamiltonian $H^*$, and the two lines use the transposed mixed matrices $H^*_{xy}$ and "
    "$(H^*_{xy})^T$. (i) $u^*$ and $\\sigma$ depend on $(p_{k+1}, x_k)$; at frozen $u^*$, $\\hat "
    "H$ is linear in $p$, so the printed coefficient of $dp_{k+1}$ in $dx_{k+1}$ is always $0$, "
    "while it is $H^*_{yy} = BB^T$ in the family $f = a(x) + Bu$, $g = \\|u\\|^2/2 + V(x)$. (ii) "
    "For $n > 1$ the two lines need transposed mixed matrices; the printed form uses the same one "
    "(if the printed symbol is read as the mixed derivative contracted in the right slot, this "
    "second point is notation only). In the symbolic family $u^*$ does not depend on $x$, so "
    "there only the $H^*_{yy}$ block separates $H^*$ from frozen $\\hat H$; the float64 family "
    "with $u^*(x, p_{k+1})$ separates every block.",
)
_dxk, _dpk, _dx1, _dp1 = (vector(s) for s in ("dx_k", "dp_k", "dx_{k+1}", "dp_{k+1}"))
_R = {"xx": matrix("H^*_{xx}"), "xy": matrix("H^*_{xy}"), "yy": matrix("H^*_{yy}")}
_P = {"xx": matrix(r"\hat{H}_{xx}"), "xy": matrix(r"\hat{H}_{px}"), "yy": matrix(r"\hat{H}_{pp}")}
LINEARISED = D3.formula(
    "corrected",
    (
        eq(_dpk, _R["xx"] * _dxk + _R["xy"] * _dp1),
        eq(_dx1, _R["xy"].T * _dxk + _R["yy"] * _dp1),
    ),
)
LINEARISED_PRINTED = D3.formula(
    "printed",
    (
        eq(_dpk, _P["xx"] * _dxk + _P["xy"] * _dp1),
        eq(_dx1, _P["xy"] * _dxk + _P["yy"] * _dp1),
    ),
)
D3.formula("reduced", REDUCED)


def _linearisation_mismatch(
    formulas: tuple[sp.Eq, sp.Eq],
    names: dict[str, sp.MatrixSymbol],
    blocks: dict[str, sp.Matrix],
    true: dict[str, sp.Matrix],
    transpose: bool,
) -> list[sp.Matrix]:
    """lhs - rhs of the displayed linearisation with its matrices given by ``blocks`` (the mixed
    one transposed when ``transpose``: the other index convention) and the differentials by the
    true linear maps (x_k, p_{k+1}) -> (p_k, x_{k+1}), columns for the unit vectors."""
    dim = true["Pxx"].rows
    dxk = sp.eye(dim).row_join(sp.zeros(dim))
    dp1 = sp.zeros(dim).row_join(sp.eye(dim))
    env = {
        "dx_k": dxk,
        "dp_{k+1}": dp1,
        "dp_k": true["Pxx"].row_join(true["Pxy"]),
        "dx_{k+1}": true["Xx"].row_join(true["Xy"]),
        str(names["xx"].name): blocks["xx"],
        str(names["xy"].name): blocks["xy"].T if transpose else blocks["xy"],
        str(names["yy"].name): blocks["yy"],
    }
    return [explicit(lhs_minus_rhs(f), env) for f in formulas]


def _d3_family() -> tuple[dict[str, sp.Matrix], dict[str, sp.Matrix], dict[str, sp.Matrix]]:
    """f = a(x) + B u, g = |u|^2/2 + V(x), n = m = 2 (a, V undefined, B symbolic): the blocks of
    H* (from the displayed reduced Hamiltonian), of Hhat at frozen u*, and the Jacobians of the
    true maps p_k = dH/dx(y, x, u*(y, x)) (the displayed step) and x_{k+1} = f(x, u*)."""
    X, Y, U = _vec("x", 2), _vec("y", 2), _vec("u", 2)
    a = sp.Matrix([sp.Function(f"a{i + 1}")(*X) for i in range(2)])
    V = sp.Function("V")(*X)
    B = sp.Matrix(2, 2, sp.symbols("b11 b12 b21 b22", real=True))

    def at_x(e: Any, x: Any) -> Any:
        return e.xreplace(dict(zip(X, x, strict=True)))

    fn = _with_hamiltonians({
        "f": lambda x, u: at_x(a, x) + B * u,
        "g": lambda x, u: _dot(u, u) / 2 + at_x(V, x),
        "h": lambda u: sp.zeros(1, 1),
    })  # fmt: skip
    values = {"y": Y, "x": X, "u": U}
    dHdu = _value(sp.Derivative(_H(_y, _xs, _us), _us), values, fn)
    sol = sp.solve(list(dHdu), list(U), dict=True)[0]
    ustar = U.xreplace(sol)
    fn["u^*"] = lambda y, x: ustar.xreplace(dict(zip(Y, y, strict=True)))
    fn[r"\sigma"] = lambda y, x: sp.zeros(1, 1)
    fn["H^*"] = _define(REDUCED, fn)
    Hs = fn["H^*"](Y, X)
    reduced = {
        "xx": sp.hessian(Hs, X),
        "xy": sp.Matrix(2, 2, lambda i, j: sp.diff(Hs, X[i], Y[j])),
        "yy": sp.hessian(Hs, Y),
    }
    H = fn["H"](Y, X, U)
    sub = dict(zip(U, ustar, strict=True))
    frozen = {
        "xx": sp.hessian(H, X).xreplace(sub),
        "xy": sp.Matrix(2, 2, lambda i, j: sp.diff(H, X[i], Y[j])).xreplace(sub),
        "yy": sp.hessian(H, Y).xreplace(sub),
    }
    pk = _value(STEP.rhs, values, fn)
    x1 = fn["f"](X, ustar)
    true = {
        "Pxx": pk.jacobian(X),
        "Pxy": pk.jacobian(Y),
        "Xx": x1.jacobian(X),
        "Xy": x1.jacobian(Y),
    }
    return reduced, frozen, true


def _d3_symbolic_defect(formulas: tuple[sp.Eq, sp.Eq], names: dict[str, Any], kind: str) -> sp.Expr:
    """Mismatch count of the displayed linearisation in the symbolic family, minimised over the
    index conventions the formula's mixed symbol admits (one for the corrected form)."""
    reduced, frozen, true = _d3_family()
    blocks = reduced if kind == "reduced" else frozen
    options = (False,) if names is _R else (False, True)
    return sp.Min(*[
        sum((_nonzero(m) for m in _linearisation_mismatch(formulas, names, blocks, true, t)),
            sp.Integer(0))
        for t in options
    ])  # fmt: skip


@D3.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d3_corrected() -> sp.Expr:
    r"""$f = a(x) + B u$, $g = |u|^2/2 + V(x)$ ($a$, $V$ undefined, $n = m = 2$): the displayed
    corrected equations with the blocks of $H^*$ reproduce the Jacobians of the true maps $(x_k,
    p_{k+1}) \mapsto (p_k, x_{k+1})$ (count of mismatching entries)."""
    return _d3_symbolic_defect(LINEARISED, _R, "reduced")


@D3.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d3_printed_frozen_control() -> sp.Expr:
    r"""Same family: the printed equations with second derivatives of $\hat H$ at frozen $u^*$
    mismatch (the $dp_{k+1}$ coefficient of $dx_{k+1}$ is 0 instead of $B B^T$), for either index
    convention of the mixed matrix (smallest count of mismatching entries)."""
    return _d3_symbolic_defect(LINEARISED_PRINTED, _P, "frozen")


@D3.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d3_printed_same_matrix() -> sp.Expr:
    """Same family, printed equations with the blocks of $H^*$: one mixed matrix in both lines
    mismatches for either index convention (smallest count of mismatching entries)."""
    return _d3_symbolic_defect(LINEARISED_PRINTED, _P, "reduced")


@functools.cache
def _d3_general_data(kind: str) -> tuple[Any, dict[Any, Any], dict[str, Any]]:
    """On the quadratic problem in matrix symbols: the alphabet; the true differentials dp_k and
    dx_{k+1} (the Jacobians of the displayed step and of x_{k+1} = f(x, u*(y, x)) by SymPy's
    matrix calculus, applied to dx_k and dp_{k+1}); and the blocks xx, xy, yy of the displayed
    H* (kind "reduced") or of H at frozen u* (kind "frozen"), the displayed Derivative objects in
    x and y (computed once: SymPy's matrix calculus takes about a second)."""
    fn, sym, w = quadratic_problem()
    Y, X = sym["y"], sym["x"]
    at = {"y": Y, "x": X}
    us = fn["u^*"](Y, X)
    pk, x1 = _value(STEP.rhs, at, fn), fn["f"](X, us)
    true = {_dpk: _grad(pk, X) * _dxk + _grad(pk, Y) * _dp1,
            _dx1: _grad(x1, X) * _dxk + _grad(x1, Y) * _dp1}  # fmt: skip
    fun = _Hstar(_y, _xs) if kind == "reduced" else _H(_y, _xs, _us)
    vals = at if kind == "reduced" else {**at, "u": us}
    pairs = {"xx": (_xs, _xs), "xy": (_xs, _y), "yy": (_y, _y)}
    return w, true, {k: _value(sp.Derivative(fun, *v), vals, fn) for k, v in pairs.items()}


def _d3_general_n(formulas: tuple[sp.Eq, sp.Eq], names: dict[str, Any], kind: str) -> sp.Expr:
    """lhs - rhs of the displayed linearisation with the true differentials and the blocks of
    :func:`_d3_general_data`, fewest words left over the index orders the mixed symbol admits."""
    w, true, blocks = _d3_general_data(kind)
    options = (False,) if names is _R else (False, True)
    counts = []
    for t in options:
        sub = {names[k]: (b.T if t and k == "xy" else b) for k, b in blocks.items()}
        sub.update(true)
        counts.append(sum((w.is_zero(w.nc(lhs_minus_rhs(f).xreplace(sub))) for f in formulas),
                          sp.Integer(0)))  # fmt: skip
    return sp.Min(*counts)


@D3.check(Level.SYMBOLIC_GENERAL_N, form="corrected")
def d3_corrected_general_n() -> sp.Expr:
    r"""Every $n$ and $m$: $f = A x + B u$, $g = \frac12 x^T P x + x^T S u + \frac12 u^T R u$
    (matrix symbols, $P$ and $R$ symmetric, $R$ invertible): the displayed corrected equations with
    the blocks of $H^*$ ($H^*_{xx} = S R^{-1} S^T - P$, $H^*_{xy} = A^T - S R^{-1} B^T$, $H^*_{yy} =
    B R^{-1} B^T$) reproduce the differentials of the true maps $(x_k, p_{k+1}) \mapsto (p_k,
    x_{k+1})$ (words left)."""
    return _d3_general_n(LINEARISED, _R, "reduced")


@D3.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def d3_printed_general_n() -> sp.Expr:
    r"""The same problem: the printed equations with the second derivatives of $\hat H$ at frozen
    $u^*$ miss them for every $n$ and $m$ (its $dp_{k+1}$ coefficient in $dx_{k+1}$ is 0, not $B
    R^{-1} B^T$), for either index order of the mixed matrix (fewest words left)."""
    return _d3_general_n(LINEARISED_PRINTED, _P, "frozen")


@D3.check(Level.SYMBOLIC_GENERAL_N, form="printed")
def d3_printed_same_matrix_general_n() -> sp.Expr:
    """The same problem, printed equations with the blocks of $H^*$: one mixed matrix in both lines
    misses them for either index order (fewest words left; $A^T - S R^{-1} B^T$ is not symmetric).
    """
    return _d3_general_n(LINEARISED_PRINTED, _P, "reduced")


def _true_maps(J: np.ndarray, dim: int) -> dict[str, sp.Matrix]:
    """From the Jacobian of (x_k, p_k) -> (x_{k+1}, p_{k+1}) the Jacobians of (x_k, p_{k+1}) ->
    (p_k, x_{k+1}): dp_k = D^-1 (dp_{k+1} - C dx_k), dx_{k+1} = A dx_k + B dp_k."""
    A, B, C, D = J[:dim, :dim], J[:dim, dim:], J[dim:, :dim], J[dim:, dim:]
    Di = np.linalg.inv(D)
    maps = {"Pxx": -Di @ C, "Pxy": Di, "Xx": A - B @ Di @ C, "Xy": B @ Di}
    return {k: sp.Matrix(v) for k, v in maps.items()}


def _d3_float_defect(formulas: tuple[sp.Eq, sp.Eq], names: dict[str, Any], kind: str) -> float:
    """Largest entry of lhs - rhs of the displayed linearisation on the nonlinear float64 family
    (3 random families and points, n = 3, m = 2), with blocks of H* or of Hhat at frozen u*,
    minimised over the index conventions the formula's mixed symbol admits."""
    worst = 0.0
    for seed in range(3):
        fam = NonlinearFamily(3, 2, seed=seed)
        rng = np.random.default_rng(100 + seed)
        xk, pk = 0.5 * rng.standard_normal(3), 0.5 * rng.standard_normal(3)
        _, y, u = fam.advance(xk, pk)
        get = fam.reduced_hessian_blocks if kind == "reduced" else fam.frozen_hessian_blocks
        blocks = {k: sp.Matrix(v) for k, v in zip(("xx", "xy", "yy"), get(xk, y, u), strict=True)}
        true = _true_maps(fam.advance_jacobian(xk, pk), 3)
        options = (False,) if names is _R else (False, True)
        gaps = []
        for t in options:
            mats = _linearisation_mismatch(formulas, names, blocks, true, t)
            gaps.append(np.max([float(abs(v)) for m in mats for v in m]))
        worst = float(np.max([worst, np.min(gaps)]))
    return worst


@D3.check(Level.FLOAT64, tol=1e-11, form="corrected")
def d3_nonlinear_corrected() -> float:
    r"""$f = x + 0.3 \tanh(W x + B u + c)$, $g = |u|^2/2 + |x|^2/4$ ($u^*$ depends on $x$ and
    $p_{k+1}$; $n = 3$, $m = 2$, 3 random points): the displayed corrected equations with the blocks
    of $H^*$ (Schur complements) against the Jacobian of the implicit advance map from scipy root
    and implicit differentiation (largest entry of the mismatch; entries are of order 1)."""
    return _d3_float_defect(LINEARISED, _R, "reduced")


@D3.check(Level.FLOAT64, tol=1e-11, form="printed")
def d3_nonlinear_printed() -> float:
    r"""Same family: the printed equations with blocks of $\hat H$ at frozen $u^*$ miss that
    Jacobian for either index convention."""
    return _d3_float_defect(LINEARISED_PRINTED, _P, "frozen")


# the paper's sentences (the hypothesis before the corollary, and the corollary)

D3.sentence(
    r"We assume that both $u^*_k$ and $\sigma$ are determined uniquely by equations (eq8.6).",
    d3_corrected,
    d3_nonlinear_corrected,
)
D3.sentence(
    r"Also note that $u^*_k=u^*_k(p_{k+1},x_k)$, $\sigma=\sigma (p_{k+1},x_k)$.",
    d3_nonlinear_corrected,
    d3_printed_frozen_control,
    d3_nonlinear_printed,
    d3_printed_general_n,
)
D3.sentence(
    r"Using this hypothesis, we have the following consequence.",
    kind="prose",
    reason="announces the corollary",
)
D3.sentence(
    r"Corollary. Assume that the extremal equations (eq8.3) hold.",
    d3_corrected,
    d3_nonlinear_corrected,
    d3_corrected_general_n,
)
D3.sentence(
    r"Then $dp_k= \frac{\partial^2\hat{H}}{\partial x^2_k}(p_{k+1},x_k,u^*_k)dx_k+ "
    r"\frac{\partial^2\hat{H}}{\partial p_{k+1}\partial x_k} (p_{k+1},x_k,u^*_k)dp_{k+1}\,, "
    r"\quad dx_{k+1}= \frac{\partial^2\hat{H}}{\partial p_{k+1}\partial x_k} (p_{k+1},x_k,u^*_k) "
    r"dx_k+ \frac{\partial^2\hat{H}}{\partial p^2_{k+1}}(p_{k+1},x_k,u^*_k) dp_{k+1}\,.$",
    d3_corrected,
    d3_printed_frozen_control,
    d3_printed_same_matrix,
    d3_nonlinear_corrected,
    d3_nonlinear_printed,
    d3_corrected_general_n,
    d3_printed_general_n,
    d3_printed_same_matrix_general_n,
)
