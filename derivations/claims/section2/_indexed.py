r"""The paper's indexed notation of Section 2 as SymPy objects, and their evaluation.

The displayed formulas of D1-D6 are written in the paper's notation: :math:`x_k`,
:math:`p^a_{k+1}` (:class:`_Sample`), sums over steps and samples, relations that hold over a
range of steps (:class:`_Steps`), dot products (:class:`_Dot`) and undefined functions
:math:`f, g, h, \phi`.  The evidence evaluates those same objects with :func:`_value` on explicit
vectors and functions, so a summation range, an index or a sign shown in the book is the one that
was checked.  The names keep their leading underscore: they are private to the section's claims.
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Callable, Sequence
from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef

from derivations.symbolic import explicit

_k, _N, _a, _M = sp.symbols("k N a M", integer=True)
_INDEX = {"k": _k, "a": _a}
# k + 1, N - 1, N + 1 unevaluated, so that they print in this order (substituting k or N evaluates)
_k1, _Nm1, _N1 = (sp.Add(s, c, evaluate=False) for s, c in ((_k, 1), (_N, -1), (_N, 1)))


def _plus(*terms: sp.Expr) -> sp.Expr:
    """A sum printed in the order written."""
    return sp.Add(*terms, evaluate=False)


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
    if isinstance(a, sp.MatrixExpr):  # symbolic dimension: a 1 x 1 matrix expression
        return a.T * b
    return a * b


def _fresh(point: Any, tag: int) -> Any:
    if isinstance(point, sp.MatrixBase):
        return sp.Matrix(point.rows, 1, [sp.Dummy(f"d{tag}_{i}") for i in range(point.rows)])
    if isinstance(point, sp.MatrixExpr):
        return sp.MatrixSymbol(sp.Dummy(f"d{tag}"), *point.shape)
    return sp.Dummy(f"d{tag}")


def _grad(value: Any, var: Any) -> Any:
    """Derivative of a scalar (gradient), vector (Jacobian) or scalar-variable expression.

    For a vector of symbolic dimension (a ``MatrixSymbol``) SymPy's matrix calculus is used: the
    gradient of a 1 x 1 expression, the Jacobian (rows: the components) of a vector one."""
    if isinstance(var, sp.MatrixSymbol):
        if not value.has(var):
            return (
                sp.ZeroMatrix(var.rows, 1)
                if value.shape == (1, 1)
                else sp.ZeroMatrix(value.rows, var.rows)
            )
        d = sp.diff(value, var)
        return d if value.shape == (1, 1) else d.T  # sp.diff gives the transposed Jacobian
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
        if isinstance(v, sp.MatrixExpr):  # symbolic dimension: nothing to expand
            return v
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
