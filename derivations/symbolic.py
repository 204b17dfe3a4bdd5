"""Small symbolic toolbox shared by the derivation modules.

* explicit matrices with symbolic entries (skew, diagonal, general) for fixed-n checks;
* the pairing, hat/vee, commutators on explicit SymPy matrices;
* noncommutative words: expansion of (A + l B)^k, reduction of trace words up to cyclic rotation
  (and reversal for skew/symmetric letters), and conversion to matrix expressions for the printer.
"""

from __future__ import annotations

import itertools
from collections import defaultdict
from collections.abc import Iterable, Sequence
from typing import Any

import sympy as sp
from sympy.matrices.expressions.applyfunc import ElementwiseApplyFunction
from sympy.printing.latex import LatexPrinter

from derivations.vocabulary import AUXILIARIES, Lam, W

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
    "explicit",
    "Words",
    "trace_words_of",
    "letters_of",
    "trace_residual",
    "latex",
    "Bracket",
    "Pair",
    "Cross",
    "eq",
    "lhs_minus_rhs",
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


# ---------------------------------------------------------------------------------------------
# kernel expressions in other algebras: explicit matrices (fixed n) and noncommutative words


def explicit(
    expr: sp.Basic,
    values: dict[str, sp.Matrix | sp.Expr],
    lam: Sequence[sp.Expr] | None = None,
) -> sp.Matrix | sp.Expr:
    """Evaluate a matrix expression of a :class:`~derivations.printer.Kernel` (or a formula) on
    explicit matrices.

    ``values`` maps a matrix symbol's name to an explicit SymPy matrix (or a scalar symbol's name
    to a value); ``lam`` gives the diagonal of Lambda, from which the auxiliaries (``Lambda``,
    ``W``) are built by the same entry formulas the printer prints.  Returns an explicit
    :class:`~sympy.Matrix` for a matrix expression, a scalar expression otherwise.  The
    expression tree is walked node by node with dense explicit arithmetic (much faster than
    substituting and calling ``doit``).
    """

    env = {
        k: (sp.Matrix(v) if isinstance(v, sp.MatrixBase) else sp.sympify(v))
        for k, v in values.items()
    }
    cache: dict[sp.Basic, Any] = {}
    size = next(
        (v.rows for v in env.values() if isinstance(v, sp.MatrixBase) and v.rows == v.cols), None
    )
    if lam is not None:
        size = len(lam)

    def ev(e: sp.Basic) -> Any:
        if e in cache:
            return cache[e]
        out = _ev(e)
        cache[e] = out
        return out

    def _ev(e: sp.Basic) -> Any:
        if isinstance(e, sp.MatrixSymbol):
            name = str(e.name)
            if name in env:
                return env[name]
            if name in AUXILIARIES:
                if lam is None:
                    raise ValueError(f"{name} needs lam (the diagonal of Lambda)")
                return sp.Matrix(AUXILIARIES[name].explicit(list(lam)))
            raise KeyError(f"no value for matrix symbol {name}")
        if isinstance(e, sp.Identity):
            return sp.eye(size)
        if isinstance(e, sp.ZeroMatrix):
            return sp.zeros(size, size)
        if isinstance(e, sp.MatMul):
            coeff, mats = e.as_coeff_matrices()
            acc = ev(mats[0])
            for m in mats[1:]:
                acc = acc * ev(m)
            return ev(coeff) * acc
        if isinstance(e, sp.MatAdd):
            acc = ev(e.args[0])
            for a in e.args[1:]:
                acc = acc + ev(a)
            return acc
        if isinstance(e, sp.Transpose):
            return ev(e.arg).T
        if isinstance(e, sp.MatPow):
            return ev(e.base) ** int(e.exp)
        if isinstance(e, sp.HadamardProduct):
            acc = ev(e.args[0])
            for a in e.args[1:]:
                acc = acc.multiply_elementwise(ev(a))
            return acc
        if isinstance(e, sp.Trace):
            return ev(e.arg).trace()
        if isinstance(e, Bracket):
            a, b = ev(e.args[0]), ev(e.args[1])
            return a * b - b * a
        if isinstance(e, Cross):
            return ev(e.args[0]).cross(ev(e.args[1]))
        if isinstance(e, Pair):
            return -sp.Rational(1, 2) * (ev(e.args[0]) * ev(e.args[1])).trace()
        if isinstance(e, ElementwiseApplyFunction):
            return ev(e.expr).applyfunc(e.function)
        if isinstance(e, sp.MatrixExpr):
            raise TypeError(f"explicit: no rule for {type(e).__name__}")
        if isinstance(e, sp.Symbol):
            return env.get(str(e.name), e)
        if not e.args:
            return e
        return e.func(*[ev(a) for a in e.args])

    return ev(expr)


class Words:
    """A noncommutative alphabet with transposes, for identities that hold for every n.

    A matrix ``X`` is a noncommutative symbol; its transpose is ``X`` itself (``symmetric``),
    ``-X`` (``skew``) or a separate letter ``X^T``.  Letters in ``orthogonal`` cancel against
    their transposes (``X X^T = X^T X = 1``).  :meth:`of` turns a matrix expression of a kernel
    or formula into a polynomial in these letters.
    """

    def __init__(
        self,
        symmetric: Iterable[str] = (),
        skew: Iterable[str] = (),
        orthogonal: Iterable[str] = (),
    ) -> None:
        self.symmetric, self.skew = set(symmetric), set(skew)
        self.orthogonal = set(orthogonal)
        self._letters: dict[str, sp.Symbol] = {}
        self._T: dict[sp.Symbol, sp.Expr] = {}

    def __call__(self, name: str) -> sp.Symbol:
        """The letter ``name`` (created on first use, with its transpose)."""
        if name not in self._letters:
            x = sp.Symbol(name, commutative=False)
            self._letters[name] = x
            if name in self.symmetric:
                self._T[x] = x
            elif name in self.skew:
                self._T[x] = -x
            else:
                xt = sp.Symbol(name + "^T", commutative=False)
                self._T[x], self._T[xt] = xt, x
        return self._letters[name]

    def letters(self, names: str) -> list[sp.Symbol]:
        return [self(s) for s in names.split()]

    def T(self, expr: sp.Expr) -> sp.Expr:
        """The transpose: words reversed, letters transposed."""
        total = sp.Integer(0)
        for term in sp.Add.make_args(sp.expand(expr)):
            c, word = letters_of(term)
            total += c * sp.Mul(*[self._T[x] for x in reversed(word)])
        return total

    def reduce(self, expr: sp.Expr) -> sp.Expr:
        """Expand and cancel ``X X^T`` and ``X^T X`` for the orthogonal letters."""
        pairs = set()
        for name in self.orthogonal:
            x = self(name)
            pairs |= {(x, self._T[x]), (self._T[x], x)}
        total = sp.Integer(0)
        for term in sp.Add.make_args(sp.expand(expr)):
            c, word = letters_of(term)
            changed = True
            while changed:
                changed = False
                for i in range(len(word) - 1):
                    if (word[i], word[i + 1]) in pairs:
                        word = word[:i] + word[i + 2 :]
                        changed = True
                        break
            total += c * sp.Mul(*word)
        return sp.expand(total)

    def is_zero(self, expr: sp.Expr) -> sp.Integer:
        """0 when ``expr`` reduces to zero, else 1 (a symbolic identity holds or it does not)."""
        return sp.Integer(0) if self.reduce(expr) == 0 else sp.Integer(1)

    def of(self, expr: sp.Basic, opaque: dict[sp.Basic, sp.Basic] | None = None) -> sp.Expr:
        """A matrix expression as a noncommutative polynomial.

        ``opaque`` maps subexpressions (e.g. ``Jinv(M)``) to matrix symbols first, so that what
        the letters cannot express (Hadamard products, entrywise functions) becomes a letter.
        """

        e = expr.xreplace(opaque) if opaque else expr
        if opaque:
            # a Hadamard product matches whatever order SymPy stored its factors in
            by_factors = {
                frozenset(k.args): v for k, v in opaque.items() if isinstance(k, sp.HadamardProduct)
            }
            e = e.replace(
                lambda x: isinstance(x, sp.HadamardProduct) and frozenset(x.args) in by_factors,
                lambda x: by_factors[frozenset(x.args)],
            )
        return self._of(e, Lam)

    def _of(self, e: sp.Basic, Lam: sp.MatrixSymbol) -> sp.Expr:
        if isinstance(e, sp.MatrixSymbol):
            return self(str(e.name))
        if isinstance(e, sp.Identity):
            return sp.Integer(1)
        if isinstance(e, sp.ZeroMatrix):
            return sp.Integer(0)
        if isinstance(e, sp.Transpose):
            return self.T(self._of(e.arg, Lam))
        if isinstance(e, sp.MatMul):
            coeff, mats = e.as_coeff_matrices()
            return coeff * sp.Mul(*[self._of(m, Lam) for m in mats])
        if isinstance(e, sp.MatAdd):
            return sp.Add(*[self._of(a, Lam) for a in e.args])
        if isinstance(e, sp.MatPow) and e.exp.is_Integer and e.exp >= 0:
            return self._of(e.base, Lam) ** int(e.exp)
        if isinstance(e, Bracket):
            a, b = (self._of(x, Lam) for x in e.args)
            return a * b - b * a
        raise TypeError(
            f"{type(e).__name__} has no noncommutative form: map it to a symbol with opaque= ({e})"
        )

    def trace_argument(
        self, expr: sp.Expr, opaque: dict[sp.Basic, sp.Basic] | None = None
    ) -> sp.Expr:
        """For a scalar sum of traces ``sum c_i tr(X_i)``: the polynomial ``sum c_i X_i``."""
        e = expr.xreplace(opaque) if opaque else expr
        total = sp.Integer(0)
        if e == 0:
            return total
        for term in sp.Add.make_args(sp.expand(e)):
            traces = [f for f in sp.Mul.make_args(term) if isinstance(f, sp.Trace)]
            if len(traces) != 1:
                raise TypeError(f"term {term} is not a multiple of one trace")
            coeff = sp.Mul(*[f for f in sp.Mul.make_args(term) if not isinstance(f, sp.Trace)])
            total += coeff * self.of(traces[0].arg)
        return total


def letters_of(term: sp.Expr) -> tuple[sp.Expr, list[sp.Symbol]]:
    """A monomial as (commutative coefficient, list of noncommutative letters), powers unrolled."""
    c, nc = term.args_cnc()
    word: list[sp.Symbol] = []
    for f in nc:
        if isinstance(f, sp.Pow):
            word.extend([f.base] * int(f.exp))
        else:
            word.append(f)
    return sp.Mul(*c), word


def trace_words_of(expr: sp.Expr) -> dict[tuple[str, ...], sp.Expr]:
    """tr(expr) as {canonical word: coefficient}, for a polynomial in noncommutative symbols.

    Words are reduced modulo cyclic rotation (tr(AB) = tr(BA)); two trace expressions are equal
    for all square matrices iff their dicts agree (zero coefficients are dropped).
    """
    acc: dict[tuple[str, ...], sp.Expr] = defaultdict(lambda: sp.Integer(0))
    for term in sp.Add.make_args(sp.expand(expr)):
        coeff, word = letters_of(term)
        names = tuple(str(x) for x in word)
        canon = min(names[i:] + names[:i] for i in range(len(names))) if names else ()
        acc[canon] += coeff
    return {w: sp.simplify(c) for w, c in acc.items() if sp.simplify(c) != 0}


def trace_residual(expr: sp.Expr) -> sp.Integer:
    """Number of canonical trace words of ``expr`` with non-zero coefficient (0: tr(expr) = 0)."""
    return sp.Integer(len(trace_words_of(expr)))


# ---------------------------------------------------------------------------------------------
# LaTeX of formulas (what the book shows is printed from the checked objects)


class _Latex(LatexPrinter):
    def _print_HadamardProduct(self, expr: sp.HadamardProduct) -> str:

        others = [a for a in expr.args if a != W]
        if len(others) == len(expr.args) - 1:
            inner = others[0] if len(others) == 1 else sp.HadamardProduct(*others)
            return r"J^{-1}\left(" + self._print(inner) + r"\right)"
        return super()._print_HadamardProduct(expr)

    def _print_ElementwiseApplyFunction(self, expr: Any) -> str:
        """f applied entrywise, shown as the scalar formula with the matrix argument in place."""
        (var,) = expr.function.variables
        hole = sp.Symbol("ARGUMENT")
        body = self._print(expr.function.expr.xreplace({var: hole}))
        return body.replace(self._print(hole), r"\left(" + self._print(expr.expr) + r"\right)")

    def _print_MatMul(self, expr: sp.MatMul) -> str:
        """A rational coefficient as a small fraction in front: tfrac12 Q M, not (1/2) Q M."""
        coeff, mats = expr.as_coeff_mmul()
        if coeff.is_Rational and coeff.q != 1 and mats:
            sign = "-" if coeff < 0 else ""
            body = self._print(mats if not isinstance(mats, sp.MatMul) else mats)
            return rf"{sign}\tfrac{{{abs(coeff.p)}}}{{{coeff.q}}}{body}"
        return super()._print_MatMul(expr)


def latex(expr: Any) -> str:
    """LaTeX for a formula: a SymPy object, or a tuple of them joined by commas."""
    if isinstance(expr, tuple | list):
        return ",\\quad ".join(latex(e) for e in expr)
    return _Latex({"mat_symbol_style": "plain", "order": "none"}).doprint(expr)


# ---------------------------------------------------------------------------------------------
# display objects for formulas: they print like the paper and evaluate with .doit()


class Bracket(sp.MatrixExpr):
    """The commutator [A, B] = A B - B A of two matrix expressions (printed as a bracket)."""

    def __new__(cls, a: sp.MatrixExpr, b: sp.MatrixExpr) -> Bracket:
        return super().__new__(cls, a, b)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[0].shape

    def doit(self, **hints: Any) -> sp.Basic:
        a, b = (x.doit(**hints) if hints.get("deep", True) else x for x in self.args)
        return a * b - b * a

    def _latex(self, printer: Any) -> str:
        a, b = self.args
        return rf"\left[{printer._print(a)}, {printer._print(b)}\right]"


class Pair(sp.Expr):
    """The pairing <a, b> = -1/2 trace(a b) on so(n) (printed with angle brackets)."""

    is_commutative = True

    def __new__(cls, a: sp.Basic, b: sp.Basic) -> Pair:
        return super().__new__(cls, a, b)

    def doit(self, **hints: Any) -> sp.Basic:
        a, b = (x.doit(**hints) for x in self.args)
        prod = a * b
        tr = prod.trace() if isinstance(prod, sp.MatrixBase) else sp.Trace(prod)
        return -sp.Rational(1, 2) * tr

    def _latex(self, printer: Any) -> str:
        a, b = self.args
        return rf"\left\langle {printer._print(a)}, {printer._print(b)}\right\rangle"


class Cross(sp.MatrixExpr):
    """The cross product u x v of two 3-vectors (printed with a times sign)."""

    def __new__(cls, a: sp.MatrixExpr, b: sp.MatrixExpr) -> Cross:
        return super().__new__(cls, a, b)

    @property
    def shape(self) -> tuple[sp.Expr, sp.Expr]:
        return self.args[0].shape

    def doit(self, **hints: Any) -> sp.Basic:
        a, b = (x.doit(**hints) for x in self.args)
        if isinstance(a, sp.MatrixBase) and isinstance(b, sp.MatrixBase):
            return sp.Matrix(a).cross(sp.Matrix(b))
        return Cross(a, b)

    def _latex(self, printer: Any) -> str:
        a, b = self.args
        return rf"{printer._print(a)} \times {printer._print(b)}"


def eq(a: sp.Basic, b: sp.Basic) -> sp.Eq:
    """An unevaluated equation ``a = b`` (a formula to display and to check)."""
    return sp.Eq(a, b, evaluate=False)


def lhs_minus_rhs(eq: sp.Basic) -> sp.Basic:
    """For an equation ``Eq(a, b)`` (a formula) the expression ``a - b`` that should vanish."""
    return eq.lhs - eq.rhs
