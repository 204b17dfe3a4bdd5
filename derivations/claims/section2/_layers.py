r"""The ResNet layer and its adjoint at matrix level (D6).

One function, :func:`layer`, builds both the displayed generic layer (activation :math:`\sigma`,
step :math:`h`) and the expressions of the emitted kernels (tanh and the logistic function), so
what the book shows and what is emitted are one construction.  :func:`_layer_env` and
:func:`_layer_function` give the explicit entries of a layer and a displayed layer as a function
:math:`f(x, u)` of explicit vectors, for the evidence.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction

from derivations.claims.section2._indexed import _vec
from derivations.symbolic import explicit
from derivations.vocabulary import entrywise, matrix, vector

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


def _layer_env(dim: int) -> dict[str, sp.Matrix]:
    return {
        "K": sp.Matrix(dim, dim, lambda i, j: sp.Symbol(f"k{i}{j}", real=True)),
        "x": _vec("x", dim),
        "beta": _vec("b", dim),
        "p": _vec("p", dim),
    }


def _unflatten(u: sp.Matrix, dim: int) -> tuple[sp.Matrix, sp.Matrix]:
    return sp.Matrix(dim, dim, list(u[: dim * dim])), sp.Matrix(list(u[dim * dim :]))


def _layer_function(shown: sp.Eq, dim: int, h: Any) -> Callable[..., Any]:
    """f(x, u) of a displayed layer, u the vector of the entries of K (row-major) and beta."""

    def f(x: sp.Matrix, u: sp.Matrix) -> sp.Matrix:
        K, beta = _unflatten(u, dim)
        return explicit(shown.rhs, {"x": x, "K": K, "beta": beta, "h": h})

    return f
