"""The shared vocabulary of the derivations: symbols, shapes, the inertia auxiliaries and the
:class:`Kernel` declaration.

Every other module of :mod:`derivations` may import this one; it imports nothing of
:mod:`derivations` itself, so it sits at the bottom of the one-way import graph::

    vocabulary  <-  symbolic  <-  registry  <-  printer  <-  text/report  <-  cli

A claim module declares its kernels here (:class:`Kernel`, :class:`Arg`, :func:`matrix`, ...);
:mod:`derivations.printer` prints them and :mod:`derivations.registry` finds them.
"""

from __future__ import annotations

import contextvars
import itertools
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction

__all__ = [
    "n",
    "Arg",
    "Aux",
    "AUXILIARIES",
    "Kernel",
    "matrix",
    "vector",
    "Lam",
    "W",
    "Jinv",
    "entrywise",
    "KERNELS",
    "CURRENT_CLAIM",
]

#: The symbolic matrix size used by every matrix-level kernel.
n = sp.Symbol("n", integer=True, positive=True)


def matrix(name: str) -> sp.MatrixSymbol:
    """An ``n x n`` matrix symbol (a kernel argument or a symbol of a displayed formula)."""
    return sp.MatrixSymbol(name, n, n)


def vector(name: str) -> sp.MatrixSymbol:
    """An ``n x 1`` column vector symbol."""
    return sp.MatrixSymbol(name, n, 1)


# ---------------------------------------------------------------------------------------------
# auxiliary matrices computed from lam


@dataclass(frozen=True)
class Aux:
    """An ``n x n`` matrix computed inside a kernel from the 1-D diagonal ``lam`` of Lambda.

    ``entry(li, lj, same)`` gives the (i, j) entry in terms of the scalars ``li = lam_i``,
    ``lj = lam_j`` (``same`` is 1 on the diagonal and 0 off it).  The fixed-n evidence builds the
    explicit matrix from it, and the printer prints its code from it.  A diagonal auxiliary is
    never formed: a product with it is printed as a row or column scaling by ``diagonal``.
    """

    name: str
    entry: Callable[[sp.Expr, sp.Expr, sp.Expr], sp.Expr]
    diagonal: Callable[[sp.Expr], sp.Expr] | None = None
    latex: str = ""

    @property
    def symbol(self) -> sp.MatrixSymbol:
        return matrix(self.name)

    def explicit(self, lam: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
        k = len(lam)
        return sp.ImmutableMatrix(
            k, k, lambda i, j: self.entry(lam[i], lam[j], sp.Integer(int(i == j)))
        )


_LI, _LJ = sp.symbols("lam_i lam_j", real=True)

#: The auxiliaries every kernel may use.  ``Lambda`` = diag(lam); ``W_ij = 1/(lam_i + lam_j)``.
AUXILIARIES: dict[str, Aux] = {
    "Lambda": Aux(
        "Lambda", lambda li, lj, same: same * li, diagonal=lambda li: li, latex=r"\Lambda"
    ),
    "W": Aux("W", lambda li, lj, same: 1 / (li + lj), latex="W"),
}
Lam = AUXILIARIES["Lambda"].symbol
W = AUXILIARIES["W"].symbol


def Jinv(X: sp.MatrixExpr) -> sp.MatrixExpr:
    r"""The inverse inertia operator :math:`J^{-1}(X)_{ij} = X_{ij}/(\lambda_i+\lambda_j)` as
    the Hadamard product ``W o X`` (this is how every kernel computes it)."""
    return sp.HadamardProduct(W, X)


# ---------------------------------------------------------------------------------------------
# entrywise scalar functions (activations)


class _Entrywise(sp.MatrixExpr):
    """A named scalar function applied entrywise (an opaque node for CSE; see :func:`entrywise`)."""

    def __new__(cls, name: str | sp.Symbol, arg: sp.MatrixExpr) -> _Entrywise:
        # sympy.cse rebuilds nodes as node.func(*node.args): accept the Symbol it holds
        return super().__new__(cls, sp.Symbol(str(name)), arg)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[1].shape

    def _entry(self, i: Any, j: Any, **kwargs: Any) -> sp.Expr:
        return _ENTRYWISE[str(self.args[0])](self.args[1]._entry(i, j, **kwargs))


_ENTRYWISE: dict[str, sp.Lambda] = {}


def entrywise(name: str, fn: sp.Lambda, arg: sp.MatrixExpr) -> sp.MatrixExpr:
    """``fn`` applied to every entry of ``arg`` (SymPy's :class:`ElementwiseApplyFunction`)."""
    _ENTRYWISE[name] = fn
    return ElementwiseApplyFunction(fn, arg)


# ---------------------------------------------------------------------------------------------
# kernels


@dataclass(frozen=True)
class Arg:
    """A kernel argument: its name, documented shape (e.g. ``"(..., n, n)"``) and meaning."""

    name: str
    shape: str
    doc: str


CURRENT_CLAIM: contextvars.ContextVar[str | None] = contextvars.ContextVar(
    "symrb_current_claim", default=None
)
KERNELS: list[Kernel] = []
_counter = itertools.count()


@dataclass(eq=False)
class Kernel:
    """A function to emit: one object, checked by the evidence of ``claims`` and printed.

    Parameters
    ----------
    name : the function name in ``symrb/_generated/<target>.py``
    target : the generated module it goes to
    args : the arguments, in order (``lam`` for kernels that use an auxiliary)
    outputs : output name -> SymPy expression; one output is returned as is, several as a tuple
    doc : one-line summary (plain text, math in ASCII), then optional paragraphs
    claims : the claims whose evidence evaluates these expressions (a test checks that each of
        them really does, see :func:`checked_by`)
    stack : stack scalar outputs along a new last axis instead of returning a tuple
    components : argument name -> Matrix of scalar symbols for its entries (``arg[..., i, j]`` or
        ``arg[..., i]``); such kernels are printed through scalar CSE
    register : False for a kernel that is only rendered (tests), never emitted
    convert : False to skip the ``numpy.asarray`` conversion of the arguments, for scalar
        kernels called with Python floats as well as arrays (a hot loop on one body: arithmetic
        on 0-d arrays costs about 1 us an operation, on floats about 50 ns)

    Reading an output with ``kernel["name"]`` records which claim's evidence is running (the
    registry sets it), so ``symrb verify`` can list, for every kernel, the claims that checked it.
    """

    name: str
    target: str
    args: Sequence[Arg]
    outputs: dict[str, sp.Basic]
    doc: str
    claims: tuple[str, ...]
    stack: bool = False
    components: dict[str, sp.Matrix] = field(default_factory=dict)
    source: str = ""
    register: bool = True
    convert: bool = True
    checked_by: set[str] = field(default_factory=set)
    order: int = field(default_factory=lambda: next(_counter))

    def __post_init__(self) -> None:
        if not self.claims:
            raise ValueError(f"kernel {self.name}: name the claim(s) whose evidence checks it")
        if not self.source:
            frame = sys._getframe(2)
            self.source = str(frame.f_globals.get("__name__", ""))
        if self.register:  # register=False: a kernel rendered by a test, never emitted
            KERNELS.append(self)

    def __getitem__(self, key: str) -> sp.Basic:
        claim = CURRENT_CLAIM.get()
        if claim is not None:
            self.checked_by.add(claim)
        return self.outputs[key]

    def __repr__(self) -> str:
        return f"Kernel({self.target}.{self.name}, claims={self.claims})"
