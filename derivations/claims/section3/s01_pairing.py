"""S1 (Section 3.1, eq. ``killing.eqn``): the pairing on so(n) and the hat map.

The paper pairs so(n) with itself by <xi, eta> = -1/2 tr(xi eta) and identifies so(3) with R^3 by
the hat map, hat(u) v = u x v.  Both are definitions: the claim is that they agree with the dot and
cross products of R^3, and that symrb's ``hat`` and ``pairing`` implement them.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

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
    """The pairing's right side on hat(u), hat(v) minus u.v expands to 0 (n = 3)."""
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    value = explicit(PAIRING.rhs, {"xi": hat3(u), "eta": hat3(v)})
    return residual(value - u.dot(v))


@S1.check(Level.SYMBOLIC_FIXED_N)
def s1_hat_is_cross() -> sp.Expr:
    """The hat matrix used throughout satisfies the defining relation hat(u) v = u x v (n = 3)."""
    u, v = sym_vector("u", 3), sym_vector("v", 3)
    return residual(explicit(lhs_minus_rhs(HAT), {"uhat": hat3(u), "v": v, "u": u}))


@S1.check(Level.FLOAT64, tol=1e-14)
def s1_symrb_hat_and_pairing() -> float:
    """symrb.hat(u) v against numpy.cross(u, v) and symrb.pairing(hat u, hat v) against u.v
    (relative, 50 random pairs)."""
    import symrb

    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, 50, 3))
    e1 = np.abs(np.einsum("...ij,...j->...i", symrb.hat(u), v) - np.cross(u, v)).max()
    e2 = np.abs(symrb.pairing(symrb.hat(u), symrb.hat(v)) - np.einsum("...i,...i", u, v)).max()
    return float(max(e1, e2) / np.abs(u).max() / np.abs(v).max())


# the paper's sentences
S1.sentence(
    r"We use the following pairing (multiple of the Killing form) on $\mathfrak{so}(n)$, the Lie "
    r"algebra of $n \times n$ real skew matrices regarded as the Lie algebra of the "
    r"$n$-dimensional proper rotation group $\operatorname{SO}(n)$: $$\left\langle \xi, \eta "
    r"\right\rangle = - \frac{1}{2} \operatorname{trace} (\xi \eta).$$",
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
)
