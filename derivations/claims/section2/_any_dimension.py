r"""The displayed formulas of Section 2 evaluated with vectors of symbolic dimension.

The fixed-n checks of D1 and D5 evaluate the paper's indexed formulas (:mod:`._indexed`) on
explicit vectors of R^2.  Here the same formula objects are evaluated on SymPy ``MatrixSymbol``
columns of symbolic size (:math:`x_k, p_k \in \mathbb{R}^n`, :math:`u_k \in \mathbb{R}^m`,
:math:`\sigma_k \in \mathbb{R}^l`, with :math:`n, m, l` symbols), so an identity found here holds
for every dimension.

Each expression is evaluated to a pair (value, first variation).  An undefined function at a point
is a fresh column named by that point (``f(x_1, u_1)``) and its variation is the chain rule with
one Jacobian ``MatrixSymbol`` per argument, also named by the point (``D_1 f(x_1, u_1)``, of size
output x argument); nothing else is assumed of :math:`f, g, h, \phi`.  A displayed
``Derivative(E, v)`` is the gradient of the variation of :math:`E` in :math:`\delta v` alone,
taken with SymPy's matrix calculus (``sp.diff`` in a ``MatrixSymbol``); the Hamiltonians
:math:`H, \hat H` are expanded from their displayed definitions.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef

from derivations.claims.section2._indexed import _Dot, _indexed_key, _key, _value

#: the symbolic dimensions of the state, control and constraint spaces
DIMS = sp.symbols("n m l", integer=True, positive=True)

Pair = tuple[Any, Any]


class Evaluator:
    """Evaluate displayed formulas to (value, variation) pairs on columns of symbolic size.

    ``columns`` maps the key of an indexed variable (``("x", 1)``, ``("p", 2, 1)``) to its
    ``MatrixSymbol``; ``frozen`` lists the keys of fixed data (no variation in a functional, but
    a displayed partial derivative may still be taken in them); ``outputs`` the
    output size of each undefined function; ``defined`` the displayed definitions of the defined
    functions (``H``, ``\\hat{H}``); ``scalars`` the values of plain symbols (``N``, a cost
    multiplier).
    """

    def __init__(
        self,
        columns: dict[Any, sp.MatrixSymbol],
        frozen: set[Any],
        outputs: dict[str, Any],
        defined: dict[str, sp.Eq],
        scalars: dict[str, Any],
    ) -> None:
        self.columns, self.frozen, self.outputs = columns, frozen, outputs
        self.defined, self.scalars = defined, scalars
        self.deltas = {
            key: sp.MatrixSymbol(f"delta {col.name}", *col.shape) for key, col in columns.items()
        }

    def free(self, key: Any) -> bool:
        """Whether a variable varies in a functional (it is not fixed data)."""
        return key not in self.frozen

    def delta(self, key: Any, live: Callable[[Any], bool]) -> Any:
        """The variation of a variable: its delta symbol if it varies here, else zero."""
        return self.deltas[key] if live(key) else sp.ZeroMatrix(*self.columns[key].shape)

    def __call__(
        self,
        e: Any,
        bound: dict[Any, Pair] | None = None,
        live: Callable[[Any], bool] | None = None,
    ) -> Pair:
        """(value, variation) of ``e``; ``bound`` gives the pairs of the parameters of a
        definition being expanded; ``live(key)`` says which variables vary (by default those
        that are not fixed data)."""
        bound = bound or {}
        live = live or self.free
        if isinstance(e, sp.Indexed):
            key = _indexed_key(e, self.scalars, {})
            return self.columns[key], self.delta(key, live)
        if isinstance(e, sp.Symbol):
            if _key(e) in bound:
                return bound[_key(e)]
            if e.name in self.columns:
                return self.columns[e.name], self.delta(e.name, live)
            return self.scalars[e.name], 0
        if isinstance(e, sp.Number):
            return e, 0
        if isinstance(e, _Dot):
            (a, da), (b, db) = (self(x, bound, live) for x in e.args)
            return a.T * b, _add(_mul(_t(da), b), _mul(a.T, db))
        if isinstance(e, sp.Sum):
            return self._sum(e, bound, live)
        if isinstance(e, sp.Derivative):
            return self._derivative(e, bound, live), None
        if isinstance(e, AppliedUndef):
            return self._function(e, bound, live)
        pairs = [self(x, bound, live) for x in e.args]
        if isinstance(e, sp.Add):
            return _fold(_add, [v for v, _ in pairs]), _fold(_add, [d for _, d in pairs])
        if isinstance(e, sp.Mul):
            consts = [v for v, d in pairs if d == 0 and not isinstance(v, sp.MatrixExpr)]
            rest = [p for p in pairs if not (p[1] == 0 and not isinstance(p[0], sp.MatrixExpr))]
            if len(rest) != 1:
                raise TypeError(f"only a constant times one quantity is supported: {e}")
            c = sp.Mul(*consts)
            return _mul(c, rest[0][0]), _mul(c, rest[0][1])
        raise TypeError(f"no rule for {type(e).__name__} ({e})")

    def _sum(self, e: sp.Sum, bound: dict[Any, Pair], live: Callable[[Any], bool]) -> Pair:
        term, *limits = e.args
        (k, lo, hi), rest = limits[0], limits[1:]
        inner = sp.Sum(term, *rest) if rest else term
        lo, hi = (int(_value(x, self.scalars, {})) for x in (lo, hi))
        pairs = [self(inner.xreplace({k: sp.Integer(j)}), bound, live) for j in range(lo, hi + 1)]
        return _fold(_add, [v for v, _ in pairs]), _fold(_add, [d for _, d in pairs])

    def _function(
        self, e: AppliedUndef, bound: dict[Any, Pair], live: Callable[[Any], bool]
    ) -> Pair:
        name = e.func.__name__
        args = [self(x, bound, live) for x in e.args]
        if name in self.defined:
            formula = self.defined[name]
            params = {_key(p): a for p, a in zip(formula.lhs.args, args, strict=True)}
            return self(formula.rhs, params, live)
        point = ", ".join(str(v) for v, _ in args)
        size = self.outputs[name]
        value = sp.MatrixSymbol(f"{name}({point})", size, 1)
        variation: Any = 0
        for i, (v, d) in enumerate(args, start=1):
            jac = sp.MatrixSymbol(f"D_{i} {name}({point})", size, v.shape[0])
            variation = _add(variation, _mul(jac, d))
        return value, variation

    def _derivative(
        self, e: sp.Derivative, bound: dict[Any, Pair], live: Callable[[Any], bool]
    ) -> Any:
        ((var, count),) = e.variable_count
        if count != 1:
            raise TypeError("only first derivatives are displayed in D1 and D5")
        key = _indexed_key(var, self.scalars, {})
        _value, variation = self(e.expr, bound, lambda k: k == key)
        return gradient(variation, self.deltas[key])


def _t(d: Any) -> Any:
    return d.T if isinstance(d, sp.MatrixExpr) else d


def _is_zero(d: Any) -> bool:
    return (not isinstance(d, sp.MatrixExpr) and d == 0) or isinstance(d, sp.ZeroMatrix)


def _mul(a: Any, b: Any) -> Any:
    if a is None or b is None:  # the variation of a displayed derivative is not needed
        return None
    if _is_zero(a) or _is_zero(b):
        return 0
    return a * b


def _add(a: Any, b: Any) -> Any:
    if a is None or b is None:
        return None
    if _is_zero(a):
        return b
    if _is_zero(b):
        return a
    return a + b


def _fold(op: Callable[[Any, Any], Any], items: list[Any]) -> Any:
    out: Any = 0
    for x in items:
        out = op(out, x)
    return out


def gradient(variation: Any, delta: sp.MatrixSymbol) -> Any:
    """The gradient of a scalar (1 x 1) first variation in ``delta`` (matrix calculus); zero
    when ``delta`` does not occur."""
    if _is_zero(variation) or not variation.has(delta):
        return sp.ZeroMatrix(*delta.shape)
    return sp.diff(variation, delta)


def nonzero(expr: Any) -> int:
    """1 if the matrix expression does not reduce to the zero matrix (0 for a scalar 0)."""
    if _is_zero(expr):
        return 0
    reduced = sp.expand(expr.doit()) if isinstance(expr, sp.MatrixExpr) else sp.expand(expr)
    return 0 if _is_zero(reduced) else 1


def minus(a: Any, b: Any) -> Any:
    """a - b for the two evaluated sides of a displayed relation (``= 0`` sides are 0)."""
    return _add(a, _mul(-1, b))
