"""S1 (Section 3.1, eq. ``killing.eqn``): the pairing on so(n) and the hat map.

The paper pairs so(n) with itself by <xi, eta> = -1/2 tr(xi eta) and identifies so(3) with R^3 by
the hat map, hat(u) v = u x v.  Both are definitions: the claim is that they agree with the dot and
cross products of R^3, and that symrb's ``hat`` and ``pairing`` implement them.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

from derivations.claims.section3._orbits import so_basis
from derivations.registry import Level, claim
from derivations.symbolic import (
    Cross,
    Pair,
    eq,
    explicit,
    hat3,
    lhs_minus_rhs,
    residual,
    sym_vector,
)
from derivations.vocabulary import matrix, vector

S1 = claim(
    "S1",
    label="killing.eqn",
    title="Pairing on $\\mathfrak{so}(n)$ agrees with the dot product of $\\mathbb{R}^3$",
    statement="[[pairing]]; for $n=3$, [[pair_is_dot]] where [[hat]].",
    expected="holds",
    section="3.1",
    where="Section 3.1 (Classical $n$-dimensional rigid body equations), the first displayed "
    "equation, $\\langle \\xi, \\eta\\rangle = -\\tfrac12 \\operatorname{tr}(\\xi\\eta)$, and the "
    "hat map $\\hat u v = u \\times v$ after it",
    note="The pairing and the hat map are definitions; what is checked is that they agree with "
    "the dot and cross products of $\\mathbb{R}^3$, and that symrb's `hat` and `pairing` "
    "implement them.",
)
_xi, _eta = matrix("xi"), matrix("eta")
_u, _v = vector("u"), vector("v")
PAIRING = S1.formula("pairing", eq(Pair(_xi, _eta), -sp.Trace(_xi * _eta) / 2))
HAT = S1.formula("hat", eq(matrix("uhat") * _v, Cross(_u, _v)))
S1.formula("pair_is_dot", eq(Pair(matrix("uhat"), matrix("vhat")), _u.T * _v))


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_pairing_is_dot() -> sp.Expr:
    r"""The pairing's right side on $\hat u$, $\hat v$ minus $u \cdot v$ expands to 0 ($n = 3$)."""
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    value = explicit(PAIRING.rhs, {"xi": hat3(u), "eta": hat3(v)})
    return residual(value - u.dot(v))


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_hat_is_cross() -> sp.Expr:
    r"""The hat matrix used throughout satisfies the defining relation $\hat u\, v = u \times v$ ($n
    = 3$)."""
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    return residual(explicit(lhs_minus_rhs(HAT), {"uhat": hat3(u), "v": v, "u": u}))


@S1.check(Level.FLOAT64, tol=1e-14)
def s1_symrb_hat_and_pairing() -> float:
    r"""symrb.hat($u$) $v$ against numpy.cross($u$, $v$) and symrb.pairing($\hat u$, $\hat v$)
    against $u \cdot v$ (relative, 50 random pairs)."""
    import symrb

    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, 50, 3))
    e1 = np.abs(np.einsum("...ij,...j->...i", symrb.hat(u), v) - np.cross(u, v)).max()
    e2 = np.abs(symrb.pairing(symrb.hat(u), symrb.hat(v)) - np.einsum("...i,...i", u, v)).max()
    return float(max(e1, e2) / np.abs(u).max() / np.abs(v).max())


def _pairing_gram(k: int) -> sp.Matrix:
    """The displayed pairing on the basis E_ij = e_i e_j^T - e_j e_i^T (i < j) of so(k)."""
    basis = so_basis(k)
    return sp.Matrix([[explicit(PAIRING.rhs, {"xi": a, "eta": b}) for b in basis] for a in basis])


def _killing_gram(k: int) -> sp.Matrix:
    """kappa(E_a, E_b) = tr(ad E_a ad E_b) from the structure constants of so(k): the coordinate
    of a skew matrix on E_ij (i < j) is its (i, j) entry."""
    basis = so_basis(k)
    pairs = list(itertools.combinations(range(k), 2))

    def ad(a: sp.Matrix) -> sp.Matrix:
        return sp.Matrix.hstack(
            *[sp.Matrix([(a * b - b * a)[i, j] for i, j in pairs]) for b in basis]
        )

    ads = [ad(a) for a in basis]
    return sp.Matrix(len(basis), len(basis), lambda a, b: (ads[a] * ads[b]).trace())


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_multiple_of_killing() -> sp.Expr:
    r"""The displayed pairing is a multiple of the Killing form: on $\mathfrak{so}(3)$,
    $\mathfrak{so}(4)$, $\mathfrak{so}(5)$ the Gram matrix of $\kappa$ (from the structure
    constants) minus $c$ times that of the displayed pairing vanishes for one non-zero $c$ ($c =
    -2(n - 2)$: $\kappa = (n - 2) \operatorname{tr}$)."""
    total = sp.Integer(0)
    for k in (3, 4, 5):
        kappa, gram = _killing_gram(k), _pairing_gram(k)
        c = kappa[0, 0] / gram[0, 0]
        total += residual(kappa - c * gram) + sp.Integer(c == 0)
    return total


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_pairing_is_inner_product() -> sp.Integer:
    r"""The displayed pairing is an inner product on $\mathfrak{so}(n)$, so it identifies
    $\mathfrak{so}(n)^*$ with $\mathfrak{so}(n)$ ($\xi \mapsto \langle \xi, \cdot\rangle$ is
    injective, hence onto): its Gram matrix on the basis $E_{ij}$ ($i < j$) is symmetric and
    positive definite for $n = 2, \dots, 6$ (here the identity). The number of $n$ for which it is
    not."""
    bad = 0
    for k in range(2, 7):
        gram = _pairing_gram(k)
        bad += int(gram != gram.T or not gram.is_positive_definite)
    return sp.Integer(bad)


# the paper's sentences
S1.sentence(
    r"We use the following pairing (multiple of the Killing form) on $\mathfrak{so}(n)$, the Lie "
    r"algebra of $n \times n$ real skew matrices regarded as the Lie algebra of the "
    r"$n$-dimensional proper rotation group $\operatorname{SO}(n)$: $\left\langle \xi, \eta "
    r"\right\rangle = - \frac{1}{2} \operatorname{trace} (\xi \eta).$",
    s1_multiple_of_killing,
    s1_pairing_is_dot,
    s1_symrb_hat_and_pairing,
)
S1.sentence(
    r"The factor of $1/2$ in (killing.eqn) is to make this inner product agree with the usual "
    r"inner product on $\mathbb{R}^3$ when it is identified with $\mathfrak{so}(3)$ in the "
    r"following standard way: associate the $3 \times 3$ skew matrix $\hat{u}$ to the vector $u$ "
    r"by $\hat{u} \cdot v = u \times v$, where $u \times v$ is the usual cross product in "
    r"$\mathbb{R}^3$.",
    s1_pairing_is_dot,
    s1_hat_is_cross,
    s1_symrb_hat_and_pairing,
)
S1.sentence(
    r"We use this inner product to identify the dual of the Lie algebra, namely "
    r"$\mathfrak{so}(n)^\ast$, with the Lie algebra $\mathfrak{so}(n)$.",
    s1_pairing_is_inner_product,
)
