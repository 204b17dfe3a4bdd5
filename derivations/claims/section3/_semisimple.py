"""The generalized rigid body on su(3) (claim S4): Mishchenko and Fomenko's equations on a
semisimple Lie algebra beyond so(n), with exact SymPy matrices.

On su(3) with a = i diag(a_j) and b = i diag(b_j) (a_j distinct) the generalized rigid body is
Mdot = [M, Omega] with Omega off the diagonal given by [a, Omega] = [b, M], that is
Omega_jk = (b_j - b_k) / (a_j - a_k) M_jk, and Omega's diagonal 0; the shifted traces of
(M + lambda a)^p are its integrals.  The pairing is <x, y> = -1/2 tr(x y), real on su(3).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence

import sympy as sp


def su3_basis() -> list[sp.Matrix]:
    """A real basis of su(3): E_jk - E_kj, i (E_jk + E_kj) (j < k), i (E_jj - E_j+1,j+1)."""
    out = []
    for j, k in itertools.combinations(range(3), 2):
        e = sp.zeros(3, 3)
        e[j, k], e[k, j] = 1, -1
        out.append(e)
        f = sp.zeros(3, 3)
        f[j, k] = f[k, j] = sp.I
        out.append(f)
    for j in range(2):
        d = sp.zeros(3, 3)
        d[j, j], d[j + 1, j + 1] = sp.I, -sp.I
        out.append(d)
    return out


def pairing(x: sp.Matrix, y: sp.Matrix) -> sp.Expr:
    """<x, y> = -1/2 tr(x y)."""
    return sp.expand(-(x * y).trace() / 2)


def element(coords: Sequence[sp.Expr]) -> sp.Matrix:
    """sum_a coords_a e_a in the basis of :func:`su3_basis`."""
    return sum((c * e for c, e in zip(coords, su3_basis(), strict=True)), sp.zeros(3, 3))


def sectional_omega(M: sp.Matrix, a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> sp.Matrix:
    """Omega with [a, Omega] = [b, M] off the diagonal and 0 on it (a = i diag a_j, b = i diag
    b_j)."""
    return sp.Matrix(3, 3, lambda j, k: 0 if j == k else (b[j] - b[k]) / (a[j] - a[k]) * M[j, k])


@functools.cache
def _gram_inverse() -> sp.Matrix:
    basis = su3_basis()
    return sp.Matrix(len(basis), len(basis), lambda p, q: pairing(basis[p], basis[q])).inv()


def gradient(F: sp.Expr, coords: Sequence[sp.Symbol]) -> sp.Matrix:
    """The element G of su(3) with <G, dM> = dF, from the Gram matrix of the pairing."""
    c = _gram_inverse() * sp.Matrix([sp.diff(F, x) for x in coords])
    return element(list(c))


def poly_pairing(x: sp.Matrix, y: sp.Matrix, gens: Sequence[sp.Symbol]) -> sp.Poly:
    """<x, y> as a polynomial in ``gens`` over the Gaussian rationals (fast exact expansion)."""
    px, py = (
        [[sp.Poly(e, *gens, domain="QQ_I") for e in row] for row in z.tolist()] for z in (x, y)
    )
    total = sp.Poly(0, *gens, domain="QQ_I")
    for j, k in itertools.product(range(3), repeat=2):
        total += px[j][k] * py[k][j]
    return -total / 2


def lie_poisson(M: sp.Matrix, gF: sp.Matrix, gG: sp.Matrix, gens: Sequence[sp.Symbol]) -> sp.Poly:
    """{F, G}(M) = -<M, [grad F, grad G]> = -<[M, grad F], grad G> (as a polynomial)."""
    return -poly_pairing(M * gF - gF * M, gG, gens)


def _poly_product(x: list, y: list) -> list:
    return [[sum((x[j][i] * y[i][k] for i in range(3)), x[0][0] * 0) for k in range(3)]
            for j in range(3)]  # fmt: skip


def shifted_integrals(
    M: sp.Matrix, a_mat: sp.Matrix, gens: Sequence[sp.Symbol]
) -> tuple[list[sp.Expr], list[sp.Expr]]:
    """The non-constant lambda-coefficients of tr((M + lambda a)^p) / i^p, p = 2, 3 (real on
    su(3)), and the Casimirs among them (the lambda^0 ones); polynomial arithmetic over the
    Gaussian rationals."""
    lam = sp.Symbol("lambda")
    X = [[sp.Poly(e, lam, *gens, domain="QQ_I") for e in row] for row in (M + lam * a_mat).tolist()]
    every, casimirs = [], []
    power = X
    for p in (2, 3):
        power = _poly_product(power, X)
        trace = sum((power[j][j] for j in range(3)), X[0][0] * 0).as_expr() / sp.I**p
        poly = sp.Poly(sp.expand(trace), lam)
        for k in range(p):
            every.append(sp.expand(poly.coeff_monomial(lam**k)))
        casimirs.append(every[-p])
    return every, casimirs
