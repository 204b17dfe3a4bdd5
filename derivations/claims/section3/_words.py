"""Noncommutative words for the symmetric rigid body (claims S6, S7, S11, S12): rewriting rules,
J^-1 of a momentum as one letter, and time derivatives by the product rule."""

from __future__ import annotations

from collections.abc import Mapping

import sympy as sp

from derivations.symbolic import Words, letters_of
from derivations.vocabulary import W, matrix


def reduce_words(
    w: Words, expr: sp.Expr, rules: Mapping[tuple[sp.Symbol, sp.Symbol], sp.Expr]
) -> sp.Expr:
    """Apply the rewriting ``rules`` (a pair of adjacent letters -> a polynomial) and the
    orthogonality of ``w`` until nothing changes."""
    current = w.reduce(expr)
    for _ in range(50):
        total = sp.Integer(0)
        for term in sp.Add.make_args(sp.expand(current)):
            c, word = letters_of(term)
            for i in range(len(word) - 1):
                if (word[i], word[i + 1]) in rules:
                    repl = rules[(word[i], word[i + 1])]
                    term = c * sp.Mul(*word[:i]) * repl * sp.Mul(*word[i + 2 :])
                    break
            total += term
        new = w.reduce(total)
        if new == current:
            return new
        current = new
    raise RuntimeError("rewriting did not terminate")


def rule(w: Words, relation: sp.Eq) -> dict[tuple[sp.Symbol, sp.Symbol], sp.Expr]:
    """A displayed relation ``X Y = poly`` (its left side one word of two letters) as a rule."""
    c, word = letters_of(sp.expand(w.of(relation.lhs.doit())))
    if len(word) != 2:
        raise ValueError(f"relation {relation} is not a rule on a pair of letters")
    return {(word[0], word[1]): sp.expand(w.of(relation.rhs.doit()) / c)}


def ratio(x: sp.Expr, t: sp.Expr) -> sp.Expr | None:
    """The scalar c with x = c t for noncommutative polynomials, or None."""
    x, t = sp.expand(x), sp.expand(t)
    if t == 0:
        return None
    lead = sp.Add.make_args(t)[0]
    coeff_t, word = letters_of(lead)
    coeff_x = sum(
        (cx for cx, wx in map(letters_of, sp.Add.make_args(x)) if wx == word),
        sp.Integer(0),
    )
    c = sp.nsimplify(coeff_x / coeff_t)
    return c if sp.expand(x - c * t) == 0 else None


def jinv_argument(node: sp.Basic) -> sp.MatrixExpr | None:
    """X for a node J^{-1}(X) (a Hadamard product with W), else None."""
    if not (isinstance(node, sp.HadamardProduct) and W in node.args):
        return None
    others = [a for a in node.args if a != W]
    return others[0] if len(others) == 1 else sp.HadamardProduct(*others)


def jinv_letters(
    expr: sp.Basic,
    w: Words,
    letters: Mapping[str, sp.MatrixExpr],
    rules: Mapping[tuple[sp.Symbol, sp.Symbol], sp.Expr] | None = None,
) -> sp.Basic:
    """Replace every ``J^{-1}(X)`` in ``expr`` by ``c L`` when X reduces (``rules``,
    orthogonality) to c times the argument of ``letters[L] = J^{-1}(Y)``: J^{-1} is linear, so
    this is exact.  Raises when some J^{-1} argument is no multiple of those."""
    rules = rules or {}
    reduced = {}
    for name, jinv in letters.items():
        arg = jinv_argument(jinv)
        if arg is None:
            raise ValueError(f"{jinv} is not J^-1 of a matrix")
        reduced[name] = reduce_words(w, w.of(arg), rules)
    mapping = {}
    for node in sp.preorder_traversal(expr):
        arg = jinv_argument(node)
        if arg is None:
            continue
        x = reduce_words(w, w.of(arg), rules)
        for name, t in reduced.items():
            c = ratio(x, t)
            if c is not None:
                mapping[node] = c * matrix(name)
                break
        else:
            raise ValueError(f"J^-1 of {arg} is no multiple of {list(letters)}")
    return expr.xreplace(mapping)


def ddt(w: Words, poly: sp.Expr, rates: Mapping[str, sp.Expr]) -> sp.Expr:
    """d/dt of a noncommutative polynomial by the product rule; ``rates`` gives the derivative of
    each letter by name (transposes follow: d/dt X^T = (d/dt X)^T)."""
    table: dict[sp.Symbol, sp.Expr] = {}
    for name, rate in rates.items():
        x = w(name)
        table[x] = rate
        xt = w.T(x)
        if xt != x and xt != -x:
            table[xt] = w.T(rate)
    total = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(poly)):
        c, word = letters_of(term)
        for i, x in enumerate(word):
            if x in table:
                total += c * sp.Mul(*word[:i]) * table[x] * sp.Mul(*word[i + 1 :])
    return sp.expand(total)
