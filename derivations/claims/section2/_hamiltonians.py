r"""The Hamiltonians of Section 2 (shared by D1-D6) and generic problem data.

Conventions (stated on the book pages): :math:`H(y,x,u) = \langle y, f(x,u)\rangle - g(x,u)` as
printed (eq8.4), with :math:`y` the costate :math:`p_{k+1}`, and :math:`\hat H = H + \langle
\sigma, h(u)\rangle` (eq8.5); the problems are minimisations, so the augmented functionals whose
critical points give the extremal equations are *minus* the cost plus multiplier terms;
:math:`H^*(y,x) = \hat H(y,x,u^*(y,x),\sigma(y,x))` is the reduced Hamiltonian and
:math:`(H^*_{xy})_{ij} = \partial^2H^*/\partial x_i\partial y_j`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp

from derivations.claims.section2._indexed import _define, _Dot, _plus, _Sample, _vec
from derivations.symbolic import eq

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
