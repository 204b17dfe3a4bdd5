"""Display objects of Section 3: SymPy nodes that print as the paper writes them.

The evidence never evaluates these nodes directly: each claim module says what it means (the
registered formula it unfolds to, or the NumPy it is computed with).  The classes of Section 3.4
keep their leading underscore: SymPy orders the arguments of a sum or a product by class name, so a
rename would reorder the displayed formulas.
"""

from __future__ import annotations

from typing import Any

import sympy as sp


class GlPair(sp.Expr):
    """The pairing of two matrices on gl(n), shown with angle brackets; its meaning is the
    registered formula S5 ``pairing`` (see :func:`unfold`)."""

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
    :func:`~derivations.claims.section3.s10_asinh_solution.evaluate` evaluates it."""

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
    """d/dt of a matrix expression (display; :func:`ddt` computes it along a vector field)."""

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


def sample_sum(expr: sp.Basic, index: sp.Symbol) -> sp.Basic:
    if isinstance(expr, sp.MatrixExpr):
        return _SampleSumMatrix(expr, index)
    return _SampleSumScalar(expr, index)


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


def minus(a: sp.MatrixExpr, b: sp.MatrixExpr) -> sp.MatrixExpr:
    return _Minus(a, b)
