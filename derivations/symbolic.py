"""Small symbolic toolbox shared by the derivation modules.

* explicit matrices with symbolic entries (skew, diagonal, general) for fixed-n checks;
* the pairing, hat/vee, commutators on explicit SymPy matrices;
* noncommutative words: expansion of (A + l B)^k, reduction of trace words up to cyclic rotation
  (and reversal for skew/symmetric letters), and conversion to matrix expressions for codegen.
"""

from __future__ import annotations

import itertools
from collections import defaultdict
from collections.abc import Sequence

import sympy as sp

__all__ = [
    "skew_matrix",
    "diag_matrix",
    "general_matrix",
    "sym_vector",
    "pair",
    "comm",
    "hat3",
    "vee3",
    "residual",
    "skew_gradient",
    "trace_words",
]


def skew_matrix(name: str, n: int) -> sp.Matrix:
    """An n x n skew matrix with independent entries name_ij (i < j)."""
    m = sp.zeros(n, n)
    for i, j in itertools.combinations(range(n), 2):
        s = sp.Symbol(f"{name}{i + 1}{j + 1}", real=True)
        m[i, j], m[j, i] = s, -s
    return m


def diag_matrix(name: str, n: int, positive: bool = True) -> sp.Matrix:
    return sp.diag(*[sp.Symbol(f"{name}{i + 1}", positive=positive) for i in range(n)])


def general_matrix(name: str, n: int, m: int | None = None) -> sp.Matrix:
    m = n if m is None else m
    return sp.Matrix(n, m, lambda i, j: sp.Symbol(f"{name}{i + 1}{j + 1}", real=True))


def sym_vector(name: str, n: int) -> sp.Matrix:
    return sp.Matrix([sp.Symbol(f"{name}{i + 1}", real=True) for i in range(n)])


def pair(a: sp.Matrix, b: sp.Matrix) -> sp.Expr:
    """<a, b> = -1/2 trace(a b)."""
    return -sp.Rational(1, 2) * (a * b).trace()


def comm(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return a * b - b * a


def hat3(v: Sequence[sp.Expr]) -> sp.Matrix:
    x, y, z = v
    return sp.Matrix([[0, -z, y], [z, 0, -x], [-y, x, 0]])


def vee3(m: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([m[2, 1], m[0, 2], m[1, 0]])


def skew_gradient(F: sp.Expr, X: sp.Matrix) -> sp.Matrix:
    """The skew G with <G, dX> = dF for the pairing -1/2 tr on so(n), where X is a skew matrix of
    independent entries x_ij (i < j): G_ij = dF/dx_ij, G_ji = -G_ij."""
    nn = X.rows
    G = sp.zeros(nn, nn)
    for i, j in itertools.combinations(range(nn), 2):
        d = sp.diff(F, X[i, j])
        G[i, j], G[j, i] = d, -d
    return G


def residual(expr: sp.Basic | sp.Matrix) -> sp.Expr:
    """The sum of |entries| of ``expr`` after full expansion and simplification (0 iff identity).

    Returns a SymPy number: zero when the identity holds; otherwise a non-zero expression is
    replaced by 1 (a symbolic identity either holds or it does not).
    """
    items = list(expr) if isinstance(expr, sp.MatrixBase) else [expr]
    total = sp.Integer(0)
    for item in items:
        e = sp.expand(item)
        if e != 0:
            e = sp.simplify(e)
        if e != 0:
            total += 1
    return total


def _canonical(
    word: tuple[str, ...], sign_of_reversal: dict[str, int] | None
) -> tuple[tuple[str, ...], int]:
    """Canonical representative of a trace word under rotation (and reversal with transposes).

    trace(w) is invariant under cyclic rotation; if every letter X satisfies X^T = s_X X, then
    trace(w) = trace(w^T) = prod(s_X) trace(reverse(w)).  Returns (representative, sign).
    """
    rots = [word[i:] + word[:i] for i in range(len(word))]
    best = min(rots)
    sign = 1
    if sign_of_reversal is not None:
        rev = tuple(reversed(word))
        rrots = [rev[i:] + rev[:i] for i in range(len(rev))]
        rbest = min(rrots)
        rsign = 1
        for letter in word:
            rsign *= sign_of_reversal[letter]
        if rbest < best:
            best, sign = rbest, rsign
        elif rbest == best and rsign == -1:
            sign = 0  # trace(w) = -trace(w): the word vanishes identically
    return best, sign


def trace_words(
    letters: dict[str, sp.Expr],
    power: int,
    param: sp.Symbol,
    transpose_sign: dict[str, int] | None = None,
) -> dict[int, dict[tuple[str, ...], sp.Expr]]:
    """Coefficients of ``param^j`` in trace((sum_X c_X X)^power) as sums of trace words.

    ``letters`` maps a letter name to its scalar coefficient (a polynomial in ``param``), e.g.
    ``{"M": 1, "A": l}`` for M + l A.  The result maps j to ``{canonical word: coefficient}``;
    words whose coefficient cancels under the rotation/reversal symmetry are dropped.
    """
    acc: dict[int, dict[tuple[str, ...], sp.Expr]] = defaultdict(
        lambda: defaultdict(lambda: sp.Integer(0))
    )
    for word in itertools.product(sorted(letters), repeat=power):
        coeff = sp.expand(sp.Mul(*[letters[x] for x in word]))
        canon, sign = _canonical(word, transpose_sign)
        poly = sp.Poly(coeff, param)
        for (j,), c in poly.terms():
            acc[j][canon] += sign * c
    out: dict[int, dict[tuple[str, ...], sp.Expr]] = {}
    for j in sorted(acc):
        terms = {w: sp.nsimplify(c) for w, c in sorted(acc[j].items()) if sp.simplify(c) != 0}
        if terms:
            out[j] = terms
    return out
