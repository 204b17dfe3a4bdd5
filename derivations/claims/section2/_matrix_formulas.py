r"""The matrix notation of Sections 2.1 and 2.2 (D7-D12) and its evaluation.

The symbols of the displayed formulas (:math:`Q_k, P_{k+1}, U_k, \Omega_k, M_{k+1}`, ...), the
display node :class:`_MatrixFunction` for :math:`\exp` and :math:`\sinh^{-1}` of a matrix, the
float64 evaluation :func:`_numeric` of a displayed matrix expression, and exact rational rotations
(:func:`_cayley_rational`).  Private to the section's claims (and symrb's method checks).
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import sympy as sp
from scipy.linalg import expm, schur

from derivations.vocabulary import Arg, matrix

# the kernels' matrix arguments (J_D, mv2, mv3)
U, Om, M = matrix("U"), matrix("Omega"), matrix("M")
ARG_LAM = Arg("lam", "(..., n)", "diagonal of Lambda, positive")


# symbols of the displayed formulas (the paper's indices)
Qk, Qk1, Qkm1 = matrix("Q_k"), matrix("Q_{k+1}"), matrix("Q_{k-1}")
Pk, Pk1 = matrix("P_k"), matrix("P_{k+1}")
Uk, Omk, Omk1 = matrix("U_k"), matrix("Omega_k"), matrix(r"\Omega_{k+1}")
Mk, Mk1 = matrix("M_k"), matrix("M_{k+1}")
Q0, P0, M0 = matrix("Q_0"), matrix("P_0"), matrix("M_0")
_k, _r, _N = sp.symbols("k r N", integer=True)
_JD = sp.Function("J_D")
_LAM3 = np.array([0.7, 1.1, 1.6])


def _lam(k: int) -> list[sp.Symbol]:
    return list(sp.symbols(f"lam1:{k + 1}", positive=True))


class _MatrixFunction(sp.MatrixExpr):
    """exp or asinh of a square matrix expression, for displayed formulas (see :func:`_numeric`)."""

    _LATEX = {"exp": r"\exp", "asinh": r"\sinh^{-1}"}

    def __new__(cls, name: str | sp.Symbol, arg: sp.MatrixExpr) -> _MatrixFunction:
        return super().__new__(cls, sp.Symbol(str(name)), arg)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[1].shape

    def _latex(self, printer: Any) -> str:
        return rf"{self._LATEX[str(self.args[0])]}\left({printer._print(self.args[1])}\right)"


def _numeric(expr: sp.Basic, env: dict[str, np.ndarray], lam: np.ndarray | None = None) -> Any:
    """A displayed formula's matrix expression evaluated in float64 (NumPy) on ``env``.

    ``Lambda`` is ``diag(lam)``; matrix exp (:class:`_MatrixFunction`) is ``scipy.linalg.expm``
    and asinh of a normal matrix is applied to the eigenvalues of its complex Schur form.
    """
    if isinstance(expr, sp.MatrixSymbol):
        name = str(expr.name)
        if name == "Lambda":
            return np.diag(np.asarray(lam, dtype=float))
        return np.asarray(env[name], dtype=float)
    if isinstance(expr, sp.Identity):
        return np.eye(next(iter(env.values())).shape[-1])
    if isinstance(expr, sp.MatMul):
        coeff, mats = expr.as_coeff_matrices()
        out = _numeric(mats[0], env, lam)
        for m in mats[1:]:
            out = out @ _numeric(m, env, lam)
        return float(coeff) * out
    if isinstance(expr, sp.MatAdd):
        return sum(_numeric(a, env, lam) for a in expr.args)
    if isinstance(expr, sp.Transpose):
        return _numeric(expr.arg, env, lam).T
    if isinstance(expr, sp.Trace):
        return float(np.trace(_numeric(expr.arg, env, lam)))
    if isinstance(expr, _MatrixFunction):
        arg = _numeric(expr.args[1], env, lam)
        if str(expr.args[0]) == "exp":
            return expm(arg)
        # a normal matrix (skew here) has a diagonal complex Schur form T = Z^H arg Z
        T, Z = schur(arg.astype(complex), output="complex")
        if np.abs(np.triu(T, 1)).max() > 1e-12 * max(1.0, np.abs(T).max()):
            raise ValueError("asinh is evaluated here for normal matrices only")
        out = Z @ np.diag(np.arcsinh(np.diag(T))) @ Z.conj().T
        if np.abs(out.imag).max() > 1e-12 * max(1.0, np.abs(out).max()):
            raise ValueError("asinh of this matrix is not real")
        return out.real
    raise TypeError(f"_numeric: no rule for {type(expr).__name__} ({expr})")


def _cayley_rational(entries: list[int], denominator: int) -> sp.Matrix:
    """An exact rational rotation (I - A)^{-1}(I + A), A the skew matrix with the given entries."""
    k = int(round((1 + np.sqrt(1 + 8 * len(entries))) / 2))
    A = sp.zeros(k, k)
    for (i, j), e in zip(itertools.combinations(range(k), 2), entries, strict=True):
        A[i, j], A[j, i] = sp.Rational(e, denominator), -sp.Rational(e, denominator)
    return (sp.eye(k) - A).inv() * (sp.eye(k) + A)
