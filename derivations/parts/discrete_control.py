r"""Discrete optimal control and deep learning (paper, Section 2, first part): claims D1-D6.

Conventions (stated on the book pages): :math:`H(y,x,u) = \langle y, f(x,u)\rangle - g(x,u)` as
printed, with :math:`y` the costate :math:`p_{k+1}`; the problems are minimisations, so the augmented
functionals whose critical points give the extremal equations are *minus* the cost plus multiplier
terms; :math:`H^*(y,x) = \hat H(y,x,u^*(y,x),\sigma(y,x))` is the reduced Hamiltonian and
:math:`(H^*_{xy})_{ij} = \partial^2H^*/\partial x_i\partial y_j`.

The displayed formulas are SymPy objects in the paper's indexed notation (:math:`x_k`,
:math:`p^a_{k+1}`, sums over steps and samples, undefined :math:`f, g, h, \phi`); the evidence
evaluates those same objects with :func:`_value` on explicit vectors and functions, so a summation
range, an index or a sign shown in the book is the one that was checked.

Emitted to ``symrb/_generated/discrete_control.py`` (claim D6): the ResNet steps
:math:`x_{k+1} = x_k + \sigma(K_kx_k+\beta_k)` (residual) and :math:`\sigma(K_kx_k+\beta_k)` (plain)
and their adjoint steps (the costate :math:`p_k = \partial H/\partial x` and
:math:`\partial H/\partial K`, :math:`\partial H/\partial\beta`), for :math:`\sigma = \tanh` and the
logistic function.  One function, :func:`layer`, builds the displayed generic layer and the kernels.
"""

from __future__ import annotations

import functools
import itertools
import operator
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction

from derivations.registry import Level, claim
from derivations.symbolic import eq, explicit, lhs_minus_rhs, residual
from derivations.vocabulary import Arg, Kernel, entrywise, matrix, n, vector

# =============================================================================================
# display objects for the indexed notation and their evaluation (private helpers; _Dot, _Sample,
# _Steps and _value would serve other discrete parts too and could move to derivations.symbolic)


class _Dot(sp.Expr):
    """The dot product <a, b> = a^T b of two vectors of R^p (printed with angle brackets)."""

    is_commutative = True

    def __new__(cls, a: sp.Basic, b: sp.Basic) -> _Dot:
        return super().__new__(cls, sp.sympify(a), sp.sympify(b))

    def _latex(self, printer: Any) -> str:
        a, b = (printer._print(x) for x in self.args)
        return rf"\left\langle {a}, {b}\right\rangle"


class _Sample(sp.Indexed):
    """x^a_k: a quantity of sample a at step k (an Indexed object printed with a superscript)."""

    def _latex(self, printer: Any) -> str:
        base, a, k = self.args
        return f"{printer._print(base.label)}^{{{printer._print(a)}}}_{{{printer._print(k)}}}"


class _Steps(sp.Basic):
    """Relations that hold for every integer k with lo <= k <= hi (printed with the range)."""

    def __new__(cls, relations: Sequence[sp.Eq], k: sp.Symbol, lo: Any, hi: Any) -> _Steps:
        return super().__new__(cls, sp.Tuple(*relations), k, sp.sympify(lo), sp.sympify(hi))

    @property
    def relations(self) -> tuple[sp.Eq, ...]:
        return tuple(self.args[0])

    def steps(self, N: int) -> range:
        """The steps k of the displayed range for a horizon of N steps."""
        _rels, _k, lo, hi = self.args
        return range(int(lo.subs(_N, N)), int(hi.subs(_N, N)) + 1)

    def at(self, k: int, which: int = 0, **indices: int) -> tuple[sp.Basic, sp.Basic]:
        """(lhs, rhs) of relation ``which`` at step k (and e.g. sample ``a=1``)."""
        return _instance(self.relations[which], {self.args[1]: k, **_named(indices)})

    def _latex(self, printer: Any) -> str:
        rels, k, lo, hi = self.args
        body = r",\quad ".join(printer._print(r) for r in rels)
        rng = f"{printer._print(lo)} \\le {printer._print(k)} \\le {printer._print(hi)}"
        return rf"{body}\quad ({rng})"


def _named(indices: dict[str, int]) -> dict[sp.Symbol, int]:
    return {_INDEX[name]: value for name, value in indices.items()}


def _instance(relation: sp.Eq, sub: dict[sp.Symbol, int]) -> tuple[sp.Basic, sp.Basic]:
    """(lhs, rhs) of a displayed relation with its free indices replaced by integers (the sides
    are substituted separately: rebuilding an ``Eq`` could evaluate it)."""
    return relation.lhs.xreplace(sub), relation.rhs.xreplace(sub)


def _key(e: sp.Basic) -> str | tuple[Any, ...]:
    if isinstance(e, sp.Indexed):
        return (str(e.base.label), *(int(i) for i in e.indices))
    return str(e.name)


def _indexed_key(
    e: sp.Indexed, values: dict[Any, Any], functions: dict[str, Any]
) -> tuple[Any, ...]:
    """The key of an indexed symbol, its indices evaluated (so x_N and p_{N+1} take N from the
    values)."""
    return (str(e.base.label), *(int(_value(i, values, functions)) for i in e.indices))


def _add(a: Any, b: Any) -> Any:
    """a + b, where a scalar zero (the right side of a displayed ``= 0``) adds to a matrix."""
    if isinstance(a, sp.MatrixBase) != isinstance(b, sp.MatrixBase):
        zero, mat = (b, a) if isinstance(a, sp.MatrixBase) else (a, b)
        if zero != 0:
            raise TypeError(f"cannot add the scalar {zero} to a matrix")
        return mat
    return a + b


def _minus(a: Any, b: Any) -> Any:
    """a - b for the two evaluated sides of a displayed relation."""
    return _add(a, -b)


def _dot(a: Any, b: Any) -> sp.Expr:
    if isinstance(a, sp.MatrixBase):
        return (a.T * b)[0, 0]
    return a * b


def _fresh(point: Any, tag: int) -> Any:
    if isinstance(point, sp.MatrixBase):
        return sp.Matrix(point.rows, 1, [sp.Dummy(f"d{tag}_{i}") for i in range(point.rows)])
    return sp.Dummy(f"d{tag}")


def _grad(value: Any, var: Any) -> Any:
    """Derivative of a scalar (gradient), vector (Jacobian) or scalar-variable expression."""
    if not isinstance(var, sp.MatrixBase):
        return value.diff(var)
    if isinstance(value, sp.MatrixBase):
        return value.jacobian(var)
    return sp.Matrix([sp.diff(value, v) for v in var])


def _value(e: Any, values: dict[Any, Any], functions: dict[str, Callable[..., Any]]) -> Any:
    """Evaluate a displayed formula on explicit data.

    ``values`` maps a symbol's name, or ``(name, *indices)`` for an indexed symbol such as
    :math:`x_2` or :math:`p^1_2`, to a SymPy scalar or column vector; ``functions`` maps the name
    of an undefined function (``f``, ``H``, ``\\phi``, ...) to a callable on such values.  Sums are
    expanded over their (evaluated) limits, ``_Dot`` is the dot product, a ``Derivative`` is the
    gradient (Jacobian) in its variables at their values, ``Subs`` evaluates at the given point,
    and matrix expressions in matrix symbols go to :func:`~derivations.symbolic.explicit`.
    """
    if isinstance(e, sp.Indexed):
        return values[_indexed_key(e, values, functions)]
    if isinstance(e, sp.Symbol):
        return values[_key(e)]
    if isinstance(e, sp.Number):
        return e
    if isinstance(e, _Dot):
        return _dot(*(_value(x, values, functions) for x in e.args))
    if isinstance(e, sp.Sum):
        term, *limits = e.args
        (k, lo, hi), rest = limits[0], limits[1:]
        inner = sp.Sum(term, *rest) if rest else term
        lo, hi = (int(_value(x, values, functions)) for x in (lo, hi))
        parts = [
            _value(inner.xreplace({k: sp.Integer(j)}), values, functions) for j in range(lo, hi + 1)
        ]
        return functools.reduce(_add, parts)
    if isinstance(e, sp.Derivative):
        return _derivative(e, values, functions)
    if isinstance(e, sp.Subs):
        inner, variables, points = e.args
        at = {
            _key(v): _value(pt, values, functions) for v, pt in zip(variables, points, strict=True)
        }
        return _value(inner, {**values, **at}, functions)
    if isinstance(e, AppliedUndef):
        return functions[e.func.__name__](*(_value(x, values, functions) for x in e.args))
    if isinstance(e, sp.MatrixExpr):
        return explicit(e, {k: v for k, v in values.items() if isinstance(k, str)})
    args = [_value(x, values, functions) for x in e.args]
    if isinstance(e, sp.Add):
        return functools.reduce(_add, args)
    if isinstance(e, sp.Mul):
        return functools.reduce(operator.mul, args)
    if isinstance(e, sp.Pow):
        return args[0] ** args[1]
    raise TypeError(f"_value: no rule for {type(e).__name__} ({e})")


def _hider() -> tuple[Callable[[Any], Any], dict[sp.Basic, sp.Basic]]:
    """A function that replaces compound values (entrywise in matrices) by dummy symbols, and the
    dict it fills (value -> dummy), so that a derivative does not expand constants."""
    hidden: dict[sp.Basic, sp.Basic] = {}

    def hide(v: Any) -> Any:
        if isinstance(v, sp.MatrixBase):
            return v.applyfunc(hide)
        if isinstance(v, sp.Basic) and not v.is_Atom:
            return hidden.setdefault(v, sp.Dummy(f"c{len(hidden)}"))
        return v

    return hide, hidden


def _derivative(e: sp.Derivative, values: dict[Any, Any], functions: dict[str, Any]) -> Any:
    """d/dv_m ... d/dv_1 of the inner expression at the values of v_1, ..., v_m: each variable is
    replaced by fresh symbols (all its occurrences: a partial derivative), the result is
    differentiated in turn and the fresh symbols are replaced by the variable's value."""
    fresh: dict[Any, Any] = {}
    order = []
    for var, count in e.variable_count:
        key = _indexed_key(var, values, functions) if isinstance(var, sp.Indexed) else _key(var)
        if key not in fresh:
            fresh[key] = _fresh(values[key], len(fresh))
        order += [key] * int(count)
    # the other values are constants of a partial derivative: hide large ones behind symbols
    hide, hidden = _hider()
    held = {k: hide(v) for k, v in values.items() if k not in fresh}
    result = _value(e.expr, {**held, **fresh}, functions)
    for key in order:
        result = _grad(result, fresh[key])
    result = result.xreplace({d: v for v, d in hidden.items()}) if hidden else result
    back: dict[sp.Basic, sp.Basic] = {}
    for key, d in fresh.items():
        point = values[key]
        back.update(zip(d, point, strict=True) if isinstance(d, sp.MatrixBase) else [(d, point)])
    if all(isinstance(v, sp.Symbol) for v in back.values()) or not result.has(sp.Derivative):
        return result.xreplace(back)
    return result.subs(back, simultaneous=True)


def _define(
    formula: sp.Eq, functions: dict[str, Any], constants: dict[Any, Any] | None = None
) -> Callable[..., Any]:
    """The function defined by a displayed formula ``F(a, b, ...) = rhs`` as a callable."""
    params = [_key(a) for a in formula.lhs.args]

    def fn(*args: Any) -> Any:
        return _value(
            formula.rhs, {**(constants or {}), **dict(zip(params, args, strict=True))}, functions
        )

    return fn


def _substituted(values: dict[Any, Any], sub: dict[sp.Basic, sp.Basic]) -> dict[Any, Any]:
    """The values with ``sub`` applied to every SymPy scalar and matrix."""
    return {k: (v.xreplace(sub) if hasattr(v, "xreplace") else v) for k, v in values.items()}


def _vec(name: str, dim: int) -> sp.Matrix:
    return sp.Matrix([sp.Symbol(f"{name}_{i + 1}", real=True) for i in range(dim)])


def _generic(nx: int, nu: int, nl: int) -> dict[str, Callable[..., Any]]:
    """Undefined smooth f: R^nx x R^nu -> R^nx, g: R^nx x R^nu -> R, h: R^nu -> R^nl and
    phi: R^nx -> R, as callables on explicit vectors."""
    X, U = _vec("X", nx), _vec("U", nu)
    F = sp.Matrix([sp.Function(f"f{i + 1}")(*X, *U) for i in range(nx)])
    G = sp.Function("g")(*X, *U)
    Hc = sp.Matrix([sp.Function(f"h{i + 1}")(*U) for i in range(nl)])
    Phi = sp.Function("phi")(*X)

    def at(expr: Any, x: Any = None, u: Any = None) -> Any:
        sub = dict(zip(X, x, strict=True)) if x is not None else {}
        sub.update(zip(U, u, strict=True) if u is not None else {})
        return expr.xreplace(sub)

    return {
        "f": lambda x, u: at(F, x, u),
        "g": lambda x, u: at(G, x, u),
        "h": lambda u: at(Hc, u=u),
        r"\phi": lambda x: at(Phi, x),
    }


def _with_hamiltonians(functions: dict[str, Any]) -> dict[str, Any]:
    """Add H and Hhat, defined by the displayed formulas, to f, g, h."""
    functions["H"] = _define(H_DEF, functions)
    functions[r"\hat{H}"] = _define(HHAT_DEF, functions)
    return functions


def _coverage_defect(
    V: sp.Expr, values: dict[Any, Any], fixed: set[Any], covered: list[Any]
) -> int:
    """How far the variables compared with a displayed equation are from being the variables of V
    (those it depends on, minus the fixed data), each once."""
    variables = {
        key
        for key, val in values.items()
        if isinstance(key, tuple) and key not in fixed and any(V.has(s) for s in val)
    }
    return len(variables.symmetric_difference(covered)) + len(covered) - len(set(covered))


def _nonzero(expr: Any) -> int:
    """Number of entries of ``expr`` that do not expand to 0.

    The identities checked here are polynomial in the values of undefined functions and their
    derivatives (f, g, sigma, sigma', ...) at canonical arguments, so expansion decides them, and
    a false identity is reported at once (``simplify`` on a large non-zero expression can take
    minutes, which would hide a wrong kernel behind a time-out)."""
    items = list(expr) if isinstance(expr, sp.MatrixBase) else [expr]
    return sum(1 for e in items if sp.expand(e) != 0)


def _least_squares_residual(equations: list[sp.Expr], unknowns: list[sp.Symbol]) -> sp.Expr:
    """|A z - b|^2 at the least-squares solution z of the linear system A z = b (exact): zero
    exactly when the equations have a solution."""
    A, b = sp.linear_eq_to_matrix([sp.expand(e) for e in equations], unknowns)
    r = A * (A.pinv() * b) - b
    return sp.nsimplify((r.T * r)[0, 0])


# =============================================================================================
# the notation shared by the claims

_k, _N, _a, _M = sp.symbols("k N a M", integer=True)
_INDEX = {"k": _k, "a": _a}
# k + 1, N - 1, N + 1 unevaluated, so that they print in this order (substituting k or N evaluates)
_k1, _Nm1, _N1 = (sp.Add(s, c, evaluate=False) for s, c in ((_k, 1), (_N, -1), (_N, 1)))


def _plus(*terms: sp.Expr) -> sp.Expr:
    """A sum printed in the order written."""
    return sp.Add(*terms, evaluate=False)


_x, _u, _p, _sig = (sp.IndexedBase(s) for s in ("x", "u", "p", r"\sigma"))
_f, _g, _h, _phi = (sp.Function(s) for s in ("f", "g", "h", r"\phi"))
_H, _Hhat, _Hstar, _ustar = (sp.Function(s) for s in ("H", r"\hat{H}", "H^*", "u^*"))
_sigma_fn = sp.Function(r"\sigma")
_y, _xs, _us, _sigma1 = sp.symbols("y x u sigma")
_C, _V = sp.symbols("C V")


def _xa(a: Any, k: Any) -> _Sample:
    return _Sample(_x, a, k)


def _pa(a: Any, k: Any) -> _Sample:
    return _Sample(_p, a, k)


#: H(y, x, u) = <y, f(x, u)> - g(x, u) (eq8.4) and Hhat = H + <sigma, h(u)> (eq8.5).
H_DEF = eq(_H(_y, _xs, _us), _plus(_Dot(_y, _f(_xs, _us)), -_g(_xs, _us)))
HHAT_DEF = eq(_Hhat(_y, _xs, _us, _sigma1), _H(_y, _xs, _us) + _Dot(_sigma1, _h(_us)))
#: the reduced Hamiltonian
REDUCED = eq(_Hstar(_y, _xs), _Hhat(_y, _xs, _ustar(_y, _xs), _sigma_fn(_y, _xs)))

# =============================================================================================
# D1: the discrete maximum principle (fixed endpoints)

D1 = claim(
    "D1",
    label="prob8.1, gendiscprop, eq8.3-eq8.6",
    title="Discrete maximum principle (fixed endpoints, control constraint)",
    statement="The discrete maximum principle (the first proposition of Section 2): a solution of the problem of minimising [[cost]] subject to "
    "[[dynamics]], with $x_0$ and $x_N$ given, and [[constraint]] satisfies the extremal equations "
    "of [[H]] and [[Hhat]], the critical points of an augmented functional $V$.",
    printed="The costate equation is stated for every step up to $N$, [[costate_printed]], with "
    "[[terminal_printed]]; the proof's functional has one multiplier for all steps, "
    "[[V_printed]], and the proof rewrites it as [[rewrite_printed]].",
    corrected="[[state]]; [[costate]] only (the equation at step 0 merely defines $p_0$, and $p_N$ "
    "is a free unknown fixed by the endpoint $x_N$); [[stationary]] with one multiplier $\\sigma_k$ "
    "per step. These are exactly the critical points of [[V]], which equals [[rewrite]].",
    expected="holds after correction",
    section="2",
    where="Section 2, the first definition (the problem with fixed endpoints $x_0$, $x_N$ and the "
    "constraint $h(u_k) = 0$) and the first proposition (the extremal equations with $H = "
    "\\langle p_{k+1}, f(x_k, u_k)\\rangle - g(x_k, u_k)$ and the multiplier $\\sigma$), with its "
    "proof",
    note="The costate equation is stated up to $k = N$ and the proof uses one multiplier "
    "$\\sigma$ for all steps. Corrected: the costate equation holds for $1 \\le k \\le N-1$ only, "
    "$p_N$ is a free unknown, and there is one multiplier $\\sigma_k$ per step. The structure of "
    "the principle is right, but three details are not. (i) The costate equation at $k = N$ with "
    "$p_{N+1} = 0$ would force $p_N = -\\partial g/\\partial x(x_N, u_N)$ for a phantom control "
    "$u_N$; for a fixed endpoint $p_N$ is free (exact example $f = x + u$, $g = u^2/2$, $x_0 = "
    "0$, $x_2 = 1$: $p_2 = 1/2$ while the printed equation gives $0$). (ii) The proof's $V$ needs "
    "one multiplier per step (the proposition's $\\sigma = \\sigma(p_{k+1}, x_k)$ already allows "
    "that; $V$ does not): in an exact example the minimiser has $\\sigma_0 = -3/7$, $\\sigma_1 = "
    "-1/7$, and with one shared $\\sigma$ the stationarity equations at the minimiser have no "
    "solution. (iii) The proof's rewriting with the sum up to $N$ adds $\\hat H(0, x_N, u_N, "
    "\\sigma) = -g(x_N, u_N) + \\langle \\sigma, h(u_N)\\rangle$.",
)
COST = D1.formula("cost", eq(_C, sp.Sum(_g(_x[_k], _u[_k]), (_k, 0, _Nm1))))
DYNAMICS = D1.formula("dynamics", _Steps([eq(_x[_k1], _f(_x[_k], _u[_k]))], _k, 0, _Nm1))
CONSTRAINT = D1.formula("constraint", _Steps([eq(_h(_u[_k]), 0)], _k, 0, _Nm1))
D1.formula("H", H_DEF)
D1.formula("Hhat", HHAT_DEF)
_H_k = _H(_p[_k1], _x[_k], _u[_k])
STATE = D1.formula("state", _Steps([eq(_x[_k1], sp.Derivative(_H_k, _p[_k1]))], _k, 0, _Nm1))
_COSTATE_EQ = eq(_p[_k], sp.Derivative(_H_k, _x[_k]))
COSTATE = D1.formula("costate", _Steps([_COSTATE_EQ], _k, 1, _Nm1))
COSTATE_PRINTED = D1.formula("costate_printed", _Steps([_COSTATE_EQ], _k, 0, _N))
TERMINAL_PRINTED = D1.formula("terminal_printed", eq(_p[_N1], 0))
STATIONARY = D1.formula(
    "stationary",
    _Steps([eq(sp.Derivative(_Hhat(_p[_k1], _x[_k], _u[_k], _sig[_k]), _u[_k]), 0)], _k, 0, _Nm1),
)


def _functional(multiplier: sp.Basic) -> sp.Sum:
    term = _plus(
        _Dot(_p[_k1], _plus(_f(_x[_k], _u[_k]), -_x[_k1])),
        _Dot(multiplier, _h(_u[_k])),
        -_g(_x[_k], _u[_k]),
    )
    return sp.Sum(term, (_k, 0, _Nm1))


V_DEF = D1.formula("V", eq(_V, _functional(_sig[_k])))
V_PRINTED = D1.formula("V_printed", eq(_V, _functional(_sigma1)))


def _rewrite(multiplier: sp.Basic, last: sp.Expr) -> sp.Expr:
    term = _plus(-_Dot(_p[_k], _x[_k]), _Hhat(_p[_k1], _x[_k], _u[_k], multiplier))
    return _plus(_Dot(_p[0], _x[0]), sp.Sum(term, (_k, 0, last)))


REWRITE = D1.formula("rewrite", eq(_V, _plus(_rewrite(_sig[_k], _Nm1), -_Dot(_p[_N], _x[_N]))))
REWRITE_PRINTED = D1.formula("rewrite_printed", eq(_V, _rewrite(_sigma1, _N)))


def _d1_variables(N: int, nx: int, nu: int, nl: int, phantom: bool = False) -> dict[Any, Any]:
    """Symbolic vectors x_0..x_N, u_k, p_0..p_{N+1}, sigma_k and one sigma (u_N with phantom)."""
    values: dict[Any, Any] = {"N": N, "sigma": _vec("s", nl)}
    for k in range(N + 2):
        values[("p", k)] = _vec(f"p{k}", nx)
    for k in range(N + 1):
        values[("x", k)] = _vec(f"x{k}", nx)
    for k in range(N + 1 if phantom else N):
        values[("u", k)] = _vec(f"u{k}", nu)
        values[(r"\sigma", k)] = _vec(f"s{k}", nl)
    return values


@D1.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d1_stationarity() -> sp.Expr:
    """The derivatives of the displayed V (one multiplier per step, x_0 and x_N fixed) in p_{k+1},
    x_k, u_k and sigma_k are the displayed state, costate, stationarity and constraint equations
    over their displayed ranges, and these cover every variable of V once (undefined f, g, h;
    n = m = 2, l = 1, N = 3)."""
    N = 3
    values = _d1_variables(N, 2, 2, 1)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    V = _value(V_DEF.rhs, values, fn)
    total = sp.Integer(0)
    covered = []
    # dV/dvar is rhs - lhs of "x_{k+1} = dH/dp" and lhs - rhs of "dHhat/du = 0"
    for steps, var, sign in ((STATE, _p[_k + 1], -1), (COSTATE, _x[_k], -1),
                             (STATIONARY, _u[_k], 1), (CONSTRAINT, _sig[_k], 1)):  # fmt: skip
        for k in steps.steps(N):
            lhs, rhs = steps.at(k)
            key = _key(var.xreplace({_k: k}))
            covered.append(key)
            side = _minus(_value(lhs, values, fn), _value(rhs, values, fn))
            total += _nonzero(_minus(_grad(V, values[key]), sign * side))
    fixed = {("x", 0), ("x", N)}
    total += _coverage_defect(V, values, fixed, covered)
    return total


def _d1_costate_range_defect(costate: _Steps) -> sp.Expr:
    """Minimise u_0^2/2 + u_1^2/2 with x_{k+1} = x_k + u_k, x_0 = 0, x_2 = 1 (n = m = 1); take
    p_1, p_2 from the displayed stationarity conditions at the minimiser and p_3 from the printed
    terminal convention; return sum |lhs - rhs| of the costate equation over its displayed steps
    k >= 1 (p_0 does not occur in V: the equation at k = 0 defines it)."""
    N, v, uN = 2, sp.Symbol("v"), sp.Symbol("u_N")
    fn = _with_hamiltonians(
        {"f": lambda x, u: x + u, "g": lambda x, u: u[0] ** 2 / 2, "h": lambda u: sp.zeros(1, 1)}
    )
    values: dict[Any, Any] = {"N": N, ("x", 0): sp.Matrix([0])}
    values.update(
        {("u", 0): sp.Matrix([v]), ("u", 1): sp.Matrix([1 - v]), ("u", N): sp.Matrix([uN])}
    )
    for k in DYNAMICS.steps(N):
        lhs, rhs = DYNAMICS.at(k)
        values[_key(lhs)] = _value(rhs, values, fn)
    best = sp.solve(sp.diff(_value(COST.rhs, values, fn), v), v)[0]
    values = _substituted(values, {v: best})
    ps = sp.symbols("P1:3")
    values.update({("p", k + 1): sp.Matrix([ps[k]]) for k in range(N)})
    values.update({(r"\sigma", k): sp.zeros(1, 1) for k in range(N)})
    eqs = []
    for k in STATIONARY.steps(N):
        lhs, rhs = STATIONARY.at(k)
        eqs += list(_value(lhs, values, fn) - sp.Matrix([_value(rhs, values, fn)]))
    sol = sp.solve(eqs, ps, dict=True)[0]
    values.update({("p", k + 1): sp.Matrix([sol[ps[k]]]) for k in range(N)})
    lhs, rhs = _instance(TERMINAL_PRINTED, {_N: N})
    values[_key(lhs)] = sp.Matrix([_value(rhs, values, fn)])
    total = sp.Integer(0)
    for k in costate.steps(N):
        if k >= 1:
            lhs, rhs = costate.at(k)
            total += sum(abs(e) for e in _value(lhs, values, fn) - _value(rhs, values, fn))
    return sp.nsimplify(total)


@D1.check(Level.EXACT_RATIONAL, form="printed")
def d1_printed_costate_at_N() -> sp.Expr:
    """f = x + u, g = u^2/2, x_0 = 0, x_2 = 1 (n = m = 1): at the exact minimiser, with p_1, p_2
    from the stationarity conditions, the printed costate equation over its range up to N (with
    p_3 = 0 and a phantom u_2) is off by |p_2 - dH/dx(0, x_2, u_2)| = 1/2."""
    return _d1_costate_range_defect(COSTATE_PRINTED)


@D1.check(Level.EXACT_RATIONAL, form="corrected")
def d1_corrected_costate_range() -> sp.Expr:
    """The same computation with the corrected range 1 <= k <= N - 1: the costate equation holds
    at the minimiser."""
    return _d1_costate_range_defect(COSTATE)


def _d1_multiplier_defect(functional: sp.Eq) -> sp.Expr:
    """f = x + u_1, g = (u_1^2 + (u_2 - x)^2)/2, h = u_1 - u_2, N = 2, x_0 = 0, x_2 = 1 (n = 1,
    m = 2, l = 1).  At the exact minimiser (from the displayed cost, dynamics and constraint), the
    derivatives of the given V in x_1, u_0, u_1 are linear in the costates and multipliers;
    returns the least-squares residual of that linear system (0 exactly when multipliers exist)."""
    N = 2
    fn = _with_hamiltonians({
        "f": lambda x, u: x + sp.Matrix([u[0]]),
        "g": lambda x, u: (u[0] ** 2 + (u[1] - x[0]) ** 2) / 2,
        "h": lambda u: sp.Matrix([u[0] - u[1]]),
    })  # fmt: skip
    values = _d1_variables(N, 1, 2, 1)
    values[("x", 0)], values[("x", 2)] = sp.Matrix([0]), sp.Matrix([1])
    # the minimiser: u_k on h(u_k) = 0, v_0 + v_1 fixed by x_2 = 1
    v = sp.Symbol("v")
    point = dict(values)
    for k, vk in enumerate((v, 1 - v)):
        w = sp.Symbol("w")
        point[("u", k)] = sp.Matrix([vk, w])
        lhs, _rhs = CONSTRAINT.at(k)
        point[("u", k)] = point[("u", k)].subs(w, sp.solve(_value(lhs, point, fn)[0], w)[0])
    point[("x", 1)] = _value(DYNAMICS.at(0)[1], point, fn)
    best = sp.solve(sp.diff(_value(COST.rhs, point, fn), v), v)[0]
    at_min = {values[key][i]: point[key][i].subs(v, best)
              for key in (("x", 1), ("u", 0), ("u", 1)) for i in range(values[key].rows)}  # fmt: skip
    V = _value(functional.rhs, values, fn)
    eqs = []
    for key in (("x", 1), ("u", 0), ("u", 1)):
        eqs += [e.xreplace(at_min) for e in _grad(V, values[key])]
    unknowns = sorted({s for e in eqs for s in e.free_symbols}, key=str)
    return _least_squares_residual(eqs, unknowns)


@D1.check(Level.EXACT_RATIONAL, form="printed")
def d1_printed_single_multiplier() -> sp.Expr:
    """f = x + u_1, g = (u_1^2 + (u_2 - x)^2)/2, h = u_1 - u_2, N = 2, x_0 = 0, x_2 = 1: at the
    exact minimiser, the stationarity equations of the printed V (one sigma) in x_1, u_0, u_1 have
    no solution for (p_1, p_2, sigma): least-squares residual of that linear system."""
    return _d1_multiplier_defect(V_PRINTED)


@D1.check(Level.EXACT_RATIONAL, form="corrected")
def d1_corrected_multipliers() -> sp.Expr:
    """The same with the corrected V (sigma_k per step): the linear system for (p_1, p_2, sigma_0,
    sigma_1) is solvable at the minimiser (residual 0)."""
    return _d1_multiplier_defect(V_DEF)


def _d1_rewrite_defect(functional: sp.Eq, rewrite: sp.Eq) -> sp.Expr:
    """The displayed functional minus its displayed rewrite, for undefined f, g, h, N = 2,
    n = m = 2, l = 1 (p_{N+1} and a phantom u_N from the printed terminal convention)."""
    N = 2
    values = _d1_variables(N, 2, 2, 1, phantom=True)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    lhs, rhs = _instance(TERMINAL_PRINTED, {_N: N})
    values[_key(lhs)] = _value(rhs, values, fn) * sp.ones(2, 1)
    return _nonzero(_value(functional.rhs, values, fn) - _value(rewrite.rhs, values, fn))


@D1.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d1_printed_rewrite() -> sp.Expr:
    """The printed V minus the proof's rewrite with the sum up to N and p_{N+1} = 0 does not
    vanish: it is -Hhat(0, x_N, u_N, sigma) (undefined f, g, h, N = 2)."""
    return _d1_rewrite_defect(V_PRINTED, REWRITE_PRINTED)


@D1.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d1_corrected_rewrite() -> sp.Expr:
    """The corrected V minus the corrected rewrite (sum up to N - 1, minus <p_N, x_N>) vanishes
    identically (undefined f, g, h, N = 2)."""
    return _d1_rewrite_defect(V_DEF, REWRITE)


# =============================================================================================
# D2: the implicit step

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
    "x_j$ or $x_i y_j$) is a transpose and does not matter for invertibility.",
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
    """The printed matrix d^2H/dy dx at u = u* against the true Jacobian of the step in y: in
    f = x + u, g = (u + x)^2/2 the printed matrix is 1 while the step's Jacobian is 0 (p_k = 0 for
    every y); in f = a(x) + b(x) u, g = u^2/2 + V(x) they differ by b b' y (count of examples)."""
    return _d2_defect(PRINTED_MATRIX)


@D2.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d2_reduced_matrix() -> sp.Expr:
    """The same comparison with the displayed right side of the corrected step Jacobian, the mixed
    derivative of H* built from the displayed reduced Hamiltonian: equal in both examples."""
    return _d2_defect(STEP_JACOBIAN.rhs)


# =============================================================================================
# D3: linearised extremal equations

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
    """f = a(x) + B u, g = |u|^2/2 + V(x) (a, V undefined, n = m = 2): the displayed corrected
    equations with the blocks of H* reproduce the Jacobians of the true maps (x_k, p_{k+1}) ->
    (p_k, x_{k+1}) (count of mismatching entries)."""
    return _d3_symbolic_defect(LINEARISED, _R, "reduced")


@D3.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d3_printed_frozen_control() -> sp.Expr:
    """Same family: the printed equations with second derivatives of Hhat at frozen u* mismatch
    (the dp_{k+1} coefficient of dx_{k+1} is 0 instead of B B^T), for either index convention of
    the mixed matrix (smallest count of mismatching entries)."""
    return _d3_symbolic_defect(LINEARISED_PRINTED, _P, "frozen")


@D3.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d3_printed_same_matrix() -> sp.Expr:
    """Same family, printed equations with the blocks of H*: one mixed matrix in both lines
    mismatches for either index convention (smallest count of mismatching entries)."""
    return _d3_symbolic_defect(LINEARISED_PRINTED, _P, "reduced")


class NonlinearFamily:
    """f(x, u) = x + tau tanh(W x + B u + c), g(x, u) = |u|^2/2 + alpha |x|^2/2 (float64).

    The implicit advance map solves p_k = H_x(y, x_k, u) and H_u(y, x_k, u) = 0 for (y, u) with
    scipy.optimize.root (analytic Jacobian), then x_{k+1} = f(x_k, u); its Jacobian follows by
    implicit differentiation.  Written from the definitions with NumPy (an independent route).
    """

    def __init__(self, nx: int, nu: int, seed: int, tau: float = 0.3, alpha: float = 0.5) -> None:
        rng = np.random.default_rng(seed)
        self.nx, self.nu, self.tau, self.alpha = nx, nu, tau, alpha
        self.W = rng.standard_normal((nx, nx))
        self.B = rng.standard_normal((nx, nu))
        self.c = rng.standard_normal(nx)

    def f(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return x + self.tau * np.tanh(self.W @ x + self.B @ u + self.c)

    def _parts(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.tanh(self.W @ x + self.B @ u + self.c)
        d = 1.0 - t**2
        return d, -2.0 * t * d

    def equations(self, x: np.ndarray, p: np.ndarray, y: np.ndarray, u: np.ndarray):
        """Residual of (p_k = H_x, 0 = H_u) and its Jacobians in (y, u), x and p."""
        d, dd = self._parts(x, u)
        tau, W, B = self.tau, self.W, self.B
        F = np.concatenate([y + tau * W.T @ (d * y) - self.alpha * x - p, tau * B.T @ (d * y) - u])
        Jy = np.vstack([np.eye(self.nx) + tau * W.T * d, tau * B.T * d])
        Ju = np.vstack([tau * W.T @ np.diag(y * dd) @ B, tau * B.T @ np.diag(y * dd) @ B])
        Ju[self.nx :] -= np.eye(self.nu)
        Jx = np.vstack([
            tau * W.T @ np.diag(y * dd) @ W - self.alpha * np.eye(self.nx),
            tau * B.T @ np.diag(y * dd) @ W,
        ])  # fmt: skip
        Jp = np.vstack([-np.eye(self.nx), np.zeros((self.nu, self.nx))])
        return F, np.hstack([Jy, Ju]), Jx, Jp

    def reduced_hessian_blocks(self, x: np.ndarray, y: np.ndarray, u: np.ndarray):
        """Second derivatives of H*(y, x) = H(y, x, u*(y, x)) by the Schur complement
        H*_ab = H_ab - H_au H_uu^{-1} H_ub: (H*_xx, H*_xy, H*_yy), (H*_xy)_ij = d2/dx_i dy_j."""
        d, dd = self._parts(x, u)
        tau, W, B = self.tau, self.W, self.B
        Hxx = tau * W.T @ np.diag(y * dd) @ W - self.alpha * np.eye(self.nx)
        Hxy = (np.eye(self.nx) + tau * d[:, None] * W).T
        Huu = tau * B.T @ np.diag(y * dd) @ B - np.eye(self.nu)
        Hux = tau * B.T @ np.diag(y * dd) @ W
        Huy = tau * B.T * d
        S = np.linalg.solve(Huu, np.hstack([Hux, Huy]))
        Sx, Sy = S[:, : self.nx], S[:, self.nx :]
        return Hxx - Hux.T @ Sx, Hxy - Hux.T @ Sy, -Huy.T @ Sy

    def frozen_hessian_blocks(self, x: np.ndarray, y: np.ndarray, u: np.ndarray):
        """Second derivatives of Hhat with the control held at u*: (H_xx, H_xy, H_yy = 0)."""
        d, dd = self._parts(x, u)
        Hxx = self.tau * self.W.T @ np.diag(y * dd) @ self.W - self.alpha * np.eye(self.nx)
        Hxy = (np.eye(self.nx) + self.tau * d[:, None] * self.W).T
        return Hxx, Hxy, np.zeros((self.nx, self.nx))

    def advance(self, x: np.ndarray, p: np.ndarray, guess: np.ndarray | None = None):
        """(x_{k+1}, p_{k+1}, u_k) from (x_k, p_k) by solving the implicit step."""
        from scipy.optimize import root

        nx = self.nx
        z0 = np.concatenate([p, np.zeros(self.nu)]) if guess is None else guess

        def fun(zz: np.ndarray):
            F, J, _, _ = self.equations(x, p, zz[:nx], zz[nx:])
            return F, J

        sol = root(fun, z0, jac=True, method="hybr", options={"xtol": 1e-14})
        y, u = sol.x[:nx], sol.x[nx:]
        F, _, _, _ = self.equations(x, p, y, u)
        if not np.max(np.abs(F)) <= 1e-12:  # hybr may flag xtol as unmet at round-off
            raise RuntimeError(f"implicit step did not converge: |F| = {np.max(np.abs(F)):.2e}")
        return self.f(x, u), y, u

    def advance_jacobian(self, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Jacobian of (x_k, p_k) -> (x_{k+1}, p_{k+1}) by implicit differentiation."""
        nx = self.nx
        _x1, y, u = self.advance(x, p)
        _F, Jyu, Jx, Jp = self.equations(x, p, y, u)
        dyu = -np.linalg.solve(Jyu, np.hstack([Jx, Jp]))
        d, _ = self._parts(x, u)
        fx = np.eye(nx) + self.tau * d[:, None] * self.W
        fu = self.tau * d[:, None] * self.B
        dx1 = np.hstack([fx, np.zeros((nx, nx))]) + fu @ dyu[nx:]
        return np.vstack([dx1, dyu[:nx]])

    def advance_jacobian_fd(self, x: np.ndarray, p: np.ndarray, step: float = 1e-6) -> np.ndarray:
        """Central finite-difference Jacobian (each perturbed solve starts from the base point)."""
        nx = self.nx
        _x1, y, u = self.advance(x, p)
        guess = np.concatenate([y, u])
        z = np.concatenate([x, p])
        cols = []
        for j in range(2 * nx):
            e = np.zeros(2 * nx)
            e[j] = step
            a1, b1, _ = self.advance((z + e)[:nx], (z + e)[nx:], guess)
            a2, b2, _ = self.advance((z - e)[:nx], (z - e)[nx:], guess)
            cols.append((np.concatenate([a1, b1]) - np.concatenate([a2, b2])) / (2 * step))
        return np.array(cols).T


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
    """f = x + 0.3 tanh(W x + B u + c), g = |u|^2/2 + |x|^2/4 (u* depends on x and p_{k+1};
    n = 3, m = 2, 3 random points): the displayed corrected equations with the blocks of H*
    (Schur complements) against the Jacobian of the implicit advance map from scipy root and
    implicit differentiation (largest entry of the mismatch; entries are of order 1)."""
    return _d3_float_defect(LINEARISED, _R, "reduced")


@D3.check(Level.FLOAT64, tol=1e-11, form="printed")
def d3_nonlinear_printed() -> float:
    """Same family: the printed equations with blocks of Hhat at frozen u* miss that Jacobian for
    either index convention."""
    return _d3_float_defect(LINEARISED_PRINTED, _P, "frozen")


# =============================================================================================
# D4: symplecticity of the advance map

D4 = claim(
    "D4",
    label="eq8.13",
    title="The advance map $(x_k, p_k) \\mapsto (x_{k+1}, p_{k+1})$ is symplectic",
    statement="The implicit advance map $\\Phi$ of the extremal equations preserves "
    "$dx\\wedge dp$: its Jacobian $D\\Phi$, obtained from the corrected linearised equations of D3 "
    "where $H^*_{xy}$ is invertible, satisfies [[symplectic]] with [[omega]].",
    expected="holds",
    section="2",
    where="Section 2, the remark after the corollary: the advance map $\\Phi$ is symplectic, "
    "$\\Phi^*(dx_{k+1} \\wedge dp_{k+1}) = dx_k \\wedge dp_k$",
    note="Shown for every symmetric $H^*_{xx}$, $H^*_{yy}$ and invertible $H^*_{xy}$ (so for "
    "every smooth $H^*$ with invertible mixed derivative): symbolic for $n = 2$, exact rational "
    "random blocks for $n = 3$, and on a nonlinear family solved numerically.",
)
_DPhi, _Omega = sp.MatrixSymbol(r"D\Phi", 2 * n, 2 * n), sp.MatrixSymbol(r"\Omega", 2 * n, 2 * n)
OMEGA = D4.formula(
    "omega",
    eq(_Omega, sp.BlockMatrix([[sp.ZeroMatrix(n, n), sp.Identity(n)],
                               [-sp.Identity(n), sp.ZeroMatrix(n, n)]])),
)  # fmt: skip
SYMPLECTIC = D4.formula("symplectic", eq(_DPhi.T * _Omega * _DPhi, _Omega))


def _advance_jacobian(Hxx: sp.Matrix, Hxy: sp.Matrix, Hyy: sp.Matrix) -> sp.Matrix:
    """D Phi obtained by solving D3's displayed corrected equations for (dx_{k+1}, dp_{k+1})."""
    dim = Hxx.rows
    dxk, dpk, dx1, dp1 = (_vec(s, dim) for s in ("dxk", "dpk", "dx1", "dp1"))
    env = {"dx_k": dxk, "dp_k": dpk, "dx_{k+1}": dx1, "dp_{k+1}": dp1,
           "H^*_{xx}": Hxx, "H^*_{xy}": Hxy, "H^*_{yy}": Hyy}  # fmt: skip
    eqs = [e for f in LINEARISED for e in explicit(lhs_minus_rhs(f), env)]
    sol = sp.solve(eqs, [*dx1, *dp1], dict=True)[0]
    new = dx1.col_join(dp1).xreplace(sol)
    return new.jacobian(dxk.col_join(dpk))


def _symplectic_defect(J: sp.Matrix) -> sp.Matrix:
    dim = J.rows // 2
    om = OMEGA.rhs.subs(n, dim).as_explicit()
    return explicit(lhs_minus_rhs(SYMPLECTIC), {r"D\Phi": J, r"\Omega": sp.Matrix(om)})


@D4.check(Level.SYMBOLIC_FIXED_N)
def d4_symbolic() -> sp.Expr:
    """D Phi from D3's corrected equations with generic symmetric H*_xx, H*_yy and generic H*_xy
    (symbolic entries, n = 2): the displayed D Phi^T Omega D Phi - Omega cancels entrywise."""
    dim = 2
    Hxx = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"s{min(i, j)}{max(i, j)}"))
    Hyy = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"t{min(i, j)}{max(i, j)}"))
    Hxy = sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"a{i}{j}"))
    return _nonzero(_symplectic_defect(_advance_jacobian(Hxx, Hxy, Hyy)).applyfunc(sp.cancel))


@D4.check(Level.EXACT_RATIONAL)
def d4_exact_n3() -> sp.Expr:
    """The same for n = 3 at 4 random rational symmetric H*_xx, H*_yy and invertible rational
    H*_xy."""
    rng = np.random.default_rng(4)
    total = sp.Integer(0)
    done = 0
    while done < 4:
        A, B, C = (sp.Matrix(3, 3, [sp.Rational(int(v), 7) for v in rng.integers(-9, 10, 9)])
                   for _ in range(3))  # fmt: skip
        if C.det() == 0:  # the statement assumes an invertible H*_xy
            continue
        total += _nonzero(_symplectic_defect(_advance_jacobian(A + A.T, C, B + B.T)))
        done += 1
    return total


def symplecticity_defects(seeds: Sequence[int] = range(5), fd: bool = False) -> list[float]:
    """Largest entry of the displayed D Phi^T Omega D Phi - Omega on NonlinearFamily(3, 2, seed)
    at a random point, D Phi by implicit differentiation or central differences."""
    out = []
    for seed in seeds:
        fam = NonlinearFamily(3, 2, seed)
        rng = np.random.default_rng(100 + seed)
        x, p = rng.standard_normal(3), 0.5 * rng.standard_normal(3)
        J = fam.advance_jacobian_fd(x, p) if fd else fam.advance_jacobian(x, p)
        out.append(float(np.max([float(abs(v)) for v in _symplectic_defect(sp.Matrix(J))])))
    return out


@D4.check(Level.FLOAT64, tol=1e-12)
def d4_float64() -> float:
    """f = x + 0.3 tanh(W x + B u + c), g = |u|^2/2 + |x|^2/4 (5 random families and points,
    n = 3, m = 2): implicit step by scipy root, D Phi by implicit differentiation, largest entry of
    the displayed D Phi^T Omega D Phi - Omega (entries of order 1)."""
    return float(np.max(symplecticity_defects()))


@D4.check(Level.FLOAT64, tol=1e-7)
def d4_float64_fd() -> float:
    """The same with D Phi by central differences of the implicit step (step 1e-6, 3 points;
    the tolerance is the differences' truncation and round-off error)."""
    return float(np.max(symplecticity_defects(range(3), fd=True)))


# =============================================================================================
# D5: multi-sample problem with terminal cost

D5 = claim(
    "D5",
    label="prob8.1m, gendiscpropm, eq8.3m-eq8.6m, m8",
    title="Multi-sample problem with terminal cost: shared controls, per-sample costates",
    statement="The multi-sample maximum principle (the second proposition of Section 2): for the problem of minimising [[cost]] subject to "
    "[[dynamics]] and the control constraint, with controls shared by the samples, the "
    "extremal equations of [[H]] have per-sample costates and an endpoint condition.",
    printed="The multi-sample problem also fixes the endpoints $x^a_N$; its costate equation is "
    "[[costate_printed]] with the un-indexed $x_k$; its endpoint condition is [[m8]].",
    corrected="The endpoint is free. The extremal equations are the critical points of [[V]]: "
    "[[state]], [[costate]], [[stationary]] with one multiplier per step, and [[endpoint]] for this "
    "$H$ (equivalently the costates are minus the gradients of the cost, D6).",
    expected="holds after correction",
    section="2",
    where="Section 2, the second definition (several samples $a = 1, \\dots, M$ and an endpoint "
    "cost $\\phi$) and the second proposition (extremal equations and the endpoint condition "
    "$p^a_N = \\partial\\phi/\\partial x^a_N$), with its proof",
    note="The problem fixes the endpoints $x^a_N$, the costate equation uses the un-indexed "
    "$x_k$, and the endpoint condition has the wrong sign. Corrected: the endpoint is free, the "
    "costate equation uses $x^a_k$, and $p^a_N = -\\partial\\phi/\\partial x^a_N$ for $H = "
    "\\langle p, f\\rangle - g$. With $H = \\langle p, f\\rangle - g$ and a minimisation, $V = "
    "-(\\text{cost}) + \\langle p, f - x\\rangle + \\langle \\sigma, h\\rangle$, so $\\partial "
    "V/\\partial x^a_N = -p^a_N - \\phi'(x^a_N)$: the endpoint sign is minus (the paper's $V$ "
    "carries $+\\phi$ and an extra $-p_N x_N$). If $x^a_N$ is fixed, $\\phi(x^a_N)$ is a constant "
    "and no endpoint condition follows. The term $-\\phi(x^a_N)$ inside the proposition's "
    "Hamiltonian is harmless (constant in the variables of $H$). The proof's $V$ needs "
    "$\\sigma_k$ per step, as in D1 (checked there).",
)
COST5 = D5.formula(
    "cost",
    eq(
        _C,
        _plus(
            sp.Sum(sp.Sum(_g(_xa(_a, _k), _u[_k]), (_k, 0, _Nm1)), (_a, 1, _M)),
            sp.Sum(_phi(_xa(_a, _N)), (_a, 1, _M)),
        ),
    ),
)
DYNAMICS5 = D5.formula("dynamics", _Steps([eq(_xa(_a, _k1), _f(_xa(_a, _k), _u[_k]))], _k, 0, _Nm1))
D5.formula("H", H_DEF)
_H_ak = _H(_pa(_a, _k1), _xa(_a, _k), _u[_k])
V5 = D5.formula(
    "V",
    eq(
        _V,
        _plus(
            sp.Sum(
                sp.Sum(_plus(_Dot(_pa(_a, _k1), _plus(_f(_xa(_a, _k), _u[_k]), -_xa(_a, _k1))),
                             -_g(_xa(_a, _k), _u[_k])), (_k, 0, _Nm1)),
                (_a, 1, _M),
            ),
            sp.Sum(_Dot(_sig[_k], _h(_u[_k])), (_k, 0, _Nm1)),
            -sp.Sum(_phi(_xa(_a, _N)), (_a, 1, _M)),
        ),
    ),
)  # fmt: skip
STATE5 = D5.formula(
    "state", _Steps([eq(_xa(_a, _k1), sp.Derivative(_H_ak, _pa(_a, _k1)))], _k, 0, _Nm1)
)
_COSTATE5_EQ = eq(_pa(_a, _k), sp.Derivative(_H_ak, _xa(_a, _k)))
COSTATE5 = D5.formula("costate", _Steps([_COSTATE5_EQ], _k, 1, _Nm1))
COSTATE5_PRINTED = D5.formula(
    "costate_printed",
    _Steps(
        [eq(_pa(_a, _k), sp.Derivative(_H(_pa(_a, _k1), _x[_k], _u[_k]), _x[_k]))],
        _k, 0, _Nm1,
    ),
)  # fmt: skip
STATIONARY5 = D5.formula(
    "stationary",
    _Steps(
        [
            eq(
                _plus(
                    sp.Sum(sp.Derivative(_H_ak, _u[_k]), (_a, 1, _M)),
                    sp.Derivative(_Dot(_sig[_k], _h(_u[_k])), _u[_k]),
                ),
                0,
            ),
            eq(_h(_u[_k]), 0),
        ],
        _k,
        0,
        _Nm1,
    ),
)
_dphi = sp.Derivative(_phi(_xa(_a, _N)), _xa(_a, _N))
ENDPOINT = D5.formula("endpoint", eq(_pa(_a, _N), -_dphi))
M8 = D5.formula("m8", eq(_pa(_a, _N), _dphi))


def _d5_variables(N: int, M: int, nx: int, nu: int, nl: int) -> dict[Any, Any]:
    values: dict[Any, Any] = {"N": N, "M": M}
    for a in range(1, M + 1):
        for k in range(N + 1):
            values[("x", a, k)] = _vec(f"x{a}{k}", nx)
            if k:
                values[("p", a, k)] = _vec(f"p{a}{k}", nx)
    for k in range(N):
        values[("u", k)] = _vec(f"u{k}", nu)
        values[(r"\sigma", k)] = _vec(f"s{k}", nl)
    return values


@D5.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d5_stationarity() -> sp.Expr:
    """The derivatives of the displayed V (free endpoint) in p^a_{k+1}, x^a_k, x^a_N, u_k and
    sigma_k are the displayed state, costate, endpoint, stationarity and constraint equations over
    their displayed ranges, covering every variable of V once (undefined f, g, h, phi; n = m = 2,
    l = 1, M = 2 samples, N = 2)."""
    N, M = 2, 2
    values = _d5_variables(N, M, 2, 2, 1)
    fn = _with_hamiltonians(_generic(2, 2, 1))
    V = _value(V5.rhs, values, fn)
    total = sp.Integer(0)
    covered = []

    def compare(lhs: sp.Basic, rhs: sp.Basic, var: sp.Basic, sign: int) -> sp.Expr:
        """dV/dvar against +-(lhs - rhs): rhs - lhs of "p = dH/dx", lhs - rhs of "... = 0"."""
        covered.append(_key(var))
        side = _minus(_value(lhs, values, fn), _value(rhs, values, fn))
        return _nonzero(_minus(_grad(V, values[_key(var)]), sign * side))

    for a in range(1, M + 1):
        for k in STATE5.steps(N):
            total += compare(*STATE5.at(k, a=a), _pa(a, k + 1), -1)
        for k in COSTATE5.steps(N):
            total += compare(*COSTATE5.at(k, a=a), _xa(a, k), -1)
        total += compare(*_instance(ENDPOINT, {_a: a, _N: N}), _xa(a, N), -1)
    for k in STATIONARY5.steps(N):
        total += compare(*STATIONARY5.at(k, 0), _u[k], 1)
        total += compare(*STATIONARY5.at(k, 1), _sig[k], 1)
    fixed = {("x", a, 0) for a in range(1, M + 1)}
    total += _coverage_defect(V, values, fixed, covered)
    return total


def _two_sample_example() -> tuple[dict[str, Any], dict[Any, Any]]:
    """M = 2 samples, N = 2, n = m = 1: f = x + u, g = (u^2 + x^2)/2, phi(x) = (x - 1)^2/2,
    x^1_0 = 0, x^2_0 = 2, no constraint.  The exact minimiser of the displayed cost along the
    displayed dynamics, as values."""
    N, M = 2, 2
    fn = _with_hamiltonians({
        "f": lambda x, u: x + u,
        "g": lambda x, u: (u[0] ** 2 + x[0] ** 2) / 2,
        "h": lambda u: sp.zeros(1, 1),
        r"\phi": lambda x: (x[0] - 1) ** 2 / 2,
    })  # fmt: skip
    us = sp.symbols("v0 v1")
    values: dict[Any, Any] = {"N": N, "M": M}
    values.update({("u", k): sp.Matrix([us[k]]) for k in range(N)})
    values.update({(r"\sigma", k): sp.zeros(1, 1) for k in range(N)})
    for a, x0 in ((1, 0), (2, 2)):
        values[("x", a, 0)] = sp.Matrix([x0])
        for k in DYNAMICS5.steps(N):
            lhs, rhs = DYNAMICS5.at(k, a=a)
            values[_key(lhs)] = _value(rhs, values, fn)
    cost = _value(COST5.rhs, values, fn)
    if not sp.hessian(cost, us).is_positive_definite:
        raise ValueError("the example is not convex")
    best = sp.solve([sp.diff(cost, v) for v in us], us, dict=True)[0]
    return fn, _substituted(values, best)


def _d5_example_defect(endpoint: sp.Eq, costate: _Steps) -> sp.Expr:
    """In the two-sample example: costates from the given endpoint condition and costate equation
    (for the un-indexed x_k of the printed eq8.3m, sample 1's state), then sum over k of
    |lhs - rhs| of the displayed stationarity condition at the exact minimiser."""
    fn, values = _two_sample_example()
    N, M = values["N"], values["M"]
    for k in range(N + 1):
        values[("x", k)] = values[("x", 1, k)]
    for a in range(1, M + 1):
        lhs, rhs = _instance(endpoint, {_a: a, _N: N})
        values[_key(lhs)] = _value(rhs, values, fn)
        for k in reversed([k for k in costate.steps(N) if k >= 1]):
            lhs, rhs = costate.at(k, a=a)
            values[_key(lhs)] = _value(rhs, values, fn)
    total = sp.Integer(0)
    for k in STATIONARY5.steps(N):
        lhs, rhs = STATIONARY5.at(k, 0)
        total += sum(abs(e) for e in _value(lhs, values, fn) - sp.Matrix([_value(rhs, values, fn)]))
    return sp.nsimplify(total)


@D5.check(Level.EXACT_RATIONAL, form="corrected")
def d5_corrected_example() -> sp.Expr:
    """2 samples, N = 2, f = x + u, g = (u^2 + x^2)/2, phi = (x - 1)^2/2, x_0 = 0 and 2: costates
    from the displayed endpoint condition and costate equation satisfy the displayed stationarity
    condition at the exact minimiser (sum over k of |sum_a H_u|)."""
    return _d5_example_defect(ENDPOINT, COSTATE5)


@D5.check(Level.EXACT_RATIONAL, form="printed")
def d5_printed_endpoint_sign() -> sp.Expr:
    """Same example with m8's endpoint sign: the stationarity condition fails at the minimiser."""
    return _d5_example_defect(M8, COSTATE5)


@D5.check(Level.EXACT_RATIONAL, form="printed")
def d5_printed_shared_state() -> sp.Expr:
    """Same example with eq8.3m's un-indexed x_k (sample 1's state for both samples): the
    stationarity condition fails at the minimiser."""
    return _d5_example_defect(ENDPOINT, COSTATE5_PRINTED)


def _d5_endpoint_defect(fixed: bool) -> sp.Expr:
    """N = 1, one sample, f = x + u, g = u^2/2, phi(x) = (x - 3)^2/2, x_0 = 0; the control is the
    minimiser of the displayed cost (free endpoint) or forced by x_1 = 1 (fixed endpoint); p_1
    from the displayed stationarity condition.  Returns the smaller mismatch of the two endpoint
    conditions, displayed corrected and m8."""
    N, M = 1, 1
    fn = _with_hamiltonians({
        "f": lambda x, u: x + u,
        "g": lambda x, u: u[0] ** 2 / 2,
        "h": lambda u: sp.zeros(1, 1),
        r"\phi": lambda x: (x[0] - 3) ** 2 / 2,
    })  # fmt: skip
    v, P = sp.symbols("v P")
    values: dict[Any, Any] = {"N": N, "M": M, ("x", 1, 0): sp.Matrix([0]), ("u", 0): sp.Matrix([v])}
    values[(r"\sigma", 0)] = sp.zeros(1, 1)
    lhs, rhs = DYNAMICS5.at(0, a=1)
    values[_key(lhs)] = _value(rhs, values, fn)
    if fixed:
        best = sp.solve(values[("x", 1, 1)][0] - 1, v)[0]
    else:
        best = sp.solve(sp.diff(_value(COST5.rhs, values, fn), v), v)[0]
    values = _substituted(values, {v: best})
    values[("p", 1, 1)] = sp.Matrix([P])
    lhs, rhs = STATIONARY5.at(0, 0)
    values[("p", 1, 1)] = sp.Matrix(
        [sp.solve(_value(lhs, values, fn)[0] - _value(rhs, values, fn), P)[0]]
    )
    gaps = []
    for condition in (ENDPOINT, M8):
        lhs, rhs = _instance(condition, {_a: 1, _N: N})
        gaps.append(abs((_value(lhs, values, fn) - _value(rhs, values, fn))[0]))
    return sp.Min(*gaps)


@D5.check(Level.EXACT_RATIONAL, form="printed")
def d5_printed_fixed_endpoint() -> sp.Expr:
    """prob8.1m fixes x_N and adds phi(x_N): with N = 1, f = x + u, g = u^2/2, x_0 = 0, x_1 = 1,
    phi = (x - 3)^2/2, the stationarity condition gives p_1 = 1 while phi'(1) = -2, so neither
    endpoint condition holds (smaller mismatch 1)."""
    return _d5_endpoint_defect(fixed=True)


@D5.check(Level.EXACT_RATIONAL, form="corrected")
def d5_free_endpoint() -> sp.Expr:
    """The same problem with a free endpoint: at the exact minimiser one of the endpoint
    conditions holds (the corrected one, as the stationarity check above shows in general)."""
    return _d5_endpoint_defect(fixed=False)


# =============================================================================================
# D6: ResNet layers; the costate recursion is back-propagation


D6 = claim(
    "D6",
    label="Remark 1, Remark 2",
    title="ResNet layers: the costate recursion is back-propagation",
    statement="Remark 1: in the ResNet framework of Benning et al. (2019) a layer is $f(x, u)$ "
    "with controls $u$ the pair $(K, \\beta)$ and $\\sigma$ the sigmoid [[sigmoid]] applied "
    "entrywise. Remark 2: the solution of the multi-sample maximum principle is back-propagation (LeCun "
    "1988). With [[H]] and no running cost, [[no_running_cost]], the costate recursion of the "
    "layers is [[adjoint]] (for the plain layer [[adjoint_plain]]), and for the endpoint condition "
    "[[endpoint]] with either sign, $s=1$ or $s=-1$, the costates and weight gradients are "
    "[[backprop]] and [[weights]] with [[cost]].",
    printed="Remark 1: the ResNet layer is [[plain_layer]]. Remark 2, read for Proposition "
    "the multi-sample maximum principle with its endpoint condition [[m8]], and a running cost $g$: the costates "
    "are the back-propagated gradients of the cost, [[backprop]] and [[weights]] with $s=1$.",
    corrected="The ResNet layer of Benning et al. is the residual layer [[residual_layer]], a "
    "perturbation of the identity, [[identity]], which the plain layer is not. The costate "
    "recursion is back-propagation for both layers when there is no running cost, with either "
    "endpoint sign (the printed sign gives the gradients, D5's sign minus the gradients); with a running "
    "cost only D5's endpoint condition [[endpoint_minus]] gives the gradients of the cost, "
    "[[backprop]] and [[weights]] with $s=-1$.",
    expected="holds after correction",
    section="2",
    where="Section 2, the paragraph 'Remark' that closes the section before Section 2.1: item 1 "
    "(the ResNet layer $f(x, u) = \\sigma(Kx + \\beta)$) and item 2 (the link with "
    "back-propagation)",
    note="Remark 1's layer $\\sigma(Kx + \\beta)$ is not the residual (ResNet) layer, and with a "
    "running cost the printed endpoint sign does not make the costates the back-propagated "
    "gradients. Corrected: the ResNet layer is $x + h\\,\\sigma(Kx + \\beta)$, and with $p^a_N = "
    "-\\partial\\phi/\\partial x^a_N$ the costates are minus the gradients of the cost, for "
    "either layer. The symrb implementation has both layers with $h = 1$ and the D5 sign (its "
    "costates are minus the back-propagated gradients). For $g = 0$ the recursion $p_k = "
    "(\\partial f/\\partial x)^T p_{k+1}$ is linear and homogeneous, so the endpoint sign is a "
    "global sign: the printed endpoint condition gives $p_k = +\\partial\\Phi/\\partial x_k$, "
    "D5's gives $p_k = -\\partial\\Phi/\\partial x_k$. With $g \\ne 0$ the recursion $p_k = "
    "(\\partial f/\\partial x)^T p_{k+1} - \\partial g/\\partial x$ is affine and only $p_N = "
    "-\\partial\\phi/\\partial x_N$ makes $p_k = -\\partial C/\\partial x_k$; with the printed "
    "sign the costates are neither plus nor minus the gradients.",
)
SIGMOID_DEF = D6.formula(
    "sigmoid", eq(sp.Function(r"\sigma")(sp.Symbol("z")), 1 / (1 + sp.exp(-sp.Symbol("z"))))
)
D6.formula("H", H_DEF)
G0 = D6.formula("no_running_cost", eq(_g(_xs, _us), 0))

# the matrix-level symbols of a layer (the kernels' arguments)
_Km, _bv, _xv, _pv = matrix("K"), vector("beta"), vector("x"), vector("p")
_hstep = sp.Symbol("h", positive=True)
_zl = sp.Dummy("z", real=True)


def _sigma_fdiff(self: sp.Function, argindex: int = 1) -> sp.Expr:
    return _DSIGMA(self.args[0])


#: a generic smooth activation, printed sigma, with derivative sigma' (both undefined)
_DSIGMA = sp.Function(r"\sigma'")
_SIGMA = type(r"\sigma", (sp.Function,), {"nargs": 1, "fdiff": _sigma_fdiff})


def _activation(expr: sp.Expr) -> tuple[sp.Lambda, sp.Lambda]:
    """sigma and sigma' as Lambdas (the derivative expanded, not simplified: SymPy would write
    1 - tanh^2 as cosh^-2, which overflows in float64)."""
    return sp.Lambda(_zl, expr), sp.Lambda(_zl, sp.expand(sp.diff(expr, _zl)))


#: the activations of the kernels; the logistic function is written (1 + tanh(z/2))/2, which is
#: 1/(1 + exp(-z)) (checked) and never overflows
ACTIVATIONS: dict[str, tuple[sp.Lambda, sp.Lambda]] = {
    "tanh": _activation(sp.tanh(_zl)),
    "logistic": _activation((1 + sp.tanh(_zl / 2)) / 2),
}
_GENERIC = (sp.Lambda(_zl, _SIGMA(_zl)), sp.Lambda(_zl, _DSIGMA(_zl)))


class _Shown(ElementwiseApplyFunction):
    """A function applied entrywise, printed sigma(K x + beta) rather than SymPy's
    (z -> sigma(z))_o(K x + beta); evaluated like any ElementwiseApplyFunction.  Only the
    displayed generic layer uses it (the kernels use entrywise(), which codegen prints)."""

    def _latex(self, printer: Any) -> str:
        return rf"{self.function.expr.func}\left({printer._print(self.expr)}\right)"


def _apply(name: str, fn: sp.Lambda, z: sp.MatrixExpr) -> sp.MatrixExpr:
    """fn entrywise on z: through codegen's entrywise() for a kernel's activation, as _Shown for
    the generic sigma of the displayed formulas."""
    return _Shown(fn, z) if name in ("sigma", "dsigma") else entrywise(name, fn, z)


def layer(act: str, residual_layer: bool, h: sp.Expr = sp.S.One) -> dict[str, sp.MatrixExpr]:
    """One layer and its adjoint at matrix level, for H(p, x, u) = <p, f(x, u)>, u = (K, beta):

    z = K x + beta, s = sigma'(z) o p (entrywise),
    x_next = x + h sigma(z) (residual) or sigma(z) (plain),
    p_prev = dH/dx = p + h K^T s or K^T s,  dH/dK = h s x^T or s x^T,  dH/dbeta = h s or s.

    ``act`` is ``"tanh"``, ``"logistic"`` (the kernels) or ``"sigma"`` (a generic activation, for
    the displayed formulas).
    """
    sig, dsig = _GENERIC if act == "sigma" else ACTIVATIONS[act]
    z = _Km * _xv + _bv
    s = sp.HadamardProduct(_apply("d" + act, dsig, z), _pv)
    c = h if residual_layer else sp.Integer(1)
    # the displayed sums keep the order x + h sigma(z) (a kernel's are printed sorted anyway)
    add = functools.partial(sp.MatAdd, evaluate=act != "sigma")
    return {
        "x_next": add(_xv, h * _apply(act, sig, z)) if residual_layer else _apply(act, sig, z),
        "p_prev": add(_pv, c * _Km.T * s) if residual_layer else _Km.T * s,
        "dH_dK": c * s * _xv.T,
        "dH_dbeta": c * s,
    }


_fxu = vector("f(x,u)")
PLAIN_LAYER = D6.formula("plain_layer", eq(_fxu, layer("sigma", False)["x_next"]))
RESIDUAL_LAYER = D6.formula("residual_layer", eq(_fxu, layer("sigma", True, _hstep)["x_next"]))
IDENTITY = D6.formula(
    "identity", eq(matrix(r"\left.\partial f/\partial x\right|_{K=0}"), sp.Identity(n))
)
_ADJ_NAMES = {
    "p_prev": vector(r"\partial H/\partial x"),
    "dH_dK": matrix(r"\partial H/\partial K"),
    "dH_dbeta": vector(r"\partial H/\partial \beta"),
}
ADJOINT = D6.formula(
    "adjoint",
    tuple(eq(_ADJ_NAMES[k], v) for k, v in layer("sigma", True, _hstep).items() if k in _ADJ_NAMES),
)
ADJOINT_PLAIN = D6.formula(
    "adjoint_plain",
    tuple(eq(_ADJ_NAMES[k], v) for k, v in layer("sigma", False).items() if k in _ADJ_NAMES),
)
_s = sp.Symbol("s")
ENDPOINT_S = D6.formula("endpoint", eq(_pa(_a, _N), _s * _dphi))
D6.formula("m8", M8)
D6.formula("endpoint_minus", ENDPOINT)
_dCdx, _dCdu = sp.IndexedBase(r"\partial C/\partial x"), sp.IndexedBase(r"\partial C/\partial u")
BACKPROP = D6.formula("backprop", eq(_pa(_a, _k), _s * _Sample(_dCdx, _a, _k)))
WEIGHTS = D6.formula(
    "weights", eq(_dCdu[_k], _s * sp.Sum(sp.Derivative(_H_ak, _u[_k]), (_a, 1, _M)))
)
D6.formula("cost", COST5)

# ---------------------------------------------------------------------------------------------
# the kernels

ARG_K = Arg("K", "(..., n, n)", "layer weight K_k")
ARG_BETA = Arg("beta", "(..., n, 1)", "layer bias beta_k")
ARG_X = Arg("x", "(..., n, 1)", "state x_k")
ARG_P = Arg("p", "(..., n, 1)", "costate p_{k+1}")
STEP_KERNELS: dict[tuple[str, bool], Kernel] = {}
ADJOINT_KERNELS: dict[tuple[str, bool], Kernel] = {}
for _act, _res in itertools.product(ACTIVATIONS, (True, False)):
    _exprs = layer(_act, _res)
    _suffix = _act + ("" if _res else "_plain")
    _form = f"x + {_act}(K x + beta)" if _res else f"{_act}(K x + beta)"
    STEP_KERNELS[(_act, _res)] = Kernel(
        name=f"resnet_step_{_suffix}",
        target="discrete_control",
        args=[ARG_K, ARG_BETA, ARG_X],
        outputs={"x_next": _exprs["x_next"]},
        doc=f"One {'residual' if _res else 'plain'} layer x_(k+1) = f(x_k, u_k) = {_form}.\n\n"
        "The control is u = (K, beta); the activation acts entrywise.",
        claims=("D6",),
    )
    ADJOINT_KERNELS[(_act, _res)] = Kernel(
        name=f"resnet_adjoint_{_suffix}",
        target="discrete_control",
        args=[ARG_K, ARG_BETA, ARG_X, ARG_P],
        outputs={k: _exprs[k] for k in ("p_prev", "dH_dK", "dH_dbeta")},
        doc=f"Adjoint step of the layer f(x, u) = {_form} for H = <p, f(x, u)>.\n\n"
        f"With z = K x + beta and s = {_act}'(z) * p (entrywise):\n"
        + ("p_k = dH/dx = p + K^T s" if _res else "p_k = dH/dx = K^T s")
        + ", dH/dK = s x^T, dH/dbeta = s.",
        claims=("D6",),
    )


# ---------------------------------------------------------------------------------------------
# D6 evidence


def _layer_env(dim: int) -> dict[str, sp.Matrix]:
    return {
        "K": sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"k{i}{j}", real=True)),
        "x": _vec("x", dim),
        "beta": _vec("b", dim),
        "p": _vec("p", dim),
    }


@D6.check(Level.SYMBOLIC_FIXED_N)
def d6_sigmoid() -> sp.Expr:
    """The activation of the logistic kernels is the displayed sigmoid 1/(1 + e^-z) (read from the
    emitted step's expression; symbolic z)."""
    z = sp.Symbol("z", real=True)
    total = sp.Integer(0)
    for res in (True, False):
        step = STEP_KERNELS[("logistic", res)]["x_next"]
        (fn,) = {e.function for e in step.atoms(ElementwiseApplyFunction)}
        want = SIGMOID_DEF.rhs.xreplace({sp.Symbol("z"): z})
        total += residual(sp.simplify((fn(z) - want).rewrite(sp.exp)))
    return total


@D6.check(Level.SYMBOLIC_FIXED_N)
def d6_kernels() -> sp.Expr:
    """Each emitted step equals the displayed layer with sigma its activation and h = 1, and each
    emitted adjoint returns the explicit gradients in x, K and beta of the displayed H with f the
    emitted step and g = 0 (symbolic entries, n = 3, tanh and logistic, residual and plain)."""
    env = _layer_env(3)
    total = sp.Integer(0)
    for (act, res), kernel in STEP_KERNELS.items():
        x_next = explicit(kernel["x_next"], env)
        shown = RESIDUAL_LAYER if res else PLAIN_LAYER
        want = explicit(shown.rhs, {**env, "h": 1}).replace(_SIGMA, ACTIVATIONS[act][0])
        total += _nonzero(x_next - want)
        fn = {"f": lambda x, u, x_next=x_next: x_next, "g": _define(G0, {})}
        H = _define(H_DEF, fn)(env["p"], env["x"], sp.Symbol("u"))
        adjoint = ADJOINT_KERNELS[(act, res)]
        grads = {
            "p_prev": _grad(H, env["x"]),
            "dH_dK": env["K"].applyfunc(lambda kij, H=H: sp.diff(H, kij)),
            "dH_dbeta": _grad(H, env["beta"]),
        }
        for name, value in grads.items():
            total += _nonzero(explicit(adjoint[name], env) - value)
    return total


def _unflatten(u: sp.Matrix, dim: int) -> tuple[sp.Matrix, sp.Matrix]:
    return sp.Matrix(dim, dim, list(u[: dim * dim])), sp.Matrix(list(u[dim * dim :]))


def _layer_function(shown: sp.Eq, dim: int, h: Any) -> Callable[..., Any]:
    """f(x, u) of a displayed layer, u the vector of the entries of K (row-major) and beta."""

    def f(x: sp.Matrix, u: sp.Matrix) -> sp.Matrix:
        K, beta = _unflatten(u, dim)
        return explicit(shown.rhs, {"x": x, "K": K, "beta": beta, "h": h})

    return f


@D6.check(Level.SYMBOLIC_FIXED_N)
def d6_adjoint_formulas() -> sp.Expr:
    """The displayed adjoint formulas of both layers (generic activation sigma, step h) are the
    gradients in x, K and beta of the displayed H with f the displayed layer and g = 0 (symbolic
    entries, n = 2)."""
    dim = 2
    env = _layer_env(dim)
    u = sp.Matrix([*env["K"], *env["beta"]])
    total = sp.Integer(0)
    for shown, adjoint in ((RESIDUAL_LAYER, ADJOINT), (PLAIN_LAYER, ADJOINT_PLAIN)):
        fn = {"f": _layer_function(shown, dim, _hstep), "g": _define(G0, {})}
        H = _define(H_DEF, fn)(env["p"], env["x"], u)
        du = _grad(H, u)
        grads = {
            r"\partial H/\partial x": _grad(H, env["x"]),
            r"\partial H/\partial K": _unflatten(du, dim)[0],
            r"\partial H/\partial \beta": _unflatten(du, dim)[1],
        }
        for formula in adjoint:
            total += _nonzero(explicit(lhs_minus_rhs(formula), {**env, **grads, "h": _hstep}))
    return total


def _cost_gradient(
    functions: dict[str, Any],
    values: dict[Any, Any],
    tails: list[tuple[int, int]],
    run: Callable[..., None],
    fresh: sp.Matrix,
    key: tuple[Any, ...],
) -> sp.Matrix:
    """Gradient of the displayed cost in the value ``key`` (a state x^a_k or a control u_k), the
    states of the given (sample, step) tails recomputed as functions of it.  The other values
    are constants of this partial derivative and are hidden behind symbols while differentiating.
    """
    hide, hidden = _hider()
    tail = {k: hide(v) for k, v in values.items()}
    tail[key] = fresh
    for a, k in tails:
        run(tail, a, k, tail[("x", a, k)])
    grad = _grad(_value(COST5.rhs, tail, functions), fresh)
    grad = grad.xreplace({d: v for v, d in hidden.items()})
    return grad.xreplace(dict(zip(fresh, values[key], strict=True)))


def _backprop_defect(
    endpoint: sp.Eq,
    signs: Sequence[int],
    running_cost: bool,
    layers: Sequence[sp.Eq] = (RESIDUAL_LAYER, PLAIN_LAYER),
    M: int = 2,
) -> int:
    """Networks of N = 2 displayed layers (generic sigma, h = 1), M samples, n = 2, random
    rational weights, inputs and target c, terminal cost phi(x) = |x - c|^2/2 and running cost
    g = 0 (the displayed no_running_cost) or g = (|x|^2 + |u|^2)/3.  Costates from the given
    endpoint condition and the costate equation p^a_k = dH/dx(p^a_{k+1}, x^a_k, u_k) of the
    displayed H; gradients of the displayed cost C in x^a_k and in u_k, the later states as
    functions of them.  Returns the number of entries of the displayed backprop and weights
    relations that fail for each sign s in ``signs``."""
    dim, N = 2, 2
    rng = np.random.default_rng(6)

    def rational(*shape: int) -> sp.Matrix:
        return sp.Matrix(
            *shape, [sp.Rational(int(v), 5) for v in rng.integers(-7, 8, int(np.prod(shape)))]
        )

    c = rational(dim, 1)
    if running_cost:

        def g(x: Any, u: Any) -> Any:
            return (_dot(x, x) + _dot(u, u)) / 3
    else:
        g = _define(G0, {})
    total = 0
    for shown in layers:
        f = _layer_function(shown, dim, sp.Integer(1))
        fn = _with_hamiltonians({"f": f, "g": g, "h": lambda u: sp.zeros(1, 1)})
        fn[r"\phi"] = lambda x: _dot(x - c, x - c) / 2
        values: dict[Any, Any] = {"N": N, "M": M, "s": _s}
        values.update({("u", k): rational(dim * dim + dim, 1) for k in range(N)})

        def run(values: dict[Any, Any], a: int, k: int, start: sp.Matrix, f: Any = f) -> None:
            values[("x", a, k)] = start
            for j in range(k, N):
                values[("x", a, j + 1)] = f(values[("x", a, j)], values[("u", j)])

        for a in range(1, M + 1):
            run(values, a, 0, rational(dim, 1))
        checks = []
        for a in range(1, M + 1):
            lhs, rhs = _instance(endpoint, {_a: a, _N: N})
            values[_key(lhs)] = _value(rhs, values, fn)
            for k in reversed(range(N)):
                lhs, rhs = _instance(_COSTATE5_EQ, {_a: a, _k: k})
                values[_key(lhs)] = _value(rhs, values, fn)
            for k in range(N + 1):
                xi = _vec("xi", dim)
                grad = _cost_gradient(fn, values, [(a, k)], run, xi, ("x", a, k))
                values[(str(_dCdx.label), a, k)] = grad
                checks.append(_instance(BACKPROP, {_a: a, _k: k}))
        for k in range(N):
            w = _vec("w", dim * dim + dim)
            grad = _cost_gradient(fn, values, [(a, k) for a in range(1, M + 1)], run, w, ("u", k))
            values[(str(_dCdu.label), k)] = grad
            checks.append(_instance(WEIGHTS, {_k: k}))
        for lhs, rhs in checks:
            gap = _minus(_value(lhs, values, fn), _value(rhs, values, fn))
            total += sum(_nonzero(gap.xreplace({_s: sign})) for sign in signs)
    return total


@D6.check(Level.EXACT_RATIONAL)
def d6_backprop_no_running_cost() -> int:
    """Both layers with a generic activation sigma, N = 2 layers, M = 2 samples, n = 2, random
    rational weights, inputs and target, phi = |x - c|^2/2, g = 0: with the displayed endpoint
    condition, the costates satisfy the displayed backprop relation at every layer and the weight
    gradients of the cost the displayed weights relation, for s = 1 (m8) and s = -1 (D5)."""
    return _backprop_defect(ENDPOINT_S, (1, -1), running_cost=False)


@D6.check(Level.EXACT_RATIONAL, form="printed")
def d6_printed_m8_running_cost() -> int:
    """The same computation (residual layer, one sample) with a running cost
    g = (|x|^2 + |u|^2)/3 and m8's endpoint condition: the backprop and weights relations with
    s = 1 fail (count of failing entries)."""
    return _backprop_defect(M8, (1,), running_cost=True, layers=(RESIDUAL_LAYER,), M=1)


@D6.check(Level.EXACT_RATIONAL, form="corrected")
def d6_corrected_running_cost() -> int:
    """The same with D5's endpoint condition: the backprop and weights relations with s = -1
    hold."""
    return _backprop_defect(ENDPOINT, (-1,), running_cost=True, layers=(RESIDUAL_LAYER,), M=1)


def _identity_defect(shown: sp.Eq) -> sp.Expr:
    """The displayed property of a residual layer evaluated on a displayed layer: its Jacobian in
    x at K = 0 (generic sigma, symbolic beta and h, n = 2) minus the identity (count of entries)."""
    env = _layer_env(2)
    J = (
        explicit(shown.rhs, {**env, "h": _hstep})
        .jacobian(env["x"])
        .xreplace({kij: 0 for kij in env["K"]})
    )
    return _nonzero(explicit(lhs_minus_rhs(IDENTITY), {IDENTITY.lhs.name: J}))


@D6.check(Level.SYMBOLIC_FIXED_N, form="printed")
def d6_printed_plain_is_not_residual() -> sp.Expr:
    """Remark 1's layer sigma(K x + beta) is not a perturbation of the identity: its Jacobian in x
    at K = 0 is 0, not I (count of mismatching entries, generic sigma, n = 2)."""
    return _identity_defect(PLAIN_LAYER)


@D6.check(Level.SYMBOLIC_FIXED_N, form="corrected")
def d6_residual_layer_is_residual() -> sp.Expr:
    """The residual layer x + h sigma(K x + beta) has Jacobian I in x at K = 0, for every beta and
    h (generic sigma, n = 2)."""
    return _identity_defect(RESIDUAL_LAYER)


def _reference_forward(x0, Ks, bs, act: str, residual_layer: bool) -> np.ndarray:
    """Independent plain-NumPy forward pass (complex-safe; no generated code): all states."""
    sig = np.tanh if act == "tanh" else (lambda z: 1.0 / (1.0 + np.exp(-z)))
    states = [x0]
    for K, b in zip(Ks, bs, strict=True):
        y = sig(states[-1] @ K.T + b)
        states.append(states[-1] + y if residual_layer else y)
    return np.stack(states)


def _reference_loss(x0, Ks, bs, targets, act: str, residual_layer: bool):
    return 0.5 * np.sum((_reference_forward(x0, Ks, bs, act, residual_layer)[-1] - targets) ** 2)


def complex_step_gradients(x0, Ks, bs, targets, act: str, residual_layer: bool, h: float = 1e-30):
    """dPhi/dK_k, dPhi/dbeta_k by the complex step Im Phi(w + i h e)/h (exact to round-off)."""
    Ks, bs = np.asarray(Ks, dtype=complex), np.asarray(bs, dtype=complex)
    gK, gb = np.zeros(Ks.shape), np.zeros(bs.shape)
    for arr, out in ((Ks, gK), (bs, gb)):
        for idx in np.ndindex(arr.shape):
            old = arr[idx]
            arr[idx] = old + 1j * h
            out[idx] = _reference_loss(x0, Ks, bs, targets, act, residual_layer).imag / h
            arr[idx] = old
    return gK, gb


def complex_step_state_gradients(states, Ks, bs, targets, act: str, residual_layer: bool,
                                 h: float = 1e-30) -> np.ndarray:  # fmt: skip
    """dPhi/dx^a_k for every layer k and sample a, by the complex step on the tail network."""
    out = np.zeros(states.shape)
    for k in range(len(Ks) + 1):
        for idx in np.ndindex(states.shape[1:]):
            xk = states[k].astype(complex)
            xk[idx] += 1j * h
            out[(k, *idx)] = (
                _reference_loss(xk, Ks[k:], bs[k:], targets, act, residual_layer).imag / h
            )
    return out


def random_network(seed: int, N: int = 4, M: int = 5, dim: int = 3, scale: float = 0.8):
    """(x0, K, beta, targets) with M samples of dimension dim and N layers."""
    rng = np.random.default_rng(seed)
    return (
        rng.standard_normal((M, dim)),
        scale * rng.standard_normal((N, dim, dim)),
        scale * rng.standard_normal((N, dim)),
        rng.standard_normal((M, dim)),
    )


@D6.check(Level.FLOAT64, tol=1e-12)
def d6_float64() -> float:
    """symrb.resnet_forward, symrb.costate_sweep and symrb.loss_gradients (both activations, both
    layers; n = 3, N = 4, M = 5, 2 random networks) against an independent NumPy forward pass and
    complex-step derivatives of its loss: states, -p (D5's sign) against dPhi/dx^a_k, and the
    weight gradients; largest error relative to the largest reference entry."""
    import symrb

    errors = []
    for seed, act, res in itertools.product(range(2), ACTIVATIONS, (True, False)):
        x0, Ks, bs, ys = random_network(seed)
        states = symrb.resnet_forward(x0, Ks, bs, activation=act, residual=res)
        p = symrb.costate_sweep(states, Ks, bs, ys, activation=act, residual=res)
        _loss, gK, gb = symrb.loss_gradients(x0, Ks, bs, ys, activation=act, residual=res)
        ref_states = _reference_forward(x0, Ks, bs, act, res)
        cK, cb = complex_step_gradients(x0, Ks, bs, ys, act, res)
        cx = complex_step_state_gradients(ref_states, Ks, bs, ys, act, res)
        for got, want in ((states, ref_states), (gK, cK), (gb, cb), (-p, cx)):
            errors.append(np.max(np.abs(got - want)) / np.max(np.abs(want)))
    return float(np.max(errors))
