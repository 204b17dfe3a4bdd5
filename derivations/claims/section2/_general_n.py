r"""Index-free evaluation for the every-n evidence of Section 2 (D2, D3, D4, D6).

The displayed formulas of D2-D6 are evaluated on matrix symbols of symbolic size (``n``, ``m``,
layer widths) and the results compared as polynomials in noncommutative letters, so an identity
that reduces to zero holds for every dimension.  Three tools:

* :class:`Alphabet`: the letters (a :class:`~derivations.symbolic.Words` alphabet) with inverses
  that cancel, :math:`XX^{-1} = X^{-1}X = 1`, and entrywise functions as letters:
  :math:`\sigma(z)` is a vector letter and :math:`\sigma'(z)\circ v` is :math:`D\,v` with
  :math:`D = \mathrm{diag}(\sigma'(z))` a symmetric letter, one per argument :math:`z` (keyed by
  the reduced polynomial of :math:`z`, so equal arguments written differently share a letter).
* :func:`directional`: the derivative :math:`\frac{d}{dt}F(v + t\,dv)|_{t=0}` of a matrix
  expression, by SymPy's differentiation in the scalar :math:`t` (product and chain rules, and
  :math:`\frac{d}{dt}\sigma(z) = \sigma'(z)\circ\dot z` for an entrywise function).
* :func:`pairing_defect`: the number of trace words by which two scalar polynomials, linear in a
  direction :math:`dv`, differ; a scalar is its own trace and its own transpose, so a word with
  :math:`dv^T` is transposed first and words are compared up to cyclic rotation.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction

from derivations.claims.section2._hamiltonians import REDUCED, _with_hamiltonians
from derivations.claims.section2._indexed import _define
from derivations.symbolic import Words, letters_of, trace_words_of
from derivations.vocabulary import n

_t = sp.Symbol("t")
#: the size of the control u (the state has size n)
m = sp.Symbol("m", integer=True, positive=True)


class Alphabet(Words):
    """Noncommutative letters with transposes (see :class:`~derivations.symbolic.Words`), plus
    inverse letters ``X^{-1}`` that cancel against ``X`` and entrywise functions as letters."""

    def __init__(self, symmetric: Iterable[str] = (), invertible: Iterable[str] = ()) -> None:
        sym = set(symmetric)
        inv = set(invertible)
        super().__init__(symmetric=sym | {f"{x}^{{-1}}" for x in inv & sym})
        self._pairs: set[tuple[sp.Expr, sp.Expr]] = set()
        for name in inv:
            x, xi = self(name), self(f"{name}^{{-1}}")
            self._pairs |= {(x, xi), (xi, x), (self._T[x], self._T[xi]), (self._T[xi], self._T[x])}
        self._entrywise: dict[tuple[str, sp.Expr], sp.Symbol] = {}

    def reduce(self, expr: sp.Expr) -> sp.Expr:
        """Expand and cancel adjacent ``X X^{-1}`` and ``X^{-1} X`` (and their transposes)."""
        total = sp.Integer(0)
        for term in sp.Add.make_args(sp.expand(expr)):
            c, word = letters_of(term)
            i = 0
            while i < len(word) - 1:
                if (word[i], word[i + 1]) in self._pairs:
                    word = word[:i] + word[i + 2 :]
                    i = max(i - 1, 0)
                else:
                    i += 1
            total += c * sp.Mul(*word)
        return sp.expand(total)

    def is_zero(self, expr: sp.Expr) -> sp.Integer:
        """0 when ``expr`` reduces to zero, else the number of words left."""
        left = self.reduce(expr)
        return sp.Integer(len(sp.Add.make_args(left)) if left != 0 else 0)

    def _function_letter(self, head: str, arg: sp.Expr, diagonal: bool) -> sp.Symbol:
        key = (head + ("[diag]" if diagonal else ""), self.reduce(arg))
        if key not in self._entrywise:
            name = f"{head}_{{{len(self._entrywise)}}}"
            if diagonal:  # diag(sigma'(z)) is symmetric
                self.symmetric.add(name)
            self._entrywise[key] = self(name)
        return self._entrywise[key]

    def nc(self, e: sp.Basic) -> sp.Expr:
        """A matrix expression (symbolic sizes) as a reduced noncommutative polynomial."""
        return self.reduce(self._of(e, None))

    def _of(self, e: sp.Basic, Lam: Any) -> sp.Expr:
        """:meth:`Words._of`, with inverses and entrywise functions (and their Hadamard products
        with a column) as letters of their own; Words' cases recurse back through here."""
        if isinstance(e, sp.Inverse):
            base = e.arg.arg if isinstance(e.arg, sp.Transpose) else e.arg
            inv = self(f"{base.name}^{{-1}}")
            return self.T(inv) if isinstance(e.arg, sp.Transpose) else inv
        if isinstance(e, (sp.HadamardProduct, ElementwiseApplyFunction)) and e.shape[0] == 1:
            # a row: the transpose of the column form (sigma(z^T) = sigma(z)^T, D diagonal)
            return self.T(self._of(e.func(*[_transposed(a) for a in e.args]), Lam))
        if isinstance(e, sp.HadamardProduct) and len(e.args) == 2:
            fun = [a for a in e.args if isinstance(a, ElementwiseApplyFunction)]
            if fun:
                other = e.args[1] if e.args[0] is fun[0] else e.args[0]
                head = str(fun[0].function.expr.func)
                letter = self._function_letter(head, self._of(fun[0].expr, Lam), True)
                return letter * self._of(other, Lam)
        if isinstance(e, ElementwiseApplyFunction):
            head = str(e.function.expr.func)
            return self._function_letter(head, self._of(e.expr, Lam), False)
        return super()._of(e, Lam)


def _transposed(a: sp.Basic) -> sp.Basic:
    """A matrix argument transposed; the function of an entrywise application is kept."""
    return a.T if isinstance(a, sp.MatrixExpr) else a


def directional(expr: sp.Basic, moves: dict[sp.MatrixSymbol, sp.MatrixExpr]) -> sp.Basic:
    """d/dt of ``expr`` with each symbol v replaced by v + t dv, at t = 0."""
    moved = expr.xreplace({v: v + _t * dv for v, dv in moves.items()})
    return sp.diff(moved, _t).xreplace({_t: sp.Integer(0)})


def _oriented(expr: sp.Expr, direction: sp.Symbol, alphabet: Alphabet) -> sp.Expr:
    """A scalar polynomial with every word that holds the transposed direction transposed."""
    dT = alphabet.T(direction)
    total = sp.Integer(0)
    for term in sp.Add.make_args(alphabet.reduce(expr)):
        _c, word = letters_of(term)
        total += alphabet.T(term) if dT in word else term
    return total


def pairing_defect(a: sp.Expr, b: sp.Expr, direction: sp.Symbol, alphabet: Alphabet) -> int:
    """Number of cyclic trace words of ``a - b`` (scalars linear in ``direction``) left after each
    word holding the transposed direction is transposed: 0 when a = b for every dimension."""
    return len(
        trace_words_of(_oriented(a, direction, alphabet) - _oriented(b, direction, alphabet))
    )


def frobenius(X: sp.Expr, dX: sp.Symbol, alphabet: Alphabet) -> sp.Expr:
    """<X, dX> = tr(X^T dX) as a polynomial (a trace word: compared with :func:`pairing_defect`)."""
    return alphabet.T(X) * dX


def blocks(e: sp.Basic, env: dict[str, sp.Matrix], alphabet: Alphabet) -> sp.Matrix:
    """A matrix expression in block matrices: ``env`` maps a matrix symbol's name to its blocks
    (a SymPy matrix of noncommutative polynomials); a transpose transposes the blocks too."""
    if isinstance(e, sp.MatrixSymbol):
        return env[str(e.name)]
    if isinstance(e, sp.BlockMatrix):
        return e.blocks.applyfunc(alphabet.nc)
    if isinstance(e, sp.Transpose):
        b = blocks(e.arg, env, alphabet)
        return sp.Matrix(b.cols, b.rows, lambda i, j: alphabet.T(b[j, i]))
    if isinstance(e, sp.MatMul):
        coeff, mats = e.as_coeff_matrices()
        out = blocks(mats[0], env, alphabet)
        for m in mats[1:]:
            out = out * blocks(m, env, alphabet)
        return coeff * out
    if isinstance(e, sp.MatAdd):
        parts = [blocks(a, env, alphabet) for a in e.args]
        return sum(parts[1:], parts[0])
    raise TypeError(f"blocks: no rule for {type(e).__name__}")


def quadratic_problem() -> tuple[dict[str, Any], dict[str, sp.MatrixSymbol], Alphabet]:
    """f = A x + B u, g = x^T P x/2 + x^T S u + u^T R u/2 with matrix symbols of sizes n x n,
    n x m, n x n, n x m, m x m (P, R symmetric, R invertible), no constraint (h = 0, sigma = 0),
    u* = R^-1 (B^T y - S^T x): the functions f, g, h, H, Hhat, u*, sigma, H* (H and H* from the
    displayed formulas), the symbols y, x, A, B, P, S, R and the alphabet.

    This is the second-order Taylor polynomial of any problem at a point (H is linear in y; linear
    terms of g change no second derivative): what first derivatives of the step and second
    derivatives of H* at a point involve."""
    sym = {c: sp.MatrixSymbol(c, r, k) for c, r, k in
           (("y", n, 1), ("x", n, 1), ("A", n, n), ("B", n, m), ("P", n, n), ("S", n, m),
            ("R", m, m))}  # fmt: skip
    A, B, P, S, R = (sym[c] for c in "ABPSR")
    fn = _with_hamiltonians({
        "f": lambda x, u: A * x + B * u,
        "g": lambda x, u: x.T * P * x / 2 + x.T * S * u + u.T * R * u / 2,
        "h": lambda u: sp.ZeroMatrix(1, 1),
    })  # fmt: skip
    fn["u^*"] = lambda y, x: R.I * (B.T * y - S.T * x)
    fn[r"\sigma"] = lambda y, x: sp.ZeroMatrix(1, 1)
    fn["H^*"] = _define(REDUCED, fn)
    return fn, sym, Alphabet(symmetric=["P", "R"], invertible=["R"])


def gradient(scalar: sp.Expr, direction: sp.Symbol, alphabet: Alphabet) -> sp.Expr:
    """The vector g with scalar = g^T direction, for a scalar polynomial linear in
    ``direction``: each word is oriented to end with the direction (a scalar is its own
    transpose) and the rest of it, transposed, is a term of g."""
    total = sp.Integer(0)
    for term in sp.Add.make_args(_oriented(scalar, direction, alphabet)):
        c, word = letters_of(term)
        if not word or word[-1] != direction or direction in word[:-1]:
            raise ValueError(f"{term} is not linear in {direction} at the right end")
        total += c * alphabet.T(sp.Mul(*word[:-1]))
    return sp.expand(total)


def substitute(poly: sp.Expr, letter: sp.Symbol, value: sp.Expr, alphabet: Alphabet) -> sp.Expr:
    """The polynomial with a letter and its transpose letter replaced by a polynomial and its
    transpose."""
    return alphabet.reduce(poly.xreplace({letter: value, alphabet.T(letter): alphabet.T(value)}))
